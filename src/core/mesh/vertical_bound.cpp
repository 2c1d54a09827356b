#include "core/mesh/vertical_bound.hpp"

#include <algorithm>
#include <utility>
#include <vector>

namespace toposimp::mesh {
namespace {

Point plan(Point3 p) { return {p.x, p.y}; }

struct PlanBox {
    double x0, y0, x1, y1;
    explicit PlanBox(Point3 p) : x0(p.x), y0(p.y), x1(p.x), y1(p.y) {}
    void add(Point3 p) {
        x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    }
    bool holds(Point3 p) const { return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1; }
    bool meets(const PlanBox& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
};

PlanBox box_of(Point3 a, Point3 b) {
    PlanBox box(a);
    box.add(b);
    return box;
}

PlanBox box_of(const exact::Triangle3& t) {
    PlanBox box(t[0]);
    box.add(t[1]);
    box.add(t[2]);
    return box;
}

// Is q in the closed triangle t, whose map-plane orientation is `turn` (not 0)?
bool in_closed(const exact::Triangle3& t, int turn, Point3 q, exact::PredicateStats& stats) {
    const Point x = plan(q);
    return exact::orient2d(plan(t[0]), plan(t[1]), x, stats) * turn >= 0 &&
           exact::orient2d(plan(t[1]), plan(t[2]), x, stats) * turn >= 0 &&
           exact::orient2d(plan(t[2]), plan(t[0]), x, stats) * turn >= 0;
}

// Per thread: which input faces and vertices this call has seen.
struct Marks {
    std::vector<std::uint32_t> face, vertex;
    std::uint32_t generation = 0;

    void start(std::size_t faces, std::size_t vertices) {
        if (face.size() != faces || vertex.size() != vertices || ++generation == 0) {
            face.assign(faces, 0);
            vertex.assign(vertices, 0);
            generation = 1;
        }
    }
};

bool by_location(Point3 a, Point3 b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

}  // namespace

VerticalBound::VerticalBound(const Mesh& input, double bound)
    : input_(input), index_(input_), border_(input_.faces.size(), 0), bound_(bound) {
    // Border edges: those no other face has, from either end.
    std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>> edges;  // (lower, higher), face·3 + k
    edges.reserve(3 * input_.faces.size());
    for (std::uint32_t f = 0; f < input_.faces.size(); ++f) {
        const Face& c = input_.faces[f];
        for (std::uint32_t k = 0; k < 3; ++k) edges.push_back({std::minmax(c[k], c[(k + 1) % 3]), 3 * f + k});
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i + 1;
        while (j < edges.size() && edges[j].first == edges[i].first) ++j;
        if (j == i + 1) border_[edges[i].second / 3] = static_cast<std::uint8_t>(border_[edges[i].second / 3] | (1u << (edges[i].second % 3)));
        i = j;
    }
}

bool VerticalBound::holds(std::span<const exact::Triangle3> fan, exact::PredicateStats& stats) const {
    if (fan.empty()) return true;
    const Point3 p = fan[0][0];
    const int turn = exact::orient2d(plan(fan[0][0]), plan(fan[0][1]), plan(fan[0][2]), stats);
    const auto triangle = [this](std::uint32_t f) -> exact::Triangle3 {
        const Face& c = input_.faces[f];
        return {input_.points[c[0]], input_.points[c[1]], input_.points[c[2]]};
    };

    // p against every input face under it.
    for (std::uint32_t f : index_.at(p.x, p.y)) {
        const exact::Triangle3 t = triangle(f);
        const int t_turn = exact::orient2d(plan(t[0]), plan(t[1]), plan(t[2]), stats);
        if (t_turn == 0 || !box_of(t).holds(p) || !in_closed(t, t_turn, p, stats)) continue;
        if (!exact::vertical_gap_within(t, p, bound_, stats)) return false;
    }

    // The input faces near the fan, each once (marked with this call's generation).
    PlanBox region = box_of(fan[0]);
    thread_local std::vector<PlanBox> boxes;
    boxes.clear();
    for (const exact::Triangle3& t : fan) {
        boxes.push_back(box_of(t));
        region.add(t[1]);
        region.add(t[2]);
    }
    thread_local Marks marks;
    marks.start(input_.faces.size(), input_.points.size());
    thread_local std::vector<std::uint32_t> faces;
    faces.clear();
    index_.visit(region.x0, region.y0, region.x1, region.y1, [](std::uint32_t f) {
        if (marks.face[f] != marks.generation) {
            marks.face[f] = marks.generation;
            faces.push_back(f);
        }
    });

    // Every input vertex in the fan against the new face over it (on an edge between two new
    // faces, either: they agree there).
    for (std::uint32_t f : faces) {
        for (std::uint32_t v : input_.faces[f]) {
            if (marks.vertex[v] == marks.generation) continue;
            marks.vertex[v] = marks.generation;
            const Point3 q = input_.points[v];
            if (!region.holds(q)) continue;
            for (std::size_t i = 0; i < fan.size(); ++i) {
                if (!boxes[i].holds(q) || !in_closed(fan[i], turn, q, stats)) continue;
                if (!exact::vertical_gap_within(fan[i], q, bound_, stats)) return false;
                break;
            }
        }
    }

    // Every crossing of an edge from p with an input edge (a touch — an end of one on the other
    // — is a vertex case above). An input edge is taken from the face that has it from its lower
    // to its higher vertex (both faces of an edge that crosses one from p are near the fan), or
    // from its only face.
    thread_local std::vector<Point3> ends;
    ends.clear();
    for (const exact::Triangle3& t : fan) {
        ends.push_back(t[1]);
        ends.push_back(t[2]);
    }
    std::sort(ends.begin(), ends.end(), by_location);
    ends.erase(std::unique(ends.begin(), ends.end(), [](Point3 a, Point3 b) { return same_location(a, b); }), ends.end());
    for (std::uint32_t f : faces) {
        const Face& c = input_.faces[f];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t iu = c[k], iw = c[(k + 1) % 3];
            if (iu > iw && (border_[f] & (1u << k)) == 0) continue;
            const Point3 u = input_.points[iu], w = input_.points[iw];
            const PlanBox edge_box = box_of(u, w);
            if (!edge_box.meets(region)) continue;
            int side_p = 2;  // orient2d(u, w, p), once per edge
            for (const Point3& l : ends) {
                if (!edge_box.meets(box_of(p, l))) continue;
                if (side_p == 2) side_p = exact::orient2d(plan(u), plan(w), plan(p), stats);
                if (side_p == 0 || exact::orient2d(plan(u), plan(w), plan(l), stats) * side_p >= 0) continue;
                const int side_u = exact::orient2d(plan(p), plan(l), plan(u), stats);
                if (side_u == 0 || exact::orient2d(plan(p), plan(l), plan(w), stats) * side_u >= 0) continue;
                if (!exact::crossing_gap_within(p, l, u, w, bound_, stats)) return false;
            }
        }
    }
    return true;
}

}  // namespace toposimp::mesh
