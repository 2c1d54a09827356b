// Segment contacts found through the row-by-row grid are exactly those a test of every pair finds.
#include "core/map/crossings.hpp"

#include "core/exact/segments.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
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

}  // namespace
}  // namespace toposimp::map
