// Fuzz target: the GIS Cup 2014 text reader (lines and control points) on any bytes, read from a
// file as the command reads it. It may refuse them (InputError), never crash.
#include "io/common/errors.hpp"
#include "io/map/giscup.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

using namespace toposimp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string path = "/tmp/toposimp-fuzz-giscup-" + std::to_string(::getpid()) + ".txt";
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (file == nullptr) return 0;
    std::fwrite(data, 1, size, file);
    std::fclose(file);
    try {
        map::MapData map;
        io::read_giscup_lines(path, map);
    } catch (const io::InputError&) {
    }
    try {
        io::read_giscup_points(path);
    } catch (const io::InputError&) {
    }
    return 0;
}
