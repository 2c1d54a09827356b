// Exact location of a point relative to a ring.
#pragma once

#include "core/exact/predicates.hpp"

#include <span>

namespace toposimp::exact {

enum class RingLocation { outside, boundary, inside };

// Where is p relative to the closed ring (closing vertex optional)? Inside means an odd number of
// crossings of a ray from p (even-odd rule), decided with exact orientation and exact coordinate
// comparisons; on any edge is boundary.
RingLocation locate_in_ring(std::span<const Point> ring, Point p, PredicateStats& stats);

}  // namespace toposimp::exact
