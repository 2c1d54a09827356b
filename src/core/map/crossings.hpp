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

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::map {

// How two segments of a map meet, beyond sharing an end location.
enum class ContactKind : std::uint8_t {
    crossing,   // proper crossing: interiors cross at one point
    touching,   // an end inside the other segment, or a partial collinear overlap
    identical,  // the same two end locations (a shared border, or two coincident lines)
};

// A contact between segments s and t, each named by its first vertex (the segment runs to the
// next vertex of its chain), s < t.
struct SegmentContact {
    std::uint32_t s, t;
    ContactKind kind;
};

// Every pair of segments of the map that meets other than at a shared end location, decided
// exactly; candidate pairs come from a uniform grid over segment boxes, each tested once. On
// `threads` threads (0: OpenMP's default); the result is the same for any number.
// `line_of`, if given, holds per segment (by first vertex) a group, or kNoLine: two segments of
// one group are neither tested nor listed (the caller, who knows them to lie on one line, counts
// their overlaps along it).
inline constexpr std::uint32_t kNoLine = UINT32_MAX;
std::vector<SegmentContact> find_segment_contacts(const MapData& map, exact::Arithmetic arithmetic,
                                                  exact::PredicateStats& stats, int threads = 0,
                                                  std::span<const std::uint32_t> line_of = {});

// Per vertex v: 1 if the segment from v to the next vertex of its chain meets another segment of
// the map improperly (any contact above). Once `cancel` is set (core/cancel.hpp) the search
// stops early and its result is incomplete: the caller must then stop.
std::vector<std::uint8_t> find_improper_segments(const MapData& map, exact::Arithmetic arithmetic,
                                                 exact::PredicateStats& stats, int threads = 0,
                                                 const std::atomic<bool>* cancel = nullptr);

// How many times the search splits its grid's rows for this map (0 to 3; see row_split in
// crossings.cpp): for tests, which must reach every shape of the grid.
unsigned search_row_split(const MapData& map);

}  // namespace toposimp::map
