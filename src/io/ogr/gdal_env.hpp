// What the commands ask of GDAL without including a GDAL header (src/cli includes none): its
// configuration options, whether it can create an output, its version.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace toposimp::io {

// GDAL configuration options (KEY VALUE, as --config gives them), set for the process.
void set_config_options(const std::vector<std::pair<std::string, std::string>>& options);

// OutputError unless GDAL has a vector driver that can create `path` (`format`: a driver's short
// name as -f gives it, or "" for the one the extension names).
void check_vector_output(const std::string& path, const std::string& format);

// Will `path` be written by GDAL's Shapefile driver?
bool is_shapefile_output(const std::string& path, const std::string& format);
// Is the output (path, -f format) TopoJSON?
bool is_topojson_output(const std::string& path, const std::string& format);

// The GDAL release this was built against and runs with, for --version.
std::string gdal_version();

}  // namespace toposimp::io
