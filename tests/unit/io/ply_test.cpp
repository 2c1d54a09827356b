// The binary PLY reader: its fast paths (records read in a tight loop while they are regular)
// must give what the general reader gives, meshes and errors alike.
#include "io/common/errors.hpp"
#include "io/mesh/mesh_files.hpp"
#include "support/temp_path.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace toposimp::testing {
namespace {

// A binary PLY body written value by value, in either byte order.
class Body {
public:
    explicit Body(bool big_endian) : big_(big_endian) {}
    template <class T>
    Body& put(T value) {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        if (big_ != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + sizeof(T));
        text_.append(bytes, sizeof(T));
        return *this;
    }
    const std::string& text() const { return text_; }

private:
    bool big_;
    std::string text_;
};

std::string write_file(const std::string& name, const std::string& text) { return write_temp_file("ply-" + name, text); }

mesh::Mesh read(const std::string& path, bool triangulate = false) {
    io::MeshReadReport report;
    return io::read_mesh(path, io::MeshReadOptions{triangulate}, report);
}

// The error read_mesh throws, or "" if none.
std::string error_of(const std::string& path, bool triangulate = false) {
    try {
        read(path, triangulate);
    } catch (const io::InputError& e) {
        return e.what();
    }
    return "";
}

const double kCoordinates[4][3] = {{0, 0, 0}, {1.5, 0, -2}, {0, 1e-300, 3}, {-7, 8, 1e300}};

// A tetrahedron's four faces; `index` writes a face's corner list as the test wants.
template <class Index>
std::string tetrahedron(bool big, const char* vertex_header, const char* face_header, Index index) {
    std::string header = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                         " 1.0\nelement vertex 4\n" + vertex_header + "element face 4\n" + face_header + "end_header\n";
    Body body(big);
    for (const auto& p : kCoordinates) {
        body.put(static_cast<float>(p[0])).put(p[1]).put(std::uint8_t{7}).put(p[2]);  // x (float), y, an extra, z
    }
    const std::uint32_t faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    for (std::size_t f = 0; f < 4; ++f) index(body, f, faces[f]);
    return header + body.text();
}

const char kVertexHeader[] = "property float x\nproperty double y\nproperty uchar quality\nproperty double z\n";

TEST(BinaryPly, BothByteOrdersAndEveryIndexTypeReadExactly) {
    for (const bool big : {false, true}) {
        for (const char* type : {"uchar", "short", "ushort", "int", "uint"}) {
            const std::string face_header = std::string("property list uchar ") + type + " vertex_indices\n";
            const std::string text = tetrahedron(big, kVertexHeader, face_header.c_str(), [&](Body& body, std::size_t, const std::uint32_t* c) {
                body.put(std::uint8_t{3});
                for (int k = 0; k < 3; ++k) {
                    if (std::string(type) == "uchar") body.put(static_cast<std::uint8_t>(c[k]));
                    if (std::string(type) == "short") body.put(static_cast<std::int16_t>(c[k]));
                    if (std::string(type) == "ushort") body.put(static_cast<std::uint16_t>(c[k]));
                    if (std::string(type) == "int") body.put(static_cast<std::int32_t>(c[k]));
                    if (std::string(type) == "uint") body.put(c[k]);
                }
            });
            const mesh::Mesh m = read(write_file("tetra.ply", text));
            ASSERT_EQ(m.points.size(), 4u) << type;
            for (std::size_t v = 0; v < 4; ++v) {
                EXPECT_EQ(m.points[v].x, static_cast<double>(static_cast<float>(kCoordinates[v][0])));
                EXPECT_EQ(m.points[v].y, kCoordinates[v][1]);
                EXPECT_EQ(m.points[v].z, kCoordinates[v][2]);
            }
            ASSERT_EQ(m.faces.size(), 4u) << type;
            EXPECT_EQ(m.faces[3], (mesh::Face{0, 3, 2})) << type << (big ? " big" : " little");
        }
    }
}

const char kIntFaces[] = "property list uchar int vertex_indices\n";

// Face 2 written by `odd`, the others as triangles of int indices.
template <class Odd>
std::string with_odd_face(Odd odd) {
    return tetrahedron(false, kVertexHeader, kIntFaces, [&](Body& body, std::size_t f, const std::uint32_t* c) {
        if (f == 2) return odd(body, c);
        body.put(std::uint8_t{3});
        for (int k = 0; k < 3; ++k) body.put(static_cast<std::int32_t>(c[k]));
    });
}

TEST(BinaryPly, APolygonAfterTrianglesIsSplitOrRefusedByNumber) {
    const std::string path = write_file("quad.ply", with_odd_face([](Body& body, const std::uint32_t* c) {
        body.put(std::uint8_t{4}).put(std::int32_t(c[0])).put(std::int32_t(c[1])).put(std::int32_t(c[2])).put(std::int32_t{0});
    }));
    EXPECT_NE(error_of(path).find("face 2 has 4 corners"), std::string::npos) << error_of(path);
    const mesh::Mesh m = read(path, true);
    ASSERT_EQ(m.faces.size(), 5u);  // faces 0, 1, the quad's two halves, face 3
    EXPECT_EQ(m.faces[2], (mesh::Face{1, 2, 3}));
    EXPECT_EQ(m.faces[3], (mesh::Face{1, 3, 0}));
    EXPECT_EQ(m.faces[4], (mesh::Face{0, 3, 2}));
}

TEST(BinaryPly, AnIndexOutOfRangeIsNamedWithItsFace) {
    for (const std::int32_t bad : {4, -1}) {
        const std::string path = write_file("index.ply", with_odd_face([bad](Body& body, const std::uint32_t*) {
            body.put(std::uint8_t{3}).put(std::int32_t{0}).put(bad).put(std::int32_t{1});
        }));
        EXPECT_NE(error_of(path).find("face 2 refers to vertex " + std::to_string(bad) + ", but there are 4 vertices"),
                  std::string::npos)
            << error_of(path);
    }
}

TEST(BinaryPly, ANonFiniteCoordinateIsNamedWithItsVertex) {
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
        std::string text = tetrahedron(false, kVertexHeader, kIntFaces, [](Body& body, std::size_t, const std::uint32_t* c) {
            body.put(std::uint8_t{3});
            for (int k = 0; k < 3; ++k) body.put(static_cast<std::int32_t>(c[k]));
        });
        // Vertex 2's y: after the header, two 21-byte records and vertex 2's x (a float).
        Body y(false);
        y.put(bad);
        text.replace(text.find("end_header\n") + 11 + 2 * 21 + 4, 8, y.text());
        const std::string path = write_file("nan.ply", text);
        EXPECT_NE(error_of(path).find("vertex 2 has a non-finite coordinate"), std::string::npos) << error_of(path);
    }
}

TEST(BinaryPly, TruncatedInsideAnyRecordIsAnError) {
    const std::string text = tetrahedron(false, kVertexHeader, kIntFaces, [](Body& body, std::size_t, const std::uint32_t* c) {
        body.put(std::uint8_t{3});
        for (int k = 0; k < 3; ++k) body.put(static_cast<std::int32_t>(c[k]));
    });
    const std::size_t body = text.find("end_header\n") + 11;
    ASSERT_EQ(text.size(), body + 4 * 21 + 4 * 13);
    ASSERT_EQ(error_of(write_file("whole.ply", text)), "");
    for (const std::size_t cut : {body + 30, body + 4 * 21, body + 4 * 21 + 13 + 5, text.size() - 1}) {
        const std::string path = write_file("cut.ply", text.substr(0, cut));
        const std::string error = error_of(path);
        EXPECT_NE(error.find("truncated binary PLY: the file ends inside " + std::string(cut < body + 4 * 21 ? "vertex" : "face")),
                  std::string::npos)
            << cut << ": " << error;
    }
}

}  // namespace
}  // namespace toposimp::testing
