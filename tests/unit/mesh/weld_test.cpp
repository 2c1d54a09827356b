// Welding vertices at the same location: an unwelded sphere (every face with corners of its own,
// as STL files give) welds back into the sphere, each location's first vertex standing for the
// others; a seam in an attribute column is reported; exact equality, no tolerance.
#include "core/mesh/mesh.hpp"
#include "core/mesh/simplify.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace toposimp::mesh {
namespace {

// Each face with three vertices of its own, its corners' copies in face order.
Mesh unwelded(const Mesh& m) {
    Mesh soup;
    for (const Face& f : m.faces) {
        const auto first = static_cast<std::uint32_t>(soup.points.size());
        for (std::uint32_t v : f) soup.points.push_back(m.points[v]);
        soup.faces.push_back({first, first + 1, first + 2});
    }
    return soup;
}

TEST(Weld, AnUnweldedSphereWeldsBackAndSimplifiesLikeTheSphere) {
    const Mesh sphere = toposimp::testing::noisy_sphere(3, 0.05, 5);
    Mesh soup = unwelded(sphere);
    EXPECT_EQ(count_coincident(soup), soup.points.size());
    const Welded welded = weld_coincident(soup);
    EXPECT_EQ(welded.vertices, soup.points.size() - sphere.points.size());
    // Each face's corners now are the first copies of the sphere's corners.
    std::vector<std::uint32_t> first_copy(sphere.points.size(), ~0u);
    for (std::uint32_t f = 0; f < sphere.faces.size(); ++f) {
        for (int k = 0; k < 3; ++k) {
            std::uint32_t& copy = first_copy[sphere.faces[f][k]];
            if (copy == ~0u) copy = 3 * f + static_cast<std::uint32_t>(k);
            EXPECT_EQ(soup.faces[f][k], copy) << f << ' ' << k;
        }
    }
    drop_unused(soup);
    EXPECT_EQ(soup.points.size(), sphere.points.size());
    EXPECT_EQ(count_coincident(soup), 0u);
    Mesh a = sphere, b = soup;
    SimplifyOptions options;
    options.threads = 1;
    EXPECT_EQ(simplify(a, options).faces_out, simplify(b, options).faces_out);
}

TEST(Weld, OnlyExactlyEqualLocationsWeldAndSeamsAreReported) {
    Mesh m;
    const double x = 0.1;
    m.points = {{x, 0, 0}, {std::nextafter(x, 1.0), 0, 0}, {0, 1, 0}, {x, 0, 0}, {-0.0, 1, 0}, {0, 0, 1}};
    m.faces = {{0, 2, 5}, {1, 2, 5}, {3, 4, 5}};
    m.vertex_attributes.width = 2;
    m.vertex_attributes.values = {1, 7, 2, 7, 3, 7, 4, 7, 3, 8, 5, 7};
    EXPECT_EQ(count_coincident(m), 4u);  // 0 and 3; 2 and 4 (−0 = +0)
    const Welded welded = weld_coincident(m);
    EXPECT_EQ(welded.vertices, 2u);
    EXPECT_EQ(m.faces, (std::vector<Face>{{0, 2, 5}, {1, 2, 5}, {0, 2, 5}}));
    // Column 0 differs between 0 and 3 (1, 4), column 1 between 2 and 4 (7, 8).
    EXPECT_EQ(welded.differs, (std::vector<bool>{true, true}));
    remove_vertex_columns(m, {true, false});
    EXPECT_EQ(m.vertex_attributes.width, 1u);
    EXPECT_EQ(m.vertex_attributes.values, (std::vector<double>{7, 7, 7, 7, 8, 7}));
    // A library caller's NaN: ordered all the same (no undefined sort), located nowhere, welded to
    // nothing.
    Mesh odd;
    const double nan = std::nan("");
    odd.points = {{nan, 0, 0}, {0, 0, 0}, {nan, 0, 0}, {0, 0, 0}, {1, nan, 2}};
    odd.faces = {{0, 1, 4}, {2, 3, 4}};
    EXPECT_EQ(count_coincident(odd), 2u);
    EXPECT_EQ(weld_coincident(odd).vertices, 1u);
    EXPECT_EQ(odd.faces, (std::vector<Face>{{0, 1, 4}, {2, 1, 4}}));
}

}  // namespace
}  // namespace toposimp::mesh
