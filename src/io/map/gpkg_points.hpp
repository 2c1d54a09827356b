// Control points read straight from a GeoPackage table with SQLite, not through OGR.
//
// OGR builds a feature and a geometry object per row: 10 M points take ~10 s of CPU that way,
// against ~1 s for SQLite to step through the rows and hand over the geometry blobs, which are
// then decoded here (GeoPackage binary header + ISO WKB, OGC 12-128r18 §2.1.3). Only what is
// plainly a point is decoded; for anything else the reader gives up and the caller reads the
// layer through OGR, which reports or handles it as for any other format.
#pragma once

#include "core/geometry.hpp"

#include <optional>
#include <string>
#include <vector>

namespace toposimp::io {

struct GpkgTable {
    std::string path;             // a local file
    std::string table;            // the layer's table
    std::string geometry_column;
    std::string fid_column;       // the integer primary key
};

// The points of every row in FID order: Point and MultiPoint geometries, 2D, Z, M or ZM, any
// byte order; NULL and empty geometries skipped. Rows are read in FID ranges on `threads`
// connections at once. InputError (naming file, table and FID) for a non-finite coordinate;
// std::nullopt when the file or a row is not what this reader decodes (then use OGR).
std::optional<std::vector<Point>> read_gpkg_points(const GpkgTable& table, unsigned threads);

// One row's geometry blob (GeoPackage binary header + ISO WKB Point or MultiPoint), its points
// appended to `out`; what read_gpkg_points decodes, exposed for its fuzz target.
enum class PointBlob { ok, not_decoded, non_finite };
PointBlob decode_point_blob(const unsigned char* data, std::size_t size, std::vector<Point>& out);

}  // namespace toposimp::io
