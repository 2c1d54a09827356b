// Mesh files: Wavefront OBJ, PLY (ASCII, binary little and big endian), OFF and STL, one codec
// file each in io/mesh/ (obj.cpp, ply.cpp, off.cpp, stl.cpp), listed once in the table of
// mesh_formats() (mesh_files.cpp), from which the command line, its help and the QGIS provider
// (through `toposimp mesh --list-formats`) take the formats.
// Positions and triangles are read, and with them what each vertex and face carries besides:
// normals, colours, texture coordinates, any other scalar PLY property. Those become attribute
// columns of the mesh (a simplified mesh blends them, see mesh.hpp) and are written back where
// the output format has a place for them. What cannot be kept is listed, and the caller says so:
// PLY list properties other than the faces' corners, OBJ texture coordinates or normals that
// differ between the faces of one vertex (seams), colours only some vertices have. Errors name
// the file and the line (or element) and throw InputError.
#pragma once

#include "core/mesh/mesh.hpp"

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace toposimp::io {

enum class MeshFormat { obj, ply, off, stl };

// The type of a column of numbers in a file (PLY's scalar types).
enum class ValueType { i8, u8, i16, u16, i32, u32, f32, f64 };

// An attribute column: its name as a PLY property, by which the writers know it (nx ny nz: a
// normal; red green blue alpha: a colour; u v, s t or texture_u texture_v: texture coordinates),
// and the type it is written with in PLY. Colours of an integer type run from 0 to the type's
// largest value, of a float type from 0 to 1.
struct AttributeColumn {
    std::string name;
    ValueType type = ValueType::f32;
    bool operator==(const AttributeColumn&) const = default;
};

// The columns of a mesh's vertex_attributes and face_attributes, in order.
struct AttributeLayout {
    std::vector<AttributeColumn> vertex, face;
};

// Shortest round-trip text of a number (for messages).
std::string io_number(double value);

struct MeshReadOptions {
    bool triangulate = false;  // split polygons into fans; otherwise a polygon is an error
};

struct MeshReadReport {
    MeshFormat format = MeshFormat::obj;
    std::string encoding;                 // PLY: ascii, binary_little_endian, binary_big_endian
    std::vector<std::string> dropped;     // attributes present in the file and not kept, each with the reason
    AttributeLayout layout;               // those kept
    std::size_t polygons_triangulated = 0;
    std::size_t ignored_elements = 0;     // OBJ lines/points, unknown PLY elements
    std::size_t welded = 0;               // STL: corners merged into another at the same location
};

namespace mesh_codec {
class MeshWriter;
struct WrittenRows;
}  // namespace mesh_codec

// A mesh format: what names it, what it can carry, and its codec. A new format is a codec file
// in io/mesh/ and a row of the table (mesh_files.cpp); nothing else lists formats.
struct MeshFormatInfo {
    MeshFormat format;
    const char* name;       // as -f takes it: "ply"
    const char* title;      // for people: "PLY"
    const char* extension;  // ".ply" (any case)
    const char* carries;    // the attributes it can hold, in words
    bool has_text_and_binary;  // --ascii chooses the text encoding
    mesh::Mesh (*read)(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report);
    // The columns of `layout` it has no place for ("vertex quality", ...).
    std::vector<std::string> (*unwritable)(const AttributeLayout& layout);
    void (*write)(const mesh::Mesh& mesh, const mesh_codec::WrittenRows& rows, mesh_codec::MeshWriter& out, bool ascii);
};

// Every mesh format, in the order the help lists them.
std::span<const MeshFormatInfo> mesh_formats();
const MeshFormatInfo& info(MeshFormat format);
// The format -f names (case-insensitive), or null.
const MeshFormatInfo* mesh_format_named(std::string_view name);
// The format of a file name's extension (case-insensitive), or null.
const MeshFormatInfo* mesh_format_by_extension(const std::string& path);
// From the file name's extension; throws InputError for anything else.
MeshFormat mesh_format_of(const std::string& path);
// Does the file name end in a mesh format's extension?
bool has_mesh_extension(const std::string& path);
const char* to_string(MeshFormat format);
// The formats' extensions or names joined for messages and help: ".obj, .ply, .off, .stl", or
// with `last` before the last one: ".obj, .ply, .off or .stl".
std::string mesh_extensions_text(const char* separator = ", ", const char* last = nullptr);
std::string mesh_format_names_text(const char* separator = ", ");

mesh::Mesh read_mesh(const std::string& path, const MeshReadOptions& options, MeshReadReport& report);

// Writes exactly the given doubles: text formats with shortest round-trip numbers, binary PLY
// with double coordinates. Attribute columns are written as the format allows (PLY: every one,
// with its type; OBJ: vertex colours, texture coordinates and normals; OFF: those and face
// colours); integer columns rounded and clamped to their type, normals scaled to unit length.
// Returns the columns the format has no place for ("vertex quality", ...), which are not written.
// `shown_as`: the name errors give the file (the destination, when `path` is its staging file).
std::vector<std::string> write_mesh(const mesh::Mesh& mesh, const AttributeLayout& layout, const std::string& path,
                                    MeshFormat format, bool ascii, const std::string& shown_as = {});

}  // namespace toposimp::io
