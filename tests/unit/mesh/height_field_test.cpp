// The height-field check: does a terrain mesh cover each point of the map plane at most once?
// Checked against a brute-force test written here (every pair of faces, exact rational
// orientations), on meshes that are height fields (grids, grids with holes, pieces side by side
// or touching at a corner) and meshes that are not (a piece above another, a ramp winding over
// itself, a fan turning twice around its centre, two faces on one side of their shared edge).
#include "core/mesh/height_field.hpp"

#include "core/mesh/plan_index.hpp"
#include "core/mesh/simplify.hpp"
#include "support/exact_checker.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace toposimp::mesh {
namespace {

// An n × n grid of unit squares from (x, y), each split in two counter-clockwise triangles;
// squares listed in `holes` (i + n·j) left out.
void add_grid(Mesh& m, int n, double x, double y, double z, const std::vector<int>& holes = {}) {
    const auto first = static_cast<std::uint32_t>(m.points.size());
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) m.points.push_back({x + i, y + j, z + 0.1 * std::sin(i + 2.0 * j)});
    }
    auto id = [&](int i, int j) { return first + static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            if (std::find(holes.begin(), holes.end(), i + n * j) != holes.end()) continue;
            m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
}

Point plan(const Mesh& m, std::uint32_t v) { return {m.points[v].x, m.points[v].y}; }

// Do two counter-clockwise triangles' interiors overlap? Some edges cross properly, or a point
// of one (corner, edge midpoint, centroid) lies strictly inside the other. (Coordinates here are
// small integers and halves: the midpoints and three times the centroids are exact.)
bool brute_overlap(const Mesh& m, const Face& f, const Face& g) {
    auto strictly_inside = [&](const Face& t, Point p, double scale) {
        for (int k = 0; k < 3; ++k) {
            const Point a = plan(m, t[k]), b = plan(m, t[(k + 1) % 3]);
            if (testing::exact_orient({scale * a.x, scale * a.y}, {scale * b.x, scale * b.y}, p) <= 0) return false;
        }
        return true;
    };
    for (const auto& [t, u] : {std::pair{f, g}, std::pair{g, f}}) {
        Point centroid{0, 0};
        for (int k = 0; k < 3; ++k) {
            const Point a = plan(m, t[k]), b = plan(m, t[(k + 1) % 3]);
            centroid = {centroid.x + a.x, centroid.y + a.y};
            if (strictly_inside(u, a, 1) || strictly_inside(u, {(a.x + b.x) / 2, (a.y + b.y) / 2}, 1)) return true;
            for (int j = 0; j < 3; ++j) {
                const Point c = plan(m, u[j]), d = plan(m, u[(j + 1) % 3]);
                if (testing::exact_orient(a, b, c) * testing::exact_orient(a, b, d) < 0 &&
                    testing::exact_orient(c, d, a) * testing::exact_orient(c, d, b) < 0) {
                    return true;
                }
            }
        }
        if (strictly_inside(u, centroid, 3)) return true;
    }
    return false;
}

bool brute_force_height_field(const Mesh& m) {
    for (std::size_t f = 0; f < m.faces.size(); ++f) {
        for (std::size_t g = f + 1; g < m.faces.size(); ++g) {
            if (brute_overlap(m, m.faces[f], m.faces[g])) return false;
        }
    }
    return true;
}

// plan_overlap agrees with the brute force; a pair it gives does overlap; the fast test never
// calls an overlapping mesh clean. Returns what the fast test said.
bool expect_agreement(const Mesh& m, bool height_field) {
    EXPECT_EQ(brute_force_height_field(m), height_field);
    const auto pair = plan_overlap(m, 1);
    EXPECT_EQ(!pair.has_value(), height_field);
    if (pair) {
        EXPECT_LT((*pair)[0], (*pair)[1]);
        EXPECT_TRUE(brute_overlap(m, m.faces[(*pair)[0]], m.faces[(*pair)[1]]));
    }
    // The slow test on its own agrees too.
    EXPECT_EQ(!PlanIndex(m).overlapping_faces(m, 1).has_value(), height_field);
    const bool fast = covers_once_by_border(m, 1);
    if (!height_field) {
        EXPECT_FALSE(fast);
    }
    // The simplifier decides the same from its own border edges (counted in its pass over each
    // vertex's faces).
    Mesh copy = m;
    SimplifyOptions options;
    options.terrain = true;
    options.stop.value = 1.0;
    const SimplifyStats stats = simplify(copy, options);
    EXPECT_EQ(stats.terrain, height_field);
    EXPECT_EQ(stats.plan_overlap, pair);
    return fast;
}

TEST(HeightField, GridsWithAndWithoutHolesAreDecidedByTheirBorder) {
    Mesh grid;
    add_grid(grid, 6, 0, 0, 0);
    EXPECT_TRUE(expect_agreement(grid, true));
    Mesh holes;
    add_grid(holes, 8, 0, 0, 0, {9, 10, 17, 21, 44});  // three holes apart, one of them of three squares
    EXPECT_TRUE(expect_agreement(holes, true));
    Mesh apart;  // two pieces side by side, a gap between them
    add_grid(apart, 3, 0, 0, 0);
    add_grid(apart, 3, 3.5, 0, 5);
    EXPECT_TRUE(expect_agreement(apart, true));
    Mesh ring;  // a piece inside the hole of another
    add_grid(ring, 6, 0, 0, 0, {14, 15, 20, 21});
    add_grid(ring, 1, 2.25, 2.25, 1);
    EXPECT_TRUE(expect_agreement(ring, true));
}

TEST(HeightField, PiecesTouchingAtACornerAreLeftToTheFaceTest) {
    Mesh m;  // the second piece's corner is the first's (same location, another vertex)
    add_grid(m, 2, 0, 0, 0);
    add_grid(m, 2, 2, 2, 0);
    EXPECT_FALSE(expect_agreement(m, true));
}

TEST(HeightField, APieceAboveAnotherOverlaps) {
    Mesh m;
    add_grid(m, 6, 0, 0, 0);
    add_grid(m, 2, 2, 2, 10);  // a deck over the middle
    expect_agreement(m, false);
    Mesh inside_hole_too_big;  // in a hole, but wider than it
    add_grid(inside_hole_too_big, 6, 0, 0, 0, {14, 15, 20, 21});
    add_grid(inside_hole_too_big, 1, 1.5, 1.5, 1);
    expect_agreement(inside_hole_too_big, false);
}

TEST(HeightField, ARampWindingOverItselfOverlaps) {
    // A strip around the origin, inner radius 2, outer 3, rising, one and a half turns.
    Mesh m;
    const int steps = 18;  // 30° each
    for (int k = 0; k <= steps; ++k) {
        const double angle = k * M_PI / 6;
        for (const double radius : {2.0, 3.0}) {
            // Rounded to halves: the brute force's midpoints and centroids stay exact.
            m.points.push_back({std::round(2 * radius * std::cos(angle)) / 2, std::round(2 * radius * std::sin(angle)) / 2, 0.5 * k});
        }
    }
    for (std::uint32_t k = 0; k < steps; ++k) {
        const std::uint32_t in = 2 * k, out = 2 * k + 1, next_in = 2 * k + 2, next_out = 2 * k + 3;
        m.faces.push_back({in, out, next_out});
        m.faces.push_back({in, next_out, next_in});
    }
    expect_agreement(m, false);
}

TEST(HeightField, AFanTurningTwiceAroundItsCentreOverlaps) {
    // Twelve faces of 60° around the centre, the rim drawn outward as it turns.
    Mesh m;
    m.points.push_back({0, 0, 0});
    const double rim[12][2] = {{4, 0}, {2, 4}, {-2, 4}, {-5, 0}, {-3, -5}, {3, -5}, {6, 0}, {3, 6}, {-3, 6}, {-7, 0}, {-4, -7}, {4, -7}};
    for (const auto& p : rim) m.points.push_back({p[0], p[1], 1});
    for (std::uint32_t k = 0; k < 12; ++k) m.faces.push_back({0, 1 + k, 1 + (k + 1) % 12});
    expect_agreement(m, false);
}

TEST(HeightField, TwoFacesOnOneSideOfTheirSharedEdgeOverlap) {
    Mesh m;
    m.points = {{0, 0, 0}, {4, 0, 0}, {2, 2, 0}, {1, 3, 1}};
    m.faces = {{0, 1, 2}, {0, 1, 3}};  // both counter-clockwise, both above the edge 0 → 1
    expect_agreement(m, false);
}

TEST(HeightField, RandomPiecesAgreeWithTheBruteForce) {
    // Grids with random holes, and a second piece somewhere near: overlapping or not.
    std::mt19937_64 random(7);
    int overlapping = 0, clean = 0;
    for (int trial = 0; trial < 16; ++trial) {
        Mesh m;
        std::vector<int> holes;
        std::uniform_int_distribution<int> square(0, 24);
        for (int h = 0; h < trial % 5; ++h) holes.push_back(square(random));
        add_grid(m, 5, 0, 0, 0, holes);
        std::uniform_int_distribution<int> half(-5, 12);
        add_grid(m, 1 + trial % 2, half(random) / 2.0, half(random) / 2.0, 2);
        const bool height_field = brute_force_height_field(m);
        (height_field ? clean : overlapping) += 1;
        expect_agreement(m, height_field);
    }
    EXPECT_GT(overlapping, 3);
    EXPECT_GT(clean, 3);
}

// The index the quick measure builds around its points lists, in each cell it fills, what the
// index of every face lists there, in the same (face) order, whatever the number of threads
// (each thread counts and places a run of faces; a cell takes the runs in order). Most faces
// span at most 2 × 2 cells (the usual path); 300 long ones, between random corners, span many.
TEST(PlanIndex, CellsNearThePointsListWhatTheWholeIndexListsInFaceOrder) {
    Mesh m = toposimp::testing::noisy_heightfield(140, 0.3, 8);  // 39 200 faces: two runs or more
    ASSERT_GT(m.faces.size(), std::size_t{32768});
    std::mt19937 corners(4);
    std::uniform_int_distribution<std::uint32_t> corner(0, static_cast<std::uint32_t>(m.points.size() - 1));
    for (int k = 0; k < 300; ++k) m.faces.insert(m.faces.begin() + k * 100, Face{corner(corners), corner(corners), corner(corners)});
    const PlanIndex whole(m);
    std::mt19937 random(9);
    std::uniform_real_distribution<double> where(-0.1, 1.1);
    Box3 box = point_box(m.points[0]);
    for (const Point3& p : m.points) box.add(p);
    std::vector<Point> near;
    for (int k = 0; k < 300; ++k) {
        near.push_back({box.lo.x + where(random) * (box.hi.x - box.lo.x), box.lo.y + where(random) * (box.hi.y - box.lo.y)});
    }
    for (const int threads : {1, 2, 3}) {
        const PlanIndex index(m, near, 1, threads);
        std::size_t listed = 0;
        for (const Point p : near) {
            const auto here = index.at(p.x, p.y), all = whole.at(p.x, p.y);
            ASSERT_TRUE(std::equal(here.begin(), here.end(), all.begin(), all.end())) << threads << " threads, at " << p.x << " " << p.y;
            listed += here.size();
        }
        EXPECT_GT(listed, near.size());
    }
}

}  // namespace
}  // namespace toposimp::mesh
