// `toposimp map`: topology-preserving simplification of line layers (EPLSimp).
#pragma once

#include "cli/cli.hpp"
#include "core/geometry.hpp"

#include <CLI/App.hpp>
#include <spdlog/logger.h>

#include <string>
#include <utility>
#include <vector>

namespace toposimp::io {
struct MemoryLayers;
}

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

// A map job whose layers come from and go to memory (the Python module): MapOptions::input and
// ::points then only name them in messages, and nothing is written to MapOptions::output.
struct MapMemory {
    const io::MemoryLayers* input = nullptr;
    const io::MemoryLayers* points = nullptr;  // or null: none (unless MapOptions::points names a file)
    const std::vector<Point>* point_coordinates = nullptr;  // control points given as coordinates, or null
    std::vector<io::MemoryLayers> output;      // per level (one without --levels), finest first
    std::vector<std::string> summaries;        // per level, the --json summary
};

// What run_map runs inside its error guard, the errors thrown as they are (io::InputError,
// io::OutputError, UsageError, TopologyFailure, toposimp::Cancelled); with `memory`, in memory.
int map_job(const MapOptions& options, Context& context, spdlog::logger& log, MapMemory* memory = nullptr);

}  // namespace toposimp::cli
