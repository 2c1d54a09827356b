// `toposimp map`: topology-preserving simplification of line layers (EPLSimp).
#pragma once

#include "cli/cli.hpp"

#include <CLI/App.hpp>

#include <string>
#include <utility>
#include <vector>

namespace toposimp::cli {

struct MapOptions {
    std::string input;
    std::string output;
    std::string points;
    std::vector<std::string> layers;
    std::string format;
    std::string layer_name;
    std::vector<std::string> layer_options;
    std::vector<std::string> dataset_options;
    std::vector<std::pair<std::string, std::string>> config;
    std::string keep;
    double keep_points = -1;
    double remove_points = -1;
    std::string max_area;     // --max-area A: map units², or with --spherical m2, ha or km2
    double weighting = 0;     // --weighting K: weighted Visvalingam (mapshaper's default: 0.7)
    bool spherical = false;   // --spherical: areas on the sphere, for longitude, latitude input
    bool max = false;
    std::string precision;  // --precision STEP (grid of published coordinates), empty: full precision
    int decimals = -1;      // --decimals D: --precision 1e-D
    int quantize = 0;       // --quantize N: quantized TopoJSON on an N×N grid over the output's extent
    std::string levels;     // --levels 20%,5%,1%: nested levels, one output each (-o holds {level})
    std::string arithmetic = "exact";
    int threads = 0;  // 0: all cores (or OMP_NUM_THREADS)
    bool giscup = false;
    bool json = false;
    bool overwrite = false;
    bool validate = false;
    bool quiet = false;
    bool progress = false;  // --progress: PROGRESS lines on stderr for GUIs
    int verbosity = 0;
};

// Declares the subcommand's options on `app`, bound to `options`.
CLI::App* add_map_command(CLI::App& app, MapOptions& options);

int run_map(const MapOptions& options, Context& context);

}  // namespace toposimp::cli
