// A GeoJSON writer that keeps coordinates bit for bit (GDAL 3.6's GeoJSON driver rounds them,
// whatever its precision options). Attributes follow GDAL's GeoJSON conventions.
#pragma once

#include "io/ogr/layer_source.hpp"

#include <string>
#include <vector>

namespace toposimp::io {

// A feature's attributes as a JSON object, following GDAL's GeoJSON conventions (also TopoJSON's
// properties).
void append_properties(std::string& out, const OGRFeature& feature, const OGRFeatureDefn& definition);

// Writes one FeatureCollection; returns warnings (e.g. M values, which GeoJSON cannot hold).
// `shown_as`: the name errors give the file (the destination, when `path` is its staging file).
std::vector<std::string> write_geojson(const std::string& path, const LayerSource& layer, const std::string& shown_as = {});

}  // namespace toposimp::io
