// A road grid over a river network, two layers simplified together: every road keeps exactly
// its crossings with every river, and no new crossing appears anywhere.
#include "cli/cli_fixtures.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace toposimp::testing {
namespace {

// Every line of every layer of `path`, as chains (all vertices kept).
map::MapData as_map(const std::string& path) {
    map::MapData map;
    for (int layer = 0; layer < 2; ++layer) {
        for (const auto& feature : read_layer(path, layer).features) {
            std::vector<Point> points;
            for (std::size_t k = 0; k + 1 < feature.coordinates.at(0).size(); k += 2) {
                points.push_back({feature.coordinates[0][k], feature.coordinates[0][k + 1]});
            }
            map.add_chain(points);
        }
    }
    return map;
}

TEST(CrossingsCli, RoadGridOverRiversKeepsEveryCrossing) {
    const auto dir = fresh_dir("road-grid");
    const std::string input = (dir / "network.gpkg").string();
    std::vector<FeatureSpec> rivers, roads;
    for (int r = 0; r < 6; ++r) {  // meandering rivers, west to east, never touching each other
        std::vector<Point> river;
        for (int i = 0; i <= 200; ++i) {
            const double x = i * 0.5;
            river.push_back({x, 15.0 * r + 4 * std::sin(x / 3 + r) + std::sin(x * 1.7)});
        }
        rivers.push_back({line_wkt(river), "river"});
    }
    for (int q = 0; q < 9; ++q) {  // roads: a grid of slightly wavy lines with many vertices
        std::vector<Point> north, east;
        for (int i = 0; i <= 100; ++i) {
            north.push_back({10.0 * q + 3 + 0.2 * std::sin(i * 0.9), -5 + i * 0.9});
            east.push_back({-2 + i * 1.05, 10.0 * q + 2 + 0.2 * std::cos(i * 0.7)});
        }
        roads.push_back({line_wkt(north), "north"});
        roads.push_back({line_wkt(east), "east"});
    }
    write_layer(input, "GPKG", wkbLineString, rivers, "rivers");
    {
        GDALDatasetUniquePtr dataset(GDALDataset::Open(input.c_str(), GDAL_OF_VECTOR | GDAL_OF_UPDATE));
        OGRLayer* layer = dataset->CreateLayer("roads", nullptr, wkbLineString, nullptr);
        for (const auto& road : roads) {
            OGRFeature feature(layer->GetLayerDefn());
            OGRGeometry* geometry = nullptr;
            OGRGeometryFactory::createFromWkt(road.wkt.c_str(), nullptr, &geometry);
            feature.SetGeometryDirectly(geometry);
            ASSERT_EQ(layer->CreateFeature(&feature), OGRERR_NONE);
        }
    }
    const std::string out = (dir / "simple.gpkg").string();
    const CliResult result = run_cli({"map", input, "--max", "-o", out, "--json"});
    ASSERT_EQ(result.code, 0) << result.err;

    const map::MapData before = as_map(input), after = as_map(out);
    ASSERT_EQ(before.chains.size(), after.chains.size());
    const auto crossings_before = crossings_between_chains(before, std::vector<std::uint8_t>(before.vertices.size(), 1));
    const auto crossings_after = crossings_between_chains(after, std::vector<std::uint8_t>(after.vertices.size(), 1));
    std::uint64_t total = 0;
    for (const auto count : crossings_before) total += count;
    EXPECT_GT(total, 100u) << "roads should cross rivers and each other";
    EXPECT_EQ(crossings_after, crossings_before) << "a crossing was lost or added";
    EXPECT_LT(after.vertices.size() * 2, before.vertices.size()) << "the network was simplified";
}

}  // namespace
}  // namespace toposimp::testing
