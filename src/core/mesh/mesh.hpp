// An indexed triangle mesh: positions and corner indices, nothing per element on the heap.
#pragma once

#include "core/geometry.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace toposimp::mesh {

using Face = std::array<std::uint32_t, 3>;

// Numbers each vertex or face carries besides its geometry: normals, colours, texture
// coordinates, any per-element property of a file. `width` per element, one row after another;
// the engine does not interpret them (the reader and writer know what each column is).
struct Attributes {
    std::size_t width = 0;
    std::vector<double> values;  // elements × width

    double* row(std::size_t i) { return values.data() + i * width; }
    const double* row(std::size_t i) const { return values.data() + i * width; }
};

struct Mesh {
    std::vector<Point3> points;
    std::vector<Face> faces;
    // Simplification gives a merged vertex the blend of its two ends' rows, weighted by where the
    // merged vertex lies along the edge (simplify.hpp); a face keeps its row.
    Attributes vertex_attributes{};
    Attributes face_attributes{};
};

// An edge shared by more than two faces: the surface is not a manifold there.
struct NonManifoldEdge {
    std::uint32_t a;
    std::uint32_t b;
    std::vector<std::uint32_t> faces;  // the first few faces on it
};

// Faces that repeat a corner index (a, a, b): they have no area and no place in a surface.
std::size_t count_repeated_corner_faces(const Mesh& mesh);

// Drops faces that repeat a corner index and vertices no face uses, with their attribute rows;
// keeps the order of the rest.
// Returns how many faces were dropped. If `kept` is given and vertices were dropped, it receives
// each kept vertex's number before (otherwise it is left empty).
std::size_t drop_unused(Mesh& mesh, std::vector<std::uint32_t>* kept = nullptr);
// The vertex half of drop_unused: vertices no face uses go, with their rows; faces that repeat
// a corner stay.
void drop_unused_vertices(Mesh& mesh, std::vector<std::uint32_t>* kept = nullptr);

// How many vertices share their location (all three coordinates equal) with another vertex.
std::size_t count_coincident(const Mesh& mesh);

// Welds vertices at the same location: in each group of such vertices the first (lowest
// number) takes the others' place in every face, so that an unwelded mesh (a triangle soup, as
// STL files give) becomes one surface. The others stay, unused (drop_unused_vertices drops them).
struct Welded {
    std::size_t vertices = 0;  // vertices replaced by another
    // Per vertex attribute column: two vertices of a group hold different values there (a seam,
    // say of texture coordinates), so the welded vertex's value stands for one of them only.
    std::vector<bool> differs;
};
Welded weld_coincident(Mesh& mesh);

// Removes the vertex attribute columns marked in `remove` (one flag per column).
void remove_vertex_columns(Mesh& mesh, const std::vector<bool>& remove);

}  // namespace toposimp::mesh
