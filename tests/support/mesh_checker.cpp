#include "support/mesh_checker.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <map>
#include <sstream>

namespace toposimp::testing {
namespace {

struct Q3 {
    mpq_class x, y, z;
};

Q3 q3(Point3 p) { return {mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}; }
Q3 sub(const Q3& a, const Q3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Q3 crossq(const Q3& a, const Q3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
mpq_class dotq(const Q3& a, const Q3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
bool equal(const Q3& a, const Q3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
bool is_zero(const Q3& a) { return sgn(a.x) == 0 && sgn(a.y) == 0 && sgn(a.z) == 0; }
const mpq_class& coord(const Q3& p, int axis) { return axis == 0 ? p.x : (axis == 1 ? p.y : p.z); }

using Tri = std::array<Q3, 3>;

// Points of a closed set, described as a convex polygon (1 point, 2 = segment, or more).
using Poly = std::vector<Q3>;

// The part of triangle t on plane (n, d): n·x = d, as a point or a segment (t crosses the plane).
Poly cut_by_plane(const Tri& t, const Q3& n, const mpq_class& d) {
    Poly out;
    mpq_class s[3];
    for (int i = 0; i < 3; ++i) s[i] = dotq(n, t[i]) - d;
    for (int i = 0; i < 3; ++i) {
        if (sgn(s[i]) == 0) out.push_back(t[i]);
        const int j = (i + 1) % 3;
        if (sgn(s[i]) * sgn(s[j]) < 0) {
            const mpq_class w = s[i] / (s[i] - s[j]);
            out.push_back({t[i].x + w * (t[j].x - t[i].x), t[i].y + w * (t[j].y - t[i].y), t[i].z + w * (t[j].z - t[i].z)});
        }
    }
    return out;
}

// Clip a convex polygon (in the plane, projected dropping `axis`) by the closed half-plane on the
// inner side of edge p→q of a polygon with orientation `turn`.
int orient_drop(const Q3& a, const Q3& b, const Q3& c, int axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const mpq_class det = (coord(b, u) - coord(a, u)) * (coord(c, v) - coord(a, v)) -
                          (coord(b, v) - coord(a, v)) * (coord(c, u) - coord(a, u));
    return sgn(det);
}

Poly clip(const Poly& poly, const Q3& p, const Q3& q, int turn, int axis) {
    Poly out;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const Q3& a = poly[i];
        const Q3& b = poly[(i + 1) % n];
        const int sa = orient_drop(p, q, a, axis) * turn, sb = orient_drop(p, q, b, axis) * turn;
        if (sa >= 0) out.push_back(a);
        if ((sa > 0 && sb < 0) || (sa < 0 && sb > 0)) {
            // Intersection of segment ab with line pq (in the projection, lifted linearly).
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            auto side = [&](const Q3& x) -> mpq_class {
                return (coord(q, u) - coord(p, u)) * (coord(x, v) - coord(p, v)) -
                       (coord(q, v) - coord(p, v)) * (coord(x, u) - coord(p, u));
            };
            const mpq_class da = side(a), db = side(b);
            const mpq_class w = da / (da - db);
            out.push_back({a.x + w * (b.x - a.x), a.y + w * (b.y - a.y), a.z + w * (b.z - a.z)});
        }
    }
    // Remove repeated points.
    Poly clean;
    for (const Q3& x : out) {
        if (clean.empty() || !equal(clean.back(), x)) clean.push_back(x);
    }
    while (clean.size() > 1 && equal(clean.front(), clean.back())) clean.pop_back();
    return clean;
}

// Is x on the closed segment ab (all exact)?
bool on_segment(const Q3& x, const Q3& a, const Q3& b) {
    if (!is_zero(crossq(sub(b, a), sub(x, a)))) return false;
    return sgn(dotq(sub(x, a), sub(x, b))) <= 0;
}

// Is every point of the intersection allowed: equal to a shared corner, or on the segment
// between the two shared corners?
bool allowed(const Poly& meet, const std::vector<Q3>& shared) {
    for (const Q3& x : meet) {
        if (shared.size() == 2) {
            if (!on_segment(x, shared[0], shared[1])) return false;
        } else if (shared.size() == 1) {
            if (!equal(x, shared[0])) return false;
        } else {
            return false;
        }
    }
    return true;
}

// The intersection of two closed triangles (non-degenerate), as points that span it.
Poly intersection(const Tri& t, const Tri& u) {
    const Q3 n1 = crossq(sub(t[1], t[0]), sub(t[2], t[0]));
    const Q3 n2 = crossq(sub(u[1], u[0]), sub(u[2], u[0]));
    const mpq_class d1 = dotq(n1, t[0]), d2 = dotq(n2, u[0]);
    const Q3 line = crossq(n1, n2);
    if (is_zero(line)) {
        if (dotq(n1, u[0]) != d1) return {};  // parallel planes
        // Coplanar: clip u by t's three edges (projection dropping the normal's largest axis).
        int axis = 0;
        for (int k = 1; k < 3; ++k) {
            if (abs(coord(n1, k)) > abs(coord(n1, axis))) axis = k;
        }
        const int turn = orient_drop(t[0], t[1], t[2], axis);
        Poly poly(u.begin(), u.end());
        if (orient_drop(u[0], u[1], u[2], axis) != turn) std::reverse(poly.begin(), poly.end());
        for (int i = 0; i < 3 && !poly.empty(); ++i) poly = clip(poly, t[i], t[(i + 1) % 3], turn, axis);
        return poly;
    }
    const Poly a = cut_by_plane(t, n2, d2), b = cut_by_plane(u, n1, d1);
    if (a.empty() || b.empty()) return {};
    // Both lie on the planes' common line: compare them by a parameter along it.
    auto param = [&](const Q3& x) { return dotq(line, x); };
    mpq_class alo = param(a[0]), ahi = alo, blo = param(b[0]), bhi = blo;
    Q3 alo_p = a[0], ahi_p = a[0], blo_p = b[0], bhi_p = b[0];
    for (const Q3& x : a) {
        const mpq_class s = param(x);
        if (s < alo) alo = s, alo_p = x;
        if (s > ahi) ahi = s, ahi_p = x;
    }
    for (const Q3& x : b) {
        const mpq_class s = param(x);
        if (s < blo) blo = s, blo_p = x;
        if (s > bhi) bhi = s, bhi_p = x;
    }
    if (ahi < blo || bhi < alo) return {};
    const Q3 lo = alo > blo ? alo_p : blo_p;
    const Q3 hi = ahi < bhi ? ahi_p : bhi_p;
    return {lo, hi};
}

bool collinear(const Tri& t) { return is_zero(crossq(sub(t[1], t[0]), sub(t[2], t[0]))); }

}  // namespace

MeshDefects find_defects(const mesh::Mesh& mesh) {
    MeshDefects defects;
    auto note = [&](const std::string& what) {
        if (defects.first.empty()) defects.first = what;
    };
    const std::size_t m = mesh.faces.size();
    std::vector<Tri> tris(m);
    std::vector<Box3> boxes(m);
    std::vector<bool> usable(m, true);
    for (std::size_t f = 0; f < m; ++f) {
        const mesh::Face& c = mesh.faces[f];
        for (int k = 0; k < 3; ++k) tris[f][k] = q3(mesh.points[c[k]]);
        boxes[f] = triangle_box(mesh.points[c[0]], mesh.points[c[1]], mesh.points[c[2]]);
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || collinear(tris[f])) {
            ++defects.degenerate_faces;
            usable[f] = false;
            note("degenerate face " + std::to_string(f));
        }
    }
    // Edges and duplicate faces.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<int>> edges;  // (lo, hi) -> directions
    std::map<std::array<std::uint32_t, 3>, int> sets;
    for (std::size_t f = 0; f < m; ++f) {
        const mesh::Face& c = mesh.faces[f];
        std::array<std::uint32_t, 3> key = c;
        std::sort(key.begin(), key.end());
        if (++sets[key] == 2) {
            ++defects.duplicate_faces;
            note("duplicate face " + std::to_string(f));
        }
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = c[k], b = c[(k + 1) % 3];
            edges[{std::min(a, b), std::max(a, b)}].push_back(a < b ? 1 : -1);
        }
    }
    for (const auto& [edge, uses] : edges) {
        if (uses.size() > 2) {
            ++defects.non_manifold_edges;
            note("non-manifold edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second));
        } else if (uses.size() == 2 && uses[0] == uses[1]) {
            ++defects.inconsistent_edges;
            note("inconsistently oriented edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second));
        }
    }
    // Vertices: the faces around each must form one fan, every two joined through a chain of
    // faces that share an edge at the vertex; two fans meeting in one vertex (two border loops
    // pinched together, two surfaces touching at a point) are not a manifold there.
    {
        std::vector<std::vector<std::uint32_t>> around(mesh.points.size());
        for (std::size_t f = 0; f < m; ++f) {
            for (std::uint32_t v : mesh.faces[f]) around[v].push_back(static_cast<std::uint32_t>(f));
        }
        for (std::uint32_t v = 0; v < around.size(); ++v) {
            const std::vector<std::uint32_t>& faces = around[v];
            if (faces.size() < 2) continue;
            std::vector<std::size_t> root(faces.size());
            for (std::size_t i = 0; i < root.size(); ++i) root[i] = i;
            auto find = [&](std::size_t i) {
                while (root[i] != i) i = root[i] = root[root[i]];
                return i;
            };
            // Faces at v sharing another corner w share the edge vw.
            std::map<std::uint32_t, std::size_t> first_with;
            for (std::size_t i = 0; i < faces.size(); ++i) {
                for (std::uint32_t w : mesh.faces[faces[i]]) {
                    if (w == v) continue;
                    const auto [at, added] = first_with.emplace(w, i);
                    if (!added) root[find(i)] = find(at->second);
                }
            }
            std::size_t fans = 0;
            for (std::size_t i = 0; i < faces.size(); ++i) fans += find(i) == i;
            if (fans > 1) {
                ++defects.non_manifold_vertices;
                note("non-manifold vertex " + std::to_string(v) + " (" + std::to_string(fans) + " fans)");
            }
        }
    }
    // Every pair of faces with overlapping boxes.
    std::vector<std::size_t> order(m);
    for (std::size_t f = 0; f < m; ++f) order[f] = f;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return boxes[a].lo.x < boxes[b].lo.x; });
    for (std::size_t i = 0; i < m; ++i) {
        const std::size_t f = order[i];
        if (!usable[f]) continue;
        for (std::size_t j = i + 1; j < m && boxes[order[j]].lo.x <= boxes[f].hi.x; ++j) {
            const std::size_t g = order[j];
            if (!usable[g] || !boxes[f].overlaps(boxes[g])) continue;
            std::vector<Q3> shared;
            for (const Q3& x : tris[f]) {
                for (const Q3& y : tris[g]) {
                    if (equal(x, y)) shared.push_back(x);
                }
            }
            const Poly meet = intersection(tris[f], tris[g]);
            if (meet.empty() || allowed(meet, shared)) continue;
            ++defects.intersecting_pairs;
            std::ostringstream what;
            what << "faces " << f << " and " << g << " intersect (" << shared.size() << " shared corners)";
            note(what.str());
        }
    }
    return defects;
}

std::size_t count_map_plane_folds(const mesh::Mesh& mesh, int turn) {
    std::size_t folds = 0;
    for (const mesh::Face& c : mesh.faces) {
        const Tri t{q3(mesh.points[c[0]]), q3(mesh.points[c[1]]), q3(mesh.points[c[2]])};
        if (orient_drop(t[0], t[1], t[2], 2) != turn) ++folds;
    }
    return folds;
}

int volume_sign(const mesh::Mesh& mesh) {
    mpq_class volume = 0;
    for (const mesh::Face& c : mesh.faces) {
        const Q3 a = q3(mesh.points[c[0]]), b = q3(mesh.points[c[1]]), d = q3(mesh.points[c[2]]);
        volume += dotq(a, crossq(b, d));
    }
    return sgn(volume);
}

bool within_vertical_gap(const mesh::Mesh& input, const mesh::Mesh& output, double bound, double* largest) {
    // Every output face clipped (in the x–y plane) to every input face whose box meets it: on
    // the piece, both surfaces are planes, so the gap is largest at the piece's corners. The
    // clipped corners keep the output face's height (clip interpolates along the polygon's
    // edges); the input face's height there is solved from its plane, n·x = d.
    struct Box2 {
        double x0, y0, x1, y1;
    };
    auto box_of = [](const mesh::Mesh& m, const mesh::Face& c) {
        Box2 b{m.points[c[0]].x, m.points[c[0]].y, m.points[c[0]].x, m.points[c[0]].y};
        for (std::uint32_t w : c) {
            b.x0 = std::min(b.x0, m.points[w].x), b.y0 = std::min(b.y0, m.points[w].y);
            b.x1 = std::max(b.x1, m.points[w].x), b.y1 = std::max(b.y1, m.points[w].y);
        }
        return b;
    };
    std::vector<Box2> input_boxes;
    for (const mesh::Face& c : input.faces) input_boxes.push_back(box_of(input, c));
    const mpq_class limit(bound);
    mpq_class most = 0;
    for (const mesh::Face& oc : output.faces) {
        const Box2 ob = box_of(output, oc);
        const Poly t{q3(output.points[oc[0]]), q3(output.points[oc[1]]), q3(output.points[oc[2]])};
        for (std::size_t f = 0; f < input.faces.size(); ++f) {
            const Box2& ib = input_boxes[f];
            if (ib.x0 > ob.x1 || ob.x0 > ib.x1 || ib.y0 > ob.y1 || ob.y0 > ib.y1) continue;
            const mesh::Face& ic = input.faces[f];
            const Tri u{q3(input.points[ic[0]]), q3(input.points[ic[1]]), q3(input.points[ic[2]])};
            const int turn = orient_drop(u[0], u[1], u[2], 2);
            if (turn == 0) continue;
            Poly piece = t;
            for (int k = 0; k < 3 && !piece.empty(); ++k) piece = clip(piece, u[k], u[(k + 1) % 3], turn, 2);
            const Q3 n = crossq(sub(u[1], u[0]), sub(u[2], u[0]));  // n.z != 0: not vertical
            const mpq_class d = dotq(n, u[0]);
            for (const Q3& x : piece) {
                const mpq_class z = (d - n.x * x.x - n.y * x.y) / n.z;
                mpq_class gap = x.z - z;
                if (sgn(gap) < 0) gap = -gap;
                if (gap > most) most = gap;
            }
        }
    }
    if (largest != nullptr) *largest = most.get_d();
    return most <= limit;
}

}  // namespace toposimp::testing
