// GIS Cup 2014 training sets at the contest's targets: zero violations (independent checker),
// the asked number of points removed, and byte-identical output to the stored golden files.
#include "cli/cli_fixtures.hpp"
#include "core/map/simplify.hpp"
#include "io/map/giscup.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace toposimp::testing {
namespace {

struct ContestCase {
    const char* set;
    std::uint64_t remove;  // input vertices − the reference output's vertices
};

std::string data(const std::string& set, const std::string& file) {
    return std::string(TOPOSIMP_TEST_DATA) + "/giscup14/" + set + "/" + file;
}

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class Contest : public ::testing::TestWithParam<ContestCase> {};

TEST_P(Contest, RemovesTheTargetWithoutViolations) {
    const ContestCase c = GetParam();
    map::MapData input;
    io::read_giscup_lines(data(c.set, "lines_out.txt"), input);
    input.control_points = io::read_giscup_points(data(c.set, "points_out.txt"));
    ASSERT_TRUE(check_planar(input).ok()) << check_planar(input).summary();

    map::MapData reference;
    io::read_giscup_lines(data(c.set, "lines_simple_out.txt"), reference);
    ASSERT_EQ(input.vertices.size() - reference.vertices.size(), c.remove) << "reference output size";

    for (const map::Target target : {map::Target::remove_points, map::Target::max}) {
        map::SimplifyOptions options;
        options.stop = {target, static_cast<double>(c.remove)};
        const map::SimplifyResult result = map::simplify(input, options);
        const CheckReport report = check_simplification(input, result.kept);
        EXPECT_TRUE(report.ok()) << c.set << ": " << report.summary();
        if (target == map::Target::remove_points) {
            EXPECT_EQ(result.stats.removed, c.remove) << c.set;
        } else {
            EXPECT_GE(result.stats.removed, c.remove) << c.set << ": --max removes at least what the reference did";
            RecordProperty(std::string(c.set) + "_max_removed", std::to_string(result.stats.removed));
        }
    }
}

TEST_P(Contest, OutputMatchesGoldenFile) {
    const ContestCase c = GetParam();
    const std::string name = std::string("giscup-") + c.set + "_--remove-points_" + std::to_string(c.remove) + ".txt";
    const auto dir = fresh_dir(std::string("golden-") + c.set);
    const std::string out = (dir / name).string();
    const CliResult result = run_cli({"map", "--giscup", data(c.set, "lines_out.txt"), "--points",
                                      data(c.set, "points_out.txt"), "--remove-points", std::to_string(c.remove), "-o", out});
    ASSERT_EQ(result.code, 0) << result.err;
    const std::string golden = slurp(testdata("golden/" + name));
    ASSERT_FALSE(golden.empty()) << "missing golden file; run scripts/regen-golden.sh";
    EXPECT_EQ(slurp(out), golden) << "output changed; if intended, run scripts/regen-golden.sh and review the diff";
}

INSTANTIATE_TEST_SUITE_P(TrainingSets, Contest, ::testing::Values(ContestCase{"td1", 883}, ContestCase{"td2", 517}),
                         [](const auto& test_info) { return std::string(test_info.param.set); });

}  // namespace
}  // namespace toposimp::testing
