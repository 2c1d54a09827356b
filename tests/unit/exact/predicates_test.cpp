// Hard cases for the exact predicates: the float filter must agree with GMP on every one, and
// the naive double test (TopoVW's) must get some of them wrong.
#include "core/exact/predicates.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace toposimp::exact {
namespace {

int naive_orient(Point a, Point b, Point c) {
    const double det = (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x);
    return (det > 0) - (det < 0);
}

double ulps_from(double value, int steps) {
    for (int i = 0; i < std::abs(steps); ++i) value = std::nextafter(value, steps > 0 ? INFINITY : -INFINITY);
    return value;
}

// Kettner et al.'s experiment (dissertation §3.3.2): p on a 256×256 grid of ulp steps around
// (0.5, 0.5), tested against the line through (12, 12) and (24, 24).
TEST(Orient2d, FilterAgreesWithGmpOnKettnerGrid) {
    const Point q{12, 12}, r{24, 24};
    PredicateStats stats;
    int naive_wrong = 0;
    for (int i = 0; i < 256; ++i) {
        for (int j = 0; j < 256; ++j) {
            const Point p{0.5 + i * 0x1p-53, 0.5 + j * 0x1p-53};
            const int exact = orient2d_gmp(p, q, r);
            ASSERT_EQ(orient2d(p, q, r, stats), exact) << i << ' ' << j;
            naive_wrong += naive_orient(p, q, r) != exact;
        }
    }
    EXPECT_GT(stats.expansion_decided, 0u);  // the filter leaves the grid's hard cases to the exact stage
    EXPECT_GT(naive_wrong, 0) << "the naive double orientation should fail somewhere on this grid";
}

TEST(Orient2d, CollinearTriplesAtLargeAndSmallScale) {
    PredicateStats stats;
    for (const double scale : {1e6, 1e-6, 1.0, 1e15}) {
        const Point a{scale, scale}, b{2 * scale, 2 * scale}, c{3 * scale, 3 * scale};
        EXPECT_EQ(orient2d(a, b, c, stats), 0) << scale;
        const Point above{c.x, ulps_from(c.y, 1)}, below{c.x, ulps_from(c.y, -1)};
        EXPECT_EQ(orient2d(a, b, above, stats), 1) << scale;
        EXPECT_EQ(orient2d(a, b, below, stats), -1) << scale;
    }
}

TEST(Orient2d, MixedSignsAroundOriginMatchGmp) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::uniform_int_distribution<int> exponent(-30, 30);
    PredicateStats stats;
    int naive_wrong = 0;
    for (int k = 0; k < 20000; ++k) {
        const Point a{std::ldexp(unit(rng), exponent(rng)), std::ldexp(unit(rng), exponent(rng))};
        const Point b{std::ldexp(unit(rng), exponent(rng)), std::ldexp(unit(rng), exponent(rng))};
        // c nearly on ab: a rounded point of the line, nudged by a few ulps.
        const double t = unit(rng) * 3;
        Point c{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        c.y = ulps_from(c.y, static_cast<int>(k % 5) - 2);
        const int exact = orient2d_gmp(a, b, c);
        ASSERT_EQ(orient2d(a, b, c, stats), exact) << k;
        ASSERT_EQ(orient2d_expansion(a, b, c), exact) << k;  // the exact stage on its own
        naive_wrong += naive_orient(a, b, c) != exact;
    }
    EXPECT_GT(naive_wrong, 0);
    EXPECT_GT(stats.expansion_decided, 0u);
    EXPECT_EQ(orient2d_expansion({0, 0}, {1e300, 1}, {1, 1}), 2);  // out of its range: GMP decides
}

TEST(Orient2d, HugeAndTinyMagnitudesFallBackCorrectly) {
    PredicateStats stats;
    const double huge = 1e300;
    EXPECT_EQ(orient2d({huge, huge}, {-huge, -huge}, {huge, -huge}, stats), orient2d_gmp({huge, huge}, {-huge, -huge}, {huge, -huge}));
    EXPECT_EQ(orient2d({-huge, -huge}, {huge, -huge}, {huge, huge}, stats), 1);  // counter-clockwise
    const double tiny = 1e-300;
    EXPECT_EQ(orient2d({0, 0}, {tiny, 0}, {0, tiny}, stats), 1);  // products underflow in doubles
    EXPECT_EQ(orient2d({0, 0}, {0, tiny}, {tiny, 0}, stats), -1);
    const double sub = 5e-324;  // smallest subnormal
    EXPECT_EQ(orient2d({0, 0}, {sub, 0}, {0, sub}, stats), 1);
    EXPECT_EQ(naive_orient({0, 0}, {tiny, 0}, {0, tiny}), 0) << "doubles round this to collinear";
    EXPECT_EQ(orient2d({DBL_MAX, 0}, {-DBL_MAX, 0}, {0, DBL_MAX}, stats), orient2d_gmp({DBL_MAX, 0}, {-DBL_MAX, 0}, {0, DBL_MAX}));
}

// Collinear and one-ulp-off triples at 2^±600: scaled exactly towards 1 and decided without GMP,
// as GMP decides.
TEST(Orient2d, OutOfRangeTriplesAreScaledExactly) {
    std::mt19937_64 random(43);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    for (int exponent : {-600, 600}) {
        PredicateStats stats;
        const double s = std::ldexp(1.0, exponent);
        for (int trial = 0; trial < 3000; ++trial) {
            const Point a{s * coordinate(random), s * coordinate(random)}, b{s * coordinate(random), s * coordinate(random)};
            const double t = std::uniform_real_distribution<double>(0, 1)(random);
            Point c{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
            if (trial % 3 != 1) c.y = std::nextafter(c.y, trial % 3 == 0 ? -INFINITY : INFINITY);
            ASSERT_EQ(orient2d(a, b, c, stats), orient2d_gmp(a, b, c)) << exponent << ' ' << trial;
        }
        EXPECT_EQ(stats.gmp_fallbacks, 0u) << exponent;
    }
}

// A triangle with one edge on y = x through (1e6, 1e6) … (1e6 + 2, 1e6 + 2): the point
// (1e6 + 1, 1e6 + 1) is exactly on it; one ulp up or down is inside or outside.
TEST(InClosedTriangle, PointsOneUlpFromAnEdge) {
    const Point a{1e6, 1e6}, b{1e6 + 2, 1e6 + 2}, c{1e6, 1e6 + 2};  // c is above the edge ab
    const Point on{1e6 + 1, 1e6 + 1};
    const Point inside{on.x, ulps_from(on.y, 1)}, outside{on.x, ulps_from(on.y, -1)};
    for (const Arithmetic mode : {Arithmetic::exact, Arithmetic::rational}) {
        PredicateStats stats;
        EXPECT_TRUE(in_closed_triangle(a, b, c, on, mode, stats));
        EXPECT_TRUE(in_closed_triangle(a, b, c, inside, mode, stats));
        EXPECT_FALSE(in_closed_triangle(a, b, c, outside, mode, stats));
        EXPECT_TRUE(in_closed_triangle(a, b, c, a, mode, stats)) << "a corner is on the boundary";
    }
}

TEST(InClosedTriangle, DegenerateTrianglesAreTheirSegmentOrPoint) {
    PredicateStats stats;
    const Point a{0, 0}, b{2, 2}, c{4, 4};
    EXPECT_TRUE(in_closed_triangle(a, b, c, {3, 3}, Arithmetic::exact, stats));
    EXPECT_TRUE(in_closed_triangle(a, c, b, {4, 4}, Arithmetic::exact, stats));
    EXPECT_FALSE(in_closed_triangle(a, b, c, {5, 5}, Arithmetic::exact, stats));
    EXPECT_FALSE(in_closed_triangle(a, b, c, {3, ulps_from(3, 1)}, Arithmetic::exact, stats));
    EXPECT_TRUE(in_closed_triangle(a, a, a, a, Arithmetic::exact, stats));
    EXPECT_FALSE(in_closed_triangle(a, a, a, {0, 5e-324}, Arithmetic::exact, stats));
    EXPECT_TRUE(in_closed_triangle(a, a, c, {1, 1}, Arithmetic::rational, stats));
    // TopoVW's barycentric test divides by zero here and calls every point outside.
    EXPECT_FALSE(in_closed_triangle_float(a, b, c, {3, 3}));
}

// On a grid of ulp steps around a point of a sloped edge, the exact modes agree with each other
// and the naive barycentric test misclassifies some points.
TEST(InClosedTriangle, FloatModeGetsNearEdgeCasesWrong) {
    const Point a{0.1, 0.3}, b{17.3, 12.7}, c{0.1, 12.7};
    PredicateStats stats;
    int float_wrong = 0;
    for (int i = -32; i < 32; ++i) {
        for (int j = -32; j < 32; ++j) {
            const Point p{ulps_from(8.7, i), ulps_from(0.3 + (8.7 - 0.1) * (12.4 / 17.2), j)};
            const bool exact = in_closed_triangle(a, b, c, p, Arithmetic::exact, stats);
            PredicateStats rational_stats;
            ASSERT_EQ(in_closed_triangle(a, b, c, p, Arithmetic::rational, rational_stats), exact);
            float_wrong += in_closed_triangle(a, b, c, p, Arithmetic::floating, stats) != exact;
        }
    }
    EXPECT_GT(stats.expansion_decided, 0u);
    EXPECT_GT(float_wrong, 0);
}

TEST(InClosedTriangle, FilterAgreesWithGmpOnRandomNearDegenerateCases) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(-1, 1);
    PredicateStats exact_stats, rational_stats;
    for (int k = 0; k < 20000; ++k) {
        const double scale = k % 2 ? 1e6 : 1e-6;
        const double shift = k % 3 == 0 ? 5e5 : 0;
        auto random_point = [&] { return Point{shift + scale * unit(rng), shift + scale * unit(rng)}; };
        const Point a = random_point(), b = random_point(), c = random_point();
        const double t = (unit(rng) + 1) / 2;
        Point p{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        p.x = ulps_from(p.x, static_cast<int>(k % 3) - 1);
        ASSERT_EQ(in_closed_triangle(a, b, c, p, Arithmetic::exact, exact_stats),
                  in_closed_triangle(a, b, c, p, Arithmetic::rational, rational_stats))
            << k;
    }
    EXPECT_GT(exact_stats.expansion_decided, 0u);
    EXPECT_LT(exact_stats.expansion_decided, exact_stats.filter_decided);
}

// The naive shoelace sum of a ring, in doubles about the origin.
int naive_area_sign(const std::vector<Point>& ring) {
    double sum = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) sum += ring[i].x * ring[i + 1].y - ring[i + 1].x * ring[i].y;
    return (sum > 0) - (sum < 0);
}

// Thin rings: a triangle whose third corner lies a few ulps off the line through the other two,
// with collinear corners added along that line, far from the origin and at tiny scales.
TEST(RingAreaSign, FilterAgreesWithGmpOnThinRings) {
    PredicateStats stats;
    int naive_wrong = 0, checked = 0;
    for (const double scale : {1.0, 1e-200, 1e6}) {
        for (const double offset : {0.0, 1e6, 1e15}) {
            for (int i = -8; i <= 8; ++i) {
                const double base = offset + 0.5 * scale;
                const Point a{base, base}, b{offset + 12 * scale, offset + 12 * scale};
                const Point c{offset + 24 * scale, ulps_from(offset + 24 * scale, i)};
                // Corners along ab (exactly on it: both coordinates equal).
                std::vector<Point> ring{a};
                for (int k = 1; k < 5; ++k) {
                    const double t = base + (b.x - base) * k / 5;
                    ring.push_back({t, t});
                }
                ring.insert(ring.end(), {b, c, a});
                const int exact = ring_area_sign_gmp(ring);
                ASSERT_EQ(ring_area_sign(ring, stats), exact) << scale << ' ' << offset << ' ' << i;
                // Reversed: the opposite sign.
                const std::vector<Point> reversed(ring.rbegin(), ring.rend());
                ASSERT_EQ(ring_area_sign(reversed, stats), -exact);
                naive_wrong += naive_area_sign(ring) != exact;
                ++checked;
            }
        }
    }
    EXPECT_GT(stats.filter_decided, 0u);
    EXPECT_GT(stats.gmp_fallbacks, 0u);  // the collinear (i = 0) and near-collinear rings
    EXPECT_GT(naive_wrong, 0) << "the naive double shoelace sum should fail somewhere among " << checked;
}

TEST(RingAreaSign, ZeroAreaOverflowAndOpenSequences) {
    PredicateStats stats;
    // Back and forth along a segment, and a collinear run: exactly zero.
    EXPECT_EQ(ring_area_sign(std::vector<Point>{{0.1, 0.3}, {7.7, 1.9}, {0.1, 0.3}}, stats), 0);
    EXPECT_EQ(ring_area_sign(std::vector<Point>{{1, 1}, {2, 2}, {3, 3}, {1, 1}}, stats), 0);
    // Products beyond 2^1000: GMP.
    const PredicateStats before = stats;
    EXPECT_EQ(ring_area_sign(std::vector<Point>{{1e300, 1e300}, {-1e300, 1e300}, {-1e300, -1e300}, {1e300, 1e300}}, stats), 1);
    EXPECT_EQ(stats.gmp_fallbacks, before.gmp_fallbacks + 1);
    // An open sequence is summed as given, about the origin, which differs from the sum about
    // its first point by o × (last − o): here +9 about the origin, −1 about (10, 0).
    const std::vector<Point> open{{10, 0}, {9, 1}, {10, 1}};
    EXPECT_EQ(ring_area_sign_gmp(open), 1);
    EXPECT_EQ(ring_area_sign(open, stats), 1);
}

// The shoelace sum about the first corner in doubles with no error bound: what the filter
// computes before it asks whether the bound settles the sign.
int unbounded_area_sign(const std::vector<Point>& ring) {
    double sum = 0;
    const Point o = ring.front();
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        sum += (ring[i].x - o.x) * (ring[i + 1].y - o.y) - (ring[i + 1].x - o.x) * (ring[i].y - o.y);
    }
    return (sum > 0) - (sum < 0);
}

// Slivers: out along y = x/3 and back a few ulps beside it, many corners, so that the terms
// cancel to almost nothing: the sum without its bound gets signs wrong, and the filter must
// hand those rings to GMP.
TEST(RingAreaSign, SliversNeedTheBound) {
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> along(0.001, 1000.0);
    std::uniform_int_distribution<int> ulps(-3, 3);
    PredicateStats stats;
    int unbounded_wrong = 0;
    for (int trial = 0; trial < 400; ++trial) {
        std::vector<double> out(20), back(20);
        for (double& t : out) t = along(random);
        for (double& t : back) t = along(random);
        std::sort(out.begin(), out.end());
        std::sort(back.rbegin(), back.rend());
        std::vector<Point> ring;
        for (const double t : out) ring.push_back({t, t / 3});
        for (const double t : back) ring.push_back({t, ulps_from(t / 3, ulps(random))});
        ring.push_back(ring.front());
        const int exact = ring_area_sign_gmp(ring);
        ASSERT_EQ(ring_area_sign(ring, stats), exact) << trial;
        unbounded_wrong += unbounded_area_sign(ring) != exact;
    }
    EXPECT_GT(unbounded_wrong, 0);
    EXPECT_GT(stats.gmp_fallbacks, 0u);
}

// Random star-shaped polygons of many corners at many scales: all decided by the filter, each
// as GMP decides.
TEST(RingAreaSign, ManyCornersDecidedByTheFilter) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> unit(0.5, 1.0);
    PredicateStats stats;
    for (int trial = 0; trial < 40; ++trial) {
        const double scale = std::ldexp(1.0, trial * 20 - 400), cx = 1e5 * scale * trial, cy = -3e4 * scale;
        const int n = 10 + 97 * trial;
        std::vector<Point> ring;
        for (int k = 0; k < n; ++k) {
            const double angle = 2 * M_PI * k / n, r = unit(random) * scale;
            ring.push_back({cx + r * std::cos(angle), cy + r * std::sin(angle)});
        }
        ring.push_back(ring.front());
        if (trial % 2 == 1) std::reverse(ring.begin(), ring.end());
        const int exact = ring_area_sign_gmp(ring);
        EXPECT_EQ(exact, trial % 2 == 1 ? -1 : 1);
        ASSERT_EQ(ring_area_sign(ring, stats), exact) << trial;
    }
    EXPECT_EQ(stats.gmp_fallbacks, 0u);
    EXPECT_EQ(stats.filter_decided, 40u);
}

}  // namespace
}  // namespace toposimp::exact
