#include "core/mesh/mesh.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <memory>
#include <numeric>

namespace toposimp::mesh {
namespace {

bool repeats_corner(const Face& f) { return f[0] == f[1] || f[1] == f[2] || f[2] == f[0]; }

// A double as an unsigned integer in the doubles' order, −0 as +0: a total order even with NaNs
// (a library caller's), which the sort needs.
std::uint64_t ordered(double value) {
    const auto bits = std::bit_cast<std::uint64_t>(value + 0.0);
    return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

// The vertex numbers ordered by location (x, then y, then z), then by number: vertices at one
// location are consecutive.
std::vector<std::uint32_t> by_location(const Mesh& mesh) {
    std::vector<std::uint32_t> order(mesh.points.size());
    std::iota(order.begin(), order.end(), 0u);
    const std::vector<Point3>& p = mesh.points;
    std::sort(order.begin(), order.end(), [&p](std::uint32_t a, std::uint32_t b) {
        const std::uint64_t ka[3] = {ordered(p[a].x), ordered(p[a].y), ordered(p[a].z)};
        const std::uint64_t kb[3] = {ordered(p[b].x), ordered(p[b].y), ordered(p[b].z)};
        return std::lexicographical_compare(ka, ka + 3, kb, kb + 3) || (std::equal(ka, ka + 3, kb) && a < b);
    });
    return order;
}

}  // namespace

std::size_t count_repeated_corner_faces(const Mesh& mesh) {
    return static_cast<std::size_t>(std::count_if(mesh.faces.begin(), mesh.faces.end(), repeats_corner));
}

std::size_t drop_unused(Mesh& mesh, std::vector<std::uint32_t>* kept) {
    const std::size_t before = mesh.faces.size();
    Attributes& face_rows = mesh.face_attributes;
    std::size_t faces = 0;
    for (std::size_t f = 0; f < before; ++f) {
        if (repeats_corner(mesh.faces[f])) continue;
        if (faces != f) {
            mesh.faces[faces] = mesh.faces[f];
            std::copy_n(face_rows.row(f), face_rows.width, face_rows.row(faces));
        }
        ++faces;
    }
    mesh.faces.resize(faces);
    face_rows.values.resize(faces * face_rows.width);
    drop_unused_vertices(mesh, kept);
    return before - faces;
}

void drop_unused_vertices(Mesh& mesh, std::vector<std::uint32_t>* kept) {
    std::vector<std::uint32_t> index(mesh.points.size(), 0);
    for (const Face& f : mesh.faces) {
        for (std::uint32_t v : f) index[v] = 1;
    }
    // The old numbers are listed only when some vertex goes.
    const bool list = kept != nullptr && std::find(index.begin(), index.end(), 0u) != index.end();
    if (kept != nullptr) kept->clear();
    Attributes& vertex_rows = mesh.vertex_attributes;
    std::uint32_t next = 0;
    for (std::uint32_t v = 0; v < mesh.points.size(); ++v) {
        if (index[v] != 0) {
            if (next != v) {
                mesh.points[next] = mesh.points[v];
                std::copy_n(vertex_rows.row(v), vertex_rows.width, vertex_rows.row(next));
            }
            index[v] = next++;
            if (list) kept->push_back(v);
        }
    }
    if (next == mesh.points.size()) return;  // (every vertex used: numbers unchanged)
    mesh.points.resize(next);
    vertex_rows.values.resize(std::size_t{next} * vertex_rows.width);
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
}

std::size_t count_coincident(const Mesh& mesh) {
    const std::vector<std::uint32_t> order = by_location(mesh);
    std::size_t count = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
        const bool before = i > 0 && same_location(mesh.points[order[i - 1]], mesh.points[order[i]]);
        const bool after = i + 1 < order.size() && same_location(mesh.points[order[i + 1]], mesh.points[order[i]]);
        count += before || after;
    }
    return count;
}

Welded weld_coincident(Mesh& mesh) {
    Welded welded;
    const Attributes& rows = mesh.vertex_attributes;
    welded.differs.assign(rows.width, false);
    const std::vector<std::uint32_t> order = by_location(mesh);
    std::vector<std::uint32_t> target(mesh.points.size());
    std::iota(target.begin(), target.end(), 0u);
    for (std::size_t i = 1; i < order.size(); ++i) {
        const std::uint32_t v = order[i];
        if (!same_location(mesh.points[order[i - 1]], mesh.points[v])) continue;
        const std::uint32_t first = target[order[i - 1]];  // the group's first, in number order
        target[v] = first;
        ++welded.vertices;
        for (std::size_t c = 0; c < rows.width; ++c) {
            // (Compared as values: NaN differs from itself, and −0 equals +0.)
            if (!(rows.row(v)[c] == rows.row(first)[c])) welded.differs[c] = true;
        }
    }
    if (welded.vertices == 0) return welded;
    for (Face& f : mesh.faces) {
        for (std::uint32_t& v : f) v = target[v];
    }
    return welded;
}

void remove_vertex_columns(Mesh& mesh, const std::vector<bool>& remove) {
    Attributes& rows = mesh.vertex_attributes;
    const std::size_t width = rows.width;
    const auto kept = static_cast<std::size_t>(std::count(remove.begin(), remove.end(), false));
    if (kept == width) return;
    const std::size_t count = width == 0 ? 0 : rows.values.size() / width;
    std::size_t at = 0;
    for (std::size_t i = 0; i < count; ++i) {
        for (std::size_t c = 0; c < width; ++c) {
            if (!remove[c]) rows.values[at++] = rows.values[i * width + c];
        }
    }
    rows.values.resize(at);
    rows.width = kept;
}

}  // namespace toposimp::mesh
