// Attributes through simplification: a merged vertex blends its two ends' rows at the point of
// their edge nearest the placement, a face keeps its row, and the rows follow every renumbering.
#include "core/mesh/simplify.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace toposimp::testing {
namespace {

double linear(const Point3& p) { return 2 * p.x - 3 * p.y + 5; }

// A flat n×n grid (z = 0) whose vertices carry (linear(position), 7, their id) and whose faces
// carry their id.
mesh::Mesh flat_grid_with_rows(int n) {
    mesh::Mesh m = noisy_heightfield(n, 0, 1);
    for (Point3& p : m.points) p.z = 0;
    m.vertex_attributes.width = 3;
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        m.vertex_attributes.values.insert(m.vertex_attributes.values.end(), {linear(m.points[v]), 7.0, static_cast<double>(v)});
    }
    m.face_attributes.width = 1;
    for (std::size_t f = 0; f < m.faces.size(); ++f) m.face_attributes.values.push_back(static_cast<double>(f));
    return m;
}

TEST(MeshAttributeBlend, OnAFlatGridEveryVertexKeepsItsLinearValue) {
    // Flat: every quadric is singular, so every merged vertex lies on its edge (an end or the
    // midpoint) and the blend of a linear function is its value there.
    mesh::Mesh m = flat_grid_with_rows(24);
    const std::size_t faces_in = m.faces.size();
    mesh::SimplifyOptions options;
    options.stop.value = 0.2;
    const mesh::SimplifyStats stats = mesh::simplify(m, options);
    ASSERT_GT(stats.collapses, 0u);
    ASSERT_EQ(m.vertex_attributes.values.size(), 3 * m.points.size());
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        const double* row = m.vertex_attributes.row(v);
        EXPECT_NEAR(row[0], linear(m.points[v]), 1e-12 * 100) << "vertex " << v;
        EXPECT_EQ(row[1], 7.0);
    }
    // Faces: each keeps the row it had (distinct input ids, as many as the faces).
    ASSERT_EQ(m.face_attributes.values.size(), m.faces.size());
    const std::set<double> ids(m.face_attributes.values.begin(), m.face_attributes.values.end());
    EXPECT_EQ(ids.size(), m.faces.size());
    EXPECT_LT(*ids.rbegin(), static_cast<double>(faces_in));
}

TEST(MeshAttributeBlend, ALockedBorderVertexKeepsItsOwnRow) {
    mesh::Mesh m = noisy_heightfield(20, 0.3, 5);
    const std::vector<Point3> input = m.points;
    m.vertex_attributes.width = 1;
    for (std::size_t v = 0; v < m.points.size(); ++v) m.vertex_attributes.values.push_back(static_cast<double>(v) + 0.1);
    std::map<std::array<double, 3>, std::size_t> id_at;
    for (std::size_t v = 0; v < input.size(); ++v) id_at[{input[v].x, input[v].y, input[v].z}] = v;
    mesh::SimplifyOptions options;
    options.stop.value = 0.1;
    options.terrain = true;
    options.lock_boundary = true;
    mesh::simplify(m, options);
    const double lo = input.front().x, hi = input.back().x;  // the grid's extent in x and y
    std::size_t border = 0;
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        const Point3& p = m.points[v];
        if (p.x != lo && p.x != hi && p.y != lo && p.y != hi) continue;
        ++border;
        const auto it = id_at.find({p.x, p.y, p.z});
        ASSERT_NE(it, id_at.end()) << "a border vertex moved";
        EXPECT_EQ(m.vertex_attributes.row(v)[0], static_cast<double>(it->second) + 0.1);
    }
    EXPECT_EQ(border, 4u * 20);
}

TEST(MeshAttributeBlend, RowsAreTheSameForAnyThreadCount) {
    std::vector<double> first_vertices, first_faces;
    for (const int threads : {1, 2}) {
        mesh::Mesh m = noisy_sphere(5, 0.05, 9);
        m.vertex_attributes.width = 2;
        for (const Point3& p : m.points) m.vertex_attributes.values.insert(m.vertex_attributes.values.end(), {p.x * p.y, p.z});
        m.face_attributes = {1, std::vector<double>(m.faces.size())};
        for (std::size_t f = 0; f < m.faces.size(); ++f) m.face_attributes.values[f] = static_cast<double>(f);
        mesh::SimplifyOptions options;
        options.stop.value = 0.1;
        options.threads = threads;
        options.parallel_threshold = 0;
        mesh::simplify(m, options);
        if (threads == 1) {
            first_vertices = m.vertex_attributes.values;
            first_faces = m.face_attributes.values;
        } else {
            EXPECT_EQ(m.vertex_attributes.values, first_vertices);
            EXPECT_EQ(m.face_attributes.values, first_faces);
        }
    }
}

// The simplifier numbers vertices and faces in a space-filling order while it works; what it
// returns is in the input's order, whatever that was.
mesh::Mesh shuffled_sphere_with_rows(unsigned seed) {
    mesh::Mesh m = noisy_sphere(6, 0.05, seed);
    std::mt19937 random(seed);
    std::vector<std::uint32_t> number(m.points.size());
    std::iota(number.begin(), number.end(), 0u);
    std::shuffle(number.begin(), number.end(), random);
    std::vector<Point3> points(m.points.size());
    for (std::size_t v = 0; v < number.size(); ++v) points[number[v]] = m.points[v];
    m.points = points;
    for (mesh::Face& f : m.faces) {
        for (std::uint32_t& v : f) v = number[v];
    }
    std::shuffle(m.faces.begin(), m.faces.end(), random);
    m.vertex_attributes.width = 2;
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        m.vertex_attributes.values.insert(m.vertex_attributes.values.end(), {static_cast<double>(v), m.points[v].z});
    }
    m.face_attributes.width = 1;
    for (std::size_t f = 0; f < m.faces.size(); ++f) m.face_attributes.values.push_back(static_cast<double>(f));
    return m;
}

TEST(MeshAttributeBlend, NothingToCollapseGivesTheInputBackInItsOrder) {
    const mesh::Mesh input = shuffled_sphere_with_rows(3);
    mesh::Mesh m = input;
    mesh::SimplifyOptions options;
    options.stop.value = 1.0;  // keep every face
    const mesh::SimplifyStats stats = mesh::simplify(m, options);
    EXPECT_EQ(stats.collapses, 0u);
    EXPECT_EQ(m.faces, input.faces);
    ASSERT_EQ(m.points.size(), input.points.size());
    for (std::size_t v = 0; v < m.points.size(); ++v) EXPECT_TRUE(same_location(m.points[v], input.points[v])) << v;
    EXPECT_EQ(m.vertex_attributes.values, input.vertex_attributes.values);
    EXPECT_EQ(m.face_attributes.values, input.face_attributes.values);
}

TEST(MeshAttributeBlend, KeptFacesComeInTheirInputOrder) {
    mesh::Mesh m = shuffled_sphere_with_rows(4);
    const mesh::Mesh input = m;
    mesh::SimplifyOptions options;
    options.stop.value = 0.2;
    ASSERT_GT(mesh::simplify(m, options).collapses, 0u);
    // Each face keeps its row (its input number): increasing, so in input order.
    ASSERT_EQ(m.face_attributes.values.size(), m.faces.size());
    EXPECT_TRUE(std::is_sorted(m.face_attributes.values.begin(), m.face_attributes.values.end()));
    EXPECT_EQ(std::adjacent_find(m.face_attributes.values.begin(), m.face_attributes.values.end()), m.face_attributes.values.end());
    // A vertex at an input vertex's location (one that never moved, or a merge placed at one
    // end) has that vertex's row.
    std::map<std::array<double, 3>, std::size_t> id_at;
    for (std::size_t v = 0; v < input.points.size(); ++v) id_at[{input.points[v].x, input.points[v].y, input.points[v].z}] = v;
    std::size_t unmoved = 0;
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        const auto it = id_at.find({m.points[v].x, m.points[v].y, m.points[v].z});
        if (it == id_at.end()) continue;
        ++unmoved;
        EXPECT_EQ(m.vertex_attributes.row(v)[0], static_cast<double>(it->second)) << "vertex " << v;
    }
    EXPECT_GT(unmoved, 10u);
}

TEST(MeshAttributeBlend, DroppedFacesAndVerticesTakeTheirRows) {
    mesh::Mesh m;
    m.points = {{9, 9, 9}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.faces = {{1, 1, 2}, {1, 2, 3}};
    m.vertex_attributes = {1, {90, 0, 10, 30}};
    m.face_attributes = {2, {-1, -2, 5, 6}};
    EXPECT_EQ(mesh::drop_unused(m), 1u);
    EXPECT_EQ(m.vertex_attributes.values, (std::vector<double>{0, 10, 30}));
    EXPECT_EQ(m.face_attributes.values, (std::vector<double>{5, 6}));
    EXPECT_EQ(m.faces, (std::vector<mesh::Face>{{0, 1, 2}}));
}

// A library caller's mesh whose tables do not match it is refused, untouched, with a message
// naming the table; so is a corner index beyond the vertices.
TEST(MeshAttributeBlend, MismatchedTablesAndIndicesAreRefused) {
    const mesh::Mesh good = flat_grid_with_rows(6);
    mesh::SimplifyOptions options;
    options.stop.target = mesh::Target::keep_fraction;
    options.stop.value = 0.5;
    auto refusal = [&](mesh::Mesh m) {
        const mesh::Mesh before = m;
        try {
            mesh::simplify(m, options);
        } catch (const std::invalid_argument& e) {
            EXPECT_EQ(m.points.size(), before.points.size());
            EXPECT_EQ(m.faces, before.faces);
            EXPECT_EQ(m.vertex_attributes.values, before.vertex_attributes.values);
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    mesh::Mesh short_rows = good;
    short_rows.vertex_attributes.values.pop_back();
    EXPECT_NE(refusal(short_rows).find("vertex attributes"), std::string::npos) << refusal(short_rows);
    mesh::Mesh extra_face_row = good;
    extra_face_row.face_attributes.values.push_back(1);
    EXPECT_NE(refusal(extra_face_row).find("face attributes"), std::string::npos) << refusal(extra_face_row);
    mesh::Mesh bad_corner = good;
    bad_corner.faces[3][1] = static_cast<std::uint32_t>(good.points.size());
    EXPECT_NE(refusal(bad_corner).find("face 3 has corner"), std::string::npos) << refusal(bad_corner);
    EXPECT_EQ(refusal(good), "accepted");
}

}  // namespace
}  // namespace toposimp::testing
