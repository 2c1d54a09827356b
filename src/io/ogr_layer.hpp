// OGR adapter for `toposimp map`: reads a line or polygon layer into the engine's MapData (lines
// as chains, polygon rings as a coverage of shared arcs, points as control points), keeps every
// feature's attributes, and writes the simplified features back through any OGR driver with the
// same fields, CRS, feature order, layer name and geometry type.
#pragma once

#include "core/map/map_data.hpp"

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace toposimp::io {

// What an input looked like; used for logging and the JSON summary.
struct LayerSummary {
    std::string driver;
    std::string layer;
    std::uint64_t features = 0;
    std::uint64_t empty_geometries = 0;  // NULL or empty: written back unchanged
    std::uint64_t untouched_points = 0;  // Point features among lines: unchanged, used as control points
    std::uint64_t polygon_features = 0;
    std::uint64_t arcs = 0;              // polygon rings split at nodes
    std::uint64_t shared_arcs = 0;       // arcs used by two rings (or twice)
    std::uint64_t degenerate_rings = 0;  // fewer than 3 corners or flat: written back unchanged
    bool has_z = false;
    bool has_m = false;
};

struct WriteOptions {
    std::string path;                          // file name, or /vsistdout/
    std::string format;                        // OGR driver short name; empty: from the extension
    std::string layer_name;                    // -nln; empty: the input layer's name
    std::vector<std::string> layer_options;    // -lco KEY=VALUE
    std::vector<std::string> dataset_options;  // -dsco KEY=VALUE
    bool overwrite = false;
    std::ostream* stdout_stream = nullptr;     // where /vsistdout/ output goes
};

class OgrLayer {
public:
    // Reads layer `layer` of `path` (empty: the first layer) into `map`, one chain per line part.
    // Throws InputError naming the file, layer and feature for anything it cannot accept.
    static OgrLayer read(const std::string& path, const std::string& layer, map::MapData& map);

    OgrLayer(OgrLayer&&) noexcept;
    ~OgrLayer();

    const LayerSummary& summary() const;

    // Writes the features with only the kept vertices. The written file is read back and its
    // coordinates compared bit for bit before it is moved into place (OutputError otherwise).
    // Returns warnings worth telling the user (e.g. values a format cannot hold).
    std::vector<std::string> write(const WriteOptions& options, const map::MapData& map,
                                   const std::vector<std::uint8_t>& kept) const;

    struct Layer;  // the layer's definition, CRS, attributes and geometry shapes

private:
    explicit OgrLayer(std::unique_ptr<Layer> layer);
    std::unique_ptr<Layer> layer_;
};

// Reads control points from "path" or "path:layer" (Point or MultiPoint features).
std::vector<Point> read_control_points(const std::string& spec);

// The GDAL release this was built against and runs with, for --version.
std::string gdal_version();

}  // namespace toposimp::io
