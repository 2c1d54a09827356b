// `toposimp mesh` end to end: formats, targets, JSON, and every kind of bad input (exit 2, a
// message naming the file and the place, no output left behind).
#include "cli/cli_fixtures.hpp"
#include "core/mesh/mesh.hpp"
#include "io/mesh/mesh_files.hpp"
#include "support/mesh_checker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>

namespace toposimp::testing {
namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

mesh::Mesh read_back(const std::string& path) {
    io::MeshReadReport report;
    return io::read_mesh(path, {}, report);
}

TEST(MeshCli, SimplifiesTheSampleTorusCleanly) {
    const auto dir = fresh_dir("mesh");
    const std::string out = (dir / "torus.obj").string();
    const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--keep", "10%", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("\"faces_in\":4800"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"faces_out\":480"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"hausdorff\""), std::string::npos);
    EXPECT_EQ(r.out.find("\"vertical_error\""), std::string::npos) << "not a terrain";
    const mesh::Mesh m = read_back(out);
    EXPECT_EQ(m.faces.size(), 480u);
    const MeshDefects defects = find_defects(m);
    EXPECT_EQ(defects.total(), 0u) << defects.first;
    // A torus stays a torus: V − E + F = 0.
    EXPECT_EQ(static_cast<long>(m.points.size()) - static_cast<long>(m.faces.size()) / 2, 0);
}

TEST(MeshCli, TerrainWithLockedBorderKeepsItsBorderAndNeverFolds) {
    const auto dir = fresh_dir("mesh");
    const std::string out = (dir / "hills.ply").string();
    const CliResult r =
        run_cli({"mesh", testdata("mesh/hills.obj"), "-o", out, "--keep", "5%", "--terrain", "--lock-boundary", "--no-hausdorff"});
    ASSERT_EQ(r.code, 0) << r.err;
    const mesh::Mesh m = read_back(out);
    EXPECT_EQ(count_map_plane_folds(m, 1), 0u);
    std::size_t border = 0;
    for (const Point3& p : m.points) border += p.x == 0 || p.y == 0 || p.x == 64 || p.y == 64;
    EXPECT_EQ(border, 256u);
    EXPECT_EQ(find_defects(m).total(), 0u);
}

TEST(MeshCli, TerrainsReportTheirVerticalError) {
    const auto dir = fresh_dir("mesh");
    const std::string out = (dir / "hills.ply").string();
    const CliResult r = run_cli({"mesh", testdata("mesh/hills.obj"), "-o", out, "--keep", "5%", "--terrain", "--lock-boundary", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto at = r.out.find("\"vertical_error\":{\"max\":");
    ASSERT_NE(at, std::string::npos) << r.out;
    const double vertical = std::stod(r.out.substr(at + std::string("\"vertical_error\":{\"max\":").size()));
    const auto hausdorff_at = r.out.find("\"hausdorff\":{\"mode\":\"quick\",\"max\":");
    ASSERT_NE(hausdorff_at, std::string::npos) << r.out;
    const double distance = std::stod(r.out.substr(hausdorff_at + std::string("\"hausdorff\":{\"mode\":\"quick\",\"max\":").size()));
    EXPECT_GT(vertical, 0.0);
    EXPECT_GE(vertical, distance);  // straight up or down is one way to the other surface
    EXPECT_NE(r.out.find("\"samples_outside\":0"), std::string::npos) << "locked border: the same plan";
}

TEST(MeshCli, MeshToStdoutKeepsTheSummaryOnStderr) {
    const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", "/vsistdout/", "-f", "off", "--json", "--no-hausdorff"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.rfind("OFF\n240 480 0\n", 0), 0u) << r.out.substr(0, 40);
    EXPECT_EQ(r.out.find("\"command\""), std::string::npos) << "JSON mixed into the mesh";
    EXPECT_NE(r.err.find("{\"command\":\"mesh\""), std::string::npos) << r.err;
}

// `toposimp formats` lists io/mesh's table: every format the readers and writers know, and -f
// and the extensions name the same ones.
TEST(MeshCli, FormatsListsEveryMeshFormat) {
    const CliResult json = run_cli({"formats", "--json"});
    ASSERT_EQ(json.code, 0) << json.err;
    const CliResult table = run_cli({"formats"});
    ASSERT_EQ(table.code, 0) << table.err;
    ASSERT_EQ(io::mesh_formats().size(), 4u);
    for (const io::MeshFormatInfo& format : io::mesh_formats()) {
        EXPECT_NE(json.out.find(std::string("{\"name\":\"") + format.name + "\",\"title\":\"" + format.title +
                                "\",\"extension\":\"" + format.extension + "\""),
                  std::string::npos)
            << json.out;
        EXPECT_NE(table.out.find(format.carries), std::string::npos) << table.out;
        EXPECT_EQ(io::mesh_format_named(format.name), &format);
        EXPECT_EQ(io::mesh_format_by_extension(std::string("x") + format.extension), &format);
    }
    EXPECT_EQ(io::mesh_format_named("PLY"), &io::info(io::MeshFormat::ply)) << "names in any case";
    EXPECT_EQ(io::mesh_format_by_extension("model.STL"), &io::info(io::MeshFormat::stl)) << "extensions in any case";
    EXPECT_EQ(io::mesh_format_named("gpkg"), nullptr);
    EXPECT_EQ(io::mesh_format_by_extension("tin.gpkg"), nullptr);
    EXPECT_EQ(io::mesh_extensions_text(", ", " or "), ".obj, .ply, .off or .stl");
}

TEST(MeshCli, EveryFormatRoundTripsExactly) {
    const auto dir = fresh_dir("mesh");
    const std::string first = (dir / "a.ply").string();
    ASSERT_EQ(run_cli({"mesh", testdata("mesh/torus.off"), "-o", first, "--keep", "30%", "--no-hausdorff"}).code, 0);
    const mesh::Mesh reference = read_back(first);
    for (const std::string name : {"b.obj", "c.off", "d.ply"}) {
        const std::string path = (dir / name).string();
        // Keeping 100% writes the mesh unchanged in another format.
        std::vector<std::string> args{"mesh", first, "-o", path, "--keep", "100%", "--no-hausdorff"};
        if (name == "d.ply") args.push_back("--ascii");
        const CliResult r = run_cli(args);
        ASSERT_EQ(r.code, 0) << r.err;
        const mesh::Mesh m = read_back(path);
        ASSERT_EQ(m.faces, reference.faces) << name;
        ASSERT_EQ(m.points.size(), reference.points.size());
        for (std::size_t i = 0; i < m.points.size(); ++i) ASSERT_TRUE(same_location(m.points[i], reference.points[i])) << name;
    }
    // STL numbers the vertices as it meets them: the same triangles, corner by corner.
    const std::string stl = (dir / "e.stl").string();
    const CliResult r = run_cli({"mesh", first, "-o", stl, "--keep", "100%", "--no-hausdorff"});
    ASSERT_EQ(r.code, 0) << r.err;
    const mesh::Mesh m = read_back(stl);
    ASSERT_EQ(m.faces.size(), reference.faces.size());
    EXPECT_EQ(m.points.size(), reference.points.size());
    for (std::size_t f = 0; f < m.faces.size(); ++f) {
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(same_location(m.points[m.faces[f][k]], reference.points[reference.faces[f][k]])) << f;
    }
    // And an STL input simplifies as one surface (its corners welded on reading).
    const std::string half = (dir / "f.obj").string();
    const CliResult simplified = run_cli({"mesh", stl, "-o", half, "--keep", "50%", "--json", "--no-hausdorff"});
    ASSERT_EQ(simplified.code, 0) << simplified.err;
    EXPECT_NE(simplified.out.find("\"welded_vertices\":" + std::to_string(3 * m.faces.size() - m.points.size()) + ","), std::string::npos)
        << simplified.out;
    const mesh::Mesh out = read_back(half);
    EXPECT_EQ(out.faces.size(), m.faces.size() / 2);
    EXPECT_EQ(find_defects(out).total(), 0u);
}

TEST(MeshCli, ColoursNormalsAndFaceValuesSurviveSimplification) {
    const auto dir = fresh_dir("mesh");
    // The torus with a uchar colour and a unit normal per vertex (from its position) and a
    // "quality" per face.
    io::MeshReadReport report;
    mesh::Mesh m = io::read_mesh(testdata("mesh/torus.off"), {}, report);
    io::AttributeLayout layout;
    layout.vertex = {{"red", io::ValueType::u8}, {"green", io::ValueType::u8}, {"blue", io::ValueType::u8},
                     {"nx", io::ValueType::f32}, {"ny", io::ValueType::f32}, {"nz", io::ValueType::f32}};
    layout.face = {{"quality", io::ValueType::f64}};
    m.vertex_attributes.width = 6;
    for (const Point3& p : m.points) {
        const double length = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
        m.vertex_attributes.values.insert(m.vertex_attributes.values.end(),
                                          {p.x > 0 ? 255.0 : 0.0, 128.0, 0.0, p.x / length, p.y / length, p.z / length});
    }
    m.face_attributes = {1, std::vector<double>(m.faces.size(), 0.5)};
    const std::string in = (dir / "coloured.ply").string(), out = (dir / "out.ply").string();
    ASSERT_TRUE(io::write_mesh(m, layout, in, io::MeshFormat::ply, false).empty());
    const CliResult r = run_cli({"mesh", in, "-o", out, "--keep", "20%", "--no-hausdorff"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("dropped"), std::string::npos) << r.err;
    io::MeshReadReport back_report;
    const mesh::Mesh back = io::read_mesh(out, {}, back_report);
    EXPECT_EQ(back_report.layout.vertex, layout.vertex);
    EXPECT_EQ(back_report.layout.face, layout.face);
    ASSERT_EQ(back.vertex_attributes.values.size(), 6 * back.points.size());
    for (std::size_t v = 0; v < back.points.size(); ++v) {
        const double* row = back.vertex_attributes.row(v);
        EXPECT_EQ(row[1], 128);  // shared by all: unchanged
        EXPECT_NEAR(row[3] * row[3] + row[4] * row[4] + row[5] * row[5], 1.0, 1e-6);  // (float columns)
    }
    EXPECT_EQ(back.face_attributes.values, std::vector<double>(back.faces.size(), 0.5));
    // OBJ has no place for a face's quality: written without it, and said so.
    const CliResult obj = run_cli({"mesh", in, "-o", (dir / "out.obj").string(), "--keep", "20%", "--no-hausdorff", "--json"});
    ASSERT_EQ(obj.code, 0) << obj.err;
    EXPECT_NE(obj.err.find("face quality not written: OBJ has no place for it"), std::string::npos) << obj.err;
    EXPECT_NE(obj.out.find("\"attributes\":{\"vertex\":[\"red\",\"green\",\"blue\",\"nx\",\"ny\",\"nz\"],\"face\":[\"quality\"],"
                           "\"dropped\":[],\"not_written\":[\"face quality\"]}"),
              std::string::npos)
        << obj.out;
}

// An unwelded mesh (each face with corners of its own, as converted from STL) is thousands of
// separate triangles: nothing collapses, and the warning says why and what to do. --weld merges
// the copies first; a colour that differs between copies (a seam) is dropped and said so.
TEST(MeshCli, UnweldedMeshIsNamedAndWeldedOnRequest) {
    const auto dir = fresh_dir("mesh");
    io::MeshReadReport report;
    const mesh::Mesh torus = io::read_mesh(testdata("mesh/torus.off"), {}, report);
    mesh::Mesh soup;
    io::AttributeLayout layout;
    layout.vertex = {{"red", io::ValueType::u8}, {"green", io::ValueType::u8}, {"blue", io::ValueType::u8}};
    soup.vertex_attributes.width = 3;
    for (std::uint32_t f = 0; f < torus.faces.size(); ++f) {
        for (std::uint32_t v : torus.faces[f]) {
            soup.points.push_back(torus.points[v]);
            // Green differs between the copies of a vertex (by face), red and blue do not.
            soup.vertex_attributes.values.insert(soup.vertex_attributes.values.end(), {v % 2 == 0 ? 255.0 : 0.0, f % 2 == 0 ? 10.0 : 20.0, 0.0});
        }
        soup.faces.push_back({3 * f, 3 * f + 1, 3 * f + 2});
    }
    const std::string in = (dir / "soup.ply").string();
    ASSERT_TRUE(io::write_mesh(soup, layout, in, io::MeshFormat::ply, false).empty());

    const CliResult plain = run_cli({"mesh", in, "-o", (dir / "plain.ply").string(), "--keep", "10%", "--no-hausdorff", "--json"});
    ASSERT_EQ(plain.code, 0) << plain.err;
    EXPECT_NE(plain.err.find("target not reached"), std::string::npos) << plain.err;
    EXPECT_NE(plain.err.find("14400 of the vertices left share their location with another: --weld merges"), std::string::npos)
        << plain.err;
    EXPECT_NE(plain.out.find("\"welded_vertices\":0,"), std::string::npos) << plain.out;

    const std::string out = (dir / "welded.ply").string();
    const CliResult welded = run_cli({"mesh", in, "-o", out, "--keep", "10%", "--weld", "--json"});
    ASSERT_EQ(welded.code, 0) << welded.err;
    EXPECT_EQ(welded.err.find("target not reached"), std::string::npos) << welded.err;
    EXPECT_NE(welded.out.find("\"welded_vertices\":12000,"), std::string::npos) << welded.out;  // 14 400 corners, 2 400 vertices
    EXPECT_NE(welded.out.find("\"faces_out\":480,"), std::string::npos) << welded.out;
    EXPECT_NE(welded.out.find("\"vertex\":[\"red\",\"blue\"]"), std::string::npos) << welded.out;
    EXPECT_NE(welded.out.find("\"dropped\":[\"vertex green: differs between vertices welded together\"]"), std::string::npos)
        << welded.out;
    const mesh::Mesh m = read_back(out);
    EXPECT_EQ(m.faces.size(), 480u);
    EXPECT_EQ(find_defects(m).total(), 0u);
}

// An output whose format cannot be told (.xyz: not a mesh format, nor a GDAL vector one) or an
// unknown driver is refused before the input is read, naming the output as given.
TEST(MeshCli, UnknownOutputFormatIsRefusedBeforeAnyWork) {
    const auto dir = fresh_dir("mesh");
    const std::string xyz = (dir / "out.xyz").string();
    CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", xyz, "--progress"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("cannot tell the output format of '" + xyz + "' from its extension; name it with -f (e.g. -f GPKG); "
                         "a mesh is written as .obj, .ply, .off or .stl"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("PROGRESS"), std::string::npos) << r.err;  // no phase started
    r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / "out.gpkg").string(), "-f", "NoSuchDriver"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("unknown vector output format 'NoSuchDriver'"), std::string::npos) << r.err;
    EXPECT_TRUE(std::filesystem::is_empty(dir)) << "nothing written";
}

TEST(MeshCli, ThreadCountDoesNotChangeTheFile) {
    const auto dir = fresh_dir("mesh");
    const std::string one = (dir / "one.ply").string(), two = (dir / "two.ply").string();
    ASSERT_EQ(run_cli({"mesh", testdata("mesh/hills.obj"), "-o", one, "--keep", "10%", "-j", "1", "--no-hausdorff"}).code, 0);
    ASSERT_EQ(run_cli({"mesh", testdata("mesh/hills.obj"), "-o", two, "--keep", "10%", "-j", "2", "--no-hausdorff"}).code, 0);
    std::ifstream a(one, std::ios::binary), b(two, std::ios::binary);
    const std::string x((std::istreambuf_iterator<char>(a)), {}), y((std::istreambuf_iterator<char>(b)), {});
    EXPECT_EQ(x, y);
}

struct BadMesh {
    const char* name;
    const char* file;
    const char* text;
    const char* message;  // a part of the error
};

class MeshBadInput : public ::testing::TestWithParam<BadMesh> {};

TEST_P(MeshBadInput, ExitsWithTwoAndAClearMessage) {
    const BadMesh& bad = GetParam();
    const auto dir = fresh_dir("mesh-bad");
    const auto input = dir / bad.file;
    write_text(input, bad.text);
    const std::string out = (dir / "out.obj").string();
    const CliResult r = run_cli({"mesh", input.string(), "-o", out});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(bad.message), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(input.string()), std::string::npos) << "the message names the file: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    // Nothing else left in the folder (no staging files).
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) files += entry.path() != input;
    EXPECT_EQ(files, 0u);
}

const char kTetra[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";

INSTANTIATE_TEST_SUITE_P(
    Kinds, MeshBadInput,
    ::testing::Values(
        BadMesh{"TruncatedOff", "t.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n", "truncated"},
        BadMesh{"TruncatedPlyHeader", "t.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "no end_header"},
        BadMesh{"TruncatedBinaryPly", "t.ply",
                "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n\x01\x02\x03",
                "truncated binary PLY"},
        BadMesh{"Quad", "q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "--triangulate"},
        BadMesh{"NanCoordinate", "n.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
        BadMesh{"IndexOutOfRange", "i.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "refers to vertex"},
        BadMesh{"OffIndexOutOfRange", "i.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "refers to vertex"},
        BadMesh{"NotANumber", "x.obj", "v 0 zero 0\n", "is not a number"},
        BadMesh{"TextureReferenceOutOfRange", "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/5 2/1 3/1\n",
                "face 1 refers to texture coordinates 5, but there are 1"},
        BadMesh{"NormalNotANumber", "n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 up 1\nf 1//1 2//1 3//1\n",
                "'up' is not a finite number"},
        BadMesh{"OffColourMissing", "c.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0\n0 1 0 0 0 1\n3 0 1 2\n",
                "vertex 1: expected a colour of 3 or 4 numbers"},
        BadMesh{"FourDimensionalOff", "h.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n",
                "only OFF with ST, C and N (3D vertices) is read"},
        BadMesh{"NonManifold", "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 -1 0\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
                "the edge between vertices 0 and 1 (counted from 0) has more than two faces (0, 1, 2"},
        // Numbered as in the file, though the unused vertex 0 and the face 0 repeating a corner are dropped.
        BadMesh{"NonManifoldAfterDroppedParts", "m.obj",
                "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 -1 0\nf 2 2 3\nf 2 3 4\nf 3 2 5\nf 2 3 6\nf 2 4 5\n",
                "the edge between vertices 1 and 2 (counted from 0) has more than two faces (1, 2, 3, ...)"},
        BadMesh{"NoFaces", "e.obj", kTetra, "no faces"},
        BadMesh{"TruncatedStl", "t.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "truncated: the file ends inside a facet"},
        BadMesh{"NotAnStl", "n.stl", "OBJ, not STL\n", "not an STL file"},
        BadMesh{"UnknownExtension", "u.xyz", "solid x\n", "neither a mesh"}),
    [](const ::testing::TestParamInfo<BadMesh>& p) { return std::string(p.param.name); });

TEST(MeshCli, PolygonsAreSplitOnlyWhenAsked) {
    const auto dir = fresh_dir("mesh");
    write_text(dir / "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    const std::string out = (dir / "out.obj").string();
    const CliResult r = run_cli({"mesh", (dir / "quad.obj").string(), "-o", out, "--triangulate", "--keep", "100%"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(read_back(out).faces.size(), 2u);
}

TEST(MeshCli, ExistingOutputIsKeptWithoutOverwrite) {
    const auto dir = fresh_dir("mesh");
    const auto out = dir / "out.obj";
    write_text(out, "keep me");
    const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out.string()});
    EXPECT_EQ(r.code, 2);
    std::ifstream in(out);
    std::string text;
    std::getline(in, text);
    EXPECT_EQ(text, "keep me");
}

}  // namespace
}  // namespace toposimp::testing

namespace toposimp::testing {
namespace {

// A 30 × 24 GeoTIFF in UTM 33N, 10 m cells, with a nodata hole.
std::string write_dem(const std::filesystem::path& dir) {
    GDALAllRegister();
    const std::string path = (dir / "dem.tif").string();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* dataset = driver->Create(path.c_str(), 30, 24, 1, GDT_Float32, nullptr);
    double gt[6] = {400000, 10, 0, 5000240, 0, -10};
    dataset->SetGeoTransform(gt);
    OGRSpatialReference srs;
    srs.importFromEPSG(32633);
    dataset->SetSpatialRef(&srs);
    GDALRasterBand* band = dataset->GetRasterBand(1);
    band->SetNoDataValue(-9999);
    std::vector<float> cells(30 * 24);
    for (int j = 0; j < 24; ++j) {
        for (int i = 0; i < 30; ++i) {
            const bool hole = (i - 20) * (i - 20) + (j - 12) * (j - 12) < 9;
            cells[j * 30 + i] = hole ? -9999.0f : static_cast<float>(100 + 10 * std::sin(i * 0.3) + 5 * std::cos(j * 0.4) + (i * j % 7));
        }
    }
    EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, 30, 24, cells.data(), 30, 24, GDT_Float32, 0, 0), CE_None);
    GDALClose(dataset);
    return path;
}

TEST(MeshCli, DemBecomesASimplifiedTinLayerInTheDemsCrs) {
    const auto dir = fresh_dir("mesh-dem");
    const std::string dem = write_dem(dir);
    const std::string out = (dir / "tin.gpkg").string();
    const CliResult r = run_cli({"mesh", dem, "-o", out, "--keep", "20%", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("\"terrain\":true"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"terrain_mode\":\"dem\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"lock_boundary\":true"), std::string::npos);
    int hole = 0;
    for (int j = 0; j < 24; ++j) {
        for (int i = 0; i < 30; ++i) hole += (i - 20) * (i - 20) + (j - 12) * (j - 12) < 9;
    }
    EXPECT_NE(r.out.find("\"cells_without_data\":" + std::to_string(hole) + ","), std::string::npos) << r.out;
    GDALDataset* read = static_cast<GDALDataset*>(GDALOpenEx(out.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(read, nullptr);
    OGRLayer* layer = read->GetLayer(0);
    ASSERT_NE(layer->GetSpatialRef(), nullptr);
    EXPECT_EQ(std::string(layer->GetSpatialRef()->GetAuthorityCode(nullptr)), "32633");
    EXPECT_EQ(wkbFlatten(layer->GetGeomType()), wkbPolygon);
    // Rebuild the mesh from the triangles: no fold in the map plane, no defect, no vertex in the hole.
    mesh::Mesh m;
    std::map<std::tuple<double, double, double>, std::uint32_t> ids;
    for (auto& feature : *layer) {
        const OGRLinearRing* ring = feature->GetGeometryRef()->toPolygon()->getExteriorRing();
        ASSERT_EQ(ring->getNumPoints(), 4);
        mesh::Face f{};
        for (int k = 0; k < 3; ++k) {
            const auto key = std::make_tuple(ring->getX(k), ring->getY(k), ring->getZ(k));
            auto [it, fresh] = ids.emplace(key, static_cast<std::uint32_t>(m.points.size()));
            if (fresh) m.points.push_back({ring->getX(k), ring->getY(k), ring->getZ(k)});
            f[k] = it->second;
        }
        m.faces.push_back(f);
    }
    GDALClose(read);
    EXPECT_EQ(count_map_plane_folds(m, 1), 0u);
    EXPECT_EQ(find_defects(m).total(), 0u);
    for (const Point3& p : m.points) {
        const double i = (p.x - 400005) / 10, j = (5000235 - p.y) / 10;
        EXPECT_GE((i - 20) * (i - 20) + (j - 12) * (j - 12), 9) << "a vertex in the nodata hole";
    }
    // The outer border of cell centres (x 400005..400295, y 5000235..5000005) is all kept.
    std::size_t border = 0;
    for (const Point3& p : m.points) border += p.x == 400005 || p.x == 400295 || p.y == 5000005 || p.y == 5000235;
    EXPECT_EQ(border, 2u * 30 + 2u * 22);
}

double json_number(const std::string& text, const std::string& key) {
    const auto at = text.find("\"" + key + "\":");
    if (at == std::string::npos) return -1;
    return std::stod(text.substr(at + key.size() + 3));
}

TEST(MeshCli, DemMaxErrorIsAGuaranteedVerticalBound) {
    // The DEM's TIN, simplified within 1.5 height units: the brute-force checker finds every
    // point of the output within 1.5 of the input straight above or below; the JSON says so.
    const auto dir = fresh_dir("mesh-dem");
    const std::string dem = write_dem(dir);
    const std::string full = (dir / "full.ply").string(), out = (dir / "bounded.ply").string();
    ASSERT_EQ(run_cli({"mesh", dem, "-o", full, "--keep", "100%", "--no-hausdorff", "-q"}).code, 0);
    const CliResult r = run_cli({"mesh", dem, "-o", out, "--max-error", "1.5", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("\"criterion\":\"vertical error <= 1.5\""), std::string::npos) << r.out;
    EXPECT_EQ(json_number(r.out, "guaranteed_vertical_error"), 1.5) << r.out;
    EXPECT_GT(json_number(r.out, "vertical"), 0) << "some collapses refused for the bound: " << r.out;
    const double sampled = json_number(r.out, "vertical_error\":{\"max");
    EXPECT_GT(sampled, 0.5);
    EXPECT_LE(sampled, 1.5);
    const mesh::Mesh input = read_back(full), output = read_back(out);
    EXPECT_LT(output.faces.size(), input.faces.size() / 2);
    double largest = 0;
    EXPECT_TRUE(within_vertical_gap(input, output, 1.5, &largest)) << largest;
    EXPECT_EQ(count_map_plane_folds(output, 1), 0u);
}

TEST(MeshCli, MaxErrorOnASurfaceThatIsNoTerrainSaysItBoundsTheQuadricError) {
    const auto dir = fresh_dir("mesh");
    const CliResult r =
        run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / "t.obj").string(), "--terrain", "--max-error", "0.05", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("not a terrain TIN"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("\"criterion\":\"quadric error <= 0.05\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"terrain\":false"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("guaranteed_vertical_error"), std::string::npos) << r.out;
}

// --terrain on a mesh whose faces overlap in the map plane (a deck over the ground): simplified
// in space, with the 3D contact tests. Taken as a terrain, it skipped them, and 20 % of this
// mesh had 5 intersecting face pairs.
TEST(MeshCli, TerrainOverlappingItselfInTheMapPlaneIsSimplifiedInSpace) {
    const auto dir = fresh_dir("mesh");
    const std::string out = (dir / "deck.obj").string();
    const CliResult r = run_cli({"mesh", testdata("mesh/bridge-deck.obj"), "-o", out, "--keep", "20%", "--terrain", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("overlap in the x-y plane, so this is not a terrain TIN"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("\"terrain\":false"), std::string::npos) << r.out;
    const mesh::Mesh m = read_back(out);
    EXPECT_LT(m.faces.size(), 300u);
    const MeshDefects defects = find_defects(m);
    EXPECT_EQ(defects.total(), 0u) << defects.first;
}

std::string contents(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Issue 33: by default the collapses are made without the contact search and the result is
// checked once (--contact-check after). The torus's result has no contact: checked, kept, and the
// file --contact-check each writes. The bridge deck's first result meets itself: simplified
// again with every collapse checked, the -v line names the faces, the progress lines the phase,
// and the file is again --contact-check each's.
TEST(MeshCli, Issue33ContactsAreCheckedOnceAfterTheCollapses) {
    const auto dir = fresh_dir("mesh");
    for (const auto& [input, keep, again] : {std::tuple<std::string, std::string, bool>{"mesh/torus.off", "10%", false},
                                            {"mesh/bridge-deck.obj", "20%", true}}) {
        const std::string after = (dir / "after.ply").string(), each = (dir / "each.ply").string();
        const CliResult a = run_cli({"mesh", testdata(input), "-o", after, "--keep", keep, "--json", "-v", "--overwrite"});
        ASSERT_EQ(a.code, 0) << a.err;
        EXPECT_NE(a.out.find(std::string("\"contact_check\":{\"mode\":\"after\",\"simplified_again\":") + (again ? "true" : "false")),
                  std::string::npos)
            << input << ": " << a.out;
        EXPECT_NE(a.err.find(again ? "simplified again with every collapse checked" : "contacts: none in the result"), std::string::npos)
            << input << ": " << a.err;
        if (again) {
            EXPECT_NE(a.err.find("meeting near ("), std::string::npos) << a.err;
            EXPECT_NE(a.out.find("\"contact_near\":["), std::string::npos) << a.out;
        } else {
            EXPECT_EQ(a.out.find("\"contact_near\""), std::string::npos) << a.out;
        }
        const CliResult e = run_cli({"mesh", testdata(input), "-o", each, "--keep", keep, "--json", "--overwrite", "--contact-check", "each"});
        ASSERT_EQ(e.code, 0) << e.err;
        EXPECT_NE(e.out.find("\"contact_check\":{\"mode\":\"each\""), std::string::npos) << e.out;
        EXPECT_EQ(contents(after), contents(each)) << input;
        const MeshDefects defects = find_defects(read_back(after));
        EXPECT_EQ(defects.total(), 0u) << input << ": " << defects.first;
        if (again) {
            const CliResult p = run_cli({"mesh", testdata(input), "-o", after, "--keep", keep, "--overwrite", "--progress"});
            ASSERT_EQ(p.code, 0) << p.err;
            const auto checking = p.err.find("PROGRESS 0 checking the result for contacts");
            const auto simplifying = p.err.find("PROGRESS 0 simplifying again, every collapse checked");
            ASSERT_NE(checking, std::string::npos) << p.err;
            EXPECT_NE(simplifying, std::string::npos) << p.err;
            EXPECT_LT(checking, simplifying) << p.err;
        }
    }
    const CliResult bad = run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / "x.ply").string(), "--contact-check", "never"});
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("--contact-check"), std::string::npos) << bad.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(MeshCli, DemBandOutOfRangeIsAnError) {
    const auto dir = fresh_dir("mesh-dem");
    const std::string dem = write_dem(dir);
    const CliResult r = run_cli({"mesh", dem, "-o", (dir / "out.obj").string(), "--band", "2"});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("no band 2"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.obj"));
}

// The distance to the input: quick by default (one point of each surface per 40 input faces, at
// least 1 024: the torus's 1 024, with the share of a surface that may lie beyond the largest
// distance found), every vertex and more with --measure full (the quick one a lower bound of it),
// none with --measure none.
TEST(MeshCli, Issue33MeasureIsQuickByDefaultFullOnRequest) {
    const auto dir = fresh_dir("mesh");
    const std::string out = (dir / "t.ply").string();
    auto largest = [](const std::string& json, const std::string& mode) {
        const std::string key = "\"hausdorff\":{\"mode\":\"" + mode + "\",\"max\":";
        const auto at = json.find(key);
        return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size()));
    };
    const CliResult quick = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--keep", "10%", "--json"});
    ASSERT_EQ(quick.code, 0) << quick.err;
    EXPECT_NE(quick.out.find("\"samples\":1024"), std::string::npos) << quick.out;
    const std::string share = "\"share_beyond_max\":";
    ASSERT_NE(quick.out.find(share), std::string::npos) << quick.out;
    EXPECT_NEAR(std::stod(quick.out.substr(quick.out.find(share) + share.size())), 1 - std::pow(0.001, 1.0 / 1024), 1e-5);
    const CliResult told = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--keep", "10%", "-v", "--overwrite"});
    ASSERT_EQ(told.code, 0) << told.err;
    EXPECT_NE(told.err.find("quick, 1024 points of each surface"), std::string::npos) << told.err;
    const CliResult full = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--keep", "10%", "--json", "--measure", "full", "--overwrite"});
    ASSERT_EQ(full.code, 0) << full.err;
    const double q = largest(quick.out, "quick"), f = largest(full.out, "full");
    ASSERT_GT(q, 0.0) << quick.out;
    ASSERT_GT(f, 0.0) << full.out;
    EXPECT_LE(q, f);
    EXPECT_GT(q, 0.5 * f);
    const CliResult none = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--json", "--measure", "none", "--overwrite"});
    ASSERT_EQ(none.code, 0) << none.err;
    EXPECT_EQ(none.out.find("\"hausdorff\":{"), std::string::npos) << none.out;
    EXPECT_EQ(run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--measure", "some", "--overwrite"}).code, 2);
    EXPECT_EQ(run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--measure", "full", "--no-hausdorff", "--overwrite"}).code, 2);
}

// Issue 33: a height field is found and simplified as a terrain without --terrain, exactly as
// with it; a mesh that is not one (a closed model, a deck over the ground, one fold) in space,
// without a warning; --no-terrain keeps the checks in space.
TEST(MeshCli, Issue33HeightFieldsAreFoundAutomatically) {
    const auto dir = fresh_dir("mesh");
    auto mode_of = [](const std::string& json) {
        const std::string key = "\"terrain_mode\":\"";
        const auto at = json.find(key);
        return at == std::string::npos ? std::string() : json.substr(at + key.size(), json.find('"', at + key.size()) - at - key.size());
    };
    auto file = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string found = (dir / "found.ply").string(), asked = (dir / "asked.ply").string(), space = (dir / "space.ply").string();
    const CliResult auto_run = run_cli({"mesh", testdata("mesh/hills.obj"), "-o", found, "--max-error", "0.3", "--json"});
    ASSERT_EQ(auto_run.code, 0) << auto_run.err;
    EXPECT_EQ(mode_of(auto_run.out), "detected") << auto_run.out;
    EXPECT_NE(auto_run.out.find("\"guaranteed_vertical_error\":0.3"), std::string::npos) << auto_run.out;
    EXPECT_EQ(auto_run.err.find("warning"), std::string::npos) << auto_run.err;
    const CliResult asked_run = run_cli({"mesh", testdata("mesh/hills.obj"), "-o", asked, "--max-error", "0.3", "--terrain", "--json"});
    ASSERT_EQ(asked_run.code, 0) << asked_run.err;
    EXPECT_EQ(mode_of(asked_run.out), "asked");
    EXPECT_EQ(file(found), file(asked));
    const CliResult off = run_cli({"mesh", testdata("mesh/hills.obj"), "-o", space, "--max-error", "0.3", "--no-terrain", "--json"});
    ASSERT_EQ(off.code, 0) << off.err;
    EXPECT_EQ(mode_of(off.out), "off");
    EXPECT_NE(file(found), file(space));

    for (const char* model : {"mesh/torus.off", "mesh/bridge-deck.obj"}) {
        const CliResult r = run_cli({"mesh", testdata(model), "-o", (dir / "m.ply").string(), "--overwrite", "--json"});
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_EQ(mode_of(r.out), "not_a_height_field") << model;
        EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    }
    // One fold: an interior vertex of the hills pushed past its neighbour in x.
    mesh::Mesh hills = read_back(testdata("mesh/hills.obj"));
    const std::uint32_t v = 65 * 30 + 30;
    ASSERT_EQ(hills.points[v].x, 30.0);
    hills.points[v].x = 31.5;
    const std::string folded = (dir / "folded.ply").string();
    io::write_mesh(hills, {}, folded, io::MeshFormat::ply, false);
    const CliResult r = run_cli({"mesh", folded, "-o", (dir / "f.ply").string(), "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(mode_of(r.out), "not_a_height_field") << r.out;
    const CliResult warned = run_cli({"mesh", folded, "-o", (dir / "g.ply").string(), "--terrain"});
    EXPECT_NE(warned.err.find("not a terrain TIN"), std::string::npos) << warned.err;
}

}  // namespace
}  // namespace toposimp::testing
