// OFF (Object File Format) and its variants: [ST][C][N]OFF header letters for texture
// coordinates, colours and normals per vertex; a face line may end in a colour. Carries vertex
// normals, colours and texture coordinates, and face colours.
#include "io/mesh/codecs.hpp"
#include "io/mesh/reading.hpp"
#include "io/mesh/writing.hpp"

#include <cmath>

namespace toposimp::io::mesh_codec {
namespace {

struct OffColours {
    std::vector<double> values;  // 4 per element (alpha 1, or 255, where absent)
    std::size_t with = 0, with_alpha = 0;
    bool integers = true;
    // tokens[first, end): the element's colour, or nothing (no colour, the default, colour-map
    // index: `with` is not counted).
    bool add(const std::vector<std::string_view>& tokens, std::size_t first, std::size_t elements, const std::string& path,
             std::size_t line) {
        const std::size_t count = tokens.size() - first;
        if (count != 3 && count != 4) return false;
        std::vector<double> numbers;
        parse_numbers(tokens, first, count, numbers, path, line);
        for (std::size_t k = first; k < tokens.size(); ++k) integers = integers && is_integer_text(tokens[k]);
        values.resize(4 * elements, std::numeric_limits<double>::quiet_NaN());  // (NaN: alpha absent)
        values.insert(values.end(), numbers.begin(), numbers.end());
        if (count == 3) values.push_back(std::numeric_limits<double>::quiet_NaN());
        ++with;
        with_alpha += count == 4;
        return true;
    }
    // Keeps them as columns of `attributes` (after those it has) if every element has one.
    void finish(const char* what, std::size_t elements, mesh::Attributes& attributes, std::vector<AttributeColumn>& layout,
                MeshReadReport& report) const {
        if (with == 0) return;
        if (with < elements) {
            report.dropped.push_back(std::string(what) + ": only " + std::to_string(with) + " of " + std::to_string(elements) +
                                     " have one");
            return;
        }
        const std::size_t width = with_alpha > 0 ? 4 : 3;
        const ValueType type = integers ? ValueType::u8 : ValueType::f32;
        add_columns(layout, {"red", "green", "blue"}, type);
        if (width == 4) add_columns(layout, {"alpha"}, type);
        std::vector<double> colours;
        colours.reserve(elements * width);
        for (std::size_t i = 0; i < elements; ++i) {
            for (std::size_t k = 0; k < width; ++k) {
                const double value = values[4 * i + k];
                colours.push_back(std::isnan(value) ? (integers ? 255.0 : 1.0) : value);
            }
        }
        append_columns(attributes, elements, width, colours);
    }
};

// OFF: "[ST][C][N]OFF", counts, vertices (x y z, then nx ny nz, r g b [a], s t as the header

}  // namespace

mesh::Mesh read_off(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    mesh::Mesh m;
    Lines lines(text);
    std::string_view line;
    std::vector<std::string_view> tokens;
    auto next_tokens = [&]() {
        while (lines.next(line)) {
            const std::size_t hash = line.find('#');
            if (hash != std::string_view::npos) line = line.substr(0, hash);
            split(line, tokens);
            if (!tokens.empty()) return true;
        }
        return false;
    };
    if (!next_tokens()) throw InputError(path + ": empty file, expected an OFF header");
    std::string header(tokens[0]);
    if (header.size() < 3 || header.substr(header.size() - 3) != "OFF") {
        throw InputError(where(path, lines.number()) + "not an OFF file (first word '" + header + "')");
    }
    std::string_view prefix = std::string_view(header).substr(0, header.size() - 3);
    auto take = [&prefix](std::string_view part) {
        if (!prefix.starts_with(part)) return false;
        prefix.remove_prefix(part.size());
        return true;
    };
    const bool texture = take("ST"), coloured = take("C"), with_normals = take("N");
    if (!prefix.empty()) {
        throw InputError(where(path, lines.number()) + "'" + header + "': only OFF with ST, C and N (3D vertices) is read");
    }
    std::size_t first = 1;
    if (tokens.size() < 4) {
        if (!next_tokens()) throw InputError(path + ": file ends before the vertex and face counts");
        first = 0;
    }
    long long counts[2];
    for (int k = 0; k < 2; ++k) {
        if (tokens.size() < first + 2 || !parse_integer(tokens[first + static_cast<std::size_t>(k)], counts[k]) || counts[k] < 0) {
            throw InputError(where(path, lines.number()) + "expected the vertex, face and edge counts");
        }
    }
    const auto vertices = static_cast<std::size_t>(counts[0]), faces = static_cast<std::size_t>(counts[1]);
    // (A count is held against the file before anything is reserved for it: a vertex takes a
    // line of at least six characters. A 20-byte file claimed 2^26 vertices: 1.6 GB reserved.)
    m.points.reserve(std::min<std::size_t>(vertices, text.size() / 6));
    const std::size_t before_colour = 3 + (with_normals ? 3 : 0), after_colour = texture ? 2 : 0;
    std::vector<double> normal_values, uv_values, numbers;
    OffColours vertex_colours, face_colours;
    for (std::size_t v = 0; v < vertices; ++v) {
        if (!next_tokens()) {
            throw InputError(path + ": truncated: the header promises " + std::to_string(vertices) +
                             " vertices, the file ends after " + std::to_string(v));
        }
        if (tokens.size() < before_colour + after_colour) {
            throw InputError(where(path, lines.number()) + "vertex " + std::to_string(v) + " needs " +
                             std::to_string(before_colour + after_colour) + " numbers ('" + header + "')");
        }
        m.points.push_back(parse_point(path, lines.number(), tokens[0], tokens[1], tokens[2], v));
        if (with_normals) {
            parse_numbers(tokens, 3, 3, numbers, path, lines.number());
            normal_values.insert(normal_values.end(), numbers.begin(), numbers.end());
        }
        if (texture) {
            parse_numbers(tokens, tokens.size() - 2, 2, numbers, path, lines.number());
            uv_values.insert(uv_values.end(), numbers.begin(), numbers.end());
            tokens.resize(tokens.size() - 2);
        }
        if (coloured && !vertex_colours.add(tokens, before_colour, v, path, lines.number())) {
            throw InputError(where(path, lines.number()) + "vertex " + std::to_string(v) +
                             ": expected a colour of 3 or 4 numbers ('" + header + "')");
        }
    }
    std::vector<std::uint32_t> corners;
    std::size_t triangles = 0;
    std::vector<std::size_t> triangles_of;  // per face of the file: its triangles (its colour goes to each)
    for (std::size_t f = 0; f < faces; ++f) {
        if (!next_tokens()) {
            throw InputError(path + ": truncated: the header promises " + std::to_string(faces) + " faces, the file ends after " +
                             std::to_string(f));
        }
        long long n = 0;
        if (!parse_integer(tokens[0], n) || n < 0 || tokens.size() < static_cast<std::size_t>(n) + 1) {
            throw InputError(where(path, lines.number()) + "face " + std::to_string(f) + ": expected a corner count and indices");
        }
        corners.clear();
        for (long long k = 1; k <= n; ++k) {
            long long index = 0;
            if (!parse_integer(tokens[static_cast<std::size_t>(k)], index)) {
                throw InputError(where(path, lines.number()) + "face " + std::to_string(f) + ": '" +
                                 std::string(tokens[static_cast<std::size_t>(k)]) + "' is not an index");
            }
            check_index(path, lines.number(), f, index, m.points.size());
            corners.push_back(static_cast<std::uint32_t>(index));
        }
        const std::size_t colour_at = static_cast<std::size_t>(n) + 1;
        if (tokens.size() > colour_at && !face_colours.add(tokens, colour_at, f, path, lines.number()) &&
            std::find(report.dropped.begin(), report.dropped.end(), "face colour-map indices") == report.dropped.end()) {
            report.dropped.push_back("face colour-map indices");
        }
        triangles_of.push_back(add_polygon(m, corners, options, report, path, lines.number(), f));
        triangles += triangles_of.back();
    }
    // Vertex columns: normals, colour, texture coordinates.
    std::vector<AttributeColumn>& layout = report.layout.vertex;
    mesh::Attributes& rows = m.vertex_attributes;
    if (with_normals) {
        add_columns(layout, {"nx", "ny", "nz"}, ValueType::f32);
        append_columns(rows, vertices, 3, normal_values);
    }
    vertex_colours.finish("vertex colours", vertices, rows, layout, report);
    if (texture) {
        add_columns(layout, {"s", "t"}, ValueType::f32);
        append_columns(rows, vertices, 2, uv_values);
    }
    // A face's colour goes with each of its triangles.
    mesh::Attributes per_face;
    face_colours.finish("face colours", faces, per_face, report.layout.face, report);
    if (per_face.width > 0) {
        m.face_attributes.width = per_face.width;
        m.face_attributes.values.reserve(triangles * per_face.width);
        for (std::size_t f = 0; f < faces; ++f) {
            const std::vector<double> row(per_face.row(f), per_face.row(f) + per_face.width);
            append_rows(m.face_attributes.values, row, triangles_of[f]);
        }
    }
    return m;
}

std::vector<std::string> off_unwritable(const AttributeLayout& layout) {
    const VertexGroups groups = find_groups(layout.vertex);
    const ColourColumns face_colour = find_colour(layout.face);
    std::vector<std::string> unwritable;
    for (std::size_t k = 0; k < layout.vertex.size(); ++k) {
        if (!groups.holds(k)) unwritable.push_back("vertex " + layout.vertex[k].name);
    }
    for (std::size_t k = 0; k < layout.face.size(); ++k) {
        if (!face_colour.holds(k)) unwritable.push_back("face " + layout.face[k].name);
    }
    return unwritable;
}

void write_off(const mesh::Mesh& m, const WrittenRows& rows, MeshWriter& out, bool /*ascii*/) {
    const AttributeLayout& layout = rows.layout;
    const VertexGroups groups = find_groups(layout.vertex);
    const ColourColumns face_colour = find_colour(layout.face);
    const std::size_t nv = m.points.size();
    const bool texture = groups.texture[0] >= 0, normals = groups.normal[0] >= 0, colours = groups.colour.present();
    const bool face_colours = face_colour.present();
    out.buffer += std::string(texture ? "ST" : "") + (colours ? "C" : "") + (normals ? "N" : "") + "OFF\n" +
              std::to_string(nv) + " " + std::to_string(m.faces.size()) + " 0\n";
    for (std::size_t v = 0; v < nv; ++v) {
        const double* row = rows.vertex.row(v);
        out.numbers("", {m.points[v].x, m.points[v].y, m.points[v].z});
        if (normals) out.numbers("", {row[groups.normal[0]], row[groups.normal[1]], row[groups.normal[2]]});
        if (colours) write_colour(out, rows.vertex, v, groups.colour, layout.vertex, true, true);
        if (texture) out.numbers("", {row[groups.texture[0]], row[groups.texture[1]]});
        out.buffer += '\n';
        out.flush();
    }
    for (std::size_t f = 0; f < m.faces.size(); ++f) {
        append_face_line(out.buffer, "3", m.faces[f], 0);
        if (face_colours) {
            out.buffer.pop_back();
            write_colour(out, rows.face, f, face_colour, layout.face, face_colour.index[3] >= 0, true);
            out.buffer += '\n';
        }
        out.flush();
    }
}

}  // namespace toposimp::io::mesh_codec
