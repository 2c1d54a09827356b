// Rounding onto a grid of published coordinates: the grid itself, the hard cases (a sliver that
// rounding would flip, a control point one ulp from a border, two borders closer than a step, an
// island smaller than a step), and random maps at coarse grids against the independent checker.
#include "core/map/rounding.hpp"

#include "core/map/simplify.hpp"
#include "support/exact_checker.hpp"
#include "support/random_maps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <random>

namespace toposimp::map {
namespace {

bool on_grid(const GridStep& grid, Point p) {
    return grid.at(*grid.nearest(p.x)) == p.x && grid.at(*grid.nearest(p.y)) == p.y;
}

RoundingResult round_all(const MapData& map, const GridStep& grid) {
    return round_to_grid(map, std::vector<std::uint8_t>(map.vertices.size(), 1), {grid});
}

void expect_clean(const MapData& map, const RoundingResult& result, const GridStep& grid) {
    const testing::CheckReport report =
        testing::check_rounded(map, result.kept, result.at, [&](Point p) { return on_grid(grid, p); });
    EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(GridStep, ParsesDecimalsAndGivesTheDoublesReadersGet) {
    const GridStep step = *GridStep::parse("0.0001");
    EXPECT_EQ(step.mantissa, 1);
    EXPECT_EQ(step.exponent, -4);
    EXPECT_EQ(step.text(), "0.0001");
    EXPECT_EQ(step.at(123457), 12.3457);       // the double the literal 12.3457 is
    EXPECT_EQ(step.at(-3), -0.0003);
    EXPECT_EQ(*step.nearest(12.34565001), 123457);
    EXPECT_EQ(*step.nearest(-0.00014), -1);
    EXPECT_EQ(GridStep::parse("2.5E3")->text(), "2500");
    EXPECT_EQ(GridStep::parse("25")->at(3), 75.0);
    EXPECT_EQ(GridStep::parse("1e-4")->at(1), 0.0001);
    EXPECT_EQ(GridStep::parse("0.50")->text(), "0.5");
    for (const char* bad : {"0", "-1", "abc", "1e999", "", ".", "1.2.3", "1e", "nan", "inf", "0.0000000000000001234567890123456"}) {
        EXPECT_FALSE(GridStep::parse(bad)) << bad;
    }
    EXPECT_FALSE(GridStep::decimals(4).nearest(1e300));  // the grid is too fine for the coordinates
}

// The fast path of GridStep::at (one IEEE operation on exact operands) gives the double that
// parsing the decimal text gives, for any step and index, at the edges of the fast path too.
TEST(GridStep, FastPathIsTheParsedValue) {
    std::mt19937_64 rng(30);
    for (int trial = 0; trial < 200000; ++trial) {
        const GridStep step{static_cast<std::int64_t>(rng() % 1000000) + 1, static_cast<int>(rng() % 61) - 30};
        const int bits = static_cast<int>(rng() % 62);
        auto k = static_cast<std::int64_t>(rng() >> (64 - bits));
        if (rng() % 2) k = -k;
        if (std::abs(static_cast<double>(k) * static_cast<double>(step.mantissa)) >= 0x1p62) continue;
        ASSERT_EQ(step.at(k), step.parsed_at(k)) << step.mantissa << "e" << step.exponent << " at " << k;
    }
    for (const std::int64_t k : {(std::int64_t{1} << 53) - 1, std::int64_t{1} << 53, (std::int64_t{1} << 53) + 1}) {
        for (const int e : {-23, -22, -1, 0, 22, 23}) {
            EXPECT_EQ((GridStep{1, e}.at(k)), (GridStep{1, e}.parsed_at(k))) << k << "e" << e;
            EXPECT_EQ((GridStep{1, e}.at(-k)), (GridStep{1, e}.parsed_at(-k))) << k << "e" << e;
        }
    }
}

// A sliver ring whose apex is 0.4 steps above its base: the nearest grid point puts the apex on
// the base line (area 0). It must keep its orientation: the apex goes one step up, or stays.
TEST(Rounding, SliverKeepsItsOrientation) {
    MapData map;
    map.add_chain({{0, 0}, {20, 0}, {10, 0.00004}, {0, 0}});
    const GridStep grid = GridStep::decimals(4);
    const RoundingResult result = round_all(map, grid);
    expect_clean(map, result, grid);
    EXPECT_NE(result.at[2].y, 0.0);
}

// A control point one ulp below a border vertex that is 0.3 steps above it: rounding the vertex
// down would carry the border across the point.
TEST(Rounding, ControlPointOneUlpFromABorderStaysOnItsSide) {
    MapData map;
    map.add_chain({{0, 0}, {1, 0.00003}, {2, 0}});
    map.add_chain({{0, 0}, {1, -1}, {2, 0}});
    map.control_points = {{1, std::nextafter(0.00003, 0.0)}};
    const GridStep grid = GridStep::decimals(4);
    const RoundingResult result = round_all(map, grid);
    expect_clean(map, result, grid);
    EXPECT_GT(result.at[1].y, map.control_points[0].y);
}

// Two borders 0.00001 apart, both nearest to the same grid line: they must not merge.
TEST(Rounding, BordersCloserThanAStepDoNotMerge) {
    MapData map;
    map.add_chain({{0, 0.00004}, {1, 0.00004}, {2, 0.00004}, {3, 0.00004}});
    map.add_chain({{0, 0.00003}, {1, 0.00002}, {2, 0.00003}, {3, 0.00002}});
    const GridStep grid = GridStep::decimals(4);
    const RoundingResult result = round_all(map, grid);
    expect_clean(map, result, grid);
    EXPECT_GT(result.stats.moved_nearest + result.stats.moved_other, 0u);
}

// An island smaller than a grid step: every corner's nearest grid point is the same. It keeps
// 3 distinct corners and its orientation (checked), on grid points around (a later pass), or,
// where a control point inside leaves no room, off the grid, reported.
TEST(Rounding, IslandSmallerThanAStepKeepsThreeCorners) {
    MapData map;
    map.add_chain({{0.00001, 0.00001}, {0.00003, 0.00001}, {0.00002, 0.00003}, {0.00001, 0.00001}});
    const GridStep grid = GridStep::decimals(4);
    const RoundingResult result = round_all(map, grid);
    expect_clean(map, result, grid);
    EXPECT_EQ(result.stats.moved_nearest + result.stats.moved_other, 3u);
    map.control_points = {{0.00002, 0.000015}};
    const RoundingResult held = round_all(map, grid);
    expect_clean(map, held, grid);
    // A control point at a corner pins that corner where it is: off the grid, reported.
    map.control_points = {{0.00003, 0.00001}};
    const RoundingResult pinned = round_all(map, grid);
    expect_clean(map, pinned, grid);
    EXPECT_EQ(pinned.stats.off_grid, 1u);
    ASSERT_EQ(pinned.off_grid.size(), 1u);
    EXPECT_EQ(pinned.off_grid[0], 1u);
}

// A vertex whose grid point is its neighbour's is removed, when the simplifier's rules allow.
TEST(Rounding, VertexOnItsNeighboursGridPointIsRemoved) {
    MapData map;
    map.add_chain({{0, 0}, {0.3, 0.2}, {3, 1}, {5, 0}});
    const GridStep grid = *GridStep::parse("1");
    const RoundingResult result = round_all(map, grid);
    expect_clean(map, result, grid);
    EXPECT_EQ(result.stats.removed, 1u);
    EXPECT_EQ(result.kept[1], 0);
}

// Written control points (point features) go on the grid too, unless their way there touches a
// line. The point on the line's middle vertex holds that vertex where it is (and stays with it);
// the line's ends go down to y = 0; the point below the line goes down to (1, 0), still below.
TEST(Rounding, WrittenPointsGoOnTheGridWithoutCrossingALine) {
    MapData map;
    map.add_chain({{0, 0.00004}, {1, 0.00004}, {2, 0.00004}});
    map.control_points = {{1, 0.00001}, {5.00004, 5.00004}, {1, 0.00004}};
    RoundingOptions options{GridStep::decimals(4)};
    options.written_points = 3;
    const RoundingResult result = round_to_grid(map, std::vector<std::uint8_t>(map.vertices.size(), 1), options);
    ASSERT_EQ(result.points.size(), 3u);
    EXPECT_EQ(result.at[0].y, 0.0);
    EXPECT_EQ(result.at[1].y, 0.00004);
    EXPECT_EQ(result.at[2].y, 0.0);
    EXPECT_EQ(result.stats.off_grid, 1u);
    EXPECT_EQ(result.points[0].x, 1.0);
    EXPECT_EQ(result.points[0].y, 0.0);
    EXPECT_EQ(result.points[1].x, 5.0);
    EXPECT_EQ(result.points[1].y, 5.0);
    EXPECT_EQ(result.points[2].x, 1.0);
    EXPECT_EQ(result.points[2].y, 0.00004);
    EXPECT_EQ(result.stats.points_moved, 2u);
    EXPECT_EQ(result.stats.points_off_grid, 1u);

    // A point whose way to its grid point would cross the line stays where it is.
    MapData across;
    across.add_chain({{0, 0.00004}, {1, 0.00004}, {2, 0.00004}});
    across.control_points = {{1, 0.00007}};  // nearest grid point (1, 0.0001); the line goes to 0
    across.control_points.push_back({1, 0.00004});  // holds the middle vertex at 0.00004
    RoundingOptions one{GridStep::decimals(4)};
    one.written_points = 1;
    const RoundingResult kept = round_to_grid(across, std::vector<std::uint8_t>(across.vertices.size(), 1), one);
    EXPECT_EQ(kept.points[0].y, 0.0001);  // way up, away from the line: fine
    // Points just below the line's first segment, wherever the line and they go, stay below it.
    for (const double x : {0.25, 0.5, 0.75}) {
        for (const double y : {0.00001, 0.00003, 0.0000399}) {
            across.control_points[0] = {x, y};
            const RoundingResult r = round_to_grid(across, std::vector<std::uint8_t>(across.vertices.size(), 1), one);
            exact::PredicateStats stats;
            EXPECT_EQ(exact::orient2d(r.at[0], r.at[1], r.points[0], stats), exact::orient2d(across.vertices[0], across.vertices[1], across.control_points[0], stats))
                << x << " " << y << " went to " << r.points[0].x << " " << r.points[0].y;
            EXPECT_EQ(r.stats.points_moved + r.stats.points_off_grid, 1u);
        }
    }
}

// Random maps (planar, and with roads crossing them), simplified, then rounded at grids from a
// thousandth of the map to a tenth of it: every promise holds (independent checker), and most
// locations reach the grid.
TEST(Rounding, RandomMapsAtCoarseGridsKeepEveryPromise) {
    std::map<std::string, std::pair<std::uint64_t, std::uint64_t>> by_step;  // on, off
    for (std::uint64_t seed = 1; seed <= 40; ++seed) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions options;
        options.roads = seed % 3 == 0 ? 3 : 0;
        options.origin_x = seed % 4 == 1 ? 1e6 : 0;
        const MapData map = testing::random_planar_map(rng, options);
        SimplifyOptions simplify_options;
        simplify_options.stop = {Target::keep_fraction, 0.4};
        const SimplifyResult simplified = simplify(map, simplify_options);
        for (const char* step : {"0.1", "1", "5", "10"}) {
            const GridStep grid = *GridStep::parse(step);
            const RoundingResult result = round_to_grid(map, simplified.kept, {grid});
            SCOPED_TRACE("seed " + std::to_string(seed) + ", step " + step);
            expect_clean(map, result, grid);
            for (std::size_t v = 0; v < result.kept.size(); ++v) EXPECT_LE(result.kept[v], simplified.kept[v]);
            by_step[step].first += result.stats.already_on_grid + result.stats.moved_nearest + result.stats.moved_other;
            by_step[step].second += result.stats.off_grid;
        }
    }
    for (const auto& [step, counts] : by_step) {
        std::printf("random maps, step %s: %llu locations on the grid, %llu off\n", step.c_str(),
                    static_cast<unsigned long long>(counts.first), static_cast<unsigned long long>(counts.second));
    }
}

}  // namespace
}  // namespace toposimp::map
