// What the mesh readers share: the whole file in memory, lines and tokens, numbers, faces and
// attribute columns, and messages that name the file and line.
#pragma once

#include "io/common/errors.hpp"
#include "io/common/number_format.hpp"
#include "io/mesh/mesh_files.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace toposimp::io::mesh_codec {

std::string lower(std::string text);

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

inline void split(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

inline std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line) + ": "; }

Point3 parse_point(const std::string& path, std::size_t line, std::string_view x, std::string_view y, std::string_view z,
                   std::size_t vertex);

inline bool parse_integer(std::string_view text, long long& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

inline bool is_integer_text(std::string_view text) {
    long long unused = 0;
    return parse_integer(text, unused);
}

// Adds a polygon's corners as triangles (a fan), or refuses a polygon. Returns how many
// triangles it added (a face's attribute row goes with each).
std::size_t add_polygon(mesh::Mesh& m, const std::vector<std::uint32_t>& corners, const MeshReadOptions& options,
                        MeshReadReport& report, const std::string& path, std::size_t line, std::size_t face);

// Appends `row` to `rows` `times` times.
inline void append_rows(std::vector<double>& rows, const std::vector<double>& row, std::size_t times) {
    for (std::size_t i = 0; i < times; ++i) rows.insert(rows.end(), row.begin(), row.end());
}

// Adds columns of one type under the given names.
inline void add_columns(std::vector<AttributeColumn>& columns, std::initializer_list<const char*> names, ValueType type) {
    for (const char* name : names) columns.push_back({name, type});
}

// Widens each of `elements` rows by the `width` values of `source` for it (width per element,
// in element order): a reader's columns, gathered apart, joined to those it has.
void append_columns(mesh::Attributes& rows, std::size_t elements, std::size_t width, const std::vector<double>& source);

void check_index(const std::string& path, std::size_t line, std::size_t face, long long index, std::size_t vertices);

// Parses tokens[first, first + count) as numbers into `out`.
void parse_numbers(const std::vector<std::string_view>& tokens, std::size_t first, std::size_t count,
                   std::vector<double>& out, const std::string& path, std::size_t line);

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

}  // namespace toposimp::io::mesh_codec
