// Mesh files: Wavefront OBJ, PLY (ASCII, binary little and big endian) and OFF.
// Positions and triangles are read; normals, colours, texture coordinates and any other
// attributes are counted and dropped (a simplified mesh has new vertices they do not describe),
// and the caller says so. Errors name the file and the line (or element) and throw InputError.
#pragma once

#include "core/mesh/mesh.hpp"

#include <string>
#include <vector>

namespace toposimp::io {

enum class MeshFormat { obj, ply, off };

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
    std::vector<std::string> dropped;     // attributes present in the file and not kept
    std::size_t polygons_triangulated = 0;
    std::size_t ignored_elements = 0;     // OBJ lines/points, unknown PLY elements
};

mesh::Mesh read_mesh(const std::string& path, const MeshReadOptions& options, MeshReadReport& report);

// Writes exactly the given doubles: text formats with shortest round-trip numbers, binary PLY
// with double coordinates.
void write_mesh(const mesh::Mesh& mesh, const std::string& path, MeshFormat format, bool ascii);

}  // namespace toposimp::io
