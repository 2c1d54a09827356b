// The engine in parts (core/map/tiles.hpp): tiles simplified on their own below the tile level,
// then the levels above over the whole map, give simplify()'s result exactly.
#include "core/map/tiles.hpp"

#include "core/cancel.hpp"
#include "core/parallel/side_by_side.hpp"
#include "support/random_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>

namespace toposimp::map {
namespace {

void expect_same(const SimplifyResult& parts, const SimplifyResult& whole, const std::string& what) {
    EXPECT_EQ(parts.kept, whole.kept) << what;
    EXPECT_EQ(parts.stats.removed, whole.stats.removed) << what;
    EXPECT_EQ(parts.stats.blocked_by_point, whole.stats.blocked_by_point) << what;
    EXPECT_EQ(parts.stats.blocked_by_ring, whole.stats.blocked_by_ring) << what;
    EXPECT_EQ(parts.stats.blocked_by_coincidence, whole.stats.blocked_by_coincidence) << what;
    EXPECT_EQ(parts.stats.pinned_by_crossing, whole.stats.pinned_by_crossing) << what;
    EXPECT_EQ(parts.stats.control_points, whole.stats.control_points) << what;
    EXPECT_EQ(parts.stats.levels, whole.stats.levels) << what;
    EXPECT_EQ(parts.stats.rounds, whole.stats.rounds) << what;
    EXPECT_EQ(parts.stats.predicates.filter_decided, whole.stats.predicates.filter_decided) << what;
    EXPECT_EQ(parts.stats.predicates.expansion_decided, whole.stats.predicates.expansion_decided) << what;
    EXPECT_EQ(parts.stats.predicates.gmp_fallbacks, whole.stats.predicates.gmp_fallbacks) << what;
    EXPECT_EQ(parts.stats.removal_goal, whole.stats.removal_goal) << what;
    EXPECT_EQ(parts.stats.target_reached, whole.stats.target_reached) << what;
    EXPECT_EQ(parts.stats.swept_as_max, whole.stats.swept_as_max) << what;
}

// The same but for the predicates' counts, which a first round built by parts (FirstRound) counts
// otherwise in its crossing search.
void expect_same_but_predicates(const SimplifyResult& parts, const SimplifyResult& whole, const std::string& what) {
    SimplifyResult same = parts;
    same.stats.predicates = whole.stats.predicates;
    expect_same(same, whole, what);
    EXPECT_EQ(parts.stats.vertices_in, whole.stats.vertices_in) << what;
    EXPECT_EQ(parts.stats.vertices_out, whole.stats.vertices_out) << what;
}

// simplify_in_tiles as it is, and keeping the live vertices only from the first round's tiles on
// (then also with the levels above the tiles and the small rounds run by that engine itself), and
// with the first round built by parts, and with nothing over the whole map (kept tiles alone).
void expect_same_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, const SimplifyResult& whole,
                          const std::string& what) {
    expect_same(simplify_in_tiles(map, options, tile_level), whole, what);
    expect_same(simplify_in_tiles(map, options, tile_level, 0, false, true), whole, what + ", live only");
    expect_same(simplify_in_tiles(map, options, tile_level, whole.stats.removed / 8, true, true), whole,
                what + ", live only, small rounds and the levels above here");
    expect_same_but_predicates(simplify_by_parts(map, options, tile_level, 64), whole, what + ", by parts");
    expect_same(simplify_in_tiles(map, options, tile_level, 0, false, false, 4), whole, what + ", the top over a subset");
    expect_same(simplify_in_tiles(map, options, tile_level, 0, false, true, 1), whole,
                what + ", live only, the top over a subset with runs of 1 at first");
    expect_same_but_predicates(simplify_with_kept_tiles(map, options, tile_level, 64, 1), whole, what + ", kept tiles alone");
}

// A random map of 100 chains (up to 50 steps each) and 40 rings, 800 control points and `roads`
// roads crossing it; `big`: 150 chains (60 steps), 60 rings, 1 500 points, for 4–5 levels of
// blocks; from x = origin_x.
MapData random_map(std::uint64_t seed, int roads, bool big = false, double origin_x = 0) {
    std::mt19937_64 rng(seed);
    testing::RandomMapOptions shape;
    shape.chains = big ? 150 : 100;
    shape.max_steps = big ? 60 : 50;
    shape.rings = big ? 60 : 40;
    shape.control_points = big ? 1500 : 800;
    shape.roads = roads;
    shape.origin_x = origin_x;
    return testing::random_planar_map(rng, shape);
}

// Options for `stop` on two threads, in parallel however small the map.
SimplifyOptions on_two_threads(StopCriterion stop) {
    SimplifyOptions options;
    options.parallel_threshold = 0;
    options.threads = 2;
    options.stop = stop;
    return options;
}

// Big enough random maps for 4–5 levels of blocks: every tile level from 0 (no level in tiles)
// to the top (one tile, nothing above), the levels from the tile level up as one more tile; and
// at each level one of the other ways in turn: those levels over the whole map's engine, small
// rounds run whole, the live vertices only from the first round's tiles on, the first round by
// parts. One test per map (seed), so that each stays well under a debug build's time limit.
class MapTilesEveryLevel : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(MapTilesEveryLevel, GivesTheSingleProcessResult) {
    const std::uint64_t seed = GetParam();
    const MapData map = random_map(seed, seed % 2 == 0 ? 6 : 0, true, seed == 3 ? 1e6 : 0);
    const GridPlan plan = plan_grid(map);
    ASSERT_GE(plan.levels, 3u) << "the map should have several levels of blocks";
    // Count targets that rounds reach: removing 60 % or 30 % of what --max removes (the roads'
    // crossings pin many vertices: 10 % of the vertices, say, no run could reach).
    double most = 0;
    for (const Target target : {Target::max, Target::max_area, Target::keep_fraction, Target::keep_points}) {
        SimplifyOptions options;
        const double all = static_cast<double>(map.vertices.size());
        options.stop = {target, target == Target::keep_fraction ? 1 - 0.6 * most / all : target == Target::keep_points ? all - 0.3 * most : 2.0};
        options.parallel_threshold = 0;
        options.threads = 2;
        const SimplifyResult whole = simplify(map, options);
        ASSERT_GT(whole.stats.removed, 0u);
        ASSERT_FALSE(whole.stats.swept_as_max) << "count targets here run in rounds";
        if (target == Target::max) most = static_cast<double>(whole.stats.removed);
        for (unsigned tile_level = 0; tile_level <= plan.levels; ++tile_level) {
            const std::string what = "seed " + std::to_string(seed) + ", target " + std::to_string(static_cast<int>(target)) +
                                     ", tile level " + std::to_string(tile_level);
            expect_same(simplify_in_tiles(map, options, tile_level), whole, what);
            // The levels from the tile level up over a subset of the live vertices, its runs
            // short (1, often too short) or not, over the whole map's engine or the live one.
            expect_same(simplify_in_tiles(map, options, tile_level, 0, false, seed % 2 == 0, tile_level % 2 == 0 ? 1 : 4), whole,
                        what + ", the top over a subset");
            // And one of the other ways to run in parts, in turn (all of them at every level
            // is too slow for a debug build).
            const std::uint64_t small = whole.stats.removed / 8;
            const std::size_t part = map.vertices.size() / 3;
            switch ((seed + static_cast<std::uint64_t>(target) + tile_level) % 7) {
                case 0:  // the levels from the tile level up over the whole map's engine, not as one more tile
                    expect_same(simplify_in_tiles(map, options, tile_level, 0, true), whole, what + ", the levels above here");
                    break;
                case 1:  // small rounds here, big ones in tiles
                    expect_same(simplify_in_tiles(map, options, tile_level, small), whole, what + ", small rounds here");
                    break;
                case 2:  // the live vertices only from the first round's tiles on
                    expect_same(simplify_in_tiles(map, options, tile_level, 0, false, true), whole, what + ", live only");
                    break;
                case 3:
                    expect_same(simplify_in_tiles(map, options, tile_level, small, true, true), whole,
                                what + ", live only, small rounds and the levels above here");
                    break;
                case 4:  // the first round built by parts: of one chain, a third of the map, all of it
                    expect_same_but_predicates(simplify_by_parts(map, options, tile_level, 1), whole, what + ", by parts of 1");
                    break;
                case 5:
                    expect_same_but_predicates(simplify_by_parts(map, options, tile_level, part), whole, what + ", by thirds");
                    break;
                default:
                    expect_same_but_predicates(simplify_by_parts(map, options, tile_level, map.vertices.size(), small), whole,
                                               what + ", by parts, small rounds here");
                    break;
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(MapTiles, MapTilesEveryLevel, ::testing::Values(std::uint64_t{1}, 2, 3, 4));

// A count target that no run can reach runs as --max in every way of running in parts too: the
// single process's result, which is --max's.
TEST(MapTiles, ACountTargetNoRunCanReachRunsAsMaxInParts) {
    const MapData map = random_map(5, 4);
    const GridPlan plan = plan_grid(map);
    SimplifyOptions options = on_two_threads({Target::max, 0});
    const SimplifyResult max = simplify(map, options);
    for (const StopCriterion stop : {StopCriterion{Target::keep_points, 0}, StopCriterion{Target::keep_fraction, 0.001}}) {
        options.stop = stop;
        const SimplifyResult whole = simplify(map, options);
        ASSERT_TRUE(whole.stats.swept_as_max);
        ASSERT_EQ(whole.kept, max.kept);
        for (unsigned tile_level = 0; tile_level <= plan.levels; tile_level += 2) {
            expect_same_in_tiles(map, options, tile_level, whole, "tile level " + std::to_string(tile_level));
        }
    }
}

// The tile level set after the engine is built (MapInParts::set_tile_level: toposimp.dask learns
// it from the workers while the set-up and the crossing search run) gives what building it at that
// level gives, capped at the levels; once a round has started it can no longer change.
TEST(MapTiles, TheTileLevelSetAfterTheSetUpIsTheOneBuiltWith) {
    const MapData map = random_map(7, 2);
    const GridPlan plan = plan_grid(map);
    ASSERT_GE(plan.levels, 3u);
    const SimplifyOptions options = on_two_threads({Target::keep_points, static_cast<double>(map.vertices.size()) * 0.8});
    const SimplifyResult whole = simplify(map, options);
    ASSERT_GT(whole.stats.rounds, 1u);
    auto run = [&](MapInParts& parts) {
        while (parts.next_round()) {
            std::vector<TileOutcome> outcomes;
            for (std::vector<TileInput>& group : parts.tile_groups()) {
                for (TileOutcome& outcome : run_tile_group(std::move(group), parts.plan(), options)) outcomes.push_back(std::move(outcome));
            }
            parts.finish_round(outcomes);
        }
        return parts.result();
    };
    for (const unsigned tile_level : {1u, plan.levels - 1, plan.levels + 5}) {
        MapInParts parts(map, options, 0);
        parts.set_tile_level(tile_level);
        EXPECT_EQ(parts.tile_level(), std::min(tile_level, plan.levels));
        expect_same(run(parts), whole, "tile level " + std::to_string(tile_level) + " set after");
    }
    MapInParts started(map, options, 1);
    ASSERT_TRUE(started.next_round());
    EXPECT_THROW(started.set_tile_level(2), std::logic_error);
}

// The first round by parts on what random maps lack: frozen chains (never simplified, yet in the
// crossing search: here roads frozen over the map), chains of one vertex, and long segments
// that pass through tiles holding none of their vertices.
TEST(MapTiles, TheFirstRoundByPartsWithFrozenChainsLoneVerticesAndLongSegments) {
    std::mt19937_64 rng(11);
    testing::RandomMapOptions shape;
    shape.chains = 150;
    shape.max_steps = 60;
    shape.rings = 40;
    shape.control_points = 800;
    shape.roads = 4;
    MapData map = testing::random_planar_map(rng, shape);
    const auto roads = static_cast<std::uint32_t>(map.chains.size());
    map.freeze(roads - 1);
    map.freeze(roads - 3);
    map.add_chain(std::vector<Point>{{50.5, 50.5}});
    map.add_chain(std::vector<Point>{{-1, 1}, {101, 99}});      // corner to corner: through every tile on the way
    map.add_chain(std::vector<Point>{{-1, 99}, {50, 50.25}, {101, 1}});
    const GridPlan plan = plan_grid(map);
    ASSERT_GE(plan.levels, 3u);
    for (const Target target : {Target::max, Target::keep_fraction}) {
        SimplifyOptions options;
        options.stop = {target, 0.6};
        const SimplifyResult whole = simplify(map, options);
        ASSERT_GT(whole.stats.pinned_by_crossing, 0u);
        ASSERT_FALSE(whole.stats.swept_as_max) << "the count target runs in rounds";
        for (unsigned tile_level = 0; tile_level <= plan.levels; ++tile_level) {
            for (const std::size_t part : {std::size_t{1}, std::size_t{500}}) {
                expect_same_but_predicates(simplify_by_parts(map, options, tile_level, part), whole,
                                           "target " + std::to_string(static_cast<int>(target)) + ", tile level " +
                                               std::to_string(tile_level) + ", parts of " + std::to_string(part));
            }
        }
    }
}

// What split_round says of each group before it is built (its tiles, its vertices with cut ends
// and control points: what a distributed run sizes its tasks by) is what group(k) builds, in every
// round; building a group twice gives the same tiles.
TEST(MapTiles, GroupSizesAreWhatTheGroupsHold) {
    std::mt19937_64 rng(7);
    testing::RandomMapOptions shape;
    shape.chains = 150;
    shape.max_steps = 60;
    shape.rings = 60;
    shape.control_points = 1500;
    shape.roads = 6;
    const MapData map = testing::random_planar_map(rng, shape);
    SimplifyOptions options;
    options.stop = {Target::keep_fraction, 0.6};
    options.parallel_threshold = 0;
    MapInParts parts(map, options, 1);
    int rounds = 0, groups_seen = 0;
    while (parts.next_round()) {
        ++rounds;
        const std::size_t groups = parts.split_round();
        std::vector<TileOutcome> outcomes;
        for (std::size_t k = 0; k < groups; ++k) {
            std::vector<TileInput> group = parts.group(k);
            ++groups_seen;
            ASSERT_EQ(parts.group_size(k), group.size());
            std::uint64_t points = 0;
            for (const TileInput& tile : group) points += tile.map.vertices.size() + tile.map.control_points.size();
            EXPECT_EQ(parts.group_points(k), points) << "round " << rounds << ", group " << k;
            const std::vector<TileInput> again = parts.group(k);
            ASSERT_EQ(again.size(), group.size());
            for (std::size_t t = 0; t < group.size(); ++t) {
                EXPECT_EQ(again[t].vertex_id, group[t].vertex_id);
                EXPECT_EQ(again[t].state, group[t].state);
                EXPECT_EQ(again[t].waits, group[t].waits);
            }
            for (TileOutcome& outcome : run_tile_group(std::move(group), parts.plan(), options)) outcomes.push_back(std::move(outcome));
        }
        parts.finish_round(outcomes);
    }
    EXPECT_GT(rounds, 1);
    EXPECT_GT(groups_seen, rounds);
    EXPECT_EQ(parts.result().stats.removed, simplify(map, options).stats.removed);
}

void expect_same_outcome(const TileOutcome& a, const TileOutcome& b, const std::string& what) {
    EXPECT_EQ(a.ids, b.ids) << what;
    EXPECT_EQ(a.states, b.states) << what;
    EXPECT_EQ(a.waits, b.waits) << what;
    // (A later list's order follows the threads that filled it; the engine takes it as a set.)
    ASSERT_EQ(a.later.size(), b.later.size()) << what;
    for (std::size_t k = 0; k < a.later.size(); ++k) {
        std::vector<std::uint32_t> x = a.later[k], y = b.later[k];
        std::sort(x.begin(), x.end());
        std::sort(y.begin(), y.end());
        EXPECT_EQ(x, y) << what << ", level T+" << k;
    }
    EXPECT_EQ(a.locations_lost, b.locations_lost) << what;
    EXPECT_EQ(a.oriented, b.oriented) << what;
    EXPECT_EQ(a.orientations, b.orientations) << what;
    EXPECT_EQ(a.stats.removed, b.stats.removed) << what;
    EXPECT_EQ(a.stats.blocked(), b.stats.blocked()) << what;
    EXPECT_EQ(a.stats.predicates.filter_decided, b.stats.predicates.filter_decided) << what;
    EXPECT_EQ(a.exhausted, b.exhausted) << what;
}

// A task's groups run side by side, a thread each (run_tile_groups, with at least as many groups
// as threads), or one after the other on all threads (fewer): the outcomes of each group run on
// its own, in the groups' order, every round; and the run goes on to the single process's result.
TEST(MapTiles, ATasksGroupsSideBySideGiveEachGroupsOwnOutcomes) {
    const MapData map = random_map(11, 6, true);
    SimplifyOptions options = on_two_threads({Target::keep_fraction, 0.5});
    const SimplifyResult whole = simplify(map, options);
    MapInParts parts(map, options, 1);
    int rounds = 0, side_by_side = 0;
    while (parts.next_round()) {
        ++rounds;
        const std::size_t count = parts.split_round();
        std::vector<std::vector<TileInput>> groups;
        std::vector<std::vector<TileOutcome>> alone;
        for (std::size_t k = 0; k < count; ++k) {
            groups.push_back(parts.group(k));
            alone.push_back(run_tile_group(parts.group(k), parts.plan(), options));
        }
        for (const int threads : {1, 2, 3, 64}) {
            SimplifyOptions task = options;
            task.threads = threads;
            if (count >= static_cast<std::size_t>(threads) && threads > 1) ++side_by_side;
            const std::vector<std::vector<TileOutcome>> together = run_tile_groups(groups, parts.plan(), task);
            ASSERT_EQ(together.size(), count);
            for (std::size_t k = 0; k < count; ++k) {
                ASSERT_EQ(together[k].size(), alone[k].size());
                for (std::size_t t = 0; t < alone[k].size(); ++t) {
                    expect_same_outcome(together[k][t], alone[k][t], "round " + std::to_string(rounds) + ", group " + std::to_string(k) +
                                                                         ", tile " + std::to_string(t) + ", " + std::to_string(threads) +
                                                                         " threads");
                }
            }
        }
        std::vector<TileOutcome> outcomes;
        for (std::vector<TileOutcome>& group : alone) {
            for (TileOutcome& outcome : group) outcomes.push_back(std::move(outcome));
        }
        parts.finish_round(outcomes);
    }
    EXPECT_GT(side_by_side, 1) << "some rounds should have run their groups side by side";
    expect_same(parts.result(), whole, "groups side by side");
}

// A group that throws (here: told to stop) does not end the program from inside the threads
// running the groups side by side: its exception reaches the caller.
TEST(MapTiles, AGroupsExceptionSideBySideReachesTheCaller) {
    const MapData map = random_map(12, 0, true);
    SimplifyOptions options = on_two_threads({Target::keep_fraction, 0.5});
    MapInParts parts(map, options, 1);
    ASSERT_TRUE(parts.next_round());
    const std::size_t count = parts.split_round();
    ASSERT_GE(count, 2u);
    std::vector<std::vector<TileInput>> groups;
    for (std::size_t k = 0; k < count; ++k) groups.push_back(parts.group(k));
    const std::atomic<bool> stop{true};
    options.cancel = &stop;
    EXPECT_THROW(run_tile_groups(groups, parts.plan(), options), Cancelled);
}

// Items side by side (parallel::side_by_side): each runs once, on one thread when there are at
// least as many items as threads, else on all of them in order; of several that throw, the first
// in order reaches the caller either way.
TEST(SideBySide, EachItemRunsOnceAndTheFirstErrorInOrderReachesTheCaller) {
    for (const int threads : {1, 2, 3, 8, 9}) {
        std::vector<int> ran(8, 0), given(8, 0);
        std::atomic<int> calls{0};
        const auto throwing = [&](std::size_t k, int each) {
            ++calls;
            ran[k] += 1;
            given[k] = each;
            if (k == 3 || k == 5) throw std::runtime_error(std::to_string(k));
        };
        try {
            parallel::side_by_side(ran.size(), threads, [](std::size_t k) { return k % 3; }, throwing);
            ADD_FAILURE() << "no exception at " << threads << " threads";
        } catch (const std::runtime_error& error) {
            EXPECT_STREQ(error.what(), "3") << threads << " threads";
        }
        const bool side = threads >= 2 && threads <= 8;
        EXPECT_EQ(calls.load(), side ? 8 : 4) << threads << " threads";  // (in order, the run stops at item 3)
        for (std::size_t k = 0; k < ran.size(); ++k) {
            if (!side && k > 3) continue;
            EXPECT_EQ(ran[k], 1) << "item " << k << ", " << threads << " threads";
            EXPECT_EQ(given[k], side ? 1 : threads) << "item " << k << ", " << threads << " threads";
        }
    }
}

// A ring whose only segments across the tile border are one segment out and the same one back
// (A, B, A): its cut ends hold 2 locations, so its pieces cannot settle the ring rule alone; the
// tiles tell each other their fixed locations level by level (here the fold-back rule would keep
// the ring's shape even if they did not: this test shows what they say, and that the result is
// still the single process's).
TEST(MapTiles, ARingWithOneSegmentOutAndBackIsDecidedOverAllTiles) {
    MapData background;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> coordinate(0, 100);
    for (int k = 0; k < 20000; ++k) background.control_points.push_back({coordinate(rng), coordinate(rng)});
    background.control_points.push_back({0, 0});
    background.control_points.push_back({100, 100});
    // The plan does not depend on where the ring's 9 vertices are, only on their number.
    MapData sized = background;
    sized.add_chain(std::vector<Point>(9, Point{50, 50}));
    const GridPlan plan = plan_grid(sized);
    ASSERT_GE(plan.levels, 4u);
    // The border between the two halves of the top block: a tile border at every level below it.
    const std::uint32_t border_column = 1u << (plan.shift + plan.levels - 2);
    double left = 0, right = 100;  // base_column(left) < border_column ≤ base_column(right)
    for (int step = 0; step < 200; ++step) {
        const double middle = 0.5 * (left + right);
        (plan.grid.base_column(middle) < border_column ? left : right) = middle;
    }
    const double cell = 100.0 / plan.grid.base_columns;
    const double a = left - 0.25 * cell, b = right + 0.25 * cell;  // A in the left half, B in the right
    ASSERT_LT(plan.grid.base_column(a), border_column);
    ASSERT_GE(plan.grid.base_column(b), border_column);
    MapData map;
    const std::vector<Point> ring = {{a, 50},           {b, 50.5},           {a, 50},
                                     {a - cell, 51},    {a - 2 * cell, 50.5}, {a - 2.5 * cell, 49.5},
                                     {a - 1.5 * cell, 49}, {a - 0.5 * cell, 49.5}, {a, 50}};
    map.add_chain(ring);
    for (const Point p : background.control_points) {
        if (std::fabs(p.x - a) > 4 * cell || std::fabs(p.y - 50) > 3 * cell) map.control_points.push_back(p);
    }
    while (map.vertices.size() + map.control_points.size() < sized.vertices.size() + sized.control_points.size()) {
        map.control_points.push_back({0, 100});
    }
    ASSERT_EQ(plan_grid(map).shift, plan.shift);
    ASSERT_EQ(plan_grid(map).grid.base_columns, plan.grid.base_columns);

    SimplifyOptions options;
    options.stop = {Target::max, 0};
    const SimplifyResult whole = simplify(map, options);
    std::vector<Point> kept;
    for (std::uint32_t v = 0; v < ring.size(); ++v) {
        if (whole.kept[v] && std::none_of(kept.begin(), kept.end(), [&](Point q) { return same_location(q, ring[v]); })) {
            kept.push_back(ring[v]);
        }
    }
    EXPECT_GE(kept.size(), 3u) << "the ring rule keeps 3 locations or more";
    EXPECT_LE(kept.size(), 4u) << "the bulk of the ring should simplify";

    // The tiles at level 1: the ring's pieces are not settled, and at level 0 their fixed
    // locations are A and B only (A's vertices and B are fixed: chain ends and cut ends; the
    // q's are of level 0), so the ring is not clear there.
    std::vector<Point> fixed;
    int pieces = 0;
    MapInParts parts(map, options, 1);
    ASSERT_TRUE(parts.next_round());
    std::vector<TileInput> tiles;
    for (std::vector<TileInput>& group : parts.tile_groups()) {
        for (TileInput& tile : group) tiles.push_back(std::move(tile));
    }
    const std::size_t tile_count = tiles.size();
    for (TileInput& tile : tiles) {
        for (std::size_t c = 0; c < tile.chain_id.size(); ++c) {
            if (tile.chain_id[c] != 0) continue;
            ++pieces;
            EXPECT_EQ(tile.settled[c], 0) << "two cut-end locations cannot settle the ring";
        }
        TileRun run(std::move(tile), plan, options);
        for (const RingLocations& open : run.open_rings(0)) {
            ASSERT_EQ(open.chain, 0u);
            for (const Point q : open.locations) {
                if (std::none_of(fixed.begin(), fixed.end(), [&](Point f) { return same_location(f, q); })) fixed.push_back(q);
            }
        }
    }
    EXPECT_EQ(pieces, 3) << "A–B on the left, B's piece on the right, B–A–q…–A on the left";
    // The two tiles holding its pieces run as one group; every other tile alone.
    MapInParts again(map, options, 1);
    ASSERT_TRUE(again.next_round());
    const std::vector<std::vector<TileInput>> groups = again.tile_groups();
    EXPECT_EQ(groups.size(), tile_count - 1);
    for (const std::vector<TileInput>& group : groups) {
        const bool holds = std::any_of(group.front().chain_id.begin(), group.front().chain_id.end(), [](std::uint32_t c) { return c == 0; });
        EXPECT_EQ(group.size(), holds ? 2u : 1u);
    }
    ASSERT_EQ(fixed.size(), 2u);
    EXPECT_TRUE(same_location(fixed[0], ring[0]) || same_location(fixed[1], ring[0]));
    EXPECT_TRUE(same_location(fixed[0], ring[1]) || same_location(fixed[1], ring[1]));
    for (unsigned tile_level = 0; tile_level <= plan.levels; ++tile_level) {
        expect_same_in_tiles(map, options, tile_level, whole, "tile level " + std::to_string(tile_level));
    }
}

// Control points over [0, 100]² that fix the plan before a test's vertices go in (the plan
// depends on the extent and the number of points only), and places in it: the border between the
// top block's two halves (a tile border at every level below), the middle of a level-0 block row.
struct Backdrop {
    GridPlan plan;
    double border = 0, row = 0, cell = 0;
    std::vector<Point> points;
    std::size_t total = 0;  // vertices and control points the plan is made for

    Backdrop(std::size_t vertices, std::uint64_t seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> coordinate(0, 100);
        for (int k = 0; k < 20000; ++k) points.push_back({coordinate(rng), coordinate(rng)});
        points.push_back({0, 0});
        points.push_back({100, 100});
        MapData sized;
        sized.control_points = points;
        sized.add_chain(std::vector<Point>(vertices, Point{50, 50}));
        plan = plan_grid(sized);
        total = vertices + points.size();
        auto boundary = [](auto&& below, double lo, double hi) {
            for (int step = 0; step < 200; ++step) {
                const double middle = 0.5 * (lo + hi);
                (below(middle) ? lo : hi) = middle;
            }
            return hi;
        };
        const std::uint32_t half = 1u << (plan.shift + plan.levels - 2);
        border = boundary([&](double v) { return plan.grid.base_column(v) < half; }, 0, 100);
        cell = 100.0 / plan.grid.base_columns;
        const std::uint32_t block_row = (plan.grid.base_rows >> (plan.shift + 1)) << plan.shift;  // a level-0 block row's first
        row = boundary([&](double v) { return plan.grid.base_row(v) < block_row; }, 0, 100) + 4 * cell;
    }

    // The backdrop's points into `map`, but those `near` its vertices, then padding up to the count.
    template <class Near>
    void fill(MapData& map, Near&& near) const {
        for (const Point q : points) {
            if (!near(q)) map.control_points.push_back(q);
        }
        while (map.vertices.size() + map.control_points.size() < total) map.control_points.push_back({100, 0});
    }
};

// A wait across tiles that a later round ends: in round 1, w (its neighbours in two tiles, so of a
// level above the tiles) waits on b, a vertex of another line inside w's triangle but in the
// other tile, outside the round's budget; in round 2, b goes at level 0 in its tile, which frees
// w, removed in round 3. (Were the wait not ended when b goes in its tile, w would wait forever.)
TEST(MapTiles, AWaitAcrossTilesEndsWhenItsBlockerGoesInAnotherTile) {
    const Backdrop backdrop(14, 5);
    const GridPlan& plan = backdrop.plan;
    ASSERT_GE(plan.levels, 4u);
    const double x = backdrop.border, y = backdrop.row, c = backdrop.cell;

    MapData map;
    map.add_chain({{x - 3 * c, y}, {x - 0.5 * c, y + 0.1 * c}, {x + 3 * c, y}});           // p, w, n: w's area 0.3 c²
    map.add_chain({{x + 0.1 * c, y - 2 * c}, {x + 0.5 * c, y + 0.03 * c}, {x + 0.9 * c, y - 2 * c}});  // b in w's triangle: 0.81 c²
    const double dx = x - 30 * c, cx = x - 50 * c;
    map.add_chain({{dx, y}, {dx + 0.5 * c, y + c}, {dx + c, y}});  // 0.5 c², and a control point in its triangle
    std::vector<Point> filler;                                       // tiny areas: round 1 takes them
    for (int k = 0; k < 5; ++k) filler.push_back({cx + 0.3 * c * k, y + (k % 2) * 0.001 * c});
    map.add_chain(filler);
    map.control_points.push_back({dx + 0.5 * c, y + 0.5 * c});
    backdrop.fill(map, [&](Point q) {
        return std::fabs(q.y - y) < 6 * c && (std::fabs(q.x - x) < 6 * c || std::fabs(q.x - dx) < 4 * c || std::fabs(q.x - cx) < 4 * c);
    });
    ASSERT_EQ(plan_grid(map).shift, plan.shift);
    ASSERT_EQ(plan_grid(map).grid.base_columns, plan.grid.base_columns);

    SimplifyOptions options;
    options.stop = {Target::keep_points, 9};  // remove 5: the filler's 3, w and b
    const SimplifyResult whole = simplify(map, options);
    ASSERT_EQ(whole.stats.removed, 5u);
    EXPECT_EQ(whole.kept[1], 0) << "w went";
    EXPECT_EQ(whole.kept[4], 0) << "b went";
    EXPECT_EQ(whole.stats.rounds, 3u) << "w waited on b, which went in round 2";
    for (unsigned tile_level = 0; tile_level + 1 < plan.levels; ++tile_level) {
        expect_same_in_tiles(map, options, tile_level, whole, "tile level " + std::to_string(tile_level));
    }
}

// A ring that touches itself (a figure eight pinched at p): its left lobe, a circle of 60
// vertices, goes down to p and two vertices, where every removal would fold it onto itself (the
// coincident-segment rule); the pinch never goes (the ring's ends lie in its triangle); the right
// lobe, a triangle, stays. The ring spans the map's middle, so its last removals are decided
// above the tiles at every tile level but the top.
TEST(MapTiles, APinchedRingKeepsItsLobesAtEveryTileLevel) {
    const Backdrop backdrop(64, 7);
    const GridPlan& plan = backdrop.plan;
    ASSERT_GE(plan.levels, 4u);
    const Point p{50, 50};
    std::vector<Point> ring{p};
    constexpr int kLeft = 60;
    for (int k = 1; k < kLeft; ++k) {
        const double angle = 2 * std::acos(-1.0) * k / kLeft;
        ring.push_back({40 + 10 * std::cos(angle), 50 + 10 * std::sin(angle)});
    }
    for (const Point q : {p, Point{70, 60}, Point{70, 40}, p}) ring.push_back(q);
    MapData map;
    map.add_chain(ring);
    backdrop.fill(map, [&](Point q) {
        return std::hypot(q.x - 40, q.y - 50) < 10.5 || (q.x > 49 && q.x < 71 && q.y > 39 && q.y < 61);
    });
    ASSERT_EQ(plan_grid(map).levels, plan.levels);
    std::uint64_t max_kept = 0;
    for (const Target target : {Target::max, Target::keep_points}) {
        SimplifyOptions options;
        // The count target: what --max keeps, reached in rounds (3, say, no run could reach: it
        // would run as --max).
        options.stop = {target, static_cast<double>(max_kept)};
        const SimplifyResult whole = simplify(map, options);
        max_kept = whole.stats.vertices_out;
        EXPECT_EQ(whole.stats.swept_as_max, false);
        EXPECT_EQ(whole.stats.rounds > 0, target == Target::keep_points);
        const std::vector<std::uint8_t> ring_kept(whole.kept.begin(), whole.kept.begin() + static_cast<std::ptrdiff_t>(ring.size()));
        EXPECT_EQ(std::count(ring_kept.begin() + 1, ring_kept.begin() + kLeft, 1), 2) << "two of the left lobe's vertices stay";
        for (std::size_t v = kLeft; v < ring.size(); ++v) EXPECT_EQ(ring_kept[v], 1) << "the pinch and the right lobe stay";
        if (target == Target::max) {
            EXPECT_GT(whole.stats.blocked_by_coincidence, 0u);  // (the rounds need not try)
        }
        for (unsigned tile_level = 0; tile_level <= plan.levels; ++tile_level) {
            expect_same_in_tiles(map, options, tile_level, whole,
                        "target " + std::to_string(static_cast<int>(target)) + ", tile level " + std::to_string(tile_level));
        }
    }
}

// A wait inside one tile while that tile sits out a round (no vertex of it in the budget): in
// round 1, w waits on b (both in the left tile, b outside the budget); in round 2 the budget is
// all in the right tile; in round 3 b goes, which must free w, removed in round 4.
TEST(MapTiles, AWaitInATileThatSitsOutARoundHolds) {
    const Backdrop backdrop(3 + 3 + 5 * 3, 6);
    const GridPlan& plan = backdrop.plan;
    ASSERT_GE(plan.levels, 4u);
    const double c = backdrop.cell, y = backdrop.row + c;
    const double x = backdrop.border - 4 * c;  // the middle of the left tile's last level-0 block
    MapData map;
    map.add_chain({{x - c, y}, {x, y + 0.02 * c}, {x + c, y}});                                // w: 0.02 c²
    map.add_chain({{x + 0.1 * c, y - 2 * c}, {x + 0.2 * c, y + 0.005 * c}, {x + 0.3 * c, y - 2 * c}});  // b in w's triangle: 0.2 c²
    const double ax = backdrop.border + 20 * c;  // the right tile: a1…a4 refused (a control point each), a5 free
    for (int k = 0; k < 5; ++k) {
        const double ay = y + 2 * c * (k - 2), h = (0.1 + 0.02 * k) * c;  // areas 0.05 … 0.09 c²
        map.add_chain({{ax - 0.5 * c, ay}, {ax, ay + h}, {ax + 0.5 * c, ay}});
        if (k < 4) map.control_points.push_back({ax, ay + h / 3});
    }
    backdrop.fill(map, [&](Point q) {
        return std::fabs(q.y - y) < 8 * c && (std::fabs(q.x - x) < 4 * c || std::fabs(q.x - ax) < 3 * c);
    });
    ASSERT_EQ(plan_grid(map).shift, plan.shift);
    ASSERT_EQ(plan_grid(map).grid.base_columns, plan.grid.base_columns);

    SimplifyOptions options;
    options.stop = {Target::remove_points, 3};  // a5, b and w
    const SimplifyResult whole = simplify(map, options);
    ASSERT_EQ(whole.stats.removed, 3u);
    EXPECT_EQ(whole.kept[1], 0) << "w went";
    EXPECT_EQ(whole.kept[4], 0) << "b went";
    EXPECT_EQ(whole.stats.rounds, 4u);
    for (unsigned tile_level = 0; tile_level + 1 < plan.levels; ++tile_level) {
        expect_same_in_tiles(map, options, tile_level, whole, "tile level " + std::to_string(tile_level));
    }
}

// The late rounds of a count target in one process select among the few vertices the round
// before left near its bound (mark_few); runs in parts select among every queued vertex. Maps
// that reach their targets in many rounds, the same marks either way, on 1 and 2 threads.
TEST(MapTiles, LateRoundsSelectAmongTheFewTheRoundBeforeLeftAsAmongAll) {
    for (const std::uint64_t seed : {11, 12}) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions shape;
        shape.chains = 400;
        shape.max_steps = 120;
        shape.rings = 150;
        shape.control_points = 3000;
        shape.roads = seed == 12 ? 6 : 0;
        const MapData map = testing::random_planar_map(rng, shape);
        for (const double keep : {0.7, 0.6}) {
            for (const int threads : {1, 2}) {
                SimplifyOptions options;
                options.stop = {Target::keep_fraction, keep};
                options.parallel_threshold = 0;
                options.threads = threads;
                const SimplifyResult whole = simplify(map, options);
                const std::string what = "seed " + std::to_string(seed) + ", keep " + std::to_string(keep) + ", " +
                                         std::to_string(threads) + " threads";
                EXPECT_GT(whole.stats.rounds_from_few, 0u) << what;
                EXPECT_LT(whole.stats.rounds_from_few, whole.stats.rounds) << what << ": the first round looks at all";
                expect_same(simplify_in_tiles(map, options, 0), whole, what);
                expect_same(simplify_in_tiles(map, options, 2, whole.stats.removed / 8, true, true), whole, what + ", in tiles");
            }
        }
    }
}

// Equal areas everywhere (zigzags on a small integer lattice): a count target's rounds end on a tie,
// broken by whole-map ids, which each tile must compare as the single process does.
TEST(MapTiles, TiesAtARoundsBoundAreBrokenByWholeMapIds) {
    MapData map;
    std::mt19937_64 rng(8);
    for (int row = 0; row < 60; ++row) {
        for (int column = 0; column < 6; ++column) {
            std::vector<Point> zigzag;
            double x = column * 80.0;
            for (int k = 0; k < 30; ++k) {
                zigzag.push_back({x, row * 4.0 + static_cast<double>(rng() % 3)});
                x += static_cast<double>(1 + rng() % 2);
            }
            map.add_chain(zigzag);
        }
    }
    const GridPlan plan = plan_grid(map);
    ASSERT_GE(plan.levels, 3u);
    for (const double keep : {0.5, 0.3, 0.1}) {
        SimplifyOptions options;
        options.stop = {Target::keep_fraction, keep};
        const SimplifyResult whole = simplify(map, options);
        ASSERT_TRUE(whole.stats.target_reached);
        // (At 50 % and 30 % the late rounds' budgets are small enough for mark_few: the ties fall to it too.)
        if (keep >= 0.3) {
            EXPECT_GT(whole.stats.rounds_from_few, 0u) << "keep " << keep;
        }
        for (unsigned tile_level = 0; tile_level <= plan.levels; ++tile_level) {
            expect_same_in_tiles(map, options, tile_level, whole,
                        "keep " + std::to_string(keep) + ", tile level " + std::to_string(tile_level));
        }
    }
}

// The levels above the tiles as one more tile (MapInParts::top): it holds the live vertices
// only, in whole-map order, and the control points that can lie in a triangle there — those
// near a run of unfixed vertices — not the others. One line zigzags across the map's middle, among
// the backdrop's points.
TEST(MapTiles, TheTopHoldsTheLiveVerticesAndThePointsNearTheirRuns) {
    const Backdrop backdrop(121, 9);
    const GridPlan& plan = backdrop.plan;
    ASSERT_GE(plan.levels, 4u);
    std::vector<Point> line;
    for (int k = 0; k <= 120; ++k) line.push_back({20 + 0.5 * k, 50 + (k % 2 == 0 ? 0.0 : 0.6)});
    MapData map;
    map.add_chain(line);
    backdrop.fill(map, [](Point) { return false; });
    ASSERT_EQ(plan_grid(map).levels, plan.levels);
    // How far outside the line's box a kept point may be: a level-0 block.
    const double block = 100.0 / plan.grid.base_columns * static_cast<double>(1u << plan.shift);
    SimplifyOptions options;
    options.stop = {Target::max, 0};
    const SimplifyResult whole = simplify(map, options);
    for (unsigned tile_level = 1; tile_level + 1 < plan.levels; ++tile_level) {
        MapInParts parts(map, options, tile_level);
        ASSERT_TRUE(parts.next_round());
        std::vector<TileOutcome> outcomes;
        for (std::vector<TileInput>& group : parts.tile_groups()) {
            for (TileOutcome& outcome : run_tile_group(std::move(group), parts.plan(), options)) outcomes.push_back(std::move(outcome));
        }
        std::vector<std::uint8_t> removed(map.vertices.size(), 0);
        for (const TileOutcome& outcome : outcomes) {
            for (std::size_t k = 0; k < outcome.ids.size(); ++k) removed[outcome.ids[k]] = outcome.states[k] == static_cast<std::uint8_t>(VertexState::removed);
        }
        ASSERT_TRUE(parts.finish_tiles(outcomes)) << "the line crosses the middle: its last vertices go above the tiles";
        const TileInput top = parts.top();
        EXPECT_EQ(top.level, plan.levels);
        EXPECT_EQ(top.first_level, tile_level);
        std::vector<std::uint32_t> live;
        for (std::uint32_t v = 0; v < map.vertices.size(); ++v) {
            if (!removed[v]) live.push_back(v);
        }
        EXPECT_EQ(top.vertex_id, live) << "tile level " << tile_level;
        EXPECT_LT(live.size(), line.size()) << "the tiles removed some";
        std::size_t near = 0;
        for (const Point q : map.control_points) near += q.x >= 20 && q.x <= 80 && q.y >= 50 && q.y <= 50.6;
        std::size_t kept_near = 0;
        for (const Point q : top.map.control_points) {
            kept_near += q.x >= 20 && q.x <= 80 && q.y >= 50 && q.y <= 50.6;
            EXPECT_TRUE(q.x > 20 - block && q.x < 80 + block && q.y > 50 - block && q.y < 50.6 + block) << q.x << " " << q.y;
        }
        EXPECT_GT(near, 10u);
        EXPECT_EQ(kept_near, near) << "every point in the line's box is kept";
        EXPECT_LT(top.map.control_points.size(), map.control_points.size() / 10);
        std::vector<TileInput> one;
        one.push_back(top);
        parts.finish_top(run_tile_group(std::move(one), parts.plan(), options).front());
        EXPECT_FALSE(parts.next_round());
        expect_same(parts.result(), whole, "tile level " + std::to_string(tile_level));
    }
}

// The tiles of a level partition the map's vertices and control points, and each piece ends
// with its cut ends: the vertices beyond the tile's border.
// Concentric wavy rings around the map's middle, each of `vertices` vertices (every level of
// blocks cuts them), random control points between them, and straight roads across at the
// quarters, eighths, … of the map (`roads` of them each way, where the block levels' seams
// lie): the rings' vertices where they cross are pinned.
MapData wavy_rings(std::uint64_t seed, int rings, int vertices, int points, int roads) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> wave(-1.5, 1.5), anywhere(0, 100);
    MapData map;
    for (int r = 0; r < rings; ++r) {
        std::vector<Point> ring;
        for (int k = 0; k < vertices; ++k) {
            const double angle = 2 * M_PI * k / vertices, radius = 8 + 5.0 * r + wave(rng);
            ring.push_back({50 + radius * std::cos(angle), 50 + radius * std::sin(angle)});
        }
        ring.push_back(ring.front());
        map.add_chain(ring);
    }
    for (int k = 0; k < points; ++k) map.control_points.push_back({anywhere(rng), anywhere(rng)});
    for (int k = 1; k <= roads; ++k) {
        const double at = 100.0 * k / (roads + 1) + 0.01;
        map.add_chain(std::vector<Point>{{at, 1}, {at, 99}});
        map.add_chain(std::vector<Point>{{1, at}, {99, at}});
    }
    return map;
}

std::size_t coincidences_checked = 0;  // run vertices and cut ends at a shared location, checked

// The subset's coincidence rule is closed: every live vertex at the location of one of the
// subset's run vertices or cut ends, where more than one live vertex is, is in the subset and in a
// run or a cut end (the rule reads its neighbours), not lone. `live`: MapInParts::top, every live
// vertex.
void expect_coincidences_in_runs(const TileInput& live, const TileInput& subset, const std::string& what) {
    std::map<std::pair<double, double>, std::vector<std::uint32_t>> at;  // location → live vertices' ids
    for (std::size_t i = 0; i < live.vertex_id.size(); ++i) at[{live.map.vertices[i].x, live.map.vertices[i].y}].push_back(live.vertex_id[i]);
    std::map<std::uint32_t, bool> in_run;  // the subset's vertices: in a run or a cut end
    for (const Chain& chain : subset.map.chains) {
        for (std::uint32_t i = chain.first; i <= chain.last; ++i) in_run[subset.vertex_id[i]] = chain.last > chain.first || subset.cut_end[i] != 0;
    }
    std::size_t checked = 0;
    for (const Chain& chain : subset.map.chains) {
        if (chain.last == chain.first && subset.cut_end[chain.first] == 0) continue;
        for (std::uint32_t i = chain.first; i <= chain.last; ++i) {
            const std::vector<std::uint32_t>& here = at[{subset.map.vertices[i].x, subset.map.vertices[i].y}];
            if (here.size() < 2) continue;
            ++checked;
            for (const std::uint32_t id : here) {
                const auto found = in_run.find(id);
                EXPECT_TRUE(found != in_run.end() && found->second) << what << ": vertex " << id << " at the location of run vertex "
                                                                    << subset.vertex_id[i] << (found == in_run.end() ? " is not in the subset" : " is lone");
            }
        }
    }
    coincidences_checked += checked;
}

// The levels from the tile level up over a subset of the live vertices (MapInParts::top_subset)
// on rings the top levels cut into runs — whether such a ring keeps 4 locations at its fixed
// vertices at a level is then decided with those outside the runs — and with runs so short
// that cascades of removals reach their cut ends (the subset then refuses its outcome, and
// longer runs follow): simplify()'s result, every target, tile level and length of runs; and
// the subset is a small part of the live map.
TEST(MapTiles, TheTopOverASubsetOfTheLiveVerticesGivesTheSingleProcessResult) {
    std::size_t exhausted = 0, outside = 0, subsets = 0, small = 0;
    // (The second map: 14 thinner rings, where a run that decided its split rings from the runs'
    // fixed locations alone gets other results with --max.)
    for (const MapData& map : {wavy_rings(7, 8, 1500, 4000, 7), wavy_rings(4, 14, 600, 2000, 0)}) {
        const GridPlan plan = plan_grid(map);
        ASSERT_GE(plan.levels, 4u);
        for (const StopCriterion stop : {StopCriterion{Target::max, 0}, StopCriterion{Target::keep_fraction, 0.1},
                                         StopCriterion{Target::keep_points, 3000}}) {
            SimplifyOptions options = on_two_threads(stop);
            const SimplifyResult whole = simplify(map, options);
            for (unsigned tile_level = 1; tile_level + 1 < plan.levels; ++tile_level) {
                for (const std::uint32_t first_runs : {1u, 4u}) {
                    MapInParts parts(map, options, tile_level);
                    while (parts.next_round()) {
                        std::vector<TileOutcome> outcomes;
                        for (std::vector<TileInput>& group : parts.tile_groups()) {
                            for (TileOutcome& outcome : run_tile_group(std::move(group), parts.plan(), options)) outcomes.push_back(std::move(outcome));
                        }
                        if (!parts.finish_tiles(outcomes)) continue;
                        for (std::uint32_t runs = first_runs;; runs *= 2) {
                            std::vector<TileInput> top;
                            const TileInput live = parts.top();
                            top.push_back(parts.top_subset(runs));
                            expect_coincidences_in_runs(live, top.front(), "runs of " + std::to_string(runs));
                            outside += top.front().outside.size();
                            ++subsets;
                            small += top.front().map.vertices.size() * 4 < map.vertices.size();
                            if (parts.finish_top_subset(run_tile_group(std::move(top), parts.plan(), options).front())) break;
                            ++exhausted;
                        }
                    }
                    expect_same(parts.result(), whole,
                                std::to_string(map.chains.size()) + " chains, target " + std::to_string(static_cast<int>(stop.target)) +
                                    ", tile level " + std::to_string(tile_level) + ", runs of " + std::to_string(first_runs) + " at first");
                }
            }
        }
    }
    EXPECT_GT(exhausted, 0u) << "runs of 1 fall short somewhere";
    EXPECT_GT(coincidences_checked, 0u) << "runs at shared locations";
    EXPECT_GT(outside, 0u) << "rings cut into runs at the levels above the tiles";
    EXPECT_GT(small * 2, subsets) << "most subsets hold under a quarter of the map";
}

TEST(MapTiles, TilesPartitionTheMap) {
    std::mt19937_64 rng(7);
    testing::RandomMapOptions shape;
    shape.chains = 100;
    shape.max_steps = 50;
    shape.control_points = 500;
    const MapData map = testing::random_planar_map(rng, shape);
    const GridPlan plan = plan_grid(map);
    SimplifyOptions options;
    options.stop = {Target::max, 0};
    for (unsigned tile_level = 0; tile_level < plan.levels; ++tile_level) {
        MapInParts parts(map, options, tile_level);
        ASSERT_TRUE(parts.next_round());
        std::vector<TileInput> tiles;
        for (std::vector<TileInput>& group : parts.tile_groups()) {
            for (TileInput& tile : group) tiles.push_back(std::move(tile));
        }
        std::vector<int> inside(map.vertices.size(), 0);
        std::size_t points = 0;
        for (const TileInput& tile : tiles) {
            points += tile.map.control_points.size();
            for (const Point p : tile.map.control_points) {
                EXPECT_EQ(plan.block_column(p, tile_level), tile.column);
                EXPECT_EQ(plan.block_row(p, tile_level), tile.row);
            }
            for (std::uint32_t c = 0; c < tile.map.chains.size(); ++c) {
                const Chain piece = tile.map.chains[c];
                for (std::uint32_t v = piece.first; v <= piece.last; ++v) {
                    const std::uint32_t id = tile.vertex_id[v];
                    EXPECT_TRUE(same_location(tile.map.vertices[v], map.vertices[id]));
                    if (v > piece.first) {
                        EXPECT_EQ(id, tile.vertex_id[v - 1] + 1) << "a piece runs along its chain";
                    }
                    const bool in = plan.block_column(map.vertices[id], tile_level) == tile.column &&
                                    plan.block_row(map.vertices[id], tile_level) == tile.row;
                    EXPECT_TRUE(in || v == piece.first || v == piece.last) << "only a piece's ends lie outside its tile";
                    EXPECT_TRUE(in || piece.last > piece.first) << "a cut end comes with the vertex inside";
                    inside[id] += in;
                }
            }
        }
        // Every control point in a tile with vertices (in the others, nothing is to be done).
        std::size_t expected = 0;
        for (const Point p : map.control_points) {
            expected += std::any_of(tiles.begin(), tiles.end(), [&](const TileInput& tile) {
                return plan.block_column(p, tile_level) == tile.column && plan.block_row(p, tile_level) == tile.row;
            });
        }
        EXPECT_EQ(points, expected);
        EXPECT_GT(points, map.control_points.size() / 2);
        EXPECT_EQ(std::count(inside.begin(), inside.end(), 1), static_cast<std::ptrdiff_t>(map.vertices.size()))
            << "every vertex inside exactly one tile";
    }
}

// Two tiles' inputs, field by field.
void expect_same_input(const TileInput& a, const TileInput& b, const std::string& what) {
    EXPECT_EQ(a.level, b.level) << what;
    EXPECT_EQ(a.column, b.column) << what;
    EXPECT_EQ(a.row, b.row) << what;
    EXPECT_EQ(a.first_level, b.first_level) << what;
    ASSERT_EQ(a.map.vertices.size(), b.map.vertices.size()) << what;
    for (std::size_t v = 0; v < a.map.vertices.size(); ++v) {
        ASSERT_TRUE(a.map.vertices[v].x == b.map.vertices[v].x && a.map.vertices[v].y == b.map.vertices[v].y) << what << ", vertex " << v;
    }
    ASSERT_EQ(a.map.chains.size(), b.map.chains.size()) << what;
    for (std::size_t c = 0; c < a.map.chains.size(); ++c) {
        EXPECT_TRUE(a.map.chains[c].first == b.map.chains[c].first && a.map.chains[c].last == b.map.chains[c].last) << what << ", piece " << c;
    }
    ASSERT_EQ(a.map.control_points.size(), b.map.control_points.size()) << what;
    for (std::size_t k = 0; k < a.map.control_points.size(); ++k) {
        EXPECT_TRUE(a.map.control_points[k].x == b.map.control_points[k].x && a.map.control_points[k].y == b.map.control_points[k].y) << what;
    }
    EXPECT_EQ(a.map.frozen, b.map.frozen) << what;
    EXPECT_EQ(a.vertex_id, b.vertex_id) << what;
    EXPECT_EQ(a.state, b.state) << what;
    EXPECT_EQ(a.marked, b.marked) << what;
    EXPECT_EQ(a.chain_id, b.chain_id) << what;
    EXPECT_EQ(a.whole_level, b.whole_level) << what;
    EXPECT_EQ(a.settled, b.settled) << what;
    EXPECT_EQ(a.distinct, b.distinct) << what;
    EXPECT_EQ(a.orientation, b.orientation) << what;
    EXPECT_EQ(a.waits, b.waits) << what;
    EXPECT_EQ(a.later, b.later) << what;
    EXPECT_EQ(a.marks, b.marks) << what;
    EXPECT_EQ(a.bound_key, b.bound_key) << what;
    EXPECT_EQ(a.bound_id, b.bound_id) << what;
    EXPECT_EQ(a.cut_end, b.cut_end) << what;
    ASSERT_EQ(a.outside.size(), b.outside.size()) << what;
    for (std::size_t k = 0; k < a.outside.size(); ++k) {
        EXPECT_EQ(a.outside[k].chain, b.outside[k].chain) << what;
        EXPECT_EQ(a.outside[k].level, b.outside[k].level) << what;
        ASSERT_EQ(a.outside[k].locations.size(), b.outside[k].locations.size()) << what << ", ring " << a.outside[k].chain;
        for (std::size_t i = 0; i < a.outside[k].locations.size(); ++i) {
            EXPECT_TRUE(same_location(a.outside[k].locations[i], b.outside[k].locations[i])) << what << ", ring " << a.outside[k].chain;
        }
    }
}

// The levels from T up over MapInParts, over the whole live map (runs = 0) or over subsets with
// runs of `runs` at first, each subset gathered from the kept tiles too (KeptTiles::top_subset)
// and checked against MapInParts's; their outcome to both.
void run_top(MapInParts& parts, KeptTiles& kept, const SimplifyOptions& options, std::uint32_t runs, const std::string& what) {
    for (;;) {
        TileInput top = runs == 0 ? parts.top() : parts.top_subset(runs);
        if (runs > 0) {
            expect_coincidences_in_runs(parts.top(), top, what + ", runs of " + std::to_string(runs));
            TileInput given = kept.top_subset(runs);
            expect_same_input(given, top, what + ", the top over a subset of runs " + std::to_string(runs));
            if (::testing::Test::HasFailure()) return;
            top = std::move(given);
        }
        std::vector<TileInput> one{top};
        const TileOutcome outcome = run_tile_group(std::move(one), parts.plan(), options).front();
        if (runs == 0) {
            parts.finish_top(outcome);
            kept.finish_top(top, outcome);
            return;
        }
        const bool taken = parts.finish_top_subset(outcome);
        ASSERT_EQ(kept.finish_top_subset(top, outcome), taken) << what;
        if (taken) return;
        runs *= 2;
    }
}

// A run in parts of `map` from the first round by parts (FirstRound), the rounds after the first
// from its tiles kept (KeptTiles) and checked against MapInParts's, round by round, group by group:
// their tiles, and the levels from T up over subsets (runs > 0) gathered from the kept tiles. The
// result must be simplify()'s; `counts` adds what the kept tiles' news did.
void expect_kept_rounds(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint32_t runs,
                        const SimplifyResult& whole, const std::string& what, KeptTiles::Counts& counts, std::size_t& rounds) {
    const GridPlan plan = plan_grid(map);
    FirstRound first(plan, tile_level, options, map.vertices.size());
    first.add_chains(map, 0, 0);
    first.add_control_points(map.control_points);
    std::vector<TileOutcome> outcomes;
    const std::size_t groups = first.split();
    KeptTiles kept = first.keep();
    for (std::size_t k = 0; k < groups; ++k) {
        for (TileOutcome& outcome : run_tile_group(first.group(k), plan, options)) outcomes.push_back(std::move(outcome));
    }
    std::unique_ptr<MapInParts> parts = first.finish(outcomes);
    kept.finish_tiles(outcomes);
    run_top(*parts, kept, options, runs, what + ", round 1");
    if (::testing::Test::HasFailure()) return;
    while (parts->next_round()) {
        ++rounds;
        const std::string here = what + ", round " + std::to_string(rounds);
        ASSERT_TRUE(kept.next_round()) << here;
        const std::size_t count = parts->split_round();
        ASSERT_EQ(kept.groups(), count) << here;
        outcomes.clear();
        for (std::size_t k = 0; k < count; ++k) {
            const std::vector<TileInput> expected = parts->group(k), given = kept.group(k);
            ASSERT_EQ(given.size(), expected.size()) << here;
            for (std::size_t i = 0; i < given.size(); ++i) {
                expect_same_input(given[i], expected[i], here + ", group " + std::to_string(k));
                if (::testing::Test::HasFailure()) return;
            }
            for (TileOutcome& outcome : run_tile_group(given, plan, options)) outcomes.push_back(std::move(outcome));
        }
        const bool above = parts->finish_tiles(outcomes);
        ASSERT_EQ(kept.finish_tiles(outcomes), above) << here;
        if (above) run_top(*parts, kept, options, runs, here);
        if (::testing::Test::HasFailure()) return;
    }
    EXPECT_FALSE(kept.next_round()) << what;
    expect_same_but_predicates(parts->result(), whole, what);
    counts += kept.counts();
}

// The rounds after the first from the first round's tiles kept (KeptTiles), each told what its
// round changed: every round's tiles are those MapInParts builds from the live map it holds, input
// for input — pieces joined where the top removed the vertices between them, cut ends moved on,
// waits, marks and settled rings —, and so is every subset of the live map for the levels from T
// up gathered from the tiles (runs of 1, often too short, and 4); the result is simplify()'s.
// Random maps with rings and roads (crossings pin vertices and leave waits across tiles), every
// count target, every tile level with levels above. One test per map; map 35 has a wait across
// tiles whose blocker goes in its tile (the lead queues the waiter again).
class MapTilesKept : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(MapTilesKept, GiveEachRoundTheTilesTheLiveMapGives) {
    const std::uint64_t seed = GetParam();
    const MapData map = random_map(seed, seed % 3 == 2 ? 0 : 6, true);
    const GridPlan plan = plan_grid(map);
    ASSERT_GE(plan.levels, 3u);
    const double all = static_cast<double>(map.vertices.size());
    KeptTiles::Counts counts;
    std::size_t rounds = 0;
    const std::size_t coincidences_before = coincidences_checked;
    for (const StopCriterion stop : {StopCriterion{Target::keep_fraction, 0.1}, StopCriterion{Target::keep_fraction, 0.3},
                                     StopCriterion{Target::keep_points, 0.75 * all}, StopCriterion{Target::remove_points, 0.2 * all},
                                     StopCriterion{Target::max, 0}}) {
        const SimplifyOptions options = on_two_threads(stop);
        const SimplifyResult whole = simplify(map, options);
        for (unsigned tile_level = 1; tile_level < plan.levels; ++tile_level) {
            // (The top over the whole live map, or over subsets with runs of 1 or 4, in turn by
            // tile level: all of them at every level is too slow for a debug build.)
            {
                const std::uint32_t runs = std::array{1u, 4u, 0u}[(tile_level + seed) % 3];
                if (runs > 0) {
                    expect_same_but_predicates(simplify_with_kept_tiles(map, options, tile_level, map.vertices.size() / 3, runs), whole,
                                               "kept tiles alone, tile level " + std::to_string(tile_level));
                }
                expect_kept_rounds(map, options, tile_level, runs, whole,
                                   "target " + std::to_string(static_cast<int>(stop.target)) + " " + std::to_string(stop.value) + ", tile level " +
                                       std::to_string(tile_level) + ", runs " + std::to_string(runs),
                                   counts, rounds);
                if (HasFailure()) return;
            }
        }
    }
    // What the news had to do, for the test to mean something.
    EXPECT_GT(rounds, 20u);
    EXPECT_GT(counts.cut_ends_moved, 0u);
    EXPECT_GT(counts.pieces_joined, 0u);
    EXPECT_GT(counts.waits_across, 0u);
    EXPECT_GT(coincidences_checked, coincidences_before) << "runs at shared locations";
    if (seed == 35) {
        EXPECT_GT(counts.queued_again, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(MapTiles, MapTilesKept, ::testing::Values(std::uint64_t{1}, 2, 3, 5, 6, 7, 35));

// The same on the wavy rings that every level cuts (TheTopOverASubset…'s maps): subsets whose
// rings are cut into runs take those rings' fixed locations outside the runs from the tiles.
TEST(MapTiles, KeptTilesGiveTheSubsetsOfRingsEveryLevelCuts) {
    KeptTiles::Counts counts;
    std::size_t rounds = 0;
    for (const MapData& map : {wavy_rings(7, 8, 1500, 4000, 7), wavy_rings(4, 14, 600, 2000, 0)}) {
        const GridPlan plan = plan_grid(map);
        for (const StopCriterion stop : {StopCriterion{Target::max, 0}, StopCriterion{Target::keep_fraction, 0.1}}) {
            const SimplifyOptions options = on_two_threads(stop);
            const SimplifyResult whole = simplify(map, options);
            for (unsigned tile_level = 1; tile_level + 1 < plan.levels; ++tile_level) {
                expect_kept_rounds(map, options, tile_level, 1, whole,
                                   "target " + std::to_string(static_cast<int>(stop.target)) + ", tile level " + std::to_string(tile_level), counts,
                                   rounds);
                if (HasFailure()) return;
            }
        }
    }
    EXPECT_GT(counts.cut_ends_moved, 0u);
}

}  // namespace
}  // namespace toposimp::map
