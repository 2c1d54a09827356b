// 3D predicates on near-degenerate input: the filter agrees with GMP everywhere, and plain
// doubles get some of these cases wrong.
#include "core/exact/predicates3d.hpp"

#include "support/mesh_checker.hpp"

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace toposimp::exact {
namespace {

Point3 up(Point3 p, int ulps) {
    for (int k = 0; k < std::abs(ulps); ++k) p.z = std::nextafter(p.z, ulps > 0 ? INFINITY : -INFINITY);
    return p;
}

// The determinant in GMP rationals, written here independently of the library.
int reference_orient3d(Point3 a, Point3 b, Point3 c, Point3 d) {
    auto q = [](double x) { return mpq_class(x); };
    const mpq_class bx = q(b.x) - q(a.x), by = q(b.y) - q(a.y), bz = q(b.z) - q(a.z);
    const mpq_class cx = q(c.x) - q(a.x), cy = q(c.y) - q(a.y), cz = q(c.z) - q(a.z);
    const mpq_class dx = q(d.x) - q(a.x), dy = q(d.y) - q(a.y), dz = q(d.z) - q(a.z);
    const mpq_class det = (by * cz - bz * cy) * dx + (bz * cx - bx * cz) * dy + (bx * cy - by * cx) * dz;
    return sgn(det);
}

TEST(Orient3d, SignsOfSimpleCases) {
    PredicateStats stats;
    const Point3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_EQ(orient3d(a, b, c, {0, 0, 1}, stats), 1);
    EXPECT_EQ(orient3d(a, b, c, {0, 0, -1}, stats), -1);
    EXPECT_EQ(orient3d(a, b, c, {5, 7, 0}, stats), 0);
    EXPECT_EQ(orient3d(a, b, c, {0, 0, 0x1p-1074}, stats), 1);  // the smallest subnormal above
}

TEST(Orient3d, FilterAgreesWithGmpNearPlanesWhereDoublesFail) {
    // Points on (or one ulp off) the plane through three points with large, mixed coordinates.
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> coordinate(-1e6, 1e6);
    PredicateStats stats;
    int float_wrong = 0, cases = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const Point3 a{coordinate(random), coordinate(random), coordinate(random)};
        const Point3 b{coordinate(random), coordinate(random), coordinate(random)};
        const Point3 c{coordinate(random), coordinate(random), coordinate(random)};
        // d on the segment between a and b, rounded: within an ulp or so of abc's plane.
        const double t = std::uniform_real_distribution<double>(0, 1)(random);
        Point3 d{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
        d = up(d, static_cast<int>(trial % 3) - 1);
        const int truth = orient3d_gmp(a, b, c, d);
        EXPECT_EQ(truth, reference_orient3d(a, b, c, d));
        EXPECT_EQ(orient3d(a, b, c, d, stats), truth);
        if (orient3d_float(a, b, c, d) != truth) ++float_wrong;
        ++cases;
    }
    EXPECT_GT(float_wrong, 0) << "plain doubles should get some of " << cases << " cases wrong";
    EXPECT_GT(stats.expansion_decided, 0u) << "the filters cannot decide points within an ulp of the plane";
}

// PlaneSide (one triangle, many points, its own filter) gives orient3d's sign on the hard cases:
// points on the plane through three points with large mixed coordinates, and one ulp off it;
// exact zeros; a subnormal above the plane; huge and tiny coordinates; mixed magnitudes.
TEST(PlaneSide, AgreesWithRationalsNearThePlane) {
    std::mt19937_64 random(17);
    PredicateStats stats;
    for (const double scale : {1e6, 1.0, 1e-6, 0x1p-600, 0x1p600, 0x1p-1000, 0x1p900}) {
        std::uniform_real_distribution<double> coordinate(-scale, scale);
        for (int trial = 0; trial < 3000; ++trial) {
            auto point = [&] { return Point3{coordinate(random), coordinate(random), coordinate(random)}; };
            const Point3 a = point(), b = point(), c = point();
            const PlaneSide side(a, b, c);
            for (int k = 0; k < 4; ++k) {
                const double s = std::uniform_real_distribution<double>(0, 1)(random), t = std::uniform_real_distribution<double>(0, 1)(random);
                Point3 d{a.x + s * (b.x - a.x) + t * (c.x - a.x), a.y + s * (b.y - a.y) + t * (c.y - a.y),
                         a.z + s * (b.z - a.z) + t * (c.z - a.z)};
                if (k == 3) d = point();
                d = up(d, trial % 3 - 1);
                ASSERT_EQ(side(d, stats), reference_orient3d(a, b, c, d)) << scale << ' ' << trial << ' ' << k;
            }
            for (const Point3& corner : {a, b, c}) ASSERT_EQ(side(corner, stats), 0);
        }
    }
    EXPECT_GT(stats.filter_decided, 0u);
    EXPECT_GT(stats.expansion_decided, 0u) << "points within an ulp of the plane are beyond any filter";
    // Exact zeros and the smallest offsets, on an axis-aligned plane and on an oblique one whose
    // points have mixed magnitudes.
    const PlaneSide flat({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    EXPECT_EQ(flat({5, 7, 0}, stats), 0);
    EXPECT_EQ(flat({5, 7, 0x1p-1074}, stats), 1);
    EXPECT_EQ(flat({-5, 7, -0x1p-1074}, stats), -1);
    const Point3 a{1e-300, 3, 2e15}, b{7e15, -1e-290, 5}, c{-2, 4e15, 1e-300};
    const PlaneSide oblique(a, b, c);
    for (const Point3 d : {Point3{1e-300, 3, 2e15}, up(Point3{1e-300, 3, 2e15}, 1), Point3{7e15 / 2, 2e15, 0}, Point3{0, 0, 0}}) {
        EXPECT_EQ(oblique(d, stats), reference_orient3d(a, b, c, d));
    }
}

// The expansion stage alone against the rational reference: points exactly on oblique planes
// (the exact zeros of flat CAD regions), one and a few ulps off them, with coordinates of mixed
// magnitude and sign (so the differences themselves are inexact in doubles), across the whole
// range the stage accepts; outside it, it declines.
TEST(Orient3dExpansion, AgreesWithRationalsOnAndNearObliquePlanes) {
    std::mt19937_64 random(11);
    int zeros = 0, nonzeros = 0;
    // The reference sign, or 2 where a magnitude lies outside [2^-150, 2^150] (the extreme
    // scales and subnormal nudges here), which the stage must decline.
    auto expected = [](Point3 a, Point3 b, Point3 c, Point3 d) {
        for (const Point3& x : {a, b, c, d}) {
            for (const double v : {x.x, x.y, x.z}) {
                if (v != 0 && !(std::fabs(v) >= 0x1p-150 && std::fabs(v) <= 0x1p150)) return 2;
            }
        }
        return reference_orient3d(a, b, c, d);
    };
    for (const double scale : {0x1p-140, 0x1p-60, 1e-3, 1.0, 1e5, 0x1p60, 0x1p140}) {
        std::uniform_int_distribution<int> small(-1000, 1000);
        std::uniform_real_distribution<double> unit(-1, 1);
        for (int trial = 0; trial < 3000; ++trial) {
            // Exactly coplanar: integer points on the plane x + 2y + 3z = k, scaled by a power
            // of two (exact), then moved by whole multiples of a vector in the plane.
            auto on_plane = [&](int k) {
                const int y = small(random), z = small(random);
                return Point3{std::ldexp(k - 2.0 * y - 3.0 * z, std::ilogb(scale)), std::ldexp(y, std::ilogb(scale)),
                              std::ldexp(z, std::ilogb(scale))};
            };
            const int k = small(random);
            const Point3 a = on_plane(k), b = on_plane(k), c = on_plane(k);
            Point3 d = on_plane(k);
            if (trial % 3 == 1) d = up(d, 1 + trial % 5);
            if (trial % 3 == 2) {
                // Random points of mixed magnitude, d on the rounded segment ab: the differences
                // (b − a etc.) are not exact in doubles.
                const Point3 p{scale * unit(random), scale * 1e-6 * unit(random), scale * 1e3 * unit(random)};
                const Point3 q{-scale * unit(random), scale * unit(random), scale * 1e-3 * unit(random)};
                const Point3 r{scale * 7 * unit(random), -scale * unit(random), scale * unit(random)};
                const double t = std::uniform_real_distribution<double>(0, 1)(random);
                const Point3 m{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)};
                EXPECT_EQ(orient3d_expansion(p, q, r, m), expected(p, q, r, m)) << scale << " trial " << trial;
                continue;
            }
            const int truth = expected(a, b, c, d);
            if (truth != 2) (truth == 0 ? zeros : nonzeros) += 1;
            EXPECT_EQ(orient3d_expansion(a, b, c, d), truth) << scale << " trial " << trial;
        }
    }
    EXPECT_GT(zeros, 1000);
    EXPECT_GT(nonzeros, 1000);
    // Outside [2^-150, 2^150] the stage declines and GMP decides.
    EXPECT_EQ(orient3d_expansion({0, 0, 0}, {1e200, 0, 0}, {0, 1, 0}, {0, 0, 1}), 2);
    EXPECT_EQ(orient3d_expansion({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1e-200}), 2);
    EXPECT_EQ(orient3d_expansion({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, -0x1p-150}), -1);
}

TEST(Orient3d, HugeAndTinyCoordinates) {
    PredicateStats stats;
    for (double scale : {0x1p-1000, 0x1p-500, 1.0, 0x1p500, 0x1p900}) {
        const Point3 a{0, 0, 0}, b{scale, 0, 0}, c{0, scale, 0};
        const Point3 above{scale / 3, scale / 3, std::nextafter(0.0, 1.0)};
        EXPECT_EQ(orient3d(a, b, c, above, stats), orient3d_gmp(a, b, c, above)) << scale;
        EXPECT_EQ(orient3d_gmp(a, b, c, above), reference_orient3d(a, b, c, above)) << scale;
        EXPECT_EQ(orient3d(a, b, c, above, stats), 1) << scale;
        const Point3 on{scale / 4, scale / 2, 0};
        EXPECT_EQ(orient3d(a, b, c, on, stats), 0) << scale;
    }
}

// Far outside the filters' and expansions' range (coordinates of 2^±500 and 2^±900) the points
// are scaled by a power of two towards 1, which is exact, and decided there without GMP; with
// coordinates of very different magnitudes the scaling would lose bits of the small ones, and
// GMP decides. Points within an ulp of a plane: the sign agrees with rationals every time.
TEST(Orient3d, OutOfRangeInputsAreScaledExactlyOrGoToGmp) {
    std::mt19937_64 random(41);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    for (int exponent : {-900, -500, 500, 900}) {
        PredicateStats stats;
        const double s = std::ldexp(1.0, exponent);
        for (int trial = 0; trial < 3000; ++trial) {
            auto point = [&] { return Point3{s * coordinate(random), s * coordinate(random), s * coordinate(random)}; };
            const Point3 a = point(), b = point(), c = point();
            const double t = std::uniform_real_distribution<double>(0, 1)(random);
            Point3 d{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
            d = up(d, trial % 3 - 1);
            ASSERT_EQ(orient3d(a, b, c, d, stats), reference_orient3d(a, b, c, d)) << exponent << ' ' << trial;
        }
        EXPECT_EQ(stats.gmp_fallbacks, 0u) << exponent;
    }
    // One coordinate 2^-1000 among others near 2^500: scaled by 2^-500 it would be subnormal.
    PredicateStats stats;
    const double big = 0x1p500;
    const Point3 a{0x1p-1000, 0, 0}, b{big, 0, 0}, c{0, big, 0};
    for (const Point3 d : {Point3{big / 3, big / 3, 0}, Point3{big / 3, big / 3, 0x1p-1000}, Point3{big / 3, big / 3, -0x1p-1074}}) {
        EXPECT_EQ(orient3d(a, b, c, d, stats), reference_orient3d(a, b, c, d));
    }
    EXPECT_GT(stats.gmp_fallbacks, 0u);
}

TEST(NormalDot, OppositeAndDegenerate) {
    PredicateStats stats;
    const Point3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_EQ(normal_dot_sign(a, b, c, a, b, c, stats), 1);
    EXPECT_EQ(normal_dot_sign(a, b, c, a, c, b, stats), -1);
    EXPECT_EQ(normal_dot_sign(a, b, c, a, b, {2, 0, 0}, stats), 0);  // collinear
    // A triangle tilted by one ulp against a vertical one: orthogonal in exact arithmetic?
    const Point3 v1{0, 0, 0}, v2{1, 0, 0}, v3{0, 0, 1};
    EXPECT_EQ(normal_dot_sign(a, b, c, v1, v2, v3, stats), 0);
    EXPECT_EQ(normal_dot_sign(a, b, c, v1, v2, {0, 0x1p-60, 1}, stats), 1);
}

// Normals of two triangles nearly orthogonal (the second's plane holds the first's normal up to
// a few ulps), at scales from 2^-300 to 2^300 (outside the semi-static filter's range at both
// ends): normal_dot_sign agrees with rationals, and plain doubles get some signs wrong.
TEST(NormalDot, AgreesWithRationalsNearOrthogonal) {
    auto reference = [](Point3 a, Point3 b, Point3 c, Point3 d, Point3 e, Point3 f) {
        auto q = [](double x) { return mpq_class(x); };
        const mpq_class bx = q(b.x) - q(a.x), by = q(b.y) - q(a.y), bz = q(b.z) - q(a.z), cx = q(c.x) - q(a.x),
                        cy = q(c.y) - q(a.y), cz = q(c.z) - q(a.z);
        const mpq_class ex = q(e.x) - q(d.x), ey = q(e.y) - q(d.y), ez = q(e.z) - q(d.z), fx = q(f.x) - q(d.x),
                        fy = q(f.y) - q(d.y), fz = q(f.z) - q(d.z);
        return sgn((by * cz - bz * cy) * (ey * fz - ez * fy) + (bz * cx - bx * cz) * (ez * fx - ex * fz) +
                   (bx * cy - by * cx) * (ex * fy - ey * fx));
    };
    std::mt19937_64 random(29);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    std::uniform_int_distribution<int> ulps(-3, 3), scale(0, 4);
    PredicateStats stats;
    int naive_wrong = 0, nonzero = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const double s = std::ldexp(1.0, std::array{-300, -20, 0, 40, 300}[static_cast<std::size_t>(scale(random))]);
        auto point = [&] { return Point3{s * coordinate(random), s * coordinate(random), s * coordinate(random)}; };
        const Point3 a = point(), b = point(), c = point(), d = point(), w = point();
        // e − d along the first triangle's normal (rounded), nudged by a few ulps.
        const double nx = (b.y - a.y) * (c.z - a.z) - (b.z - a.z) * (c.y - a.y);
        const double ny = (b.z - a.z) * (c.x - a.x) - (b.x - a.x) * (c.z - a.z);
        const double nz = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        const double norm = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!(norm > 0) || !std::isfinite(norm)) continue;
        Point3 e{d.x + s * nx / norm, d.y + s * ny / norm, d.z + s * nz / norm};
        for (int k = ulps(random); k != 0; k += k > 0 ? -1 : 1) e.x = std::nextafter(e.x, k > 0 ? INFINITY : -INFINITY);
        const Point3 f = w;
        const int expected = reference(a, b, c, d, e, f);
        EXPECT_EQ(normal_dot_sign(a, b, c, d, e, f, stats), expected) << "trial " << trial;
        const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z, cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z;
        const double ex = e.x - d.x, ey = e.y - d.y, ez = e.z - d.z, fx = f.x - d.x, fy = f.y - d.y, fz = f.z - d.z;
        const double naive = (by * cz - bz * cy) * (ey * fz - ez * fy) + (bz * cx - bx * cz) * (ez * fx - ex * fz) +
                             (bx * cy - by * cx) * (ex * fy - ey * fx);
        naive_wrong += ((naive > 0) - (naive < 0)) != expected;
        nonzero += expected != 0;
    }
    EXPECT_GT(naive_wrong, 100);
    EXPECT_GT(nonzero, 10000);
}

TEST(SegmentTriangle, TouchesAndMisses) {
    PredicateStats stats;
    const Triangle3 t{Point3{0, 0, 0}, Point3{4, 0, 0}, Point3{0, 4, 0}};
    EXPECT_TRUE(segment_meets_triangle({1, 1, -1}, {1, 1, 1}, t, stats));    // pierces
    EXPECT_TRUE(segment_meets_triangle({2, 2, -1}, {2, 2, 1}, t, stats));    // through the hypotenuse
    EXPECT_TRUE(segment_meets_triangle({1, 1, 0}, {1, 1, 5}, t, stats));     // endpoint on the face
    EXPECT_TRUE(segment_meets_triangle({0, 0, 1}, {0, 0, -1}, t, stats));    // through a corner
    EXPECT_FALSE(segment_meets_triangle({1, 1, 0x1p-1000}, {1, 1, 5}, t, stats));  // just above
    EXPECT_TRUE(segment_meets_triangle({-1, 1, 0}, {1, 1, 0}, t, stats));    // coplanar, crosses an edge
    EXPECT_FALSE(segment_meets_triangle({-1, 1, 0}, {-0.5, 1, 0}, t, stats));  // coplanar, outside
    EXPECT_TRUE(segment_meets_triangle({-1, 0, 0}, {5, 0, 0}, t, stats));    // along an edge
    // Just beyond the hypotenuse x + y = 4 by the smallest step in x.
    const double x = std::nextafter(2.0, 3.0);
    EXPECT_FALSE(segment_meets_triangle({x, 2, -1}, {x, 2, 1}, t, stats));
    // Degenerate triangle (a segment) crossed by a segment.
    const Triangle3 flat{Point3{0, 0, 0}, Point3{2, 2, 2}, Point3{1, 1, 1}};
    EXPECT_TRUE(segment_meets_triangle({0, 2, 1}, {2, 0, 1}, flat, stats));
    EXPECT_FALSE(segment_meets_triangle({0, 2, 1.5}, {2, 0, 1.5}, flat, stats));
}

TEST(FacesConflict, SharedCornersAndEdges) {
    PredicateStats stats;
    const Point3 s{0, 0, 0}, a{1, 0, 0}, b{0, 1, 0};
    const Triangle3 f{s, a, b};
    // Share the corner s, other face below the plane: fine.
    EXPECT_FALSE(faces_conflict(f, {s, Point3{-1, 0, -1}, Point3{0, -1, -1}}, stats));
    // Share s, coplanar, in the opposite quadrant: fine; overlapping angle: conflict.
    EXPECT_FALSE(faces_conflict(f, {s, Point3{-1, 0, 0}, Point3{0, -1, 0}}, stats));
    EXPECT_TRUE(faces_conflict(f, {s, Point3{1, 1, 0}, Point3{2, 1, 0}}, stats));
    // Share s, non-coplanar, but the other face pierces f: conflict.
    EXPECT_TRUE(faces_conflict(f, {s, Point3{0.5, 0.2, 1}, Point3{0.2, 0.5, -1}}, stats));
    // Share an edge: a hinge is fine, a coplanar fold-over is a conflict.
    EXPECT_FALSE(faces_conflict(f, {a, b, Point3{1, 1, 0}}, stats));
    EXPECT_FALSE(faces_conflict(f, {a, b, Point3{0.2, 0.2, 1}}, stats));
    EXPECT_TRUE(faces_conflict(f, {a, b, Point3{0.2, 0.2, 0}}, stats));
    // The fold one ulp out of the plane is a legitimate (very sharp) hinge.
    EXPECT_FALSE(faces_conflict(f, {a, b, Point3{0.2, 0.2, 0x1p-1074}}, stats));
    // Same three corners: a duplicate.
    EXPECT_TRUE(faces_conflict(f, {b, s, a}, stats));
    // No shared corner, touching at a point: conflict.
    EXPECT_TRUE(faces_conflict(f, {Point3{0.25, 0.25, 0}, Point3{1, 1, 1}, Point3{0, 1, 1}}, stats));
}

}  // namespace
}  // namespace toposimp::exact

namespace toposimp::exact {
namespace {

// A point with small integer coordinates on the oblique plane x + 2y + 3z = 7: exactly
// representable, and close enough to its neighbours that touching and collinear cases abound.
Point3 on_oblique_plane(std::mt19937_64& random) {
    std::uniform_int_distribution<int> small(-4, 4);
    const int y = small(random), z = small(random);
    return Point3{7.0 - 2.0 * y - 3.0 * z, static_cast<double>(y), static_cast<double>(z)};
}

// Coplanar pairs on an oblique plane (as in flat CAD regions, where triangles_meet decides in
// one projection), with small integer coordinates so that touching, overlapping, nested and
// disjoint pairs all occur, some with u one ulp off the plane: triangles_meet agrees with the
// tests' independent checker (exact plane cuts and polygon clipping in rationals).
TEST(TrianglesMeet, CoplanarPairsAgreeWithTheIndependentChecker) {
    std::mt19937_64 random(5);
    auto on_plane = [&] { return on_oblique_plane(random); };
    PredicateStats stats;
    int meeting = 0, apart = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const Triangle3 t{on_plane(), on_plane(), on_plane()};
        Triangle3 u{on_plane(), on_plane(), on_plane()};
        if (trial % 4 == 3) u[trial % 3].x = std::nextafter(u[trial % 3].x, 100.0);  // off the plane
        bool shares = false;
        for (const Point3& p : t) {
            for (const Point3& q : u) shares = shares || (p.x == q.x && p.y == q.y && p.z == q.z);
        }
        // The checker allows contact at shared corners and reports degenerate faces instead
        // of their contacts.
        if (shares || degenerate(t, stats) || degenerate(u, stats)) continue;
        mesh::Mesh pair;
        pair.points = {t[0], t[1], t[2], u[0], u[1], u[2]};
        pair.faces = {{0, 1, 2}, {3, 4, 5}};
        const bool checker = testing::find_defects(pair).intersecting_pairs > 0;
        EXPECT_EQ(triangles_meet(t, u, stats), checker) << "trial " << trial;
        EXPECT_EQ(triangles_meet(u, t, stats), checker) << "trial " << trial << " (swapped)";
        (checker ? meeting : apart) += 1;
    }
    EXPECT_GT(meeting, 300);
    EXPECT_GT(apart, 300);
}

// How many corners of f share their location with one of g's.
int shared_corners(const Triangle3& f, const Triangle3& g) {
    int shared = 0;
    for (const Point3& p : f) {
        for (const Point3& q : g) shared += same_location(p, q);
    }
    return shared;
}

// The checker's verdict on faces sharing the corner f[i] = g[j] (one vertex of the pair).
bool checker_finds_contact(const Triangle3& f, int i, const Triangle3& g, int j) {
    mesh::Mesh pair;
    pair.points = {f[0], f[1], f[2], g[(j + 1) % 3], g[(j + 2) % 3]};
    mesh::Face second{};
    second[j] = static_cast<std::uint32_t>(i);
    second[(j + 1) % 3] = 3;
    second[(j + 2) % 3] = 4;
    pair.faces = {{0, 1, 2}, second};
    return testing::find_defects(pair).intersecting_pairs > 0;
}

// Coplanar faces sharing one corner (fans of a flat region, where faces_conflict first looks for
// a line through the corner that separates them): its answer agrees with the checker's.
TEST(FacesConflict, CoplanarFacesSharingOneCornerAgreeWithTheIndependentChecker) {
    std::mt19937_64 random(9);
    auto on_plane = [&] { return on_oblique_plane(random); };
    PredicateStats stats;
    int conflicts = 0, clean = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const Point3 s = on_plane();
        const Triangle3 f{s, on_plane(), on_plane()};
        const Triangle3 g{on_plane(), s, on_plane()};
        if (degenerate(f, stats) || degenerate(g, stats) || shared_corners(f, g) != 1) continue;
        const bool checker = checker_finds_contact(f, 0, g, 1);
        EXPECT_EQ(faces_conflict(f, g, stats), checker) << "trial " << trial;
        EXPECT_EQ(faces_conflict(g, f, stats), checker) << "trial " << trial << " (swapped)";
        (checker ? conflicts : clean) += 1;
    }
    EXPECT_GT(conflicts, 300);
    EXPECT_GT(clean, 300);
}

// Faces sharing one corner in space (the pairs around a collapsed star), small integer
// coordinates so that corners in the other's plane, edges through the other face and crossings
// exactly at an edge all occur: faces_conflict agrees with the checker, with and without the
// sides of g's corners given (given, some as kSideUnknown).
TEST(FacesConflict, FacesSharingOneCornerInSpaceAgreeWithTheIndependentChecker) {
    std::mt19937_64 random(13);
    std::uniform_int_distribution<int> small(-3, 3);
    auto point = [&] { return Point3{static_cast<double>(small(random)), static_cast<double>(small(random)), static_cast<double>(small(random))}; };
    PredicateStats stats;
    int conflicts = 0, clean = 0, crossing_each_other = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const Point3 s = point();
        const Triangle3 f{point(), s, point()};
        const Triangle3 g{point(), point(), s};
        if (degenerate(f, stats) || degenerate(g, stats) || shared_corners(f, g) != 1) continue;
        const bool checker = checker_finds_contact(f, 1, g, 2);
        std::array<int, 3> g_sides{}, f_sides{};
        for (int k = 0; k < 3; ++k) {
            g_sides[k] = reference_orient3d(f[0], f[1], f[2], g[k]);
            f_sides[k] = reference_orient3d(g[0], g[1], g[2], f[k]);
        }
        if (g_sides[0] * g_sides[1] < 0 && f_sides[0] * f_sides[2] < 0) ++crossing_each_other;
        std::array<int, 3> partly = g_sides;
        partly[trial % 3] = kSideUnknown;
        EXPECT_EQ(faces_conflict(f, g, stats), checker) << "trial " << trial;
        EXPECT_EQ(faces_conflict(f, g, g_sides, stats), checker) << "trial " << trial << " (sides given)";
        EXPECT_EQ(faces_conflict(f, g, partly, stats), checker) << "trial " << trial << " (some sides given)";
        EXPECT_EQ(faces_conflict(g, f, f_sides, stats), checker) << "trial " << trial << " (swapped)";
        (checker ? conflicts : clean) += 1;
    }
    EXPECT_GT(conflicts, 1000);
    EXPECT_GT(clean, 1000);
    EXPECT_GT(crossing_each_other, 1000);
}

// Faces apart in index but close in space (a fold of the surface near a collapsed star), with
// small integer coordinates so that a corner or an edge of one face resting on the other's
// plane is common (as along the creases of CAD models), besides pairs each strictly across the
// other's plane: triangles_meet and faces_conflict agree with the checker, the sides given or
// not.
TEST(TrianglesMeet, PairsInSpaceAgreeWithTheIndependentChecker) {
    std::mt19937_64 random(17);
    std::uniform_int_distribution<int> small(-2, 2);
    auto point = [&] { return Point3{static_cast<double>(small(random)), static_cast<double>(small(random)), static_cast<double>(small(random))}; };
    auto counts = [](const Triangle3& t, const Triangle3& u) {  // u's corners: on t's plane, above, below
        std::array<int, 3> count{};
        for (const Point3& p : u) {
            const int side = reference_orient3d(t[0], t[1], t[2], p);
            ++count[side == 0 ? 0 : side > 0 ? 1 : 2];
        }
        return count;
    };
    auto rests_on = [&](const Triangle3& t, const Triangle3& u) {  // u touches t's plane, not crossing it
        const auto [zero, positive, negative] = counts(t, u);
        return zero > 0 && zero < 3 && (positive == 0) != (negative == 0);
    };
    auto crosses = [&](const Triangle3& t, const Triangle3& u) {  // u strictly across t's plane
        const auto [zero, positive, negative] = counts(t, u);
        return zero == 0 && positive > 0 && negative > 0;
    };
    PredicateStats stats;
    int meeting = 0, apart = 0, resting = 0, resting_meeting = 0, crossing = 0, crossing_meeting = 0;
    for (int trial = 0; trial < 30000; ++trial) {
        const Triangle3 t{point(), point(), point()};
        const Triangle3 u{point(), point(), point()};
        if (shared_corners(t, u) != 0 || degenerate(t, stats) || degenerate(u, stats)) continue;
        mesh::Mesh pair;
        pair.points = {t[0], t[1], t[2], u[0], u[1], u[2]};
        pair.faces = {{0, 1, 2}, {3, 4, 5}};
        const bool checker = testing::find_defects(pair).intersecting_pairs > 0;
        std::array<int, 3> u_sides{};
        for (int k = 0; k < 3; ++k) u_sides[k] = reference_orient3d(t[0], t[1], t[2], u[k]);
        EXPECT_EQ(triangles_meet(t, u, stats), checker) << "trial " << trial;
        EXPECT_EQ(triangles_meet(u, t, stats), checker) << "trial " << trial << " (swapped)";
        EXPECT_EQ(faces_conflict(t, u, u_sides, stats), checker) << "trial " << trial << " (sides given)";
        (checker ? meeting : apart) += 1;
        if (rests_on(t, u) || rests_on(u, t)) {
            ++resting;
            resting_meeting += checker;
        }
        if (crosses(t, u) && crosses(u, t)) {
            ++crossing;
            crossing_meeting += checker;
        }
    }
    EXPECT_GT(meeting, 1000);
    EXPECT_GT(apart, 1000);
    EXPECT_GT(resting_meeting, 300);
    EXPECT_GT(resting - resting_meeting, 300);
    EXPECT_GT(crossing_meeting, 300);
    EXPECT_GT(crossing - crossing_meeting, 300);
}

// Fans around p, as a collapse to p makes them: rings around p (small integer coordinates, so
// corners on a triangle's line through p, on the counting ray and in one plane are common),
// rings winding twice around p, and random rings. Whenever simple_fan passes a fan, the checker
// finds no two of its triangles meeting beyond their shared corner or edge (and no degenerate
// one); it passes most rings around p and never one winding twice.
TEST(SimpleFan, PassesOnlyFansWhoseTrianglesDoNotMeet) {
    std::mt19937_64 random(21);
    std::uniform_int_distribution<int> small(-3, 3), radius(1, 4);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    PredicateStats stats;
    int passed = 0, around = 0, refused_meeting = 0;
    for (int trial = 0; trial < 6000; ++trial) {
        const int kind = trial % 3;  // 0 around p, 1 twice around p, 2 random
        const std::size_t n = 3 + static_cast<std::size_t>(trial / 3) % 6 + (kind == 1 ? 2 : 0);
        const Point3 p{static_cast<double>(small(random)), static_cast<double>(small(random)), static_cast<double>(small(random))};
        std::vector<Point3> ring;
        for (std::size_t i = 0; i < n; ++i) {
            if (kind == 2) {
                ring.push_back({p.x + small(random), p.y + small(random), p.z + small(random)});
                continue;
            }
            const double turns = kind == 0 ? 1.0 : 2.0;
            const double angle = 2 * M_PI * turns * (static_cast<double>(i) + jitter(random)) / static_cast<double>(n);
            const double r = radius(random);
            ring.push_back({p.x + std::round(r * std::cos(angle)), p.y + std::round(r * std::sin(angle)), p.z + small(random) / 2});
        }
        mesh::Mesh fan;
        fan.points.push_back(p);
        fan.points.insert(fan.points.end(), ring.begin(), ring.end());
        for (std::size_t i = 0; i < n; ++i) {
            fan.faces.push_back({0, static_cast<std::uint32_t>(i + 1), static_cast<std::uint32_t>((i + 1) % n + 1)});
        }
        const bool simple = simple_fan(p, ring, stats);
        const testing::MeshDefects defects = testing::find_defects(fan);
        const bool meets = defects.intersecting_pairs + defects.degenerate_faces + defects.duplicate_faces > 0;
        if (simple) {
            EXPECT_FALSE(meets) << "trial " << trial << ": " << defects.first;
            ++passed;
            around += kind == 0;
        } else {
            refused_meeting += meets;
        }
        if (kind == 1) {
            EXPECT_FALSE(simple) << "trial " << trial << " (twice around p)";
        }
    }
    EXPECT_GT(around, 1000);
    EXPECT_GT(passed - around, 20);
    EXPECT_GT(refused_meeting, 1000);
}

// Vertical gaps, by a different method: the point on the plane or the crossing point solved in
// rationals, the heights interpolated there, the difference compared with the bound.
bool reference_vertical_within(const Triangle3& t, Point3 v, double bound) {
    auto q = [](double x) { return mpq_class(x); };
    // z = z0 + α(x − x0) + β(y − y0) through the three corners (Cramer's rule).
    const mpq_class x1 = q(t[1].x) - q(t[0].x), y1 = q(t[1].y) - q(t[0].y), z1 = q(t[1].z) - q(t[0].z);
    const mpq_class x2 = q(t[2].x) - q(t[0].x), y2 = q(t[2].y) - q(t[0].y), z2 = q(t[2].z) - q(t[0].z);
    const mpq_class det = x1 * y2 - x2 * y1;
    const mpq_class alpha = (z1 * y2 - z2 * y1) / det, beta = (x1 * z2 - x2 * z1) / det;
    const mpq_class z = q(t[0].z) + alpha * (q(v.x) - q(t[0].x)) + beta * (q(v.y) - q(t[0].y));
    return abs(z - q(v.z)) <= q(bound);
}

bool reference_crossing_within(Point3 a, Point3 b, Point3 u, Point3 w, double bound) {
    auto q = [](double x) { return mpq_class(x); };
    // a + s(b − a) = u + r(w − u), solved for s and r.
    const mpq_class dx = q(b.x) - q(a.x), dy = q(b.y) - q(a.y), ex = q(w.x) - q(u.x), ey = q(w.y) - q(u.y);
    const mpq_class fx = q(u.x) - q(a.x), fy = q(u.y) - q(a.y);
    const mpq_class det = dx * (-ey) - dy * (-ex);
    const mpq_class s = (fx * (-ey) - fy * (-ex)) / det, r = (dx * fy - dy * fx) / det;
    const mpq_class za = q(a.z) + s * (q(b.z) - q(a.z)), zu = q(u.z) + r * (q(w.z) - q(u.z));
    return abs(za - zu) <= q(bound);
}

TEST(VerticalGap, ExactlyAtTheBound) {
    PredicateStats stats;
    const Triangle3 t{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
    EXPECT_TRUE(vertical_gap_within(t, {0.25, 0.25, 3}, 3, stats));
    EXPECT_FALSE(vertical_gap_within(t, {0.25, 0.25, 3}, std::nextafter(3.0, 0.0), stats));
    EXPECT_TRUE(vertical_gap_within(t, {0.25, 0.25, -3}, 3, stats));
    EXPECT_FALSE(vertical_gap_within(t, {0.25, 0.25, 0x1p-1074}, 0, stats));
    EXPECT_TRUE(vertical_gap_within(t, {7, -5, 0}, 0, stats));  // outside the face: its plane
    // Clockwise corners: the same heights.
    const Triangle3 cw{{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}};
    EXPECT_TRUE(vertical_gap_within(cw, {0.25, 0.25, 3}, 3, stats));
    EXPECT_FALSE(vertical_gap_within(cw, {0.25, 0.25, 3}, 2.5, stats));
    // Crossing diagonals of the unit square, one at height 0, the other rising from 0 to 2:
    // 1 apart where they cross.
    EXPECT_TRUE(crossing_gap_within({0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 2}, 1, stats));
    EXPECT_FALSE(crossing_gap_within({0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 2}, std::nextafter(1.0, 0.0), stats));
    EXPECT_TRUE(crossing_gap_within({1, 0, 0}, {0, 1, 2}, {0, 0, 0}, {1, 1, 0}, 1, stats));
}

TEST(VerticalGap, AgreesWithRationalsWhenTheBoundIsTheRoundedGap) {
    // Large offsets, the bound the gap computed in doubles and nudged by an ulp either way: the
    // exact answers flip right at the true gap, which doubles cannot place.
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> unit(0, 1), height(-50, 50);
    PredicateStats stats;
    int float_wrong = 0, cases = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const double ox = 4e5 + 1e4 * unit(random), oy = 6e6 + 1e4 * unit(random);
        const Triangle3 t{{{ox, oy, height(random)}, {ox + 30 * unit(random) + 1, oy, height(random)},
                           {ox, oy + 30 * unit(random) + 1, height(random)}}};
        const Point3 v{ox + 0.3 * unit(random), oy + 0.3 * unit(random), height(random)};
        // The gap in doubles, as a naive implementation would compute it.
        const double x1 = t[1].x - t[0].x, y1 = t[1].y - t[0].y, z1 = t[1].z - t[0].z;
        const double x2 = t[2].x - t[0].x, y2 = t[2].y - t[0].y, z2 = t[2].z - t[0].z;
        const double det = x1 * y2 - x2 * y1;
        const double z = t[0].z + (z1 * y2 - z2 * y1) / det * (v.x - t[0].x) + (x1 * z2 - x2 * z1) / det * (v.y - t[0].y);
        const double naive = std::fabs(z - v.z);
        for (double bound : {std::nextafter(naive, 0.0), naive, std::nextafter(naive, INFINITY)}) {
            const bool truth = reference_vertical_within(t, v, bound);
            EXPECT_EQ(vertical_gap_within(t, v, bound, stats), truth) << trial;
            if ((naive <= bound) != truth) ++float_wrong;
            ++cases;
        }
        // A segment from v across the triangle's edge from corner 1 to 2, the bound its naive gap
        // at the crossing (± an ulp).
        const Point3 w{ox + 40 + 10 * unit(random), oy + 40 + 10 * unit(random), height(random)};
        const Point3 a = t[1], b = t[2];
        const double dx = b.x - a.x, dy = b.y - a.y, ex = w.x - v.x, ey = w.y - v.y, fx = v.x - a.x, fy = v.y - a.y;
        const double cross = dx * ey - dy * ex;
        const double along = (fx * ey - fy * ex) / cross, across = (fx * dy - fy * dx) / cross;
        const double crossing_naive = std::fabs(a.z + along * (b.z - a.z) - (v.z + across * (w.z - v.z)));
        for (double bound : {std::nextafter(crossing_naive, 0.0), crossing_naive, std::nextafter(crossing_naive, INFINITY)}) {
            const bool truth = reference_crossing_within(a, b, v, w, bound);
            EXPECT_EQ(crossing_gap_within(a, b, v, w, bound, stats), truth) << trial;
            if ((crossing_naive <= bound) != truth) ++float_wrong;
            cases += 1;
        }
    }
    EXPECT_GT(float_wrong, 0) << "plain doubles should misplace some of " << cases << " bounds";
    EXPECT_GT(stats.gmp_fallbacks, 0u);
}

TEST(VerticalGap, HugeAndTinyCoordinates) {
    PredicateStats stats;
    for (double scale : {0x1p-600, 0x1p-40, 1.0, 0x1p40, 0x1p500}) {
        const Triangle3 t{{{0, 0, 0}, {scale, 0, 0}, {0, scale, 0}}};
        const Point3 v{scale / 4, scale / 4, scale};
        EXPECT_TRUE(vertical_gap_within(t, v, scale, stats)) << scale;
        EXPECT_FALSE(vertical_gap_within(t, v, std::nextafter(scale, 0.0), stats)) << scale;
        EXPECT_TRUE(crossing_gap_within({0, 0, 0}, {scale, scale, 0}, {scale, 0, 0}, {0, scale, 2 * scale}, scale, stats));
        EXPECT_FALSE(crossing_gap_within({0, 0, 0}, {scale, scale, 0}, {scale, 0, 0}, {0, scale, 2 * scale},
                                         std::nextafter(scale, 0.0), stats));
    }
}

}  // namespace
}  // namespace toposimp::exact
