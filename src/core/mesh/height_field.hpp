// Is a terrain mesh a height field over a planar triangulation: do its faces, all turned the same
// way in the map plane, cover each point of it at most once?
//
// The terrain simplifier relies on it: with every face kept turned its way and the border kept,
// a height field stays one, so no 3D contact search is needed, and the vertical bound compares
// the output with the one input face under each point. A mesh that is not one (a ramp that
// winds over itself, a bridge deck over the road below, two sheets one above the other) must
// be simplified as a surface in space.
#pragma once

#include "core/mesh/mesh.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace toposimp::mesh {

using DirectedEdge = std::pair<std::uint32_t, std::uint32_t>;

// The border edges (v, w), sorted: a face has the edge from v to w and none the edge from w to v
// (one such pair per face that has it). `threads`: 0 for OpenMP's default.
std::vector<DirectedEdge> border_edges(const Mesh& mesh, int threads = 0);

// `mesh`: faces all turned `turn` (±1) in the map plane, none degenerate there, no edge with
// more than two faces; `border`: its border_edges. Two faces whose interiors overlap in the map
// plane, the smallest such pair of face numbers, or none: it is a height field. `threads`: 0 for
// OpenMP's default (the answer does not depend on it).
std::optional<std::array<std::uint32_t, 2>> plan_overlap(const Mesh& mesh, int turn, const std::vector<DirectedEdge>& border,
                                                         int threads = 0);
inline std::optional<std::array<std::uint32_t, 2>> plan_overlap(const Mesh& mesh, int turn) {
    return plan_overlap(mesh, turn, border_edges(mesh));
}

// The fast test plan_overlap tries first, exposed for the tests. True: no two faces overlap.
// False: not shown (they may or may not).
//
// Why a test of the border is enough. Where the faces are consistently oriented (every edge with
// two faces has them on either side of it: traversed once each way), the faces over a point,
// all turned `turn`, number `turn` times the winding number of the border edges around it (the
// border of their sum, as chains). If the border is a set of simple closed loops, pairwise
// apart, a thin strip along one side of a loop meets no other loop, so the count is one value
// over it, and one less across the loop; every region the loops bound borders a loop. So the
// count is at most one everywhere exactly when, for every loop, it is one on the side of its
// faces: the loop's own winding on that side plus the other loops' winding numbers around one
// of its corners. Costs a pass over the vertices' faces and work on the border only; false
// (the slow test decides) when the border is not such loops, or has so many loops that the
// windings would cost more than the slow test.
bool covers_once_by_border(const Mesh& mesh, int turn, const std::vector<DirectedEdge>& border);
inline bool covers_once_by_border(const Mesh& mesh, int turn) { return covers_once_by_border(mesh, turn, border_edges(mesh)); }

}  // namespace toposimp::mesh
