// The vertical-error guarantee for terrains: a collapse is made only if, over the part of the
// map plane it changes, the new surface stays within `bound` of the input surface straight above
// or below — everywhere, not at samples.
//
// Why checking finitely many points is enough: over the changed region R (the collapse's faces
// before and after cover the same part of the map plane: no face folds over, the border does
// not move), the height difference between the new faces and the input faces is linear on each
// cell of their overlay (a new face cut by an input face: convex), so it is largest at the
// cells' corners. Those are the input vertices in R, the new faces' corners, and the crossings
// of the new faces' edges with the input's edges. The corners and edges on R's border are
// unchanged by the collapse and were within the bound before (induction from the input, where
// the difference is 0), so what is left to check is: every input vertex in R against the new
// face over it, the merged vertex p against every input face under it, and every crossing of an
// edge from p with an input edge. Each comparison is exact (vertical_gap_within,
// crossing_gap_within).
//
// Finding them without searching: every input vertex is kept in the list of a current face over
// it (at the start, a face it is a corner of), so those in R are in the lists of the faces the
// collapse replaces, and after it they move to the new faces found over them. The input edges
// crossing an edge from p are found by walking the input faces along it, from those under p.
//
// This assumes the input is a height field (its faces do not overlap in the map plane), as every
// DEM-derived TIN is; the simplifier checks it of any other (height_field.hpp).
#pragma once

#include "core/exact/predicates3d.hpp"
#include "core/mesh/mesh.hpp"
#include "core/mesh/plan_index.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::mesh {

class VerticalBound {
public:
    // `input`: the terrain the simplifier starts from; its face ids are the simplifier's.
    VerticalBound(const Mesh& input, double bound);

    // `fan`: the faces a collapse makes, each with the merged vertex p as its first corner, all
    // turned the same way in the map plane (none degenerate there); `before`: the faces it
    // removes or changes, which cover the same region. Is the new surface there within the bound
    // of the input's? Safe to call from several threads for disjoint regions.
    bool holds(std::span<const exact::Triangle3> fan, std::span<const std::uint32_t> before, exact::PredicateStats& stats);

    // After holds() said yes on this thread and the collapse was made: `after[i]` is the face
    // that fan[i] became. The input vertices of `before` move to the new faces over them.
    void collapsed(std::span<const std::uint32_t> before, std::span<const std::uint32_t> after);

    // The simplifier renumbered its faces: face kept[i] is now face i, the others are gone.
    void renumber_faces(std::span<const std::uint32_t> kept);

private:
    // Does the walk along the segment from p to l meet only crossings within the bound?
    bool crossings_hold(Point3 p, Point3 l, std::span<const std::uint32_t> start, exact::PredicateStats& stats);

    static constexpr std::uint32_t kNone = 0xffffffffu;
    Mesh input_;
    PlanIndex index_;
    std::vector<std::array<std::uint32_t, 3>> neighbour_;  // per input face, across its edge from corner k (kNone: border)
    std::vector<std::uint32_t> first_;  // per current face: the first input vertex listed in it
    std::vector<std::uint32_t> next_;   // per input vertex: the next one in its face's list
    double bound_;
};

}  // namespace toposimp::mesh
