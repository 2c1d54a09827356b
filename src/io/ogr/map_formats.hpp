// The map output formats toposimp knows more about than GDAL tells: which extension names which
// driver, and the rules of writing each. One row per format (map_formats.cpp); any other GDAL
// vector driver that can create files is used as GDAL has it. Whatever the driver, every output
// is read back and its coordinates compared bit for bit before it is moved into place, so a
// driver that rounds is refused, not trusted (ogr_dataset.cpp).
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace toposimp::io {

struct MapFormatRules {
    const char* driver;      // GDAL's short name
    const char* extensions;  // that name this driver, space-separated, lower case ("" if GDAL's list decides)
    bool several_layers;     // one file holds several layers (else one layer per file)
    bool several_files;      // a dataset is several files, so it cannot go to stdout
    bool own_writer;         // written by toposimp itself (GDAL 3.6 rounds GeoJSON, cannot write TopoJSON): io/ogr/*_writer.cpp
    bool keeps_fid_column;   // the source's FID column name is kept (FID=...), renamed away from any field of that name
    const char* layer_option;  // "KEY=VALUE" toposimp sets unless the user sets KEY (-lco), or null
    const char* recommended;   // keeps every coordinate (tested): its name for messages that suggest one, or null
};

std::span<const MapFormatRules> map_format_rules();
// The rules of `driver` (GDAL's short name), or null: GDAL's own behaviour.
const MapFormatRules* map_format_rules(std::string_view driver);
// The driver a lower-case extension (without the dot) names in the table, or null.
const char* map_driver_for_extension(std::string_view extension);
// The recommended formats but `driver`'s, for a message: "FlatGeobuf (.fgb), Shapefile (.shp) or GeoJSON (.geojson)".
std::string recommended_formats_but(std::string_view driver);

}  // namespace toposimp::io
