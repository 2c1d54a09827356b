#include "validate/layers.hpp"

#include "io/common/errors.hpp"
#include "io/ogr/gdal_support.hpp"

namespace toposimp::validate {
namespace {

std::vector<Point> points_of(const OGRSimpleCurve& curve) {
    std::vector<Point> points(curve.getNumPoints());
    for (int i = 0; i < curve.getNumPoints(); ++i) points[i] = {curve.getX(i), curve.getY(i)};
    return points;
}

void add_geometry(Feature& feature, const OGRGeometry& geometry) {
    switch (wkbFlatten(geometry.getGeometryType())) {
        case wkbLineString:
        case wkbLinearRing:
            feature.type = Feature::Type::lines;
            feature.parts.push_back(points_of(*geometry.toSimpleCurve()));
            break;
        case wkbPolygon: {
            feature.type = Feature::Type::polygons;
            std::uint32_t rings = 0;
            for (const OGRLinearRing* ring : *geometry.toPolygon()) {
                if (ring->IsEmpty()) continue;
                feature.parts.push_back(points_of(*ring));
                ++rings;
            }
            // (An empty polygon, a multipolygon's EMPTY member, holds nothing to compare, and
            // GDAL's GeoJSON and TopoJSON readers leave it out of what they give back.)
            if (rings > 0) feature.rings_per_polygon.push_back(rings);
            break;
        }
        case wkbPoint:
        case wkbMultiPoint: feature.type = Feature::Type::points; break;
        case wkbMultiLineString:
        case wkbMultiPolygon:
        case wkbGeometryCollection:
            for (const OGRGeometry* member : *geometry.toGeometryCollection()) add_geometry(feature, *member);
            break;
        default: break;
    }
}

// Do the rings in `parts` (and rings_per_polygon) give GEOS this polygon geometry as it is?
// Polygons and multipolygons without an empty ring or member: yes.
bool rings_stand_for(const OGRGeometry& geometry) {
    const OGRwkbGeometryType type = wkbFlatten(geometry.getGeometryType());
    auto whole = [](const OGRPolygon& polygon) {
        if (polygon.IsEmpty()) return false;
        for (const OGRLinearRing* ring : polygon) {
            if (ring->IsEmpty()) return false;
        }
        return true;
    };
    if (type == wkbPolygon) return whole(*geometry.toPolygon());
    if (type != wkbMultiPolygon) return false;
    for (const OGRPolygon* polygon : *geometry.toMultiPolygon()) {
        if (!whole(*polygon)) return false;
    }
    return true;
}

}  // namespace

std::vector<Layer> read_layers(const std::string& path, const std::vector<std::string>& names, const std::string& key) {
    io::DatasetPtr dataset = io::open_vector(path);
    std::vector<OGRLayer*> sources;
    if (names.empty()) {
        for (int i = 0; i < dataset->GetLayerCount(); ++i) sources.push_back(dataset->GetLayer(i));
    } else {
        for (const std::string& name : names) sources.push_back(&io::pick_layer(*dataset, path, name));
    }
    std::vector<Layer> layers;
    io::QuietGdal quiet;
    for (OGRLayer* source : sources) {
        Layer layer;
        layer.name = source->GetName();
        layer.without_nulls = std::string(dataset->GetDriverName()) == "TopoJSON";
        const int key_field = key.empty() ? -1 : source->GetLayerDefn()->GetFieldIndex(key.c_str());
        if (!key.empty() && key_field < 0) {
            throw io::InputError("'" + path + "', layer '" + layer.name + "' has no field '" + key + "' (--key)");
        }
        std::size_t index = 0;
        for (auto& ogr_feature : *source) {
            Feature feature;
            feature.key = key_field >= 0 ? ogr_feature->GetFieldAsString(key_field) : std::to_string(index);
            if (const OGRGeometry* geometry = ogr_feature->GetGeometryRef()) {
                add_geometry(feature, *geometry);
                feature.has_geometry = true;
                if (feature.type == Feature::Type::polygons && !rings_stand_for(*geometry)) feature.geometry.reset(geometry->clone());
            }
            layer.features.push_back(std::move(feature));
            ++index;
        }
        layers.push_back(std::move(layer));
    }
    return layers;
}

}  // namespace toposimp::validate
