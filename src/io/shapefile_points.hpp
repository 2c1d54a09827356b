// Control points read straight from a Shapefile's .shp, .shx and .dbf, not through OGR.
//
// Reading features through OGR makes the Shapefile driver parse the layer's .prj with PROJ
// (and look for a matching EPSG entry in proj.db) the first time a geometry is handed out:
// on a small map that is a fifth of the whole run, for a CRS the control points do not need.
// The point records themselves are trivial to decode (ESRI Shapefile Technical Description,
// 1998): this reader does that and gives up on anything unexpected, and the caller then reads
// the layer through OGR, which reports or handles it as for any other format.
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

}  // namespace toposimp::io
