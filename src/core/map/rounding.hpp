// Rounding a simplified map onto a grid of published coordinates without changing its topology.
//
// Every location of the simplified map (its kept vertices, grouped by location) is moved to a
// grid point, one location at a time, and each move is made only if it is safe by the same kind
// of exact rule the simplifier uses. Moving location L from p to t, with x each location joined
// to L by a live segment:
//   (M1) each closed triangle (x, p, t) holds no live location but x and L, and no control point
//        but at x (a point at x stays on the line, where it was);
//   (M2) the segment (p, t) meets no live segment improperly (exact::improper_contact), other
//        than those at L;
//   (M3) a ring left with 3 or 4 live corners keeps at least 3 distinct locations and its
//        orientation (the input ring's area sign).
// Why that keeps every relation: while L slides from p to t, its segment to x sweeps exactly the
// triangle (x, p, t). A control point outside all of them is never crossed, so no point changes
// side or polygon. A segment s not at L that meets a new segment (x, t) has no end in the
// triangle (M1), so it enters and leaves the triangle through its sides: not through (p, t)
// (M2) nor through the corners p or t (then s would meet (p, t)), so through (x, p) and (x, t):
// s crossed the old segment, which in a map the simplifier left clean means an input crossing,
// and it now crosses the new one instead — the same crossing, moved, never a new contact and
// never a lost one. Segments at L meet only at L: one's far end on another's new segment would
// lie in that segment's triangle (M1). Rings stay simple during the slide, so they keep their
// orientation; M3 covers the degenerate ends of that argument.
//
// When the grid point of L is where a chain neighbour already is (the grid is coarse against
// the segment), the vertex is instead removed, by the simplifier's own rules (the triangle
// (a, p, c) of its neighbours empty but for a and c, its two segments free of contacts, a ring
// keeping 3 corners and its orientation, no segment made to coincide with another): the count
// of kept vertices then drops below the target, and the stats say by how much.
//
// A location that no grid point serves — in a first pass its nearest grid point, in later
// passes any of the 3×3 around it, nearest first, as neighbours move, then the 5×5 — is taken
// out when it is a single vertex inside a chain and the simplifier's rules allow (then the
// grid points are tried again for the rest); otherwise it stays exactly where it is: off the
// grid, reported, never a broken promise. Vertices of frozen chains (degenerate input rings,
// written as given) stay where they are too.
//
// Control points that are written too (the point features of the layers being simplified) go on
// the grid as well, each only if its path from where it is to the grid point meets no live
// segment or location at all (so it crosses nothing, and a point on a line stays where it is).
//
// Sequential and in input order, so the result is the same on any machine and thread count.
#pragma once

#include "core/exact/predicates.hpp"
#include "core/map/grid_step.hpp"
#include "core/map/map_data.hpp"

#include <cstdint>
#include <vector>

namespace toposimp::map {

struct RoundingOptions {
    OutputGrid grid;
    exact::Arithmetic arithmetic = exact::Arithmetic::exact;
    int passes = 6;  // passes over the locations not yet on the grid (the first tries only the nearest point)
    std::size_t written_points = 0;  // control points [0, n) are written out: put them on the grid too
};

struct RoundingStats {
    std::uint64_t locations = 0;        // distinct locations of the kept vertices
    std::uint64_t already_on_grid = 0;  // on their grid point from the start
    std::uint64_t moved_nearest = 0;    // moved to the nearest grid point
    std::uint64_t moved_other = 0;      // moved to another grid point of the 3×3 around
    std::uint64_t removed = 0;          // vertices removed: their grid point was a neighbour's, or none was safe
    std::uint64_t removed_off_grid = 0; //   of which: no grid point near was safe (taken out instead)
    std::uint64_t off_grid = 0;         // locations left where they were: no grid point was safe
    std::uint64_t frozen = 0;           // locations on frozen chains, left as given
    std::uint64_t points_moved = 0;     // written control points put on the grid (or on it already)
    std::uint64_t points_off_grid = 0;  // written control points left where they were
    std::uint32_t passes = 0;
    exact::PredicateStats predicates;
};

struct RoundingResult {
    OutputGrid grid;                      // the grid rounded to
    std::vector<Point> at;                // per vertex: where it is written (meaningful where kept)
    std::vector<std::uint8_t> kept;       // the kept vertices after rounding (a subset of those given)
    std::vector<std::uint32_t> off_grid;  // one vertex per location left off the grid, in input order
    std::vector<Point> points;            // the written control points [0, written_points), where they are written
    RoundingStats stats;
    double seconds = 0;
};

// Rounds the kept vertices of `map` onto options.grid. Throws std::invalid_argument if the grid
// is too fine for the coordinates (|x| / step ≥ 2^62, or 2^52 for a quantized grid).
RoundingResult round_to_grid(const MapData& map, const std::vector<std::uint8_t>& kept, const RoundingOptions& options);

}  // namespace toposimp::map
