#include "core/mesh/mesh.hpp"

#include <algorithm>
#include <memory>

namespace toposimp::mesh {
namespace {

bool repeats_corner(const Face& f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }

}  // namespace

std::optional<NonManifoldEdge> find_non_manifold_edge(const Mesh& mesh) {
    // Edge uses bucketed by their smaller vertex (a counting sort: linear, where sorting all
    // 3F uses took a tenth of a 2 M-triangle run), each small bucket then sorted by (larger
    // vertex, face), in parallel: the first edge with more than two uses, in vertex order.
    struct Use {
        std::uint32_t hi, face;
        bool operator<(const Use& other) const { return hi != other.hi ? hi < other.hi : face < other.face; }
    };
    const auto n = static_cast<std::int64_t>(mesh.points.size());
    std::vector<std::uint32_t> start(mesh.points.size() + 1, 0);
    for (const Face& face : mesh.faces) {
        if (repeats_corner(face)) continue;
        for (int k = 0; k < 3; ++k) ++start[std::min(face[k], face[(k + 1) % 3]) + 1];
    }
    for (std::size_t v = 0; v < mesh.points.size(); ++v) start[v + 1] += start[v];
    const auto uses = std::make_unique_for_overwrite<Use[]>(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
        const Face& face = mesh.faces[f];
        if (repeats_corner(face)) continue;
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = face[k], b = face[(k + 1) % 3];
            uses[fill[std::min(a, b)]++] = {std::max(a, b), f};
        }
    }
    // The bucket's first edge with more than two uses, if any (the bucket sorted).
    auto first_bad = [&](std::uint32_t lo) -> std::optional<NonManifoldEdge> {
        Use* const first = uses.get() + start[lo];
        Use* const last = uses.get() + start[lo + 1];
        std::sort(first, last);
        for (Use* i = first; i != last;) {
            Use* j = i;
            while (j != last && j->hi == i->hi) ++j;
            if (j - i > 2) {
                NonManifoldEdge edge{lo, i->hi, {}};
                for (Use* k = i; k != j && k != i + 4; ++k) edge.faces.push_back(k->face);
                return edge;
            }
            i = j;
        }
        return std::nullopt;
    };
    std::int64_t bad = n;
#pragma omp parallel for schedule(static) reduction(min : bad)
    for (std::int64_t lo = 0; lo < n; ++lo) {
        if (lo < bad && first_bad(static_cast<std::uint32_t>(lo))) bad = lo;
    }
    if (bad == n) return std::nullopt;
    return first_bad(static_cast<std::uint32_t>(bad));
}

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
    if (kept != nullptr) kept->clear();
    const auto used = static_cast<std::size_t>(std::count(index.begin(), index.end(), 1u));
    std::uint32_t next = 0;
    for (std::uint32_t v = 0; v < mesh.points.size(); ++v) {
        if (index[v] != 0) {
            mesh.points[next] = mesh.points[v];
            index[v] = next++;
            if (kept != nullptr && used < mesh.points.size()) kept->push_back(v);
        }
    }
    mesh.points.resize(next);
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
    return before - mesh.faces.size();
}

}  // namespace toposimp::mesh
