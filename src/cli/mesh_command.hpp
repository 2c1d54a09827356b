// `toposimp mesh`: simplification of triangle meshes that never self-intersects (UGSimp).
#pragma once

#include "cli/cli.hpp"

#include <CLI/App.hpp>

#include <string>

namespace toposimp::cli {

struct MeshCommandOptions {
    std::string input;
    std::string output;
    std::string format;        // obj, ply, off (default: from the output's extension)
    std::string keep;          // share of faces, 10% or 0.1
    double keep_faces = -1;
    double max_error = -1;
    bool lock_boundary = false;
    bool free_boundary = false;
    int band = 1;
    std::string layer_name = "tin";
    bool terrain = false;
    bool triangulate = false;
    bool ascii = false;
    bool no_hausdorff = false;
    int threads = 0;
    bool json = false;
    bool overwrite = false;
    bool quiet = false;
    bool progress = false;  // --progress: PROGRESS lines on stderr for GUIs
    int verbosity = 0;
};

CLI::App* add_mesh_command(CLI::App& app, MeshCommandOptions& options);

int run_mesh(const MeshCommandOptions& options, Context& context);

}  // namespace toposimp::cli
