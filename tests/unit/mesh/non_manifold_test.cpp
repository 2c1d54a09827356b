// The simplifier finds a non-manifold edge in its own pass over each vertex's faces: it must name
// the edge a plain count of every edge's faces names on the input as given (vertex and face
// numbers of the input, though faces repeating a corner and unused vertices are dropped first),
// and leave the mesh unsimplified.
#include "core/mesh/mesh.hpp"
#include "core/mesh/simplify.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <optional>
#include <random>
#include <utility>
#include <vector>

namespace toposimp::mesh {
namespace {

// The least edge (a < b) with more than two faces, and its first four faces: each edge's faces
// listed in a map.
std::optional<NonManifoldEdge> find_non_manifold_edge(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> faces_of;
    for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
        const Face& c = m.faces[f];
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
        for (int k = 0; k < 3; ++k) faces_of[std::minmax(c[k], c[(k + 1) % 3])].push_back(f);
    }
    for (const auto& [edge, faces] : faces_of) {
        if (faces.size() > 2) {
            return NonManifoldEdge{edge.first, edge.second, std::vector<std::uint32_t>(faces.begin(), faces.begin() + std::min<std::size_t>(faces.size(), 4))};
        }
    }
    return std::nullopt;
}

// Random triangles over a few vertices: non-manifold edges likely, some faces repeating a
// corner, some vertices unused.
Mesh soup(std::mt19937& random) {
    Mesh m;
    const int vertices = std::uniform_int_distribution<int>(4, 14)(random);
    std::uniform_real_distribution<double> coordinate(-1, 1);
    for (int v = 0; v < vertices; ++v) m.points.push_back({coordinate(random), coordinate(random), coordinate(random)});
    const int faces = std::uniform_int_distribution<int>(1, 3 * vertices)(random);
    std::uniform_int_distribution<std::uint32_t> corner(0, static_cast<std::uint32_t>(vertices - 1));
    for (int f = 0; f < faces; ++f) {
        Face face{corner(random), corner(random), corner(random)};
        if (face[0] == face[1] && random() % 4 != 0) continue;  // a few repeat a corner
        m.faces.push_back(face);
    }
    return m;
}

TEST(NonManifoldInput, TheSimplifierNamesTheEdgeTheInputCheckNames) {
    std::mt19937 random(12);
    int named = 0, unused_or_repeated = 0, manifold = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        Mesh m = soup(random);
        const auto expected = find_non_manifold_edge(m);
        if (!expected) {
            Mesh copy = m;
            if (!copy.faces.empty() && count_repeated_corner_faces(copy) < copy.faces.size()) {
                EXPECT_FALSE(simplify(copy, SimplifyOptions{}).non_manifold.has_value()) << trial;
                ++manifold;
            }
            continue;
        }
        ++named;
        Mesh copy = m;
        unused_or_repeated += drop_unused(copy) > 0 || copy.points.size() < m.points.size();
        SimplifyOptions options;
        options.stop.value = 0.5;
        const std::vector<Face> faces = m.faces;
        const SimplifyStats stats = simplify(m, options);
        ASSERT_TRUE(stats.non_manifold.has_value()) << trial;
        EXPECT_EQ(stats.non_manifold->a, expected->a) << trial;
        EXPECT_EQ(stats.non_manifold->b, expected->b) << trial;
        EXPECT_EQ(stats.non_manifold->faces, expected->faces) << trial;
        EXPECT_EQ(stats.collapses, 0u);
        // The faces are the input's but for those repeating a corner.
        std::vector<Face> kept;
        for (const Face& f : faces) {
            if (f[0] != f[1] && f[1] != f[2] && f[2] != f[0]) kept.push_back(f);
        }
        EXPECT_EQ(m.faces.size(), kept.size());
    }
    // The cases the test means to cover came up.
    EXPECT_GT(named, 500);
    EXPECT_GT(unused_or_repeated, 100);
    EXPECT_GT(manifold, 100);
}

}  // namespace
}  // namespace toposimp::mesh
