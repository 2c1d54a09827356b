// The datasets `toposimp check` compares, read through OGR: each feature's lines or polygon rings
// as point lists (and, where those cannot stand for it in GEOS, its geometry), keyed by a field
// or by order.
#pragma once

#include "core/geometry.hpp"

#include <ogr_geometry.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace toposimp::validate {

struct Feature {
    enum class Type { none, lines, polygons, points };
    std::string key;
    Type type = Type::none;
    std::vector<std::vector<Point>> parts;  // lines: line parts; polygons: rings, polygon by polygon
    std::vector<std::uint32_t> rings_per_polygon;
    bool has_geometry = false;  // (a feature may have none)
    // The geometry as read, kept only for polygons that `parts` cannot give GEOS as they were: an
    // empty ring or polygon, a collection of polygons and other things. Otherwise GEOS gets the
    // rings from `parts` (a copy of every polygon kept through the check was a sixth of its memory).
    std::unique_ptr<OGRGeometry> geometry;
};

struct Layer {
    std::string name;
    std::vector<Feature> features;
    // Read from a TopoJSON: GDAL's reader drops the features whose geometry is null (the
    // specification's {"type":null}, which toposimp writes for a feature without one), so the
    // features in order are the others.
    bool without_nulls = false;
};

// The named layers of `path` (none named: every layer); InputError for an unreadable dataset, a
// missing layer or a missing key field.
std::vector<Layer> read_layers(const std::string& path, const std::vector<std::string>& names, const std::string& key);

}  // namespace toposimp::validate
