#include "io/mesh/writing.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>

namespace toposimp::io::mesh_codec {

MeshWriter::MeshWriter(const std::string& path, const std::string& shown_as)
    : shown_as_(shown_as.empty() ? path : shown_as), out_(path, std::ios::binary) {
    if (!out_) throw OutputError(shown_as_ + ": cannot create: " + std::strerror(errno));
}

void MeshWriter::finish() {
    flush(true);
    out_.close();
    // (The reason, "No space left on device" say, not just that it failed.)
    if (!out_) throw OutputError(shown_as_ + ": cannot write: " + std::strerror(errno));
}

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

void write_colour(MeshWriter& out, const mesh::Attributes& rows, std::size_t i, const ColourColumns& columns,
                  const std::vector<AttributeColumn>& types, bool with_alpha, bool off) {
    std::string& buffer = out.buffer;
    const std::size_t count = with_alpha ? 4 : 3;
    const bool integers = off && columns.all_of(types, ValueType::u8);
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
        if (off && !integers && buffer.find_first_of(".eEn", at) == std::string::npos) buffer += ".0";
    }
}

}  // namespace toposimp::io::mesh_codec
