// Parallel simplification of real maps: the output is the same for any number of threads.
#include "cli/cli_fixtures.hpp"
#include "core/map/simplify.hpp"
#include "io/map/giscup.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <random>

namespace toposimp::testing {
namespace {

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every loop forced parallel (threshold 0): 2, 3, 4 and 7 threads give the 1-thread result.
void expect_same_for_any_thread_count(const map::MapData& input, const std::string& name) {
    for (const map::StopCriterion stop : {map::StopCriterion{map::Target::max, 0},
                                          map::StopCriterion{map::Target::keep_fraction, 0.5},
                                          map::StopCriterion{map::Target::keep_fraction, 0.1}}) {
        map::SimplifyOptions options;
        options.stop = stop;
        options.parallel_threshold = 0;
        options.threads = 1;
        const map::SimplifyResult serial = map::simplify(input, options);
        EXPECT_GT(serial.stats.levels, 1u) << name << ": the map should span several blocks";
        for (const int threads : {2, 3, 4, 7}) {
            options.threads = threads;
            const map::SimplifyResult parallel = map::simplify(input, options);
            ASSERT_EQ(parallel.kept, serial.kept) << name << ", " << threads << " threads";
            EXPECT_EQ(parallel.stats.threads, threads);
        }
    }
}

TEST(Parallel, NaturalEarthStatesSameForAnyThreadCount) {
    map::MapData map;
    const io::OgrDataset dataset = io::OgrDataset::read(testdata("ne_states_slice.gpkg"), {}, map);
    // 2 000 control points scattered over the map's extent (fixed seed).
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> x(5.85, 18.83), y(45.82, 55.06);
    for (int i = 0; i < 2000; ++i) map.control_points.push_back({x(rng), y(rng)});
    expect_same_for_any_thread_count(map, "ne_states_slice");
}

TEST(Parallel, GiscupTrainingSetsSameForAnyThreadCount) {
    for (const std::string set : {"td1", "td2"}) {
        const std::string dir = std::string(TOPOSIMP_TEST_DATA) + "/giscup14/" + set + "/";
        map::MapData map;
        io::read_giscup_lines(dir + "lines_out.txt", map);
        map.control_points = io::read_giscup_points(dir + "points_out.txt");
        expect_same_for_any_thread_count(map, set);
    }
}

// Through the CLI: -j changes nothing in the written file (GeoJSON: no timestamps inside).
TEST(Parallel, CliOutputByteIdenticalForAnyThreadCount) {
    const auto dir = fresh_dir("parallel-cli");
    std::string first;
    for (const char* threads : {"1", "2", "3"}) {
        const std::string out = (dir / (std::string("out") + threads + ".geojson")).string();
        const CliResult run = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "--keep", "20%", "-j", threads, "-o", out, "-q"});
        ASSERT_EQ(run.code, 0) << run.err;
        if (first.empty()) {
            first = slurp(out);
            ASSERT_FALSE(first.empty());
        } else {
            EXPECT_EQ(slurp(out), first) << "-j " << threads;
        }
    }
}

}  // namespace
}  // namespace toposimp::testing
