#include "core/map/coverage.hpp"

#include "core/map/simplify.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <gmpxx.h>

#include <cmath>
#include <map>
#include <random>

namespace toposimp::map {
namespace {

std::vector<Point> points_of(const MapData& map, const std::vector<std::uint32_t>& ids) {
    std::vector<Point> points;
    for (const std::uint32_t v : ids) points.push_back(map.vertices[v]);
    return points;
}

int area_sign(const std::vector<Point>& ring) {
    mpq_class twice = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        twice += mpq_class(ring[i].x) * mpq_class(ring[i + 1].y) - mpq_class(ring[i + 1].x) * mpq_class(ring[i].y);
    }
    return sgn(twice);
}

SimplifyResult simplify_max(const MapData& map) {
    SimplifyOptions options;
    options.stop.target = Target::max;
    return simplify(map, options);
}

// Two squares sharing the border x = 1, with a wiggle on it that both rings carry.
TEST(Coverage, SharedBorderIsOneArcSimplifiedOnce) {
    Coverage coverage;
    const std::vector<Point> left{{0, 0}, {1, 0}, {1.1, 0.5}, {1, 1}, {0, 1}, {0, 0}};
    const std::vector<Point> right{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1.1, 0.5}, {1, 0}};
    coverage.add_ring(left);
    coverage.add_ring(right);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.arc_count(), 3u);
    EXPECT_EQ(coverage.shared_arc_count(), 1u);
    const SimplifyResult result = simplify_max(map);
    EXPECT_TRUE(testing::check_simplification(map, result.kept).ok());
    const auto a = points_of(map, coverage.ring_vertices(0, result.kept));
    const auto b = points_of(map, coverage.ring_vertices(1, result.kept));
    // Both keep or both lose the wiggle: the border stays shared.
    const bool a_has = std::any_of(a.begin(), a.end(), [](Point p) { return p.x == 1.1; });
    const bool b_has = std::any_of(b.begin(), b.end(), [](Point p) { return p.x == 1.1; });
    EXPECT_EQ(a_has, b_has);
    EXPECT_TRUE(same_location(a.front(), a.back()));
    EXPECT_TRUE(same_location(a.front(), {0, 0})) << "the ring starts where it started";
    EXPECT_EQ(area_sign(a), area_sign(left));
    EXPECT_EQ(area_sign(b), area_sign(right));
}

TEST(Coverage, IslandIsOneClosedArcAndKeepsThreeCorners) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {2, 0}, {2, 2}, {1, 2.1}, {0, 2}});  // not closed: closed on output
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.arc_count(), 1u);
    const SimplifyResult result = simplify_max(map);
    const auto ring = points_of(map, coverage.ring_vertices(0, result.kept));
    EXPECT_EQ(ring.size(), 4u);
    EXPECT_TRUE(same_location(ring.front(), ring.back()));
    EXPECT_EQ(area_sign(ring), 1);
}

TEST(Coverage, DegenerateRingsComeBackAsTheyWere) {
    Coverage coverage;
    const std::vector<Point> flat{{0, 0}, {1, 0}, {2, 0}, {0, 0}};
    const std::vector<Point> dot{{5, 5}, {5, 5}, {5, 5}};
    coverage.add_ring(flat);
    coverage.add_ring(dot);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.degenerate_ring_count(), 2u);
    const SimplifyResult result = simplify_max(map);
    EXPECT_EQ(result.stats.removed, 0u);
    EXPECT_EQ(points_of(map, coverage.ring_vertices(0, result.kept)).size(), flat.size());
    EXPECT_EQ(points_of(map, coverage.ring_vertices(1, result.kept)).size(), dot.size());
}

// Neighbours that share a border geometrically but not vertex for vertex: the T-contact and the
// overlapping edges are kept as they are, so no gap or overlap can open.
TEST(Coverage, BorderWithoutSharedVerticesIsKept) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {0.5, -0.1}, {1, 0}, {1, 1}, {0.5, 1.1}, {0, 1}, {0, 0}});
    coverage.add_ring(std::vector<Point>{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 0.5}, {1, 0}});  // (1, 0.5) lies on the left square's edge
    MapData map;
    coverage.build(map);
    const SimplifyResult result = simplify_max(map);
    EXPECT_TRUE(testing::check_simplification(map, result.kept).ok());
    const auto left = points_of(map, coverage.ring_vertices(0, result.kept));
    const auto right = points_of(map, coverage.ring_vertices(1, result.kept));
    auto has = [](const std::vector<Point>& ring, Point p) {
        return std::any_of(ring.begin(), ring.end(), [&](Point q) { return same_location(p, q); });
    };
    EXPECT_TRUE(has(left, {1, 0}) && has(left, {1, 1})) << "the left square's border edge stays";
    EXPECT_TRUE(has(right, {1, 0.5})) << "the T-contact stays";
    EXPECT_GT(result.stats.pinned_by_crossing, 0u);
}

TEST(Coverage, DuplicateVerticesDoNotSplitArcs) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {1, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}});
    coverage.add_ring(std::vector<Point>{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 0}});
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.shared_arc_count(), 1u);
}

// Random coverages: a jittered grid of quadrilateral cells whose borders wiggle, each border
// carried identically by both cells. Every ring comes back closed, with its orientation, and
// the arcs pass the independent checker.
TEST(Coverage, RandomGridCoveragesStayValid) {
    for (std::uint64_t seed = 0; seed < 30; ++seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> jitter(-0.25, 0.25);
        const int n = 6;
        std::vector<Point> corner((n + 1) * (n + 1));
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; j <= n; ++j) corner[i * (n + 1) + j] = {i + (i % n ? jitter(rng) : 0), j + (j % n ? jitter(rng) : 0)};
        }
        // Wiggly border between two corners, the same points for both cells.
        std::map<std::pair<int, int>, std::vector<Point>> borders;
        auto border = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            auto it = borders.find(key);
            if (it == borders.end()) {
                std::vector<Point> line;
                const Point p = corner[key.first], q = corner[key.second];
                for (int k = 1; k < 6; ++k) {
                    const double t = k / 6.0;
                    line.push_back({p.x + t * (q.x - p.x) + jitter(rng) * 0.1, p.y + t * (q.y - p.y) + jitter(rng) * 0.1});
                }
                it = borders.emplace(key, line).first;
            }
            std::vector<Point> line = it->second;
            if (a > b) std::reverse(line.begin(), line.end());
            return line;
        };
        Coverage coverage;
        std::vector<std::vector<Point>> input;
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < n; ++j) {
                const int c[4] = {i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1};
                std::vector<Point> ring;
                for (int k = 0; k < 4; ++k) {
                    ring.push_back(corner[c[k]]);
                    const auto line = border(c[k], c[(k + 1) % 4]);
                    ring.insert(ring.end(), line.begin(), line.end());
                }
                ring.push_back(ring.front());
                input.push_back(ring);
                coverage.add_ring(ring);
            }
        }
        MapData map;
        coverage.build(map);
        ASSERT_TRUE(testing::check_planar(map).ok()) << "seed " << seed;
        EXPECT_EQ(coverage.shared_arc_count(), 2u * n * (n - 1));
        const SimplifyResult result = simplify_max(map);
        ASSERT_TRUE(testing::check_simplification(map, result.kept).ok()) << "seed " << seed;
        for (std::uint32_t r = 0; r < coverage.ring_count(); ++r) {
            const auto ring = points_of(map, coverage.ring_vertices(r, result.kept));
            ASSERT_GE(ring.size(), 4u);
            ASSERT_TRUE(same_location(ring.front(), ring.back()));
            ASSERT_EQ(area_sign(ring), area_sign(input[r])) << "seed " << seed << " ring " << r;
        }
        EXPECT_GT(result.stats.removed, 0u);
    }
}

// A coverage of more than 65 536 ring points groups the points by location a bucket of
// locations at a time (coverage.cpp): a 60 × 60 grid of cells with five points on each border
// gets a node at every corner where three or more cells (or two and the outside) meet, one arc
// per border (the corner cells' two outer borders one), and every ring comes back as it was
// given.
TEST(Coverage, BigGridHasTheArcsOfItsBorders) {
    const int n = 60;
    auto corner = [&](int i, int j) { return Point{i * 10.0, j * 10.0}; };
    auto border = [&](int i0, int j0, int i1, int j1) {
        std::vector<Point> line;
        const Point p = corner(i0, j0), q = corner(i1, j1);
        for (int k = 1; k < 6; ++k) {
            const double t = k / 6.0;
            // A wiggle that depends on the border alone, so both cells carry the same points.
            const double wiggle = 0.5 * std::sin(0.7 * (p.x + q.x) + 1.3 * (p.y + q.y) + k);
            line.push_back({p.x + t * (q.x - p.x) + (p.y == q.y ? 0.0 : wiggle), p.y + t * (q.y - p.y) + (p.x == q.x ? 0.0 : wiggle)});
        }
        return line;
    };
    Coverage coverage;
    std::vector<std::vector<Point>> input;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            const int c[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
            std::vector<Point> ring;
            for (int k = 0; k < 4; ++k) {
                const auto [a0, a1] = c[k];
                const auto [b0, b1] = c[(k + 1) % 4];
                ring.push_back(corner(a0, a1));
                std::vector<Point> line = a0 < b0 || a1 < b1 ? border(a0, a1, b0, b1) : border(b0, b1, a0, a1);
                if (!(a0 < b0 || a1 < b1)) std::reverse(line.begin(), line.end());
                ring.insert(ring.end(), line.begin(), line.end());
            }
            ring.push_back(ring.front());
            input.push_back(ring);
            coverage.add_ring(ring);
        }
    }
    ASSERT_GT(coverage.point_count(), 65536u);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.point_count(), static_cast<std::uint32_t>(n * n * 25));
    EXPECT_EQ(coverage.shared_arc_count(), 2u * n * (n - 1));
    EXPECT_EQ(coverage.arc_count(), 2u * n * (n - 1) + 4u * n - 4u);
    const std::vector<std::uint8_t> all(map.vertices.size(), 1);
    for (std::uint32_t r = 0; r < coverage.ring_count(); ++r) {
        const auto ring = points_of(map, coverage.ring_vertices(r, all));
        ASSERT_EQ(ring.size(), input[r].size()) << "ring " << r;
        for (std::size_t k = 0; k < ring.size(); ++k) ASSERT_TRUE(same_location(ring[k], input[r][k])) << "ring " << r << ", point " << k;
    }
}

}  // namespace
}  // namespace toposimp::map
