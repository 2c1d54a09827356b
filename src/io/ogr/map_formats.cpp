#include "io/ogr/map_formats.hpp"

#include <array>

namespace toposimp::io {
namespace {

// driver, extensions, several layers, several files, own writer, keeps the FID column, layer option, recommended
constexpr std::array<MapFormatRules, 13> kRules{{
    {"ESRI Shapefile", "shp", false, true, false, false, nullptr, "Shapefile (.shp)"},
    {"GPKG", "gpkg", true, false, false, true, nullptr, "GeoPackage (.gpkg)"},
    {"GeoJSON", "geojson json", false, false, true, false, nullptr, "GeoJSON (.geojson)"},
    // GDAL reads it only: toposimp writes it (io/ogr/topojson_writer.cpp), one object per layer.
    {"TopoJSON", "topojson", true, false, true, false, nullptr, "TopoJSON (.topojson)"},
    // Its spatial index sorts the features: the input order is kept unless asked.
    {"FlatGeobuf", "fgb", false, false, false, false, "SPATIAL_INDEX=NO", "FlatGeobuf (.fgb)"},
    // Read, never written: GDAL 3.6's GML reader parses coordinates inexactly (the read-back refuses).
    {"GML", "gml", false, false, false, false, nullptr, nullptr},
    // Geometries dropped unless written as WKT (17 significant digits: ogr_dataset.cpp).
    {"CSV", "csv", false, false, false, false, "GEOMETRY=AS_WKT", nullptr},
    {"KML", "kml", false, false, false, false, nullptr, nullptr},
    {"SQLite", "sqlite", true, false, false, true, nullptr, nullptr},
    {"GeoJSONSeq", "geojsonl geojsons", false, false, false, false, nullptr, nullptr},
    {"OpenFileGDB", "", true, false, false, false, nullptr, nullptr},
    {"FileGDB", "", true, false, false, false, nullptr, nullptr},
    {"MapInfo File", "", false, true, false, false, nullptr, nullptr},
}};

}  // namespace

std::span<const MapFormatRules> map_format_rules() { return kRules; }

const MapFormatRules* map_format_rules(std::string_view driver) {
    for (const MapFormatRules& rules : kRules) {
        if (driver == rules.driver) return &rules;
    }
    return nullptr;
}

const char* map_driver_for_extension(std::string_view extension) {
    if (extension.empty()) return nullptr;
    for (const MapFormatRules& rules : kRules) {
        std::string_view list = rules.extensions;
        while (!list.empty()) {
            const std::size_t space = list.find(' ');
            if (list.substr(0, space) == extension) return rules.driver;
            list = space == std::string_view::npos ? std::string_view{} : list.substr(space + 1);
        }
    }
    return nullptr;
}

std::string recommended_formats_but(std::string_view driver) {
    std::string text, last;
    for (const MapFormatRules& rules : kRules) {
        if (rules.recommended == nullptr || driver == rules.driver) continue;
        if (!last.empty()) text += (text.empty() ? "" : ", ") + last;
        last = rules.recommended;
    }
    return text.empty() ? last : text + " or " + last;
}

}  // namespace toposimp::io
