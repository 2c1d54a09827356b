#include "io/ogr_layer.hpp"

#include "io/errors.hpp"
#include "io/geojson_writer.hpp"
#include "io/output_file.hpp"
#include "core/map/coverage.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>

namespace toposimp::io {
namespace {

constexpr std::uint32_t kEmptyPart = std::numeric_limits<std::uint32_t>::max();

void register_drivers() {
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
}

// Silences GDAL's own printing for a scope; its messages are read with last_gdal_error().
class QuietGdal {
public:
    QuietGdal() {
        CPLPushErrorHandler(CPLQuietErrorHandler);
        CPLErrorReset();
    }
    ~QuietGdal() { CPLPopErrorHandler(); }
};

std::string last_gdal_error() {
    const char* message = CPLGetLastErrorMsg();
    return message && *message ? std::string(": ") + message : std::string();
}

struct DatasetCloser {
    void operator()(GDALDataset* dataset) const { GDALClose(dataset); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

DatasetPtr open_vector(const std::string& path) {
    register_drivers();
    QuietGdal quiet;
    auto* dataset = static_cast<GDALDataset*>(
        GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
    if (dataset == nullptr) {
        std::error_code error;
        if (path.rfind("/vsi", 0) != 0 && !std::filesystem::exists(path, error)) {
            throw InputError("cannot open '" + path + "': no such file");
        }
        throw InputError("cannot open '" + path + "' as a vector dataset" + last_gdal_error());
    }
    return DatasetPtr(dataset);
}

std::string layer_names(GDALDataset& dataset) {
    std::string names;
    for (int i = 0; i < dataset.GetLayerCount(); ++i) {
        names += (i ? ", " : "") + std::string(dataset.GetLayer(i)->GetName());
    }
    return names.empty() ? "none" : names;
}

OGRLayer& pick_layer(GDALDataset& dataset, const std::string& path, const std::string& name) {
    if (dataset.GetLayerCount() == 0) throw InputError("'" + path + "' has no vector layer");
    if (name.empty()) return *dataset.GetLayer(0);
    OGRLayer* layer = dataset.GetLayerByName(name.c_str());
    if (layer == nullptr) {
        throw InputError("'" + path + "' has no layer '" + name + "' (layers: " + layer_names(dataset) + ")");
    }
    return *layer;
}

std::string feature_label(const std::string& path, OGRLayer& layer, GIntBig fid) {
    return "'" + path + "', layer '" + std::string(layer.GetName()) + "', feature " + std::to_string(fid);
}


}  // namespace

struct OgrLayer::Layer {
    // What a feature's geometry became: chains (lines), coverage rings (polygons), or an
    // untouched copy (points, which also serve as obstacles).
    enum class Kind : std::uint8_t { null, lines, polygons, untouched };
    struct Shape {
        OGRwkbGeometryType type = wkbUnknown;  // the feature's own type, with Z/M flags
        Kind kind = Kind::null;
        std::uint32_t first = 0;  // lines: into items (chain per part); polygons: into items
        std::uint32_t count = 0;  //   (ring count, then ring ids, per polygon); untouched: into untouched
    };

    LayerSummary summary;
    std::string fid_column;
    OGRwkbGeometryType geometry_type = wkbUnknown;
    std::unique_ptr<OGRSpatialReference> srs;
    OGRFeatureDefn* definition = nullptr;  // reference-counted
    std::vector<OGRFeatureUniquePtr> features;  // attributes only: geometries are in the map
    std::vector<Shape> shapes;
    std::vector<std::uint32_t> items;
    std::vector<std::unique_ptr<OGRGeometry>> untouched;
    map::Coverage coverage;
    std::vector<double> z, m;            // per map vertex, when the layer has Z / M
    std::vector<double> ring_z, ring_m;  // per coverage ring point, until the coverage is built

    ~Layer() {
        if (definition) definition->Release();
    }

    bool carries_zm() const { return summary.has_z || summary.has_m; }

    std::unique_ptr<OGRGeometry> build_geometry(std::size_t index, const map::MapData& map,
                                                const std::vector<std::uint8_t>& kept) const;
};

namespace {

std::vector<Point> read_points(const OGRSimpleCurve& curve, const std::string& label) {
    const int count = curve.getNumPoints();
    std::vector<Point> points(count);
    for (int i = 0; i < count; ++i) {
        points[i] = {curve.getX(i), curve.getY(i)};
        if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
            throw InputError(label + ": vertex " + std::to_string(i) + " has a non-finite coordinate (" +
                             std::to_string(points[i].x) + ", " + std::to_string(points[i].y) + ")");
        }
    }
    return points;
}

void append_zm(const OGRSimpleCurve& curve, std::vector<double>& z, std::vector<double>& m) {
    for (int i = 0; i < curve.getNumPoints(); ++i) {
        z.push_back(curve.Is3D() ? curve.getZ(i) : 0.0);
        m.push_back(curve.IsMeasured() ? curve.getM(i) : 0.0);
    }
}

std::uint32_t add_line(OgrLayer::Layer& layer, const OGRSimpleCurve& curve, map::MapData& map, const std::string& label) {
    if (curve.getNumPoints() == 0) return kEmptyPart;
    if (map.vertices.size() + curve.getNumPoints() > std::numeric_limits<std::uint32_t>::max() / 2) {
        throw InputError(label + ": more than 2 billion vertices in one map");
    }
    const std::uint32_t chain = map.add_chain(read_points(curve, label));
    if (layer.carries_zm()) append_zm(curve, layer.z, layer.m);
    return chain;
}

void add_polygon(OgrLayer::Layer& layer, const OGRPolygon& polygon, const std::string& label) {
    std::vector<const OGRLinearRing*> rings;
    for (const OGRLinearRing* ring : polygon) {
        if (!ring->IsEmpty()) rings.push_back(ring);
    }
    layer.items.push_back(static_cast<std::uint32_t>(rings.size()));
    for (const OGRLinearRing* ring : rings) {
        layer.items.push_back(layer.coverage.add_ring(read_points(*ring, label)));
        if (layer.carries_zm()) append_zm(*ring, layer.ring_z, layer.ring_m);
    }
}

void set_point(OGRSimpleCurve& line, int i, Point p, bool with_z, bool with_m, double z, double m) {
    if (with_z && with_m) {
        line.setPoint(i, p.x, p.y, z, m);
    } else if (with_z) {
        line.setPoint(i, p.x, p.y, z);
    } else if (with_m) {
        line.setPointM(i, p.x, p.y, m);
    } else {
        line.setPoint(i, p.x, p.y);
    }
}

}  // namespace

OgrLayer::OgrLayer(std::unique_ptr<Layer> layer) : layer_(std::move(layer)) {}
OgrLayer::OgrLayer(OgrLayer&&) noexcept = default;
OgrLayer::~OgrLayer() = default;

const LayerSummary& OgrLayer::summary() const { return layer_->summary; }

OgrLayer OgrLayer::read(const std::string& path, const std::string& layer_name, map::MapData& map) {
    DatasetPtr dataset = open_vector(path);
    OGRLayer& source = pick_layer(*dataset, path, layer_name);
    auto layer = std::make_unique<Layer>();
    layer->summary.driver = dataset->GetDriver() ? dataset->GetDriver()->GetDescription() : "";
    layer->summary.layer = source.GetName();
    layer->fid_column = source.GetFIDColumn();
    layer->geometry_type = source.GetGeomType();
    layer->summary.has_z = OGR_GT_HasZ(layer->geometry_type);
    layer->summary.has_m = OGR_GT_HasM(layer->geometry_type);
    if (const OGRSpatialReference* srs = source.GetSpatialRef()) layer->srs.reset(srs->Clone());
    layer->definition = source.GetLayerDefn();
    layer->definition->Reference();

    QuietGdal quiet;
    source.ResetReading();
    std::uint64_t simplifiable = 0;
    while (OGRFeatureUniquePtr feature{source.GetNextFeature()}) {
        const std::string label = feature_label(path, source, feature->GetFID());
        Layer::Shape shape;
        shape.first = static_cast<std::uint32_t>(layer->items.size());
        OGRGeometry* geometry = feature->GetGeometryRef();
        if (geometry != nullptr) {
            shape.type = geometry->getGeometryType();
            const bool z = geometry->Is3D(), m = geometry->IsMeasured();
            if ((z && !layer->summary.has_z) || (m && !layer->summary.has_m)) {
                // A layer declared 2D holding 3D features: keep their Z/M too.
                layer->summary.has_z = layer->summary.has_z || z;
                layer->summary.has_m = layer->summary.has_m || m;
                layer->z.resize(map.vertices.size(), 0.0);
                layer->m.resize(map.vertices.size(), 0.0);
                layer->ring_z.resize(layer->coverage.point_count(), 0.0);
                layer->ring_m.resize(layer->coverage.point_count(), 0.0);
            }
            switch (wkbFlatten(shape.type)) {
                case wkbLineString:
                    shape.kind = Layer::Kind::lines;
                    layer->items.push_back(add_line(*layer, *geometry->toLineString(), map, label));
                    break;
                case wkbMultiLineString:
                    shape.kind = Layer::Kind::lines;
                    for (const OGRLineString* part : *geometry->toMultiLineString()) {
                        layer->items.push_back(add_line(*layer, *part, map, label));
                    }
                    break;
                case wkbPolygon:
                    shape.kind = Layer::Kind::polygons;
                    add_polygon(*layer, *geometry->toPolygon(), label);
                    break;
                case wkbMultiPolygon:
                    shape.kind = Layer::Kind::polygons;
                    for (const OGRPolygon* polygon : *geometry->toMultiPolygon()) add_polygon(*layer, *polygon, label);
                    break;
                case wkbPoint:
                case wkbMultiPoint: {
                    // Points among lines: written back untouched, kept on their side as control points.
                    shape.kind = Layer::Kind::untouched;
                    shape.first = static_cast<std::uint32_t>(layer->untouched.size());
                    auto add = [&](const OGRPoint& point) {
                        if (point.IsEmpty()) return;
                        const Point p{point.getX(), point.getY()};
                        if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(label + ": point has a non-finite coordinate");
                        map.control_points.push_back(p);
                    };
                    if (wkbFlatten(shape.type) == wkbPoint) {
                        add(*geometry->toPoint());
                    } else {
                        for (const OGRPoint* point : *geometry->toMultiPoint()) add(*point);
                    }
                    layer->untouched.emplace_back(geometry->clone());
                    ++layer->summary.untouched_points;
                    break;
                }
                default:
                    throw InputError(label + ": geometry is " + OGRGeometryTypeToName(shape.type) +
                                     "; toposimp map simplifies (Multi)LineString and (Multi)Polygon features" +
                                     (OGR_GT_IsNonLinear(shape.type) ? " (linearize curves first: ogr2ogr -nlt CONVERT_TO_LINEAR)" : ""));
            }
            if (shape.kind != Layer::Kind::untouched) shape.count = static_cast<std::uint32_t>(layer->items.size()) - shape.first;
            if (shape.kind == Layer::Kind::untouched) shape.count = 1;
        }
        if (geometry == nullptr || geometry->IsEmpty()) {
            ++layer->summary.empty_geometries;
        } else if (shape.kind != Layer::Kind::untouched) {
            ++simplifiable;
            if (shape.kind == Layer::Kind::polygons) ++layer->summary.polygon_features;
        }
        feature->SetGeometryDirectly(nullptr);
        layer->shapes.push_back(shape);
        layer->features.push_back(std::move(feature));
    }
    if (CPLGetLastErrorType() >= CE_Failure) {
        throw InputError("error reading '" + path + "', layer '" + layer->summary.layer + "'" + last_gdal_error());
    }
    layer->summary.features = layer->features.size();
    if (simplifiable == 0) {
        throw InputError("'" + path + "', layer '" + layer->summary.layer + "' has no line or polygon geometry (" +
                         OGRGeometryTypeToName(layer->geometry_type) + ", " +
                         std::to_string(layer->summary.features) + " features)");
    }
    // Polygon rings become arcs: one chain per border, shared by the polygons on both sides.
    const std::size_t before = map.vertices.size();
    layer->coverage.build(map);
    if (layer->carries_zm()) {
        layer->z.resize(map.vertices.size(), 0.0);
        layer->m.resize(map.vertices.size(), 0.0);
        for (std::size_t v = before; v < map.vertices.size(); ++v) {
            const std::uint32_t origin = layer->coverage.source_of(static_cast<std::uint32_t>(v));
            layer->z[v] = layer->ring_z[origin];
            layer->m[v] = layer->ring_m[origin];
        }
    }
    layer->summary.arcs = layer->coverage.arc_count();
    layer->summary.shared_arcs = layer->coverage.shared_arc_count();
    layer->summary.degenerate_rings = layer->coverage.degenerate_ring_count();
    return OgrLayer(std::move(layer));
}

std::unique_ptr<OGRGeometry> OgrLayer::Layer::build_geometry(std::size_t index, const map::MapData& map,
                                                             const std::vector<std::uint8_t>& kept) const {
    const Shape& shape = shapes[index];
    const bool with_z = OGR_GT_HasZ(shape.type), with_m = OGR_GT_HasM(shape.type);
    auto zm_flags = [&](OGRGeometry& geometry) {
        if (with_z) geometry.set3D(TRUE);
        if (with_m) geometry.setMeasured(TRUE);
    };
    auto fill = [&](OGRSimpleCurve& curve, const std::vector<std::uint32_t>& vertices) {
        curve.setNumPoints(static_cast<int>(vertices.size()), FALSE);
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const std::uint32_t v = vertices[i];
            set_point(curve, static_cast<int>(i), map.vertices[v], with_z, with_m, with_z ? z[v] : 0.0, with_m ? m[v] : 0.0);
        }
    };
    switch (shape.kind) {
        case Kind::null: return nullptr;
        case Kind::untouched: return std::unique_ptr<OGRGeometry>(untouched[shape.first]->clone());
        case Kind::lines: {
            auto make_line = [&](std::uint32_t chain_index) {
                auto line = std::make_unique<OGRLineString>();
                zm_flags(*line);
                if (chain_index == kEmptyPart) return line;
                std::vector<std::uint32_t> vertices;
                for (std::uint32_t v = map.chains[chain_index].first; v <= map.chains[chain_index].last; ++v) {
                    if (kept[v]) vertices.push_back(v);
                }
                fill(*line, vertices);
                return line;
            };
            if (wkbFlatten(shape.type) == wkbLineString) return make_line(shape.count ? items[shape.first] : kEmptyPart);
            auto multi = std::make_unique<OGRMultiLineString>();
            zm_flags(*multi);
            for (std::uint32_t k = 0; k < shape.count; ++k) multi->addGeometryDirectly(make_line(items[shape.first + k]).release());
            return multi;
        }
        case Kind::polygons: {
            std::uint32_t k = shape.first;
            auto make_polygon = [&]() {
                auto polygon = std::make_unique<OGRPolygon>();
                zm_flags(*polygon);
                const std::uint32_t rings = items[k++];
                for (std::uint32_t r = 0; r < rings; ++r) {
                    auto ring = std::make_unique<OGRLinearRing>();
                    zm_flags(*ring);
                    fill(*ring, coverage.ring_vertices(items[k++], kept));
                    polygon->addRingDirectly(ring.release());
                }
                return polygon;
            };
            if (wkbFlatten(shape.type) == wkbPolygon) {
                if (shape.count == 0) {
                    auto empty = std::make_unique<OGRPolygon>();
                    zm_flags(*empty);
                    return empty;
                }
                return make_polygon();
            }
            auto multi = std::make_unique<OGRMultiPolygon>();
            zm_flags(*multi);
            while (k < shape.first + shape.count) multi->addGeometryDirectly(make_polygon().release());
            return multi;
        }
    }
    return nullptr;
}

namespace {

GDALDriver* choose_driver(const WriteOptions& options) {
    register_drivers();
    GDALDriverManager& drivers = *GetGDALDriverManager();
    std::string name = options.format;
    if (name.empty()) {
        std::string extension = std::filesystem::path(options.path).extension().string();
        if (!extension.empty()) extension.erase(0, 1);
        std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
        static const std::pair<const char*, const char*> kKnown[] = {
            {"shp", "ESRI Shapefile"}, {"gpkg", "GPKG"},  {"geojson", "GeoJSON"}, {"json", "GeoJSON"},
            {"fgb", "FlatGeobuf"},     {"gml", "GML"},    {"csv", "CSV"},         {"kml", "KML"},
            {"sqlite", "SQLite"},      {"geojsonl", "GeoJSONSeq"}, {"geojsons", "GeoJSONSeq"},
        };
        for (const auto& [known_extension, driver] : kKnown) {
            if (extension == known_extension) name = driver;
        }
        for (int i = 0; name.empty() && i < drivers.GetDriverCount(); ++i) {
            GDALDriver* driver = drivers.GetDriver(i);
            const char* extensions = driver->GetMetadataItem(GDAL_DMD_EXTENSIONS);
            if (!extensions || !driver->GetMetadataItem(GDAL_DCAP_VECTOR) || !driver->GetMetadataItem(GDAL_DCAP_CREATE)) {
                continue;
            }
            const CPLStringList list(CSLTokenizeString(extensions));
            if (!extension.empty() && list.FindString(extension.c_str()) >= 0) name = driver->GetDescription();
        }
        if (name.empty()) {
            throw OutputError("cannot tell the output format of '" + options.path + "' from its extension; name it with -f (e.g. -f GPKG)");
        }
    }
    GDALDriver* driver = drivers.GetDriverByName(name.c_str());
    if (driver == nullptr || !driver->GetMetadataItem(GDAL_DCAP_VECTOR)) {
        throw OutputError("unknown vector output format '" + name + "' (see `ogrinfo --formats`)");
    }
    if (!driver->GetMetadataItem(GDAL_DCAP_CREATE)) throw OutputError("GDAL cannot create '" + name + "' files");
    return driver;
}

// The point sequences of a geometry: line parts, polygon rings (all of them, in order), points.
void collect_parts(const OGRGeometry* geometry, std::vector<const OGRSimpleCurve*>& parts,
                   std::vector<const OGRPoint*>& points) {
    if (geometry == nullptr || geometry->IsEmpty()) return;
    switch (wkbFlatten(geometry->getGeometryType())) {
        case wkbLineString: parts.push_back(geometry->toLineString()); break;
        case wkbPolygon:
            for (const OGRLinearRing* ring : *geometry->toPolygon()) {
                if (!ring->IsEmpty()) parts.push_back(ring);
            }
            break;
        case wkbPoint: points.push_back(geometry->toPoint()); break;
        case wkbMultiLineString:
        case wkbMultiPolygon:
        case wkbMultiPoint:
        case wkbGeometryCollection:
            for (const OGRGeometry* member : *geometry->toGeometryCollection()) collect_parts(member, parts, points);
            break;
        default: break;
    }
}

// Do two geometries hold the same coordinates, bit for bit? A LineString equals a one-part
// MultiLineString, and a ring may come back reversed (Shapefile writes rings in its own
// orientation); nothing else may differ.
bool same_coordinates(const OGRGeometry* expected, const OGRGeometry* actual, std::string& difference) {
    std::vector<const OGRSimpleCurve*> want, got;
    std::vector<const OGRPoint*> want_points, got_points;
    collect_parts(expected, want, want_points);
    collect_parts(actual, got, got_points);
    if (want.size() != got.size() || want_points.size() != got_points.size()) {
        difference = std::to_string(want.size()) + " parts became " + std::to_string(got.size());
        return false;
    }
    for (std::size_t k = 0; k < want_points.size(); ++k) {
        if (!(want_points[k]->getX() == got_points[k]->getX()) || !(want_points[k]->getY() == got_points[k]->getY())) {
            difference = "point " + std::to_string(k) + " moved";
            return false;
        }
    }
    for (std::size_t k = 0; k < want.size(); ++k) {
        const int n = want[k]->getNumPoints();
        if (n != got[k]->getNumPoints()) {
            difference = "part " + std::to_string(k) + " has " + std::to_string(got[k]->getNumPoints()) +
                         " vertices, not " + std::to_string(n);
            return false;
        }
        auto matches = [&](bool reversed, int& bad) {
            for (int i = 0; i < n; ++i) {
                const int j = reversed ? n - 1 - i : i;
                const bool z_differs = want[k]->Is3D() && got[k]->Is3D() && !(want[k]->getZ(i) == got[k]->getZ(j));
                if (!(want[k]->getX(i) == got[k]->getX(j)) || !(want[k]->getY(i) == got[k]->getY(j)) || z_differs) {
                    bad = i;
                    return false;
                }
            }
            return true;
        };
        int bad = 0, ignored = 0;
        const bool ring = wkbFlatten(want[k]->getGeometryType()) == wkbLineString && want[k]->get_IsClosed();
        if (!matches(false, bad) && !(ring && matches(true, ignored))) {
            char text[200];
            std::snprintf(text, sizeof text, "part %zu, vertex %d: (%.17g, %.17g) was written as (%.17g, %.17g)", k, bad,
                          want[k]->getX(bad), want[k]->getY(bad), got[k]->getX(bad), got[k]->getY(bad));
            difference = text;
            return false;
        }
    }
    return true;
}

}  // namespace

std::vector<std::string> OgrLayer::write(const WriteOptions& options, const map::MapData& map,
                                         const std::vector<std::uint8_t>& kept) const {
    const Layer& layer = *layer_;
    std::vector<std::string> warnings;
    GDALDriver* driver = choose_driver(options);
    const std::string driver_name = driver->GetDescription();
    OutputFile output(options.path, options.overwrite, options.stdout_stream);
    if (output.to_stdout() && (driver_name == "ESRI Shapefile" || driver_name == "MapInfo File")) {
        throw OutputError("a " + driver_name + " is several files and cannot go to stdout; use -f GeoJSON, FlatGeobuf or GPKG");
    }
    const std::string layer_name = options.layer_name.empty() ? layer.summary.layer : options.layer_name;

    if (driver_name == "GeoJSON") {
        if (!options.layer_options.empty() || !options.dataset_options.empty()) {
            warnings.push_back("-lco/-dsco are ignored for GeoJSON: toposimp writes GeoJSON itself to keep coordinates exact");
        }
        GeoJsonLayer json;
        json.name = layer_name;
        json.srs = layer.srs.get();
        json.definition = layer.definition;
        json.feature_count = layer.features.size();
        json.feature = [&](std::size_t i) { return layer.features[i].get(); };
        json.geometry = [&](std::size_t i) { return layer.build_geometry(i, map, kept); };
        auto more = write_geojson(output.staging_path(), json);
        warnings.insert(warnings.end(), more.begin(), more.end());
    } else {
        QuietGdal quiet;
        CPLStringList dataset_options, layer_options;
        for (const auto& option : options.dataset_options) dataset_options.AddString(option.c_str());
        for (const auto& option : options.layer_options) layer_options.AddString(option.c_str());
        // CSV drops geometries unless asked to write them as WKT.
        if (driver_name == "CSV" && layer_options.FetchNameValue("GEOMETRY") == nullptr) {
            layer_options.SetNameValue("GEOMETRY", "AS_WKT");
        }
        // Databases with an FID column (GPKG, SQLite): keep the source's FID column name, and
        // never collide with an attribute field of that name (GML inputs have a string 'fid').
        if ((driver_name == "GPKG" || driver_name == "SQLite") && layer_options.FetchNameValue("FID") == nullptr) {
            std::string fid = layer.fid_column.empty() ? "fid" : layer.fid_column;
            while (layer.definition->GetFieldIndex(fid.c_str()) >= 0) fid += "_";
            layer_options.SetNameValue("FID", fid.c_str());
        }
        // FlatGeobuf's spatial index sorts the features; keep the input order unless asked.
        if (driver_name == "FlatGeobuf" && layer_options.FetchNameValue("SPATIAL_INDEX") == nullptr) {
            layer_options.SetNameValue("SPATIAL_INDEX", "NO");
        }
        // CSV writes WKT: ask for 17 significant digits (the read-back below checks the result).
        CPLConfigOptionSetter precision("OGR_WKT_PRECISION", "17", true);
        DatasetPtr dataset(driver->Create(output.staging_path().c_str(), 0, 0, 0, GDT_Unknown, dataset_options.List()));
        if (!dataset) throw OutputError("cannot create '" + options.path + "' (" + driver_name + ")" + last_gdal_error());
        OGRLayer* target = dataset->CreateLayer(layer_name.c_str(), layer.srs.get(), layer.geometry_type, layer_options.List());
        if (target == nullptr) throw OutputError("cannot create layer '" + layer_name + "' in '" + options.path + "'" + last_gdal_error());
        for (int i = 0; i < layer.definition->GetFieldCount(); ++i) {
            if (target->CreateField(layer.definition->GetFieldDefn(i), TRUE) != OGRERR_NONE) {
                throw OutputError("cannot create field '" + std::string(layer.definition->GetFieldDefn(i)->GetNameRef()) +
                                  "' in '" + options.path + "'" + last_gdal_error());
            }
        }
        if (target->GetLayerDefn()->GetFieldCount() != layer.definition->GetFieldCount()) {
            throw OutputError("'" + options.path + "' (" + driver_name + ") could not keep all " +
                              std::to_string(layer.definition->GetFieldCount()) + " fields");
        }
        std::vector<int> field_map(layer.definition->GetFieldCount());
        for (std::size_t i = 0; i < field_map.size(); ++i) field_map[i] = static_cast<int>(i);
        const bool keep_fids = !layer.fid_column.empty();
        const bool transaction = dataset->StartTransaction() == OGRERR_NONE;
        for (std::size_t i = 0; i < layer.features.size(); ++i) {
            OGRFeature feature(target->GetLayerDefn());
            feature.SetFrom(layer.features[i].get(), field_map.data(), TRUE);
            if (keep_fids) feature.SetFID(layer.features[i]->GetFID());
            feature.SetGeometryDirectly(layer.build_geometry(i, map, kept).release());
            if (target->CreateFeature(&feature) != OGRERR_NONE) {
                throw OutputError("cannot write feature " + std::to_string(layer.features[i]->GetFID()) + " to '" +
                                  options.path + "'" + last_gdal_error());
            }
        }
        if (transaction && dataset->CommitTransaction() != OGRERR_NONE) {
            throw OutputError("cannot commit '" + options.path + "'" + last_gdal_error());
        }
        dataset.reset();
        if (CPLGetLastErrorType() >= CE_Failure) throw OutputError("error writing '" + options.path + "'" + last_gdal_error());
    }

    // Read the file back: coordinates must have survived bit for bit, features all there.
    {
        DatasetPtr written = open_vector(output.staging_path());
        OGRLayer* check = written->GetLayerByName(layer_name.c_str());
        if (check == nullptr && written->GetLayerCount() == 1) check = written->GetLayer(0);
        if (check == nullptr) throw OutputError("'" + options.path + "': written layer '" + layer_name + "' cannot be read back");
        QuietGdal quiet;
        std::size_t i = 0;
        for (OGRFeatureUniquePtr feature{check->GetNextFeature()}; feature; feature.reset(check->GetNextFeature()), ++i) {
            if (i >= layer.features.size()) break;
            std::string difference;
            const auto expected = layer.build_geometry(i, map, kept);
            if (!same_coordinates(expected.get(), feature->GetGeometryRef(), difference)) {
                throw OutputError("the " + driver_name + " driver changed coordinates while writing '" + options.path +
                                  "' (feature " + std::to_string(layer.features[i]->GetFID()) + ", " + difference +
                                  "); toposimp never rounds coordinates: write GeoPackage (.gpkg), FlatGeobuf (.fgb), "
                                  "Shapefile (.shp) or GeoJSON (.geojson) instead");
            }
        }
        if (i != layer.features.size()) {
            throw OutputError("'" + options.path + "' holds " + std::to_string(i) + " features after writing, not " +
                              std::to_string(layer.features.size()));
        }
    }
    output.commit([driver](const std::string& existing) {
        QuietGdal quiet;
        driver->Delete(existing.c_str());
    });
    return warnings;
}

std::vector<Point> read_control_points(const std::string& spec) {
    std::string path = spec, layer_name;
    std::error_code error;
    const std::size_t colon = spec.rfind(':');
    if (!std::filesystem::exists(spec, error) && colon != std::string::npos && colon > 0 && spec.rfind("/vsi", 0) != 0) {
        path = spec.substr(0, colon);
        layer_name = spec.substr(colon + 1);
    }
    DatasetPtr dataset = open_vector(path);
    OGRLayer& layer = pick_layer(*dataset, path, layer_name);
    std::vector<Point> points;
    QuietGdal quiet;
    auto add = [&](const OGRPoint& point, const std::string& label) {
        if (point.IsEmpty()) return;
        const Point p{point.getX(), point.getY()};
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(label + ": control point has a non-finite coordinate");
        points.push_back(p);
    };
    while (OGRFeatureUniquePtr feature{layer.GetNextFeature()}) {
        const OGRGeometry* geometry = feature->GetGeometryRef();
        if (geometry == nullptr) continue;
        const std::string label = feature_label(path, layer, feature->GetFID());
        switch (wkbFlatten(geometry->getGeometryType())) {
            case wkbPoint: add(*geometry->toPoint(), label); break;
            case wkbMultiPoint:
                for (const OGRPoint* point : *geometry->toMultiPoint()) add(*point, label);
                break;
            default:
                throw InputError(label + ": control points must be Point or MultiPoint, not " +
                                 OGRGeometryTypeToName(geometry->getGeometryType()));
        }
    }
    if (CPLGetLastErrorType() >= CE_Failure) throw InputError("error reading '" + path + "'" + last_gdal_error());
    return points;
}

std::string gdal_version() { return GDALVersionInfo("RELEASE_NAME"); }

}  // namespace toposimp::io
