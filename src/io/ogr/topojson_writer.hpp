// A TopoJSON writer (GDAL reads TopoJSON but cannot write it): one object per layer, each a
// GeometryCollection of the features with their properties; every arc — a border shared by
// two polygons, a line — written once and referenced by the geometries that use it (a reversed
// use as ~index, as the specification says); `bbox`; coordinates bit for bit (shortest
// round-trip decimals), so an unquantized file reads back exactly what toposimp checked.
#pragma once

#include "core/geometry.hpp"
#include "io/ogr/topo_transform.hpp"

#include <ogrsf_frmts.h>

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace toposimp::io {

// One feature's geometry as arc references or points.
struct TopoGeometry {
    enum class Type { null, point, multi_point, line_string, multi_line_string, polygon, multi_polygon };
    Type type = Type::null;
    // Lines: one list of arc references per line (a LineString has one). Polygons: per polygon,
    // its rings, each a list of arc references. A reference is an arc index, or ~index reversed.
    std::vector<std::vector<std::int64_t>> lines;
    std::vector<std::vector<std::vector<std::int64_t>>> polygons;
    std::vector<Point> points;
    bool has_z = false, has_m = false;  // dropped: TopoJSON positions are written as x, y
};

struct TopologyLayer {
    std::string name;
    const OGRFeatureDefn* definition = nullptr;
    std::size_t feature_count = 0;
    std::function<const OGRFeature*(std::size_t)> feature;
    std::function<TopoGeometry(std::size_t)> geometry;
};

// Writes a Topology of `layers` whose arcs are arc(0) … arc(arc_count − 1), each a list of
// positions and, when `ranks` is filled, a third coordinate per position (nested levels: how many
// levels keep the vertex, so that a viewer shows level k by the positions ranked k or more). With a transform, every position must be one it decodes to exactly (OutputError
// otherwise); arcs are then written as integer deltas, points as integers. Returns warnings (Z or
// M values left out). `shown_as`: the name errors give the file.
std::vector<std::string> write_topojson(const std::string& path, std::span<const TopologyLayer> layers, std::size_t arc_count,
                                        const std::function<void(std::size_t, std::vector<Point>&, std::vector<int>& ranks)>& arc,
                                        const std::string& shown_as = {}, const TopoTransform* transform = nullptr);

}  // namespace toposimp::io
