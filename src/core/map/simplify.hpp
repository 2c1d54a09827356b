// EPLSimp / TopoVW map simplification (dissertation chapters 2–3).
//
// Interior vertices are ranked by Visvalingam–Whyatt effective area in one priority queue and
// removed smallest first, but a vertex v with chain neighbours a, c is removed only when
//   1. the closed triangle (a, v, c) holds no other live vertex and no control point, except
//      points at the very locations of a and c (they stay where they are; see 3 for the one
//      way such a point could still matter);
//   2. a closed chain keeps at least 3 distinct locations and, when only 3 remain, they turn
//      the same way as the input ring (non-zero area, same orientation);
//   3. the new segment (a, c) does not coincide with another live segment with the same two
//      end locations (two lines with the same endpoints, or a chain folding back on itself).
// and never removes a vertex at either end of a segment that crosses or touches another segment
// improperly in the input (crossings.hpp). These rules keep every topological relation: no new
// contact between segments, crossings of the input kept as they are, no control point changes
// side (the detour a…c swept by the removals is a union of such empty triangles). Predicates
// are exact unless Arithmetic::floating is asked for.
#pragma once

#include "core/exact/predicates.hpp"
#include "core/map/map_data.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace toposimp::map {

// When to stop removing vertices.
enum class Target {
    keep_fraction,  // keep ceil(value · input vertices) vertices
    keep_points,    // keep `value` vertices in total
    remove_points,  // remove `value` vertices (GIS Cup 2014 convention)
    max_area,       // remove while the smallest effective area is ≤ value (map units²)
    max,            // remove every vertex that can be removed
};

struct StopCriterion {
    Target target = Target::keep_fraction;
    double value = 0.1;
};

struct SimplifyOptions {
    StopCriterion stop;
    exact::Arithmetic arithmetic = exact::Arithmetic::exact;
    // Called now and then with the share of the work done (0…1); may be empty. Only reports.
    std::function<void(double done)> progress;
};

struct SimplifyStats {
    std::uint64_t vertices_in = 0;
    std::uint64_t vertices_out = 0;
    std::uint64_t control_points = 0;
    std::uint64_t removed = 0;
    std::uint64_t removal_goal = 0;          // for count targets; 0 otherwise
    bool target_reached = true;              // false if a count target could not be met
    std::uint64_t blocked_by_point = 0;      // removals refused: a point in the triangle
    std::uint64_t blocked_by_ring = 0;       // refused: a ring would lose area or orientation
    std::uint64_t blocked_by_coincidence = 0;  // refused: two segments would coincide
    std::uint64_t pinned_by_crossing = 0;    // interior vertices kept: ends of crossing segments
    exact::PredicateStats predicates;

    std::uint64_t blocked() const { return blocked_by_point + blocked_by_ring + blocked_by_coincidence; }
};

struct SimplifyResult {
    std::vector<std::uint8_t> kept;  // per input vertex: 1 if it is in the output
    SimplifyStats stats;
};

// How many removals a count target asks for on a map with `vertices` vertices.
std::uint64_t removal_goal(const StopCriterion& stop, std::uint64_t vertices);

SimplifyResult simplify(const MapData& map, const SimplifyOptions& options);

}  // namespace toposimp::map
