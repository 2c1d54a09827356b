// A GeoJSON writer that keeps coordinates bit for bit (GDAL 3.6's GeoJSON driver rounds them,
// whatever its precision options). Attributes follow GDAL's GeoJSON conventions.
#pragma once

#include <ogrsf_frmts.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace toposimp::io {

struct GeoJsonLayer {
    std::string name;
    const OGRSpatialReference* srs = nullptr;  // may be null
    const OGRFeatureDefn* definition = nullptr;
    std::size_t feature_count = 0;
    // Feature i (attributes only) and its geometry (may be null).
    std::function<const OGRFeature*(std::size_t)> feature;
    std::function<std::unique_ptr<OGRGeometry>(std::size_t)> geometry;
};

// Writes one FeatureCollection; returns warnings (e.g. M values, which GeoJSON cannot hold).
std::vector<std::string> write_geojson(const std::string& path, const GeoJsonLayer& layer);

}  // namespace toposimp::io
