// The CGAL peer for the mesh benchmark: Surface_mesh_simplification edge collapse with the
// Garland–Heckbert plane policies, stopping at a face count. Reads and writes with toposimp's
// mesh I/O; prints the time of the simplification call alone.
#include "core/mesh/mesh.hpp"
#include "io/mesh/mesh_files.hpp"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <map>

using Kernel = CGAL::Simple_cartesian<double>;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMS = CGAL::Surface_mesh_simplification;

int main(int argc, char** argv) {
    if (argc < 4) {
        std::cerr << "usage: cgal_simplify IN OUT TARGET_FACES\n";
        return 2;
    }
    using namespace toposimp;
    io::MeshReadReport report;
    const mesh::Mesh in = io::read_mesh(argv[1], {}, report);
    Surface surface;
    std::vector<Surface::Vertex_index> vertex;
    for (const Point3& p : in.points) vertex.push_back(surface.add_vertex(Kernel::Point_3(p.x, p.y, p.z)));
    std::size_t skipped = 0;
    for (const mesh::Face& f : in.faces) {
        if (surface.add_face(vertex[f[0]], vertex[f[1]], vertex[f[2]]) == Surface::null_face()) ++skipped;
    }
    const auto target = static_cast<std::size_t>(std::atoll(argv[3]));
    const auto start = std::chrono::steady_clock::now();
    // CGAL 5.5 counts edges: a closed triangle mesh has 3/2 edges per face (a terrain slightly fewer).
    SMS::Count_stop_predicate<Surface> stop(target * 3 / 2);
    SMS::GarlandHeckbert_plane_policies<Surface, Kernel> policies(surface);
    SMS::edge_collapse(surface, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    mesh::Mesh out;
    std::map<Surface::Vertex_index, std::uint32_t> id;
    for (Surface::Vertex_index v : surface.vertices()) {
        id[v] = static_cast<std::uint32_t>(out.points.size());
        const auto& p = surface.point(v);
        out.points.push_back({p.x(), p.y(), p.z()});
    }
    for (Surface::Face_index f : surface.faces()) {
        mesh::Face face{};
        int k = 0;
        for (Surface::Vertex_index v : CGAL::vertices_around_face(surface.halfedge(f), surface)) face[k++] = id[v];
        out.faces.push_back(face);
    }
    mesh::drop_unused(out);
    io::write_mesh(out, {}, argv[2], io::mesh_format_of(argv[2]), false);
    std::cout << "{\"simplify_seconds\":" << seconds << ",\"faces_out\":" << out.faces.size() << ",\"faces_not_added\":" << skipped
              << "}\n";
    return 0;
}
