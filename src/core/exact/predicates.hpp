// Exact geometric predicates on double coordinates.
//
// Every sign decision the simplifier makes goes through this file. The `exact` mode evaluates
// each predicate first in double precision with a semi-static error bound (Shewchuk, "Adaptive
// Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997, §4.2: the
// orient2d bound (3 + 16ε)ε·(|detleft| + |detright|)); only when that bound cannot certify the
// sign is the determinant recomputed exactly: in floating-point expansions (expansion.hpp) for
// inputs within 2^±150, with GMP rationals beyond. `rational` always uses GMP, as
// the dissertation's EPLSimp did (chapter 3). `floating` is the naive double barycentric test of
// TopoVW (chapter 2): it can answer wrongly near edges and is kept for experiments only.
#pragma once

#include "core/geometry.hpp"

#include <cstdint>
#include <span>
#include <string_view>

namespace toposimp::exact {

enum class Arithmetic { exact, rational, floating };

std::string_view to_string(Arithmetic arithmetic);

// How often the float filter decided, and how often GMP had to.
struct PredicateStats {
    std::uint64_t filter_decided = 0;     // by a floating-point error bound
    std::uint64_t expansion_decided = 0;  // exactly, in floating-point expansions (no allocation)
    std::uint64_t gmp_fallbacks = 0;      // exactly, in GMP (inputs beyond the expansions' range)

    PredicateStats& operator+=(const PredicateStats& other) {
        filter_decided += other.filter_decided;
        expansion_decided += other.expansion_decided;
        gmp_fallbacks += other.gmp_fallbacks;
        return *this;
    }
};

// Sign of the orientation determinant in floating-point expansions (exact), or 2 when an input
// lies outside expansion::in_range and only GMP can decide. For tests and the filters.
int orient2d_expansion(Point a, Point b, Point c);

// Sign of the orientation determinant, computed exactly with GMP:
// > 0: c lies left of the directed line a→b (counter-clockwise turn), < 0: right, 0: collinear.
int orient2d_gmp(Point a, Point b, Point c);

// The same sign, decided by the float filter when it can be certified, by GMP otherwise.
int orient2d(Point a, Point b, Point c, PredicateStats& stats);

// Sign of the shoelace sum over consecutive corners of `ring` (twice its signed area when the
// ring is closed: its last corner at its first's location): > 0 counter-clockwise, < 0
// clockwise. A closed ring is summed about its first corner in doubles with a forward error
// bound (2(n + 8)ε times the sum of the products' magnitudes, n corners); GMP decides when the
// bound does not, and always for an open sequence.
int ring_area_sign(std::span<const Point> ring, PredicateStats& stats);
int ring_area_sign_gmp(std::span<const Point> ring);

// Is p in the closed triangle abc (interior or boundary)? Degenerate triangles (collinear or
// coincident corners) are the closed segment or point they span.
bool in_closed_triangle(Point a, Point b, Point c, Point p, Arithmetic arithmetic, PredicateStats& stats);

// The same test for many points against one triangle: the triangle's orientation is decided
// once, up front.
class ClosedTriangle {
public:
    ClosedTriangle(Point a, Point b, Point c, Arithmetic arithmetic, PredicateStats& stats);
    bool contains(Point p);

private:
    int orient(Point u, Point v, Point w);

    Point a_, b_, c_;
    Arithmetic arithmetic_;
    PredicateStats& stats_;
    int turn_ = 0;  // orientation of abc: +1 counter-clockwise, -1 clockwise, 0 degenerate
};

// TopoVW's barycentric test in plain doubles (unsafe: wrong near edges, false for degenerate
// triangles). Exposed for tests that show what it gets wrong.
bool in_closed_triangle_float(Point a, Point b, Point c, Point p);

}  // namespace toposimp::exact
