// Whether a surface meets itself: the check of a whole mesh that UGSimp's result gets when its
// collapses were made without a contact search (ContactCheck::at_the_end in simplify.hpp).
#pragma once

#include "core/exact/predicates.hpp"
#include "core/mesh/mesh.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>

namespace toposimp::mesh {

struct SelfContact {
    // Pairs of faces f < g that conflict (exact::faces_conflict: they meet anywhere but at corners
    // they share by location and along the segment between two such), plus each degenerate face
    // (collinear or coincident corners), which counts as paired with itself.
    std::uint64_t pairs = 0;
    // The least such pair (by f, then g), if any.
    std::optional<std::array<std::uint32_t, 2>> first;
};

// Every pair of faces whose boxes meet is tested, exactly. The faces are bucketed in a uniform
// grid (cells about twice the mean edge, larger while faces would fill too many cells) and each
// pair tested once, in the cell holding the low corner of the overlap of their boxes. The answer
// does not depend on the grid or on `threads` (0: OpenMP's default).
// `changed` (one flag per face, or empty: all): only pairs with a changed face count, and only a
// changed face's degeneracy; the others are listed only in cells a changed face meets.
SelfContact find_self_contact(const Mesh& mesh, int threads, exact::PredicateStats& stats,
                              std::span<const std::uint8_t> changed = {});

}  // namespace toposimp::mesh
