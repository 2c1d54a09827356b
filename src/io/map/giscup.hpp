// The ACM SIGSPATIAL GIS Cup 2014 text format: one geometry per line,
//   ID:<gml:LineString ...><gml:coordinates decimal="." cs="," ts=" ">x,y x,y </gml:coordinates></gml:LineString>
// (points likewise with gml:Point). Coordinates are read correctly rounded and written in
// shortest round-trip form, so the values survive bit for bit.
#pragma once

#include "core/map/map_data.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace toposimp::io {

struct GiscupLines {
    std::vector<std::string> ids;        // per chain, in file order
    std::vector<std::string> prefixes;   // per chain: the text before the first coordinate
};

// Appends one chain per input line to `map`.
GiscupLines read_giscup_lines(const std::string& path, map::MapData& map);
std::vector<Point> read_giscup_points(const std::string& path);

// Writes the kept vertices of each chain, one line each, with the input's IDs and tags.
void write_giscup_lines(std::ostream& out, const GiscupLines& lines, const map::MapData& map,
                        const std::vector<std::uint8_t>& kept);

}  // namespace toposimp::io
