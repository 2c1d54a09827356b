#include "io/mesh_io.hpp"

#include "io/errors.hpp"
#include "io/number_format.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
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

void split(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        const std::size_t start = i;
        while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
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

// Adds a polygon's corners as triangles (a fan), or refuses a polygon.
void add_polygon(mesh::Mesh& m, const std::vector<std::uint32_t>& corners, const MeshReadOptions& options,
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
}

void check_index(const std::string& path, std::size_t line, std::size_t face, long long index, std::size_t vertices) {
    if (index < 0 || static_cast<std::size_t>(index) >= vertices) {
        throw InputError(where(path, line) + "face " + std::to_string(face) + " refers to vertex " + std::to_string(index) +
                         ", but there are " + std::to_string(vertices) + " vertices");
    }
}

bool parse_integer(std::string_view text, long long& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

mesh::Mesh read_obj(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    mesh::Mesh m;
    Lines lines(text);
    std::string_view line;
    std::vector<std::string_view> tokens;
    std::vector<std::uint32_t> corners;
    bool normals = false, uvs = false, colours = false;
    std::size_t face = 0;
    while (lines.next(line)) {
        split(line, tokens);
        if (tokens.empty() || tokens[0].front() == '#') continue;
        const std::string_view kind = tokens[0];
        if (kind == "v") {
            if (tokens.size() < 4) throw InputError(where(path, lines.number()) + "a vertex needs x y z");
            m.points.push_back(parse_point(path, lines.number(), tokens[1], tokens[2], tokens[3], m.points.size() + 1));
            if (tokens.size() >= 7) colours = true;
        } else if (kind == "vn") {
            normals = true;
        } else if (kind == "vt") {
            uvs = true;
        } else if (kind == "f") {
            ++face;
            corners.clear();
            for (std::size_t k = 1; k < tokens.size(); ++k) {
                const std::string_view ref = tokens[k].substr(0, tokens[k].find('/'));
                long long index = 0;
                if (!parse_integer(ref, index) || index == 0) {
                    throw InputError(where(path, lines.number()) + "face " + std::to_string(face) + ": '" +
                                     std::string(tokens[k]) + "' is not a vertex reference");
                }
                // OBJ counts from 1; negative references count back from the last vertex read.
                const long long zero_based = index > 0 ? index - 1 : static_cast<long long>(m.points.size()) + index;
                check_index(path, lines.number(), face, zero_based, m.points.size());
                corners.push_back(static_cast<std::uint32_t>(zero_based));
            }
            add_polygon(m, corners, options, report, path, lines.number(), face);
        } else if (kind == "l" || kind == "p") {
            ++report.ignored_elements;
        }
    }
    if (normals) report.dropped.push_back("normals (vn)");
    if (uvs) report.dropped.push_back("texture coordinates (vt)");
    if (colours) report.dropped.push_back("vertex colours");
    return m;
}

// OFF: "OFF" (or COFF, NOFF, ...), counts, vertices, faces; '#' comments anywhere.
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
    if (header.find('C') != std::string::npos) report.dropped.push_back("vertex colours");
    if (header.find('N') != std::string::npos) report.dropped.push_back("normals");
    if (header.find("ST") != std::string::npos) report.dropped.push_back("texture coordinates");
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
    for (std::size_t v = 0; v < vertices; ++v) {
        if (!next_tokens()) {
            throw InputError(path + ": truncated: the header promises " + std::to_string(vertices) +
                             " vertices, the file ends after " + std::to_string(v));
        }
        if (tokens.size() < 3) throw InputError(where(path, lines.number()) + "a vertex needs x y z");
        m.points.push_back(parse_point(path, lines.number(), tokens[0], tokens[1], tokens[2], v));
    }
    std::vector<std::uint32_t> corners;
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
        if (tokens.size() > static_cast<std::size_t>(n) + 1 &&
            std::find(report.dropped.begin(), report.dropped.end(), "face colours") == report.dropped.end()) {
            report.dropped.push_back("face colours");
        }
        add_polygon(m, corners, options, report, path, lines.number(), f);
    }
    return m;
}

// ---- PLY ----

enum class Scalar { i8, u8, i16, u16, i32, u32, f32, f64 };

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
// `record` bytes.
std::size_t read_points(BinaryReader& binary, std::size_t count, std::size_t record, const std::size_t offset[3],
                        const Scalar type[3], std::vector<Point3>& points) {
    const std::string_view rest = binary.rest();
    const std::size_t whole = std::min(count, rest.size() / record);
    const bool swap = binary.swap();
    std::size_t i = 0;
    for (; i < whole; ++i) {
        const char* r = rest.data() + i * record;
        const Point3 p{decode(type[0], r + offset[0], swap), decode(type[1], r + offset[1], swap), decode(type[2], r + offset[2], swap)};
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) break;
        points.push_back(p);
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
        int axis_of[64];
        int list_index = -1;
        for (std::size_t k = 0; k < element.properties.size() && k < 64; ++k) {
            const Property& p = element.properties[k];
            axis_of[k] = -1;
            if (is_vertex && !p.list && (p.name == "x" || p.name == "y" || p.name == "z")) {
                axis_of[k] = p.name[0] - 'x';
            } else if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                list_index = static_cast<int>(k);
            } else if (is_vertex || is_face) {
                const std::string what = element.name + " property '" + p.name + "'";
                if (std::find(report.dropped.begin(), report.dropped.end(), what) == report.dropped.end()) {
                    report.dropped.push_back(what);
                }
            }
        }
        if (element.properties.size() > 64) throw InputError(path + ": too many properties in element " + element.name);
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
            for (std::size_t k = 0; k < element.properties.size(); ++k) {
                const Scalar t = element.properties[k].type;
                if (axis_of[k] >= 0) offset[axis_of[k]] = record, type[axis_of[k]] = t;
                record += size_of(t);
            }
            i = read_points(binary, element.count, record, offset, type, m.points);
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
                }
            }
            if (is_vertex) m.points.push_back(p);
            if (is_face) add_polygon(m, corners, options, report, path, ascii ? lines.number() : 0, i);
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
    throw InputError(path + ": unknown mesh format (use a .obj, .ply or .off file, or -f)");
}

bool has_mesh_extension(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    const std::string extension = dot == std::string::npos ? "" : lower(path.substr(dot + 1));
    return extension == "obj" || extension == "ply" || extension == "off";
}

const char* to_string(MeshFormat format) {
    switch (format) {
        case MeshFormat::obj: return "OBJ";
        case MeshFormat::ply: return "PLY";
        case MeshFormat::off: return "OFF";
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
    }
    return {};
}

void write_mesh(const mesh::Mesh& m, const std::string& path, MeshFormat format, bool ascii) {
    std::ofstream out(path, std::ios::binary);
    if (!out) throw OutputError(path + ": cannot create: " + std::strerror(errno));
    std::string buffer;
    auto flush = [&](bool force) {
        if (force || buffer.size() > (1u << 20)) {
            out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            buffer.clear();
        }
    };
    auto point_line = [&](const char* prefix, const Point3& p) {
        buffer += prefix;
        append_number(buffer, p.x);
        buffer += ' ';
        append_number(buffer, p.y);
        buffer += ' ';
        append_number(buffer, p.z);
        buffer += '\n';
        flush(false);
    };
    switch (format) {
        case MeshFormat::obj:
            buffer += "# toposimp mesh\n";
            for (const Point3& p : m.points) point_line("v ", p);
            for (const mesh::Face& f : m.faces) {
                append_face_line(buffer, "f", f, 1);
                flush(false);
            }
            break;
        case MeshFormat::off:
            buffer += "OFF\n" + std::to_string(m.points.size()) + " " + std::to_string(m.faces.size()) + " 0\n";
            for (const Point3& p : m.points) point_line("", p);
            for (const mesh::Face& f : m.faces) {
                append_face_line(buffer, "3", f, 0);
                flush(false);
            }
            break;
        case MeshFormat::ply: {
            buffer += std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
                      " 1.0\ncomment toposimp mesh\nelement vertex " + std::to_string(m.points.size()) +
                      "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                      std::to_string(m.faces.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
            if (ascii) {
                for (const Point3& p : m.points) point_line("", p);
                for (const mesh::Face& f : m.faces) {
                    append_face_line(buffer, "3", f, 0);
                    flush(false);
                }
                break;
            }
            auto put = [&](const void* bytes, std::size_t n) {
                char little[8];
                std::memcpy(little, bytes, n);
                if constexpr (std::endian::native == std::endian::big) std::reverse(little, little + n);
                buffer.append(little, n);
            };
            for (const Point3& p : m.points) {
                put(&p.x, 8);
                put(&p.y, 8);
                put(&p.z, 8);
                flush(false);
            }
            for (const mesh::Face& f : m.faces) {
                buffer += '\3';
                for (std::uint32_t v : f) put(&v, 4);
                flush(false);
            }
            break;
        }
    }
    flush(true);
    out.close();
    if (!out) throw OutputError(path + ": write error");
}

}  // namespace toposimp::io
