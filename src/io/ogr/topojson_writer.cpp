#include "io/ogr/topojson_writer.hpp"

#include "io/common/errors.hpp"
#include "io/common/json_text.hpp"
#include "io/common/number_format.hpp"
#include "io/ogr/geojson_writer.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

namespace toposimp::io {
namespace {

void append_position(std::string& out, Point p) {
    out += '[';
    append_number(out, p.x);
    out += ',';
    append_number(out, p.y);
    out += ']';
}

void append_references(std::string& out, const std::vector<std::int64_t>& arcs) {
    out += '[';
    for (std::size_t i = 0; i < arcs.size(); ++i) {
        if (i) out += ',';
        out += std::to_string(arcs[i]);
    }
    out += ']';
}

template <class Items, class Write>
void append_list(std::string& out, const Items& items, Write&& write) {
    out += '[';
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (i) out += ',';
        write(items[i]);
    }
    out += ']';
}

struct Extent {
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
    void add(Point p) {
        min_x = std::min(min_x, p.x);
        min_y = std::min(min_y, p.y);
        max_x = std::max(max_x, p.x);
        max_y = std::max(max_y, p.y);
    }
};

}  // namespace

std::vector<std::string> write_topojson(const std::string& path, std::span<const TopologyLayer> layers, std::size_t arc_count,
                                        const std::function<void(std::size_t, std::vector<Point>&, std::vector<int>& ranks)>& arc,
                                        const std::string& shown_as, const TopoTransform* transform) {
    const std::string& name = shown_as.empty() ? path : shown_as;
    // With a transform: the integer a coordinate stands for, checked to decode back to it.
    auto quantum = [&](double value, double scale, double translate) {
        const auto q = static_cast<std::int64_t>(std::llround((value - translate) / scale));
        for (const std::int64_t c : {q, q - 1, q + 1}) {
            const double product = static_cast<double>(c) * scale;
            if (product + translate == value) return c;
        }
        throw OutputError("cannot write '" + name + "': a coordinate (" + std::to_string(value) + ") is not on the quantization grid");
    };
    auto position = [&](std::string& out, Point p) {
        if (!transform) return append_position(out, p);
        out += '[';
        out += std::to_string(quantum(p.x, transform->scale_x, transform->translate_x));
        out += ',';
        out += std::to_string(quantum(p.y, transform->scale_y, transform->translate_y));
        out += ']';
    };
    std::vector<std::string> warnings;
    std::ofstream file(path, std::ios::binary);
    if (!file) throw OutputError("cannot create '" + name + "': " + std::strerror(errno));
    // Written as it goes, a megabyte at a time: the header, the objects, the arcs, and last the
    // bounding box, known only then (member order is free in JSON).
    auto flush = [&](std::string& text) {
        if (text.size() < (1 << 20)) return;
        file << text;
        text.clear();
    };
    Extent extent;
    std::string out = "{\"type\":\"Topology\",\n";
    if (transform) {
        out += "\"transform\":{\"scale\":[";
        append_number(out, transform->scale_x);
        out += ',';
        append_number(out, transform->scale_y);
        out += "],\"translate\":[";
        append_number(out, transform->translate_x);
        out += ',';
        append_number(out, transform->translate_y);
        out += "]},\n";
    }
    bool dropped_z = false, dropped_m = false;
    std::string& objects = out;
    objects += "\"objects\":{";
    for (std::size_t l = 0; l < layers.size(); ++l) {
        const TopologyLayer& layer = layers[l];
        if (l) objects += ",\n";
        append_json_string(objects, layer.name.c_str());
        objects += ":{\"type\":\"GeometryCollection\",\"geometries\":[\n";
        for (std::size_t i = 0; i < layer.feature_count; ++i) {
            const TopoGeometry geometry = layer.geometry(i);
            dropped_z = dropped_z || geometry.has_z;
            dropped_m = dropped_m || geometry.has_m;
            if (i) objects += ",\n";
            objects += "{\"type\":";
            using Type = TopoGeometry::Type;
            switch (geometry.type) {
                case Type::null: objects += "null"; break;
                case Type::point:
                    objects += "\"Point\",\"coordinates\":";
                    if (geometry.points.empty()) {
                        objects += "[]";
                    } else {
                        extent.add(geometry.points.front());
                        position(objects, geometry.points.front());
                    }
                    break;
                case Type::multi_point:
                    objects += "\"MultiPoint\",\"coordinates\":";
                    append_list(objects, geometry.points, [&](Point p) {
                        extent.add(p);
                        position(objects, p);
                    });
                    break;
                case Type::line_string:
                    objects += "\"LineString\",\"arcs\":";
                    append_references(objects, geometry.lines.empty() ? std::vector<std::int64_t>{} : geometry.lines.front());
                    break;
                case Type::multi_line_string:
                    objects += "\"MultiLineString\",\"arcs\":";
                    append_list(objects, geometry.lines, [&](const auto& line) { append_references(objects, line); });
                    break;
                case Type::polygon:
                    objects += "\"Polygon\",\"arcs\":";
                    if (geometry.polygons.empty()) {
                        objects += "[]";
                    } else {
                        append_list(objects, geometry.polygons.front(), [&](const auto& ring) { append_references(objects, ring); });
                    }
                    break;
                case Type::multi_polygon:
                    objects += "\"MultiPolygon\",\"arcs\":";
                    append_list(objects, geometry.polygons, [&](const auto& polygon) {
                        append_list(objects, polygon, [&](const auto& ring) { append_references(objects, ring); });
                    });
                    break;
            }
            objects += ",\"properties\":";
            append_properties(objects, *layer.feature(i), *layer.definition);
            objects += '}';
            flush(objects);
        }
        objects += "\n]}";
    }
    objects += "}";
    std::string& arcs = out;
    arcs += ",\n\"arcs\":[";
    std::vector<Point> positions;
    std::vector<int> ranks;
    // The rank, when there is one, as a third coordinate: `text` ends with the position's ']'.
    auto rank = [&](std::string& text, std::size_t k) {
        if (ranks.empty()) return;
        text.pop_back();
        text += ',' + std::to_string(ranks[k]) + ']';
    };
    for (std::size_t a = 0; a < arc_count; ++a) {
        ranks.clear();
        arc(a, positions, ranks);
        if (a) arcs += ",\n";
        if (transform) {
            // Delta-encoded: the first position as it is, then each as the step from the last.
            arcs += '[';
            std::int64_t last_x = 0, last_y = 0;
            for (std::size_t k = 0; k < positions.size(); ++k) {
                extent.add(positions[k]);
                const std::int64_t qx = quantum(positions[k].x, transform->scale_x, transform->translate_x);
                const std::int64_t qy = quantum(positions[k].y, transform->scale_y, transform->translate_y);
                if (k) arcs += ',';
                arcs += '[' + std::to_string(qx - last_x) + ',' + std::to_string(qy - last_y) + ']';
                rank(arcs, k);
                last_x = qx;
                last_y = qy;
            }
            arcs += ']';
        } else {
            arcs += '[';
            for (std::size_t k = 0; k < positions.size(); ++k) {
                if (k) arcs += ',';
                extent.add(positions[k]);
                append_position(arcs, positions[k]);
                rank(arcs, k);
            }
            arcs += ']';
        }
        flush(arcs);
    }
    arcs += "]";
    if (extent.min_x <= extent.max_x) {
        out += ",\n\"bbox\":[";
        append_number(out, extent.min_x);
        out += ',';
        append_number(out, extent.min_y);
        out += ',';
        append_number(out, extent.max_x);
        out += ',';
        append_number(out, extent.max_y);
        out += "]";
    }
    file << out << "}\n";
    file.close();
    if (!file) throw OutputError("cannot write '" + name + "': " + std::strerror(errno));
    if (dropped_z) warnings.push_back("TopoJSON positions are written as x, y: Z values were not written");
    if (dropped_m) warnings.push_back("TopoJSON positions are written as x, y: M values were not written");
    return warnings;
}

}  // namespace toposimp::io
