// Terrain from a raster DEM (any GDAL raster): one vertex per valid cell centre in map
// coordinates (the geotransform applied; z = the cell value), two triangles per square of four
// valid centres, one per square of three; nodata cells and non-finite values are left out.
// Triangles are counter-clockwise in the map plane. And a TIN written as an OGR layer.
#pragma once

#include "core/mesh/mesh.hpp"

#include <string>

namespace toposimp::io {

struct Dem {
    mesh::Mesh tin;
    std::string crs_wkt;          // the raster's CRS, "" if it has none
    int width = 0, height = 0;
    std::size_t nodata_cells = 0;  // left out (nodata or not finite)
};

// InputError if GDAL cannot open `path` as a raster or it has no such band.
Dem read_dem(const std::string& path, int band);

// Each triangle as a Polygon Z feature of one layer (GDAL driver from the extension or
// `driver`), in the given CRS. For GeoPackage, Shapefile, FlatGeobuf, GeoJSON...
void write_tin_layer(const mesh::Mesh& tin, const std::string& path, const std::string& driver, const std::string& crs_wkt,
                     const std::string& layer_name);

}  // namespace toposimp::io
