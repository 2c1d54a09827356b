// Attribute values as text, the way text formats (GeoJSON, GML) write them.
#pragma once

#include <ogrsf_frmts.h>

#include <string>

namespace toposimp::io {

// ISO 8601 text of a Date, Time or DateTime field: "2024-05-01", "12:30:05.250", "…T…Z".
std::string iso_date_time(const OGRFeature& feature, int field, OGRFieldType type);

}  // namespace toposimp::io
