#include "io/mesh/reading.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace toposimp::io::mesh_codec {

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

Point3 parse_point(const std::string& path, std::size_t line, std::string_view x, std::string_view y, std::string_view z,
                   std::size_t vertex) {
    double c[3];
    const std::string_view text[3] = {x, y, z};
    for (int k = 0; k < 3; ++k) {
        if (!parse_number(text[k], c[k])) {
            throw InputError(where(path, line) + "vertex " + std::to_string(vertex) + ": '" + std::string(text[k]) +
                             "' is not a number");
        }
        if (!std::isfinite(c[k])) {
            throw InputError(where(path, line) + "vertex " + std::to_string(vertex) + " has a non-finite coordinate (" +
                             std::string(text[k]) + ")");
        }
    }
    return {c[0], c[1], c[2]};
}

std::size_t add_polygon(mesh::Mesh& m, const std::vector<std::uint32_t>& corners, const MeshReadOptions& options,
                        MeshReadReport& report, const std::string& path, std::size_t line, std::size_t face) {
    if (corners.size() < 3) {
        throw InputError(where(path, line) + "face " + std::to_string(face) + " has " + std::to_string(corners.size()) +
                         " corners; a face needs 3");
    }
    if (corners.size() > 3) {
        if (!options.triangulate) {
            throw InputError(where(path, line) + "face " + std::to_string(face) + " has " + std::to_string(corners.size()) +
                             " corners: toposimp mesh simplifies triangles; pass --triangulate to split polygons into fans");
        }
        ++report.polygons_triangulated;
    }
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) m.faces.push_back({corners[0], corners[k], corners[k + 1]});
    return corners.size() - 2;
}

void append_columns(mesh::Attributes& rows, std::size_t elements, std::size_t width, const std::vector<double>& source) {
    std::vector<double> joined;
    joined.reserve(elements * (rows.width + width));
    for (std::size_t i = 0; i < elements; ++i) {
        joined.insert(joined.end(), rows.row(i), rows.row(i) + rows.width);
        joined.insert(joined.end(), source.begin() + static_cast<std::ptrdiff_t>(i * width),
                      source.begin() + static_cast<std::ptrdiff_t>((i + 1) * width));
    }
    rows.values.swap(joined);
    rows.width += width;
}

void check_index(const std::string& path, std::size_t line, std::size_t face, long long index, std::size_t vertices) {
    if (index < 0 || static_cast<std::size_t>(index) >= vertices) {
        throw InputError(where(path, line) + "face " + std::to_string(face) + " refers to vertex " + std::to_string(index) +
                         ", but there are " + std::to_string(vertices) + " vertices");
    }
}

void parse_numbers(const std::vector<std::string_view>& tokens, std::size_t first, std::size_t count,
                   std::vector<double>& out, const std::string& path, std::size_t line) {
    out.clear();
    for (std::size_t k = first; k < first + count; ++k) {
        double value = 0;
        if (!parse_number(tokens[k], value) || !std::isfinite(value)) {
            throw InputError(where(path, line) + "'" + std::string(tokens[k]) + "' is not a finite number");
        }
        out.push_back(value);
    }
}

}  // namespace toposimp::io::mesh_codec
