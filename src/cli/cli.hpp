// The toposimp command line as a library: tests call run() in-process.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace toposimp::map {
struct MapData;
struct SimplifyOptions;
struct SimplifyResult;
}  // namespace toposimp::map

namespace toposimp::io {
struct VerticesInFile;
}  // namespace toposimp::io

namespace toposimp::cli {

// Exit statuses (DESIGN.md): 0 ok, 1 topology or validation failure, 2 usage or input error.
enum ExitCode : int { kOk = 0, kTopologyFailure = 1, kUsageError = 2 };

struct Context {
    std::ostream& out;                // results: --json, help text
    std::ostream& err;                // messages
    bool err_is_terminal = false;     // print the one-line summary even without -v
    // In-process callers (the Python module): progress as calls, (phase, share done 0…1), and a
    // flag that stops the engine (it then throws toposimp::Cancelled).
    std::function<void(const std::string& phase, double done)> progress{};
    const std::atomic<bool>* cancel = nullptr;
    // In-process callers that run the map engine elsewhere (python3 -m toposimp.dask): called in
    // place of map::simplify, and must give what it gives. Empty: the engine runs here.
    std::function<map::SimplifyResult(const map::MapData&, const map::SimplifyOptions&)> map_engine{};
    // And where set, for a map whose vertices the engine reads from the input itself: a plain
    // PolyLine Shapefile written to a Shapefile, at one target, published as simplified (no
    // --decimals, --precision or --levels). The map then holds its chains and control points,
    // and no vertex (io::VerticesInFile says where they are); this process never reads them all.
    std::function<map::SimplifyResult(const map::MapData&, const map::SimplifyOptions&, const io::VerticesInFile&)> map_engine_in_file{};
    // And where set too: whether to leave them in the file, given the input's size on disk in
    // bytes (a file's, or the regular files' of a folder). Empty: wherever the input allows it.
    std::function<bool(std::uintmax_t bytes)> leave_in_file_if{};
};

// Runs `toposimp ARGS...` (args excludes the program name) and returns the exit status.
int run(const std::vector<std::string>& args, Context& context);

}  // namespace toposimp::cli
