// `toposimp check`: what, if anything, a simplification broke (any tool's output).
#pragma once

#include "cli/cli.hpp"
#include "validate/check.hpp"

#include <CLI/App.hpp>

#include <string>

namespace toposimp::cli {

struct CheckCommandOptions {
    validate::CheckOptions check;
    std::string precision;  // --precision STEP: the simplified output was rounded onto this grid
    int decimals = -1;      // --decimals D: --precision 1e-D
    bool json = false;
    std::string geojson_errors;
    bool quiet = false;
    bool progress = false;  // --progress: PROGRESS lines on stderr for GUIs
    int verbosity = 0;
};

CLI::App* add_check_command(CLI::App& app, CheckCommandOptions& options);

int run_check(const CheckCommandOptions& options, Context& context);

// The report as a table, as JSON, and as GeoJSON points (one per violation).
void print_table(std::ostream& out, const validate::CheckReport& report);
void print_json(std::ostream& out, const validate::CheckReport& report);
std::string violations_geojson(const validate::CheckReport& report);

}  // namespace toposimp::cli
