// The meshoptimizer peer for the mesh benchmark: meshopt_simplify (edge collapse to existing
// vertices, quadric error) to a target face count, with or without meshopt_SimplifyLockBorder.
// Reads and writes with toposimp's mesh I/O so every tool pays the same I/O; prints the time of
// the simplification call alone.
#include "core/mesh/mesh.hpp"
#include "io/mesh/mesh_files.hpp"

#include <meshoptimizer.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>

int main(int argc, char** argv) {
    if (argc < 4) {
        std::cerr << "usage: meshopt_simplify IN OUT TARGET_FACES [--lock-border]\n";
        return 2;
    }
    using namespace toposimp;
    io::MeshReadReport report;
    mesh::Mesh m = io::read_mesh(argv[1], {}, report);
    const auto target = static_cast<std::size_t>(std::atoll(argv[3]));
    const bool lock = argc > 4 && std::strcmp(argv[4], "--lock-border") == 0;
    std::vector<float> positions;
    positions.reserve(m.points.size() * 3);
    for (const Point3& p : m.points) {
        positions.push_back(static_cast<float>(p.x));
        positions.push_back(static_cast<float>(p.y));
        positions.push_back(static_cast<float>(p.z));
    }
    std::vector<unsigned int> indices;
    for (const mesh::Face& f : m.faces) indices.insert(indices.end(), f.begin(), f.end());
    std::vector<unsigned int> out(indices.size());
    const auto start = std::chrono::steady_clock::now();
    float error = 0;
    const std::size_t count = meshopt_simplify(out.data(), indices.data(), indices.size(), positions.data(), m.points.size(),
                                               3 * sizeof(float), 3 * target, std::numeric_limits<float>::max(),
                                               lock ? meshopt_SimplifyLockBorder : 0, &error);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    m.faces.clear();
    for (std::size_t i = 0; i < count; i += 3) m.faces.push_back({out[i], out[i + 1], out[i + 2]});
    mesh::drop_unused(m);  // vertices keep their original double positions
    io::write_mesh(m, {}, argv[2], io::mesh_format_of(argv[2]), false);
    std::cout << "{\"simplify_seconds\":" << seconds << ",\"faces_out\":" << m.faces.size() << "}\n";
    return 0;
}
