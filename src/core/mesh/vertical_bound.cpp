#include "core/mesh/vertical_bound.hpp"

#include <algorithm>
#include <utility>

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
};

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

// Per thread, for walks: the input faces a walk has visited and the sides of the input vertices
// it has classified, stamped with the walk's number (no clearing between walks).
struct WalkMarks {
    std::vector<std::uint32_t> face, vertex;
    std::vector<std::int8_t> side;
    std::uint32_t walk = 0;

    void start(std::size_t faces, std::size_t vertices) {
        if (face.size() != faces || vertex.size() != vertices || ++walk == 0) {
            face.assign(faces, 0);
            vertex.assign(vertices, 0);
            side.assign(vertices, 0);
            walk = 1;
        }
    }
};

// What holds() found, for collapsed(): input vertex and the fan face over it.
thread_local std::vector<std::pair<std::uint32_t, std::uint32_t>> placed;

}  // namespace

VerticalBound::VerticalBound(const Mesh& input, double bound)
    : input_(input), index_(input_), neighbour_(input_.faces.size(), {kNone, kNone, kNone}),
      first_(input_.faces.size(), kNone), next_(input_.points.size(), kNone), bound_(bound) {
    // Neighbours across edges: the faces of each edge, found by sorting (lower, higher, face·3 + k).
    std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>> edges;
    edges.reserve(3 * input_.faces.size());
    for (std::uint32_t f = 0; f < input_.faces.size(); ++f) {
        const Face& c = input_.faces[f];
        for (std::uint32_t k = 0; k < 3; ++k) edges.push_back({std::minmax(c[k], c[(k + 1) % 3]), 3 * f + k});
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
        if (edges[i].first != edges[i + 1].first) continue;
        const std::uint32_t x = edges[i].second, y = edges[i + 1].second;  // (a manifold edge: two at most)
        neighbour_[x / 3][x % 3] = y / 3;
        neighbour_[y / 3][y % 3] = x / 3;
    }
    // Each input vertex listed in the first face it is a corner of.
    std::vector<std::uint8_t> listed(input_.points.size(), 0);
    for (std::uint32_t f = 0; f < input_.faces.size(); ++f) {
        for (std::uint32_t v : input_.faces[f]) {
            if (listed[v]) continue;
            listed[v] = 1;
            next_[v] = first_[f];
            first_[f] = v;
        }
    }
}

bool VerticalBound::holds(std::span<const exact::Triangle3> fan, std::span<const std::uint32_t> before,
                          exact::PredicateStats& stats) {
    placed.clear();
    if (fan.empty()) return true;
    const Point3 p = fan[0][0];
    const int turn = exact::orient2d(plan(fan[0][0]), plan(fan[0][1]), plan(fan[0][2]), stats);

    // p against every input face under it.
    thread_local std::vector<std::uint32_t> under;
    under.clear();
    for (std::uint32_t f : index_.at(p.x, p.y)) {
        const Face& c = input_.faces[f];
        const exact::Triangle3 t{input_.points[c[0]], input_.points[c[1]], input_.points[c[2]]};
        const int t_turn = exact::orient2d(plan(t[0]), plan(t[1]), plan(t[2]), stats);
        if (t_turn == 0 || !box_of(t).holds(p) || !in_closed(t, t_turn, p, stats)) continue;
        if (!exact::vertical_gap_within(t, p, bound_, stats)) return false;
        under.push_back(f);
    }
    if (under.empty()) return false;  // (p off the input: not a height field there)

    // Every input vertex listed in the faces replaced against the new face over it (on an edge
    // between two new faces, either: they agree there).
    thread_local std::vector<PlanBox> boxes;
    boxes.clear();
    for (const exact::Triangle3& t : fan) boxes.push_back(box_of(t));
    for (std::uint32_t f : before) {
        for (std::uint32_t v = first_[f]; v != kNone; v = next_[v]) {
            const Point3 q = input_.points[v];
            std::size_t i = 0;
            while (i < fan.size() && !(boxes[i].holds(q) && in_closed(fan[i], turn, q, stats))) ++i;
            if (i == fan.size()) return false;  // (not covered by the new faces: cannot happen without a fold)
            if (!exact::vertical_gap_within(fan[i], q, bound_, stats)) return false;
            placed.emplace_back(v, static_cast<std::uint32_t>(i));
        }
    }

    // Every crossing of an edge from p with an input edge: a walk along each, once.
    thread_local std::vector<Point3> ends;
    ends.clear();
    for (const exact::Triangle3& t : fan) {
        ends.push_back(t[1]);
        ends.push_back(t[2]);
    }
    std::sort(ends.begin(), ends.end(), [](Point3 u, Point3 w) { return u.x != w.x ? u.x < w.x : u.y != w.y ? u.y < w.y : u.z < w.z; });
    ends.erase(std::unique(ends.begin(), ends.end(), [](Point3 u, Point3 w) { return same_location(u, w); }), ends.end());
    for (const Point3& l : ends) {
        if (!crossings_hold(p, l, under, stats)) return false;
    }
    return true;
}

bool VerticalBound::crossings_hold(Point3 p, Point3 l, std::span<const std::uint32_t> start, exact::PredicateStats& stats) {
    thread_local WalkMarks marks;
    thread_local std::vector<std::uint32_t> queue;
    marks.start(input_.faces.size(), input_.points.size());
    const std::uint32_t walk = marks.walk;
    const Point a = plan(p), b = plan(l);
    const double x0 = std::min(a.x, b.x), x1 = std::max(a.x, b.x), y0 = std::min(a.y, b.y), y1 = std::max(a.y, b.y);
    auto side = [&](std::uint32_t v) {
        if (marks.vertex[v] != walk) {
            marks.vertex[v] = walk;
            marks.side[v] = static_cast<std::int8_t>(exact::orient2d(a, b, plan(input_.points[v]), stats));
        }
        return marks.side[v];
    };
    // On the line through p and l: on the closed segment iff in its box.
    auto on_segment = [&](Point3 q) { return q.x >= x0 && q.x <= x1 && q.y >= y0 && q.y <= y1; };
    queue.assign(start.begin(), start.end());
    for (std::uint32_t f : start) marks.face[f] = walk;
    // A search (last in, first out) over the input faces meeting the closed segment, through the
    // edges meeting it (the faces a segment meets are connected that way: it goes from one to the
    // next through an edge, or through a vertex, all of whose edges meet it).
    while (!queue.empty()) {
        const std::uint32_t f = queue.back();
        queue.pop_back();
        const Face& c = input_.faces[f];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t iu = c[k], iw = c[(k + 1) % 3];
            const int su = side(iu), sw = side(iw);
            if (su * sw > 0) continue;  // the edge is on one side of the line
            const Point3 u = input_.points[iu], w = input_.points[iw];
            bool meets;
            if (su != 0 && sw != 0) {
                const int tp = exact::orient2d(plan(u), plan(w), a, stats), tl = exact::orient2d(plan(u), plan(w), b, stats);
                if (tp * tl > 0) continue;  // the segment is on one side of the edge's line
                meets = true;
                // A proper crossing (an end of either on the other is a vertex case), checked
                // from the face that has the edge from its lower vertex, or its only face.
                if (tp != 0 && tl != 0 && (iu < iw || neighbour_[f][k] == kNone) &&
                    !exact::crossing_gap_within(p, l, u, w, bound_, stats)) {
                    return false;
                }
            } else {
                meets = (su == 0 && on_segment(u)) || (sw == 0 && on_segment(w)) ||
                        (su == 0 && sw == 0 && std::max(u.x, w.x) >= x0 && std::min(u.x, w.x) <= x1 &&
                         std::max(u.y, w.y) >= y0 && std::min(u.y, w.y) <= y1);
            }
            const std::uint32_t g = neighbour_[f][k];
            if (meets && g != kNone && marks.face[g] != walk) {
                marks.face[g] = walk;
                queue.push_back(g);
            }
        }
    }
    return true;
}

void VerticalBound::collapsed(std::span<const std::uint32_t> before, std::span<const std::uint32_t> after) {
    for (std::uint32_t f : before) first_[f] = kNone;
    for (const auto& [v, i] : placed) {
        const std::uint32_t f = after[i];
        next_[v] = first_[f];
        first_[f] = v;
    }
    placed.clear();
}

void VerticalBound::renumber_faces(std::span<const std::uint32_t> kept) {
    for (std::size_t i = 0; i < kept.size(); ++i) first_[i] = first_[kept[i]];
    first_.resize(kept.size());
}

}  // namespace toposimp::mesh
