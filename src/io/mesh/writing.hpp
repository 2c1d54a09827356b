// What the mesh writers share: a buffered file with numbers written shortest round-trip, the
// attribute columns each format has a place for, and the values as written.
#pragma once

#include "io/common/errors.hpp"
#include "io/common/number_format.hpp"
#include "io/mesh/mesh_files.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace toposimp::io::mesh_codec {

// The output file, through a buffer written out a megabyte at a time (a line or record is
// flushed only when it is whole).
class MeshWriter {
public:
    // `shown_as`: the name errors give the file (the destination, when `path` is its staging file).
    MeshWriter(const std::string& path, const std::string& shown_as);
    std::string buffer;
    void flush(bool force = false) {
        if (force || buffer.size() > (1u << 20)) {
            out_.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            buffer.clear();
        }
    }
    // Numbers separated by spaces, after `prefix`.
    void numbers(std::string_view prefix, std::initializer_list<double> values) {
        buffer += prefix;
        for (double value : values) {
            if (!buffer.empty() && buffer.back() != '\n') buffer += ' ';
            append_number(buffer, value);
        }
    }
    // Writes what is left and closes the file (OutputError if that fails).
    void finish();

private:
    std::string shown_as_;
    std::ofstream out_;
};

// The rows of a mesh as written (written_values), and their columns.
struct WrittenRows {
    const mesh::Attributes& vertex;
    const mesh::Attributes& face;
    const AttributeLayout& layout;
};

inline void append_face_line(std::string& out, const char* prefix, const mesh::Face& f, std::uint32_t base) {
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

int column_named(const std::vector<AttributeColumn>& columns, std::string_view name);

ColourColumns find_colour(const std::vector<AttributeColumn>& columns);

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

VertexGroups find_groups(const std::vector<AttributeColumn>& columns);

// The largest value of an integer type (a colour's full intensity), 1 for a float type.
double colour_scale(ValueType type);

// The rows as written: integer columns rounded and clamped to their type (a blend of two
// integers is seldom one), the normal (columns `normal`, or none if -1) scaled to unit length (a
// blend of two unit vectors is shorter).
mesh::Attributes written_values(const mesh::Attributes& rows, const std::vector<AttributeColumn>& columns,
                                std::array<int, 3> normal);

std::string ply_type_name(ValueType type);

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

// A colour as OFF or OBJ writes it (row i of `rows`, columns `columns` of types `types`): from 0
// to 1, or OFF's integers if all its columns are uchar (`off`); in OFF a number from 0 to 1
// always shows a decimal point, so that it reads as such.
void write_colour(MeshWriter& out, const mesh::Attributes& rows, std::size_t i, const ColourColumns& columns,
                  const std::vector<AttributeColumn>& types, bool with_alpha, bool off);

}  // namespace toposimp::io::mesh_codec
