// Fuzz target: the Shapefile record readers (.shp, .shx and .dbf decoded past OGR). The input is
// split into the three files at two 16-bit lengths it starts with; the readers may refuse the
// files (std::nullopt, or InputError for a non-finite point), never crash or allocate more than
// the files hold. The same for a range of records (ShapeReader, read_shapefile_lines).
#include "io/common/errors.hpp"
#include "io/map/shapefile.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

using namespace toposimp;

namespace {

void write(const std::string& path, const std::uint8_t* data, std::size_t size) {
    if (std::FILE* file = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data, 1, size, file);
        std::fclose(file);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 4) return 0;
    const std::size_t shx = std::size_t{data[0]} << 8 | data[1], dbf = std::size_t{data[2]} << 8 | data[3];
    data += 4;
    size -= 4;
    const std::size_t shx_size = std::min(shx, size), dbf_size = std::min(dbf, size - shx_size);
    const std::string stem = "/tmp/toposimp-fuzz-shape-" + std::to_string(::getpid());
    write(stem + ".shx", data, shx_size);
    write(stem + ".dbf", data + shx_size, dbf_size);
    write(stem + ".shp", data + shx_size + dbf_size, size - shx_size - dbf_size);
    try {
        io::read_shapefile_points(stem + ".shp");
    } catch (const io::InputError&) {
    }
    io::read_shapefile_shapes(stem + ".shp");
    io::for_each_shape(stem + ".shp", [](std::uint64_t, const io::ShapeRecord&) { return true; });
    // A range of records, its first found through the .shx (a part read by a worker).
    if (std::optional<io::ShapeReader> reader = io::ShapeReader::open(stem + ".shp", 1, 4)) {
        while (reader->next() != nullptr) {
        }
    }
    try {
        io::read_shapefile_lines(stem + ".shp", "fuzz", 1, 4);
    } catch (const io::InputError&) {
    }
    return 0;
}
