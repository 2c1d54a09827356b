// `toposimp map` end to end, in-process: formats, attributes, CRS, order, exact coordinates.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace toposimp::testing {
namespace {

// Is `kept` an order-preserving subset of `input` (tuples of `width` values) with the same
// first and last tuple?
bool is_vertex_subset(const std::vector<double>& input, const std::vector<double>& kept, std::size_t width) {
    if (kept.size() < 2 * width || input.size() < kept.size()) return false;
    auto tuple_equal = [&](std::size_t i, std::size_t k) {
        for (std::size_t d = 0; d < width; ++d) {
            if (!(input[i * width + d] == kept[k * width + d])) return false;
        }
        return true;
    };
    const std::size_t n = input.size() / width, m = kept.size() / width;
    if (!tuple_equal(0, 0) || !tuple_equal(n - 1, m - 1)) return false;
    std::size_t k = 0;
    for (std::size_t i = 0; i < n && k < m; ++i) {
        if (tuple_equal(i, k)) ++k;
    }
    return k == m;
}

TEST(MapCli, HelpAndVersion) {
    CliResult help = run_cli({"--help"});
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("map"), std::string::npos);
    CliResult map_help = run_cli({"map", "--help"});
    EXPECT_EQ(map_help.code, 0);
    EXPECT_NE(map_help.out.find("--remove-points"), std::string::npos) << map_help.out;
    CliResult version = run_cli({"--version"});
    EXPECT_EQ(version.code, 0);
    EXPECT_NE(version.out.find("toposimp 0.1.0"), std::string::npos);
}

TEST(MapCli, UsageErrorsExitWithTwo) {
    EXPECT_EQ(run_cli({"map", "--frobnicate"}).code, 2);
    EXPECT_EQ(run_cli({"map", testdata("nh_borders.gpkg")}).code, 2) << "missing -o";
    const auto dir = fresh_dir("usage");
    const std::string out = (dir / "out.gpkg").string();
    for (const char* keep : {"150", "abc", "-5%"}) {
        CliResult result = run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--keep", keep});
        EXPECT_EQ(result.code, 2) << keep;
    }
    EXPECT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--max", "--keep", "5%"}).code, 2);
    EXPECT_TRUE(files_in(dir).empty());
}

TEST(MapCli, SimplifiesGeoPackageKeepingAttributesCrsAndOrder) {
    const auto dir = fresh_dir("gpkg");
    const std::string out = (dir / "simple.gpkg").string();
    const CliResult result = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--points",
                                      testdata("nh_borders.gpkg") + ":places", "--keep", "20%", "-o", out, "--json"});
    ASSERT_EQ(result.code, 0) << result.err;
    EXPECT_NE(result.out.find("\"vertices_in\":992"), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("\"vertices_out\":199"), std::string::npos) << result.out;  // ceil(0.2 · 992)
    EXPECT_NE(result.out.find("\"control_points\":26"), std::string::npos);
    EXPECT_NE(result.out.find("\"peak_memory_mib\":"), std::string::npos);

    GDALAllRegister();
    GDALDatasetUniquePtr source(GDALDataset::Open(testdata("nh_borders.gpkg").c_str(), GDAL_OF_VECTOR));
    GDALDatasetUniquePtr simple(GDALDataset::Open(out.c_str(), GDAL_OF_VECTOR));
    ASSERT_TRUE(simple);
    OGRLayer* in = source->GetLayerByName("borders");
    OGRLayer* outl = simple->GetLayerByName("borders");
    ASSERT_NE(outl, nullptr);
    EXPECT_TRUE(in->GetSpatialRef()->IsSame(outl->GetSpatialRef()));
    EXPECT_EQ(in->GetFeatureCount(), outl->GetFeatureCount());
    EXPECT_EQ(outl->GetLayerDefn()->GetFieldCount(), in->GetLayerDefn()->GetFieldCount());
    for (auto& original : *in) {
        OGRFeatureUniquePtr written(outl->GetNextFeature());
        ASSERT_TRUE(written);
        EXPECT_EQ(written->GetFID(), original->GetFID());
        EXPECT_EQ(written->GetFieldAsInteger("id"), original->GetFieldAsInteger("id"));
        EXPECT_STREQ(written->GetFieldAsString("name"), original->GetFieldAsString("name"));
        const OGRLineString* a = original->GetGeometryRef()->toLineString();
        const OGRLineString* b = written->GetGeometryRef()->toLineString();
        std::vector<double> va, vb;
        for (int i = 0; i < a->getNumPoints(); ++i) va.insert(va.end(), {a->getX(i), a->getY(i)});
        for (int i = 0; i < b->getNumPoints(); ++i) vb.insert(vb.end(), {b->getX(i), b->getY(i)});
        EXPECT_TRUE(is_vertex_subset(va, vb, 2)) << "feature " << original->GetFID();
    }
}

// Coordinates that GDAL's own text writers round (DESIGN.md, known traps).
const std::string kTrickyLine =
    "LINESTRING (68.35270000000001 0.30000000000000004, 70.1 0.1, 72.00000000000001 5.123456789012345e-7, "
    "75.5 1e-300, 80.12345678901234 123456789.12345679, 90 0.1)";

class ExactFormats : public ::testing::TestWithParam<const char*> {};

TEST_P(ExactFormats, WriteCoordinatesBitForBit) {
    const auto dir = fresh_dir(std::string("format-") + GetParam());
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbLineString, {{kTrickyLine, "tricky"}, {"LINESTRING (0 0, 1 1, 2 0)", "plain"}});
    const std::string out = (dir / (std::string("out.") + GetParam())).string();
    const CliResult result = run_cli({"map", input, "--keep", "60%", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const ReadLayer original = read_layer(input), written = read_layer(out);
    ASSERT_EQ(written.features.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(written.features[i].name, original.features[i].name);
        EXPECT_EQ(written.features[i].rank, original.features[i].rank);
        ASSERT_EQ(written.features[i].coordinates.size(), 1u);
        EXPECT_TRUE(is_vertex_subset(original.features[i].coordinates[0], written.features[i].coordinates[0], 2))
            << GetParam() << " feature " << i;
    }
    EXPECT_FALSE(written.srs_wkt.empty()) << "CRS kept";
}

// Polygons with holes, and multipolygons: every ring keeps only vertices of its input ring (it
// may start at a node, and Shapefile may reverse it), holes stay holes, shared borders shared.
TEST_P(ExactFormats, WritePolygonsBitForBit) {
    const auto dir = fresh_dir(std::string("polygons-") + GetParam());
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbMultiPolygon,
                {{"MULTIPOLYGON (((0 0, 10 0, 10.1 5, 10 10, 0 10, 0 0), (2 2, 2 3, 2.5 3.1, 3 3, 3 2, 2 2)), "
                  "((20 0, 30 0, 30 10, 20 10, 20.1 5.0000000000000009, 20 0)))", "islands"},
                 {"MULTIPOLYGON (((10 0, 15 0, 15 10, 10 10, 10.1 5, 10 0)))", "neighbour"}});
    const std::string out = (dir / (std::string("out.") + GetParam())).string();
    const CliResult result = run_cli({"map", input, "--max", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const ReadLayer original = read_layer(input), written = read_layer(out);
    ASSERT_EQ(written.features.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(written.features[i].name, original.features[i].name);
        ASSERT_EQ(written.features[i].coordinates.size(), original.features[i].coordinates.size()) << GetParam();
        for (std::size_t r = 0; r < original.features[i].coordinates.size(); ++r) {
            const auto& in = original.features[i].coordinates[r];
            const auto& out_ring = written.features[i].coordinates[r];
            EXPECT_GE(out_ring.size(), 8u) << "a ring keeps 3 corners and closes";
            // Rings may start at a node, so compare as sets of vertices.
            for (std::size_t k = 0; k < out_ring.size(); k += 2) {
                bool found = false;
                for (std::size_t j = 0; j < in.size(); j += 2) found = found || (in[j] == out_ring[k] && in[j + 1] == out_ring[k + 1]);
                EXPECT_TRUE(found) << GetParam() << " feature " << i << " ring " << r << ": vertex not from the input";
            }
        }
    }
    // The border x = 10 with its wiggle (10.1, 5) is shared: both features keep it or neither does.
    auto has_wiggle = [](const ReadFeature& feature) {
        for (const auto& ring : feature.coordinates) {
            for (std::size_t k = 0; k < ring.size(); k += 2) {
                if (ring[k] == 10.1 && ring[k + 1] == 5) return true;
            }
        }
        return false;
    };
    EXPECT_EQ(has_wiggle(written.features[0]), has_wiggle(written.features[1])) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Drivers, ExactFormats, ::testing::Values("gpkg", "shp", "fgb", "geojson"));

TEST(MapCli, RefusesATextDriverThatRoundsCoordinates) {
    const auto dir = fresh_dir("csv-rounding");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbLineString, {{"LINESTRING (0 5e-324, 1 1, 2 0)", "subnormal"}});
    const std::string out = (dir / "out.csv").string();
    const CliResult result = run_cli({"map", input, "--keep", "100%", "-o", out});
    EXPECT_EQ(result.code, 2);
    EXPECT_NE(result.err.find("changed coordinates"), std::string::npos) << result.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_EQ(files_in(dir), std::vector<std::string>{"in.gpkg"});
}

TEST(MapCli, KeepsZAndMOfKeptVertices) {
    const auto dir = fresh_dir("zm");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbLineStringZM,
                {{"LINESTRING ZM (0 0 10 100, 1 0.1 11 101, 2 0 12 102, 3 3 13 103, 4 0 14 104)", "zm"}});
    const std::string out = (dir / "out.gpkg").string();
    ASSERT_EQ(run_cli({"map", input, "--max", "-o", out}).code, 0);
    const ReadLayer written = read_layer(out);
    ASSERT_EQ(written.features.size(), 1u);
    EXPECT_EQ(written.features[0].type, wkbLineStringZM);
    const std::vector<double> expected{0, 0, 10, 100, 4, 0, 14, 104};
    EXPECT_EQ(written.features[0].coordinates[0], expected);
}

TEST(MapCli, MultiLineStringsAndEmptyGeometriesSurvive) {
    const auto dir = fresh_dir("multi");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbMultiLineString,
                {{"MULTILINESTRING ((0 0, 1 1, 2 0), (10 10, 11 12, 12 10))", "two parts"},
                 {"", "null geometry"},
                 {"MULTILINESTRING EMPTY", "empty"}});
    const std::string out = (dir / "out.gpkg").string();
    const CliResult result = run_cli({"map", input, "--max", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    EXPECT_NE(result.err.find("2 features with an empty or NULL geometry are written unchanged"), std::string::npos)
        << result.err;
    const ReadLayer written = read_layer(out);
    ASSERT_EQ(written.features.size(), 3u);
    EXPECT_EQ(written.features[0].coordinates, (std::vector<std::vector<double>>{{0, 0, 2, 0}, {10, 10, 12, 10}}));
    EXPECT_TRUE(written.features[1].null_geometry);
    EXPECT_FALSE(written.features[2].null_geometry);
    EXPECT_TRUE(written.features[2].coordinates.empty());
    EXPECT_EQ(written.features[2].name, "empty");
}

// A PolyLine Shapefile is decoded from its records straight into the map (issue 34): one-part
// and multi-part records, a null shape, and the same output as from a GeoPackage of the same lines.
TEST(MapCli, ShapefileRecordsReadStraightGiveTheSameOutput) {
    const auto dir = fresh_dir("shp-records");
    const std::vector<FeatureSpec> lines{{"LINESTRING (0 0, 1 1, 2 0, 3 1.5, 4 0)", "one"},
                                         {"MULTILINESTRING ((0 5, 1 6, 2 5), (10 10, 11 12, 12 10, 13 12.5))", "two"},
                                         {"", "null"},
                                         {"LINESTRING (0 -3, 1 -2, 2 -3.5, 3 -2)", "three"}};
    const std::string shp = (dir / "in.shp").string(), gpkg = (dir / "in.gpkg").string();
    write_layer(shp, "ESRI Shapefile", wkbLineString, lines, "in");
    write_layer(gpkg, "GPKG", wkbMultiLineString, lines, "in");
    const std::string from_shp = (dir / "from_shp.shp").string(), from_gpkg = (dir / "from_gpkg.shp").string();  // (the straight path: Shapefile to Shapefile)
    for (const auto& [input, out] : {std::pair{shp, from_shp}, std::pair{gpkg, from_gpkg}}) {
        const CliResult result = run_cli({"map", input, "--keep", "60%", "-o", out});
        ASSERT_EQ(result.code, 0) << input << ": " << result.err;
    }
    const ReadLayer a = read_layer(from_shp), b = read_layer(from_gpkg);
    ASSERT_EQ(a.features.size(), 4u);
    ASSERT_EQ(b.features.size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_EQ(a.features[k].coordinates, b.features[k].coordinates) << k;
        EXPECT_EQ(a.features[k].null_geometry, b.features[k].null_geometry) << k;
    }
    EXPECT_EQ(a.features[1].coordinates.size(), 2u);
    EXPECT_TRUE(a.features[2].null_geometry);
}

TEST(MapCli, OverwriteIsExplicit) {
    const auto dir = fresh_dir("overwrite");
    const std::string out = (dir / "out.shp").string();
    ASSERT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--max", "-o", out}).code, 0);
    const CliResult again = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--keep", "50%", "-o", out});
    EXPECT_EQ(again.code, 2);
    EXPECT_NE(again.err.find("--overwrite"), std::string::npos);
    ASSERT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--keep", "50%", "-o", out, "--overwrite"}).code, 0);
    std::size_t vertices = 0;
    for (const auto& feature : read_layer(out).features) vertices += feature.coordinates[0].size() / 2;
    EXPECT_EQ(vertices, 496u);
    for (const auto& name : files_in(dir)) EXPECT_EQ(name.rfind("out.", 0), 0u) << "left over: " << name;
}

TEST(MapCli, GdalStyleLayerOptions) {
    const auto dir = fresh_dir("nln");
    const std::string out = (dir / "out.gpkg").string();
    const CliResult result = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--max", "-o", out, "-nln", "generalised",
                                      "-lco", "DESCRIPTION=simplified borders"});
    ASSERT_EQ(result.code, 0) << result.err;
    EXPECT_EQ(read_layer(out).name, "generalised");
}

TEST(MapCli, GiscupFormatLikeTheContestProgram) {
    const auto dir = fresh_dir("giscup");
    const std::string out = (dir / "out.txt").string();
    const std::string data = std::string(TOPOSIMP_TEST_DATA) + "/giscup14/td1/";
    const CliResult result = run_cli({"map", "--giscup", data + "lines_out.txt", "--points", data + "points_out.txt",
                                      "--remove-points", "883", "-o", out, "--json"});
    ASSERT_EQ(result.code, 0) << result.err;
    EXPECT_NE(result.out.find("\"vertices_out\":109"), std::string::npos) << result.out;
    EXPECT_TRUE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace toposimp::testing

namespace toposimp::testing {
namespace {

TEST(MapCli, WritesToStdoutForPipelines) {
    const CliResult result = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--max", "-f", "GeoJSON", "-o", "/vsistdout/", "--json"});
    ASSERT_EQ(result.code, 0) << result.err;
    EXPECT_EQ(result.out.rfind("{\n\"type\":\"FeatureCollection\"", 0), 0u) << result.out.substr(0, 80);
    EXPECT_NE(result.out.find("\"name\":\"border 1\""), std::string::npos);
    EXPECT_NE(result.err.find("\"command\":\"map\""), std::string::npos) << "the JSON summary goes to stderr";
}

}  // namespace
}  // namespace toposimp::testing

namespace toposimp::testing {
namespace {

CliResult run_cli_on_terminal(const std::vector<std::string>& args) {
    std::ostringstream out, err;
    cli::Context context{out, err, true};
    const int code = cli::run(args, context);
    return {code, out.str(), err.str()};
}

TEST(MapCli, ProgressOnATerminalOnly) {
    const auto dir = fresh_dir("progress");
    const CliResult terminal = run_cli_on_terminal({"map", testdata("nh_borders.gpkg"), "--max", "-o", (dir / "a.gpkg").string()});
    ASSERT_EQ(terminal.code, 0);
    EXPECT_NE(terminal.err.find("\r\033[Ktoposimp: simplifying"), std::string::npos) << terminal.err;
    EXPECT_NE(terminal.err.find("\r\033[Ktoposimp: writing"), std::string::npos);
    EXPECT_NE(terminal.err.find("info: 992 -> "), std::string::npos) << "summary line on a terminal";
    const CliResult quiet = run_cli_on_terminal({"map", testdata("nh_borders.gpkg"), "--max", "-q", "-o", (dir / "b.gpkg").string()});
    EXPECT_EQ(quiet.err, "");
    const CliResult pipe = run_cli({"map", testdata("nh_borders.gpkg"), "--max", "-o", (dir / "c.gpkg").string()});
    EXPECT_EQ(pipe.err.find('\r'), std::string::npos);
    EXPECT_EQ(pipe.err, "") << "silent in pipes";
}

}  // namespace
}  // namespace toposimp::testing

namespace toposimp::testing {
namespace {

// Without -l every layer is read: the points layer is written back unchanged and keeps its
// points on their side of the borders, exactly as --points would.
TEST(MapCli, AllLayersOfAGeoPackageTogether) {
    const auto dir = fresh_dir("all-layers");
    const std::string together = (dir / "together.gpkg").string(), separate = (dir / "separate.gpkg").string();
    const CliResult all = run_cli({"map", testdata("nh_borders.gpkg"), "--max", "-o", together, "--json"});
    ASSERT_EQ(all.code, 0) << all.err;
    EXPECT_NE(all.out.find("\"control_points\":26"), std::string::npos) << all.out;
    const CliResult one = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--points",
                                   testdata("nh_borders.gpkg") + ":places", "--max", "-o", separate});
    ASSERT_EQ(one.code, 0) << one.err;
    EXPECT_EQ(read_layer(together, 0).features.size(), 27u);
    EXPECT_EQ(read_layer(together, 1).name, "places");
    EXPECT_EQ(read_layer(together, 1).features.size(), 26u);
    const auto a = read_layer(together, 0), b = read_layer(separate, 0);
    for (std::size_t i = 0; i < a.features.size(); ++i) EXPECT_EQ(a.features[i].coordinates, b.features[i].coordinates);
    // A one-layer format cannot take both.
    const CliResult shp = run_cli({"map", testdata("nh_borders.gpkg"), "--max", "-o", (dir / "x.shp").string()});
    EXPECT_EQ(shp.code, 2);
    EXPECT_NE(shp.err.find("pick one with -l"), std::string::npos) << shp.err;
}

// Two polygon layers whose borders coincide (states and the countries they make up) share arcs:
// simplified together, a country border and the state borders on it stay identical.
TEST(MapCli, LayersShareBordersWithEachOther) {
    const auto dir = fresh_dir("shared-layers");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbPolygon,
                {{"POLYGON ((0 0, 1 0.1, 2 0, 2 1, 2.1 2, 2 3, 1 3.1, 0 3, 0.1 2, 0 1, 0 0))", "country"}}, "countries");
    {
        GDALDatasetUniquePtr dataset(GDALDataset::Open(input.c_str(), GDAL_OF_VECTOR | GDAL_OF_UPDATE));
        OGRLayer* states = dataset->CreateLayer("states", nullptr, wkbPolygon, nullptr);
        OGRFieldDefn name_field("name", OFTString);
        ASSERT_EQ(states->CreateField(&name_field), OGRERR_NONE);
        for (const char* wkt : {"POLYGON ((0 0, 1 0.1, 2 0, 2 1, 1 1.4, 0 1, 0 0))",
                                "POLYGON ((0 1, 1 1.4, 2 1, 2.1 2, 2 3, 1 3.1, 0 3, 0.1 2, 0 1))"}) {
            OGRFeature feature(states->GetLayerDefn());
            OGRGeometry* geometry = nullptr;
            OGRGeometryFactory::createFromWkt(wkt, nullptr, &geometry);
            feature.SetGeometryDirectly(geometry);
            ASSERT_EQ(states->CreateFeature(&feature), OGRERR_NONE);
        }
    }
    const std::string out = (dir / "out.gpkg").string();
    const CliResult result = run_cli({"map", input, "--max", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const auto country = read_layer(out, 0).features.at(0).coordinates.at(0);
    const auto states = read_layer(out, 1);
    // Every vertex of the country outline is a vertex of some state, and vice versa for the
    // states' outer vertices: the outlines coincide.
    auto contains = [](const std::vector<double>& ring, double x, double y) {
        for (std::size_t k = 0; k + 1 < ring.size(); k += 2) {
            if (ring[k] == x && ring[k + 1] == y) return true;
        }
        return false;
    };
    for (std::size_t k = 0; k + 1 < country.size(); k += 2) {
        const bool in_a_state = contains(states.features[0].coordinates[0], country[k], country[k + 1]) ||
                                contains(states.features[1].coordinates[0], country[k], country[k + 1]);
        EXPECT_TRUE(in_a_state) << country[k] << " " << country[k + 1];
    }
    EXPECT_LT(country.size(), 22u) << "the outline was simplified";
}

}  // namespace
}  // namespace toposimp::testing
