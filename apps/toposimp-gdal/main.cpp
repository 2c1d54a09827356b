// toposimp-gdal: the whole toposimp command line (maps, checks, meshes, DEMs, OGR layers).
// `toposimp` (apps/toposimp) starts it in its own place for every job that needs GDAL.
#include "cli/cli.hpp"
#include "cli/interrupt.hpp"

#include <malloc.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
    // Big maps allocate and free arrays of hundreds of MB phase after phase. By default glibc
    // maps each such array fresh from the kernel and unmaps it when freed, so every phase pays
    // for zeroing new pages again (an eighth of the run on a 10 M-vertex map). Keep freed
    // memory in the heap instead; peak memory is unchanged.
    mallopt(M_MMAP_THRESHOLD, 1 << 30);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    toposimp::cli::clean_up_on_interrupt();
    std::ios::sync_with_stdio(false);
    toposimp::cli::Context context{std::cout, std::cerr, ::isatty(STDERR_FILENO) == 1};
    return toposimp::cli::run({argv + 1, argv + argc}, context);
}
