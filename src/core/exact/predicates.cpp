#include "core/exact/predicates.hpp"

#include "core/exact/expansion.hpp"

#include <gmpxx.h>

#include <cmath>

namespace toposimp::exact {

std::string_view to_string(Arithmetic arithmetic) {
    switch (arithmetic) {
        case Arithmetic::exact: return "exact";
        case Arithmetic::rational: return "rational";
        case Arithmetic::floating: return "float";
    }
    return "?";
}

namespace {

constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1.0: the unit roundoff of binary64
constexpr double kOrientBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
// Below this magnitude products may be subnormal and the relative bound no longer holds; such
// cases go to GMP. Far above the subnormal range so the bound's own rounding cannot matter.
constexpr double kMinCertifiable = 0x1p-900;

int sign_of(const mpq_class& value) { return sgn(value); }

int orient_rational(Point a, Point b, Point c) {
    // mpq_class(double) is exact: every finite double is a dyadic rational.
    const mpq_class ax(a.x), ay(a.y), bx(b.x), by(b.y), cx(c.x), cy(c.y);
    const mpq_class det = (ax - cx) * (by - cy) - (ay - cy) * (bx - cx);
    return sign_of(det);
}

// Point in the closed segment hull of three collinear points (exact: only comparisons).
bool in_collinear_hull(Point a, Point b, Point c, Point p, Arithmetic arithmetic, PredicateStats& stats) {
    const Box box = triangle_box(a, b, c);
    if (!box_contains(box, p)) return false;
    // The two corners farthest apart span the hull; if all coincide the hull is one point.
    Point u = a, v = b;
    if (same_location(u, v)) v = c;
    if (same_location(u, v)) return same_location(p, u);
    // u != v span the line through all three corners; p on that line and in their box is in.
    const int side = arithmetic == Arithmetic::rational ? orient_rational(u, v, p) : orient2d(u, v, p, stats);
    return side == 0;
}

}  // namespace

int orient2d_gmp(Point a, Point b, Point c) { return orient_rational(a, b, c); }

int orient2d_expansion(Point a, Point b, Point c) {
    using namespace expansion;
    for (const Point& p : {a, b, c}) {
        if (!in_range(p.x) || !in_range(p.y)) return 2;
    }
    const Expansion<2> ax = difference(a.x, c.x), ay = difference(a.y, c.y);
    const Expansion<2> bx = difference(b.x, c.x), by = difference(b.y, c.y);
    return sum(product(ax, by), negate(product(ay, bx))).sign();
}

int orient2d(Point a, Point b, Point c, PredicateStats& stats) {
    const double detleft = (a.x - c.x) * (b.y - c.y);
    const double detright = (a.y - c.y) * (b.x - c.x);
    const double det = detleft - detright;
    const double detsum = std::fabs(detleft) + std::fabs(detright);
    // The filter certifies the sign only with finite, well-scaled terms (no overflow, no
    // subnormal products). NaN compares false everywhere and falls through to GMP as well.
    if (detsum >= kMinCertifiable && detsum <= 0x1p1000) {
        const double bound = kOrientBound * detsum;
        if (det > bound) {
            ++stats.filter_decided;
            return 1;
        }
        if (-det > bound) {
            ++stats.filter_decided;
            return -1;
        }
    } else if (detleft == 0.0 && detright == 0.0 && (a.x == c.x || b.y == c.y) && (a.y == c.y || b.x == c.x)) {
        // Both products are exactly zero because a factor is exactly zero: det is exactly 0.
        ++stats.filter_decided;
        return 0;
    } else {
        // Out of the filter's range (coordinates far from 1, or far apart): once more with all
        // points scaled towards 1, if that is exact (the determinant is then 2^2k times this
        // one; the second call's k is 0, so there is no third).
        const double values[] = {a.x, a.y, b.x, b.y, c.x, c.y};
        if (const int k = expansion::exact_rescaling(values); k != 0) {
            auto scaled = [k](Point p) { return Point{expansion::times_power_of_two(p.x, k), expansion::times_power_of_two(p.y, k)}; };
            return orient2d(scaled(a), scaled(b), scaled(c), stats);
        }
    }
    if (const int sign = orient2d_expansion(a, b, c); sign != 2) {
        ++stats.expansion_decided;
        return sign;
    }
    ++stats.gmp_fallbacks;
    return orient_rational(a, b, c);
}

int ring_area_sign_gmp(std::span<const Point> ring) {
    mpq_class twice_area = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        const Point p = ring[i], q = ring[i + 1];
        twice_area += mpq_class(p.x) * mpq_class(q.y) - mpq_class(q.x) * mpq_class(p.y);
    }
    return sign_of(twice_area);
}

int ring_area_sign(std::span<const Point> ring, PredicateStats& stats) {
    const std::size_t n = ring.size();
    if (n >= 2 && n < (std::size_t{1} << 40) && same_location(ring.front(), ring.back())) {
        // About the first corner (a closed ring's sum does not depend on the origin): the terms
        // stay small for a small ring far from the origin. Each term a×b of rounded differences
        // is within γ4 of its magnitude |ax·by| + |bx·ay|, the sum adds γ(n−2) of theirs, and the
        // magnitudes' own rounding is covered by the factor 2 (n·ε < 2^-13 here). Magnitudes
        // outside [2^-900, 2^1000] (underflow, overflow, NaN) are left to GMP.
        const Point o = ring.front();
        double sum = 0, magnitude = 0;
        for (std::size_t i = 0; i + 1 < n; ++i) {
            const double ax = ring[i].x - o.x, ay = ring[i].y - o.y;
            const double bx = ring[i + 1].x - o.x, by = ring[i + 1].y - o.y;
            const double left = ax * by, right = bx * ay;
            sum += left - right;
            magnitude += std::fabs(left) + std::fabs(right);
        }
        if (magnitude >= kMinCertifiable && magnitude <= 0x1p1000) {
            const double bound = 2.0 * (static_cast<double>(n) + 8.0) * kEpsilon * magnitude;
            if (sum > bound || -sum > bound) {
                ++stats.filter_decided;
                return sum > 0 ? 1 : -1;
            }
        }
    }
    ++stats.gmp_fallbacks;
    return ring_area_sign_gmp(ring);
}

ClosedTriangle::ClosedTriangle(Point a, Point b, Point c, Arithmetic arithmetic, PredicateStats& stats)
    : a_(a), b_(b), c_(c), arithmetic_(arithmetic), stats_(stats) {
    if (arithmetic_ != Arithmetic::floating) turn_ = orient(a, b, c);
}

int ClosedTriangle::orient(Point u, Point v, Point w) {
    return arithmetic_ == Arithmetic::rational ? orient_rational(u, v, w) : orient2d(u, v, w, stats_);
}

bool ClosedTriangle::contains(Point p) {
    if (arithmetic_ == Arithmetic::floating) return in_closed_triangle_float(a_, b_, c_, p);
    if (turn_ == 0) return in_collinear_hull(a_, b_, c_, p, arithmetic_, stats_);
    // p is in the closed triangle iff it is not strictly on the outer side of any edge.
    if (orient(a_, b_, p) * turn_ < 0) return false;
    if (orient(b_, c_, p) * turn_ < 0) return false;
    return orient(c_, a_, p) * turn_ >= 0;
}

bool in_closed_triangle(Point a, Point b, Point c, Point p, Arithmetic arithmetic, PredicateStats& stats) {
    return ClosedTriangle(a, b, c, arithmetic, stats).contains(p);
}

bool in_closed_triangle_float(Point a, Point b, Point c, Point p) {
    // Barycentric coordinates of p in abc, as TopoVW computed them.
    const double denominator = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
    const double alpha = ((b.y - c.y) * (p.x - c.x) + (c.x - b.x) * (p.y - c.y)) / denominator;
    const double beta = ((c.y - a.y) * (p.x - c.x) + (a.x - c.x) * (p.y - c.y)) / denominator;
    const double gamma = 1.0 - alpha - beta;
    return alpha >= 0.0 && alpha <= 1.0 && beta >= 0.0 && beta <= 1.0 && gamma >= 0.0 && gamma <= 1.0;
}

}  // namespace toposimp::exact
