// Temporary file names for tests. A name per test keeps the tests of one ctest run apart; the
// build tree's name in it keeps apart two build trees testing at once (the dev and the sanitizer
// builds), and a rerun in the same tree reuses its files instead of leaving new ones behind.
#pragma once

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace toposimp::testing {

inline std::filesystem::path temp_path(const std::string& name) {
    static const std::string tree = [] {
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016zx", std::hash<std::string>{}(TOPOSIMP_TEST_TREE));
        return std::string(hex, 8);
    }();
    return std::filesystem::temp_directory_path() / ("toposimp-" + tree + "-" + name);
}

// `bytes` written to temp_path(name), whose path it returns.
inline std::string write_temp_file(const std::string& name, const std::string& bytes) {
    const std::string path = temp_path(name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

}  // namespace toposimp::testing
