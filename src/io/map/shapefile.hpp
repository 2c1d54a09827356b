// Shapefile records read straight from the .shp, .shx and .dbf, not through OGR: control
// points, and the shapes of a written output when they are read back.
//
// Reading features through OGR makes the Shapefile driver parse the layer's .prj with PROJ
// (and look for a matching EPSG entry in proj.db) the first time a geometry is handed out:
// on a small map that is a fifth of the whole run, for a CRS neither use needs. The records
// themselves are simple to decode (ESRI Shapefile Technical Description, 1998): these readers
// do that and give up on anything unexpected, and the caller then reads the layer through OGR,
// which reports or handles it as for any other format.
#pragma once

#include "core/geometry.hpp"

#include <optional>
#include <string>
#include <vector>

namespace toposimp::io {

// The points of every record of the .shp at `path`, in record order, as OGR hands them out:
// Point and MultiPoint shapes, plain, Z or M; null shapes and empty multipoints skipped, and
// records marked deleted in the .dbf skipped. InputError (naming the file and FID) for a
// non-finite coordinate; std::nullopt when a sibling file is missing or anything is not what
// this reader decodes: other shape types, records out of step with the .shx or the .dbf.
std::optional<std::vector<Point>> read_shapefile_points(const std::string& path);

// One record's shape: its parts' vertices one after another (z only for Z shape types, else
// empty), and where each part starts; no parts for a null shape.
struct ShapeRecord {
    std::vector<Point> xy;
    std::vector<double> z;
    std::vector<std::size_t> part_starts;
};

// Every record of the PolyLine or Polygon (plain, Z or M) .shp at `path`, in record order;
// std::nullopt if a record is deleted in the .dbf, when a sibling file is missing or anything
// is not what this reader decodes (as for read_shapefile_points). Coordinates as stored,
// non-finite ones included.
std::optional<std::vector<ShapeRecord>> read_shapefile_shapes(const std::string& path);

}  // namespace toposimp::io
