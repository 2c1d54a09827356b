// Messy input: each kind gets its documented behaviour (README, man page), never a crash.
#include "cli/cli_fixtures.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace toposimp::testing {
namespace {

const char* kMessy = R"({"type":"FeatureCollection","name":"messy","features":[
{"type":"Feature","properties":{"name":"unclosed"},"geometry":{"type":"Polygon","coordinates":[[[0,0],[4,0],[4.1,2],[4,4],[0,4]]]}},
{"type":"Feature","properties":{"name":"bowtie"},"geometry":{"type":"Polygon","coordinates":[[[10,0],[11,0.1],[12,0],[12,2],[11,1.9],[10,2],[12,0.5],[10,0]]]}},
{"type":"Feature","properties":{"name":"spike"},"geometry":{"type":"Polygon","coordinates":[[[20,0],[22,0],[22,0],[22,1],[23,1.5],[22,1],[22,2],[20,2],[20,0]]]}},
{"type":"Feature","properties":{"name":"flat"},"geometry":{"type":"Polygon","coordinates":[[[30,0],[31,0],[32,0],[30,0]]]}},
{"type":"Feature","properties":{"name":"line"},"geometry":{"type":"LineString","coordinates":[[0,10],[1,10.1],[2,10],[3,10.2],[4,10]]}},
{"type":"Feature","properties":{"name":"point"},"geometry":{"type":"Point","coordinates":[1,10.05]}},
{"type":"Feature","properties":{"name":"null"},"geometry":null}
]})";

class MessyInput : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fresh_dir("messy");
        std::ofstream(dir_ / "messy.geojson") << kMessy;
        const std::string out = (dir_ / "out.gpkg").string();
        result_ = run_cli({"map", (dir_ / "messy.geojson").string(), "--max", "-v", "-o", out});
        ASSERT_EQ(result_.code, 0) << result_.err;
        layer_ = read_layer(out);
        ASSERT_EQ(layer_.features.size(), 7u);
    }

    const ReadFeature& feature(const std::string& name) const {
        for (const auto& f : layer_.features) {
            if (f.name == name) return f;
        }
        throw std::runtime_error("no feature " + name);
    }

    static bool has(const ReadFeature& f, double x, double y) {
        for (const auto& part : f.coordinates) {
            for (std::size_t k = 0; k + 1 < part.size(); k += 2) {
                if (part[k] == x && part[k + 1] == y) return true;
            }
        }
        return false;
    }

    std::filesystem::path dir_;
    CliResult result_;
    ReadLayer layer_;
};

TEST_F(MessyInput, FeatureOrderAndMixedTypesKept) {
    const std::vector<std::string> names{"unclosed", "bowtie", "spike", "flat", "line", "point", "null"};
    for (std::size_t i = 0; i < names.size(); ++i) EXPECT_EQ(layer_.features[i].name, names[i]);
    EXPECT_EQ(wkbFlatten(feature("line").type), wkbLineString);
    EXPECT_EQ(wkbFlatten(feature("unclosed").type), wkbPolygon);
    EXPECT_EQ(wkbFlatten(feature("point").type), wkbPoint);
    EXPECT_TRUE(feature("null").null_geometry);
}

TEST_F(MessyInput, UnclosedRingIsClosed) {
    const auto& ring = feature("unclosed").coordinates.at(0);
    ASSERT_GE(ring.size(), 8u);
    EXPECT_EQ(ring[0], ring[ring.size() - 2]);
    EXPECT_EQ(ring[1], ring[ring.size() - 1]);
}

TEST_F(MessyInput, SelfIntersectingRingKeepsItsDefectAndNothingWorse) {
    // (10,2)–(12,0.5) ends on the edge (12,0)–(12,2): those vertices stay; the rest may go.
    const auto& bowtie = feature("bowtie");
    for (const auto& [x, y] : std::vector<std::pair<double, double>>{{10, 2}, {12, 0.5}, {12, 0}, {12, 2}}) {
        EXPECT_TRUE(has(bowtie, x, y)) << x << " " << y;
    }
    EXPECT_FALSE(has(bowtie, 11, 0.1));
}

TEST_F(MessyInput, SpikeStaysAndDuplicatesGo) {
    const auto& ring = feature("spike").coordinates.at(0);
    EXPECT_TRUE(has(feature("spike"), 23, 1.5)) << "a spike is part of the input's shape";
    for (std::size_t k = 2; k < ring.size(); k += 2) {
        EXPECT_FALSE(ring[k] == ring[k - 2] && ring[k + 1] == ring[k - 1]) << "consecutive duplicate at " << k / 2;
    }
}

TEST_F(MessyInput, ZeroAreaRingWrittenUnchanged) {
    EXPECT_EQ(feature("flat").coordinates.at(0), (std::vector<double>{30, 0, 31, 0, 32, 0, 30, 0}));
    EXPECT_NE(result_.err.find("1 polygon rings with fewer than 3 corners or no area are written unchanged"), std::string::npos)
        << result_.err;
}

TEST_F(MessyInput, PointFeaturesActAsControlPoints) {
    // (1, 10.05) is below the line (which passes (1, 10.1)); it must stay below. A naive pass
    // removing (1, 10.1) first would leave it above the segment (0, 10)–(2, 10).
    const auto& line = feature("line").coordinates.at(0);
    const Point p{1, 10.05};
    bool checked = false;
    for (std::size_t k = 0; k + 3 < line.size(); k += 2) {
        const Point a{line[k], line[k + 1]}, b{line[k + 2], line[k + 3]};
        if (a.x <= p.x && p.x <= b.x) {
            EXPECT_LT(exact_orient(a, b, p), 0) << "the point must stay right of (below) the line";
            checked = true;
        }
    }
    EXPECT_TRUE(checked);
    EXPECT_NE(result_.err.find("1 point features are written unchanged"), std::string::npos) << result_.err;
}

// Many tiny features and one large ring: nothing is lost, every ring keeps 3 corners.
TEST(MessyScale, ManyTinyFeaturesAndOneLargeRing) {
    const auto dir = fresh_dir("messy-scale");
    const std::string input = (dir / "in.gpkg").string();
    std::vector<FeatureSpec> specs;
    for (int i = 0; i < 2000; ++i) {
        const double x = (i % 50) * 3.0, y = (i / 50) * 3.0;
        char wkt[200];
        std::snprintf(wkt, sizeof wkt, "POLYGON ((%g %g, %g %g, %g %g, %g %g, %g %g))", x, y, x + 1, y, x + 1.5, y + 0.5, x + 1, y + 1, x, y);
        specs.push_back({wkt, "tiny"});
    }
    std::string big = "POLYGON ((";
    const int n = 100000;
    for (int i = 0; i <= n; ++i) {
        const double angle = 2 * M_PI * (i % n) / n, r = 1000 + (i % 7);
        char point[64];
        std::snprintf(point, sizeof point, "%s%.17g %.17g", i ? ", " : "", 75 + r * std::cos(angle), 60 + r * std::sin(angle));
        big += point;
    }
    specs.push_back({big + "))", "large"});
    write_layer(input, "GPKG", wkbPolygon, specs, "parcels");
    const std::string out = (dir / "out.gpkg").string();
    const CliResult result = run_cli({"map", input, "--keep", "5%", "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const ReadLayer written = read_layer(out);
    ASSERT_EQ(written.features.size(), specs.size());
    for (const auto& f : written.features) {
        ASSERT_EQ(f.coordinates.size(), 1u);
        EXPECT_GE(f.coordinates[0].size(), 8u);
    }
    EXPECT_LT(written.features.back().coordinates[0].size(), 2u * n / 10);
}

}  // namespace
}  // namespace toposimp::testing
