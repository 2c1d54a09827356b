// Fuzz target: one mesh format's reader (TOPOSIMP_FUZZ_FORMAT: obj, ply, off or stl) on any
// bytes. It may refuse them (InputError), never crash, read out of bounds or loop without end;
// what it accepts is a mesh whose corners name existing vertices and whose attribute rows fit.
#include "io/common/errors.hpp"
#include "io/mesh/codecs.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

using namespace toposimp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    io::MeshReadOptions options;
    options.triangulate = size % 2 == 1;  // both ways over the corpus
    io::MeshReadReport report;
    try {
        const mesh::Mesh m = io::mesh_codec::TOPOSIMP_FUZZ_READER("fuzz." TOPOSIMP_FUZZ_FORMAT, text, options, report);
        for (const mesh::Face& f : m.faces) {
            for (const std::uint32_t v : f) {
                if (v >= m.points.size()) std::abort();
            }
        }
        if (m.vertex_attributes.values.size() != m.points.size() * m.vertex_attributes.width) std::abort();
        if (m.face_attributes.values.size() != m.faces.size() * m.face_attributes.width) std::abort();
        if (report.layout.vertex.size() != m.vertex_attributes.width || report.layout.face.size() != m.face_attributes.width) {
            std::abort();
        }
    } catch (const io::InputError&) {
    }
    return 0;
}
