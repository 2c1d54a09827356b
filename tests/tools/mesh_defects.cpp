// mesh_defects MESH [--terrain] [--against ORIGINAL]: counts what the independent checker of the tests finds in a
// mesh file — face pairs that intersect beyond their shared corners/edge, non-manifold edges,
// inconsistently oriented edges, degenerate and duplicate faces, and with --terrain faces folded
// over in the x–y plane; with --against, the sampled Hausdorff distance to the original (the
// same measurement toposimp mesh reports), and with both the sampled vertical error (terrains).
// For checking any tool's output (benchmarks).
// Prints one JSON line.
#include "core/mesh/distance.hpp"
#include "io/mesh/mesh_files.hpp"
#include "support/mesh_checker.hpp"

#include <algorithm>
#include <cstring>
#include <iostream>

int main(int argc, char** argv) {
    if (argc < 2) {
        std::cerr << "usage: mesh_defects MESH [--terrain] [--against ORIGINAL]\n";
        return 2;
    }
    try {
        toposimp::io::MeshReadReport report;
        toposimp::io::MeshReadOptions options;
        options.triangulate = true;
        const toposimp::mesh::Mesh m = toposimp::io::read_mesh(argv[1], options, report);
        const toposimp::testing::MeshDefects d = toposimp::testing::find_defects(m);
        std::cout << "{\"faces\":" << m.faces.size() << ",\"intersecting_pairs\":" << d.intersecting_pairs
                  << ",\"non_manifold_edges\":" << d.non_manifold_edges << ",\"inconsistent_edges\":" << d.inconsistent_edges
                  << ",\"degenerate_faces\":" << d.degenerate_faces << ",\"duplicate_faces\":" << d.duplicate_faces;
        bool terrain = false;
        const char* against = nullptr;
        for (int i = 2; i < argc; ++i) {
            if (std::strcmp(argv[i], "--terrain") == 0) {
                terrain = true;
            } else if (std::strcmp(argv[i], "--against") == 0 && i + 1 < argc) {
                against = argv[++i];
            }
        }
        if (terrain) std::cout << ",\"map_plane_folds\":" << toposimp::testing::count_map_plane_folds(m, 1);
        if (against != nullptr) {
            const toposimp::mesh::Mesh original = toposimp::io::read_mesh(against, options, report);
            const std::size_t samples = std::clamp<std::size_t>(4 * original.faces.size(), 50000, 400000);
            const auto h = toposimp::mesh::hausdorff(original, m, samples);
            std::cout << ",\"hausdorff\":" << h.max() << ",\"hausdorff_fraction\":" << (h.diagonal > 0 ? h.max() / h.diagonal : 0.0)
                      << ",\"mean_distance\":" << 0.5 * (h.forward.mean + h.backward.mean);
            if (terrain) {
                const auto v = toposimp::mesh::vertical_error(original, m, samples);
                std::cout << ",\"vertical_error\":" << v.max() << ",\"vertical_samples_outside\":" << v.outside;
            }
        }
        std::cout << "}\n";
        return 0;
    } catch (const std::exception& error) {
        std::cerr << "mesh_defects: " << error.what() << "\n";
        return 2;
    }
}
