// Vertex and face attributes through the mesh readers and writers: what each format keeps, the
// values exactly where the type holds them, and what is dropped or not written, with the reason.
#include "io/mesh/mesh_files.hpp"
#include "support/temp_path.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace toposimp::testing {
namespace {

std::string write_file(const std::string& name, const std::string& text) { return write_temp_file("attributes-" + name, text); }

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

struct Read {
    mesh::Mesh mesh;
    io::MeshReadReport report;
};

Read read(const std::string& path, bool triangulate = false) {
    Read r;
    r.mesh = io::read_mesh(path, io::MeshReadOptions{triangulate}, r.report);
    return r;
}

std::vector<std::string> names(const std::vector<io::AttributeColumn>& columns) {
    std::vector<std::string> out;
    for (const auto& c : columns) out.push_back(c.name);
    return out;
}

bool mentions(const std::vector<std::string>& lines, const std::string& part) {
    return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(part) != std::string::npos; });
}

// Two triangles; per vertex a float normal, a uchar colour, a double "quality" and a short
// "label"; per face a uchar red and a uint "material".
const char* kPlyHeader =
    "element vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
    "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty double quality\n"
    "property short label\nelement face 2\nproperty list uchar int vertex_indices\nproperty uchar red\n"
    "property uint material\nend_header\n";
const char* kPlyBody =
    "0 0 0 0 0 1 255 0 0 0.1 -7\n1 0 0 0 0 1 0 255 0 0.2 300\n1 1 0 0 0 1 0 0 255 1e-300 -32768\n0 1 0 0 0 1 1 2 3 4.5 32767\n"
    "3 0 1 2 10 4000000000\n3 0 2 3 20 1\n";

void expect_sample_values(const Read& r) {
    ASSERT_EQ(names(r.report.layout.vertex),
              (std::vector<std::string>{"nx", "ny", "nz", "red", "green", "blue", "quality", "label"}));
    ASSERT_EQ(names(r.report.layout.face), (std::vector<std::string>{"red", "material"}));
    EXPECT_EQ(r.report.layout.vertex[3].type, io::ValueType::u8);
    EXPECT_EQ(r.report.layout.vertex[6].type, io::ValueType::f64);
    EXPECT_EQ(r.report.layout.vertex[7].type, io::ValueType::i16);
    EXPECT_EQ(r.report.layout.face[1].type, io::ValueType::u32);
    ASSERT_EQ(r.mesh.vertex_attributes.width, 8u);
    ASSERT_EQ(r.mesh.vertex_attributes.values.size(), 32u);
    EXPECT_EQ(std::vector<double>(r.mesh.vertex_attributes.row(2), r.mesh.vertex_attributes.row(3)),
              (std::vector<double>{0, 0, 1, 0, 0, 255, 1e-300, -32768}));
    EXPECT_EQ(r.mesh.vertex_attributes.row(3)[7], 32767);
    EXPECT_EQ(r.mesh.face_attributes.values, (std::vector<double>{10, 4000000000.0, 20, 1}));
}

TEST(MeshAttributes, PlyPropertiesOfEveryTypeSurviveEveryEncoding) {
    const Read ascii = read(write_file("a.ply", std::string("ply\nformat ascii 1.0\n") + kPlyHeader + kPlyBody));
    expect_sample_values(ascii);
    // Written back in binary and in ASCII, read again: the same columns, types and values.
    for (const bool as_text : {false, true}) {
        const std::string out = temp_path(as_text ? "attributes-out.ply" : "attributes-out-binary.ply").string();
        EXPECT_TRUE(io::write_mesh(ascii.mesh, ascii.report.layout, out, io::MeshFormat::ply, as_text).empty());
        const Read back = read(out);
        expect_sample_values(back);
        EXPECT_EQ(back.report.layout.vertex, ascii.report.layout.vertex);
        EXPECT_EQ(back.report.layout.face, ascii.report.layout.face);
    }
}

TEST(MeshAttributes, BigEndianBinaryPlyReadsTheSameColumns) {
    // The fast path of the vertex records, with a column before and after the coordinates.
    std::string body;
    auto put = [&body](auto value) {
        char bytes[sizeof(value)];
        std::memcpy(bytes, &value, sizeof(value));
        if constexpr (std::endian::native == std::endian::little) std::reverse(bytes, bytes + sizeof(value));
        body.append(bytes, sizeof(value));
    };
    for (int v = 0; v < 3; ++v) {
        put(static_cast<std::uint16_t>(1000 + v));
        put(static_cast<float>(v == 1));
        put(static_cast<float>(v == 2));
        put(0.0f);
        put(0.25 * v);
    }
    put(static_cast<std::uint8_t>(3));
    for (int k = 0; k < 3; ++k) put(static_cast<std::int32_t>(k));
    const Read r = read(write_file("be.ply",
                                   "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty ushort id\nproperty float x\n"
                                   "property float y\nproperty float z\nproperty double weight\nelement face 1\n"
                                   "property list uchar int vertex_indices\nend_header\n" + body));
    EXPECT_EQ(names(r.report.layout.vertex), (std::vector<std::string>{"id", "weight"}));
    EXPECT_EQ(r.mesh.vertex_attributes.values, (std::vector<double>{1000, 0, 1001, 0.25, 1002, 0.5}));
    EXPECT_EQ(r.mesh.points[2].y, 1);
}

TEST(MeshAttributes, PlyListPropertiesAreDroppedWithTheirName) {
    const Read r = read(write_file("lists.ply",
                                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                   "property list uchar int neighbours\nproperty float quality\nelement face 1\n"
                                   "property list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n"
                                   "0 0 0 2 1 2 0.5\n1 0 0 0 1.5\n0 1 0 1 7 2.5\n3 0 1 2 6 0 0 1 0 0 1\n"));
    EXPECT_EQ(names(r.report.layout.vertex), (std::vector<std::string>{"quality"}));
    EXPECT_EQ(r.mesh.vertex_attributes.values, (std::vector<double>{0.5, 1.5, 2.5}));
    EXPECT_TRUE(mentions(r.report.dropped, "vertex property 'neighbours' (a list)"));
    EXPECT_TRUE(mentions(r.report.dropped, "face property 'texcoord' (a list)"));
}

TEST(MeshAttributes, ObjColoursTextureAndNormalsOnePerVertexAreKept) {
    const Read r = read(write_file("kept.obj",
                                   "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\n"
                                   "vt 0 0\nvt 1 0\nvt 0 1\nvt 0 1\nvn 0 0 1\n"
                                   "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/4/1 2/2/1\n"));  // (vt 3 and 4 are equal)
    EXPECT_TRUE(r.report.dropped.empty());
    ASSERT_EQ(names(r.report.layout.vertex), (std::vector<std::string>{"red", "green", "blue", "u", "v", "nx", "ny", "nz"}));
    EXPECT_EQ(std::vector<double>(r.mesh.vertex_attributes.row(2), r.mesh.vertex_attributes.row(3)),
              (std::vector<double>{0, 0, 0.5, 0, 1, 0, 0, 1}));
}

TEST(MeshAttributes, ObjSeamsAndPartialColoursAreDroppedWithTheReason) {
    const Read r = read(write_file("seam.obj",
                                   "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nvn 0 0 1\n"
                                   "f 1/1/1 2/2/1 3/3/1\nf 2/2/1 4/1/1 3/4/1\n"));
    EXPECT_TRUE(mentions(r.report.dropped, "vertex 3 has different ones in different faces (a seam)"));
    EXPECT_TRUE(mentions(r.report.dropped, "vertex colours: only 1 of 4 vertices have one"));
    EXPECT_EQ(names(r.report.layout.vertex), (std::vector<std::string>{"nx", "ny", "nz"}));  // one normal each
    const Read partial = read(write_file("partial.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n"));
    EXPECT_TRUE(mentions(partial.report.dropped, "texture coordinates: some face corners have none"));
    EXPECT_EQ(partial.mesh.vertex_attributes.width, 0u);
}

// v x y z r g b a: the alpha is kept when every colour has one (and named as not written when
// the output is OBJ, whose colours have none), dropped with the reason when only some do.
TEST(MeshAttributes, ObjColourAlphaIsKeptWhenEveryColourHasOne) {
    const Read r = read(write_file("alpha.obj", "v 0 0 0 1 0 0 0.25\nv 1 0 0 0 1 0 1\nv 0 1 0 0 0 1 0.5\nf 1 2 3\n"));
    EXPECT_TRUE(r.report.dropped.empty());
    ASSERT_EQ(names(r.report.layout.vertex), (std::vector<std::string>{"red", "green", "blue", "alpha"}));
    EXPECT_EQ(std::vector<double>(r.mesh.vertex_attributes.row(0), r.mesh.vertex_attributes.row(1)),
              (std::vector<double>{1, 0, 0, 0.25}));
    const std::string ply = temp_path("attributes-alpha-out.ply").string();
    EXPECT_TRUE(io::write_mesh(r.mesh, r.report.layout, ply, io::MeshFormat::ply, false).empty());
    EXPECT_EQ(read(ply).mesh.vertex_attributes.row(2)[3], 0.5);
    const std::string obj = temp_path("attributes-alpha-out.obj").string();
    EXPECT_EQ(io::write_mesh(r.mesh, r.report.layout, obj, io::MeshFormat::obj, false), (std::vector<std::string>{"vertex alpha"}));
    const Read some = read(write_file("some-alpha.obj", "v 0 0 0 1 0 0 0.25\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"));
    EXPECT_TRUE(mentions(some.report.dropped, "vertex colour alpha: only 1 of 3 colours have one"));
    EXPECT_EQ(names(some.report.layout.vertex), (std::vector<std::string>{"red", "green", "blue"}));
}

TEST(MeshAttributes, OffColoursAreIntegersOrFractionsByTheFile) {
    const Read ints = read(write_file("c.off", "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n0 1 0 0 0 255 0\n3 0 1 2\n"));
    EXPECT_EQ(names(ints.report.layout.vertex), (std::vector<std::string>{"red", "green", "blue", "alpha"}));
    EXPECT_EQ(ints.report.layout.vertex[0].type, io::ValueType::u8);
    EXPECT_EQ(ints.mesh.vertex_attributes.row(1)[3], 128);
    const std::string obj = temp_path("attributes-off-colours.obj").string();  // OBJ colours have no alpha
    EXPECT_EQ(io::write_mesh(ints.mesh, ints.report.layout, obj, io::MeshFormat::obj, false), (std::vector<std::string>{"vertex alpha"}));
    // Normals, a colour without alpha, texture coordinates, a colour per face split with its quad.
    const Read all = read(write_file("stcn.off",
                                     "STCNOFF\n4 1 0\n0 0 0 0 0 1 1 0 0 0 0\n1 0 0 0 0 1 0 1 0.0 1 0\n"
                                     "1 1 0 0 0 1 0 0 1 1 1\n0 1 0 0 0 1 0.5 0.5 0.5 0 1\n4 0 1 2 3 0.25 0.5 1.0\n"),
                          true);
    ASSERT_EQ(names(all.report.layout.vertex), (std::vector<std::string>{"nx", "ny", "nz", "red", "green", "blue", "s", "t"}));
    EXPECT_EQ(all.report.layout.vertex[3].type, io::ValueType::f32);
    EXPECT_EQ(std::vector<double>(all.mesh.vertex_attributes.row(3), all.mesh.vertex_attributes.row(4)),
              (std::vector<double>{0, 0, 1, 0.5, 0.5, 0.5, 0, 1}));
    EXPECT_EQ(names(all.report.layout.face), (std::vector<std::string>{"red", "green", "blue"}));
    EXPECT_EQ(all.mesh.face_attributes.values, (std::vector<double>{0.25, 0.5, 1, 0.25, 0.5, 1}));
}

// Tokens are separated by the C locale's white space: space, tab, CR (Windows line ends),
// vertical tab and form feed. Anything else, a non-ASCII byte included, belongs to a token.
TEST(MeshAttributes, TextTokensSplitAtEveryKindOfWhiteSpace) {
    const Read r = read(write_file("ws.off", "OFF\r\n3\t1 0\r\n0\v0\f0\r\n 1 \t0 0\n0 1 0\n3\t0\t1\t2\r\n"));
    ASSERT_EQ(r.mesh.points.size(), 3u);
    EXPECT_EQ(r.mesh.points[1].x, 1);
    EXPECT_EQ(r.mesh.faces, (std::vector<mesh::Face>{{0, 1, 2}}));
    EXPECT_THROW(read(write_file("nbsp.off", "OFF\n3 1 0\n0\xa0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")), std::exception);
}

TEST(MeshAttributes, ObjAndOffWriteWhatTheyHoldAndNameTheRest) {
    const Read ply = read(write_file("w.ply", std::string("ply\nformat ascii 1.0\n") + kPlyHeader + kPlyBody));
    const std::string obj = temp_path("attributes-w.obj").string();
    const std::vector<std::string> not_in_obj = io::write_mesh(ply.mesh, ply.report.layout, obj, io::MeshFormat::obj, false);
    EXPECT_EQ(not_in_obj, (std::vector<std::string>{"vertex quality", "vertex label", "face red", "face material"}));
    const std::string text = read_text(obj);
    EXPECT_NE(text.find("v 1 0 0 0 1 0\n"), std::string::npos) << text;  // green 255 → 1
    EXPECT_NE(text.find("vn 0 0 1\n"), std::string::npos);
    EXPECT_NE(text.find("f 1//1 2//2 3//3\n"), std::string::npos);
    const Read obj_back = read(obj);
    EXPECT_EQ(names(obj_back.report.layout.vertex), (std::vector<std::string>{"red", "green", "blue", "nx", "ny", "nz"}));
    // OFF: colours of uchar columns as integers; a fraction always with a point, so that a
    // colour of 1 reads back as full intensity, not as 1 of 255.
    const std::string off = temp_path("attributes-w.off").string();
    EXPECT_EQ(io::write_mesh(ply.mesh, ply.report.layout, off, io::MeshFormat::off, false),
              (std::vector<std::string>{"vertex quality", "vertex label", "face red", "face material"}));  // (red alone: no colour)
    EXPECT_EQ(read_text(off).substr(0, 5), "CNOFF");
    const Read off_back = read(off);
    EXPECT_EQ(off_back.report.layout.vertex[3].type, io::ValueType::u8);
    EXPECT_EQ(off_back.mesh.vertex_attributes.row(1)[4], 255);
    EXPECT_EQ(off_back.mesh.vertex_attributes.row(1)[6], 255);  // alpha: opaque
    const std::string again = temp_path("attributes-again.off").string();
    io::write_mesh(obj_back.mesh, obj_back.report.layout, again, io::MeshFormat::off, false);
    const Read fractions = read(again);
    EXPECT_EQ(fractions.report.layout.vertex[3].type, io::ValueType::f32);
    EXPECT_EQ(fractions.mesh.vertex_attributes.row(1)[4], 1.0);
    // A face colour, split with its quad, written per triangle.
    const Read quad = read(write_file("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 10 20 30 40\n"), true);
    const std::string triangles = temp_path("attributes-quad-out.off").string();
    EXPECT_TRUE(io::write_mesh(quad.mesh, quad.report.layout, triangles, io::MeshFormat::off, false).empty());
    EXPECT_NE(read_text(triangles).find("3 0 1 2 10 20 30 40\n3 0 2 3 10 20 30 40\n"), std::string::npos) << read_text(triangles);
}

TEST(MeshAttributes, WrittenIntegersAreRoundedAndClampedAndNormalsUnit) {
    mesh::Mesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.faces = {{0, 1, 2}};
    m.vertex_attributes = {4, {300.4, 0, 0, 2, -5, 0, 3, 4, 12.6, 0, 0, 0.5}};
    io::AttributeLayout layout;
    layout.vertex = {{"red", io::ValueType::u8}, {"nx", io::ValueType::f32}, {"ny", io::ValueType::f32}, {"nz", io::ValueType::f32}};
    const std::string out = temp_path("attributes-round.ply").string();
    io::write_mesh(m, layout, out, io::MeshFormat::ply, true);
    const Read back = read(out);
    EXPECT_EQ(back.mesh.vertex_attributes.values, (std::vector<double>{255, 0, 0, 1, 0, 0, 0.6, 0.8, 13, 0, 0, 1}));
}

}  // namespace
}  // namespace toposimp::testing
