// Invariants over many random planar maps, checked by the independent exact checker:
// vertex subset with endpoints, no new contact between segments, every detour empty.
#include "core/map/simplify.hpp"

#include "support/exact_checker.hpp"
#include "support/random_maps.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace toposimp {
namespace {

struct Setting {
    const char* name;
    testing::RandomMapOptions map;
};

std::vector<Setting> settings() {
    std::vector<Setting> list;
    testing::RandomMapOptions options;
    list.push_back({"around_origin", options});
    options.origin_x = 500000.25;
    options.origin_y = 4.6e6;
    list.push_back({"utm_metres", options});
    options.origin_x = 0;
    options.origin_y = 0;
    options.extent = 1e-6;
    list.push_back({"tiny", options});
    options.extent = 1e12;
    options.origin_x = -3e11;
    list.push_back({"huge_mixed_signs", options});
    options = {};
    options.chains = 30;
    options.max_steps = 40;
    options.control_points = 120;
    list.push_back({"crowded", options});
    return list;
}

class RandomMaps : public ::testing::TestWithParam<map::StopCriterion> {};

TEST_P(RandomMaps, KeepTopologyAndSubset) {
    int maps = 0;
    std::uint64_t removed = 0;
    for (const Setting& setting : settings()) {
        for (std::uint64_t seed = 0; seed < 40; ++seed) {
            std::mt19937_64 rng(seed * 7919 + 17);
            const map::MapData input = testing::random_planar_map(rng, setting.map);
            ASSERT_TRUE(testing::check_planar(input).ok()) << setting.name << " seed " << seed << ": generator made a non-planar map";
            map::SimplifyOptions options;
            options.stop = GetParam();
            const map::SimplifyResult result = map::simplify(input, options);
            const testing::CheckReport report = testing::check_simplification(input, result.kept);
            ASSERT_TRUE(report.ok()) << setting.name << " seed " << seed << ": " << report.summary();
            for (std::uint32_t v = 0; v < input.vertices.size(); ++v) removed += result.kept[v] ? 0 : 1;
            ++maps;
        }
    }
    EXPECT_EQ(maps, 200);
    EXPECT_GT(removed, 1000u) << "the maps should simplify substantially";
}

INSTANTIATE_TEST_SUITE_P(Targets, RandomMaps,
                         ::testing::Values(map::StopCriterion{map::Target::max, 0},
                                           map::StopCriterion{map::Target::keep_fraction, 0.5},
                                           map::StopCriterion{map::Target::keep_fraction, 0.1}),
                         [](const auto& test_info) { return std::to_string(test_info.index); });

// The float filter never changes a decision: exact and all-GMP modes give the same output.
TEST(RandomMapsModes, ExactAndRationalAgree) {
    for (const Setting& setting : settings()) {
        for (std::uint64_t seed = 0; seed < 10; ++seed) {
            std::mt19937_64 rng(seed + 1000);
            const map::MapData input = testing::random_planar_map(rng, setting.map);
            map::SimplifyOptions options;
            options.stop.target = map::Target::max;
            const auto exact = map::simplify(input, options);
            options.arithmetic = exact::Arithmetic::rational;
            const auto rational = map::simplify(input, options);
            ASSERT_EQ(exact.kept, rational.kept) << setting.name << " seed " << seed;
        }
    }
}

// Roads laid over a planar map cross it anywhere: every crossing between two lines stays (same
// count for every pair of lines), and no new contact or side change appears.
TEST(RandomMapsWithCrossings, KeepEveryCrossingAndAddNone) {
    int crossing_maps = 0;
    for (const Setting& setting : settings()) {
        for (std::uint64_t seed = 0; seed < 20; ++seed) {
            std::mt19937_64 rng(seed * 104729 + 5);
            testing::RandomMapOptions options = setting.map;
            options.roads = 4;
            const map::MapData input = testing::random_planar_map(rng, options);
            const std::vector<std::uint8_t> all(input.vertices.size(), 1);
            const auto before = testing::crossings_between_chains(input, all);
            for (const map::StopCriterion stop : {map::StopCriterion{map::Target::max, 0}, map::StopCriterion{map::Target::keep_fraction, 0.5}}) {
                map::SimplifyOptions simplify_options;
                simplify_options.stop = stop;
                const map::SimplifyResult result = map::simplify(input, simplify_options);
                const testing::CheckReport report = testing::check_simplification(input, result.kept);
                ASSERT_TRUE(report.ok()) << setting.name << " seed " << seed << ": " << report.summary();
                ASSERT_EQ(testing::crossings_between_chains(input, result.kept), before) << setting.name << " seed " << seed;
                EXPECT_GT(result.stats.removed, 0u);
            }
            std::uint64_t crossings = 0;
            for (const auto count : before) crossings += count;
            crossing_maps += crossings > 0;
        }
    }
    EXPECT_GT(crossing_maps, 80) << "most maps should have crossings";
}

// The output never depends on the number of threads: every loop forced parallel (threshold 0)
// on 2, 3, 4 and 7 threads gives the 1-thread result, for every stopping rule.
TEST(RandomMapsParallel, SameOutputForAnyThreadCount) {
    const std::vector<map::StopCriterion> stops{{map::Target::max, 0},
                                                {map::Target::keep_fraction, 0.5},
                                                {map::Target::keep_fraction, 0.1},
                                                {map::Target::remove_points, 37},
                                                {map::Target::max_area, 1e-3}};
    int compared = 0;
    for (const Setting& setting : settings()) {
        for (std::uint64_t seed = 0; seed < 12; ++seed) {
            std::mt19937_64 rng(seed * 31337 + 3);
            testing::RandomMapOptions map_options = setting.map;
            map_options.roads = static_cast<int>(seed % 3);  // some maps with crossings
            const map::MapData input = testing::random_planar_map(rng, map_options);
            for (const map::StopCriterion& stop : stops) {
                map::SimplifyOptions options;
                options.stop = stop;
                options.parallel_threshold = 0;
                options.threads = 1;
                const map::SimplifyResult serial = map::simplify(input, options);
                for (const int threads : {2, 3, 4, 7}) {
                    options.threads = threads;
                    const map::SimplifyResult parallel = map::simplify(input, options);
                    ASSERT_EQ(parallel.kept, serial.kept) << setting.name << " seed " << seed << ", " << threads << " threads";
                    ASSERT_EQ(parallel.stats.blocked(), serial.stats.blocked());
                    ASSERT_EQ(parallel.stats.rounds, serial.stats.rounds);
                    ++compared;
                }
            }
        }
    }
    EXPECT_EQ(compared, 5 * 12 * 5 * 4);
}

// Count targets land exactly on the target whenever they say they reached it, and they reach
// it on almost every map (they stop short only when no vertex can go any more).
TEST(RandomMapsParallel, CountTargetsLandExactly) {
    int reached = 0, runs = 0;
    for (const Setting& setting : settings()) {
        for (std::uint64_t seed = 0; seed < 20; ++seed) {
            std::mt19937_64 rng(seed * 65537 + 11);
            const map::MapData input = testing::random_planar_map(rng, setting.map);
            for (const map::StopCriterion stop : {map::StopCriterion{map::Target::keep_fraction, 0.5},
                                                  map::StopCriterion{map::Target::keep_points, 60},
                                                  map::StopCriterion{map::Target::remove_points, 25}}) {
                map::SimplifyOptions options;
                options.stop = stop;
                options.parallel_threshold = 0;
                const map::SimplifyResult result = map::simplify(input, options);
                const std::uint64_t goal = map::removal_goal(stop, input.vertices.size());
                ++runs;
                if (result.stats.target_reached) {
                    ++reached;
                    ASSERT_EQ(result.stats.removed, goal) << setting.name << " seed " << seed;
                } else {
                    ASSERT_LT(result.stats.removed, goal);
                    // Stopped short: then not one more vertex can go.
                    map::MapData rest;
                    rest.control_points = input.control_points;
                    for (const map::Chain& chain : input.chains) {
                        std::vector<Point> kept;
                        for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
                            if (result.kept[v]) kept.push_back(input.vertices[v]);
                        }
                        rest.add_chain(kept);
                    }
                    map::SimplifyOptions more;
                    more.stop = {map::Target::remove_points, 1};
                    EXPECT_EQ(map::simplify(rest, more).stats.removed, 0u) << setting.name << " seed " << seed;
                }
            }
        }
    }
    EXPECT_GT(reached, runs * 3 / 4);
}

// The most any run can remove, counted here from the rules' own terms: chain ends stay, pinned
// vertices stay, and a closed chain keeps min(3, d) of its d distinct locations, its ends at
// one of them (so min(2, d − 1) of its interior vertices, which pinned ones may be).
std::uint64_t most_that_can_go(const map::MapData& map, std::uint64_t pinned) {
    std::uint64_t interior = 0, ring_minimum = 0;
    for (const map::Chain& chain : map.chains) {
        if (chain.last > chain.first) interior += chain.last - chain.first - 1;
        const Point first = map.vertices[chain.first], last = map.vertices[chain.last];
        if (chain.last == chain.first || first.x != last.x || first.y != last.y) continue;
        std::set<std::pair<double, double>> locations;
        for (std::uint32_t v = chain.first; v < chain.last; ++v) {
            locations.emplace(map.vertices[v].x + 0.0, map.vertices[v].y + 0.0);  // (−0 as 0)
        }
        ring_minimum += std::min<std::uint64_t>(2, locations.size() - 1);
    }
    const std::uint64_t queued = interior - pinned;
    return queued - std::min(queued, ring_minimum > pinned ? ring_minimum - pinned : 0);
}

// A count target asking for at least that many removals cannot be reached by any run: it runs
// as --max (one sweep, no rounds) and gives --max's result; one removal fewer runs in rounds and
// never removes more than asked. And --max never removes more than the bound (which is what
// makes the first case safe).
TEST(RandomMapsParallel, ACountTargetNoRunCanReachRunsAsMax) {
    int swept = 0;
    for (Setting setting : settings()) {
        setting.map.rings = 8;
        setting.map.roads = 2;
        for (std::uint64_t seed = 0; seed < 10; ++seed) {
            std::mt19937_64 rng(seed * 7919 + 3);
            const map::MapData input = testing::random_planar_map(rng, setting.map);
            const std::string what = std::string(setting.name) + " seed " + std::to_string(seed);
            for (const int threads : {1, 3}) {
                map::SimplifyOptions options;
                options.parallel_threshold = 0;
                options.threads = threads;
                options.stop = {map::Target::max, 0};
                const map::SimplifyResult max = map::simplify(input, options);
                const std::uint64_t bound = most_that_can_go(input, max.stats.pinned_by_crossing);
                ASSERT_LE(max.stats.removed, bound) << what;
                if (bound == 0) continue;
                options.stop = {map::Target::remove_points, static_cast<double>(bound)};
                const map::SimplifyResult at_bound = map::simplify(input, options);
                EXPECT_TRUE(at_bound.stats.swept_as_max) << what;
                EXPECT_EQ(at_bound.kept, max.kept) << what;
                EXPECT_EQ(at_bound.stats.rounds, 0u) << what;
                EXPECT_EQ(at_bound.stats.removal_goal, bound) << what;
                EXPECT_EQ(at_bound.stats.target_reached, max.stats.removed == bound) << what;
                options.stop = {map::Target::keep_points, 0};
                EXPECT_EQ(map::simplify(input, options).kept, max.kept) << what;
                options.stop = {map::Target::remove_points, static_cast<double>(bound - 1)};
                const map::SimplifyResult below = map::simplify(input, options);
                EXPECT_FALSE(below.stats.swept_as_max) << what;
                EXPECT_GE(below.stats.rounds, 1u) << what;
                EXPECT_LE(below.stats.removed, bound - 1) << what;
                swept += at_bound.stats.swept_as_max;
            }
        }
    }
    EXPECT_GT(swept, 50);
}

// Repeated runs give the same output (no dependence on addresses or hash order).
TEST(RandomMapsModes, Deterministic) {
    std::mt19937_64 rng(99);
    testing::RandomMapOptions options;
    options.chains = 40;
    const map::MapData input = testing::random_planar_map(rng, options);
    map::SimplifyOptions simplify_options;
    simplify_options.stop = {map::Target::keep_fraction, 0.3};
    EXPECT_EQ(map::simplify(input, simplify_options).kept, map::simplify(input, simplify_options).kept);
}

}  // namespace
}  // namespace toposimp
