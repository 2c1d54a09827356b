// Exact predicates on 3D points for mesh simplification.
//
// Each predicate is the sign of a polynomial in the input doubles. It is evaluated once in
// double precision with a running forward error bound (every operation carries |error| ≤ e,
// grown by the unit roundoff per operation — the "dynamic filter" of Burnikel, Funke and Seel,
// "Exact geometric computation using cascading", 2001); only when |value| does not exceed the
// bound is the sign computed exactly: in floating-point expansions (orient3d, for inputs within
// 2^±150) or else with GMP integers. No epsilon anywhere: a sign is either certified or
// recomputed exactly.
//
// Contacts between closed triangles are decided from these signs alone (segment–triangle tests,
// with every degenerate and coplanar case reduced to exact 2D tests in coordinate projections).
#pragma once

#include "core/exact/predicates.hpp"
#include "core/geometry.hpp"

#include <array>
#include <span>

namespace toposimp::exact {

using Triangle3 = std::array<Point3, 3>;

// Sign of ((b − a) × (c − a)) · (d − a): > 0 when d lies on the side the normal of the
// counter-clockwise triangle abc points to, 0 when the four points are coplanar.
int orient3d(Point3 a, Point3 b, Point3 c, Point3 d, PredicateStats& stats);
int orient3d_gmp(Point3 a, Point3 b, Point3 c, Point3 d);

// orient3d(a, b, c, d) for many points d and one triangle abc: the triangle's part of the filter
// (its edges from a and their cross product) computed once, a point's in six multiplications;
// what the filter leaves undecided goes to orient3d itself. The filter is Shewchuk's with a as
// the reference point instead of d: ((b − a) × (c − a)) · (d − a), evaluated as the sum of three
// terms, each a rounded difference times a difference of two products of rounded differences,
// has the shape his bound (7 + 56ε)ε·permanent covers, the permanent the same six products in
// absolute value. It is taken a little wider here: (8 + 64ε)ε. (Both members are compiled with
// the other predicates, never contracted into FMAs: not inline.)
class PlaneSide {
public:
    PlaneSide(Point3 a, Point3 b, Point3 c);
    int operator()(Point3 d, PredicateStats& stats) const;

private:
    Point3 a_, b_, c_;
    Point3 normal_{}, magnitude_{};
};
// The same sign in floating-point expansions (exact), or 2 when an input lies outside
// expansion::in_range. orient3d uses it between its filters and GMP: exact zeros (coplanar
// points, everywhere in flat CAD regions) cost no allocation.
int orient3d_expansion(Point3 a, Point3 b, Point3 c, Point3 d);
// The same determinant in plain doubles (unsafe; for tests that show what it gets wrong).
int orient3d_float(Point3 a, Point3 b, Point3 c, Point3 d);

// Sign of ((b − a) × (c − a)) · ((e − d) × (f − d)): do the normals of abc and def point the
// same way (> 0), opposite ways (< 0), or is one triangle degenerate or are they orthogonal (0)?
int normal_dot_sign(Point3 a, Point3 b, Point3 c, Point3 d, Point3 e, Point3 f, PredicateStats& stats);

// Orientation of the triangle projected by dropping `axis` (see drop_axis): the sign of the
// normal's `axis` component.
int orient_projected(Point3 a, Point3 b, Point3 c, int axis, PredicateStats& stats);

// Are a, b, c collinear or coincident (a zero normal)?
bool degenerate(const Triangle3& t, PredicateStats& stats);

// Do the closed segment pq and the closed triangle abc share a point? Any degeneracy allowed.
bool segment_meets_triangle(Point3 p, Point3 q, const Triangle3& t, PredicateStats& stats);

// Do two closed triangles share a point? Any degeneracy allowed.
bool triangles_meet(const Triangle3& t, const Triangle3& u, PredicateStats& stats);

// The same when every corner of u is known to lie in t's plane (orient3d == 0): 1 they meet,
// 0 they do not, −1 t is degenerate (then ask triangles_meet).
int coplanar_triangles_meet(const Triangle3& t, const Triangle3& u, PredicateStats& stats);

// May two faces of one surface sit side by side? `f` must be non-degenerate. They may share
// corners (compared by location) and meet exactly there: at one shared corner, or along the
// segment between two. Any other contact — a crossing, a touch, a coplanar overlap, a third
// shared corner (a duplicate face) — is a conflict. A degenerate `g` that shares a corner is
// reported as a conflict too (the caller refuses rather than reasons about it).
bool faces_conflict(const Triangle3& f, const Triangle3& g, PredicateStats& stats);
// The same when some of g's corners' sides of f's plane are known: g_sides[k] is
// orient3d(f[0], f[1], f[2], g[k]), or kSideUnknown (then computed if needed).
constexpr int kSideUnknown = 2;
bool faces_conflict(const Triangle3& f, const Triangle3& g, std::array<int, 3> g_sides, PredicateStats& stats);

// Do the triangles (p, ring[i], ring[i + 1]) (cyclically; the fan a collapse to p makes) meet
// one another only at p and along their shared edges from p? True only if they do; false may
// also mean that this quick proof failed (too few corners, the fan not turning one way as seen
// along the corners' mean normal, or winding around p more than once): then test pairs.
bool simple_fan(Point3 p, std::span<const Point3> ring, PredicateStats& stats);

// Vertical gaps between terrain faces (x–y is the map plane, z the height). Both decide
// exactly whether a height difference is at most `bound` (≥ 0): the difference and the bound
// times its denominator are polynomials in the inputs, signed by the dynamic filter or in GMP.
//
// |height of t's plane above v's map position − v.z| ≤ bound. t must not be degenerate in the
// map plane (its projection has area).
bool vertical_gap_within(const Triangle3& t, Point3 v, double bound, PredicateStats& stats);
// The map-plane segments ab and uw cross at one point inside both (the caller has shown it with
// orient2d): at that point, |height on ab − height on uw| ≤ bound (heights interpolated along
// each segment).
bool crossing_gap_within(Point3 a, Point3 b, Point3 u, Point3 w, double bound, PredicateStats& stats);

}  // namespace toposimp::exact
