// Independent checks of a triangle mesh for the tests: brute force over all face pairs, every
// decision computed with GMP rationals by a different method than the engine's (planes and
// exact intersection points/segments, polygon clipping for coplanar pairs). Slow; small meshes.
#pragma once

#include "core/mesh/mesh.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace toposimp::testing {

struct MeshDefects {
    std::size_t intersecting_pairs = 0;   // faces meeting beyond the corners/edge they share
    std::size_t non_manifold_edges = 0;   // edges with more than two faces
    std::size_t inconsistent_edges = 0;   // two faces using an edge in the same direction
    std::size_t degenerate_faces = 0;     // collinear corners or a repeated corner
    std::size_t duplicate_faces = 0;      // two faces on the same three vertices
    std::size_t non_manifold_vertices = 0;  // faces around a vertex in more than one fan (a pinch)
    std::string first;                    // a description of the first defect found

    std::size_t total() const {
        return intersecting_pairs + non_manifold_edges + inconsistent_edges + degenerate_faces + duplicate_faces +
               non_manifold_vertices;
    }
};

MeshDefects find_defects(const mesh::Mesh& mesh);

// Faces whose orientation in the x–y plane is not `turn` (+1 or −1): folds of a terrain.
std::size_t count_map_plane_folds(const mesh::Mesh& mesh, int turn);

// Is every point of the output terrain within `bound` (exactly) of the input terrain straight
// above or below it, wherever both have a face? Brute force: each output face clipped to each
// input face in the x–y plane, the height difference compared at the pieces' corners. The
// largest difference, rounded, goes to `largest`.
bool within_vertical_gap(const mesh::Mesh& input, const mesh::Mesh& output, double bound, double* largest = nullptr);

// Twice the signed volume enclosed (exact sign: +1, 0, −1) — for closed meshes.
int volume_sign(const mesh::Mesh& mesh);

}  // namespace toposimp::testing
