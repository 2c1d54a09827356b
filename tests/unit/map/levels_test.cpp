// Nested levels: each level's kept vertices are a subset of the level before, each keeps every
// promise against the input (independent checker), a count level keeps what a single run to the
// same target keeps, and the result is the same on any number of threads.
#include "core/map/levels.hpp"

#include "support/exact_checker.hpp"
#include "support/random_maps.hpp"

#include <gtest/gtest.h>

#include <random>

namespace toposimp::map {
namespace {

TEST(Levels, NestedEachCleanAndCountedAgainstTheInput) {
    const std::vector<StopCriterion> levels{{Target::keep_fraction, 0.6}, {Target::keep_fraction, 0.3}, {Target::keep_points, 40}};
    for (std::uint64_t seed = 1; seed <= 25; ++seed) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions random;
        random.roads = seed % 3 == 0 ? 2 : 0;
        const MapData map = testing::random_planar_map(rng, random);
        SimplifyOptions options;
        options.parallel_threshold = 0;
        options.threads = 1;
        const std::vector<SimplifyResult> one = simplify_levels(map, options, levels).results;
        options.threads = 3;
        const std::vector<SimplifyResult> three = simplify_levels(map, options, levels).results;
        ASSERT_EQ(one.size(), levels.size());
        for (std::size_t k = 0; k < levels.size(); ++k) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", level " + std::to_string(k));
            EXPECT_EQ(one[k].kept, three[k].kept) << "depends on the threads";
            const testing::CheckReport report = testing::check_simplification(map, one[k].kept);
            EXPECT_TRUE(report.ok()) << report.summary();
            if (k > 0) {
                for (std::size_t v = 0; v < map.vertices.size(); ++v) EXPECT_LE(one[k].kept[v], one[k - 1].kept[v]) << v;
            }
            // Where a single run reaches the target, the level keeps as many vertices.
            SimplifyOptions single = options;
            single.stop = levels[k];
            const SimplifyResult alone = simplify(map, single);
            std::uint64_t kept = 0;
            for (const std::uint8_t flag : one[k].kept) kept += flag;
            if (alone.stats.target_reached && one[k].stats.target_reached) {
                EXPECT_EQ(kept, alone.stats.vertices_out);
            }
        }
    }
}

// Levels on a grid: the first rounded, the coarser simplified from it. Each level keeps every
// promise against the input at the rounded positions, is on the grid wherever the first is, and
// keeps a subset of the level before at the same positions; the same on any number of threads.
TEST(Levels, RoundedLevelsAreNestedOnTheGridAndClean) {
    const std::vector<StopCriterion> levels{{Target::keep_fraction, 0.5}, {Target::keep_fraction, 0.25}, {Target::keep_points, 30}};
    std::uint64_t moved = 0;
    for (std::uint64_t seed = 1; seed <= 25; ++seed) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions random;
        random.roads = seed % 3 == 0 ? 2 : 0;
        const MapData map = testing::random_planar_map(rng, random);
        const GridStep step = *GridStep::parse(seed % 2 ? "1" : "5");
        auto on_grid = [&](Point p) { return step.at(*step.nearest(p.x)) == p.x && step.at(*step.nearest(p.y)) == p.y; };
        LevelRounding rounding;
        rounding.grid = [&](const std::vector<std::uint8_t>&) { return OutputGrid(step); };
        SimplifyOptions options;
        options.parallel_threshold = 0;
        options.threads = 1;
        const Levels one = simplify_levels(map, options, levels, &rounding);
        options.threads = 3;
        const Levels three = simplify_levels(map, options, levels, &rounding);
        ASSERT_TRUE(one.rounding && three.rounding);
        const std::vector<Point>& at = one.rounding->at;
        for (std::size_t k = 0; k < levels.size(); ++k) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", level " + std::to_string(k));
            EXPECT_EQ(one.results[k].kept, three.results[k].kept) << "depends on the threads";
            const testing::CheckReport report = testing::check_rounded(map, one.results[k].kept, at, on_grid);
            EXPECT_TRUE(report.ok()) << report.summary();
            for (std::size_t v = 0; k > 0 && v < map.vertices.size(); ++v) {
                EXPECT_LE(one.results[k].kept[v], one.results[k - 1].kept[v]) << v;
            }
        }
        for (std::size_t v = 0; v < map.vertices.size(); ++v) {
            EXPECT_TRUE(!one.results[0].kept[v] || (at[v].x == three.rounding->at[v].x && at[v].y == three.rounding->at[v].y));
            if (one.results[0].kept[v] && (at[v].x != map.vertices[v].x || at[v].y != map.vertices[v].y)) ++moved;
        }
    }
    EXPECT_GT(moved, 0u) << "the grids moved nothing: the test tests nothing";
}

}  // namespace
}  // namespace toposimp::map

namespace toposimp::map {
namespace {

// Which of two bumps on a line goes first, with one vertex to remove.
std::uint32_t first_removed(const MapData& map, const Ranking& ranking) {
    SimplifyOptions options;
    options.ranking = ranking;
    options.stop = {Target::remove_points, 1};
    const SimplifyResult result = simplify(map, options);
    for (std::uint32_t v = 0; v < result.kept.size(); ++v) {
        if (!result.kept[v]) return v;
    }
    return ~0u;
}

// A triangle near the pole is smaller than one at the equator with the same size in degrees²:
// on the sphere it ranks by its true size.
TEST(Ranking, SphericalAreasRankAHighLatitudeTriangleByItsTrueSize) {
    MapData map;
    // Bump 1 at the equator, 0.010 degrees high; bump 2 at 80° N, 0.011 degrees high (bigger in
    // degrees², about 0.19 times the size on the Earth).
    map.add_chain({{0, 0}, {0.5, 0.010}, {1, 0}});
    map.add_chain({{0, 80}, {0.5, 80.011}, {1, 80}});
    EXPECT_EQ(first_removed(map, {}), 1u);                // plain: the equator's, smaller in degrees²
    EXPECT_EQ(first_removed(map, {0, true}), 4u);         // on the sphere: the polar one
}

// Weighted Visvalingam removes a spike before a blunt bump of the same area.
TEST(Ranking, WeightingRemovesSharpAnglesFirst) {
    MapData map;
    map.add_chain({{0, 0}, {0.05, 1.0}, {0.1, 0}});    // a spike: area 0.05, angle about 6°
    map.add_chain({{10, 0}, {10.5, 0.099}, {11, 0}});  // blunt: area 0.0495, angle about 157°
    EXPECT_EQ(first_removed(map, {}), 4u);           // plain: the smaller area
    EXPECT_EQ(first_removed(map, {0.7, false}), 1u); // weighted: the spike
}

// Weighted and spherical ranking: clean by the independent checker and the same on any number of
// threads.
TEST(Ranking, WeightedSphericalIsCleanAndThreadIndependent) {
    for (std::uint64_t seed = 1; seed <= 15; ++seed) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions random;
        random.origin_x = -30;
        random.origin_y = 40;
        random.extent = 40;  // degrees, up to 80° N
        const MapData map = testing::random_planar_map(rng, random);
        SimplifyOptions options;
        options.ranking = {0.7, true};
        options.stop = {Target::keep_fraction, 0.3};
        options.parallel_threshold = 0;
        options.threads = 1;
        const SimplifyResult one = simplify(map, options);
        options.threads = 3;
        const SimplifyResult three = simplify(map, options);
        EXPECT_EQ(one.kept, three.kept) << seed;
        const testing::CheckReport report = testing::check_simplification(map, one.kept);
        EXPECT_TRUE(report.ok()) << seed << report.summary();
    }
}

}  // namespace
}  // namespace toposimp::map
