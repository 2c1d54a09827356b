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

// Shapefile lines to a Shapefile: the shapes are decoded from the .shp and the .prj is carried
// over byte for byte (no CRS parsing); the result is the one OGR's reading gives (the same input
// to a GeoPackage, which parses the CRS).
TEST(Formats, ShapefileLinesToShapefileKeepTheirPrjAsItIs) {
    const auto dir = fresh_dir("shp-prj");
    const std::string in = (dir / "roads.shp").string();
    std::vector<FeatureSpec> features;
    for (int i = 0; i < 40; ++i) {
        std::string wkt = "LINESTRING (";
        for (int k = 0; k < 12; ++k) {
            if (k > 0) wkt += ',';
            wkt += std::to_string(1000.0 * i + 10.0 * k + 0.1);
            wkt += ' ';
            wkt += std::to_string((k * k * 7 + i) % 13 + 0.3);
        }
        wkt += ")";
        if (i % 5 == 1) wkt = "MULTILINESTRING ((" + std::to_string(1000.0 * i) + " 500,1 2,3 4,5 7),(9 9,10 12,13 9,16 12))";
        features.push_back({i % 9 == 4 ? "" : wkt, "road " + std::to_string(i)});
    }
    write_layer(in, "ESRI Shapefile", wkbLineString, features, "roads");
    // A .prj as some tool wrote it, line end included (OGR would rewrite it on a round trip).
    const std::string prj =
        "PROJCS[\"My_UTM_33\",GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137.0,298.257223563]],"
        "PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]],PROJECTION[\"Transverse_Mercator\"],"
        "PARAMETER[\"False_Easting\",500000.0],PARAMETER[\"False_Northing\",0.0],PARAMETER[\"Central_Meridian\",15.0],"
        "PARAMETER[\"Scale_Factor\",0.9996],PARAMETER[\"Latitude_Of_Origin\",0.0],UNIT[\"Meter\",1.0]]\r\n";
    std::ofstream(dir / "roads.prj", std::ios::binary | std::ios::trunc) << prj;

    const std::string shp = (dir / "out.shp").string(), gpkg = (dir / "out.gpkg").string();
    for (const std::string& out : {shp, gpkg}) {
        const CliResult result = run_cli({"map", in, "--keep", "50%", "-o", out});
        ASSERT_EQ(result.code, 0) << result.err;
    }
    std::ifstream copied(dir / "out.prj", std::ios::binary);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(copied), {}), prj);
    const ReadLayer from_shp = read_layer(shp), from_gpkg = read_layer(gpkg);
    EXPECT_NE(from_gpkg.srs_wkt.find("Transverse_Mercator"), std::string::npos) << from_gpkg.srs_wkt;
    ASSERT_EQ(from_shp.features.size(), features.size());
    ASSERT_EQ(from_gpkg.features.size(), features.size());
    std::size_t multi = 0, null = 0;
    for (std::size_t i = 0; i < features.size(); ++i) {
        const ReadFeature &a = from_shp.features[i], &b = from_gpkg.features[i];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.rank, static_cast<int>(i));
        EXPECT_EQ(a.null_geometry, b.null_geometry) << i;
        EXPECT_EQ(a.type, b.type) << i;
        EXPECT_EQ(a.coordinates, b.coordinates) << i;
        multi += a.type == wkbMultiLineString;
        null += a.null_geometry;
    }
    EXPECT_EQ(multi, 7u);
    EXPECT_EQ(null, 4u);
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
