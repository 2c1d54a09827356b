#include "core/mesh/mesh.hpp"

#include <algorithm>

namespace toposimp::mesh {
namespace {

bool repeats_corner(const Face& f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }

}  // namespace

std::optional<NonManifoldEdge> find_non_manifold_edge(const Mesh& mesh) {
    struct Use {
        std::uint32_t lo, hi, face;
    };
    std::vector<Use> uses;
    uses.reserve(mesh.faces.size() * 3);
    for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
        const Face& face = mesh.faces[f];
        if (repeats_corner(face)) continue;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = face[k], b = face[(k + 1) % 3];
            uses.push_back({std::min(a, b), std::max(a, b), f});
        }
    }
    std::sort(uses.begin(), uses.end(), [](const Use& x, const Use& y) {
        return x.lo != y.lo ? x.lo < y.lo : (x.hi != y.hi ? x.hi < y.hi : x.face < y.face);
    });
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i;
        while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
        if (j - i > 2) {
            NonManifoldEdge edge{uses[i].lo, uses[i].hi, {}};
            for (std::size_t k = i; k < j && k < i + 4; ++k) edge.faces.push_back(uses[k].face);
            return edge;
        }
        i = j;
    }
    return std::nullopt;
}

std::size_t count_repeated_corner_faces(const Mesh& mesh) {
    return static_cast<std::size_t>(std::count_if(mesh.faces.begin(), mesh.faces.end(), repeats_corner));
}

std::size_t drop_unused(Mesh& mesh) {
    const std::size_t before = mesh.faces.size();
    std::erase_if(mesh.faces, repeats_corner);
    std::vector<std::uint32_t> index(mesh.points.size(), 0);
    for (const Face& f : mesh.faces) {
        for (std::uint32_t v : f) index[v] = 1;
    }
    std::uint32_t next = 0;
    for (std::size_t v = 0; v < mesh.points.size(); ++v) {
        if (index[v] != 0) {
            mesh.points[next] = mesh.points[v];
            index[v] = next++;
        }
    }
    mesh.points.resize(next);
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
    return before - mesh.faces.size();
}

}  // namespace toposimp::mesh
