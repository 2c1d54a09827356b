#include "io/mesh/mesh_files.hpp"

#include "io/common/input_file.hpp"
#include "io/mesh/codecs.hpp"
#include "io/mesh/reading.hpp"
#include "io/mesh/writing.hpp"

#include <array>

namespace toposimp::io {
namespace {

using namespace mesh_codec;

// The mesh formats: the only list of them.
constexpr std::array<MeshFormatInfo, 4> kFormats{{
    {MeshFormat::obj, "obj", "OBJ", ".obj", "vertex colours, texture coordinates and normals (one per vertex)", false,
     read_obj, obj_unwritable, write_obj},
    {MeshFormat::ply, "ply", "PLY", ".ply", "every scalar vertex and face property, with its type", true, read_ply,
     ply_unwritable, write_ply},
    {MeshFormat::off, "off", "OFF", ".off", "vertex normals, colours and texture coordinates; face colours", false, read_off,
     off_unwritable, write_off},
    {MeshFormat::stl, "stl", "STL", ".stl", "positions only (corners welded on reading)", true, read_stl, stl_unwritable,
     write_stl},
}};

std::string extension_of(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    return dot == std::string::npos ? "" : lower(path.substr(dot));
}

}  // namespace

std::string io_number(double value) {
    std::string text;
    append_number(text, value);
    return text;
}

std::span<const MeshFormatInfo> mesh_formats() { return kFormats; }

const MeshFormatInfo& info(MeshFormat format) {
    for (const MeshFormatInfo& row : kFormats) {
        if (row.format == format) return row;
    }
    return kFormats.front();  // (every format has a row)
}

const MeshFormatInfo* mesh_format_named(std::string_view name) {
    const std::string wanted = lower(std::string(name));
    for (const MeshFormatInfo& row : kFormats) {
        if (wanted == row.name) return &row;
    }
    return nullptr;
}

const MeshFormatInfo* mesh_format_by_extension(const std::string& path) {
    const std::string extension = extension_of(path);
    for (const MeshFormatInfo& row : kFormats) {
        if (extension == row.extension) return &row;
    }
    return nullptr;
}

MeshFormat mesh_format_of(const std::string& path) {
    if (const MeshFormatInfo* row = mesh_format_by_extension(path)) return row->format;
    throw InputError(path + ": unknown mesh format (use a " + mesh_extensions_text(", ", " or ") + " file, or -f)");
}

bool has_mesh_extension(const std::string& path) { return mesh_format_by_extension(path) != nullptr; }

const char* to_string(MeshFormat format) { return info(format).title; }

std::string mesh_extensions_text(const char* separator, const char* last) {
    std::string text;
    for (std::size_t i = 0; i < kFormats.size(); ++i) {
        const char* before = i == 0 ? "" : last && i + 1 == kFormats.size() ? last : separator;
        text += before + std::string(kFormats[i].extension);
    }
    return text;
}

std::string mesh_format_names_text(const char* separator) {
    std::string text;
    for (const MeshFormatInfo& row : kFormats) text += (text.empty() ? "" : separator) + std::string(row.name);
    return text;
}

mesh::Mesh read_mesh(const std::string& path, const MeshReadOptions& options, MeshReadReport& report) {
    report.format = mesh_format_of(path);
    const std::string data = read_file(path);
    std::string_view text(data);
    // A PLY or OFF file under another mesh extension is read as what it is, when its first line
    // says so exactly: "ply", or an OFF header word ([ST][C][N][4][n]OFF). Never for STL, whose
    // binary header is free text (issue 29: one starting "OFFSHORE"), and never on a word that
    // merely begins the same (an OBJ starting "# OFFSET").
    if (report.format != MeshFormat::stl) {
        const std::string_view first = text.substr(0, std::min(text.find_first_of("\r\n"), text.size()));
        const std::string_view word = first.substr(0, std::min(first.find_first_of(" \t"), first.size()));
        const bool off_word = word.ends_with("OFF") && word.substr(0, word.size() - 3).find_first_not_of("STCN4n") == std::string_view::npos;
        if (first == "ply") {
            report.format = MeshFormat::ply;
        } else if (off_word) {
            report.format = MeshFormat::off;
        }
    }
    return info(report.format).read(path, text, options, report);
}

std::vector<std::string> write_mesh(const mesh::Mesh& m, const AttributeLayout& layout, const std::string& path,
                                    MeshFormat format, bool ascii, const std::string& shown_as) {
    const MeshFormatInfo& codec = info(format);
    std::vector<std::string> unwritable = codec.unwritable(layout);
    const VertexGroups groups = find_groups(layout.vertex);
    const mesh::Attributes vertex_rows = written_values(m.vertex_attributes, layout.vertex, groups.normal);
    const mesh::Attributes face_rows = written_values(m.face_attributes, layout.face, {-1, -1, -1});  // (no normal)
    MeshWriter out(path, shown_as);
    codec.write(m, {vertex_rows, face_rows, layout}, out, ascii);
    out.finish();
    return unwritable;
}

}  // namespace toposimp::io
