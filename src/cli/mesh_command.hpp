// `toposimp mesh`: simplification of triangle meshes that never self-intersects (UGSimp).
#pragma once

#include "cli/cli.hpp"
#include "io/ogr/dem.hpp"

#include "io/mesh/mesh_files.hpp"

#include <CLI/App.hpp>
#include <spdlog/logger.h>

#include <string>
#include <vector>

namespace toposimp::cli {

struct MeshCommandOptions {
    std::string input;
    std::string output;
    std::string format;        // a mesh format's name (io::mesh_formats()) or an OGR driver; default: the output's extension
    std::string keep;          // share of faces, 10% or 0.1
    double keep_faces = -1;
    double max_error = -1;
    bool lock_boundary = false;
    bool free_boundary = false;
    int band = 1;
    std::string layer_name = "tin";
    bool terrain = false;     // --terrain: a TIN over the x-y plane (a warning if it is not one)
    bool no_terrain = false;  // --no-terrain: simplify in space even a height field
    // Neither: a height field (every face turned the same way in the x-y plane, none degenerate
    // or overlapping there, decided exactly) is simplified as a terrain, anything else in space.
    bool triangulate = false;
    bool weld = false;  // --weld: merge vertices at the same location first
    bool ascii = false;
    bool no_hausdorff = false;  // --no-hausdorff: --measure none
    std::string measure = "quick";  // --measure quick|full|none: how the distance to the input is measured
    // --contact-check after|each: the result checked once for contacts (a second run with every
    // collapse checked if it has one), or every collapse checked (mesh::ContactCheck)
    std::string contact_check = "after";
    int threads = 0;
    bool json = false;
    bool overwrite = false;
    bool quiet = false;
    bool progress = false;  // --progress: PROGRESS lines on stderr for GUIs
    int verbosity = 0;
};

CLI::App* add_mesh_command(CLI::App& app, MeshCommandOptions& options);

// What the mesh command needs GDAL for: DEM rasters in, OGR layers of triangles out. The whole
// tool passes io's functions; the launcher (apps/toposimp) links no GDAL and runs only the jobs
// that need neither (mesh_needs_gdal).
struct MeshGdal {
    io::Dem (*read_dem)(const std::string& path, int band) = nullptr;
    void (*write_tin_layer)(const mesh::Mesh& tin, const std::string& path, const std::string& driver,
                            const std::string& crs_wkt, const std::string& layer_name) = nullptr;
    // Throws io::OutputError unless GDAL can create a layer at `path` (driver: -f, or "" for the
    // extension's): asked before any work.
    void (*check_layer_output)(const std::string& path, const std::string& driver) = nullptr;
};

// Does the job read a DEM or write an OGR layer?
bool mesh_needs_gdal(const MeshCommandOptions& options);

// `args` (without the program name) as a mesh command alone, or false if they are anything else
// (another command, --help, a usage error): the whole tool then answers them.
bool parse_mesh_command(const std::vector<std::string>& args, MeshCommandOptions& options);

int run_mesh(const MeshCommandOptions& options, Context& context, const MeshGdal& gdal);

// A mesh job on a mesh in memory (the Python module): MeshCommandOptions::input and ::output
// only name it in messages; nothing is read or written.
struct MeshMemory {
    mesh::Mesh mesh;             // in: the mesh to simplify; out: the simplified mesh
    io::AttributeLayout layout;  // what its attribute columns are
    std::string summary;         // out: the --json summary
};

// What run_mesh runs inside its error guard, the errors thrown as they are (io::InputError,
// io::OutputError, UsageError, toposimp::Cancelled); with `memory`, in memory.
int mesh_job(const MeshCommandOptions& options, Context& context, const MeshGdal& gdal, spdlog::logger& log,
             MeshMemory* memory = nullptr);

// `toposimp formats`: the mesh formats (io/mesh's table) with what each carries, as a table or
// as JSON (the QGIS provider builds its file filters from it).
void print_mesh_formats(std::ostream& out, bool json);

}  // namespace toposimp::cli
