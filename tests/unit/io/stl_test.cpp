// STL in and out: binary when the size says so (whatever the header's first word), text
// otherwise; corners welded into shared vertices; clear errors naming the file and the line or
// triangle. Written as binary only when every coordinate is a float32 (exact), else as text
// with every digit: both read back to the same doubles.
#include "io/common/errors.hpp"
#include "io/mesh/mesh_files.hpp"
#include "support/temp_path.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace toposimp::testing {
namespace {

std::string write_file(const std::string& name, const std::string& bytes) { return write_temp_file("stl-" + name, bytes); }

template <class T>
void put(std::string& out, T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
    out.append(bytes, sizeof(T));
}

// A tetrahedron's four faces, turned outward, as binary STL with `header` (80 bytes).
std::string binary_tetrahedron(const std::string& header, std::uint16_t attribute = 0) {
    const float p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    std::string out = header;
    out.resize(80, '\0');
    put(out, std::uint32_t{4});
    for (const auto& f : faces) {
        for (int k = 0; k < 3; ++k) put(out, 0.0f);  // (a normal, not read)
        for (int v : f) {
            for (float c : p[v]) put(out, c);
        }
        put(out, attribute);
    }
    return out;
}

mesh::Mesh read(const std::string& path, io::MeshReadReport& report, bool triangulate = false) {
    return io::read_mesh(path, io::MeshReadOptions{triangulate}, report);
}

TEST(Stl, BinaryIsToldBySizeAndItsCornersAreWelded) {
    // A header starting with "solid", as many binary writers leave it.
    io::MeshReadReport report;
    const mesh::Mesh m = read(write_file("tet.stl", binary_tetrahedron("solid tetrahedron")), report);
    EXPECT_EQ(report.format, io::MeshFormat::stl);
    EXPECT_EQ(report.encoding, "binary");
    EXPECT_EQ(m.points.size(), 4u);
    EXPECT_EQ(report.welded, 8u);  // 12 corners, 4 locations
    ASSERT_EQ(m.faces.size(), 4u);
    EXPECT_EQ(m.points[m.faces[2][0]].x, 1);  // (1, 0, 0), (0, 1, 0), (0, 0, 1)
    EXPECT_EQ(m.points[m.faces[2][2]].z, 1);
    EXPECT_TRUE(report.dropped.empty());
    io::MeshReadReport coloured;
    read(write_file("tet-coloured.stl", binary_tetrahedron("", 0x7c00)), coloured);
    ASSERT_EQ(coloured.dropped.size(), 1u);
    EXPECT_NE(coloured.dropped[0].find("4 of 4 triangles"), std::string::npos) << coloured.dropped[0];
}

TEST(Stl, TextWithAnyCaseAndLineEndsReadsTheSameDoubles) {
    const std::string text =
        "solid t\r\n  FACET NORMAL 0 0 1\r\n    outer loop\r\n      vertex 0.1 0 0\r\n      vertex 1 0.30000000000000004 0\r\n"
        "      vertex 0 1 0\r\n    endloop\r\n  endfacet\r\n"
        "  facet normal 0 0 1\n outer loop\n vertex 1 0.30000000000000004 0\n vertex 1 1 0\n vertex 0 1 0\n endloop\n endfacet\n"
        "endsolid t\n";
    io::MeshReadReport report;
    const mesh::Mesh m = read(write_file("square.stl", text), report);
    EXPECT_EQ(report.encoding, "ascii");
    EXPECT_EQ(m.points.size(), 4u);
    EXPECT_EQ(m.faces.size(), 2u);
    EXPECT_EQ(m.points[1].y, 0.30000000000000004);
    EXPECT_EQ(m.faces[1][0], m.faces[0][1]);  // the shared corner welded
    // A facet with two corners at one location is kept, repeating a corner: the command warns
    // and drops it with the others of its kind.
    const std::string degenerate = "solid d\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
    io::MeshReadReport degenerate_report;
    const mesh::Mesh d = read(write_file("degenerate.stl", degenerate), degenerate_report);
    EXPECT_EQ(d.points.size(), 2u);
    EXPECT_EQ(d.faces, (std::vector<mesh::Face>{{0, 0, 1}}));
}

TEST(Stl, BadFilesNameTheFileAndThePlace) {
    auto message = [](const std::string& name, const std::string& bytes, bool triangulate = false) {
        try {
            io::MeshReadReport report;
            read(write_file(name, bytes), report, triangulate);
        } catch (const io::InputError& error) {
            return std::string(error.what());
        }
        return std::string("no error");
    };
    const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
    EXPECT_NE(message("short.stl", "solid s\n" + facet + "facet normal 0 0 1\nouter loop\nvertex 0 0 0\n").find("short.stl: truncated"),
              std::string::npos);
    EXPECT_NE(message("nan.stl", "solid s\n" + facet + "facet normal 0 0 1\nouter loop\nvertex 0 nan 0\n").find("nan.stl:11: triangle 1 has a non-finite coordinate"),
              std::string::npos);
    EXPECT_NE(message("word.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 zero 0\n").find("word.stl:4: 'zero' is not a number"),
              std::string::npos);
    EXPECT_NE(message("junk.stl", "solid s\nfacet normal 0 0 1\nbanana\n").find("junk.stl:3: 'banana' is not an STL keyword"),
              std::string::npos);
    std::string cut = binary_tetrahedron("binary");
    cut.resize(cut.size() - 7);
    EXPECT_NE(message("cut.stl", cut).find("not an STL file: not binary (84 bytes and 50 per triangle: its header counts 4 triangles, "
                                           "the file has 277 bytes)"),
              std::string::npos);
    const std::string quad = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\n";
    EXPECT_NE(message("quad.stl", quad).find("quad.stl:8: face 0 has 4 corners"), std::string::npos) << message("quad.stl", quad);
    EXPECT_EQ(message("quad.stl", quad, true), "no error");
    std::string infinite = binary_tetrahedron("");
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(infinite.data() + 84 + 50 * 2 + 12, &inf, 4);
    EXPECT_NE(message("inf.stl", infinite).find("inf.stl: triangle 2 has a non-finite coordinate"), std::string::npos);
}

TEST(Stl, WrittenBinaryOnlyWhenExactAndReadBackTheSame) {
    io::MeshReadReport report;
    const mesh::Mesh floats = read(write_file("tet-in.stl", binary_tetrahedron("")), report);
    const std::string binary = temp_path("stl-out-binary.stl").string();
    EXPECT_TRUE(io::write_mesh(floats, {}, binary, io::MeshFormat::stl, false).empty());
    EXPECT_EQ(std::filesystem::file_size(binary), 84u + 4 * 50);
    // A coordinate that is no float32: text, every digit. Faces carry no values in STL.
    mesh::Mesh doubles = floats;
    doubles.points[3].z = 0.1;
    doubles.face_attributes = {1, std::vector<double>(doubles.faces.size(), 0.5)};
    io::AttributeLayout layout;
    layout.face = {{"quality", io::ValueType::f32}};
    const std::string text = temp_path("stl-out-text.stl").string();
    EXPECT_EQ(io::write_mesh(doubles, layout, text, io::MeshFormat::stl, false), (std::vector<std::string>{"face quality"}));
    // --ascii: text even when binary would be exact.
    const std::string asked = temp_path("stl-out-asked.stl").string();
    io::write_mesh(floats, {}, asked, io::MeshFormat::stl, true);
    for (const auto& [path, written, encoding] : {std::tuple{binary, &floats, "binary"}, std::tuple{text, static_cast<const mesh::Mesh*>(&doubles), "ascii"},
                                                  std::tuple{asked, &floats, "ascii"}}) {
        io::MeshReadReport back_report;
        const mesh::Mesh back = read(path, back_report);
        EXPECT_EQ(back_report.encoding, encoding) << path;
        ASSERT_EQ(back.faces.size(), written->faces.size());
        for (std::size_t f = 0; f < back.faces.size(); ++f) {
            for (int k = 0; k < 3; ++k) {
                EXPECT_TRUE(same_location(back.points[back.faces[f][k]], written->points[written->faces[f][k]])) << path << ' ' << f;
            }
        }
    }
}

// Damaged files (cut short, bytes overwritten, dropped or inserted, in either encoding) are read
// or refused with an InputError: nothing else escapes (and under the sanitizers, no bad access).
TEST(Stl, DamagedFilesAreReadOrRefusedCleanly) {
    std::string text = "solid s\n";
    for (int f = 0; f < 20; ++f) {
        text += "facet normal 0 0 1\nouter loop\nvertex " + std::to_string(f) + " 0 0\nvertex " + std::to_string(f + 1) +
                " 0 0\nvertex " + std::to_string(f) + " 1 0\nendloop\nendfacet\n";
    }
    text += "endsolid s\n";
    const std::string sources[] = {text, binary_tetrahedron("solid")};
    std::mt19937 random(17);
    int refused = 0, read_ok = 0;
    for (int trial = 0; trial < 600; ++trial) {
        std::string bytes = sources[trial % 2];
        auto at = [&] { return std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(random); };
        auto byte = [&] { return static_cast<char>(std::uniform_int_distribution<int>(0, 255)(random)); };
        switch (trial / 2 % 4) {
            case 0: bytes.resize(at()); break;
            case 1:
                for (int k = 0; k < 8; ++k) bytes[at()] = byte();
                break;
            case 2: bytes.erase(at(), 1 + at() % 16); break;
            default: bytes.insert(at(), 1 + at() % 8, byte()); break;
        }
        try {
            io::MeshReadReport report;
            const mesh::Mesh m = read(write_file("damaged.stl", bytes), report);
            for (const mesh::Face& f : m.faces) {
                for (std::uint32_t v : f) ASSERT_LT(v, m.points.size()) << trial;
            }
            ++read_ok;
        } catch (const io::InputError&) {
            ++refused;
        }
    }
    EXPECT_GT(refused, 100);
    EXPECT_GT(read_ok, 50);
}

}  // namespace
}  // namespace toposimp::testing
