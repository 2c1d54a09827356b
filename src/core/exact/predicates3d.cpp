#include "core/exact/predicates3d.hpp"

#include "core/exact/expansion.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace toposimp::exact {
namespace {

constexpr double kUnitRoundoff = 0x1p-53;

// A double with a bound on its distance to the exact value of the expression it stands for.
struct Bounded {
    double value;
    double error = 0.0;

    Bounded(double v) : value(v) {}  // NOLINT: inputs are exact
    Bounded(double v, double e) : value(v), error(e) {}
};

// A non-zero error bound is never let below kErrorFloor: terms of the bound that underflow lose
// up to 2^-1074 each, and this floor covers them (values that small go to GMP instead).
// A zero bound stays zero only while every step was exact.
constexpr double kErrorFloor = 0x1p-960;

Bounded settle(double v, double e, bool exact) {
    if (!exact && !(e >= kErrorFloor)) e = kErrorFloor;
    return {v, e};
}

Bounded operator+(Bounded a, Bounded b) {
    const double v = a.value + b.value;
    const double e = a.error + b.error + kUnitRoundoff * std::fabs(v);
    return settle(v, e, e == 0.0);
}

Bounded operator-(Bounded a, Bounded b) {
    const double v = a.value - b.value;
    const double e = a.error + b.error + kUnitRoundoff * std::fabs(v);
    return settle(v, e, e == 0.0);
}

Bounded operator*(Bounded a, Bounded b) {
    const double v = a.value * b.value;
    const double e = std::fabs(a.value) * b.error + std::fabs(b.value) * a.error + a.error * b.error + kUnitRoundoff * std::fabs(v);
    // Exact only if no error came in and the product neither rounded (kU·|v| = 0 means v = 0,
    // and then a factor was 0 or it underflowed) nor underflowed.
    const bool underflow = v == 0.0 ? (a.value != 0.0 && b.value != 0.0) : std::fabs(v) < 0x1p-1021;
    return settle(v, e, e == 0.0 && !underflow && a.error == 0.0 && b.error == 0.0);
}

// The certified sign, or 2 when the bound cannot decide. The bound itself was computed with
// rounding (at most a few dozen operations, each off by a factor ≤ 1 + u): widened by 2^-40.
int certified_sign(Bounded x) {
    if (!std::isfinite(x.value) || !std::isfinite(x.error)) return 2;
    if (x.error == 0.0) return (x.value > 0) - (x.value < 0);  // every step was exact
    const double bound = x.error * (1.0 + 0x1p-40);
    if (x.value > bound) return 1;
    if (-x.value > bound) return -1;
    return 2;
}

// The polynomials, written once for every number type: `to` turns an input double into T.
template <class T, class To>
T orient3d_expr(Point3 a, Point3 b, Point3 c, Point3 d, To to) {
    const T bx = to(b.x) - to(a.x), by = to(b.y) - to(a.y), bz = to(b.z) - to(a.z);
    const T cx = to(c.x) - to(a.x), cy = to(c.y) - to(a.y), cz = to(c.z) - to(a.z);
    const T dx = to(d.x) - to(a.x), dy = to(d.y) - to(a.y), dz = to(d.z) - to(a.z);
    const T nx = by * cz - bz * cy, ny = bz * cx - bx * cz, nz = bx * cy - by * cx;
    return nx * dx + ny * dy + nz * dz;
}

template <class T, class To>
T normal_dot_expr(Point3 a, Point3 b, Point3 c, Point3 d, Point3 e, Point3 f, To to) {
    const T bx = to(b.x) - to(a.x), by = to(b.y) - to(a.y), bz = to(b.z) - to(a.z);
    const T cx = to(c.x) - to(a.x), cy = to(c.y) - to(a.y), cz = to(c.z) - to(a.z);
    const T ex = to(e.x) - to(d.x), ey = to(e.y) - to(d.y), ez = to(e.z) - to(d.z);
    const T fx = to(f.x) - to(d.x), fy = to(f.y) - to(d.y), fz = to(f.z) - to(d.z);
    const T n1x = by * cz - bz * cy, n1y = bz * cx - bx * cz, n1z = bx * cy - by * cx;
    const T n2x = ey * fz - ez * fy, n2y = ez * fx - ex * fz, n2z = ex * fy - ey * fx;
    return n1x * n2x + n1y * n2y + n1z * n2z;
}

template <class T>
struct Plain {
    T operator()(double x) const { return T(x); }
};

// Exact fallback in integers: every finite double is m·2^e with |m| < 2^53; scaled by one
// common power of two, all inputs become integers and the polynomial's sign is unchanged (the
// scale is positive). GMP integers need no gcd per operation, unlike rationals.
class ToInteger {
public:
    template <std::size_t N>
    explicit ToInteger(const Point3 (&points)[N]) {
        for (const Point3& p : points) {
            for (double x : {p.x, p.y, p.z}) {
                if (x != 0.0) {
                    int e = 0;
                    std::frexp(x, &e);
                    lowest_ = std::min(lowest_, e);
                }
            }
        }
    }
    mpz_class operator()(double x) const {
        if (x == 0.0) return 0;
        int e = 0;
        const double f = std::frexp(x, &e);
        mpz_class z(static_cast<long>(std::ldexp(f, 53)));  // exact: |f·2^53| < 2^53
        mpz_mul_2exp(z.get_mpz_t(), z.get_mpz_t(), static_cast<mp_bitcnt_t>(e - lowest_));
        return z;
    }

private:
    int lowest_ = std::numeric_limits<int>::max();
};

// A height difference as a fraction with the bound scaled alike: difference = value /
// denominator, slack = bound · denominator. |difference| ≤ bound iff value − slack and value +
// slack do not both lie on one side of zero in the denominator's direction.
template <class T>
struct Gap {
    T value, denominator, slack;
};

// t's plane over v, relative to v: with A_i = orient2d(v, t_{i+1}, t_{i+2}) in the map plane,
// the height there is Σ z_i·A_i / D, D = orient2d(t0, t1, t2), the barycentric weights' sum.
template <class To>
auto vertical_gap_expr(const Triangle3& t, Point3 v, double bound, To to) {
    using T = decltype(to(0.0));
    const T x0 = to(t[0].x) - to(v.x), y0 = to(t[0].y) - to(v.y), z0 = to(t[0].z) - to(v.z);
    const T x1 = to(t[1].x) - to(v.x), y1 = to(t[1].y) - to(v.y), z1 = to(t[1].z) - to(v.z);
    const T x2 = to(t[2].x) - to(v.x), y2 = to(t[2].y) - to(v.y), z2 = to(t[2].z) - to(v.z);
    const T value = z0 * (x1 * y2 - y1 * x2) + z1 * (x2 * y0 - y2 * x0) + z2 * (x0 * y1 - y0 * x1);
    const T denominator = (to(t[1].x) - to(t[0].x)) * (to(t[2].y) - to(t[0].y)) -
                          (to(t[1].y) - to(t[0].y)) * (to(t[2].x) - to(t[0].x));
    return Gap<T>{value, denominator, to(bound) * denominator};
}

// At the crossing c of ab and uw, with K = (b − a) × (w − u), o_x = orient2d(u, w, x) and
// q_x = orient2d(a, b, x): c = a + (o_a / K)(b − a) = u − (q_u / K)(w − u), so, heights taken
// relative to a, h_ab(c) − h_uw(c) = (z_b·o_a + z_w·q_u − z_u·q_w) / K.
template <class To>
auto crossing_gap_expr(Point3 a, Point3 b, Point3 u, Point3 w, double bound, To to) {
    using T = decltype(to(0.0));
    const T bx = to(b.x) - to(a.x), by = to(b.y) - to(a.y), bz = to(b.z) - to(a.z);
    const T ux = to(u.x) - to(a.x), uy = to(u.y) - to(a.y), uz = to(u.z) - to(a.z);
    const T wx = to(w.x) - to(a.x), wy = to(w.y) - to(a.y), wz = to(w.z) - to(a.z);
    const T ex = to(w.x) - to(u.x), ey = to(w.y) - to(u.y);  // w − u
    const T o_a = ey * ux - ex * uy;                         // (w − u) × (a − u), a − u = −u here
    const T q_u = bx * uy - by * ux, q_w = bx * wy - by * wx;
    const T denominator = bx * ey - by * ex;
    const T value = bz * o_a + wz * q_u - uz * q_w;
    return Gap<T>{value, denominator, to(bound) * denominator};
}

// 1 within, 0 not, 2 undecided (only from Bounded).
template <class T>
int gap_verdict(const Gap<T>& gap, int (*sign)(const T&)) {
    const int d = sign(gap.denominator);
    const int over = sign(gap.value - gap.slack), under = sign(gap.value + gap.slack);
    if (d == 2 || over == 2 || under == 2) return 2;
    return over * d <= 0 && under * d >= 0 ? 1 : 0;
}

int bounded_sign(const Bounded& x) { return certified_sign(x); }
int integer_sign(const mpz_class& x) { return sgn(x); }

int orient2(Point a, Point b, Point c, PredicateStats& stats) { return orient2d(a, b, c, stats); }

bool in_segment_box(Point x, Point a, Point b) {
    return x.x >= std::fmin(a.x, b.x) && x.x <= std::fmax(a.x, b.x) && x.y >= std::fmin(a.y, b.y) &&
           x.y <= std::fmax(a.y, b.y);
}

bool on_closed_segment(Point x, Point a, Point b, PredicateStats& stats) {
    if (same_location(a, b)) return same_location(x, a);
    return in_segment_box(x, a, b) && orient2(a, b, x, stats) == 0;
}

// Closed segments in the plane, any degeneracy.
bool segments_meet_2d(Point p, Point q, Point r, Point s, PredicateStats& stats) {
    if (std::fmax(p.x, q.x) < std::fmin(r.x, s.x) || std::fmax(r.x, s.x) < std::fmin(p.x, q.x) ||
        std::fmax(p.y, q.y) < std::fmin(r.y, s.y) || std::fmax(r.y, s.y) < std::fmin(p.y, q.y)) {
        return false;
    }
    if (same_location(p, q)) return on_closed_segment(p, r, s, stats);
    if (same_location(r, s)) return on_closed_segment(r, p, q, stats);
    const int o1 = orient2(p, q, r, stats), o2 = orient2(p, q, s, stats);
    if (o1 * o2 > 0) return false;
    const int o3 = orient2(r, s, p, stats), o4 = orient2(r, s, q, stats);
    if (o3 * o4 > 0) return false;
    // Not separated by either line. If all four are collinear, overlapping boxes of collinear
    // segments mean overlapping intervals; otherwise the segments cross or touch.
    return true;
}

bool segment_meets_triangle_2d(Point p, Point q, Point a, Point b, Point c, PredicateStats& stats) {
    if (in_closed_triangle(a, b, c, p, Arithmetic::exact, stats)) return true;
    if (in_closed_triangle(a, b, c, q, Arithmetic::exact, stats)) return true;
    return segments_meet_2d(p, q, a, b, stats) || segments_meet_2d(p, q, b, c, stats) ||
           segments_meet_2d(p, q, c, a, stats);
}

Box3 segment_box(Point3 p, Point3 q) {
    Box3 box = point_box(p);
    box.add(q);
    return box;
}

// Closed segments in space, any degeneracy: they can only meet if the four points are coplanar,
// and then they meet iff their projections meet in all three coordinate planes (one of the
// projections is one-to-one on their common plane, and a projection cannot separate sets that meet).
bool segments_meet_3d(Point3 p, Point3 q, Point3 r, Point3 s, PredicateStats& stats) {
    if (!segment_box(p, q).overlaps(segment_box(r, s))) return false;
    if (orient3d(p, q, r, s, stats) != 0) return false;
    for (int axis = 0; axis < 3; ++axis) {
        if (!segments_meet_2d(drop_axis(p, axis), drop_axis(q, axis), drop_axis(r, axis), drop_axis(s, axis), stats)) {
            return false;
        }
    }
    return true;
}

// The projection (axis dropped) in which a non-degenerate triangle keeps its area, and its
// orientation there. Returns axis -1 for a degenerate triangle.
std::pair<int, int> area_axis(const Triangle3& t, PredicateStats& stats) {
    for (int axis = 2; axis >= 0; --axis) {
        const int turn = orient_projected(t[0], t[1], t[2], axis, stats);
        if (turn != 0) return {axis, turn};
    }
    return {-1, 0};
}

// Is x, a point of the plane of the non-degenerate triangle t, inside t's closed angle at its
// corner `at` (at s)? Decided in the projection dropping `axis`, where t keeps its area and
// turns `turn` (area_axis): one-to-one on t's plane. The half-open segment (s, x] then enters t
// (the angle is below π, t holds the points of the angle near s); otherwise it never meets t.
bool in_angle(Point3 s, Point3 x, const Triangle3& t, int at, int axis, int turn, PredicateStats& stats) {
    const Point ps = drop_axis(s, axis), px = drop_axis(x, axis);
    const Point pa = drop_axis(t[(at + 1) % 3], axis), pb = drop_axis(t[(at + 2) % 3], axis);
    return orient2(ps, pa, px, stats) * turn >= 0 && orient2(ps, pb, px, stats) * turn <= 0;
}

// Does the half-open segment (s, x] enter the closed, non-degenerate triangle t, which has its
// corner `at` at s? Only if x lies in t's plane, inside the angle of t at s.
bool enters(Point3 s, Point3 x, const Triangle3& t, int at, PredicateStats& stats) {
    if (orient3d(t[0], t[1], t[2], x, stats) != 0) return false;
    const auto [axis, turn] = area_axis(t, stats);
    return in_angle(s, x, t, at, axis, turn, stats);
}

// Do the coplanar, non-degenerate triangles f and g, sharing the corner f[i] = g[j] (at s),
// meet beyond it? Exactly when their closed angles F and G at s share a ray: near s each
// triangle is its angle, and each lies in it. Their intersection, if more than s, is a convex
// angle whose edge rays are edge rays of F or G: if neither of G's lies in F, both are F's, so
// F lies in G and so does either edge ray of F. Decided in the projection where f keeps its
// area, one-to-one on the common plane.
bool coplanar_meet_beyond_corner(const Triangle3& f, int i, const Triangle3& g, int j, PredicateStats& stats) {
    const auto [axis, turn_f] = area_axis(f, stats);
    const Point3 s = f[i];
    if (in_angle(s, g[(j + 1) % 3], f, i, axis, turn_f, stats) || in_angle(s, g[(j + 2) % 3], f, i, axis, turn_f, stats)) {
        return true;
    }
    const int turn_g = orient2(drop_axis(s, axis), drop_axis(g[(j + 1) % 3], axis), drop_axis(g[(j + 2) % 3], axis), stats);
    return in_angle(s, f[(i + 1) % 3], g, j, axis, turn_g, stats);
}

// Triangle u touches the plane of triangle t without crossing it: its corners' sides `side`
// (orient3d against t) are all ≥ 0 or all ≤ 0, some 0, not all. The points of u on the plane
// are then the hull of its corners there (a point's side is the weighted sum of the corners'),
// so u meets t iff that corner or segment meets t: decided in the projection where t keeps its
// area. −1 when t is degenerate (undecided).
int touching_meets(const Triangle3& t, const Triangle3& u, const std::array<int, 3>& side, PredicateStats& stats) {
    const int axis = area_axis(t, stats).first;
    if (axis < 0) return -1;
    Point on[2];
    int count = 0;
    for (int k = 0; k < 3; ++k) {
        if (side[k] == 0) on[count++] = drop_axis(u[k], axis);
    }
    const Point a = drop_axis(t[0], axis), b = drop_axis(t[1], axis), c = drop_axis(t[2], axis);
    if (count == 1) return in_closed_triangle(a, b, c, on[0], Arithmetic::exact, stats) ? 1 : 0;
    return segment_meets_triangle_2d(on[0], on[1], a, b, c, stats) ? 1 : 0;
}

// Whether three sides (orient3d signs) cross a plane strictly: none zero, not all alike. One
// corner is then alone on its side.
bool crosses(const std::array<int, 3>& side) {
    return side[0] != 0 && side[1] != 0 && side[2] != 0 && !(side[0] == side[1] && side[1] == side[2]);
}

// Triangles t and u, each strictly across the other's plane (`t_sides`: t's corners against
// u's plane; `u_sides`: u's against t's; see crosses). After Guigue & Devillers (2003), derived
// here in our orientation. Rotate each so that p1 = t[i] and q1 = u[j] are alone on their sides
// (rotation keeps the planes' orientations); P and Q their sides. The planes meet in a line L
// with direction d = n_t × n_u, where t meets it in the segment A2A3 (A_k on p1p_k) and u in C2C3
// (C_m on q1q_m); t ∩ u is the overlap of the two. Writing p_k − p1 and q_m − q1 as positive
// multiples of A_k − p1 and C_m − q1 and expanding (x × y)·(n_t × n_u),
//   sign d·(C_m − A_k) = orient3d(p1, p_k, q1, q_m) · P · Q,
// and in t's plane d = n_t × (n_u's part there), which points from L to p1's side when P > 0:
// d·(A3 − A2) has the sign of −P; likewise d·(C3 − C2) that of +Q. So t's segment runs from
// A_lo to A_hi along d (lo = 3, hi = 2 when P > 0, else the reverse), u's from C_lo to C_hi
// (lo = 2, hi = 3 when Q > 0), and they overlap iff C_lo is not beyond A_hi nor A_lo beyond
// C_hi.
bool crossing_triangles_meet(const Triangle3& t, const std::array<int, 3>& t_sides, const Triangle3& u,
                             const std::array<int, 3>& u_sides, PredicateStats& stats) {
    auto lone = [](const std::array<int, 3>& side) { return side[0] == side[1] ? 2 : side[0] == side[2] ? 1 : 0; };
    const int i = lone(t_sides), j = lone(u_sides);
    const int pq = t_sides[i] * u_sides[j];  // P · Q
    auto p = [&](int k) { return t[(i + k - 1) % 3]; };  // p(1) = p1, p(2), p(3) in t's turn
    auto q = [&](int m) { return u[(j + m - 1) % 3]; };
    const int a_lo = t_sides[i] > 0 ? 3 : 2, a_hi = 5 - a_lo;
    const int c_lo = u_sides[j] > 0 ? 2 : 3, c_hi = 5 - c_lo;
    // Sign of d·(C_m − A_k).
    auto after = [&](int m, int k) { return orient3d(p(1), p(k), q(1), q(m), stats) * pq; };
    return after(c_lo, a_hi) <= 0 && after(c_hi, a_lo) >= 0;
}

// Whether three sides (orient3d signs) touch a plane without crossing it: none opposite, some
// zero, not all.
bool touches(const std::array<int, 3>& side) {
    const bool zero = side[0] == 0 || side[1] == 0 || side[2] == 0;
    const bool positive = side[0] > 0 || side[1] > 0 || side[2] > 0;
    const bool negative = side[0] < 0 || side[1] < 0 || side[2] < 0;
    return zero && positive != negative;
}

// p with every coordinate times 2^k.
Point3 scaled(Point3 p, int k) {
    using expansion::times_power_of_two;
    return {times_power_of_two(p.x, k), times_power_of_two(p.y, k), times_power_of_two(p.z, k)};
}

}  // namespace

int orient3d_gmp(Point3 a, Point3 b, Point3 c, Point3 d) {
    const Point3 points[] = {a, b, c, d};
    return sgn(orient3d_expr<mpz_class>(a, b, c, d, ToInteger(points)));
}

int orient3d_expansion(Point3 a, Point3 b, Point3 c, Point3 d) {
    using namespace expansion;
    for (const Point3& p : {a, b, c, d}) {
        if (!in_range(p.x) || !in_range(p.y) || !in_range(p.z)) return 2;
    }
    const Expansion<2> bx = difference(b.x, a.x), by = difference(b.y, a.y), bz = difference(b.z, a.z);
    const Expansion<2> cx = difference(c.x, a.x), cy = difference(c.y, a.y), cz = difference(c.z, a.z);
    const Expansion<2> dx = difference(d.x, a.x), dy = difference(d.y, a.y), dz = difference(d.z, a.z);
    // Differences all exact (one double each; common where the filter fails: coplanar points
    // with short coordinates): the same determinant over doubles, in expansions of at most 24
    // terms instead of products of two-term expansions.
    const Expansion<2>* differences[] = {&bx, &by, &bz, &cx, &cy, &cz, &dx, &dy, &dz};
    if (std::all_of(std::begin(differences), std::end(differences), [](const Expansion<2>* e) { return e->n <= 1; })) {
        auto lone = [](const Expansion<2>& e) { return e.n == 0 ? 0.0 : e.c[0]; };
        auto times = [](double x, double y) {
            Expansion<2> e;
            double y_hi, y_lo, hi, lo;
            split(y, y_hi, y_lo);
            two_product_split(x, y, y_hi, y_lo, hi, lo);
            if (lo != 0.0) e.c[e.n++] = lo;
            if (hi != 0.0) e.c[e.n++] = hi;
            return e;
        };
        const double Bx = lone(bx), By = lone(by), Bz = lone(bz), Cx = lone(cx), Cy = lone(cy), Cz = lone(cz);
        const Expansion<4> nx = sum(times(By, Cz), negate(times(Bz, Cy)));
        const Expansion<4> ny = sum(times(Bz, Cx), negate(times(Bx, Cz)));
        const Expansion<4> nz = sum(times(Bx, Cy), negate(times(By, Cx)));
        return sum(sum(scale(nx, lone(dx)), scale(ny, lone(dy))), scale(nz, lone(dz))).sign();
    }
    const Expansion<16> nx = sum(product(by, cz), negate(product(bz, cy)));
    const Expansion<16> ny = sum(product(bz, cx), negate(product(bx, cz)));
    const Expansion<16> nz = sum(product(bx, cy), negate(product(by, cx)));
    return sum(sum(product(nx, dx), product(ny, dy)), product(nz, dz)).sign();
}

PlaneSide::PlaneSide(Point3 a, Point3 b, Point3 c) : a_(a), b_(b), c_(c) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double yz = uy * vz, zy = uz * vy, zx = uz * vx, xz = ux * vz, xy = ux * vy, yx = uy * vx;
    normal_ = {yz - zy, zx - xz, xy - yx};
    magnitude_ = {std::fabs(yz) + std::fabs(zy), std::fabs(zx) + std::fabs(xz), std::fabs(xy) + std::fabs(yx)};
}

int PlaneSide::operator()(Point3 d, PredicateStats& stats) const {
    const double wx = d.x - a_.x, wy = d.y - a_.y, wz = d.z - a_.z;
    const double det = wx * normal_.x + wy * normal_.y + wz * normal_.z;
    const double permanent = std::fabs(wx) * magnitude_.x + std::fabs(wy) * magnitude_.y + std::fabs(wz) * magnitude_.z;
    if (permanent >= 0x1p-800 && permanent <= 0x1p1000) {
        const double bound = (8.0 + 64.0 * kUnitRoundoff) * kUnitRoundoff * permanent;
        if (det > bound) {
            ++stats.filter_decided;
            return 1;
        }
        if (-det > bound) {
            ++stats.filter_decided;
            return -1;
        }
    }
    return orient3d(a_, b_, c_, d, stats);
}

int orient3d(Point3 a, Point3 b, Point3 c, Point3 d, PredicateStats& stats) {
    // Shewchuk's semi-static filter first (orient3dfast with the bound (7 + 56ε)ε·permanent);
    // his determinant det[a−d; b−d; c−d] is the negative of ours.
    const double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
    const double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;
    const double adz = a.z - d.z, bdz = b.z - d.z, cdz = c.z - d.z;
    const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    const double cdxady = cdx * ady, adxcdy = adx * cdy;
    const double adxbdy = adx * bdy, bdxady = bdx * ady;
    const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
    const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                             (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                             (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
    if (permanent >= 0x1p-800 && permanent <= 0x1p1000) {
        const double bound = (7.0 + 56.0 * kUnitRoundoff) * kUnitRoundoff * permanent;
        if (det > bound) {
            ++stats.filter_decided;
            return -1;
        }
        if (-det > bound) {
            ++stats.filter_decided;
            return 1;
        }
    }
    // Terms out of the filter's range (coordinates far from 1, or far apart), and the points out
    // of the expansions' range below: once more with all points scaled towards 1, if that is
    // exact (the determinant is then 2^3k times this one; the second call's k is 0, so there is
    // no third). A permanent of exactly 0 is mostly exact zeros (points in a plane z = const),
    // which the expansions decide at once: not scaled first.
    const double values[] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
    auto rescaled = [&](int& sign) {
        const int k = expansion::exact_rescaling(values);
        if (k != 0) sign = orient3d(scaled(a, k), scaled(b, k), scaled(c, k), scaled(d, k), stats);
        return k != 0;
    };
    int sign = 2;
    if (permanent > 0.0 && !(permanent >= 0x1p-800 && permanent <= 0x1p1000) && rescaled(sign)) [[unlikely]] {
        return sign;
    }
    // The dynamic filter next, unless the determinant came out exactly zero: then the points are
    // almost surely coplanar (flat regions), which no filter can certify.
    sign = det == 0.0 ? 2 : certified_sign(orient3d_expr<Bounded>(a, b, c, d, Plain<Bounded>{}));
    if (sign != 2) {
        ++stats.filter_decided;
        return sign;
    }
    sign = orient3d_expansion(a, b, c, d);
    if (sign != 2) {
        ++stats.expansion_decided;
        return sign;
    }
    if (rescaled(sign)) return sign;
    ++stats.gmp_fallbacks;
    return orient3d_gmp(a, b, c, d);
}

int orient3d_float(Point3 a, Point3 b, Point3 c, Point3 d) {
    const double det = orient3d_expr<double>(a, b, c, d, Plain<double>{});
    return (det > 0) - (det < 0);
}

int normal_dot_sign(Point3 a, Point3 b, Point3 c, Point3 d, Point3 e, Point3 f, PredicateStats& stats) {
    // A semi-static filter first. Evaluated in doubles, each of the 36 terms of the expanded
    // polynomial (a product of four differences) picks up at most 9 roundings (difference,
    // product, subtraction in each cross product, their product, two additions), so the error is
    // at most γ9 times the sum of the terms' magnitudes, which the same evaluation over
    // magnitudes (`permanent`) underestimates by at most the factor 1 − γ9: 10u·permanent covers
    // both and the rounding of the bound itself. That model needs no underflow or overflow: with
    // every nonzero difference within 2^±200, a product of two is a double of at least 2^-400, a
    // nonzero cross product component at least its ulp, 2^-452, and a product of two components
    // at least 2^-904 (a sum that lands below 2^-1022 is exact); nothing exceeds 2^803.
    const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z, cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z;
    const double ex = e.x - d.x, ey = e.y - d.y, ez = e.z - d.z, fx = f.x - d.x, fy = f.y - d.y, fz = f.z - d.z;
    bool in_range = true;
    for (const double v : {bx, by, bz, cx, cy, cz, ex, ey, ez, fx, fy, fz}) {
        const double m = std::fabs(v);
        in_range &= m == 0.0 || (m >= 0x1p-200 && m <= 0x1p200);
    }
    if (in_range) {
        const double n1x = by * cz - bz * cy, n1y = bz * cx - bx * cz, n1z = bx * cy - by * cx;
        const double n2x = ey * fz - ez * fy, n2y = ez * fx - ex * fz, n2z = ex * fy - ey * fx;
        const double value = n1x * n2x + n1y * n2y + n1z * n2z;
        const double m1x = std::fabs(by * cz) + std::fabs(bz * cy), m1y = std::fabs(bz * cx) + std::fabs(bx * cz),
                     m1z = std::fabs(bx * cy) + std::fabs(by * cx);
        const double m2x = std::fabs(ey * fz) + std::fabs(ez * fy), m2y = std::fabs(ez * fx) + std::fabs(ex * fz),
                     m2z = std::fabs(ex * fy) + std::fabs(ey * fx);
        const double bound = 10.0 * kUnitRoundoff * (m1x * m2x + m1y * m2y + m1z * m2z);
        if (value > bound || -value > bound) {
            ++stats.filter_decided;
            return value > 0 ? 1 : -1;
        }
    }
    // As orient3d: out of range, scaled towards 1 if that is exact (the value is then 2^4k times
    // this one).
    if (!in_range) [[unlikely]] {
        const double values[] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z, e.x, e.y, e.z, f.x, f.y, f.z};
        if (const int k = expansion::exact_rescaling(values); k != 0) {
            return normal_dot_sign(scaled(a, k), scaled(b, k), scaled(c, k), scaled(d, k), scaled(e, k), scaled(f, k), stats);
        }
    }
    const int sign = certified_sign(normal_dot_expr<Bounded>(a, b, c, d, e, f, Plain<Bounded>{}));
    if (sign != 2) {
        ++stats.filter_decided;
        return sign;
    }
    ++stats.gmp_fallbacks;
    const Point3 points[] = {a, b, c, d, e, f};
    return sgn(normal_dot_expr<mpz_class>(a, b, c, d, e, f, ToInteger(points)));
}

// The semi-static stage of the gap predicates: value ≈ ṽ within value_error, denominator ≈ d̃
// within denominator_error (Shewchuk's bounds for the orient3d and orient2d shapes), and the
// two roundings of ṽ ∓ bound·d̃ on top, all widened by 2^-40 for the rounding of the bound's own
// arithmetic. 1 within, 0 not, 2 undecided (a bound out of range, or too close to call).
int gap_verdict_static(double value, double value_error, double denominator, double denominator_error, double bound) {
    if (!(bound <= 0x1p1000) || !(std::fabs(denominator) > denominator_error)) return 2;
    const double slack = bound * denominator;
    if (bound != 0.0 && std::fabs(slack) < 0x1p-900) return 2;  // (may have underflowed)
    const double base = value_error + bound * denominator_error + kUnitRoundoff * std::fabs(slack);
    const double over = value - slack, under = value + slack;
    const double over_error = (base + kUnitRoundoff * std::fabs(over)) * (1.0 + 0x1p-40);
    const double under_error = (base + kUnitRoundoff * std::fabs(under)) * (1.0 + 0x1p-40);
    if (!(std::fabs(over) > over_error) || !(std::fabs(under) > under_error)) return 2;
    const int d = denominator > 0 ? 1 : -1;
    const int over_sign = over > 0 ? 1 : -1, under_sign = under > 0 ? 1 : -1;
    return over_sign * d < 0 && under_sign * d > 0 ? 1 : 0;
}

// Whether a permanent lies where Shewchuk's static bounds hold (no overflow, and underflow
// below what the bound covers).
bool permanent_in_range(double permanent) { return permanent >= 0x1p-800 && permanent <= 0x1p1000; }

// The cascade of both gap predicates: the static stage from the value and the denominator
// computed in doubles with their permanents (the orient3d and orient2d shapes), then the
// dynamic filter, then GMP integers. `expression(to)` is the predicate's Gap over `to`'s number
// type; `points` its inputs (the bound among them) for the integer scaling.
template <class Expression>
bool decide_gap(double value, double permanent, double denominator, double denominator_permanent, double bound,
                const Point3 (&points)[5], Expression expression, PredicateStats& stats) {
    if (permanent_in_range(permanent) && permanent_in_range(denominator_permanent)) {
        const int verdict = gap_verdict_static(value, (7.0 + 56.0 * kUnitRoundoff) * kUnitRoundoff * permanent, denominator,
                                               (3.0 + 16.0 * kUnitRoundoff) * kUnitRoundoff * denominator_permanent, bound);
        if (verdict != 2) {
            ++stats.filter_decided;
            return verdict == 1;
        }
    }
    const int verdict = gap_verdict(expression(Plain<Bounded>{}), bounded_sign);
    if (verdict != 2) {
        ++stats.filter_decided;
        return verdict == 1;
    }
    ++stats.gmp_fallbacks;
    return gap_verdict(expression(ToInteger(points)), integer_sign) == 1;
}

bool vertical_gap_within(const Triangle3& t, Point3 v, double bound, PredicateStats& stats) {
    if (t[0].z == v.z && t[1].z == v.z && t[2].z == v.z) {
        ++stats.filter_decided;  // all at v's height: a gap of exactly 0
        return bound >= 0.0;
    }
    // The value is orient3d(t0, t1, t2, v) in Shewchuk's arrangement, the denominator orient2d(t0, t1, t2).
    const double x0 = t[0].x - v.x, y0 = t[0].y - v.y, z0 = t[0].z - v.z;
    const double x1 = t[1].x - v.x, y1 = t[1].y - v.y, z1 = t[1].z - v.z;
    const double x2 = t[2].x - v.x, y2 = t[2].y - v.y, z2 = t[2].z - v.z;
    const double x1y2 = x1 * y2, y1x2 = y1 * x2, x2y0 = x2 * y0, y2x0 = y2 * x0, x0y1 = x0 * y1, y0x1 = y0 * x1;
    const double value = z0 * (x1y2 - y1x2) + z1 * (x2y0 - y2x0) + z2 * (x0y1 - y0x1);
    const double permanent = std::fabs(z0) * (std::fabs(x1y2) + std::fabs(y1x2)) + std::fabs(z1) * (std::fabs(x2y0) + std::fabs(y2x0)) +
                             std::fabs(z2) * (std::fabs(x0y1) + std::fabs(y0x1));
    const double left = (t[0].x - t[2].x) * (t[1].y - t[2].y), right = (t[0].y - t[2].y) * (t[1].x - t[2].x);
    const Point3 points[] = {t[0], t[1], t[2], v, {bound, 0, 0}};
    return decide_gap(value, permanent, left - right, std::fabs(left) + std::fabs(right), bound, points,
                      [&](auto to) { return vertical_gap_expr(t, v, bound, to); }, stats);
}

bool crossing_gap_within(Point3 a, Point3 b, Point3 u, Point3 w, double bound, PredicateStats& stats) {
    const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z;
    const double ux = u.x - a.x, uy = u.y - a.y, uz = u.z - a.z;
    const double wx = w.x - a.x, wy = w.y - a.y, wz = w.z - a.z;
    if (bz == 0.0 && wz == 0.0 && uz == 0.0) {
        ++stats.filter_decided;  // all four at one height: a gap of exactly 0
        return bound >= 0.0;
    }
    // The orient3d shape again (three rounded differences times a 2×2 determinant of rounded
    // differences, summed), and the orient2d shape for the denominator.
    const double ex = w.x - u.x, ey = w.y - u.y;
    const double eyux = ey * ux, exuy = ex * uy, bxuy = bx * uy, byux = by * ux, bxwy = bx * wy, bywx = by * wx;
    const double value = bz * (eyux - exuy) + wz * (bxuy - byux) - uz * (bxwy - bywx);
    const double permanent = std::fabs(bz) * (std::fabs(eyux) + std::fabs(exuy)) + std::fabs(wz) * (std::fabs(bxuy) + std::fabs(byux)) +
                             std::fabs(uz) * (std::fabs(bxwy) + std::fabs(bywx));
    const double left = bx * ey, right = by * ex;
    const Point3 points[] = {a, b, u, w, {bound, 0, 0}};
    return decide_gap(value, permanent, left - right, std::fabs(left) + std::fabs(right), bound, points,
                      [&](auto to) { return crossing_gap_expr(a, b, u, w, bound, to); }, stats);
}

int orient_projected(Point3 a, Point3 b, Point3 c, int axis, PredicateStats& stats) {
    return orient2(drop_axis(a, axis), drop_axis(b, axis), drop_axis(c, axis), stats);
}

bool degenerate(const Triangle3& t, PredicateStats& stats) { return area_axis(t, stats).first < 0; }

bool segment_meets_triangle(Point3 p, Point3 q, const Triangle3& t, PredicateStats& stats) {
    if (!segment_box(p, q).overlaps(triangle_box(t[0], t[1], t[2]))) return false;
    const int axis = area_axis(t, stats).first;
    if (axis < 0) {
        // A segment or a point: the union of its three sides.
        return segments_meet_3d(p, q, t[0], t[1], stats) || segments_meet_3d(p, q, t[1], t[2], stats) ||
               segments_meet_3d(p, q, t[2], t[0], stats);
    }
    const int sp = orient3d(t[0], t[1], t[2], p, stats);
    const int sq = orient3d(t[0], t[1], t[2], q, stats);
    if (sp * sq > 0) return false;
    if (sp == 0 && sq == 0) {
        // All five points lie in t's plane, which the projection dropping `axis` (where t keeps
        // its area) maps one-to-one: they meet iff their projections do.
        return segment_meets_triangle_2d(drop_axis(p, axis), drop_axis(q, axis), drop_axis(t[0], axis),
                                         drop_axis(t[1], axis), drop_axis(t[2], axis), stats);
    }
    // The line pq meets t's plane in one point (t is not degenerate, p ≠ q); it lies in the
    // closed triangle iff the line passes no edge on the outer side.
    const int s1 = orient3d(p, q, t[0], t[1], stats);
    const int s2 = orient3d(p, q, t[1], t[2], stats);
    const int s3 = orient3d(p, q, t[2], t[0], stats);
    const bool positive = s1 > 0 || s2 > 0 || s3 > 0;
    const bool negative = s1 < 0 || s2 < 0 || s3 < 0;
    return !(positive && negative);
}

// Conditions, all exact: (1) at least three corners; (2) seen along a direction n — from the
// point q = p + n — every triangle turns one way σ: orient3d(p, x, y, q) = σ; (3) around p the
// triangles wind once: a ray from p (towards s, as seen along n) lies in exactly one triangle's
// half-open angle [x, y), counted with ρ(v) = orient3d(p, v, s, q): the angle holds the ray iff
// σρ(x) ≥ 0 and σρ(y) < 0.
//
// Why that is enough. Project along n onto a plane: orient3d(p, u, v, q) is the orientation of
// the projected p, u, v (the determinant of u − p, v − p and q − p ignores any part along n), so
// by (2) each projected triangle is proper, turning σ, and spans an angle at p below π; (3)
// decides for each angle, as the meet of a closed and an open half-plane, whether the ray lies
// in it (half-open: the ray along y counts for the next triangle only). Around the ring the
// angles follow one another, all turning σ, back to the start: they cover the directions around
// p a whole number of times, once by (3). So the angles of two triangles share only their
// common ray, if they are neighbours in the ring, and each projected triangle lies in its angle:
// two projected triangles meet only at p, or along their shared edge. A common point of two
// triangles projects there, and each triangle projects one-to-one: it is p, or on their shared
// edge in both. (n, q and s are rounded choices: any is sound, a poor one fails a condition.)
bool simple_fan(Point3 p, std::span<const Point3> ring, PredicateStats& stats) {
    const std::size_t n = ring.size();
    if (n < 3) return false;
    double nx = 0, ny = 0, nz = 0, extent = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Point3 x = ring[i], y = ring[(i + 1) % n];
        const double ux = x.x - p.x, uy = x.y - p.y, uz = x.z - p.z, vx = y.x - p.x, vy = y.y - p.y, vz = y.z - p.z;
        nx += uy * vz - uz * vy, ny += uz * vx - ux * vz, nz += ux * vy - uy * vx;
        extent = std::max({extent, std::fabs(ux), std::fabs(uy), std::fabs(uz)});
    }
    const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!(length > 0) || !std::isfinite(length) || !(extent > 0)) return false;
    const double scale = extent / length;
    const Point3 q{p.x + nx * scale, p.y + ny * scale, p.z + nz * scale};
    // s off n's line: along the axis where n is smallest.
    Point3 s = p;
    const double ax = std::fabs(nx), ay = std::fabs(ny), az = std::fabs(nz);
    (ax <= ay && ax <= az ? s.x : ay <= az ? s.y : s.z) += extent;
    if (!std::isfinite(q.x + q.y + q.z + s.x + s.y + s.z)) return false;
    const int sigma = orient3d(p, ring[0], ring[1], q, stats);
    if (sigma == 0) return false;
    for (std::size_t i = 1; i < n; ++i) {
        if (orient3d(p, ring[i], ring[(i + 1) % n], q, stats) != sigma) return false;
    }
    const int rho_first = sigma * orient3d(p, ring[0], s, q, stats);
    int rho = rho_first, rays = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const int rho_next = i + 1 < n ? sigma * orient3d(p, ring[i + 1], s, q, stats) : rho_first;
        rays += rho >= 0 && rho_next < 0;
        rho = rho_next;
    }
    return rays == 1;
}

int coplanar_triangles_meet(const Triangle3& t, const Triangle3& u, PredicateStats& stats) {
    // The projection dropping the axis where t keeps its area maps t's plane one-to-one, so
    // the closed triangles meet iff their projections do: an edge of u meets t, or t lies
    // inside u (then t's corner does).
    const auto [axis, turn] = area_axis(t, stats);
    if (axis < 0) return -1;
    auto flat = [dropped = axis](Point3 p) { return drop_axis(p, dropped); };  // (clang 14 captures no bindings)
    // Quick rejection: u strictly beyond the line of one of t's edges (side-by-side faces of a
    // flat region, the usual case).
    for (int i = 0; i < 3; ++i) {
        const Point a = flat(t[i]), b = flat(t[(i + 1) % 3]);
        bool beyond = true;
        for (int j = 0; j < 3 && beyond; ++j) beyond = orient2(a, b, flat(u[j]), stats) * turn < 0;
        if (beyond) return 0;
    }
    for (int i = 0; i < 3; ++i) {
        if (segment_meets_triangle_2d(flat(u[i]), flat(u[(i + 1) % 3]), flat(t[0]), flat(t[1]), flat(t[2]), stats)) {
            return 1;
        }
    }
    return in_closed_triangle(flat(u[0]), flat(u[1]), flat(u[2]), flat(t[0]), Arithmetic::exact, stats) ? 1 : 0;
}

namespace {

// The sides of u's corners with respect to t's plane, each computed when first asked unless
// given.
class Sides {
public:
    Sides(const Triangle3& t, const Triangle3& u, std::array<int, 3> known, PredicateStats& stats)
        : t_(t), u_(u), side_(known), stats_(stats) {}
    int operator()(std::size_t k) {
        if (side_[k] == kSideUnknown) side_[k] = orient3d(t_[0], t_[1], t_[2], u_[k], stats_);
        return side_[k];
    }

private:
    const Triangle3& t_;
    const Triangle3& u_;
    std::array<int, 3> side_;
    PredicateStats& stats_;
};

bool triangles_meet(const Triangle3& t, const Triangle3& u, Sides& side, PredicateStats& stats) {
    if (!triangle_box(t[0], t[1], t[2]).overlaps(triangle_box(u[0], u[1], u[2]))) return false;
    // u strictly on one side of t's plane: apart (the usual quick rejection).
    const int u0 = side(0), u1 = side(1);
    if (u0 * u1 >= 0) {
        const std::array<int, 3> sides{u0, u1, side(2)};
        if (u0 != 0 && sides[1] == u0 && sides[2] == u0) return false;
        if (u0 == 0 && u1 == 0 && sides[2] == 0) {
            // u lies in the plane of t (in flat regions, most pairs).
            if (const int met = coplanar_triangles_meet(t, u, stats); met >= 0) return met == 1;
        } else if (touches(sides)) {
            // u rests on t's plane at a corner or an edge (along creases of CAD models).
            if (const int met = touching_meets(t, u, sides, stats); met >= 0) return met == 1;
        }
    }
    // The same with the roles swapped: t strictly on one side of u's plane, or resting on it.
    std::array<int, 3> t_sides{};
    for (int k = 0; k < 3; ++k) t_sides[k] = orient3d(u[0], u[1], u[2], t[k], stats);
    if (t_sides[0] != 0 && t_sides[1] == t_sides[0] && t_sides[2] == t_sides[0]) return false;
    if (touches(t_sides)) {
        if (const int met = touching_meets(u, t, t_sides, stats); met >= 0) return met == 1;
    }
    const std::array<int, 3> u_sides{u0, u1, side(2)};
    if (crosses(t_sides) && crosses(u_sides)) return crossing_triangles_meet(t, t_sides, u, u_sides, stats);
    // Closed triangles meet iff an edge of one meets the other: the boundary of their
    // intersection (a point, segment or convex polygon) lies on their edges.
    for (int i = 0; i < 3; ++i) {
        if (segment_meets_triangle(t[i], t[(i + 1) % 3], u, stats)) return true;
    }
    for (int i = 0; i < 3; ++i) {
        if (segment_meets_triangle(u[i], u[(i + 1) % 3], t, stats)) return true;
    }
    return false;
}

}  // namespace

bool triangles_meet(const Triangle3& t, const Triangle3& u, PredicateStats& stats) {
    Sides side(t, u, {kSideUnknown, kSideUnknown, kSideUnknown}, stats);
    return triangles_meet(t, u, side, stats);
}

bool faces_conflict(const Triangle3& f, const Triangle3& g, PredicateStats& stats) {
    return faces_conflict(f, g, {kSideUnknown, kSideUnknown, kSideUnknown}, stats);
}

bool faces_conflict(const Triangle3& f, const Triangle3& g, std::array<int, 3> g_sides, PredicateStats& stats) {
    if (!triangle_box(f[0], f[1], f[2]).overlaps(triangle_box(g[0], g[1], g[2]))) return false;
    int shared = 0;
    int f_at[3], g_at[3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            if (same_location(f[i], g[j])) {
                f_at[shared] = i;
                g_at[shared] = j;
                ++shared;
                break;
            }
        }
    }
    Sides side(f, g, g_sides, stats);
    if (shared == 0) return triangles_meet(f, g, side, stats);
    if (shared == 3 || degenerate(g, stats)) return true;
    if (shared == 1) {
        // Quick acceptance: the other two corners of one face strictly on one side of the
        // other's plane — that face then meets the other's plane only at s.
        const int i0 = f_at[0], j0 = g_at[0];
        const int g1 = side((j0 + 1) % 3), g2 = side((j0 + 2) % 3);
        if (g1 != 0 && g2 == g1) return false;
        if (g1 == 0 || g2 == 0) {
            const auto [f_axis, f_turn] = area_axis(f, stats);
            if (f_axis >= 0) {
                // Coplanar: do their angles at s share a ray?
                if (g1 == 0 && g2 == 0) return coplanar_meet_beyond_corner(f, i0, g, j0, stats);
                // One other corner c of g on f's plane, the other off it: g meets that plane in
                // the segment sc (the hull of its corners there), which enters f iff c lies in
                // f's angle at s.
                const Point3 c = g[g1 == 0 ? (j0 + 1) % 3 : (j0 + 2) % 3];
                return in_angle(f[i0], c, f, i0, f_axis, f_turn, stats);
            }
        }
        const int f1 = orient3d(g[0], g[1], g[2], f[(i0 + 1) % 3], stats);
        const int f2 = orient3d(g[0], g[1], g[2], f[(i0 + 2) % 3], stats);
        if (f1 != 0 && f2 == f1) return false;
        if ((f1 == 0) != (f2 == 0)) {
            // The same with the roles swapped (g is not degenerate).
            const auto [g_axis, g_turn] = area_axis(g, stats);
            const Point3 c = f[f1 == 0 ? (i0 + 1) % 3 : (i0 + 2) % 3];
            return in_angle(f[i0], c, g, j0, g_axis, g_turn, stats);
        }
        if (g1 * g2 < 0 && f1 * f2 < 0) {
            // Each face crosses the other's plane: it meets the line L where the planes meet in
            // a segment from s to a point strictly inside its angle at s (on its opposite edge).
            // They meet beyond s iff the two segments leave s the same way along L, iff the
            // point Y where g's opposite edge pq crosses f's plane lies inside f's angle at s,
            // not in the opposite angle (L runs through one and the other). Write f = (s, u, v)
            // in its turn. orient3d(p, q, s, u) has the sign of orient3d(Y, q, s, u) (Y lies
            // between p and q), which is orient3d(Y, s, u, q): q's side of f's plane (g2) when
            // Y, s, u turn as f does — Y on v's side of the line su — and −g2 on the other side
            // (never on the line: u is off g's plane, which holds p, q and s). Likewise for vs.
            const Point3 p = g[(j0 + 1) % 3], q = g[(j0 + 2) % 3];
            const Point3 u = f[(i0 + 1) % 3], v = f[(i0 + 2) % 3];
            return orient3d(p, q, f[i0], u, stats) == g2 && orient3d(p, q, v, f[i0], stats) == g2;
        }
        // (Left: a degenerate f.) Meeting beyond the shared corner s means an edge opposite s
        // meets the other face, or an edge leaving s runs into the other face's angle at s.
        const int i = f_at[0], j = g_at[0];
        const Point3 s = f[i];
        if (segment_meets_triangle(f[(i + 1) % 3], f[(i + 2) % 3], g, stats)) return true;
        if (segment_meets_triangle(g[(j + 1) % 3], g[(j + 2) % 3], f, stats)) return true;
        if (enters(s, f[(i + 1) % 3], g, j, stats) || enters(s, f[(i + 2) % 3], g, j, stats)) return true;
        return enters(s, g[(j + 1) % 3], f, i, stats) || enters(s, g[(j + 2) % 3], f, i, stats);
    }
    // Two shared corners s, t: non-coplanar faces meet exactly along st; coplanar ones overlap
    // iff their third corners lie on the same side of st.
    const int x_at = 3 - f_at[0] - f_at[1], y_at = 3 - g_at[0] - g_at[1];
    if (side(y_at) != 0) return false;
    const Point3 s = f[f_at[0]], t = f[f_at[1]], x = f[x_at], y = g[y_at];
    const auto [axis, turn] = area_axis(f, stats);
    (void)turn;
    const int side_x = orient2(drop_axis(s, axis), drop_axis(t, axis), drop_axis(x, axis), stats);
    const int side_y = orient2(drop_axis(s, axis), drop_axis(t, axis), drop_axis(y, axis), stats);
    return side_x * side_y > 0;
}

}  // namespace toposimp::exact
