// Fuzz target: a whole GeoPackage (SQLite) file read by the control-point reader, table
// "points", columns fid and geom, on two connections. Any bytes: points, a refusal (std::nullopt:
// the caller falls back to OGR) or an InputError naming the file and feature; never a crash,
// an unbounded reservation (FIDs far apart) or a non-finite point handed on.
#include "io/common/errors.hpp"
#include "io/map/gpkg_points.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

using namespace toposimp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string path = [] {
        const char* folder = std::getenv("TMPDIR");
        return std::string(folder != nullptr ? folder : "/tmp") + "/toposimp-fuzz-gpkg-" + std::to_string(getpid()) + ".gpkg";
    }();
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    try {
        const auto points = io::read_gpkg_points({path, "points", "geom", "fid"}, 2);
        if (points) {
            for (const Point& p : *points) {
                if (!std::isfinite(p.x) || !std::isfinite(p.y)) std::abort();
            }
        }
    } catch (const io::InputError& error) {
        if (std::string(error.what()).find(path) == std::string::npos) std::abort();  // names the file
    }
    return 0;
}
