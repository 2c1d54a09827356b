// Mesh files: Wavefront OBJ, PLY (ASCII, binary little and big endian) and OFF.
// Positions and triangles are read, and with them what each vertex and face carries besides:
// normals, colours, texture coordinates, any other scalar PLY property. Those become attribute
// columns of the mesh (a simplified mesh blends them, see mesh.hpp) and are written back where
// the output format has a place for them. What cannot be kept is listed, and the caller says so:
// PLY list properties other than the faces' corners, OBJ texture coordinates or normals that
// differ between the faces of one vertex (seams), colours only some vertices have. Errors name
// the file and the line (or element) and throw InputError.
#pragma once

#include "core/mesh/mesh.hpp"

#include <string>
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

// From the file name's extension (case-insensitive); throws InputError for anything else.
MeshFormat mesh_format_of(const std::string& path);
// Does the file name end in .obj, .ply or .off?
bool has_mesh_extension(const std::string& path);
const char* to_string(MeshFormat format);

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

mesh::Mesh read_mesh(const std::string& path, const MeshReadOptions& options, MeshReadReport& report);

// Writes exactly the given doubles: text formats with shortest round-trip numbers, binary PLY
// with double coordinates. Attribute columns are written as the format allows (PLY: every one,
// with its type; OBJ: vertex colours, texture coordinates and normals; OFF: those and face
// colours); integer columns rounded and clamped to their type, normals scaled to unit length.
// Returns the columns the format has no place for ("vertex quality", ...), which are not written.
std::vector<std::string> write_mesh(const mesh::Mesh& mesh, const AttributeLayout& layout, const std::string& path,
                                    MeshFormat format, bool ascii);

}  // namespace toposimp::io
