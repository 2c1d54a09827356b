// Each kind of bad input: a clear message naming file, layer and feature, exit 2, and no
// output file (nor temporary leftovers) in the output folder.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace toposimp::testing {
namespace {

struct Failure {
    CliResult result;
    std::filesystem::path dir;
};

void expect_clean_failure(const CliResult& result, const std::filesystem::path& dir, const std::string& message,
                          const std::vector<std::string>& allowed_files) {
    EXPECT_EQ(result.code, 2) << result.err;
    EXPECT_NE(result.err.find(message), std::string::npos) << "message was: " << result.err;
    auto files = files_in(dir);
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, allowed_files) << "output or temporary files left behind";
}

TEST(MapBadInput, MissingFile) {
    const auto dir = fresh_dir("bad-missing");
    const auto result = run_cli({"map", (dir / "nope.shp").string(), "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "nope.shp': no such file", {});
}

TEST(MapBadInput, UnknownLayerListsTheLayers) {
    const auto dir = fresh_dir("bad-layer");
    const auto result = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "rivers", "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "has no layer 'rivers' (layers: borders, places)", {});
}

TEST(MapBadInput, NotALineFile) {
    const auto dir = fresh_dir("bad-unreadable");
    std::ofstream(dir / "junk.gpkg") << "this is not a GeoPackage";
    const auto result = run_cli({"map", (dir / "junk.gpkg").string(), "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "cannot open", {"junk.gpkg"});
}

TEST(MapBadInput, CurvedGeometryNamesTheFeature) {
    const auto dir = fresh_dir("bad-curves");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbCircularString, {{"CIRCULARSTRING (0 0, 1 1, 2 0)", "arc"}}, "arcs");
    const auto result = run_cli({"map", input, "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "layer 'arcs', feature 1: geometry is Circular String", {"in.gpkg"});
    EXPECT_NE(result.err.find("CONVERT_TO_LINEAR"), std::string::npos);
}

TEST(MapBadInput, GeometryCollectionNamesTheFeature) {
    const auto dir = fresh_dir("bad-collection");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbUnknown,
                {{"LINESTRING (0 0, 1 1, 2 0)", "fine"}, {"GEOMETRYCOLLECTION (POINT (0 0), LINESTRING (0 0, 1 1))", "mixed"}}, "things");
    const auto result = run_cli({"map", input, "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "layer 'things', feature 2: geometry is Geometry Collection", {"in.gpkg"});
}

TEST(MapBadInput, OnlyEmptyGeometries) {
    const auto dir = fresh_dir("bad-empty");
    const std::string input = (dir / "in.gpkg").string();
    write_layer(input, "GPKG", wkbLineString, {{"", "null"}, {"LINESTRING EMPTY", "empty"}});
    const auto result = run_cli({"map", input, "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "has no line or polygon geometry", {"in.gpkg"});
}

TEST(MapBadInput, ControlPointsLayerWithLines) {
    const auto dir = fresh_dir("bad-points");
    const auto result = run_cli({"map", testdata("nh_borders.gpkg"), "--points", testdata("nh_borders.gpkg") + ":borders",
                                 "-o", (dir / "out.gpkg").string()});
    expect_clean_failure(result, dir, "control points must be Point or MultiPoint, not Line String", {});
}

TEST(MapBadInput, NonFiniteCoordinates) {
    // GDAL's GeoJSON reader accepts NaN and 1e999 (→ infinity); binary writers refuse them.
    for (const char* bad : {"NaN", "1e999"}) {
        const auto dir = fresh_dir("bad-nan");
        std::ofstream(dir / "in.geojson")
            << R"({"type":"FeatureCollection","name":"roads","features":[{"type":"Feature","properties":{},)"
            << R"("geometry":{"type":"LineString","coordinates":[[0,0],[)" << bad << R"(,1],[2,0]]}}]})";
        const auto result = run_cli({"map", (dir / "in.geojson").string(), "-o", (dir / "out.gpkg").string()});
        expect_clean_failure(result, dir, "layer 'roads', feature 0: vertex 1 has a non-finite coordinate", {"in.geojson"});
    }
}

TEST(MapBadInput, OutputFolderMissingOrFormatUnknown) {
    const auto dir = fresh_dir("bad-output");
    // Each fails before the input is read (no progress phase starts).
    auto result = run_cli({"map", testdata("nh_borders.gpkg"), "-o", (dir / "no/such/dir/out.gpkg").string(), "--progress"});
    expect_clean_failure(result, dir, "does not exist", {});
    EXPECT_EQ(result.err.find("PROGRESS"), std::string::npos) << result.err;
    result = run_cli({"map", testdata("nh_borders.gpkg"), "-o", (dir / "out.xyz").string(), "--progress"});
    expect_clean_failure(result, dir, "cannot tell the output format", {});
    EXPECT_EQ(result.err.find("PROGRESS"), std::string::npos) << result.err;
    result = run_cli({"map", testdata("nh_borders.gpkg"), "-f", "NoSuchDriver", "-o", (dir / "out.x").string()});
    expect_clean_failure(result, dir, "unknown vector output format 'NoSuchDriver'", {});
}

TEST(MapBadInput, ShapefileCannotGoToStdout) {
    const auto dir = fresh_dir("bad-stdout");
    const auto result = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "-f", "ESRI Shapefile", "-o", "/vsistdout/"});
    expect_clean_failure(result, dir, "cannot go to stdout", {});
    EXPECT_TRUE(result.out.empty());
}

TEST(MapBadInput, MalformedGiscupFile) {
    const auto dir = fresh_dir("bad-giscup");
    std::ofstream(dir / "lines.txt") << "1:<gml:LineString><gml:coordinates>0,0 1,1 2,zero </gml:coordinates></gml:LineString>\n";
    const auto result = run_cli({"map", "--giscup", (dir / "lines.txt").string(), "-o", (dir / "out.txt").string()});
    expect_clean_failure(result, dir, "lines.txt:1: feature 1: bad coordinate '2,zero'", {"lines.txt"});
}

}  // namespace
}  // namespace toposimp::testing
