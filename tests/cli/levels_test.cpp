// --levels: one output per level from one run, each level's vertices among the level before's,
// each checked clean; the JSON summary lists the levels; a pattern without {level}, levels out of
// order and unknown levels are refused before anything is read.
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace toposimp::testing
