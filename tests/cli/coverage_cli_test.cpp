// Polygon coverages end to end on real data (Natural Earth states), checked with GEOS through
// OGR's geometry methods: valid polygons, borders still shared (no overlaps, no new gaps),
// control points in the same polygon.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <random>

namespace toposimp::testing {
namespace {

std::vector<std::unique_ptr<OGRGeometry>> geometries(const std::string& path) {
    GDALAllRegister();
    GDALDatasetUniquePtr dataset(GDALDataset::Open(path.c_str(), GDAL_OF_VECTOR));
    std::vector<std::unique_ptr<OGRGeometry>> list;
    for (auto& feature : *dataset->GetLayer(0)) list.emplace_back(feature->GetGeometryRef()->clone());
    return list;
}

double total_area(const std::vector<std::unique_ptr<OGRGeometry>>& list) {
    double area = 0;
    for (const auto& g : list) area += g->toMultiPolygon()->get_Area();
    return area;
}

// Holes of the union: a gap between neighbours would add one.
int union_holes(const std::vector<std::unique_ptr<OGRGeometry>>& list) {
    OGRMultiPolygon all;
    for (const auto& g : list) {
        for (const OGRPolygon* polygon : *g->toMultiPolygon()) all.addGeometry(polygon);
    }
    std::unique_ptr<OGRGeometry> merged(all.UnionCascaded());
    int holes = 0;
    auto count = [&](const OGRPolygon* polygon) { holes += polygon->getNumInteriorRings(); };
    if (wkbFlatten(merged->getGeometryType()) == wkbPolygon) count(merged->toPolygon());
    else for (const OGRPolygon* polygon : *merged->toMultiPolygon()) count(polygon);
    return holes;
}

int containing(const std::vector<std::unique_ptr<OGRGeometry>>& list, const OGRPoint& point) {
    for (std::size_t i = 0; i < list.size(); ++i) {
        if (list[i]->Contains(&point)) return static_cast<int>(i);
    }
    return -1;
}

TEST(CoverageCli, NaturalEarthStatesStayACoverage) {
    const auto dir = fresh_dir("coverage-ne");
    const std::string input = testdata("ne_states_slice.gpkg");
    // Control points: random points over the map, from a fixed seed.
    const std::string points = (dir / "points.gpkg").string();
    std::vector<OGRPoint> places;
    {
        std::mt19937_64 rng(2024);
        std::uniform_real_distribution<double> lon(5.9, 19.0), lat(45.8, 55.1);
        std::vector<FeatureSpec> specs;
        for (int i = 0; i < 400; ++i) {
            places.emplace_back(lon(rng), lat(rng));
            char wkt[80];
            std::snprintf(wkt, sizeof wkt, "POINT (%.17g %.17g)", places.back().getX(), places.back().getY());
            specs.push_back({wkt, "p"});
        }
        write_layer(points, "GPKG", wkbPoint, specs, "places");
    }
    const std::string out = (dir / "states_10.gpkg").string();
    const CliResult result = run_cli({"map", input, "--points", points, "--keep", "10%", "-o", out, "--json"});
    ASSERT_EQ(result.code, 0) << result.err;

    const auto before = geometries(input), after = geometries(out);
    ASSERT_EQ(before.size(), after.size());
    std::size_t vertices_before = 0, vertices_after = 0;
    for (std::size_t i = 0; i < before.size(); ++i) {
        ASSERT_TRUE(before[i]->IsValid()) << "input feature " << i;
        EXPECT_TRUE(after[i]->IsValid()) << "output feature " << i;
        for (const OGRPolygon* polygon : *before[i]->toMultiPolygon()) {
            for (const OGRLinearRing* ring : *polygon) vertices_before += ring->getNumPoints();
        }
        for (const OGRPolygon* polygon : *after[i]->toMultiPolygon()) {
            for (const OGRLinearRing* ring : *polygon) vertices_after += ring->getNumPoints();
        }
    }
    EXPECT_LT(vertices_after * 3, vertices_before) << "substantial simplification";
    // No overlaps: neighbours meet along borders only (GEOS overlay in doubles: allow rounding).
    const double area = total_area(after);
    for (std::size_t i = 0; i < after.size(); ++i) {
        for (std::size_t j = i + 1; j < after.size(); ++j) {
            OGREnvelope a, b;
            after[i]->getEnvelope(&a);
            after[j]->getEnvelope(&b);
            if (!a.Intersects(b)) continue;
            std::unique_ptr<OGRGeometry> overlap(after[i]->Intersection(after[j].get()));
            double overlap_area = 0;
            if (overlap && OGR_GT_IsSubClassOf(wkbFlatten(overlap->getGeometryType()), wkbSurface)) {
                overlap_area = overlap->toSurface()->get_Area();
            } else if (overlap && wkbFlatten(overlap->getGeometryType()) == wkbGeometryCollection) {
                for (const OGRGeometry* part : *overlap->toGeometryCollection()) {
                    if (OGR_GT_IsSubClassOf(wkbFlatten(part->getGeometryType()), wkbSurface)) overlap_area += part->toSurface()->get_Area();
                }
            } else if (overlap && wkbFlatten(overlap->getGeometryType()) == wkbMultiPolygon) {
                overlap_area = overlap->toMultiPolygon()->get_Area();
            }
            EXPECT_LE(overlap_area, 1e-12 * area) << "features " << i << " and " << j << " overlap";
        }
    }
    // No gaps: the union has as many holes as before.
    EXPECT_EQ(union_holes(after), union_holes(before));
    // Every control point is in the same state as before.
    for (const OGRPoint& place : places) {
        EXPECT_EQ(containing(after, place), containing(before, place)) << place.getX() << " " << place.getY();
    }
}

}  // namespace
}  // namespace toposimp::testing
