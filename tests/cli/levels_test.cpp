// --levels: one output per level from one run, each level's vertices among the level before's,
// each checked clean; the JSON summary lists the levels; a pattern without {level}, levels out of
// order and unknown levels are refused before anything is read.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>

namespace toposimp::testing {
namespace {

std::set<std::pair<double, double>> locations(const std::string& path) {
    std::set<std::pair<double, double>> out;
    for (const ReadFeature& feature : read_layer(path).features) {
        for (const auto& part : feature.coordinates) {
            for (std::size_t k = 0; k + 1 < part.size(); k += 2) out.insert({part[k], part[k + 1]});
        }
    }
    return out;
}

TEST(Levels, OneRunWritesNestedLevelsEachClean) {
    const auto dir = fresh_dir("levels");
    const std::string input = testdata("nh_borders.gpkg");
    const std::string pattern = (dir / "nh_{level}.gpkg").string();
    const CliResult map = run_cli({"map", input, "-l", "borders", "-p", input + ":places", "-o", pattern, "--levels", "60%,30%,40", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    EXPECT_EQ(map.out.rfind("{\"command\":\"map\",\"levels\":[{\"command\":\"map\"", 0), 0u) << map.out.substr(0, 200);
    const std::vector<std::string> names{"60pct", "30pct", "40"};
    std::set<std::pair<double, double>> before;
    for (std::size_t k = 0; k < names.size(); ++k) {
        const std::string out = (dir / ("nh_" + names[k] + ".gpkg")).string();
        const CliResult check = run_cli({"check", input, out, "-l", "borders", "-p", input + ":places"});
        EXPECT_EQ(check.code, 0) << names[k] << ": " << check.out;
        const std::set<std::pair<double, double>> here = locations(out);
        if (k > 0) {
            for (const auto& location : here) EXPECT_TRUE(before.count(location)) << names[k] << " has a vertex " << names[k - 1] << " lacks";
            EXPECT_LT(here.size(), before.size());
        }
        before = here;
    }
}

// All levels in one TopoJSON: the finest level's arcs, each position carrying as a third
// coordinate the number of levels that keep it, so that the positions ranked k or more are level k
// (topojson-simplify's simplify(topology, k); scripts/topojson_client.py checks that with npm's
// packages). Rounding would move the levels apart: refused.
TEST(Levels, OneTopoJsonRanksEachPositionByTheLevelsThatKeepIt) {
    const auto dir = fresh_dir("levels");
    const std::string input = testdata("ne_states_slice.gpkg"), topo = (dir / "ranked.topojson").string();
    const CliResult map = run_cli({"map", input, "--levels", "60%,30%,22%", "-o", topo, "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    std::vector<std::uint64_t> kept;
    for (std::size_t at = map.out.find("\"vertices_out\":"); at != std::string::npos; at = map.out.find("\"vertices_out\":", at + 1)) {
        kept.push_back(std::stoull(map.out.substr(at + 15)));
    }
    ASSERT_EQ(kept.size(), 3u);
    std::ifstream in(topo);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string arcs = arcs_of(text);
    std::vector<std::uint64_t> ranked(4, 0);
    const std::regex position(R"(\[-?[0-9.e+-]+,-?[0-9.e+-]+,([0-9]+)\])");
    for (auto m = std::sregex_iterator(arcs.begin(), arcs.end(), position); m != std::sregex_iterator(); ++m) {
        const int rank = std::stoi((*m)[1]);
        ASSERT_TRUE(rank >= 1 && rank <= 3) << m->str();
        for (int k = 1; k <= rank; ++k) ++ranked[k];
    }
    for (int k = 1; k <= 3; ++k) EXPECT_EQ(ranked[k], kept[k - 1]) << "level " << k;
    // Quantized, its arcs would be delta-encoded: dropping a level's positions would shift the rest.
    const CliResult quantized = run_cli({"map", input, "--levels", "60%,30%", "-o", (dir / "r.topojson").string(), "--quantize", "100000"});
    EXPECT_EQ(quantized.code, 2);
    EXPECT_NE(quantized.err.find("delta-encoded"), std::string::npos) << quantized.err;
}

// Levels on a grid: the first level rounded, the coarser ones simplified from it, so every
// level's locations are on the grid and among the level before's; each checked clean against the
// input on the grid; one ranked TopoJSON at 3 decimals too, its positions on the grid.
TEST(Levels, RoundedLevelsAreNestedToTheLocation) {
    const auto dir = fresh_dir("levels");
    const std::string input = testdata("ne_states_slice.gpkg");
    const std::string pattern = (dir / "states_{level}.geojson").string();
    const CliResult map = run_cli({"map", input, "-o", pattern, "--levels", "60%,35%,25%", "--decimals", "2", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    auto on_grid = [](double value) {
        const double scaled = value * 100;
        return std::abs(scaled - std::nearbyint(scaled)) < 1e-6;  // (the test's own rough look at the text)
    };
    std::set<std::pair<double, double>> before;
    std::size_t off = 0;
    for (const char* name : {"60pct", "35pct", "25pct"}) {
        const std::string out = (dir / ("states_" + std::string(name) + ".geojson")).string();
        const CliResult check = run_cli({"check", input, out, "--decimals", "2"});
        EXPECT_EQ(check.code, 0) << name << ": " << check.out;
        const std::set<std::pair<double, double>> here = locations(out);
        for (const auto& [x, y] : here) off += !on_grid(x) || !on_grid(y);
        if (!before.empty()) {
            for (const auto& location : here) EXPECT_TRUE(before.count(location)) << name << " has a location the level before lacks";
            EXPECT_LT(here.size(), before.size());
        }
        before = here;
    }
    // What the JSON says is off the grid is what the files hold.
    std::size_t said = 0;
    for (std::size_t at = map.out.find("\"off_grid\":"); at != std::string::npos; at = map.out.find("\"off_grid\":", at + 1)) {
        said += std::stoull(map.out.substr(at + 11));
    }
    EXPECT_EQ(off, said) << map.out;
    const std::string topo = (dir / "ranked.topojson").string();
    const CliResult ranked = run_cli({"map", input, "--levels", "50%,20%", "-o", topo, "--decimals", "3"});
    ASSERT_EQ(ranked.code, 0) << ranked.err;
    std::ifstream in(topo);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string arcs = arcs_of(text);
    const std::regex position(R"(\[(-?[0-9.e+-]+),(-?[0-9.e+-]+),([0-9]+)\])");
    std::size_t positions = 0;
    for (auto m = std::sregex_iterator(arcs.begin(), arcs.end(), position); m != std::sregex_iterator(); ++m, ++positions) {
        for (int axis = 1; axis <= 2; ++axis) {
            const std::string digits = (*m)[axis].str();
            const auto dot = digits.find('.');
            EXPECT_TRUE(dot == std::string::npos || digits.size() - dot - 1 <= 3) << m->str();
        }
    }
    EXPECT_GT(positions, 100u);
}

TEST(Levels, BadLevelsAreRefusedBeforeReading) {
    const auto dir = fresh_dir("levels");
    const std::string input = testdata("nh_borders.gpkg");
    const std::string pattern = (dir / "nh_{level}.gpkg").string();
    for (const std::vector<std::string>& bad : {std::vector<std::string>{"--levels", "20%,5%", "-o", (dir / "nh.gpkg").string()},
                                                {"--levels", "5%,20%", "-o", pattern},
                                                {"--levels", "20%,abc", "-o", pattern},
                                                {"--levels", "20%", "--keep", "5%", "-o", pattern}}) {
        std::vector<std::string> arguments{"map", input};
        arguments.insert(arguments.end(), bad.begin(), bad.end());
        const CliResult result = run_cli(arguments);
        EXPECT_EQ(result.code, 2) << bad[1];
        EXPECT_FALSE(result.err.empty());
    }
    EXPECT_TRUE(files_in(dir).empty());
}

// --weighting and --spherical order the removals only: the output still checks clean; spherical
// ranking needs longitude, latitude (NH borders are in Web Mercator: refused, naming the layer),
// and only then may --max-area carry a unit.
TEST(Ranking, WeightedAndSphericalRunsAreCleanAndUnitsNeedTheSphere) {
    const auto dir = fresh_dir("ranking");
    const std::string states = testdata("ne_states_slice.gpkg"), out = (dir / "states.gpkg").string();
    const CliResult weighted = run_cli({"map", states, "-o", out, "--keep", "20%", "--weighting", "0.7", "--spherical", "--json"});
    ASSERT_EQ(weighted.code, 0) << weighted.err;
    EXPECT_NE(weighted.out.find("\"ranking\":{\"weighting\":0.7,\"spherical\":true}"), std::string::npos) << weighted.out;
    EXPECT_EQ(run_cli({"check", states, out}).code, 0);
    const CliResult area = run_cli({"map", states, "-o", out, "--overwrite", "--max-area", "20km2", "--spherical", "--json"});
    ASSERT_EQ(area.code, 0) << area.err;
    EXPECT_NE(area.out.find("effective area <= 2e+07"), std::string::npos) << area.out;
    EXPECT_EQ(run_cli({"check", states, out}).code, 0);

    const CliResult unit = run_cli({"map", states, "-o", (dir / "u.gpkg").string(), "--max-area", "20km2"});
    EXPECT_EQ(unit.code, 2);
    EXPECT_NE(unit.err.find("--spherical"), std::string::npos) << unit.err;
    const CliResult projected = run_cli({"map", testdata("nh_borders.gpkg"), "-o", (dir / "nh.gpkg").string(), "--spherical"});
    EXPECT_EQ(projected.code, 2);
    EXPECT_NE(projected.err.find("layer 'borders'"), std::string::npos) << projected.err;
    EXPECT_EQ(run_cli({"map", states, "-o", (dir / "w.gpkg").string(), "--weighting", "1.5"}).code, 2);
    EXPECT_FALSE(std::filesystem::exists(dir / "u.gpkg") || std::filesystem::exists(dir / "nh.gpkg") || std::filesystem::exists(dir / "w.gpkg"));
}

// A Shapefile's copy of `layer` of the GeoPackage `source`, at `shp`.
void shapefile_copy(const std::string& source, const char* layer, const std::string& shp) {
    GDALAllRegister();
    GDALDatasetUniquePtr from(GDALDataset::Open(source.c_str(), GDAL_OF_VECTOR));
    GDALDataset* to = GetGDALDriverManager()->GetDriverByName("ESRI Shapefile")->Create(shp.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
    ASSERT_NE(to, nullptr);
    EXPECT_NE(to->CopyLayer(from->GetLayerByName(layer), std::filesystem::path(shp).stem().c_str()), nullptr);
    GDALClose(to);
}

// A Shapefile going to a Shapefile carries its .prj as a file, unparsed; --spherical parses it then:
// Natural Earth's polygons (longitude, latitude) are ranked on the sphere and their .prj goes to
// the output as it was; NH's borders (Web Mercator) are refused, naming the layer, nothing written.
TEST(Ranking, SphericalReadsTheCrsOfAShapefileCarriedAsAFile) {
    const auto dir = fresh_dir("ranking-shp");
    const std::string states = (dir / "states.shp").string(), borders = (dir / "borders.shp").string();
    shapefile_copy(testdata("ne_states_slice.gpkg"), "states", states);
    shapefile_copy(testdata("nh_borders.gpkg"), "borders", borders);
    const std::filesystem::path out = dir / "out";
    std::filesystem::create_directories(out);
    const CliResult spherical = run_cli({"map", states, "-o", (out / "states.shp").string(), "--keep", "20%", "--spherical", "--json"});
    ASSERT_EQ(spherical.code, 0) << spherical.err;
    EXPECT_NE(spherical.out.find("\"spherical\":true"), std::string::npos) << spherical.out;
    auto bytes = [](const std::filesystem::path& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_FALSE(bytes(dir / "states.prj").empty());
    EXPECT_EQ(bytes(out / "states.prj"), bytes(dir / "states.prj"));
    EXPECT_EQ(run_cli({"check", states, (out / "states.shp").string()}).code, 0);
    const CliResult projected = run_cli({"map", borders, "-o", (out / "borders.shp").string(), "--spherical"});
    EXPECT_EQ(projected.code, 2);
    EXPECT_NE(projected.err.find("layer 'borders' is not in a geographic CRS"), std::string::npos) << projected.err;
    EXPECT_FALSE(std::filesystem::exists(out / "borders.shp"));
}

}  // namespace
}  // namespace toposimp::testing
