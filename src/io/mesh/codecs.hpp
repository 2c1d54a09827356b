// The mesh codecs, one file each (obj.cpp, ply.cpp, off.cpp, stl.cpp): each reads a whole file's
// text, says which attribute columns it has no place for, and writes. The table of
// mesh_files.cpp lists them.
#pragma once

#include "io/mesh/mesh_files.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace toposimp::io::mesh_codec {

mesh::Mesh read_obj(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report);
mesh::Mesh read_ply(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report);
mesh::Mesh read_off(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report);
mesh::Mesh read_stl(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report);

std::vector<std::string> obj_unwritable(const AttributeLayout& layout);
std::vector<std::string> ply_unwritable(const AttributeLayout& layout);
std::vector<std::string> off_unwritable(const AttributeLayout& layout);
std::vector<std::string> stl_unwritable(const AttributeLayout& layout);

void write_obj(const mesh::Mesh& mesh, const WrittenRows& rows, MeshWriter& out, bool ascii);
void write_ply(const mesh::Mesh& mesh, const WrittenRows& rows, MeshWriter& out, bool ascii);
void write_off(const mesh::Mesh& mesh, const WrittenRows& rows, MeshWriter& out, bool ascii);
void write_stl(const mesh::Mesh& mesh, const WrittenRows& rows, MeshWriter& out, bool ascii);

}  // namespace toposimp::io::mesh_codec
