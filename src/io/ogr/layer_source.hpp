// One layer as the text writers (GeoJSON, GML) see it: its definition and a way to get each
// feature's attributes and its simplified geometry.
#pragma once

#include <ogrsf_frmts.h>

#include <functional>
#include <memory>
#include <string>

namespace toposimp::io {

struct LayerSource {
    std::string name;
    const OGRSpatialReference* srs = nullptr;  // may be null
    const OGRFeatureDefn* definition = nullptr;
    std::size_t feature_count = 0;
    // Feature i (attributes only) and its geometry (may be null).
    std::function<const OGRFeature*(std::size_t)> feature;
    std::function<std::unique_ptr<OGRGeometry>(std::size_t)> geometry;
};

}  // namespace toposimp::io
