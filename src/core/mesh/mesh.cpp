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
    std::erase_if(mesh.faces, repeats_corner);
    std::vector<std::uint32_t> index(mesh.points.size(), 0);
    for (const Face& f : mesh.faces) {
        for (std::uint32_t v : f) index[v] = 1;
    }
    // The old numbers are listed only when some vertex goes.
    const bool list = kept != nullptr && std::find(index.begin(), index.end(), 0u) != index.end();
    if (kept != nullptr) kept->clear();
    std::uint32_t next = 0;
    for (std::uint32_t v = 0; v < mesh.points.size(); ++v) {
        if (index[v] != 0) {
            mesh.points[next] = mesh.points[v];
            index[v] = next++;
            if (list) kept->push_back(v);
        }
    }
    mesh.points.resize(next);
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
    return before - mesh.faces.size();
}

}  // namespace toposimp::mesh
