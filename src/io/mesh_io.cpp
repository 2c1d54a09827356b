#include "io/mesh_io.hpp"

#include "io/errors.hpp"
#include "io/number_format.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

namespace toposimp::io {
namespace {

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
    // In big chunks (a character at a time took a tenth of a second on a 2 M-triangle PLY).
    std::string data;
    std::size_t size = 0;
    // At once when the size is known (a regular file): no growing, no copying.
    std::error_code error;
    const std::uintmax_t known = std::filesystem::is_regular_file(path, error) ? std::filesystem::file_size(path, error) : 0;
    if (!error && known > 0) {
        data.resize(known);
        in.read(data.data(), static_cast<std::streamsize>(known));
        size = static_cast<std::size_t>(in.gcount());
        if (size < known || in.peek() != std::char_traits<char>::eof()) {
            in.clear();  // (it changed meanwhile: read on as for a stream)
        } else {
            return data;
        }
    }
    for (;;) {
        data.resize(size + (std::size_t{1} << 22));
        in.read(data.data() + size, static_cast<std::streamsize>(data.size() - size));
        size += static_cast<std::size_t>(in.gcount());
        if (!in) break;
    }
    if (in.bad()) throw InputError(path + ": read error");
    data.resize(size);
    return data;
}

// Splits text into lines with their numbers, and lines into whitespace-separated tokens.
class Lines {
public:
    explicit Lines(std::string_view text) : text_(text) {}
    bool next(std::string_view& line) {
        if (at_ >= text_.size()) return false;
        const std::size_t end = std::min(text_.find('\n', at_), text_.size());
        line = text_.substr(at_, end - at_);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        at_ = end + 1;
        ++number_;
        return true;
    }
    std::size_t number() const { return number_; }
    std::size_t offset() const { return std::min(at_, text_.size()); }

private:
    std::string_view text_;
    std::size_t at_ = 0;
    std::size_t number_ = 0;
};

// The C locale's white space (what std::isspace says there), without its library call per
// character: a third of the time to read an OFF file went to those calls.
constexpr bool is_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

void split(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line) + ": "; }

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

bool parse_integer(std::string_view text, long long& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

// Adds a polygon's corners as triangles (a fan), or refuses a polygon. Returns how many
// triangles it added (a face's attribute row goes with each).
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

// Appends `row` to `rows` `times` times.
void append_rows(std::vector<double>& rows, const std::vector<double>& row, std::size_t times) {
    for (std::size_t i = 0; i < times; ++i) rows.insert(rows.end(), row.begin(), row.end());
}

// Adds columns of one type under the given names.
void add_columns(std::vector<AttributeColumn>& columns, std::initializer_list<const char*> names, ValueType type) {
    for (const char* name : names) columns.push_back({name, type});
}

// Widens each of `elements` rows by the `width` values of `source` for it (width per element,
// in element order): a reader's columns, gathered apart, joined to those it has.
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

bool is_integer_text(std::string_view text) {
    long long unused = 0;
    return parse_integer(text, unused);
}

void check_index(const std::string& path, std::size_t line, std::size_t face, long long index, std::size_t vertices) {
    if (index < 0 || static_cast<std::size_t>(index) >= vertices) {
        throw InputError(where(path, line) + "face " + std::to_string(face) + " refers to vertex " + std::to_string(index) +
                         ", but there are " + std::to_string(vertices) + " vertices");
    }
}

// OBJ names texture coordinates (vt) and normals (vn) per face corner. They become a vertex's
// attributes when every corner names one and the corners of a vertex agree on its value;
// otherwise (a seam, or corners without) they are dropped.
class CornerValues {
public:
    CornerValues(const char* what, std::size_t width) : what_(what), width_(width) {}
    void list(const std::vector<double>& values) { listed_.insert(listed_.end(), values.begin(), values.end()); }
    std::size_t listed() const { return listed_.size() / width_; }
    // A corner of `vertex` naming `reference` (empty: none).
    void corner(std::uint32_t vertex, std::string_view reference, std::size_t vertices, const std::string& path,
                std::size_t line, std::size_t face) {
        if (reference.empty()) {
            missing_ = missing_ || listed() > 0;
            return;
        }
        long long index = 0;
        if (!parse_integer(reference, index) || index == 0) {
            throw InputError(where(path, line) + "face " + std::to_string(face) + ": '" + std::string(reference) +
                             "' is not a reference to " + what_);
        }
        const long long zero_based = index > 0 ? index - 1 : static_cast<long long>(listed()) + index;
        if (listed() == 0) {  // (all defined after the faces that use them: not read)
            forward_ = true;
            return;
        }
        if (zero_based < 0 || static_cast<std::size_t>(zero_based) >= listed()) {
            throw InputError(where(path, line) + "face " + std::to_string(face) + " refers to " + what_ + " " +
                             std::to_string(index) + ", but there are " + std::to_string(listed()));
        }
        if (chosen_.size() < vertices) chosen_.resize(vertices, 0);
        const auto entry = static_cast<std::uint32_t>(zero_based) + 1;
        std::uint32_t& mine = chosen_[vertex];
        if (mine == 0) {
            mine = entry;
        } else if (mine != entry && !std::equal(value(mine), value(mine) + width_, value(entry)) && !seam_) {
            seam_ = vertex;
        }
    }
    // Keeps the values as columns, or says why not.
    void finish(mesh::Mesh& m, std::vector<AttributeColumn>& layout, std::initializer_list<const char*> names,
                MeshReadReport& report) const {
        if (forward_) {
            report.dropped.push_back(std::string(what_) + ": faces refer to them before they are listed");
            return;
        }
        if (listed_.empty()) return;
        if (seam_) {
            report.dropped.push_back(std::string(what_) + " (vt/vn): vertex " + std::to_string(*seam_ + 1) +
                                     " has different ones in different faces (a seam)");
            return;
        }
        if (missing_) {
            report.dropped.push_back(std::string(what_) + ": some face corners have none");
            return;
        }
        add_columns(layout, names, ValueType::f32);
        std::vector<double> per_vertex;
        per_vertex.reserve(m.points.size() * width_);
        for (std::size_t v = 0; v < m.points.size(); ++v) {
            const std::uint32_t entry = v < chosen_.size() ? chosen_[v] : 0;  // (0: in no face, dropped)
            for (std::size_t k = 0; k < width_; ++k) per_vertex.push_back(entry == 0 ? 0.0 : value(entry)[k]);
        }
        append_columns(m.vertex_attributes, m.points.size(), width_, per_vertex);
    }

private:
    const double* value(std::uint32_t entry) const { return listed_.data() + (entry - 1) * width_; }
    const char* what_;
    std::size_t width_;
    std::vector<double> listed_;
    std::vector<std::uint32_t> chosen_;  // per vertex: the entry its corners name, plus 1; 0: none yet
    bool missing_ = false, forward_ = false;
    std::optional<std::uint32_t> seam_;
};

// Parses tokens[first, first + count) as numbers into `out`.
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

mesh::Mesh read_obj(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    mesh::Mesh m;
    Lines lines(text);
    std::string_view line;
    std::vector<std::string_view> tokens;
    std::vector<std::uint32_t> corners;
    std::vector<double> numbers, colours, alphas;
    std::size_t coloured = 0;  // vertices with a colour (v x y z r g b)
    std::size_t with_alpha = 0;  // and of those, with a fourth number (v x y z r g b a)
    CornerValues uvs("texture coordinates", 2), normals("normals", 3);
    std::size_t face = 0;
    while (lines.next(line)) {
        split(line, tokens);
        if (tokens.empty() || tokens[0].front() == '#') continue;
        const std::string_view kind = tokens[0];
        if (kind == "v") {
            if (tokens.size() < 4) throw InputError(where(path, lines.number()) + "a vertex needs x y z");
            m.points.push_back(parse_point(path, lines.number(), tokens[1], tokens[2], tokens[3], m.points.size() + 1));
            if (tokens.size() >= 7) {
                parse_numbers(tokens, 4, tokens.size() >= 8 ? 4 : 3, numbers, path, lines.number());
                colours.resize(3 * (m.points.size() - 1), 0.0);
                colours.insert(colours.end(), numbers.begin(), numbers.begin() + 3);
                alphas.resize(m.points.size() - 1, 1.0);
                alphas.push_back(numbers.size() == 4 ? numbers[3] : 1.0);
                ++coloured;
                with_alpha += numbers.size() == 4;
            }
        } else if (kind == "vn") {
            if (tokens.size() < 4) throw InputError(where(path, lines.number()) + "a normal needs x y z");
            parse_numbers(tokens, 1, 3, numbers, path, lines.number());
            normals.list(numbers);
        } else if (kind == "vt") {
            if (tokens.size() < 2) throw InputError(where(path, lines.number()) + "texture coordinates need u (and v)");
            parse_numbers(tokens, 1, std::min<std::size_t>(tokens.size() - 1, 2), numbers, path, lines.number());
            numbers.resize(2, 0.0);
            uvs.list(numbers);
        } else if (kind == "f") {
            ++face;
            corners.clear();
            for (std::size_t k = 1; k < tokens.size(); ++k) {
                // v, v/vt, v//vn or v/vt/vn.
                const std::string_view token = tokens[k];
                const std::size_t slash = token.find('/');
                const std::string_view ref = token.substr(0, slash);
                long long index = 0;
                if (!parse_integer(ref, index) || index == 0) {
                    throw InputError(where(path, lines.number()) + "face " + std::to_string(face) + ": '" +
                                     std::string(tokens[k]) + "' is not a vertex reference");
                }
                // OBJ counts from 1; negative references count back from the last vertex read.
                const long long zero_based = index > 0 ? index - 1 : static_cast<long long>(m.points.size()) + index;
                check_index(path, lines.number(), face, zero_based, m.points.size());
                const auto vertex = static_cast<std::uint32_t>(zero_based);
                corners.push_back(vertex);
                std::string_view uv, normal;
                if (slash != std::string_view::npos) {
                    const std::string_view rest = token.substr(slash + 1);
                    const std::size_t second = rest.find('/');
                    uv = rest.substr(0, second);
                    if (second != std::string_view::npos) normal = rest.substr(second + 1);
                }
                uvs.corner(vertex, uv, m.points.size(), path, lines.number(), face);
                normals.corner(vertex, normal, m.points.size(), path, lines.number(), face);
            }
            add_polygon(m, corners, options, report, path, lines.number(), face);
        } else if (kind == "l" || kind == "p") {
            ++report.ignored_elements;
        }
    }
    std::vector<AttributeColumn>& layout = report.layout.vertex;
    if (coloured == m.points.size() && coloured > 0) {
        add_columns(layout, {"red", "green", "blue"}, ValueType::f32);
        append_columns(m.vertex_attributes, m.points.size(), 3, colours);
        if (with_alpha == coloured) {
            add_columns(layout, {"alpha"}, ValueType::f32);
            append_columns(m.vertex_attributes, m.points.size(), 1, alphas);
        } else if (with_alpha > 0) {
            report.dropped.push_back("vertex colour alpha: only " + std::to_string(with_alpha) + " of " +
                                     std::to_string(coloured) + " colours have one");
        }
    } else if (coloured > 0) {
        report.dropped.push_back("vertex colours: only " + std::to_string(coloured) + " of " + std::to_string(m.points.size()) +
                                 " vertices have one");
    }
    uvs.finish(m, layout, {"u", "v"}, report);
    normals.finish(m, layout, {"nx", "ny", "nz"}, report);
    return m;
}

// OFF colours: integers from 0 to 255, or numbers from 0 to 1 (Geomview's rule, taken per file:
// integers throughout, or not). Counts how many elements have 3 or 4 components.
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
// says), faces (a corner count, the corners, a colour maybe); '#' comments anywhere.
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
    m.points.reserve(std::min<std::size_t>(vertices, 1u << 26));
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

// ---- PLY ----

using Scalar = ValueType;

bool scalar_of(std::string_view name, Scalar& type) {
    static const std::pair<std::string_view, Scalar> names[] = {
        {"char", Scalar::i8},    {"int8", Scalar::i8},     {"uchar", Scalar::u8},   {"uint8", Scalar::u8},
        {"short", Scalar::i16},  {"int16", Scalar::i16},   {"ushort", Scalar::u16}, {"uint16", Scalar::u16},
        {"int", Scalar::i32},    {"int32", Scalar::i32},   {"uint", Scalar::u32},   {"uint32", Scalar::u32},
        {"float", Scalar::f32},  {"float32", Scalar::f32}, {"double", Scalar::f64}, {"float64", Scalar::f64}};
    for (const auto& [n, t] : names) {
        if (n == name) {
            type = t;
            return true;
        }
    }
    return false;
}

std::size_t size_of(Scalar type) {
    switch (type) {
        case Scalar::i8: case Scalar::u8: return 1;
        case Scalar::i16: case Scalar::u16: return 2;
        case Scalar::i32: case Scalar::u32: case Scalar::f32: return 4;
        case Scalar::f64: return 8;
    }
    return 0;
}

struct Property {
    std::string name;
    Scalar type = Scalar::f32;
    bool list = false;
    Scalar count_type = Scalar::u8;
};

struct Element {
    std::string name;
    std::size_t count = 0;
    std::vector<Property> properties;
};

// The scalar of type T at `bytes`, byte-swapped first if `swap`.
template <class T>
double load(const char* bytes, bool swap) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, bytes, sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    T value;
    std::memcpy(&value, b, sizeof(T));
    return static_cast<double>(value);
}

inline double decode(Scalar type, const char* bytes, bool swap) {
    switch (type) {
        case Scalar::i8: return load<std::int8_t>(bytes, swap);
        case Scalar::u8: return load<std::uint8_t>(bytes, swap);
        case Scalar::i16: return load<std::int16_t>(bytes, swap);
        case Scalar::u16: return load<std::uint16_t>(bytes, swap);
        case Scalar::i32: return load<std::int32_t>(bytes, swap);
        case Scalar::u32: return load<std::uint32_t>(bytes, swap);
        case Scalar::f32: return load<float>(bytes, swap);
        case Scalar::f64: return load<double>(bytes, swap);
    }
    return 0;
}

// Reads scalars from a binary body, with the file's byte order.
class BinaryReader {
public:
    BinaryReader(const std::string& path, std::string_view data, bool big_endian)
        : path_(path), data_(data), swap_(big_endian != (std::endian::native == std::endian::big)) {}

    // `what` names the element read, for the error (called only then).
    template <class What>
    double read(Scalar type, What what) {
        const std::size_t n = size_of(type);
        if (at_ + n > data_.size()) throw InputError(path_ + ": truncated binary PLY: the file ends inside " + what());
        const double value = decode(type, data_.data() + at_, swap_);
        at_ += n;
        return value;
    }
    // The bytes not read yet, and a way past some of them.
    std::string_view rest() const { return data_.substr(at_); }
    void skip(std::size_t n) { at_ += n; }
    bool swap() const { return swap_; }

private:
    const std::string& path_;
    std::string_view data_;
    bool swap_;
    std::size_t at_ = 0;
};

// The fast paths of a binary body. Each reads records while they are regular and stops at the
// first that is not (truncated, a non-finite coordinate, a face not a triangle, an index out of
// range), which the general reader then reads and reports: the result and the errors are the
// general reader's. Returns how many records it read.
//
// An element of scalars only, whose x, y and z are at `offset` with `type` in records of
// `record` bytes; its other properties, (offset, type) each, are attribute columns.
std::size_t read_points(BinaryReader& binary, std::size_t count, std::size_t record, const std::size_t offset[3],
                        const Scalar type[3], const std::vector<std::pair<std::size_t, Scalar>>& columns,
                        std::vector<Point3>& points, std::vector<double>& values) {
    const std::string_view rest = binary.rest();
    const std::size_t whole = std::min(count, rest.size() / record);
    const bool swap = binary.swap();
    std::size_t i = 0;
    for (; i < whole; ++i) {
        const char* r = rest.data() + i * record;
        const Point3 p{decode(type[0], r + offset[0], swap), decode(type[1], r + offset[1], swap), decode(type[2], r + offset[2], swap)};
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) break;
        points.push_back(p);
        for (const auto& [at, column_type] : columns) values.push_back(decode(column_type, r + at, swap));
    }
    binary.skip(i * record);
    return i;
}

// An element whose one property is the vertex list, of triangles.
std::size_t read_triangles(BinaryReader& binary, std::size_t count, Scalar count_type, Scalar index_type, std::size_t vertices,
                           std::vector<mesh::Face>& faces) {
    const std::string_view rest = binary.rest();
    const std::size_t head = size_of(count_type), size = size_of(index_type), record = head + 3 * size;
    const std::size_t whole = std::min(count, rest.size() / record);  // (if every record is a triangle)
    const bool swap = binary.swap();
    const auto limit = static_cast<double>(vertices);
    std::size_t i = 0;
    for (; i < whole; ++i) {
        const char* r = rest.data() + i * record;
        if (decode(count_type, r, swap) != 3) break;
        mesh::Face f;
        bool ok = true;
        for (int k = 0; k < 3; ++k) {
            const double index = decode(index_type, r + head + k * size, swap);
            ok = ok && index >= 0 && index < limit;
            f[k] = ok ? static_cast<std::uint32_t>(index) : 0;
        }
        if (!ok) break;
        faces.push_back(f);
    }
    binary.skip(i * record);
    return i;
}

mesh::Mesh read_ply(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    Lines lines(text);
    std::string_view line;
    std::vector<std::string_view> tokens;
    if (!lines.next(line) || line != "ply") throw InputError(path + ":1: not a PLY file (it must start with 'ply')");
    std::vector<Element> elements;
    std::string encoding;
    bool ended = false;
    while (lines.next(line)) {
        split(line, tokens);
        if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
        if (tokens[0] == "end_header") {
            ended = true;
            break;
        }
        if (tokens[0] == "format" && tokens.size() >= 2) {
            encoding = tokens[1];
        } else if (tokens[0] == "element" && tokens.size() == 3) {
            long long count = 0;
            if (!parse_integer(tokens[2], count) || count < 0) {
                throw InputError(where(path, lines.number()) + "bad element count '" + std::string(tokens[2]) + "'");
            }
            elements.push_back({std::string(tokens[1]), static_cast<std::size_t>(count), {}});
        } else if (tokens[0] == "property" && !elements.empty()) {
            Property property;
            bool ok = false;
            if (tokens.size() == 5 && tokens[1] == "list") {
                property.list = true;
                ok = scalar_of(tokens[2], property.count_type) && scalar_of(tokens[3], property.type);
                property.name = tokens[4];
            } else if (tokens.size() == 3) {
                ok = scalar_of(tokens[1], property.type);
                property.name = tokens[2];
            }
            if (!ok) throw InputError(where(path, lines.number()) + "cannot read property '" + std::string(line) + "'");
            elements.back().properties.push_back(property);
        } else {
            throw InputError(where(path, lines.number()) + "unexpected header line '" + std::string(line) + "'");
        }
    }
    if (!ended) throw InputError(path + ": truncated PLY header (no end_header)");
    if (encoding != "ascii" && encoding != "binary_little_endian" && encoding != "binary_big_endian") {
        throw InputError(path + ": unknown PLY format '" + encoding + "'");
    }
    report.encoding = encoding;
    const bool ascii = encoding == "ascii";
    BinaryReader binary(path, text.substr(lines.offset()), encoding == "binary_big_endian");
    std::vector<std::string_view> body_tokens;

    mesh::Mesh m;
    std::vector<std::uint32_t> corners;
    std::vector<double> values;
    for (const Element& element : elements) {
        const bool is_vertex = element.name == "vertex", is_face = element.name == "face";
        if (element.properties.size() > 64) throw InputError(path + ": too many properties in element " + element.name);
        // Each property: a coordinate (axis_of), the corner list, an attribute column (column_of),
        // or neither (a list: dropped).
        int axis_of[64], column_of[64];
        int list_index = -1;
        mesh::Attributes* rows = is_vertex ? &m.vertex_attributes : is_face ? &m.face_attributes : nullptr;
        std::vector<AttributeColumn>* layout = is_vertex ? &report.layout.vertex : is_face ? &report.layout.face : nullptr;
        for (std::size_t k = 0; k < element.properties.size(); ++k) {
            const Property& p = element.properties[k];
            axis_of[k] = column_of[k] = -1;
            if (is_vertex && !p.list && (p.name == "x" || p.name == "y" || p.name == "z")) {
                axis_of[k] = p.name[0] - 'x';
            } else if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                list_index = static_cast<int>(k);
            } else if (rows != nullptr && !p.list) {
                column_of[k] = static_cast<int>(layout->size());
                layout->push_back({p.name, p.type});
            } else if (rows != nullptr) {
                const std::string what = element.name + " property '" + p.name + "' (a list)";
                if (std::find(report.dropped.begin(), report.dropped.end(), what) == report.dropped.end()) {
                    report.dropped.push_back(what);
                }
            }
        }
        if (rows != nullptr) rows->width = layout->size();
        if (is_vertex) {
            int seen = 0;
            for (std::size_t k = 0; k < element.properties.size(); ++k) seen += axis_of[k] >= 0;
            if (seen != 3) throw InputError(path + ": the vertex element needs properties x, y and z");
        }
        if (is_face && list_index < 0) throw InputError(path + ": the face element needs a vertex_indices list");
        if (!is_vertex && !is_face) report.ignored_elements += element.count;
        // (A header cannot make this reserve more than the file could hold: an element takes a byte at least.)
        if (is_vertex) m.points.reserve(m.points.size() + std::min(element.count, text.size()));
        if (is_face) m.faces.reserve(m.faces.size() + std::min(element.count, text.size()));
        std::size_t i = 0;
        if (!ascii && is_vertex && std::none_of(element.properties.begin(), element.properties.end(), [](const Property& p) { return p.list; })) {
            std::size_t record = 0, offset[3] = {0, 0, 0};
            Scalar type[3] = {Scalar::f64, Scalar::f64, Scalar::f64};
            std::vector<std::pair<std::size_t, Scalar>> columns;
            for (std::size_t k = 0; k < element.properties.size(); ++k) {
                const Scalar t = element.properties[k].type;
                if (axis_of[k] >= 0) offset[axis_of[k]] = record, type[axis_of[k]] = t;
                if (column_of[k] >= 0) columns.emplace_back(record, t);
                record += size_of(t);
            }
            m.vertex_attributes.values.reserve(std::min(element.count, text.size()) * columns.size());
            i = read_points(binary, element.count, record, offset, type, columns, m.points, m.vertex_attributes.values);
        } else if (!ascii && is_face && element.properties.size() == 1) {
            const Property& list = element.properties[0];
            i = read_triangles(binary, element.count, list.count_type, list.type, m.points.size(), m.faces);
        }
        for (; i < element.count; ++i) {
            // The element's name for messages, made only for one.
            const auto what = [&element, i] { return element.name + " " + std::to_string(i); };
            std::size_t token = 0;
            if (ascii) {
                do {
                    if (!lines.next(line)) {
                        throw InputError(path + ": truncated: the header promises " + std::to_string(element.count) + " " +
                                         element.name + " elements, the file ends after " + std::to_string(i));
                    }
                    split(line, body_tokens);
                } while (body_tokens.empty());
            }
            auto next_value = [&](Scalar type) -> double {
                if (!ascii) return binary.read(type, what);
                if (token >= body_tokens.size()) throw InputError(where(path, lines.number()) + what() + " has too few values");
                double value = 0;
                if (!parse_number(body_tokens[token], value)) {
                    throw InputError(where(path, lines.number()) + what() + ": '" + std::string(body_tokens[token]) + "' is not a number");
                }
                ++token;
                return value;
            };
            Point3 p{0, 0, 0};
            corners.clear();
            values.clear();
            for (std::size_t k = 0; k < element.properties.size(); ++k) {
                const Property& property = element.properties[k];
                if (property.list) {
                    const double n = next_value(property.count_type);
                    if (!(n >= 0) || n > 1e6) throw InputError(path + ": " + what() + " has a bad list length");
                    for (std::size_t c = 0; c < static_cast<std::size_t>(n); ++c) {
                        const double value = next_value(property.type);
                        if (static_cast<int>(k) == list_index) {
                            if (!(value >= 0) || value >= static_cast<double>(m.points.size())) {
                                throw InputError(path + ": " + what() + " refers to vertex " + io_number(value) + ", but there are " +
                                                 std::to_string(m.points.size()) + " vertices");
                            }
                            corners.push_back(static_cast<std::uint32_t>(value));
                        }
                    }
                } else {
                    const double value = next_value(property.type);
                    if (is_vertex && axis_of[k] >= 0) {
                        if (!std::isfinite(value)) throw InputError(path + ": " + what() + " has a non-finite coordinate");
                        (axis_of[k] == 0 ? p.x : (axis_of[k] == 1 ? p.y : p.z)) = value;
                    }
                    if (column_of[k] >= 0) values.push_back(value);
                }
            }
            if (is_vertex) {
                m.points.push_back(p);
                rows->values.insert(rows->values.end(), values.begin(), values.end());
            }
            if (is_face) {
                const std::size_t added = add_polygon(m, corners, options, report, path, ascii ? lines.number() : 0, i);
                append_rows(rows->values, values, added);
            }
        }
    }
    return m;
}

void append_face_line(std::string& out, const char* prefix, const mesh::Face& f, std::uint32_t base) {
    out += prefix;
    for (std::uint32_t v : f) {
        out += ' ';
        out += std::to_string(v + base);
    }
    out += '\n';
}

// The columns of a colour (red, green, blue, alpha; -1 where absent).
struct ColourColumns {
    std::array<int, 4> index{-1, -1, -1, -1};
    bool present() const { return index[0] >= 0 && index[1] >= 0 && index[2] >= 0; }
    bool holds(std::size_t k) const {
        return present() && std::find(index.begin(), index.end(), static_cast<int>(k)) != index.end();
    }
    bool all_of(const std::vector<AttributeColumn>& columns, ValueType type) const {
        for (int k : index) {
            if (k >= 0 && columns[static_cast<std::size_t>(k)].type != type) return false;
        }
        return true;
    }
};

int column_named(const std::vector<AttributeColumn>& columns, std::string_view name) {
    for (std::size_t k = 0; k < columns.size(); ++k) {
        if (columns[k].name == name) return static_cast<int>(k);
    }
    return -1;
}

ColourColumns find_colour(const std::vector<AttributeColumn>& columns) {
    ColourColumns colour;
    const char* names[4] = {"red", "green", "blue", "alpha"};
    for (int k = 0; k < 4; ++k) colour.index[static_cast<std::size_t>(k)] = column_named(columns, names[k]);
    return colour;
}

// The vertex columns OBJ and OFF have a place for.
struct VertexGroups {
    std::array<int, 3> normal{-1, -1, -1};  // nx ny nz
    std::array<int, 2> texture{-1, -1};     // u v, s t or texture_u texture_v
    ColourColumns colour;
    bool holds(std::size_t k) const {
        const int i = static_cast<int>(k);
        return (normal[0] >= 0 && std::find(normal.begin(), normal.end(), i) != normal.end()) ||
               (texture[0] >= 0 && std::find(texture.begin(), texture.end(), i) != texture.end()) || colour.holds(k);
    }
};

VertexGroups find_groups(const std::vector<AttributeColumn>& columns) {
    VertexGroups groups;
    const std::array<int, 3> normal{column_named(columns, "nx"), column_named(columns, "ny"), column_named(columns, "nz")};
    if (normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0) groups.normal = normal;
    for (const auto& [u, v] : {std::pair{"u", "v"}, std::pair{"s", "t"}, std::pair{"texture_u", "texture_v"}}) {
        const std::array<int, 2> texture{column_named(columns, u), column_named(columns, v)};
        if (texture[0] >= 0 && texture[1] >= 0) {
            groups.texture = texture;
            break;
        }
    }
    groups.colour = find_colour(columns);
    return groups;
}

// The largest value of an integer type (a colour's full intensity), 1 for a float type.
double colour_scale(ValueType type) {
    switch (type) {
        case ValueType::i8: return 127;
        case ValueType::u8: return 255;
        case ValueType::i16: return 32767;
        case ValueType::u16: return 65535;
        case ValueType::i32: return 2147483647.0;
        case ValueType::u32: return 4294967295.0;
        case ValueType::f32: case ValueType::f64: return 1;
    }
    return 1;
}

// The rows as written: integer columns rounded and clamped to their type (a blend of two
// integers is seldom one), the normal (columns `normal`, or none if -1) scaled to unit length (a
// blend of two unit vectors is shorter).
mesh::Attributes written_values(const mesh::Attributes& rows, const std::vector<AttributeColumn>& columns,
                                std::array<int, 3> normal) {
    mesh::Attributes out = rows;
    for (std::size_t i = 0; out.width > 0 && i < out.values.size() / out.width; ++i) {
        double* row = out.row(i);
        for (std::size_t k = 0; k < out.width; ++k) {
            const ValueType type = columns[k].type;
            if (type == ValueType::f32 || type == ValueType::f64) continue;
            const double top = colour_scale(type), bottom = type == ValueType::u8 || type == ValueType::u16 || type == ValueType::u32
                                                                 ? 0.0
                                                                 : -top - 1;
            row[k] = std::isnan(row[k]) ? 0.0 : std::clamp(std::nearbyint(row[k]), bottom, top);
        }
        if (normal[0] >= 0) {
            double& x = row[normal[0]];
            double& y = row[normal[1]];
            double& z = row[normal[2]];
            const double length = std::sqrt(x * x + y * y + z * z);
            if (length > 0 && std::isfinite(length)) x /= length, y /= length, z /= length;
        }
    }
    return out;
}

std::string ply_type_name(ValueType type) {
    switch (type) {
        case ValueType::i8: return "char";
        case ValueType::u8: return "uchar";
        case ValueType::i16: return "short";
        case ValueType::u16: return "ushort";
        case ValueType::i32: return "int";
        case ValueType::u32: return "uint";
        case ValueType::f32: return "float";
        case ValueType::f64: return "double";
    }
    return "double";
}

// `value` (already in range for an integer type) as `type`, through `put(bytes, size)`.
template <class Put>
void put_scalar(Put& put, ValueType type, double value) {
    auto as = [&]<class T>(T converted) { put(&converted, sizeof(T)); };
    switch (type) {
        case ValueType::i8: as(static_cast<std::int8_t>(value)); break;
        case ValueType::u8: as(static_cast<std::uint8_t>(value)); break;
        case ValueType::i16: as(static_cast<std::int16_t>(value)); break;
        case ValueType::u16: as(static_cast<std::uint16_t>(value)); break;
        case ValueType::i32: as(static_cast<std::int32_t>(value)); break;
        case ValueType::u32: as(static_cast<std::uint32_t>(value)); break;
        case ValueType::f32: as(static_cast<float>(value)); break;
        case ValueType::f64: as(value); break;
    }
}

// STL: triangles with corners of their own. Binary (an 80-byte header, a little-endian uint32
// count, then per triangle a normal, three corners as float32 and a uint16 "attribute byte
// count") when the size is exactly that; otherwise text ("solid", then per facet "facet normal …,
// outer loop, vertex x y z three times, endloop, endfacet", and "endsolid"). Corners at the same
// location are welded into one vertex (STL has no other way to share them); facet normals are
// not read (they follow from the corners).
mesh::Mesh read_stl(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    mesh::Mesh m;
    constexpr bool big_endian = std::endian::native == std::endian::big;
    const std::uint64_t count = text.size() >= 84 ? static_cast<std::uint64_t>(load<std::uint32_t>(text.data() + 80, big_endian)) : 0;
    auto corner = [&](Point3 p, std::size_t triangle, std::size_t line) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw InputError((line > 0 ? where(path, line) : path + ": ") + "triangle " + std::to_string(triangle) +
                             " has a non-finite coordinate");
        }
        m.points.push_back(p);
    };
    if (text.size() >= 84 && text.size() == 84 + 50 * count) {
        report.encoding = "binary";
        if (count > std::numeric_limits<std::uint32_t>::max() / 3) {
            throw InputError(path + ": " + std::to_string(count) + " triangles: more corners than 32-bit vertex numbers hold");
        }
        m.points.reserve(3 * count);
        m.faces.reserve(count);
        std::size_t coloured = 0;
        for (std::size_t t = 0; t < count; ++t) {
            const char* r = text.data() + 84 + 50 * t;
            for (int k = 0; k < 3; ++k) {
                const char* c = r + 12 + 12 * k;
                corner({load<float>(c, big_endian), load<float>(c + 4, big_endian), load<float>(c + 8, big_endian)}, t, 0);
            }
            const auto first = static_cast<std::uint32_t>(3 * t);
            m.faces.push_back({first, first + 1, first + 2});
            coloured += r[48] != 0 || r[49] != 0;
        }
        if (coloured > 0) {
            report.dropped.push_back("face attribute bytes (a colour in some tools): " + std::to_string(coloured) + " of " +
                                     std::to_string(count) + " triangles have them; not read");
        }
    } else {
        report.encoding = "ascii";
        Lines lines(text);
        std::string_view line;
        std::vector<std::string_view> tokens;
        bool started = false;
        std::vector<std::uint32_t> loop;  // the current facet's corners
        std::size_t facet = 0;
        while (lines.next(line)) {
            split(line, tokens);
            if (tokens.empty()) continue;
            const std::string keyword = lower(std::string(tokens[0]));
            if (!started) {
                if (keyword != "solid") {
                    throw InputError(path + ": not an STL file: not binary (84 bytes and 50 per triangle: its header counts " +
                                     std::to_string(count) + " triangles, the file has " + std::to_string(text.size()) +
                                     " bytes) and not text starting with 'solid'");
                }
                started = true;
            } else if (keyword == "vertex") {
                if (tokens.size() < 4) throw InputError(where(path, lines.number()) + "a vertex needs 3 numbers");
                double c[3];
                for (int a = 0; a < 3; ++a) {
                    if (!parse_number(tokens[1 + static_cast<std::size_t>(a)], c[a])) {
                        throw InputError(where(path, lines.number()) + "'" + std::string(tokens[1 + static_cast<std::size_t>(a)]) +
                                         "' is not a number");
                    }
                }
                loop.push_back(static_cast<std::uint32_t>(m.points.size()));
                corner({c[0], c[1], c[2]}, facet, lines.number());
            } else if (keyword == "endloop") {
                add_polygon(m, loop, options, report, path, lines.number(), facet);
                ++facet;
                loop.clear();
            } else if (keyword != "facet" && keyword != "outer" && keyword != "endfacet" && keyword != "solid" &&
                       keyword != "endsolid") {
                throw InputError(where(path, lines.number()) + "'" + std::string(tokens[0]) + "' is not an STL keyword");
            }
        }
        if (!started) throw InputError(path + ": empty file, expected an STL solid");
        if (!loop.empty()) throw InputError(path + ": truncated: the file ends inside a facet");
    }
    report.welded = mesh::weld_coincident(m).vertices;
    mesh::drop_unused_vertices(m);  // (faces with a repeated corner stay: the caller warns about them)
    return m;
}

}  // namespace

std::string io_number(double value) {
    std::string text;
    append_number(text, value);
    return text;
}

MeshFormat mesh_format_of(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    const std::string extension = dot == std::string::npos ? "" : lower(path.substr(dot + 1));
    if (extension == "obj") return MeshFormat::obj;
    if (extension == "ply") return MeshFormat::ply;
    if (extension == "off") return MeshFormat::off;
    if (extension == "stl") return MeshFormat::stl;
    throw InputError(path + ": unknown mesh format (use a .obj, .ply, .off or .stl file, or -f)");
}

bool has_mesh_extension(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    const std::string extension = dot == std::string::npos ? "" : lower(path.substr(dot + 1));
    return extension == "obj" || extension == "ply" || extension == "off" || extension == "stl";
}

const char* to_string(MeshFormat format) {
    switch (format) {
        case MeshFormat::obj: return "OBJ";
        case MeshFormat::ply: return "PLY";
        case MeshFormat::off: return "OFF";
        case MeshFormat::stl: return "STL";
    }
    return "?";
}

mesh::Mesh read_mesh(const std::string& path, const MeshReadOptions& options, MeshReadReport& report) {
    const std::string data = read_all(path);
    std::string_view text(data);
    // Recognise the format by content first, by extension otherwise.
    if (text.substr(0, 4) == "ply\n" || text.substr(0, 5) == "ply\r\n") {
        report.format = MeshFormat::ply;
    } else {
        std::string first(text.substr(0, std::min<std::size_t>(text.size(), 8)));
        if (first.find("OFF") != std::string::npos && first.find("OFF") < 5) {
            report.format = MeshFormat::off;
        } else {
            report.format = mesh_format_of(path);
        }
    }
    switch (report.format) {
        case MeshFormat::obj: return read_obj(path, text, options, report);
        case MeshFormat::ply: return read_ply(path, text, options, report);
        case MeshFormat::off: return read_off(path, text, options, report);
        case MeshFormat::stl: return read_stl(path, text, options, report);
    }
    return {};
}

std::vector<std::string> write_mesh(const mesh::Mesh& m, const AttributeLayout& layout, const std::string& path,
                                    MeshFormat format, bool ascii) {
    const VertexGroups groups = find_groups(layout.vertex);
    const ColourColumns face_colour = find_colour(layout.face);
    std::vector<std::string> unwritable;
    if (format != MeshFormat::ply) {
        const bool stl = format == MeshFormat::stl;  // (no place for any)
        for (std::size_t k = 0; k < layout.vertex.size(); ++k) {
            const bool alpha_in_obj = format == MeshFormat::obj && static_cast<int>(k) == groups.colour.index[3];  // (v x y z r g b)
            if (stl || !groups.holds(k) || alpha_in_obj) unwritable.push_back("vertex " + layout.vertex[k].name);
        }
        for (std::size_t k = 0; k < layout.face.size(); ++k) {
            if (stl || format == MeshFormat::obj || !face_colour.holds(k)) unwritable.push_back("face " + layout.face[k].name);
        }
    }
    const mesh::Attributes vertex_rows = written_values(m.vertex_attributes, layout.vertex, groups.normal);
    const mesh::Attributes face_rows = written_values(m.face_attributes, layout.face, {-1, -1, -1});  // (no normal)

    std::ofstream out(path, std::ios::binary);
    if (!out) throw OutputError(path + ": cannot create: " + std::strerror(errno));
    std::string buffer;
    auto flush = [&](bool force) {
        if (force || buffer.size() > (1u << 20)) {
            out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            buffer.clear();
        }
    };
    // Numbers separated by spaces, after `prefix` (a line is flushed only when it is whole).
    auto numbers = [&](std::string_view prefix, std::initializer_list<double> values) {
        buffer += prefix;
        for (double value : values) {
            if (!buffer.empty() && buffer.back() != '\n') buffer += ' ';
            append_number(buffer, value);
        }
    };
    // A colour as OFF or OBJ writes it: from 0 to 1, or OFF's integers if all its columns are
    // uchar; in OFF a number from 0 to 1 always shows a decimal point, so that it reads as such.
    auto colour = [&](const mesh::Attributes& rows, std::size_t i, const ColourColumns& columns,
                      const std::vector<AttributeColumn>& types, bool with_alpha) {
        const std::size_t count = with_alpha ? 4 : 3;
        const bool integers = format == MeshFormat::off && columns.all_of(types, ValueType::u8);
        for (std::size_t k = 0; k < count; ++k) {
            const int column = columns.index[k];
            double value = column >= 0 ? rows.row(i)[column] : -1.0;
            if (column < 0) {
                value = integers ? 255.0 : 1.0;  // (no alpha: opaque)
            } else if (!integers) {
                value /= colour_scale(types[static_cast<std::size_t>(column)].type);
            }
            buffer += ' ';
            const std::size_t at = buffer.size();
            append_number(buffer, value);
            if (format == MeshFormat::off && !integers && buffer.find_first_of(".eEn", at) == std::string::npos) buffer += ".0";
        }
    };
    const std::size_t nv = m.points.size();
    switch (format) {
        case MeshFormat::obj: {
            buffer += "# toposimp mesh\n";
            for (std::size_t v = 0; v < nv; ++v) {
                numbers("v", {m.points[v].x, m.points[v].y, m.points[v].z});
                if (groups.colour.present()) colour(vertex_rows, v, groups.colour, layout.vertex, false);
                buffer += '\n';
                flush(false);
            }
            for (std::size_t v = 0; groups.texture[0] >= 0 && v < nv; ++v) {
                const double* row = vertex_rows.row(v);
                numbers("vt", {row[groups.texture[0]], row[groups.texture[1]]});
                buffer += '\n';
                flush(false);
            }
            for (std::size_t v = 0; groups.normal[0] >= 0 && v < nv; ++v) {
                const double* row = vertex_rows.row(v);
                numbers("vn", {row[groups.normal[0]], row[groups.normal[1]], row[groups.normal[2]]});
                buffer += '\n';
                flush(false);
            }
            // v, v/vt, v//vn or v/vt/vn: one texture coordinate and one normal per vertex.
            const std::string suffix = groups.texture[0] >= 0 ? (groups.normal[0] >= 0 ? "/@/@" : "/@")
                                       : groups.normal[0] >= 0 ? "//@" : "";
            for (const mesh::Face& f : m.faces) {
                buffer += 'f';
                for (std::uint32_t v : f) {
                    const std::string number = std::to_string(v + 1);
                    buffer += ' ';
                    buffer += number;
                    for (char c : suffix) {
                        if (c == '@') {
                            buffer += number;
                        } else {
                            buffer += c;
                        }
                    }
                }
                buffer += '\n';
                flush(false);
            }
            break;
        }
        case MeshFormat::off: {
            const bool texture = groups.texture[0] >= 0, normals = groups.normal[0] >= 0, colours = groups.colour.present();
            const bool face_colours = face_colour.present();
            buffer += std::string(texture ? "ST" : "") + (colours ? "C" : "") + (normals ? "N" : "") + "OFF\n" +
                      std::to_string(nv) + " " + std::to_string(m.faces.size()) + " 0\n";
            for (std::size_t v = 0; v < nv; ++v) {
                const double* row = vertex_rows.row(v);
                numbers("", {m.points[v].x, m.points[v].y, m.points[v].z});
                if (normals) numbers("", {row[groups.normal[0]], row[groups.normal[1]], row[groups.normal[2]]});
                if (colours) colour(vertex_rows, v, groups.colour, layout.vertex, true);
                if (texture) numbers("", {row[groups.texture[0]], row[groups.texture[1]]});
                buffer += '\n';
                flush(false);
            }
            for (std::size_t f = 0; f < m.faces.size(); ++f) {
                append_face_line(buffer, "3", m.faces[f], 0);
                if (face_colours) {
                    buffer.pop_back();
                    colour(face_rows, f, face_colour, layout.face, face_colour.index[3] >= 0);
                    buffer += '\n';
                }
                flush(false);
            }
            break;
        }
        case MeshFormat::ply: {
            buffer += std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
                      " 1.0\ncomment toposimp mesh\nelement vertex " + std::to_string(nv) +
                      "\nproperty double x\nproperty double y\nproperty double z\n";
            for (const AttributeColumn& column : layout.vertex) buffer += "property " + ply_type_name(column.type) + " " + column.name + "\n";
            buffer += "element face " + std::to_string(m.faces.size()) + "\nproperty list uchar uint vertex_indices\n";
            for (const AttributeColumn& column : layout.face) buffer += "property " + ply_type_name(column.type) + " " + column.name + "\n";
            buffer += "end_header\n";
            if (ascii) {
                auto columns = [&](const mesh::Attributes& rows, std::size_t i) {
                    for (std::size_t k = 0; k < rows.width; ++k) {
                        buffer += ' ';
                        append_number(buffer, rows.row(i)[k]);
                    }
                    buffer += '\n';
                    flush(false);
                };
                for (std::size_t v = 0; v < nv; ++v) {
                    numbers("", {m.points[v].x, m.points[v].y, m.points[v].z});
                    columns(vertex_rows, v);
                }
                for (std::size_t f = 0; f < m.faces.size(); ++f) {
                    append_face_line(buffer, "3", m.faces[f], 0);
                    buffer.pop_back();
                    columns(face_rows, f);
                }
                break;
            }
            auto put = [&](const void* bytes, std::size_t n) {
                char little[8];
                std::memcpy(little, bytes, n);
                if constexpr (std::endian::native == std::endian::big) std::reverse(little, little + n);
                buffer.append(little, n);
            };
            auto columns = [&](const mesh::Attributes& rows, const std::vector<AttributeColumn>& types, std::size_t i) {
                for (std::size_t k = 0; k < rows.width; ++k) put_scalar(put, types[k].type, rows.row(i)[k]);
            };
            for (std::size_t v = 0; v < nv; ++v) {
                const Point3& p = m.points[v];
                put(&p.x, 8);
                put(&p.y, 8);
                put(&p.z, 8);
                columns(vertex_rows, layout.vertex, v);
                flush(false);
            }
            for (std::size_t f = 0; f < m.faces.size(); ++f) {
                buffer += '\3';
                for (std::uint32_t v : m.faces[f]) put(&v, 4);
                columns(face_rows, layout.face, f);
                flush(false);
            }
            break;
        }
        case MeshFormat::stl: {
            // Binary STL holds float32 corners: written only if every coordinate is one (else the
            // rounding could make faces cross); text otherwise, every digit kept.
            const bool floats = std::all_of(m.points.begin(), m.points.end(), [](const Point3& p) {
                return static_cast<float>(p.x) == p.x && static_cast<float>(p.y) == p.y && static_cast<float>(p.z) == p.z;
            });
            auto normal_of = [&](const mesh::Face& f) {
                const Point3 a = m.points[f[0]], b = m.points[f[1]], c = m.points[f[2]];
                const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
                const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
                const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
                return length > 0 && std::isfinite(length) ? Point3{nx / length, ny / length, nz / length} : Point3{0, 0, 0};
            };
            if (floats && !ascii && m.faces.size() <= std::numeric_limits<std::uint32_t>::max()) {
                buffer.append(80, '\0');
                buffer.replace(0, 22, "toposimp mesh (binary)");
                auto put = [&](auto value) {
                    char bytes[sizeof(value)];
                    std::memcpy(bytes, &value, sizeof(value));
                    if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(value));
                    buffer.append(bytes, sizeof(value));
                };
                put(static_cast<std::uint32_t>(m.faces.size()));
                for (const mesh::Face& f : m.faces) {
                    const Point3 n = normal_of(f);
                    for (double value : {n.x, n.y, n.z}) put(static_cast<float>(value));
                    for (std::uint32_t v : f) {
                        for (double value : {m.points[v].x, m.points[v].y, m.points[v].z}) put(static_cast<float>(value));
                    }
                    put(std::uint16_t{0});
                    flush(false);
                }
            } else {
                buffer += "solid toposimp\n";
                for (const mesh::Face& f : m.faces) {
                    const Point3 n = normal_of(f);
                    numbers("facet normal", {n.x, n.y, n.z});
                    buffer += "\nouter loop\n";
                    for (std::uint32_t v : f) {
                        numbers("vertex", {m.points[v].x, m.points[v].y, m.points[v].z});
                        buffer += '\n';
                    }
                    buffer += "endloop\nendfacet\n";
                    flush(false);
                }
                buffer += "endsolid toposimp\n";
            }
            break;
        }
    }
    flush(true);
    out.close();
    if (!out) throw OutputError(path + ": write error");
    return unwritable;
}

}  // namespace toposimp::io
