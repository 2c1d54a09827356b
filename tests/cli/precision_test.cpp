// --precision and --decimals: every written x and y on the grid (or reported off it), and
// `toposimp check` finding nothing but the moved vertices (not_subset, which rounding is).
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

namespace toposimp::testing {
namespace {

// Is `value` the double a reader parses from its shortest text with at most `decimals` decimals?
bool has_decimals_at_most(double value, int decimals) {
    char text[64];
    const auto end = std::to_chars(text, text + sizeof text, value, std::chars_format::fixed).ptr;
    const std::string written(text, end);
    const auto point = written.find('.');
    return point == std::string::npos || static_cast<int>(written.size() - point - 1) <= decimals;
}

std::string contents(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::uint64_t json_number(const std::string& json, const std::string& key) {
    const auto at = json.find("\"" + key + "\":");
    if (at == std::string::npos) return ~0ull;
    return std::stoull(json.substr(at + key.size() + 3));
}

TEST(Precision, EveryCoordinateOnTheGridAndTheTopologyKept) {
    const auto dir = fresh_dir("precision");
    const std::string input = testdata("ne_states_slice.gpkg");
    for (const int decimals : {1, 2, 3}) {
        SCOPED_TRACE(decimals);
        const std::string out = (dir / ("states" + std::to_string(decimals) + ".gpkg")).string();
        const CliResult map = run_cli({"map", input, "-o", out, "--keep", "20%", "--decimals", std::to_string(decimals), "--json"});
        ASSERT_EQ(map.code, 0) << map.err;
        const std::uint64_t off_grid = json_number(map.out, "off_grid");
        ASSERT_NE(off_grid, ~0ull) << map.out;
        EXPECT_GT(json_number(map.out, "moved_nearest"), 0u);
        std::uint64_t on = 0;
        std::set<std::pair<double, double>> off;  // locations written off the grid
        for (const ReadFeature& feature : read_layer(out).features) {
            for (const auto& part : feature.coordinates) {
                for (std::size_t k = 0; k + 1 < part.size(); k += 2) {
                    if (has_decimals_at_most(part[k], decimals) && has_decimals_at_most(part[k + 1], decimals)) ++on;
                    else off.insert({part[k], part[k + 1]});
                }
            }
        }
        EXPECT_GT(on, 500u);
        EXPECT_LE(off.size(), off_grid + json_number(map.out, "frozen"));  // only those reported
        // Every kind of violation but not_subset (the rounded vertices are not the input's).
        const CliResult check = run_cli({"check", input, out, "--json"});
        const auto begin = check.out.find("\"counts\":{");
        ASSERT_NE(begin, std::string::npos) << check.out;
        const std::string counts = check.out.substr(begin + 10, check.out.find('}', begin) - begin - 10);
        std::size_t kinds = 0;
        for (std::size_t at = 0; at < counts.size();) {
            const std::size_t end = std::min(counts.find(',', at), counts.size());
            const std::string entry = counts.substr(at, end - at);
            const std::string kind = entry.substr(1, entry.find('"', 1) - 1);
            ++kinds;
            if (kind != "not_subset") {
                EXPECT_EQ(entry.substr(entry.find(':') + 1), "0") << entry;
            }
            at = end + 1;
        }
        EXPECT_GT(kinds, 10u) << counts;
    }
}

TEST(Precision, AStepInMapUnitsAndTheSameGridAsDecimals) {
    const auto dir = fresh_dir("precision");
    const std::string input = testdata("ne_states_slice.gpkg");
    const std::string a = (dir / "a.geojson").string(), b = (dir / "b.geojson").string();
    ASSERT_EQ(run_cli({"map", input, "-o", a, "--decimals", "2"}).code, 0);
    ASSERT_EQ(run_cli({"map", input, "-o", b, "--precision", "0.01"}).code, 0);
    EXPECT_EQ(contents(a), contents(b));
    const CliResult coarse = run_cli({"map", input, "-o", (dir / "c.geojson").string(), "--precision", "0.5", "--json"});
    ASSERT_EQ(coarse.code, 0) << coarse.err;
    EXPECT_NE(coarse.out.find("\"grid\":\"0.5\""), std::string::npos) << coarse.out;
}

TEST(Precision, BadStepsAreRefused) {
    const auto dir = fresh_dir("precision");
    const std::string input = testdata("ne_states_slice.gpkg"), out = (dir / "out.gpkg").string();
    for (const char* step : {"0", "-0.1", "abc", "1e999", "nan"}) {
        const CliResult result = run_cli({"map", input, "-o", out, "--precision", step});
        EXPECT_EQ(result.code, 2) << step;
        EXPECT_NE(result.err.find("--precision"), std::string::npos) << result.err;
    }
    EXPECT_EQ(run_cli({"map", input, "-o", out, "--precision", "0.1", "--decimals", "2"}).code, 2);
    EXPECT_EQ(run_cli({"map", input, "-o", out, "--decimals", "-1"}).code, 2);
    const CliResult fine = run_cli({"map", input, "-o", out, "--precision", "1e-300"});
    EXPECT_EQ(fine.code, 2);
    EXPECT_NE(fine.err.find("too fine"), std::string::npos) << fine.err;
    EXPECT_TRUE(files_in(dir).empty());
}

// The point features of the layers simplified go on the grid too (they are written out), and the
// check with the grid given finds everything in place.
TEST(Precision, PointLayersGoOnTheGridToo) {
    const auto dir = fresh_dir("precision");
    const std::string input = testdata("nh_borders.gpkg"), out = (dir / "out.gpkg").string();
    const CliResult map = run_cli({"map", input, "-o", out, "--decimals", "2", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    const std::uint64_t on = json_number(map.out, "points_on_grid"), off = json_number(map.out, "points_off_grid");
    const ReadLayer places = read_layer(out, 1);
    ASSERT_EQ(places.name, "places");
    EXPECT_EQ(on + off, places.features.size());
    EXPECT_GT(on, 0u);
    std::uint64_t written_on = 0;
    for (const ReadFeature& feature : places.features) {
        const auto& xy = feature.coordinates.at(0);
        written_on += has_decimals_at_most(xy[0], 2) && has_decimals_at_most(xy[1], 2);
    }
    EXPECT_EQ(written_on, on);
    const CliResult check = run_cli({"check", input, out, "-l", "borders", "-p", input + ":places", "--decimals", "2"});
    EXPECT_EQ(check.code, 0) << check.out;
}

// check --decimals / --precision: a vertex on the grid up to a step from an original vertex
// stands for it; --validate passes the grid on.
TEST(Precision, CheckAcceptsRoundedVerticesAndStillFindsWhatRoundingBroke) {
    const auto dir = fresh_dir("precision");
    const std::string input = testdata("ne_states_slice.gpkg"), out = (dir / "out.gpkg").string();
    ASSERT_EQ(run_cli({"map", input, "-o", out, "--decimals", "2", "--validate"}).code, 0);
    const CliResult strict = run_cli({"check", input, out, "--json"});
    EXPECT_EQ(strict.code, 1);
    EXPECT_NE(strict.out.find("\"not_subset\":"), std::string::npos);
    const CliResult rounded = run_cli({"check", input, out, "--decimals", "2", "--json"});
    EXPECT_EQ(rounded.code, 0) << rounded.out;
    EXPECT_EQ(run_cli({"check", input, out, "--precision", "0.01"}).code, 0);
    EXPECT_EQ(run_cli({"check", input, out, "--precision", "zero"}).code, 2);

    // A line rounded across a control point (the apex 0.004 above it goes to 0 at 2 decimals),
    // and a vertex put three steps away: found with the grid given.
    const std::string original = (dir / "line.gpkg").string(), simplified = (dir / "rounded.gpkg").string();
    write_layer(original, "GPKG", wkbLineString, {{"LINESTRING (0 0,1 0.004,2 0)", "a"}});
    write_layer(simplified, "GPKG", wkbLineString, {{"LINESTRING (0 0,1 0,2 0)", "a"}});
    const std::string points = (dir / "points.gpkg").string();
    write_layer(points, "GPKG", wkbPoint, {{"POINT (1 0.003)", "p"}}, "points");
    const CliResult swept = run_cli({"check", original, simplified, "-p", points, "--decimals", "2", "--json"});
    EXPECT_EQ(swept.code, 1);
    EXPECT_NE(swept.out.find("\"point_changed_side\":2"), std::string::npos) << swept.out;  // by both segments
    EXPECT_NE(swept.out.find("swept by the rounded segment"), std::string::npos) << swept.out;
    EXPECT_EQ(run_cli({"check", original, simplified, "--decimals", "2"}).code, 0);  // no points: a clean rounding
    write_layer(simplified, "GPKG", wkbLineString, {{"LINESTRING (0 0,1 0.03,2 0)", "a"}}, "lines");
    const CliResult far = run_cli({"check", original, simplified, "--decimals", "2", "--json"});
    EXPECT_NE(far.out.find("\"not_subset\":1"), std::string::npos) << far.out;
}

// A ring a few grid steps across, rounded and written the other way round (as writers that follow
// RFC 7946 rewind rings): every vertex stands for every original one, so it matches forwards and
// backwards; check found it "flipped" by taking the forward match. Orientation is now judged
// against every way the ring can run along the original. A truly flipped ring is still found.
TEST(Precision, CheckDoesNotCallARewoundTinyRingFlipped) {
    const auto dir = fresh_dir("precision");
    const std::string original = (dir / "o.gpkg").string(), rewound = (dir / "r.gpkg").string(), flipped = (dir / "f.gpkg").string();
    write_layer(original, "GPKG", wkbPolygon, {{"POLYGON ((0.001 0.001,0.001 0.019,0.019 0.01,0.001 0.001))", "t"}}, "rings");
    write_layer(rewound, "GPKG", wkbPolygon, {{"POLYGON ((0 0,0.02 0.01,0 0.02,0 0))", "t"}}, "rings");
    const CliResult check = run_cli({"check", original, rewound, "--decimals", "2", "--json"});
    EXPECT_EQ(check.code, 0) << check.out;
    // A U-shape whose three corners, in its own order, turn the other way: flipped, grid or not
    // (CheckCli.RingFlipped without a grid).
    write_layer(original, "GPKG", wkbPolygon, {{"POLYGON ((0 0,4 0,4 4,3 4,3 1,1 1,1 4,0 4,0 0))", "t"}}, "rings");
    write_layer(flipped, "GPKG", wkbPolygon, {{"POLYGON ((4 4,3 1,1 4,4 4))", "t"}}, "rings");
    const CliResult really = run_cli({"check", original, flipped, "--decimals", "2", "--json"});
    EXPECT_NE(really.out.find("\"ring_flipped\":1"), std::string::npos) << really.out;
}

}  // namespace
}  // namespace toposimp::testing
