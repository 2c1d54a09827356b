// `toposimp check` on hand-made broken simplifications: one per kind of violation, each found
// with the right count and place; a clean simplification passes.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <random>

namespace toposimp::testing {
namespace {

struct Case {
    std::filesystem::path dir;
    std::string original, simplified;
};

// Writes the original and simplified layers ("lines", fields name/rank) as two GeoPackages.
Case make_case(const std::string& name, OGRwkbGeometryType type, const std::vector<std::string>& before,
               const std::vector<std::string>& after) {
    Case c{fresh_dir("check-" + name), {}, {}};
    c.original = (c.dir / "original.gpkg").string();
    c.simplified = (c.dir / "simplified.gpkg").string();
    auto specs = [](const std::vector<std::string>& wkts) {
        std::vector<FeatureSpec> list;
        for (const auto& wkt : wkts) list.push_back({wkt, "f"});
        return list;
    };
    write_layer(c.original, "GPKG", type, specs(before));
    write_layer(c.simplified, "GPKG", type, specs(after));
    return c;
}

// Runs check with --json and returns (exit code, count of `kind`, the JSON).
struct Checked {
    int code;
    int count;
    std::string json;
};

Checked run_check(const Case& c, const std::string& kind, std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"check", c.original, c.simplified, "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult result = run_cli(args);
    const std::string needle = "\"" + kind + "\":";
    const auto at = result.out.find(needle);
    const int count = at == std::string::npos ? -1 : std::stoi(result.out.substr(at + needle.size()));
    return {result.code, count, result.out + result.err};
}

const std::string kZigzag = "LINESTRING (0 0, 1 1, 2 0, 3 1, 4 0)";

TEST(CheckCli, CleanSimplificationPasses) {
    const Case c = make_case("clean", wkbLineString, {kZigzag, "LINESTRING (0 3, 1 2.5, 2 3, 3 2.5, 4 3)"},
                             {"LINESTRING (0 0, 4 0)", "LINESTRING (0 3, 2 3, 4 3)"});
    const Checked checked = run_check(c, "new_crossing");
    EXPECT_EQ(checked.code, 0) << checked.json;
    EXPECT_NE(checked.json.find("\"clean\":true"), std::string::npos);
}

// A simplified layer saved under another name in a dataset with several layers (as QGIS may
// save it): --simplified-layer names it; without it the layers cannot be matched.
TEST(CheckCli, SimplifiedLayerNamedExplicitly) {
    const Case c = make_case("renamed", wkbLineString, {kZigzag}, {kZigzag});
    const std::string other = (c.dir / "two_layers.gpkg").string();
    write_layer(other, "GPKG", wkbLineString, {{"LINESTRING (0 0, 1 1, 2 0, 3 5, 4 0)", "f"}}, "simplified");
    {
        // A second layer that a by-name match would not find either.
        GDALDataset* dataset = GDALDataset::Open(other.c_str(), GDAL_OF_VECTOR | GDAL_OF_UPDATE);
        ASSERT_NE(dataset, nullptr);
        dataset->CreateLayer("notes", nullptr, wkbPoint, nullptr);
        GDALClose(dataset);
    }
    const CliResult unmatched = run_cli({"check", c.original, other, "--json"});
    EXPECT_EQ(unmatched.code, 2) << unmatched.out << unmatched.err;
    EXPECT_NE(unmatched.err.find("has no layer 'lines'"), std::string::npos) << unmatched.err;
    const Checked named = run_check({c.dir, c.original, other}, "not_subset", {"-l", "lines", "--simplified-layer", "simplified"});
    EXPECT_EQ(named.code, 1) << named.json;
    EXPECT_EQ(named.count, 1) << named.json;  // (3 5) is not an input vertex
    // The original has one layer, so -l may be left out.
    const Checked short_form = run_check({c.dir, c.original, other}, "not_subset", {"-L", "simplified"});
    EXPECT_EQ(short_form.count, 1) << short_form.json;
}

TEST(CheckCli, FeatureLost) {
    const Case c = make_case("lost", wkbLineString, {kZigzag, "LINESTRING (0 3, 4 3)"}, {"LINESTRING (0 0, 4 0)", ""});
    const Checked checked = run_check(c, "feature_lost");
    EXPECT_EQ(checked.code, 1);
    EXPECT_EQ(checked.count, 1) << checked.json;
    EXPECT_NE(checked.json.find("\"feature\":\"1\""), std::string::npos);
}

TEST(CheckCli, PartsChanged) {
    const Case c = make_case("parts", wkbMultiLineString, {"MULTILINESTRING ((0 0, 1 1, 2 0), (5 5, 6 6))"},
                             {"MULTILINESTRING ((0 0, 2 0))"});
    EXPECT_EQ(run_check(c, "parts_changed").count, 1);
}

TEST(CheckCli, MovedVertexIsNotASubset) {
    const Case c = make_case("subset", wkbLineString, {kZigzag}, {"LINESTRING (0 0, 2 0.5, 4 0)"});
    const Checked checked = run_check(c, "not_subset");
    EXPECT_EQ(checked.count, 1) << checked.json;
}

TEST(CheckCli, NewCrossingsFoundWhereTheyAre) {
    // The second line dips to (2, 0.5) between the zigzag's peaks; cutting the valley (2, 0)
    // makes the segment (1,1)–(3,1) cross the dip twice.
    const Case c = make_case("crossing", wkbLineString, {kZigzag, "LINESTRING (0 3, 1 3, 2 0.5, 3 3, 4 3)"},
                             {"LINESTRING (0 0, 1 1, 3 1, 4 0)", "LINESTRING (0 3, 1 3, 2 0.5, 3 3, 4 3)"});
    const Checked checked = run_check(c, "new_crossing");
    EXPECT_EQ(checked.code, 1);
    EXPECT_EQ(checked.count, 1) << "one pair of lines" << checked.json;
    EXPECT_NE(checked.json.find("0 before, 2 after"), std::string::npos) << checked.json;
    EXPECT_NE(checked.json.find("\"y\":1"), std::string::npos) << "located on y = 1: " << checked.json;
}

TEST(CheckCli, LostCrossing) {
    const Case c = make_case("lost-crossing", wkbLineString, {kZigzag, "LINESTRING (1.5 2, 1.5 0.2)"},
                             {"LINESTRING (0 0, 4 0)", "LINESTRING (1.5 2, 1.5 0.2)"});
    EXPECT_EQ(run_check(c, "lost_crossing").count, 1);
}

TEST(CheckCli, NewTouching) {
    // A line ending at (1, 0): the straightened zigzag runs through that end.
    const Case c = make_case("touching", wkbLineString, {kZigzag, "LINESTRING (1 -1, 1 0)"},
                             {"LINESTRING (0 0, 2 0, 4 0)", "LINESTRING (1 -1, 1 0)"});
    EXPECT_EQ(run_check(c, "new_touching").count, 1);
}

TEST(CheckCli, LinesBecomingCoincident) {
    const Case c = make_case("coincident", wkbLineString, {"LINESTRING (0 10, 1 11, 2 10)", "LINESTRING (0 10, 2 10)"},
                             {"LINESTRING (0 10, 2 10)", "LINESTRING (0 10, 2 10)"});
    EXPECT_EQ(run_check(c, "new_coincidence").count, 1);
}

TEST(CheckCli, BorderNoLongerShared) {
    const Case c = make_case("border", wkbPolygon,
                             {"POLYGON ((0 0, 1 0, 1.2 1, 1 2, 0 2, 0 0))", "POLYGON ((1 0, 2 0, 2 2, 1 2, 1.2 1, 1 0))"},
                             {"POLYGON ((0 0, 1 0, 1 2, 0 2, 0 0))", "POLYGON ((1 0, 2 0, 2 2, 1 2, 1.2 1, 1 0))"});
    const Checked checked = run_check(c, "border_no_longer_shared");
    EXPECT_EQ(checked.count, 1) << checked.json;
    EXPECT_EQ(checked.code, 1);
}

TEST(CheckCli, RingCollapsed) {
    const Case c = make_case("collapsed", wkbPolygon, {"POLYGON ((0 0, 2 0, 2 2, 0 2, 0 0))"}, {"POLYGON ((0 0, 2 0, 0 0))"});
    EXPECT_EQ(run_check(c, "ring_collapsed").count, 1);
}

TEST(CheckCli, RingFlipped) {
    // A U-shape, counter-clockwise; three of its corners in the same cyclic order turn clockwise.
    const Case c = make_case("flipped", wkbPolygon, {"POLYGON ((0 0, 4 0, 4 4, 3 4, 3 1, 1 1, 1 4, 0 4, 0 0))"},
                             {"POLYGON ((4 4, 3 1, 1 4, 4 4))"});
    EXPECT_EQ(run_check(c, "ring_flipped").count, 1);
}

// A valid star whose vertex subset is self-intersecting: found by search, from a fixed seed.
TEST(CheckCli, InvalidPolygonByGeos) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> radius(0.2, 1.0);
    for (int attempt = 0; attempt < 2000; ++attempt) {
        const int n = 12;
        std::vector<std::pair<double, double>> star;
        for (int i = 0; i < n; ++i) {
            const double angle = 2 * M_PI * i / n, r = radius(rng);
            star.emplace_back(r * std::cos(angle), r * std::sin(angle));
        }
        std::vector<int> keep;
        for (int i = 0; i < n; ++i) {
            if (rng() % 3 == 0) keep.push_back(i);
        }
        if (keep.size() < 4) continue;
        auto ring = [&](const std::vector<int>& ids) {
            std::string wkt = "POLYGON ((";
            for (std::size_t k = 0; k <= ids.size(); ++k) {
                char p[64];
                std::snprintf(p, sizeof p, "%s%.17g %.17g", k ? ", " : "", star[ids[k % ids.size()]].first, star[ids[k % ids.size()]].second);
                wkt += p;
            }
            return wkt + "))";
        };
        std::vector<int> all(n);
        for (int i = 0; i < n; ++i) all[i] = i;
        OGRGeometry* simplified = nullptr;
        const std::string simplified_wkt = ring(keep);
        OGRGeometryFactory::createFromWkt(simplified_wkt.c_str(), nullptr, &simplified);
        const bool invalid = !simplified->IsValid();
        OGRGeometryFactory::destroyGeometry(simplified);
        if (!invalid) continue;
        const Case c = make_case("invalid", wkbPolygon, {ring(all)}, {simplified_wkt});
        const Checked checked = run_check(c, "invalid_polygon");
        EXPECT_EQ(checked.count, 1) << checked.json;
        EXPECT_NE(checked.json.find("\"decided_by\":\"GEOS\""), std::string::npos);
        return;
    }
    FAIL() << "no invalid subset found";
}

// GEOS judges polygons from the rings the check keeps (not from a copy of each geometry): the
// same reasons and places as GEOS gives for the geometries OGR reads — a bow tie, overlapping
// members of a multipolygon, a hole outside its shell, a ring of three points, a ring left open
// — and an original that is invalid already is counted, not reported.
TEST(CheckCli, PolygonValidityFromTheKeptRings) {
    auto square = [](int x) {
        return "POLYGON ((" + std::to_string(x) + " 0, " + std::to_string(x + 4) + " 0, " + std::to_string(x + 4) + " 4, " +
               std::to_string(x) + " 4, " + std::to_string(x) + " 0))";
    };
    const Case c = make_case(
        "validity", wkbUnknown,
        {square(0), "MULTIPOLYGON (((10 0, 14 0, 14 4, 12 5, 10 4, 10 0)), ((20 0, 24 0, 24 4, 20 4, 20 0)))",
         "POLYGON ((30 0, 34 0, 34 4, 32 5, 30 4, 30 0), (31 1, 33 1, 33 3, 31 3, 31 1))", square(40), square(50),
         "POLYGON ((60 0, 64 4, 64 0, 60 4, 60 0))"},
        {"POLYGON ((0 0, 4 4, 4 0, 0 4, 0 0))", "MULTIPOLYGON (((10 0, 14 0, 14 4, 10 4, 10 0)), ((12 0, 24 0, 24 4, 12 4, 12 0)))",
         "POLYGON ((30 0, 34 0, 34 4, 30 4, 30 0), (35 1, 36 1, 36 2, 35 2, 35 1))", "POLYGON ((40 0, 44 0, 40 0))",
         "POLYGON ((50 0, 54 0, 54 4, 50 4))", "POLYGON ((60 0, 64 4, 64 0, 60 0))"});
    const Checked checked = run_check(c, "invalid_polygon");
    EXPECT_EQ(checked.count, 5) << checked.json;
    for (const char* expected : {"\"feature\":\"0\",\"other\":\"\",\"x\":2,\"y\":2,\"detail\":\"Self-intersection\"",
                                 "\"feature\":\"1\",\"other\":\"\",\"x\":14,\"y\":0,\"detail\":\"Self-intersection\"",
                                 "\"feature\":\"2\",\"other\":\"\",\"x\":35,\"y\":1,\"detail\":\"Hole lies outside shell\"",
                                 "\"feature\":\"3\",\"other\":\"\",\"x\":40,\"y\":0,\"detail\":\"Too few points in geometry component\"",
                                 "\"feature\":\"4\",\"other\":\"\",\"x\":0,\"y\":0,\"detail\":\"GEOS cannot read the geometry\""}) {
        EXPECT_NE(checked.json.find(expected), std::string::npos) << expected << " in " << checked.json;
    }
    EXPECT_NE(checked.json.find("\"invalid_in_original\":1"), std::string::npos) << checked.json;
}

TEST(CheckCli, ControlPointChangedPolygonAndSide) {
    const Case c = make_case("points", wkbPolygon,
                             {"POLYGON ((0 0, 1 0, 1.3 1, 1 2, 0 2, 0 0))", "POLYGON ((1 0, 2 0, 2 2, 1 2, 1.3 1, 1 0))"},
                             {"POLYGON ((0 0, 1 0, 1 2, 0 2, 0 0))", "POLYGON ((1 0, 2 0, 2 2, 1 2, 1 0))"});
    const std::string points = (c.dir / "points.gpkg").string();
    write_layer(points, "GPKG", wkbPoint, {{"POINT (1.1 1)", "moved"}, {"POINT (0.5 1)", "fine"}}, "places");
    const Checked checked = run_check(c, "point_changed_polygon", {"--points", points});
    EXPECT_EQ(checked.count, 2) << "left lost it, right gained it: " << checked.json;
    EXPECT_NE(checked.json.find("\"x\":1.1"), std::string::npos);

    const Case lines = make_case("side", wkbLineString, {kZigzag}, {"LINESTRING (0 0, 4 0)"});
    const std::string below = (lines.dir / "points.gpkg").string();
    write_layer(below, "GPKG", wkbPoint, {{"POINT (1 0.5)", "swept"}, {"POINT (2 -1)", "fine"}}, "places");
    const Checked side = run_check(lines, "point_changed_side", {"--points", below});
    EXPECT_EQ(side.count, 1) << side.json;
}

// Long detours and rings with many control points in them are located through an index
// (exact::RingLocator; before it, a coastline a peer had cut down to a quadrilateral took hours
// to check against 10 M points): the same counts. A 200-tooth zigzag line simplified to its
// ends sweeps the point under the middle of each of its 400 segments and none above them; a
// square whose top is such a zigzag, cut back to the square, loses the point under each.
TEST(CheckCli, ControlPointsInLongDetoursAndRings) {
    constexpr int kTeeth = 200;
    std::string zigzag = "LINESTRING (", top;
    std::vector<FeatureSpec> line_points, ring_points;
    for (int k = 0; k <= 2 * kTeeth; ++k) zigzag += (k ? ", " : "") + std::to_string(k) + " " + std::to_string(k % 2);
    zigzag += ")";
    for (int k = 2 * kTeeth; k >= 0; --k) top += ", " + std::to_string(k) + " " + std::to_string(2 + k % 2);
    for (int k = 0; k < 2 * kTeeth; ++k) {
        const std::string x = std::to_string(k) + ".5";
        line_points.push_back({"POINT (" + x + " 0.25)", "swept"});   // under the zigzag's segment
        line_points.push_back({"POINT (" + x + " 0.75)", "above"});   // above it: outside the detour
        ring_points.push_back({"POINT (" + x + " 2.25)", "lost"});    // under the top: inside, then outside
        ring_points.push_back({"POINT (" + x + " 1)", "inside"});     // inside both
    }
    const std::string n = std::to_string(2 * kTeeth);
    const Case lines = make_case("long-detour", wkbLineString, {zigzag}, {"LINESTRING (0 0, " + n + " 0)"});
    const std::string line_file = (lines.dir / "points.gpkg").string();
    write_layer(line_file, "GPKG", wkbPoint, line_points, "places");
    const Checked side = run_check(lines, "point_changed_side", {"--points", line_file});
    EXPECT_EQ(side.count, 2 * kTeeth) << side.json.substr(0, 2000);

    const Case polygons = make_case("long-ring", wkbPolygon, {"POLYGON ((0 0, " + n + " 0" + top + ", 0 0))"},
                                    {"POLYGON ((0 0, " + n + " 0, " + n + " 2, 0 2, 0 0))"});
    const std::string ring_file = (polygons.dir / "points.gpkg").string();
    write_layer(ring_file, "GPKG", wkbPoint, ring_points, "places");
    const Checked moved = run_check(polygons, "point_changed_polygon", {"--points", ring_file});
    EXPECT_EQ(moved.count, 2 * kTeeth) << moved.json.substr(0, 2000);
}

TEST(CheckCli, GeoJsonErrorsAndTable) {
    const Case c = make_case("outputs", wkbLineString, {kZigzag, "LINESTRING (0 3, 1 3, 2 0.5, 3 3, 4 3)"},
                             {"LINESTRING (0 0, 1 1, 3 1, 4 0)", "LINESTRING (0 3, 1 3, 2 0.5, 3 3, 4 3)"});
    const std::string errors = (c.dir / "errors.geojson").string();
    const CliResult table = run_cli({"check", c.original, c.simplified, "--geojson-errors", errors});
    EXPECT_EQ(table.code, 1);
    EXPECT_NE(table.out.find("new_crossing"), std::string::npos) << table.out;
    const ReadLayer points = read_layer(errors);
    ASSERT_EQ(points.features.size(), 1u);
    EXPECT_EQ(run_cli({"check", c.original, (c.dir / "missing.gpkg").string()}).code, 2);
}

}  // namespace
}  // namespace toposimp::testing

namespace toposimp::testing {
namespace {

// A naive Visvalingam–Whyatt pass (each line on its own, no topology rules) to 10% of the
// vertices of the NH borders: check finds what it broke; toposimp's own output at the same
// target is clean.
TEST(CheckCli, FindsTheErrorsOfANaiveVisvalingamPass) {
    const auto dir = fresh_dir("naive-vw");
    GDALAllRegister();
    GDALDatasetUniquePtr source(GDALDataset::Open(testdata("nh_borders.gpkg").c_str(), GDAL_OF_VECTOR));
    const std::string naive = (dir / "naive.gpkg").string();
    {
        GDALDatasetUniquePtr out(GetGDALDriverManager()->GetDriverByName("GPKG")->Create(naive.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
        OGRLayer* in = source->GetLayerByName("borders");
        OGRLayer* layer = out->CreateLayer("borders", in->GetSpatialRef(), wkbLineString, nullptr);
        for (auto& feature : *in) {
            const OGRLineString* line = feature->GetGeometryRef()->toLineString();
            std::vector<std::pair<double, double>> points;
            for (int i = 0; i < line->getNumPoints(); ++i) points.emplace_back(line->getX(i), line->getY(i));
            const std::size_t keep = std::max<std::size_t>(2, points.size() / 10);
            while (points.size() > keep) {  // drop the smallest effective area, again and again
                std::size_t best = 1;
                double smallest = INFINITY;
                for (std::size_t i = 1; i + 1 < points.size(); ++i) {
                    const auto [ax, ay] = points[i - 1];
                    const auto [bx, by] = points[i];
                    const auto [cx, cy] = points[i + 1];
                    const double area = std::fabs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax));
                    if (area < smallest) smallest = area, best = i;
                }
                points.erase(points.begin() + static_cast<std::ptrdiff_t>(best));
            }
            OGRLineString simplified;
            for (const auto& [x, y] : points) simplified.addPoint(x, y);
            OGRFeature copy(layer->GetLayerDefn());
            copy.SetGeometry(&simplified);
            ASSERT_EQ(layer->CreateFeature(&copy), OGRERR_NONE);
        }
    }
    const std::string places = testdata("nh_borders.gpkg") + ":places";
    const CliResult naive_check = run_cli({"check", testdata("nh_borders.gpkg"), naive, "-l", "borders", "-p", places, "--json"});
    EXPECT_EQ(naive_check.code, 1) << naive_check.out << naive_check.err;
    // At 10% the naive pass moves border lines over places (and would cross lines at lower targets).
    EXPECT_EQ(naive_check.out.find("\"point_changed_side\":0"), std::string::npos) << naive_check.out;
    EXPECT_NE(naive_check.out.find("\"clean\":false"), std::string::npos);

    const std::string ours = (dir / "ours.gpkg").string();
    ASSERT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "-p", places, "--keep", "10%", "-o", ours}).code, 0);
    const CliResult our_check = run_cli({"check", testdata("nh_borders.gpkg"), ours, "-l", "borders", "-p", places});
    EXPECT_EQ(our_check.code, 0) << our_check.out;
}

// map --validate: a run that breaks topology (the unsafe float mode on a point TopoVW
// misjudges) ends with exit 1 and no output; a safe run writes its output.
TEST(CheckCli, MapValidateRefusesToWriteABrokenResult) {
    const auto dir = fresh_dir("validate");
    const std::string input = (dir / "in.gpkg").string(), points = (dir / "points.gpkg").string();
    write_layer(input, "GPKG", wkbLineString, {{"LINESTRING (0.1 0.3, 0.1 12.7, 17.3 12.7)", "edge"}});
    // (2.3359999999999892, 1.9119999999999922) is inside the triangle, one ulp from its edge:
    // the float barycentric test calls it outside (see MapSimplify.FloatModeBreaksTopology…).
    write_layer(points, "GPKG", wkbPoint, {{"POINT (2.3359999999999892 1.9119999999999922)", "p"}}, "places");
    const std::string broken = (dir / "broken.gpkg").string();
    const CliResult unsafe = run_cli({"map", input, "-p", points, "--max", "--arithmetic", "float", "--validate", "-o", broken});
    EXPECT_EQ(unsafe.code, 1) << unsafe.err;
    EXPECT_NE(unsafe.err.find("point_changed_side"), std::string::npos) << unsafe.err;
    EXPECT_FALSE(std::filesystem::exists(broken));
    const std::string safe = (dir / "safe.gpkg").string();
    EXPECT_EQ(run_cli({"map", input, "-p", points, "--max", "--validate", "-o", safe}).code, 0);
    EXPECT_TRUE(std::filesystem::exists(safe));
    const CliResult from_stdin = run_cli({"map", "/vsistdin/", "--validate", "-f", "GPKG", "-o", (dir / "x.gpkg").string()});
    EXPECT_EQ(from_stdin.code, 2);
    EXPECT_NE(from_stdin.err.find("standard input"), std::string::npos) << from_stdin.err;
}

}  // namespace
}  // namespace toposimp::testing
