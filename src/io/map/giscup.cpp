#include "io/map/giscup.hpp"

#include "io/common/errors.hpp"
#include "io/common/input_file.hpp"
#include "io/common/number_format.hpp"

#include <cmath>
#include <fstream>
#include <ostream>
#include <string_view>

namespace toposimp::io {
namespace {

constexpr std::string_view kCoordinatesTag = "<gml:coordinates";
constexpr std::string_view kCoordinatesEnd = "</gml:coordinates>";

struct ParsedLine {
    std::string id;
    std::string prefix;
    std::vector<Point> points;
};

std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line); }

ParsedLine parse_line(std::string_view text, const std::string& path, std::size_t line_number) {
    const std::size_t colon = text.find(':');
    const std::size_t tag = text.find(kCoordinatesTag);
    if (colon == std::string_view::npos || tag == std::string_view::npos || colon > tag) {
        throw InputError(where(path, line_number) + ": not a GIS Cup geometry (expected 'ID:<gml:...><gml:coordinates ...>')");
    }
    const std::size_t open_end = text.find('>', tag);
    const std::size_t close = text.find(kCoordinatesEnd, tag);
    if (open_end == std::string_view::npos || close == std::string_view::npos || close < open_end) {
        throw InputError(where(path, line_number) + ": unterminated <gml:coordinates> element");
    }
    ParsedLine parsed;
    parsed.id = std::string(text.substr(0, colon));
    parsed.prefix = std::string(text.substr(0, open_end + 1));
    std::string_view coordinates = text.substr(open_end + 1, close - open_end - 1);
    while (!coordinates.empty()) {
        const std::size_t start = coordinates.find_first_not_of(" \t\r\n");
        if (start == std::string_view::npos) break;
        coordinates.remove_prefix(start);
        const std::size_t end = std::min(coordinates.find_first_of(" \t\r\n"), coordinates.size());
        const std::string_view token = coordinates.substr(0, end);
        coordinates.remove_prefix(end);
        const std::size_t comma = token.find(',');
        Point p{};
        if (comma == std::string_view::npos || !parse_number(token.substr(0, comma), p.x) ||
            !parse_number(token.substr(comma + 1), p.y)) {
            throw InputError(where(path, line_number) + ": feature " + parsed.id + ": bad coordinate '" +
                             std::string(token) + "'");
        }
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
            throw InputError(where(path, line_number) + ": feature " + parsed.id + ": coordinate '" +
                             std::string(token) + "' is not finite");
        }
        parsed.points.push_back(p);
    }
    return parsed;
}

template <class Visit>
void for_each_geometry(const std::string& path, Visit&& visit) {
    const std::string data = read_file(path);
    std::string_view rest = data;
    std::size_t line_number = 0;
    while (!rest.empty()) {
        const std::size_t end = std::min(rest.find('\n'), rest.size());
        const std::string_view text = rest.substr(0, end);
        rest.remove_prefix(std::min(end + 1, rest.size()));
        ++line_number;
        if (text.find_first_not_of(" \t\r") == std::string_view::npos) continue;
        visit(parse_line(text, path, line_number), line_number);
    }
}

}  // namespace

GiscupLines read_giscup_lines(const std::string& path, map::MapData& map) {
    GiscupLines lines;
    for_each_geometry(path, [&](ParsedLine parsed, std::size_t line_number) {
        if (parsed.points.size() < 2) {
            throw InputError(where(path, line_number) + ": feature " + parsed.id + ": a line needs at least 2 points");
        }
        map.add_chain(parsed.points);
        lines.ids.push_back(std::move(parsed.id));
        lines.prefixes.push_back(std::move(parsed.prefix));
    });
    if (lines.ids.empty()) throw InputError(path + ": no lines");
    return lines;
}

std::vector<Point> read_giscup_points(const std::string& path) {
    std::vector<Point> points;
    for_each_geometry(path, [&](ParsedLine parsed, std::size_t line_number) {
        if (parsed.points.size() != 1) {
            throw InputError(where(path, line_number) + ": feature " + parsed.id + ": a control point needs exactly 1 coordinate");
        }
        points.push_back(parsed.points.front());
    });
    return points;
}

void write_giscup_lines(std::ostream& out, const GiscupLines& lines, const map::MapData& map,
                        const std::vector<std::uint8_t>& kept) {
    std::string text;
    for (std::size_t c = 0; c < map.chains.size(); ++c) {
        text.clear();
        text += lines.prefixes[c];
        for (std::uint32_t v = map.chains[c].first; v <= map.chains[c].last; ++v) {
            if (!kept[v]) continue;
            append_number(text, map.vertices[v].x);
            text += ',';
            append_number(text, map.vertices[v].y);
            text += ' ';
        }
        text += "</gml:coordinates></gml:LineString>\n";
        out << text;
    }
}

}  // namespace toposimp::io
