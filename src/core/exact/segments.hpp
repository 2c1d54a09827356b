// Exact segment–segment contact classification for planar maps.
#pragma once

#include "core/exact/predicates.hpp"

namespace toposimp::exact {

// The side of ab that c lies on (1 left, -1 right, 0 on the line) in the given arithmetic.
int orientation(Point a, Point b, Point c, Arithmetic arithmetic, PredicateStats& stats);

// Do the closed segments pq and rs meet anywhere other than at a location that is an endpoint of
// both? That is a crossing, a T-contact (an endpoint inside the other segment), or a collinear
// overlap — a contact a planar map does not have. Segments may be degenerate (p = q).
bool improper_contact(Point p, Point q, Point r, Point s, Arithmetic arithmetic, PredicateStats& stats);

// Do the interiors of pq and rs cross at a single point (each pair of ends strictly on
// opposite sides of the other segment's line)?
bool proper_crossing(Point p, Point q, Point r, Point s, Arithmetic arithmetic, PredicateStats& stats);

}  // namespace toposimp::exact
