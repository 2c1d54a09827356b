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
// This assumes the input is a height field (its faces do not overlap in the map plane), as every
// DEM-derived TIN is.
#pragma once

#include "core/exact/predicates3d.hpp"
#include "core/mesh/mesh.hpp"
#include "core/mesh/plan_index.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::mesh {

class VerticalBound {
public:
    // Keeps a copy of the input terrain.
    VerticalBound(const Mesh& input, double bound);

    // `fan`: the faces a collapse makes, each with the merged vertex p as its first corner, all
    // turned the same way in the map plane (none degenerate there), covering the region the
    // collapse changes. Is the new surface there within the bound of the input's?
    bool holds(std::span<const exact::Triangle3> fan, exact::PredicateStats& stats) const;

    double bound() const { return bound_; }

private:
    Mesh input_;
    PlanIndex index_;
    std::vector<std::uint8_t> border_;  // per input face, bit k: its edge from corner k has no other face
    double bound_;
};

}  // namespace toposimp::mesh
