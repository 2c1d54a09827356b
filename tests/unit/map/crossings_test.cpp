// Segment contacts found through the row-by-row grid are exactly those a test of every pair finds.
#include "core/map/crossings.hpp"

#include "core/exact/segments.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

namespace toposimp::map {
namespace {

std::vector<SegmentContact> every_pair(const MapData& map) {
    std::vector<std::uint32_t> segments;
    for (const Chain& chain : map.chains) {
        for (std::uint32_t v = chain.first; v < chain.last; ++v) segments.push_back(v);
    }
    // Every pair whose x ranges overlap (no other pair can meet): a sweep over left ends.
    auto left = [&](std::uint32_t v) { return std::min(map.vertices[v].x, map.vertices[v + 1].x); };
    auto right = [&](std::uint32_t v) { return std::max(map.vertices[v].x, map.vertices[v + 1].x); };
    std::sort(segments.begin(), segments.end(), [&](std::uint32_t a, std::uint32_t b) { return left(a) < left(b); });
    exact::PredicateStats stats;
    std::vector<SegmentContact> found;
    for (std::size_t i = 0; i < segments.size(); ++i) {
        for (std::size_t j = i + 1; j < segments.size() && left(segments[j]) <= right(segments[i]); ++j) {
            const std::uint32_t s = std::min(segments[i], segments[j]), t = std::max(segments[i], segments[j]);
            const Point p = map.vertices[s], q = map.vertices[s + 1], r = map.vertices[t], u = map.vertices[t + 1];
            if (!exact::improper_contact(p, q, r, u, exact::Arithmetic::exact, stats)) continue;
            ContactKind kind = ContactKind::touching;
            if ((same_location(p, r) && same_location(q, u)) || (same_location(p, u) && same_location(q, r))) {
                kind = ContactKind::identical;
            } else if (exact::proper_crossing(p, q, r, u, exact::Arithmetic::exact, stats)) {
                kind = ContactKind::crossing;
            }
            found.push_back({s, t, kind});
        }
    }
    std::sort(found.begin(), found.end(), [](const SegmentContact& a, const SegmentContact& b) {
        return a.s < b.s || (a.s == b.s && a.t < b.t);
    });
    return found;
}

// Random walks on a coarse lattice (collinear overlaps, touches, shared and duplicate vertices)
// mixed with free ones (proper crossings), some long segments spanning many cells.
MapData tangled_map(std::uint64_t seed, int chains, int steps, int extent) {
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int> lattice(0, extent), step(-2, 2), pick(0, 19);
    std::uniform_real_distribution<double> free(0, extent);
    MapData map;
    for (int c = 0; c < chains; ++c) {
        std::vector<Point> points;
        Point at{static_cast<double>(lattice(rng)), static_cast<double>(lattice(rng))};
        for (int k = 0; k < steps; ++k) {
            points.push_back(at);
            const int kind = pick(rng);
            if (kind == 0) {
                at = {free(rng), free(rng)};  // a long jump
            } else if (kind == 1) {
                at = {at.x + free(rng) / extent, at.y - free(rng) / extent};  // off the lattice
            } else {
                at = {std::round(at.x) + step(rng), std::round(at.y) + step(rng)};
            }
        }
        map.add_chain(points);
    }
    return map;
}

void check_against(const std::vector<SegmentContact>& grid, const std::vector<SegmentContact>& brute);

void expect_same_contacts(const MapData& map) {
    const std::vector<SegmentContact> brute = every_pair(map);
    for (const int threads : {1, 2, 3}) {
        exact::PredicateStats stats;
        check_against(find_segment_contacts(map, exact::Arithmetic::exact, stats, threads), brute);
    }
}

void check_against(const std::vector<SegmentContact>& grid, const std::vector<SegmentContact>& brute) {
    ASSERT_GT(brute.size(), 10u);
    ASSERT_EQ(grid.size(), brute.size());
    for (std::size_t i = 0; i < brute.size(); ++i) {
        EXPECT_EQ(std::tie(grid[i].s, grid[i].t, grid[i].kind), std::tie(brute[i].s, brute[i].t, brute[i].kind)) << i;
    }
}

TEST(SegmentContacts, SmallMapsMatchEveryPairTest) {
    for (std::uint64_t seed = 1; seed <= 20; ++seed) expect_same_contacts(tangled_map(seed, 12, 40, 30));
}

// Over 2^14 segments: the parallel path, rows split between threads.
TEST(SegmentContacts, BigMapMatchesEveryPairTest) {
    const MapData map = tangled_map(99, 170, 100, 300);
    ASSERT_GT(map.vertices.size() - map.chains.size(), std::size_t{1} << 14);
    expect_same_contacts(map);
}

// find_improper_segments flags exactly the segments in some contact, with the same predicate
// counts for any thread count, on small and big (parallel) tangled maps.
TEST(SegmentContacts, ImproperSegmentsAreThoseInAContact) {
    for (const auto& [seed, chains, steps, extent] : {std::tuple{1, 12, 40, 30}, std::tuple{7, 12, 40, 30}, std::tuple{99, 170, 100, 300}}) {
        const MapData map = tangled_map(static_cast<std::uint64_t>(seed), chains, steps, extent);
        std::vector<std::uint8_t> expected(map.vertices.size(), 0);
        for (const SegmentContact& c : every_pair(map)) expected[c.s] = expected[c.t] = 1;
        ASSERT_GT(std::count(expected.begin(), expected.end(), 1), 10);
        std::uint64_t tests_one_thread = 0;
        for (const int threads : {1, 2, 3}) {
            exact::PredicateStats stats;
            EXPECT_EQ(find_improper_segments(map, exact::Arithmetic::exact, stats, threads), expected) << seed << " " << threads;
            const std::uint64_t tests = stats.filter_decided + stats.expansion_decided + stats.gmp_fallbacks;
            if (threads == 1) tests_one_thread = tests;
            EXPECT_EQ(tests, tests_one_thread) << "predicate counts depend on the threads";
        }
    }
}

// Long segments at every slope, entered only in the cells of their parts in each row: chords
// across the whole map (steep, shallow, near-axis), at coordinates where the grid's cells are
// large and small against the coordinates' ulps, and one grid too fine to clip at all.
TEST(SegmentContacts, LongSegmentsAtEverySlopeMatchEveryPairTest) {
    for (const auto& [seed, offset, scale] : {std::tuple{3, 0.0, 1.0}, std::tuple{4, 1e6, 1e-3}, std::tuple{5, -3e8, 1e2},
                                             std::tuple{6, 1e9, 1e-6}, std::tuple{7, 0.0, 1e-300}}) {
        std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
        std::uniform_real_distribution<double> unit(0, 100);
        std::uniform_int_distribution<int> lattice(0, 100), pick(0, 3);
        MapData map;
        for (int c = 0; c < 300; ++c) {
            std::vector<Point> points;
            for (int k = 0; k < 3; ++k) {
                double x = unit(rng), y = unit(rng);
                if (pick(rng) == 0) x = lattice(rng), y = lattice(rng);  // shared lattice points: touches
                if (k == 1 && pick(rng) == 0) y = points.back().y + 1e-3 * unit(rng);  // near horizontal
                points.push_back({offset + scale * x, offset + scale * y});
            }
            map.add_chain(points);
        }
        expect_same_contacts(map);
        std::vector<std::uint8_t> expected(map.vertices.size(), 0);
        for (const SegmentContact& contact : every_pair(map)) expected[contact.s] = expected[contact.t] = 1;
        exact::PredicateStats stats;
        EXPECT_EQ(find_improper_segments(map, exact::Arithmetic::exact, stats, 2), expected) << seed;
    }
}

// Issue 29, case 9, in two dimensions: a track back and forth along a diagonal as long as the
// map. Each segment's box covers every cell, so entering boxes would put 40 000 segments in
// 20 000 cells each (8·10^8 entries); entering their parts puts each in a few hundred.
TEST(SegmentContacts, Issue29BackAndForthDiagonalIsEnteredAlongItsCells) {
    MapData map;
    std::vector<Point> points;
    for (int i = 0; i < 40000; ++i) {
        const double t = i % 2 == 0 ? 0.5 * (i % 7) : 1000.0 - 0.5 * (i % 5);
        points.push_back({t, 0.5 * t});
    }
    map.add_chain(points);
    exact::PredicateStats stats;
    const std::vector<std::uint8_t> improper = find_improper_segments(map, exact::Arithmetic::exact, stats, 2);
    EXPECT_EQ(std::count(improper.begin(), improper.end() - 1, 1), 39999);
    EXPECT_LT(stats.filter_decided + stats.expansion_decided + stats.gmp_fallbacks, 40000u * 141u * 4u * 3u);
}

// Issue 29, case 9: a line running back and forth over one stretch (a GPS track repeating a
// route) has a contact between nearly every pair of its segments; finding which segments have
// one took time and memory with their square (100 000 vertices: 7 GB in 60 s, no end). Every
// segment is found, and in a pass per cell (ctest's timeout would end a quadratic run).
TEST(SegmentContacts, Issue29BackAndForthLineIsSettledInLinearPasses) {
    MapData map;
    std::vector<Point> points;
    // Along one line (y = 0), each turn a little further or shorter: collinear overlaps throughout.
    for (int i = 0; i < 40000; ++i) points.push_back({i % 2 == 0 ? 0.1 * (i % 7) : 10.0 - 0.1 * (i % 5), 0.0});
    map.add_chain(points);
    exact::PredicateStats stats;
    const std::vector<std::uint8_t> improper = find_improper_segments(map, exact::Arithmetic::exact, stats, 2);
    EXPECT_EQ(std::count(improper.begin(), improper.end() - 1, 1), 39999);
    // Each cell settles its segments in a pass or two, the rest passed over: the tests grow with
    // the segments times the cells they span (141 here), not with their square (8·10^8 pairs).
    EXPECT_LT(stats.filter_decided + stats.expansion_decided + stats.gmp_fallbacks, 40000u * 141u * 4u);
}

// Consecutive segments of a chain running strictly one way through their shared vertex, in x or
// in y, meet there alone and are settled without a predicate (issue 34); one folding back by a
// single ulp, or lying back along itself, still is improper.
TEST(SegmentContacts, Issue34ConsecutiveSegmentsFoldingBackByAnUlpAreImproper) {
    const double up = std::nextafter(1.0, 2.0), down = std::nextafter(1.0, 0.0);
    struct Case {
        Point p, q, u;
        bool improper;
    };
    for (const auto& [p, q, u, improper] : {Case{{0, 0}, {1, 0}, {up, 0}, false}, Case{{0, 0}, {1, 0}, {down, 0}, true},
                                             Case{{0, 0}, {1, 1}, {0.5, 2}, false}, Case{{0, 5}, {0, 1}, {0, down}, false},
                                             Case{{0, 5}, {0, 1}, {0, up}, true}, Case{{3, 3}, {1, 1}, {2, 2}, true},
                                             Case{{1e300, -1e-300}, {-1e300, 1e-300}, {1e300, 0}, false}}) {
        MapData map;
        map.add_chain(std::vector<Point>{p, q, u});
        exact::PredicateStats stats;
        const std::vector<std::uint8_t> found = find_improper_segments(map, exact::Arithmetic::exact, stats, 1);
        EXPECT_EQ(found[0] == 1, improper) << p.x << "," << p.y << " " << q.x << "," << q.y << " " << u.x << "," << u.y;
        EXPECT_EQ(found[0], found[1]);
    }
}

// Vertices crowded along lines (GSHHG's shores) make the search split its rows (issue 34): dense
// walks on a fine lattice in a few spots of a wide map — overlaps, touches, crossings — found
// exactly as a test of every pair finds them, with every split the search can choose.
MapData crowded_map(std::uint64_t seed, int blobs, int steps, double extent) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> where(0, extent);
    std::uniform_int_distribution<int> step(-1, 1), pick(0, 9);
    MapData map;
    map.add_chain(std::vector<Point>{{0, 0}, {extent, extent}});  // across everything
    for (int b = 0; b < blobs; ++b) {
        std::vector<Point> points;
        Point at{std::round(where(rng)), std::round(where(rng))};
        for (int k = 0; k < steps; ++k) {
            points.push_back(at);
            at = {at.x + 0.25 * step(rng), at.y + 0.25 * step(rng)};
            if (pick(rng) == 0) at = {at.x + 0.1, at.y - 0.07};  // off the lattice
        }
        map.add_chain(points);
    }
    return map;
}

TEST(SegmentContacts, Issue34CrowdedMapsSplitRowsAndMatchEveryPairTest) {
    std::set<unsigned> splits;
    for (const auto& [seed, blobs, steps, extent] : {std::tuple{5, 600, 8, 300.0}, std::tuple{7, 100, 60, 300.0}, std::tuple{8, 60, 150, 300.0}, std::tuple{2, 8, 2500, 1000.0},
                                                      std::tuple{3, 6, 4000, 3000.0}, std::tuple{4, 3, 8000, 1e5}}) {
        const MapData map = crowded_map(static_cast<std::uint64_t>(seed), blobs, steps, extent);
        splits.insert(search_row_split(map));
        expect_same_contacts(map);
        std::vector<std::uint8_t> expected(map.vertices.size(), 0);
        for (const SegmentContact& c : every_pair(map)) expected[c.s] = expected[c.t] = 1;
        for (const int threads : {1, 2}) {
            exact::PredicateStats stats;
            EXPECT_EQ(find_improper_segments(map, exact::Arithmetic::exact, stats, threads), expected) << seed << " " << threads;
        }
    }
    EXPECT_EQ(splits, (std::set<unsigned>{0, 1, 2, 3}));
}

}  // namespace
}  // namespace toposimp::map
