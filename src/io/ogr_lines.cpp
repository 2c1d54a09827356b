#include "io/ogr_lines.hpp"

#include "io/errors.hpp"
#include "io/geojson_writer.hpp"
#include "io/output_file.hpp"

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

bool is_empty(const OGRGeometry* geometry) { return geometry == nullptr || geometry->IsEmpty(); }

}  // namespace

struct OgrLines::Layer {
    // One feature's geometry: a run of parts (chain indices, kEmptyPart for an empty member).
    struct Shape {
        OGRwkbGeometryType type = wkbUnknown;  // the feature's own type, with Z/M flags
        bool null = true;
        std::uint32_t first_part = 0;
        std::uint32_t part_count = 0;
    };

    LayerSummary summary;
    std::string fid_column;
    OGRwkbGeometryType geometry_type = wkbUnknown;
    std::unique_ptr<OGRSpatialReference> srs;
    OGRFeatureDefn* definition = nullptr;  // reference-counted
    std::vector<OGRFeatureUniquePtr> features;  // attributes only: geometries are in the map
    std::vector<Shape> shapes;
    std::vector<std::uint32_t> parts;
    std::vector<double> z, m;  // per map vertex, when the layer has Z / M

    ~Layer() {
        if (definition) definition->Release();
    }

    std::unique_ptr<OGRGeometry> build_geometry(std::size_t index, const map::MapData& map,
                                                const std::vector<std::uint8_t>& kept) const;
};

namespace {

std::uint32_t add_part(OgrLines::Layer& layer, const OGRSimpleCurve& curve, map::MapData& map,
                       const std::string& label) {
    const int count = curve.getNumPoints();
    if (count == 0) return kEmptyPart;
    if (map.vertices.size() + count > std::numeric_limits<std::uint32_t>::max() - 1) {
        throw InputError(label + ": more than 4 billion vertices in one map");
    }
    std::vector<Point> points(count);
    for (int i = 0; i < count; ++i) {
        points[i] = {curve.getX(i), curve.getY(i)};
        if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
            throw InputError(label + ": vertex " + std::to_string(i) + " has a non-finite coordinate (" +
                             std::to_string(points[i].x) + ", " + std::to_string(points[i].y) + ")");
        }
    }
    if (layer.summary.has_z || layer.summary.has_m) {
        for (int i = 0; i < count; ++i) {
            layer.z.push_back(curve.Is3D() ? curve.getZ(i) : 0.0);
            layer.m.push_back(curve.IsMeasured() ? curve.getM(i) : 0.0);
        }
    }
    return map.add_chain(points);
}

}  // namespace

OgrLines::OgrLines(std::unique_ptr<Layer> layer) : layer_(std::move(layer)) {}
OgrLines::OgrLines(OgrLines&&) noexcept = default;
OgrLines::~OgrLines() = default;

const LayerSummary& OgrLines::summary() const { return layer_->summary; }

OgrLines OgrLines::read(const std::string& path, const std::string& layer_name, map::MapData& map) {
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
    std::uint64_t lines = 0;
    while (OGRFeatureUniquePtr feature{source.GetNextFeature()}) {
        const std::string label = feature_label(path, source, feature->GetFID());
        Layer::Shape shape;
        shape.first_part = static_cast<std::uint32_t>(layer->parts.size());
        OGRGeometry* geometry = feature->GetGeometryRef();
        if (geometry != nullptr) {
            shape.null = false;
            shape.type = geometry->getGeometryType();
            const bool z = geometry->Is3D(), m = geometry->IsMeasured();
            if ((z && !layer->summary.has_z) || (m && !layer->summary.has_m)) {
                // A layer declared 2D holding 3D features: keep their Z/M too.
                layer->summary.has_z = layer->summary.has_z || z;
                layer->summary.has_m = layer->summary.has_m || m;
                layer->z.resize(map.vertices.size(), 0.0);
                layer->m.resize(map.vertices.size(), 0.0);
            }
            switch (wkbFlatten(shape.type)) {
                case wkbLineString:
                    layer->parts.push_back(add_part(*layer, *geometry->toLineString(), map, label));
                    break;
                case wkbMultiLineString:
                    for (const OGRLineString* part : *geometry->toMultiLineString()) {
                        layer->parts.push_back(add_part(*layer, *part, map, label));
                    }
                    break;
                default:
                    throw InputError(label + ": geometry is " + OGRGeometryTypeToName(shape.type) +
                                     "; toposimp map simplifies LineString and MultiLineString layers");
            }
        }
        shape.part_count = static_cast<std::uint32_t>(layer->parts.size()) - shape.first_part;
        if (is_empty(geometry)) {
            ++layer->summary.empty_geometries;
        } else {
            ++lines;
        }
        feature->SetGeometryDirectly(nullptr);
        layer->shapes.push_back(shape);
        layer->features.push_back(std::move(feature));
    }
    if (CPLGetLastErrorType() >= CE_Failure) {
        throw InputError("error reading '" + path + "', layer '" + layer->summary.layer + "'" + last_gdal_error());
    }
    layer->summary.features = layer->features.size();
    if (lines == 0) {
        throw InputError("'" + path + "', layer '" + layer->summary.layer + "' has no line geometry (" +
                         OGRGeometryTypeToName(layer->geometry_type) + ", " +
                         std::to_string(layer->summary.features) + " features)");
    }
    return OgrLines(std::move(layer));
}

std::unique_ptr<OGRGeometry> OgrLines::Layer::build_geometry(std::size_t index, const map::MapData& map,
                                                             const std::vector<std::uint8_t>& kept) const {
    const Shape& shape = shapes[index];
    if (shape.null) return nullptr;
    const bool with_z = OGR_GT_HasZ(shape.type), with_m = OGR_GT_HasM(shape.type);
    auto make_line = [&](std::uint32_t chain_index) {
        auto line = std::make_unique<OGRLineString>();
        if (with_z) line->set3D(TRUE);
        if (with_m) line->setMeasured(TRUE);
        if (chain_index == kEmptyPart) return line;
        const map::Chain& chain = map.chains[chain_index];
        int count = 0;
        for (std::uint32_t v = chain.first; v <= chain.last; ++v) count += kept[v] ? 1 : 0;
        line->setNumPoints(count, FALSE);
        int i = 0;
        for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
            if (!kept[v]) continue;
            const Point p = map.vertices[v];
            if (with_z && with_m) {
                line->setPoint(i, p.x, p.y, z[v], m[v]);
            } else if (with_z) {
                line->setPoint(i, p.x, p.y, z[v]);
            } else if (with_m) {
                line->setPointM(i, p.x, p.y, m[v]);
            } else {
                line->setPoint(i, p.x, p.y);
            }
            ++i;
        }
        return line;
    };
    if (wkbFlatten(shape.type) == wkbLineString) {
        if (shape.part_count == 0) return make_line(kEmptyPart);
        return make_line(parts[shape.first_part]);
    }
    auto multi = std::make_unique<OGRMultiLineString>();
    for (std::uint32_t k = 0; k < shape.part_count; ++k) multi->addGeometryDirectly(make_line(parts[shape.first_part + k]).release());
    if (with_z) multi->set3D(TRUE);
    if (with_m) multi->setMeasured(TRUE);
    return multi;
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

// Do two geometries hold the same coordinates, bit for bit (LineString ≡ one-part MultiLineString)?
bool same_coordinates(const OGRGeometry* expected, const OGRGeometry* actual, std::string& difference) {
    auto parts = [](const OGRGeometry* g) {
        std::vector<const OGRLineString*> list;
        if (g == nullptr || g->IsEmpty()) return list;
        if (wkbFlatten(g->getGeometryType()) == wkbLineString) {
            list.push_back(g->toLineString());
        } else if (wkbFlatten(g->getGeometryType()) == wkbMultiLineString) {
            for (const OGRLineString* part : *g->toMultiLineString()) {
                if (!part->IsEmpty()) list.push_back(part);
            }
        }
        return list;
    };
    const auto want = parts(expected), got = parts(actual);
    if (want.size() != got.size()) {
        difference = std::to_string(want.size()) + " parts became " + std::to_string(got.size());
        return false;
    }
    for (std::size_t k = 0; k < want.size(); ++k) {
        if (want[k]->getNumPoints() != got[k]->getNumPoints()) {
            difference = "part " + std::to_string(k) + " has " + std::to_string(got[k]->getNumPoints()) +
                         " vertices, not " + std::to_string(want[k]->getNumPoints());
            return false;
        }
        for (int i = 0; i < want[k]->getNumPoints(); ++i) {
            const bool z_differs = want[k]->Is3D() && got[k]->Is3D() && !(want[k]->getZ(i) == got[k]->getZ(i));
            if (!(want[k]->getX(i) == got[k]->getX(i)) || !(want[k]->getY(i) == got[k]->getY(i)) || z_differs) {
                char text[160];
                std::snprintf(text, sizeof text, "vertex %d: (%.17g, %.17g) was written as (%.17g, %.17g)", i,
                              want[k]->getX(i), want[k]->getY(i), got[k]->getX(i), got[k]->getY(i));
                difference = text;
                return false;
            }
        }
    }
    return true;
}

}  // namespace

std::vector<std::string> OgrLines::write(const WriteOptions& options, const map::MapData& map,
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
