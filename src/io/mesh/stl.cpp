// STL: triangles with corners of their own, binary or text. Corners at one location are welded
// on reading; nothing but positions is carried.
#include "io/mesh/codecs.hpp"
#include "io/mesh/reading.hpp"
#include "io/mesh/writing.hpp"

#include <bit>
#include <cmath>
#include <limits>

namespace toposimp::io::mesh_codec {

// STL: triangles with corners of their own. Binary (an 80-byte header, a little-endian uint32
// count, then per triangle a normal, three corners as float32 and a uint16 "attribute byte
// count") when the size is exactly that; otherwise text ("solid", then per facet "facet normal …,
// outer loop, vertex x y z three times, endloop, endfacet", and "endsolid"). Corners at the same
// location are welded into one vertex (STL has no other way to share them); facet normals are
// not read (they follow from the corners).
mesh::Mesh read_stl(const std::string& path, std::string_view text, const MeshReadOptions& options, MeshReadReport& report) {
    mesh::Mesh m;
    constexpr bool big_endian = std::endian::native == std::endian::big;
    const std::uint64_t count = text.size() >= 84 ? static_cast<std::uint64_t>(load<std::uint32_t>(text.data() + 80, big_endian)) : 0;
    auto corner = [&](Point3 p, std::size_t triangle, std::size_t line) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw InputError((line > 0 ? where(path, line) : path + ": ") + "triangle " + std::to_string(triangle) +
                             " has a non-finite coordinate");
        }
        m.points.push_back(p);
    };
    if (text.size() >= 84 && text.size() == 84 + 50 * count) {
        report.encoding = "binary";
        if (count > std::numeric_limits<std::uint32_t>::max() / 3) {
            throw InputError(path + ": " + std::to_string(count) + " triangles: more corners than 32-bit vertex numbers hold");
        }
        m.points.reserve(3 * count);
        m.faces.reserve(count);
        std::size_t coloured = 0;
        for (std::size_t t = 0; t < count; ++t) {
            const char* r = text.data() + 84 + 50 * t;
            for (int k = 0; k < 3; ++k) {
                const char* c = r + 12 + 12 * k;
                corner({load<float>(c, big_endian), load<float>(c + 4, big_endian), load<float>(c + 8, big_endian)}, t, 0);
            }
            const auto first = static_cast<std::uint32_t>(3 * t);
            m.faces.push_back({first, first + 1, first + 2});
            coloured += r[48] != 0 || r[49] != 0;
        }
        if (coloured > 0) {
            report.dropped.push_back("face attribute bytes (a colour in some tools): " + std::to_string(coloured) + " of " +
                                     std::to_string(count) + " triangles have them; not read");
        }
    } else {
        report.encoding = "ascii";
        Lines lines(text);
        std::string_view line;
        std::vector<std::string_view> tokens;
        bool started = false;
        std::vector<std::uint32_t> loop;  // the current facet's corners
        std::size_t facet = 0;
        while (lines.next(line)) {
            split(line, tokens);
            if (tokens.empty()) continue;
            const std::string keyword = lower(std::string(tokens[0]));
            if (!started) {
                if (keyword != "solid") {
                    throw InputError(path + ": not an STL file: not binary (84 bytes and 50 per triangle: its header counts " +
                                     std::to_string(count) + " triangles, the file has " + std::to_string(text.size()) +
                                     " bytes) and not text starting with 'solid'");
                }
                started = true;
            } else if (keyword == "vertex") {
                if (tokens.size() < 4) throw InputError(where(path, lines.number()) + "a vertex needs 3 numbers");
                double c[3];
                for (int a = 0; a < 3; ++a) {
                    if (!parse_number(tokens[1 + static_cast<std::size_t>(a)], c[a])) {
                        throw InputError(where(path, lines.number()) + "'" + std::string(tokens[1 + static_cast<std::size_t>(a)]) +
                                         "' is not a number");
                    }
                }
                loop.push_back(static_cast<std::uint32_t>(m.points.size()));
                corner({c[0], c[1], c[2]}, facet, lines.number());
            } else if (keyword == "endloop") {
                add_polygon(m, loop, options, report, path, lines.number(), facet);
                ++facet;
                loop.clear();
            } else if (keyword != "facet" && keyword != "outer" && keyword != "endfacet" && keyword != "solid" &&
                       keyword != "endsolid") {
                throw InputError(where(path, lines.number()) + "'" + std::string(tokens[0]) + "' is not an STL keyword");
            }
        }
        if (!started) throw InputError(path + ": empty file, expected an STL solid");
        if (!loop.empty()) throw InputError(path + ": truncated: the file ends inside a facet");
    }
    report.welded = mesh::weld_coincident(m).vertices;
    mesh::drop_unused_vertices(m);  // (faces with a repeated corner stay: the caller warns about them)
    return m;
}

std::vector<std::string> stl_unwritable(const AttributeLayout& layout) {
    std::vector<std::string> unwritable;
    for (const AttributeColumn& column : layout.vertex) unwritable.push_back("vertex " + column.name);
    for (const AttributeColumn& column : layout.face) unwritable.push_back("face " + column.name);
    return unwritable;
}

void write_stl(const mesh::Mesh& m, const WrittenRows& /*rows*/, MeshWriter& out, bool ascii) {
    // Binary STL holds float32 corners: written only if every coordinate is one (else the
    // rounding could make faces cross); text otherwise, every digit kept.
    const bool floats = std::all_of(m.points.begin(), m.points.end(), [](const Point3& p) {
        return static_cast<float>(p.x) == p.x && static_cast<float>(p.y) == p.y && static_cast<float>(p.z) == p.z;
    });
    auto normal_of = [&](const mesh::Face& f) {
        const Point3 a = m.points[f[0]], b = m.points[f[1]], c = m.points[f[2]];
        const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
        const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
        return length > 0 && std::isfinite(length) ? Point3{nx / length, ny / length, nz / length} : Point3{0, 0, 0};
    };
    if (floats && !ascii && m.faces.size() <= std::numeric_limits<std::uint32_t>::max()) {
        out.buffer.append(80, '\0');
        out.buffer.replace(0, 22, "toposimp mesh (binary)");
        auto put = [&](auto value) {
            char bytes[sizeof(value)];
            std::memcpy(bytes, &value, sizeof(value));
            if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(value));
            out.buffer.append(bytes, sizeof(value));
        };
        put(static_cast<std::uint32_t>(m.faces.size()));
        for (const mesh::Face& f : m.faces) {
            const Point3 n = normal_of(f);
            for (double value : {n.x, n.y, n.z}) put(static_cast<float>(value));
            for (std::uint32_t v : f) {
                for (double value : {m.points[v].x, m.points[v].y, m.points[v].z}) put(static_cast<float>(value));
            }
            put(std::uint16_t{0});
            out.flush();
        }
    } else {
        out.buffer += "solid toposimp\n";
        for (const mesh::Face& f : m.faces) {
            const Point3 n = normal_of(f);
            out.numbers("facet normal", {n.x, n.y, n.z});
            out.buffer += "\nouter loop\n";
            for (std::uint32_t v : f) {
                out.numbers("vertex", {m.points[v].x, m.points[v].y, m.points[v].z});
                out.buffer += '\n';
            }
            out.buffer += "endloop\nendfacet\n";
            out.flush();
        }
        out.buffer += "endsolid toposimp\n";
    }
}

}  // namespace toposimp::io::mesh_codec
