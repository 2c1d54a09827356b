// Progress for GUIs (--progress) and what an interrupted run leaves behind (nothing).
#include "cli/cli_fixtures.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <regex>
#include <sstream>

extern char** environ;

namespace toposimp::testing {
namespace {

struct ProgressLine {
    int percent;
    std::string phase;
};

// Every line of `err` that is a progress line; fails the test on a malformed one.
std::vector<ProgressLine> progress_lines(const std::string& err) {
    static const std::regex line_form(R"(PROGRESS (\d{1,3}) (\S.*))");
    std::vector<ProgressLine> lines;
    std::istringstream in(err);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("PROGRESS", 0) != 0) continue;
        std::smatch match;
        EXPECT_TRUE(std::regex_match(line, match, line_form)) << line;
        if (match.empty()) continue;
        lines.push_back({std::stoi(match[1]), match[2]});
        EXPECT_LE(lines.back().percent, 100) << line;
    }
    return lines;
}

// Phases in order of appearance; within a phase the percent never goes back and starts at 0.
std::vector<std::string> phases(const std::vector<ProgressLine>& lines) {
    std::vector<std::string> names;
    int last = -1;
    for (const ProgressLine& l : lines) {
        if (names.empty() || l.phase != names.back()) {
            names.push_back(l.phase);
            EXPECT_EQ(l.percent, 0) << "a phase starts at 0: " << l.phase;
        } else {
            EXPECT_GT(l.percent, last) << l.phase;  // one line per change
        }
        last = l.percent;
    }
    return names;
}

TEST(Progress, MapReportsEachPhaseAsLines) {
    const auto dir = fresh_dir("progress");
    const std::string out = (dir / "out.gpkg").string();
    const CliResult r = run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--keep", "10%", "--progress", "--validate"});
    ASSERT_EQ(r.code, 0) << r.err;
    const std::vector<std::string> names = phases(progress_lines(r.err));
    const std::vector<std::string> expected{"reading " + testdata("nh_borders.gpkg"), "simplifying", "writing " + out,
                                            "validating"};
    EXPECT_EQ(names, expected) << r.err;
}

// -vv lists a count target's rounds, one line each, their removals adding up to the run's; none
// for --max, which sweeps once.
TEST(Progress, VeryVerboseMapListsEachRound) {
    const auto dir = fresh_dir("progress");
    const std::string out = (dir / "out.gpkg").string();
    auto json_number = [](const std::string& json, const std::string& key) {
        std::smatch match;
        EXPECT_TRUE(std::regex_search(json, match, std::regex("\"" + key + "\":(\\d+)"))) << key << " in " << json;
        return match.empty() ? -1L : std::stol(match[1]);
    };
    const CliResult r = run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--keep", "10%", "-vv", "--json", "-j", "2"});
    ASSERT_EQ(r.code, 0) << r.err;
    static const std::regex round_line(R"(toposimp: trace: round (\d+): (\d+) removed; selection \d+\.\d{3} s, scheduling \d+\.\d{3} s, sweep \d+\.\d{3} s)");
    long rounds = 0, removed = 0;
    std::istringstream in(r.err);
    for (std::string line; std::getline(in, line);) {
        std::smatch match;
        if (!std::regex_match(line, match, round_line)) continue;
        EXPECT_EQ(std::stol(match[1]), ++rounds) << line;
        removed += std::stol(match[2]);
    }
    EXPECT_GT(rounds, 1) << r.err;
    EXPECT_EQ(rounds, json_number(r.out, "rounds")) << r.err;
    EXPECT_EQ(removed, json_number(r.out, "removed")) << r.err;
    const CliResult once = run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--max", "-vv", "--overwrite"});
    ASSERT_EQ(once.code, 0) << once.err;
    EXPECT_EQ(once.err.find("trace: round"), std::string::npos) << once.err;
}

TEST(Progress, MeshReportsSimplificationUpToTheTarget) {
    const auto dir = fresh_dir("progress");
    const std::string out = (dir / "torus.ply").string();
    const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", out, "--keep", "10%", "--progress"});
    ASSERT_EQ(r.code, 0) << r.err;
    const std::vector<ProgressLine> lines = progress_lines(r.err);
    const std::vector<std::string> expected{"reading " + testdata("mesh/torus.off"), "simplifying",
                                            "checking the result for contacts", "writing " + out,
                                            "measuring the Hausdorff distance"};
    EXPECT_EQ(phases(lines), expected) << r.err;
    // The target is reached, so the simplifying phase ends at 100.
    int last_simplifying = -1;
    for (const ProgressLine& l : lines) {
        if (l.phase == "simplifying") last_simplifying = l.percent;
    }
    EXPECT_EQ(last_simplifying, 100) << r.err;
}

TEST(Progress, CheckAndErrorsStillReadable) {
    const auto dir = fresh_dir("progress");
    const CliResult r = run_cli({"check", testdata("nh_borders.gpkg"), testdata("nh_borders.gpkg"), "--progress", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(phases(progress_lines(r.err)).size(), 1u) << r.err;
    EXPECT_EQ(r.out.rfind("{\"command\":\"check\"", 0), 0u) << "stdout keeps the JSON only: " << r.out;
    // An error after a phase began is still its own line.
    const CliResult bad = run_cli({"mesh", (dir / "missing.off").string(), "-o", (dir / "x.ply").string(), "--progress"});
    EXPECT_EQ(bad.code, 2);
    EXPECT_EQ(phases(progress_lines(bad.err)).size(), 1u) << bad.err;
    std::istringstream lines(bad.err);
    std::string line;
    bool error_line = false;
    while (std::getline(lines, line)) {
        EXPECT_EQ(line.find("PROGRESS"), line.rfind("PROGRESS", 0) == 0 ? 0 : std::string::npos) << line;
        error_line = error_line || (line.find("error") != std::string::npos && line.find("missing.off") != std::string::npos);
    }
    EXPECT_TRUE(error_line) << bad.err;
}

TEST(Progress, NothingOnAPipeWithoutTheFlag) {
    const auto dir = fresh_dir("progress");
    const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / "t.obj").string(), "--no-hausdorff"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
}

// A 600 × 600 grid (718 k triangles) as an ESRI ASCII DEM: long enough to simplify in a debug
// build that a signal sent when simplification starts arrives before the output is written.
std::string write_big_dem(const std::filesystem::path& dir) {
    const std::string path = (dir / "dem.asc").string();
    std::FILE* file = std::fopen(path.c_str(), "w");
    constexpr int n = 600;
    std::fprintf(file, "ncols %d\nnrows %d\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n", n, n);
    for (int r = 0; r < n; ++r) {
        for (int c = 0; c < n; ++c) std::fprintf(file, "%.3f ", 20 * std::sin(r * 0.05) * std::cos(c * 0.07) + ((r * 31 + c * 17) % 7) * 0.1);
        std::fputc('\n', file);
    }
    std::fclose(file);
    return path;
}

// Runs the real executable, reads its stderr until a line containing `when`, sends `sig`, and
// returns the wait status.
int interrupt_at(const std::vector<std::string>& args, const std::string& when, int sig, std::string& err) {
    int pipe_ends[2];
    if (::pipe(pipe_ends) != 0) return -1;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_ends[1], STDERR_FILENO);
    posix_spawn_file_actions_addclose(&actions, pipe_ends[0]);
    std::vector<std::string> all{TOPOSIMP_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, TOPOSIMP_BINARY, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_ends[1]);
    if (spawned != 0) return -1;
    bool sent = false;
    char buffer[4096];
    ssize_t got = 0;
    while ((got = ::read(pipe_ends[0], buffer, sizeof buffer)) > 0) {
        err.append(buffer, static_cast<std::size_t>(got));
        if (!sent && err.find(when) != std::string::npos) {
            ::kill(pid, sig);
            sent = true;
        }
    }
    ::close(pipe_ends[0]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return status;
}

TEST(Interrupt, SignalLeavesNoOutputAndNoStagingFolder) {
    const auto dir = fresh_dir("interrupt");
    const std::string dem = write_big_dem(dir);
    for (const int sig : {SIGTERM, SIGINT}) {
        const std::string out = (dir / "tin.ply").string();
        std::string err;
        const int status = interrupt_at({"mesh", dem, "-o", out, "--progress", "--no-hausdorff", "-j", "1"},
                                        "PROGRESS 0 simplifying", sig, err);
        ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status << "\n" << err;
        EXPECT_EQ(WTERMSIG(status), sig) << err;
        std::vector<std::string> left;
        for (const auto& entry : std::filesystem::directory_iterator(dir)) left.push_back(entry.path().filename().string());
        EXPECT_EQ(left, std::vector<std::string>{"dem.asc"}) << "sig " << sig;
    }
}

}  // namespace
}  // namespace toposimp::testing
