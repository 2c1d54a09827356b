// Crossing input (roads over rivers, T-junctions without a shared vertex, overlapping lines).
//
// The point-in-triangle rule keeps a map planar only if it starts planar. Where the input has a
// segment with an improper contact (see exact::improper_contact), the vertices at both ends of
// that segment are pinned: never removed. Then every other live segment stays free of improper
// contacts, by induction over removals: if the new segment (a, c) replacing a, v, c met some
// segment s improperly, s would have an endpoint in the closed triangle (a, v, c) — refused by
// the point rule — or would cross or touch the edge (a, v) or (v, c) away from shared ends,
// which only pinned segments do. So crossings in the input stay exactly as they are and no new
// one appears.
#pragma once

#include "core/exact/predicates.hpp"
#include "core/map/map_data.hpp"

#include <cstdint>
#include <vector>

namespace toposimp::map {

// Per vertex v: 1 if the segment from v to the next vertex of its chain meets another segment of
// the map improperly. Found with a uniform grid over segment boxes; each candidate pair is tested
// once, exactly.
std::vector<std::uint8_t> find_improper_segments(const MapData& map, exact::Arithmetic arithmetic,
                                                 exact::PredicateStats& stats);

}  // namespace toposimp::map
