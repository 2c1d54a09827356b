// Wavefront OBJ: `v x y z [r g b]`, `vt`, `vn` and `f` lines (corners `v`, `v/vt`, `v//vn` or
// `v/vt/vn`, 1-based or negative). Carries vertex colours, texture coordinates and normals (one
// per vertex: seams are dropped), no face attributes.
#include "io/mesh/codecs.hpp"
#include "io/mesh/reading.hpp"
#include "io/mesh/writing.hpp"

#include <cmath>
#include <optional>

namespace toposimp::io::mesh_codec {
namespace {

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

}  // namespace

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

std::vector<std::string> obj_unwritable(const AttributeLayout& layout) {
    const VertexGroups groups = find_groups(layout.vertex);
    std::vector<std::string> unwritable;
    for (std::size_t k = 0; k < layout.vertex.size(); ++k) {
        const bool alpha = static_cast<int>(k) == groups.colour.index[3];  // (v x y z r g b)
        if (!groups.holds(k) || alpha) unwritable.push_back("vertex " + layout.vertex[k].name);
    }
    for (const AttributeColumn& column : layout.face) unwritable.push_back("face " + column.name);
    return unwritable;
}

void write_obj(const mesh::Mesh& m, const WrittenRows& rows, MeshWriter& out, bool /*ascii*/) {
    const AttributeLayout& layout = rows.layout;
    const VertexGroups groups = find_groups(layout.vertex);
    const std::size_t nv = m.points.size();
    out.buffer += "# toposimp mesh\n";
    for (std::size_t v = 0; v < nv; ++v) {
        out.numbers("v", {m.points[v].x, m.points[v].y, m.points[v].z});
        if (groups.colour.present()) write_colour(out, rows.vertex, v, groups.colour, layout.vertex, false, false);
        out.buffer += '\n';
        out.flush();
    }
    for (std::size_t v = 0; groups.texture[0] >= 0 && v < nv; ++v) {
        const double* row = rows.vertex.row(v);
        out.numbers("vt", {row[groups.texture[0]], row[groups.texture[1]]});
        out.buffer += '\n';
        out.flush();
    }
    for (std::size_t v = 0; groups.normal[0] >= 0 && v < nv; ++v) {
        const double* row = rows.vertex.row(v);
        out.numbers("vn", {row[groups.normal[0]], row[groups.normal[1]], row[groups.normal[2]]});
        out.buffer += '\n';
        out.flush();
    }
    // v, v/vt, v//vn or v/vt/vn: one texture coordinate and one normal per vertex.
    const std::string suffix = groups.texture[0] >= 0 ? (groups.normal[0] >= 0 ? "/@/@" : "/@")
                               : groups.normal[0] >= 0 ? "//@" : "";
    for (const mesh::Face& f : m.faces) {
        out.buffer += 'f';
        for (std::uint32_t v : f) {
            const std::string number = std::to_string(v + 1);
            out.buffer += ' ';
            out.buffer += number;
            for (char c : suffix) {
                if (c == '@') {
                    out.buffer += number;
                } else {
                    out.buffer += c;
                }
            }
        }
        out.buffer += '\n';
        out.flush();
    }
}

}  // namespace toposimp::io::mesh_codec
