#include "core/mesh/mesh.hpp"

#include <algorithm>
#include <memory>

namespace toposimp::mesh {
namespace {

bool repeats_corner(const Face& f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }

}  // namespace

std::size_t count_repeated_corner_faces(const Mesh& mesh) {
    return static_cast<std::size_t>(std::count_if(mesh.faces.begin(), mesh.faces.end(), repeats_corner));
}

std::size_t drop_unused(Mesh& mesh, std::vector<std::uint32_t>* kept) {
    const std::size_t before = mesh.faces.size();
    Attributes& face_rows = mesh.face_attributes;
    std::size_t faces = 0;
    for (std::size_t f = 0; f < before; ++f) {
        if (repeats_corner(mesh.faces[f])) continue;
        if (faces != f) {
            mesh.faces[faces] = mesh.faces[f];
            std::copy_n(face_rows.row(f), face_rows.width, face_rows.row(faces));
        }
        ++faces;
    }
    mesh.faces.resize(faces);
    face_rows.values.resize(faces * face_rows.width);
    std::vector<std::uint32_t> index(mesh.points.size(), 0);
    for (const Face& f : mesh.faces) {
        for (std::uint32_t v : f) index[v] = 1;
    }
    // The old numbers are listed only when some vertex goes.
    const bool list = kept != nullptr && std::find(index.begin(), index.end(), 0u) != index.end();
    if (kept != nullptr) kept->clear();
    Attributes& vertex_rows = mesh.vertex_attributes;
    std::uint32_t next = 0;
    for (std::uint32_t v = 0; v < mesh.points.size(); ++v) {
        if (index[v] != 0) {
            if (next != v) {
                mesh.points[next] = mesh.points[v];
                std::copy_n(vertex_rows.row(v), vertex_rows.width, vertex_rows.row(next));
            }
            index[v] = next++;
            if (list) kept->push_back(v);
        }
    }
    if (next == mesh.points.size()) return before - faces;  // (every vertex used: numbers unchanged)
    mesh.points.resize(next);
    vertex_rows.values.resize(std::size_t{next} * vertex_rows.width);
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
    return before - faces;
}

}  // namespace toposimp::mesh
