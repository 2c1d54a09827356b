// Text formats and pipelines: CSV (WKT) and GML in, CSV out, GML out refused (GDAL 3.6 writes
// 15 significant digits), and a real shell pipeline through /vsistdin/ and /vsistdout/.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace toposimp::testing {
namespace {

std::size_t vertex_count(const ReadLayer& layer) {
    std::size_t n = 0;
    for (const auto& f : layer.features) {
        for (const auto& part : f.coordinates) n += part.size() / 2;
    }
    return n;
}

TEST(Formats, CsvWithWktInAndOut) {
    const auto dir = fresh_dir("csv");
    const std::string csv = (dir / "borders.csv").string();
    const CliResult first = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--keep", "50%", "-o", csv});
    ASSERT_EQ(first.code, 0) << first.err;
    const ReadLayer written = read_layer(csv);
    ASSERT_EQ(written.features.size(), 27u);
    EXPECT_EQ(vertex_count(written), 496u);
    // And back in: CSV with a WKT column is an input like any other.
    const std::string again = (dir / "again.gpkg").string();
    const CliResult second = run_cli({"map", csv, "--keep", "50%", "-o", again});
    ASSERT_EQ(second.code, 0) << second.err;
    EXPECT_EQ(vertex_count(read_layer(again)), 248u);
}

TEST(Formats, GmlInButNotOut) {
    const auto dir = fresh_dir("gml");
    const std::string gml = (dir / "in.gml").string();
    std::ofstream(gml) << R"(<?xml version="1.0" encoding="utf-8" ?>
<ogr:FeatureCollection xmlns:ogr="http://ogr.maptools.org/" xmlns:gml="http://www.opengis.net/gml">
  <gml:featureMember><ogr:roads fid="roads.0"><ogr:geometryProperty><gml:LineString>
    <gml:coordinates>-7984749.593824852,5368675.690126911 -7984392.035620423,5367570.791302501 -7983220.843257783,5366848.500158152 -7982343.534350842,5364796.5795687605</gml:coordinates>
  </gml:LineString></ogr:geometryProperty><ogr:name>one</ogr:name></ogr:roads></gml:featureMember>
</ogr:FeatureCollection>
)";
    const std::string out = (dir / "out.gpkg").string();
    const CliResult result = run_cli({"map", gml, "--max", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const ReadLayer written = read_layer(out);
    ASSERT_EQ(written.features.size(), 1u);
    EXPECT_EQ(written.features[0].coordinates[0],
              (std::vector<double>{-7984749.593824852, 5368675.690126911, -7982343.534350842, 5364796.5795687605}));
    const CliResult refused = run_cli({"map", gml, "--max", "-o", (dir / "out.gml").string()});
    EXPECT_EQ(refused.code, 2);
    EXPECT_NE(refused.err.find("the GML driver changed coordinates"), std::string::npos) << refused.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.gml"));
}

// A real pipeline: cat | toposimp … /vsistdin/ … /vsistdout/ | file.
TEST(Formats, ShellPipelineThroughStdinAndStdout) {
    const auto dir = fresh_dir("pipeline");
    const std::string geojson = (dir / "in.geojson").string();
    ASSERT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--keep", "100%", "-o", geojson}).code, 0);
    const std::string out = (dir / "out.geojson").string();
    const std::string command = "cat '" + geojson + "' | '" + TOPOSIMP_BINARY +
                                "' map /vsistdin/ -f GeoJSON -o /vsistdout/ --keep 20% --json 2>'" + (dir / "err.txt").string() +
                                "' > '" + out + "'";
    ASSERT_EQ(std::system(command.c_str()), 0);
    const ReadLayer written = read_layer(out);
    EXPECT_EQ(written.features.size(), 27u);
    EXPECT_EQ(vertex_count(written), 199u);
    std::ifstream err(dir / "err.txt");
    const std::string messages((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    EXPECT_NE(messages.find("\"vertices_out\":199"), std::string::npos) << "JSON summary on stderr: " << messages;
}

TEST(Formats, FailedPipelineWritesNothingToStdout) {
    const auto dir = fresh_dir("pipeline-fail");
    const std::string command = "echo 'not json' | '" + std::string(TOPOSIMP_BINARY) +
                                "' map /vsistdin/ -f GeoJSON -o /vsistdout/ > '" + (dir / "out.txt").string() + "' 2>/dev/null";
    const int status = std::system(command.c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2);
    EXPECT_EQ(std::filesystem::file_size(dir / "out.txt"), 0u);
}

}  // namespace
}  // namespace toposimp::testing
