#include "io/ogr/geojson_writer.hpp"

#include "io/common/errors.hpp"
#include "io/ogr/field_text.hpp"
#include "io/common/json_text.hpp"
#include "io/common/number_format.hpp"

#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <fstream>

namespace toposimp::io {
namespace {

void append_property(std::string& out, const OGRFeature& feature, int field) {
    const OGRFieldDefn* definition = feature.GetFieldDefnRef(field);
    const OGRFieldType type = definition->GetType();
    const bool boolean = definition->GetSubType() == OFSTBoolean;
    int count = 0;
    switch (type) {
        case OFTInteger:
            if (boolean) {
                out += feature.GetFieldAsInteger(field) ? "true" : "false";
            } else {
                out += std::to_string(feature.GetFieldAsInteger(field));
            }
            return;
        case OFTInteger64: out += std::to_string(feature.GetFieldAsInteger64(field)); return;
        case OFTReal: append_json_number(out, feature.GetFieldAsDouble(field)); return;
        case OFTDate:
        case OFTTime:
        case OFTDateTime: append_json_string(out, iso_date_time(feature, field, type)); return;
        case OFTIntegerList: {
            const int* values = feature.GetFieldAsIntegerList(field, &count);
            out += '[';
            for (int i = 0; i < count; ++i) {
                if (i) out += ',';
                out += boolean ? (values[i] ? "true" : "false") : std::to_string(values[i]);
            }
            out += ']';
            return;
        }
        case OFTInteger64List: {
            const GIntBig* values = feature.GetFieldAsInteger64List(field, &count);
            out += '[';
            for (int i = 0; i < count; ++i) {
                if (i) out += ',';
                out += std::to_string(values[i]);
            }
            out += ']';
            return;
        }
        case OFTRealList: {
            const double* values = feature.GetFieldAsDoubleList(field, &count);
            out += '[';
            for (int i = 0; i < count; ++i) {
                if (i) out += ',';
                append_json_number(out, values[i]);
            }
            out += ']';
            return;
        }
        case OFTStringList: {
            char** values = feature.GetFieldAsStringList(field);
            out += '[';
            for (int i = 0; values && values[i]; ++i) {
                if (i) out += ',';
                append_json_string(out, values[i]);
            }
            out += ']';
            return;
        }
        default: append_json_string(out, feature.GetFieldAsString(field)); return;
    }
}

struct CoordinateWriter {
    std::string& out;
    bool dropped_m = false;

    void line(const OGRSimpleCurve& curve) {
        out += '[';
        for (int i = 0; i < curve.getNumPoints(); ++i) {
            if (i) out += ',';
            position(curve.getX(i), curve.getY(i), curve, curve.Is3D() ? curve.getZ(i) : 0.0);
        }
        out += ']';
    }

    void position(double x, double y, const OGRGeometry& owner, double z) {
        out += '[';
        append_number(out, x);
        out += ',';
        append_number(out, y);
        if (owner.Is3D()) {
            out += ',';
            append_number(out, z);
        }
        out += ']';
        dropped_m = dropped_m || owner.IsMeasured();
    }

    void polygon(const OGRPolygon& shape) {
        out += '[';
        bool first = true;
        for (const OGRLinearRing* ring : shape) {
            if (!first) out += ',';
            first = false;
            line(*ring);
        }
        out += ']';
    }

    template <class Collection, class Write>
    void members(const Collection& collection, Write&& write) {
        out += '[';
        for (int i = 0; i < collection.getNumGeometries(); ++i) {
            if (i) out += ',';
            write(*collection.getGeometryRef(i));
        }
        out += ']';
    }

    void geometry(const OGRGeometry* geometry) {
        if (geometry == nullptr) {
            out += "null";
            return;
        }
        const OGRwkbGeometryType type = wkbFlatten(geometry->getGeometryType());
        switch (type) {
            case wkbPoint: {
                out += R"({"type":"Point","coordinates":)";
                const OGRPoint& point = *geometry->toPoint();
                if (point.IsEmpty()) {
                    out += "[]";
                } else {
                    position(point.getX(), point.getY(), point, point.getZ());
                }
                break;
            }
            case wkbMultiPoint:
                out += R"({"type":"MultiPoint","coordinates":)";
                members(*geometry->toMultiPoint(), [&](const OGRPoint& p) { position(p.getX(), p.getY(), p, p.getZ()); });
                break;
            case wkbLineString:
                out += R"({"type":"LineString","coordinates":)";
                line(*geometry->toLineString());
                break;
            case wkbMultiLineString:
                out += R"({"type":"MultiLineString","coordinates":)";
                members(*geometry->toMultiLineString(), [&](const OGRLineString& part) { line(part); });
                break;
            case wkbPolygon:
                out += R"({"type":"Polygon","coordinates":)";
                polygon(*geometry->toPolygon());
                break;
            case wkbMultiPolygon:
                out += R"({"type":"MultiPolygon","coordinates":)";
                members(*geometry->toMultiPolygon(), [&](const OGRPolygon& part) { polygon(part); });
                break;
            default:
                throw OutputError(std::string("GeoJSON writer: unsupported geometry type ") +
                                  OGRGeometryTypeToName(geometry->getGeometryType()));
        }
        out += '}';
    }
};

void append_crs(std::string& out, const OGRSpatialReference* srs, std::vector<std::string>& warnings) {
    if (srs == nullptr) return;
    const char* authority = srs->GetAuthorityName(nullptr);
    const char* code = srs->GetAuthorityCode(nullptr);
    if (authority && code) {
        std::string name = std::string("urn:ogc:def:crs:") + authority + "::" + code;
        if (std::string(authority) == "EPSG" && std::string(code) == "4326") name = "urn:ogc:def:crs:OGC:1.3:CRS84";
        out += R"("crs":{"type":"name","properties":{"name":)";
        append_json_string(out, name.c_str());
        out += "}},\n";
    } else {
        warnings.push_back("the layer's CRS has no authority code and cannot be written to GeoJSON; it is left out");
    }
}

}  // namespace

void append_properties(std::string& out, const OGRFeature& feature, const OGRFeatureDefn& definition) {
    out += '{';
    bool first = true;
    for (int field = 0; field < definition.GetFieldCount(); ++field) {
        if (!feature.IsFieldSet(field)) continue;
        if (!first) out += ',';
        first = false;
        append_json_string(out, definition.GetFieldDefn(field)->GetNameRef());
        out += ':';
        if (feature.IsFieldNull(field)) {
            out += "null";
        } else {
            append_property(out, feature, field);
        }
    }
    out += '}';
}

std::vector<std::string> write_geojson(const std::string& path, const LayerSource& layer, const std::string& shown_as) {
    const std::string& name = shown_as.empty() ? path : shown_as;
    std::vector<std::string> warnings;
    std::ofstream file(path, std::ios::binary);
    if (!file) throw OutputError("cannot create '" + name + "': " + std::strerror(errno));
    std::string out = "{\n\"type\":\"FeatureCollection\",\n\"name\":";
    append_json_string(out, layer.name.c_str());
    out += ",\n";
    append_crs(out, layer.srs, warnings);
    out += "\"features\":[\n";
    CoordinateWriter coordinates{out};
    for (std::size_t i = 0; i < layer.feature_count; ++i) {
        const OGRFeature& feature = *layer.feature(i);
        out += i ? ",\n{\"type\":\"Feature\",\"properties\":" : "{\"type\":\"Feature\",\"properties\":";
        append_properties(out, feature, *layer.definition);
        out += ",\"geometry\":";
        coordinates.geometry(layer.geometry(i).get());
        out += '}';
        if (out.size() > (1 << 20)) {
            file << out;
            out.clear();
        }
    }
    out += "\n]\n}\n";
    file << out;
    file.close();
    if (!file) throw OutputError("cannot write '" + name + "': " + std::strerror(errno));
    if (coordinates.dropped_m) warnings.push_back("GeoJSON has no M coordinates: M values were not written");
    return warnings;
}

}  // namespace toposimp::io
