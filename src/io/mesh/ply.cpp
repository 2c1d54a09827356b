// PLY (Stanford polygon file): ASCII, binary little and big endian. Every scalar property of the
// vertices and faces is carried, with its type; list properties other than the faces' corners are
// dropped.
#include "io/mesh/codecs.hpp"
#include "io/mesh/reading.hpp"
#include "io/mesh/writing.hpp"

#include <bit>
#include <cmath>
#include <limits>

namespace toposimp::io::mesh_codec {
namespace {

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

}  // namespace

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
            // One vertex and one face element: a second would renumber the first's (issue 29).
            for (const Element& before : elements) {
                if ((tokens[1] == "vertex" || tokens[1] == "face") && before.name == tokens[1]) {
                    throw InputError(where(path, lines.number()) + "a second '" + before.name + "' element (a PLY file has one)");
                }
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
            // Each axis once: a record with x twice and no z would be read past its end (issue 29).
            int seen = 0;
            for (std::size_t k = 0; k < element.properties.size(); ++k) {
                if (axis_of[k] < 0) continue;
                if ((seen & (1 << axis_of[k])) != 0) {
                    throw InputError(path + ": the vertex element has property " + element.properties[k].name + " twice");
                }
                seen |= 1 << axis_of[k];
            }
            if (seen != 7) throw InputError(path + ": the vertex element needs properties x, y and z");
        }
        if (is_face && list_index < 0) throw InputError(path + ": the face element needs a vertex_indices list");
        if (!is_vertex && !is_face) {
            report.ignored_elements += element.count;
            if (element.properties.empty()) continue;  // nothing to read, however many (issue 29: a loop of 2^63)
        }
        // Every count is held against what the rest of the file can hold before anything is
        // allocated or looped over: an element takes its fixed-size values (binary) or a line
        // of at least one character (text).
        const std::size_t room = ascii ? text.size() - std::min(text.size(), lines.offset()) : binary.rest().size();
        std::size_t least = 0;
        for (const Property& p : element.properties) least += ascii ? 0 : size_of(p.list ? p.count_type : p.type);
        if (ascii) least = 1;
        if (element.count > room / least) {
            throw InputError(path + (ascii ? ": truncated: the file ends inside " : ": truncated binary PLY: the file ends inside ") +
                             element.name + " " + std::to_string(room / least) + " (the header promises " +
                             std::to_string(element.count) + ")");
        }
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

std::vector<std::string> ply_unwritable(const AttributeLayout& /*layout*/) { return {}; }

void write_ply(const mesh::Mesh& m, const WrittenRows& rows, MeshWriter& out, bool ascii) {
    const AttributeLayout& layout = rows.layout;
    const std::size_t nv = m.points.size();
    out.buffer += std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
              " 1.0\ncomment toposimp mesh\nelement vertex " + std::to_string(nv) +
              "\nproperty double x\nproperty double y\nproperty double z\n";
    for (const AttributeColumn& column : layout.vertex) out.buffer += "property " + ply_type_name(column.type) + " " + column.name + "\n";
    out.buffer += "element face " + std::to_string(m.faces.size()) + "\nproperty list uchar uint vertex_indices\n";
    for (const AttributeColumn& column : layout.face) out.buffer += "property " + ply_type_name(column.type) + " " + column.name + "\n";
    out.buffer += "end_header\n";
    if (ascii) {
        auto columns = [&](const mesh::Attributes& table, std::size_t i) {
            for (std::size_t k = 0; k < table.width; ++k) {
                out.buffer += ' ';
                append_number(out.buffer, table.row(i)[k]);
            }
            out.buffer += '\n';
            out.flush();
        };
        for (std::size_t v = 0; v < nv; ++v) {
            out.numbers("", {m.points[v].x, m.points[v].y, m.points[v].z});
            columns(rows.vertex, v);
        }
        for (std::size_t f = 0; f < m.faces.size(); ++f) {
            append_face_line(out.buffer, "3", m.faces[f], 0);
            out.buffer.pop_back();
            columns(rows.face, f);
        }
        return;
    }
    auto put = [&](const void* bytes, std::size_t n) {
        char little[8];
        std::memcpy(little, bytes, n);
        if constexpr (std::endian::native == std::endian::big) std::reverse(little, little + n);
        out.buffer.append(little, n);
    };
    auto columns = [&](const mesh::Attributes& table, const std::vector<AttributeColumn>& types, std::size_t i) {
        for (std::size_t k = 0; k < table.width; ++k) put_scalar(put, types[k].type, table.row(i)[k]);
    };
    for (std::size_t v = 0; v < nv; ++v) {
        const Point3& p = m.points[v];
        put(&p.x, 8);
        put(&p.y, 8);
        put(&p.z, 8);
        columns(rows.vertex, layout.vertex, v);
        out.flush();
    }
    for (std::size_t f = 0; f < m.faces.size(); ++f) {
        out.buffer += '\3';
        for (std::uint32_t v : m.faces[f]) put(&v, 4);
        columns(rows.face, layout.face, f);
        out.flush();
    }
}

}  // namespace toposimp::io::mesh_codec
