// The sampled Hausdorff distance searches a grid of faces and stops when no unsearched cell can
// hold a nearer face: it must find what a search of every face finds. With no face samples asked
// for, the samples are the vertices and one point per face (a + (b − a)/3 + (c − a)/3), which
// this test rebuilds and measures against every face with its own point–triangle distance.
#include "core/mesh/distance.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

namespace toposimp::mesh {
namespace {

struct V3 {
    double x, y, z;
};
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 at(const Mesh& m, std::uint32_t v) { return {m.points[v].x, m.points[v].y, m.points[v].z}; }

// Distance from p to the segment ab.
double to_segment(V3 p, V3 a, V3 b) {
    const V3 d = b - a;
    const double length2 = dot(d, d);
    const double t = length2 > 0 ? std::clamp(dot(p - a, d) / length2, 0.0, 1.0) : 0.0;
    const V3 q = a + t * d - p;
    return std::sqrt(dot(q, q));
}

// Distance from p to the triangle abc: to its plane if p projects inside it, else to its nearest
// edge (by barycentric signs of the projection).
double to_triangle(V3 p, V3 a, V3 b, V3 c) {
    const double edges = std::min({to_segment(p, a, b), to_segment(p, b, c), to_segment(p, c, a)});
    const V3 u = b - a, v = c - a;
    const V3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    const double n2 = dot(n, n);
    if (!(n2 > 0)) return edges;
    const double height = dot(p - a, n) / n2;
    const V3 q = p - height * n;  // p's projection on the plane
    auto side = [&](V3 s, V3 t) {
        const V3 e = t - s, w = q - s;
        return dot(V3{e.y * w.z - e.z * w.y, e.z * w.x - e.x * w.z, e.x * w.y - e.y * w.x}, n);
    };
    if (side(a, b) >= 0 && side(b, c) >= 0 && side(c, a) >= 0) return std::min(edges, std::fabs(height) * std::sqrt(n2));
    return edges;
}

// Largest and mean distance from from's vertices and face points to the nearest face of to.
OneWayDistance brute_force(const Mesh& from, const Mesh& to) {
    std::vector<V3> samples;
    for (std::uint32_t v = 0; v < from.points.size(); ++v) samples.push_back(at(from, v));
    for (const Face& f : from.faces) {
        const V3 a = at(from, f[0]), b = at(from, f[1]), c = at(from, f[2]);
        samples.push_back(a + (1.0 / 3.0) * (b - a) + (1.0 / 3.0) * (c - a));
    }
    OneWayDistance result;
    double sum = 0;
    for (const V3& p : samples) {
        double nearest = std::numeric_limits<double>::infinity();
        for (const Face& g : to.faces) nearest = std::min(nearest, to_triangle(p, at(to, g[0]), at(to, g[1]), at(to, g[2])));
        result.max = std::max(result.max, nearest);
        sum += nearest;
    }
    result.samples = samples.size();
    result.mean = sum / static_cast<double>(samples.size());
    return result;
}

void expect_close(double grid, double brute) { EXPECT_NEAR(grid, brute, 1e-12 * std::max(1.0, std::fabs(brute))); }

void expect_same(const Mesh& a, const Mesh& b) {
    const HausdorffDistance d = hausdorff(a, b, 0);
    const OneWayDistance forward = brute_force(a, b), backward = brute_force(b, a);
    EXPECT_EQ(d.forward.samples, forward.samples);
    EXPECT_EQ(d.backward.samples, backward.samples);
    expect_close(d.forward.max, forward.max);
    expect_close(d.forward.mean, forward.mean);
    expect_close(d.backward.max, backward.max);
    expect_close(d.backward.mean, backward.mean);
}

// Random triangles of very different sizes scattered in a box: big ones span many cells, small
// ones one; samples fall near cell sides and far from any face.
Mesh scattered(std::mt19937& random, int count, double extent) {
    std::uniform_real_distribution<double> where(0, extent), size(0.001, 0.4 * extent), offset(-1, 1);
    Mesh m;
    for (int i = 0; i < count; ++i) {
        const Point3 c{where(random), where(random), where(random)};
        const double s = i % 5 == 0 ? size(random) : 0.01 * size(random);
        const auto first = static_cast<std::uint32_t>(m.points.size());
        for (int k = 0; k < 3; ++k) m.points.push_back({c.x + s * offset(random), c.y + s * offset(random), c.z + s * offset(random)});
        m.faces.push_back({first, first + 1, first + 2});
    }
    return m;
}

Mesh scattered_example() {
    std::mt19937 random(11);
    return scattered(random, 80, 2.0);
}

TEST(Hausdorff, GridSearchFindsTheNearestFaceOfScatteredTriangles) {
    std::mt19937 random(7);
    for (int round = 0; round < 6; ++round) {
        const Mesh a = scattered(random, 150, 10.0);
        const Mesh b = scattered(random, 120, round % 2 == 0 ? 10.0 : 3.0);  // b inside or around a
        expect_same(a, b);
    }
}

TEST(Hausdorff, GridSearchFindsTheNearestFaceOfNearbySurfaces) {
    // A sphere against a coarser, noisier and shifted one: the nearest face is usually in the
    // sample's own cell or the next.
    const Mesh fine = toposimp::testing::noisy_sphere(3, 0.0, 1);
    const Mesh coarse = toposimp::testing::noisy_sphere(2, 0.05, 2, {0.1, -0.05, 0.02});
    expect_same(fine, coarse);
}

// Issue 29, case 13: long thin faces (a polygon split into a fan from one corner) are listed only
// in the cells they meet, in cells sized by their area, and the search still finds every nearest
// face: a fan against a noisy, shifted fan of another size.
Mesh fan(int corners, double radius, double lift, int seed) {
    std::mt19937 random(static_cast<unsigned>(seed));
    std::uniform_real_distribution<double> noise(-0.01, 0.01);
    Mesh m;
    for (int k = 0; k < corners; ++k) {
        const double angle = 2 * 3.141592653589793 * k / corners;
        m.points.push_back({radius * std::cos(angle) * (1 + noise(random)), radius * std::sin(angle), lift + noise(random)});
    }
    for (int k = 1; k + 1 < corners; ++k) m.faces.push_back({0, static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k + 1)});
    return m;
}

TEST(Hausdorff, Issue29ThinFanFacesAreFoundInTheCellsTheyMeet) {
    expect_same(fan(400, 1.0, 0.0, 1), fan(150, 1.05, 0.02, 2));
    expect_same(fan(60, 1.0, 0.0, 3), scattered_example());
}

// At 2^±500 units squared lengths times squared lengths overflow or underflow; the distances are
// measured in a frame that takes the scale out, so they are the unscaled ones times 2^k exactly.
TEST(Hausdorff, ScaledByAPowerOfTwoMeasuresTheSame) {
    const Mesh fine = toposimp::testing::noisy_sphere(3, 0.0, 1);
    const Mesh coarse = toposimp::testing::noisy_sphere(2, 0.05, 2, {0.1, -0.05, 0.02});
    const HausdorffDistance unit = hausdorff(fine, coarse, 20000);
    ASSERT_GT(unit.max(), 0.0);
    for (int k : {-500, 500}) {
        auto scaled = [k](Mesh m) {
            for (Point3& p : m.points) p = {std::ldexp(p.x, k), std::ldexp(p.y, k), std::ldexp(p.z, k)};
            return m;
        };
        const HausdorffDistance d = hausdorff(scaled(fine), scaled(coarse), 20000);
        EXPECT_EQ(d.forward.max, std::ldexp(unit.forward.max, k)) << k;
        EXPECT_EQ(d.backward.max, std::ldexp(unit.backward.max, k)) << k;
        EXPECT_EQ(d.forward.mean, std::ldexp(unit.forward.mean, k)) << k;
        EXPECT_EQ(d.diagonal, std::ldexp(unit.diagonal, k)) << k;
    }
}

}  // namespace
}  // namespace toposimp::mesh

namespace toposimp::mesh {
namespace {

// The quick measure: its points, measured against every face, give its numbers.
void expect_spread_same(const Mesh& a, const Mesh& b, std::size_t count) {
    const HausdorffDistance d = spread_hausdorff(a, b, count);
    for (const auto& [from, to, side] : {std::tuple{&a, &b, d.forward}, std::tuple{&b, &a, d.backward}}) {
        const std::vector<Point3> points = spread_points(*from, count);
        ASSERT_EQ(points.size(), count);
        double most = 0, sum = 0;
        for (const Point3& p : points) {
            double nearest = std::numeric_limits<double>::infinity();
            for (const Face& g : to->faces) nearest = std::min(nearest, to_triangle({p.x, p.y, p.z}, at(*to, g[0]), at(*to, g[1]), at(*to, g[2])));
            most = std::max(most, nearest);
            sum += nearest;
        }
        EXPECT_EQ(side.samples, count);
        expect_close(side.max, most);
        expect_close(side.mean, sum / static_cast<double>(count));
    }
}

// Specks along the diagonal of a big box: a grid of millions of cells for a few thousand faces.
Mesh specks(int count, double shift) {
    Mesh m;
    for (int i = 0; i < count; ++i) {
        const double t = 100.0 * i / count + shift;
        const auto first = static_cast<std::uint32_t>(m.points.size());
        m.points.insert(m.points.end(), {{t, t, t}, {t + 0.01, t, t}, {t, t + 0.01, t + 0.003}});
        m.faces.push_back({first, first + 1, first + 2});
    }
    return m;
}

TEST(QuickMeasure, IndexingOnlyNearTheSpreadPointsFindsTheNearestFaces) {
    const Mesh fine = toposimp::testing::noisy_sphere(3, 0.0, 1);
    const Mesh coarse = toposimp::testing::noisy_sphere(2, 0.05, 2, {0.1, -0.05, 0.02});
    expect_spread_same(fine, coarse, 2000);
    // Far apart: every search leaves the first shells, and the cells around are filled wider.
    expect_spread_same(fine, toposimp::testing::noisy_sphere(2, 0.05, 3, {6.0, 1.0, -2.0}), 500);
    std::mt19937 random(5);
    expect_spread_same(scattered(random, 150, 10.0), scattered(random, 120, 3.0), 1500);
    expect_spread_same(fan(400, 1.0, 0.0, 1), fan(150, 1.05, 0.02, 2), 1000);
    // Specks: the entries of millions of cells are sorted by cell in passes (not counted per cell).
    expect_spread_same(specks(3000, 0.0), specks(800, 0.02), 1200);
}

// At least eight times as many faces as points (the input, measured from the points of the
// output): one pass over the faces measures the points in blocks of a quarter cell around them;
// up to 8 it leaves open finish in one more pass, more in the indexed search. The same numbers as
// every face measured, for any thread count.
TEST(QuickMeasure, OnePassOverManyFacesFindsTheNearestFaces) {
    const Mesh fine = toposimp::testing::noisy_sphere(4, 0.01, 1);  // 5 120 faces: two chunks of the pass
    const Mesh coarse = toposimp::testing::noisy_sphere(2, 0.05, 2, {0.1, -0.05, 0.02});
    expect_spread_same(coarse, fine, 300);
    expect_spread_same(fine, fine, 600);  // every distance zero
    // Points a little off the surface, farther than their blocks reach: with 8 points, 4 are left
    // to the second pass, with 50, 20 to the search; 8 points further off leave 7 to the second
    // pass, three of them nearer to a face outside their blocks (the counts when this test was
    // written).
    auto scaled = [](Mesh m, double by) {
        for (Point3& p : m.points) p = {p.x * by, p.y * by, p.z * by};
        return m;
    };
    const Mesh around = scaled(toposimp::testing::noisy_sphere(1, 0.0, 9), 1.01);
    expect_spread_same(around, fine, 8);
    expect_spread_same(around, fine, 50);
    expect_spread_same(scaled(toposimp::testing::noisy_sphere(2, 0.0, 9), 1.08), fine, 8);
    // Far apart: the pass leaves every point open, with no face measured; the search finishes them.
    expect_spread_same(toposimp::testing::noisy_sphere(2, 0.05, 3, {6.0, 1.0, -2.0}), fine, 200);
    expect_spread_same(toposimp::testing::noisy_sphere(2, 0.05, 3, {6.0, 1.0, -2.0}), fine, 5);
    // Long thin faces, whose boxes span many cells; specks in a grid of millions of cells.
    expect_spread_same(fan(150, 1.05, 0.02, 2), fan(4000, 1.0, 0.0, 1), 400);
    expect_spread_same(specks(800, 0.02), specks(6000, 0.0), 300);
    std::mt19937 random(7);
    expect_spread_same(scattered(random, 100, 3.0), scattered(random, 1500, 10.0), 150);
    // (The coarse sphere's points against the fine one's faces take the pass.)
    for (const int threads : {2, 3}) {
        const HausdorffDistance one = spread_hausdorff(coarse, fine, 300, 1), more = spread_hausdorff(coarse, fine, 300, threads);
        EXPECT_EQ(one.forward.max, more.forward.max);
        EXPECT_EQ(one.forward.mean, more.forward.mean);
        EXPECT_EQ(one.backward.max, more.backward.max);
        EXPECT_EQ(one.backward.mean, more.backward.mean);
    }
}

// The quick measure's points: one per 40 input faces, from 1 024 to 8 192; and the share of a
// surface that may lie beyond the largest distance they find, at 99.9 % confidence.
TEST(QuickMeasure, PointsGrowWithTheInputWithinBounds) {
    EXPECT_EQ(quick_points(0), 1024u);
    EXPECT_EQ(quick_points(40 * 1024 - 1), 1024u);
    EXPECT_EQ(quick_points(40 * 3000), 3000u);
    EXPECT_EQ(quick_points(40 * 8192 + 39), 8192u);
    EXPECT_EQ(quick_points(100000000), 8192u);
    for (const std::size_t points : {1024u, 2000u, 8192u}) {
        const double share = share_beyond(points);
        EXPECT_NEAR(std::pow(1 - share, static_cast<double>(points)), 0.001, 1e-9) << points;
    }
    EXPECT_NEAR(share_beyond(8192), 8.43e-4, 1e-6);
    EXPECT_GT(share_beyond(1024), share_beyond(8192));
}

TEST(QuickMeasure, PointsAreSpreadByAreaAndTheSameForAnyThreads) {
    const Mesh fine = toposimp::testing::noisy_sphere(3, 0.02, 4);
    const Mesh coarse = toposimp::testing::noisy_sphere(2, 0.05, 5);
    const HausdorffDistance one = spread_hausdorff(fine, coarse, 4096, 1), two = spread_hausdorff(fine, coarse, 4096, 2);
    EXPECT_EQ(one.forward.max, two.forward.max);
    EXPECT_EQ(one.forward.mean, two.forward.mean);
    EXPECT_EQ(one.backward.max, two.backward.max);
    // A lower bound of the full measure's largest distance (which includes every vertex).
    const HausdorffDistance full = hausdorff(fine, coarse, 200000);
    EXPECT_LE(one.max(), full.max() * (1 + 1e-12));
    EXPECT_GT(one.max(), 0.5 * full.max());
    // Two faces of areas 1 and 3 get a quarter and three quarters of the points.
    Mesh two_faces;
    two_faces.points = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {10, 0, 0}, {13, 0, 0}, {10, 2, 0}};
    two_faces.faces = {{0, 1, 2}, {3, 4, 5}};
    std::size_t on_first = 0;
    for (const Point3& p : spread_points(two_faces, 1000)) on_first += p.x < 5;
    EXPECT_EQ(on_first, 250u);
}

// For terrains both quick measures come from one plan index: the same numbers as each alone,
// also where the border moved (points with no face above or below are measured in space).
TEST(QuickMeasure, TerrainMeasureEqualsTheTwoMeasuresAlone) {
    const Mesh ground = toposimp::testing::noisy_heightfield(40, 0.3, 6);
    Mesh moved = toposimp::testing::noisy_heightfield(25, 0.3, 7);
    for (Point3& p : moved.points) p = {p.x * 40.0 / 25.0 + 0.7, p.y * 40.0 / 25.0 - 0.4, p.z + 0.05};
    for (const auto& [a, b] : {std::pair<const Mesh*, const Mesh*>{&ground, &moved}, std::pair<const Mesh*, const Mesh*>{&moved, &ground}}) {
        const TerrainMeasure both = spread_terrain_measure(*a, *b, 3000);
        const HausdorffDistance distance = spread_hausdorff(*a, *b, 3000);
        const VerticalError vertical = spread_vertical_error(*a, *b, 3000);
        EXPECT_EQ(both.distance.forward.max, distance.forward.max);
        EXPECT_EQ(both.distance.backward.max, distance.backward.max);
        expect_close(both.distance.forward.mean, distance.forward.mean);
        EXPECT_EQ(both.vertical.forward.max, vertical.forward.max);
        EXPECT_EQ(both.vertical.backward.max, vertical.backward.max);
        EXPECT_EQ(both.vertical.outside, vertical.outside);
        EXPECT_GT(both.vertical.outside, 0u);
        EXPECT_LE(both.distance.max(), both.vertical.max() * (1 + 1e-9));
    }
}

}  // namespace
}  // namespace toposimp::mesh
