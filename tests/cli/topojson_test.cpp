// TopoJSON output: one object per layer, shared borders written once as arcs used by both
// polygons (one of them reversed), points as coordinates, attributes as properties; GDAL reads
// it back with the same features and coordinates bit for bit (toposimp's own read-back checks
// that before moving the file into place; here again from outside).
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>

namespace toposimp::testing {
namespace {

std::string contents(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A ring's vertices from its first smallest (x, y) on, without the closing one: rings compared
// whatever vertex they start at (TopoJSON rings start where their first arc does).
std::vector<std::pair<double, double>> canonical_ring(const std::vector<double>& flat) {
    std::vector<std::pair<double, double>> ring;
    for (std::size_t k = 0; k + 1 < flat.size(); k += 2) ring.emplace_back(flat[k], flat[k + 1]);
    if (!ring.empty()) ring.pop_back();
    std::rotate(ring.begin(), std::min_element(ring.begin(), ring.end()), ring.end());
    return ring;
}

TEST(TopoJson, SharedBordersAreArcsWrittenOnceAndGdalReadsTheSameFeatures) {
    const auto dir = fresh_dir("topojson");
    const std::string input = testdata("ne_states_slice.gpkg");
    const std::string topo = (dir / "states.topojson").string(), gpkg = (dir / "states.gpkg").string();
    const CliResult map = run_cli({"map", input, "-o", topo, "--keep", "20%"});
    ASSERT_EQ(map.code, 0) << map.err;
    ASSERT_EQ(run_cli({"map", input, "-o", gpkg, "--keep", "20%"}).code, 0);
    const std::string text = contents(topo);
    EXPECT_EQ(text.rfind("{\"type\":\"Topology\"", 0), 0u);
    EXPECT_NE(text.find("\"bbox\":["), std::string::npos);
    EXPECT_NE(text.find("\"objects\":{\"states\":{\"type\":\"GeometryCollection\""), std::string::npos);
    // Shared borders: some arc is used forwards by one ring and backwards (~i) by another.
    std::set<long> forwards, backwards;
    const std::regex arcs(R"re("arcs":(\[[-0-9,\[\]]*\]))re");
    const std::regex number(R"(-?[0-9]+)");
    for (auto m = std::sregex_iterator(text.begin(), text.end(), arcs); m != std::sregex_iterator(); ++m) {
        const std::string list = (*m)[1];
        for (auto n = std::sregex_iterator(list.begin(), list.end(), number); n != std::sregex_iterator(); ++n) {
            const long value = std::stol(n->str());
            (value < 0 ? backwards : forwards).insert(value < 0 ? ~value : value);
        }
    }
    std::vector<long> shared;
    std::set_intersection(forwards.begin(), forwards.end(), backwards.begin(), backwards.end(), std::back_inserter(shared));
    EXPECT_GT(shared.size(), 10u);

    const ReadLayer from_topology = read_layer(topo), from_gpkg = read_layer(gpkg);
    ASSERT_EQ(from_topology.features.size(), from_gpkg.features.size());
    for (std::size_t i = 0; i < from_gpkg.features.size(); ++i) {
        const ReadFeature &a = from_topology.features[i], &b = from_gpkg.features[i];
        EXPECT_EQ(a.name, b.name);
        ASSERT_EQ(a.coordinates.size(), b.coordinates.size()) << b.name;
        for (std::size_t k = 0; k < b.coordinates.size(); ++k) {
            EXPECT_EQ(canonical_ring(a.coordinates[k]), canonical_ring(b.coordinates[k])) << b.name << " ring " << k;
        }
    }
}

TEST(TopoJson, SeveralLayersLinesPointsAndAGrid) {
    const auto dir = fresh_dir("topojson");
    const std::string input = testdata("nh_borders.gpkg"), topo = (dir / "nh.topojson").string();
    const CliResult map = run_cli({"map", input, "-o", topo, "-f", "TopoJSON", "--decimals", "1", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    const std::string text = contents(topo);
    EXPECT_NE(text.find("\"borders\":{\"type\":\"GeometryCollection\""), std::string::npos);
    EXPECT_NE(text.find("\"places\":{\"type\":\"GeometryCollection\""), std::string::npos);
    EXPECT_NE(text.find("{\"type\":\"LineString\",\"arcs\":["), std::string::npos);
    EXPECT_NE(text.find("{\"type\":\"Point\",\"coordinates\":["), std::string::npos);
    // On the grid: no position with more than one decimal (none is reported off it here).
    EXPECT_NE(map.out.find("\"off_grid\":0,"), std::string::npos) << map.out;
    EXPECT_NE(map.out.find("\"points_off_grid\":0"), std::string::npos) << map.out;
    const std::string arcs = arcs_of(text);
    EXPECT_FALSE(std::regex_search(arcs, std::regex(R"(\.[0-9]{2})"))) << arcs.substr(0, 300);
    EXPECT_EQ(read_layer(topo, 0).features.size(), 27u);
    EXPECT_EQ(read_layer(topo, 1).features.size(), 26u);
    // A file of that name is refused without --overwrite, and replaced with it (removed by
    // toposimp, not by GDAL, which would parse it whole to list its files); standard output
    // works too.
    EXPECT_EQ(run_cli({"map", input, "-o", topo, "-f", "TopoJSON"}).code, 2);
    const CliResult again = run_cli({"map", input, "-o", topo, "-f", "TopoJSON", "--decimals", "1", "--overwrite"});
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_EQ(contents(topo), text);
    EXPECT_EQ(files_in(dir), std::vector<std::string>{"nh.topojson"});
    const CliResult piped = run_cli({"map", input, "-o", "/vsistdout/", "-f", "TopoJSON"});
    ASSERT_EQ(piped.code, 0) << piped.err;
    EXPECT_EQ(piped.out.rfind("{\"type\":\"Topology\"", 0), 0u) << piped.out.substr(0, 200);
}

// --quantize N: a transform and integer, delta-encoded arcs; every position one the transform
// decodes to exactly (GDAL reads them back bit for bit, toposimp's own read-back checks that),
// and check reads the grid from the transform. A grid too coarse for the topology is refused,
// with nothing left behind; so is --quantize for anything but TopoJSON.
TEST(TopoJson, QuantizedKeepsTheTopologyOrIsRefused) {
    const auto dir = fresh_dir("topojson");
    const std::string input = testdata("ne_states_slice.gpkg"), topo = (dir / "q.topojson").string();
    const CliResult map = run_cli({"map", input, "-o", topo, "--keep", "20%", "--quantize", "10000", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    const std::string text = contents(topo);
    EXPECT_NE(text.find("\"transform\":{\"scale\":["), std::string::npos);
    const std::string arcs = arcs_of(text);
    EXPECT_FALSE(std::regex_search(arcs, std::regex(R"([0-9]\.[0-9])"))) << "arcs hold integers only";
    const CliResult check = run_cli({"check", input, topo, "--json"});
    EXPECT_EQ(check.code, 0) << check.out.substr(0, 1500);
    // Unquantized TopoJSON has no transform: checked as it is.
    const std::string plain = (dir / "plain.topojson").string();
    ASSERT_EQ(run_cli({"map", input, "-o", plain, "--keep", "20%"}).code, 0);
    EXPECT_EQ(run_cli({"check", input, plain}).code, 0);

    const CliResult coarse = run_cli({"map", input, "-o", (dir / "coarse.topojson").string(), "--keep", "20%", "--quantize", "100"});
    EXPECT_EQ(coarse.code, 2);
    EXPECT_NE(coarse.err.find("--quantize 100:"), std::string::npos) << coarse.err;
    EXPECT_NE(coarse.err.find("--quantize 1000"), std::string::npos) << coarse.err;
    const CliResult not_topology = run_cli({"map", input, "-o", (dir / "q.gpkg").string(), "--quantize", "10000"});
    EXPECT_EQ(not_topology.code, 2);
    EXPECT_NE(not_topology.err.find("TopoJSON"), std::string::npos) << not_topology.err;
    EXPECT_EQ(run_cli({"map", input, "-o", (dir / "r.topojson").string(), "--quantize", "10000", "--decimals", "3"}).code, 2);
    std::vector<std::string> files = files_in(dir);
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"plain.topojson", "q.topojson"}));
}

// Features without a geometry are written as the specification's null objects, which GDAL's
// TopoJSON reader drops: toposimp's read-back compares each feature GDAL gives back with the
// input's next one that has a geometry (it once took them for the features in order, and
// refused the file: "0 parts became 1"), and so does check (which found features lost and
// borders no longer shared). Empty geometries are written and read back empty; a
// multipolygon's EMPTY member too, which GDAL's reader leaves out and check does not count (it
// found "1 parts became 1").
TEST(TopoJson, NullAndEmptyGeometriesAreWrittenAndReadBack) {
    const auto dir = fresh_dir("topojson");
    const std::string lines = (dir / "lines.gpkg").string(), cells = (dir / "cells.gpkg").string();
    write_layer(lines, "GPKG", wkbLineString,
                {{"", "null first"},
                 {"LINESTRING (0 0, 1 0.1, 2 0, 3 0.2, 4 0)", "a"},
                 {"", "null"},
                 {"LINESTRING EMPTY", "empty"},
                 {"LINESTRING (0 1, 1 1.1, 2 1, 3 1.2, 4 1)", "b"},
                 {"", "null last"}});
    write_layer(cells, "GPKG", wkbPolygon,
                {{"POLYGON ((0 0, 1 0, 1 1, 0.5 1.1, 0 1, 0 0))", "left"},
                 {"", "null"},
                 {"POLYGON ((1 0, 2 0, 2 1, 1 1, 1 0))", "right"},
                 {"MULTIPOLYGON (((2 0, 3 0, 3 1, 2 1, 2 0)), EMPTY)", "with an empty member"},
                 {"POLYGON EMPTY", "empty"}},
                "cells");
    for (const std::string& input : {lines, cells}) {
        const std::string topo = (dir / (std::filesystem::path(input).stem().string() + ".topojson")).string();
        const CliResult map = run_cli({"map", input, "-o", topo, "--keep", "50%"});
        ASSERT_EQ(map.code, 0) << map.err;
        const std::string text = contents(topo);
        const std::size_t nulls = input == lines ? 3 : 1;
        std::size_t found = 0;
        for (std::size_t at = text.find("{\"type\":null,"); at != std::string::npos; at = text.find("{\"type\":null,", at + 1)) ++found;
        EXPECT_EQ(found, nulls) << text.substr(0, 600);
        const ReadLayer read = read_layer(topo);
        ASSERT_EQ(read.features.size(), (input == lines ? 6u : 5u) - nulls);
        const auto empty = std::find_if(read.features.begin(), read.features.end(), [](const ReadFeature& f) { return f.name == "empty"; });
        ASSERT_NE(empty, read.features.end());
        EXPECT_TRUE(empty->coordinates.empty() || empty->coordinates.front().empty());
        const CliResult check = run_cli({"check", input, topo});
        EXPECT_EQ(check.code, 0) << check.out;
    }
}

}  // namespace
}  // namespace toposimp::testing
