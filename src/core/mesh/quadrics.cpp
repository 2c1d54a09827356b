// Garland–Heckbert quadrics (Garland & Heckbert 1997) per vertex, with heavily weighted planes
// along the border (§6), and the placement of a merged vertex that minimises their sum.
#include "core/mesh/simplifier.hpp"

#include <omp.h>

namespace toposimp::mesh::detail {

void Simplifier::build_quadrics() {
    // Each face's plane once (unit normal, offset, and the normal's length: twice the area).
    struct Plane {
        double a, b, c, d, length;
    };
    const auto m = static_cast<std::int64_t>(face_.size());
    const auto n = static_cast<std::int64_t>(pos_.size());
    double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, lo_z = lo_x;
    double hi_x = -lo_x, hi_y = -lo_x, hi_z = -lo_x;
#pragma omp parallel for schedule(static) reduction(min : lo_x, lo_y, lo_z) reduction(max : hi_x, hi_y, hi_z) num_threads(threads_)
    for (std::int64_t i = 0; i < n; ++i) {
        const Point3 p = pos_[static_cast<std::size_t>(i)];
        lo_x = std::min(lo_x, p.x), lo_y = std::min(lo_y, p.y), lo_z = std::min(lo_z, p.z);
        hi_x = std::max(hi_x, p.x), hi_y = std::max(hi_y, p.y), hi_z = std::max(hi_z, p.z);
    }
    if (n > 0) frame_ = frame_around({{lo_x, lo_y, lo_z}, {hi_x, hi_y, hi_z}});
    // Left uninitialised (written once below, in parallel): zeroing and faulting in ~40 bytes per
    // face serially first took as long as the loop.
    const std::unique_ptr<Plane[]> planes(new Plane[face_.size()]);
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (std::int64_t i = 0; i < m; ++i) {
        const Face& f = face_[static_cast<std::size_t>(i)];
        const Point3 normal = cross(span(pos_[f[0]], pos_[f[1]]), span(pos_[f[0]], pos_[f[2]]));
        const double length = norm(normal);
        Plane& plane = planes[static_cast<std::size_t>(i)];
        plane.length = length;
        if (!(length > 0)) continue;
        const Point3 unit{normal.x / length, normal.y / length, normal.z / length};
        plane = {unit.x, unit.y, unit.z, -dot(unit, local(pos_[f[0]])), length};
    }
    // Each vertex sums the planes of its faces in list order: deterministic for any thread count.
    // Its neighbours are counted as it goes, by the faces it shares with each and the way those
    // turn (w after v, or before it): one face, a border edge; more than two, a non-manifold edge.
    quadric_ = std::make_unique_for_overwrite<Quadric[]>(pos_.size());  // each written once below
    const bool want_border = options_.terrain && !options_.height_field;
    const auto parts = static_cast<std::size_t>(threads_);
    std::vector<std::vector<DirectedEdge>> border_parts(parts);
    std::vector<DirectedEdge> first_bad(parts, {kNone, kNone});  // each thread's least non-manifold edge
#pragma omp parallel num_threads(threads_)
    {
        // (neighbour, how many of v's faces have it, of those how many have it after v): a vertex
        // has a few, a scan, no sort.
        struct Seen {
            std::uint32_t vertex, count, after;
        };
        std::vector<Seen> seen;
        const auto me = static_cast<std::size_t>(omp_get_thread_num());
        auto meet = [&seen](std::uint32_t w, bool after) {
            for (Seen& s : seen) {
                if (s.vertex == w) {
                    ++s.count;
                    s.after += after;
                    return;
                }
            }
            seen.push_back({w, 1, after});
        };
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            const auto v = static_cast<std::uint32_t>(i);
            seen.clear();
            Quadric q{};
            for (std::uint32_t c = head_[v]; c != kNone; c = next_[c]) {
                const Face& f = face_[c / 3];
                const auto k = c % 3;
                meet(f[(k + 1) % 3], true);
                meet(f[(k + 2) % 3], false);
                const Plane& plane = planes[c / 3];
                if (!(plane.length > 0)) continue;
                const double area = 0.5 * plane.length;
                q.add_plane(plane.a, plane.b, plane.c, plane.d, area);
                q.area += area;
            }
            quadric_[v] = q;
            for (const Seen& s : seen) {
                if (s.count == 1) flags_[v] |= kBoundary;
                if (s.count > 2 && s.vertex > v && DirectedEdge{v, s.vertex} < first_bad[me]) first_bad[me] = {v, s.vertex};
                // A face has v → w and none w → v: once per such face.
                if (want_border && s.after == s.count) border_parts[me].insert(border_parts[me].end(), s.after, {v, s.vertex});
            }
        }
    }
    const DirectedEdge bad = *std::min_element(first_bad.begin(), first_bad.end());
    if (bad.first != kNone) {
        NonManifoldEdge edge{bad.first, bad.second, {}};
        for (std::uint32_t c = head_[bad.first]; c != kNone && edge.faces.size() < 4; c = next_[c]) {
            const Face& f = face_[c / 3];
            if (f[0] == bad.second || f[1] == bad.second || f[2] == bad.second) edge.faces.push_back(c / 3);
        }
        non_manifold_ = std::move(edge);
    }
    border_.clear();
    for (const auto& part : border_parts) border_.insert(border_.end(), part.begin(), part.end());
    std::sort(border_.begin(), border_.end());
}

void Simplifier::add_border_planes() {
    // Each border vertex finds its border edges (a neighbour met in only one of its faces) and
    // unless locked adds for each a plane through the edge perpendicular to its face, weighted
    // heavily (Garland & Heckbert §6), in neighbour order; computed from the edge's lower id so
    // both ends add the same quadric.
    const auto n = static_cast<std::int64_t>(pos_.size());
#pragma omp parallel num_threads(threads_)
    {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> seen;     // (neighbour, face), with repeats
        std::vector<std::pair<std::uint32_t, std::uint32_t>> borders;  // (neighbour, face)
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            const auto v = static_cast<std::uint32_t>(i);
            if ((flags_[v] & kBoundary) == 0) continue;
            if (lock_) {
                flags_[v] |= kLocked;
                continue;
            }
            seen.clear();
            for (std::uint32_t c = head_[v]; c != kNone; c = next_[c]) {
                const Face& f = face_[c / 3];
                seen.emplace_back(f[(c % 3 + 1) % 3], c / 3);
                seen.emplace_back(f[(c % 3 + 2) % 3], c / 3);
            }
            borders.clear();
            for (const auto& [w, face] : seen) {
                const auto times = std::count_if(seen.begin(), seen.end(), [neighbour = w](const auto& s) { return s.first == neighbour; });
                if (times == 1) borders.emplace_back(w, face);
            }
            std::sort(borders.begin(), borders.end());
            Quadric& q = quadric_[v];
            for (const auto& [w, face] : borders) {
                const auto lo = std::min(v, w), hi = std::max(v, w);
                const Face& f = face_[face];
                const Point3 normal = cross(span(pos_[f[0]], pos_[f[1]]), span(pos_[f[0]], pos_[f[2]]));
                const Point3 edge = span(pos_[lo], pos_[hi]);
                const Point3 side = cross(edge, normal);
                const double length = norm(side);
                if (length > 0) {
                    const Point3 unit{side.x / length, side.y / length, side.z / length};
                    Quadric border{};
                    border.add_plane(unit.x, unit.y, unit.z, -dot(unit, local(pos_[lo])), 1000.0 * dot(edge, edge));
                    q += border;
                }
            }
        }
    }
}

bool Simplifier::place(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, Placement& out) const {
    const bool locked_a = (flags_[a] & kLocked) != 0, locked_b = (flags_[b] & kLocked) != 0;
    if (locked_a && locked_b) return false;
    const Quadric q = quadric_[a] + quadric_[b];
    if (locked_a || locked_b) {
        out.p = locked_a ? pos_[a] : pos_[b];
        out.cost = q(local(out.p));
        out.bound = false;
        return true;
    }
    // Optimal placement: solve the 3×3 system ∇(vᵀQv) = 0 (v about frame_) by Cramer's rule when it
    // is well conditioned and its solution stays near the edge and inside the block.
    const double m00 = q.xx, m01 = q.xy, m02 = q.xz, m11 = q.yy, m12 = q.yz, m22 = q.zz;
    const double r0 = -q.xw, r1 = -q.yw, r2 = -q.zw;
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11;
    const double det = m00 * c00 + m01 * c01 + m02 * c02;
    const double scale = std::max({std::fabs(m00), std::fabs(m11), std::fabs(m22)});
    const Point3 pa = pos_[a], pb = pos_[b];
    // (Halves first: no overflow; the same double as half the sum otherwise.)
    const Point3 mid{0.5 * pa.x + 0.5 * pb.x, 0.5 * pa.y + 0.5 * pb.y, 0.5 * pa.z + 0.5 * pb.z};
    bool bound = false;
    if (std::fabs(det) > 1e-10 * scale * scale * scale && std::isfinite(det)) {
        const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12, c22 = m00 * m11 - m01 * m01;
        const Point3 p{(c00 * r0 + c01 * r1 + c02 * r2) / det * frame_.unscale + frame_.centre.x,
                       (c01 * r0 + c11 * r1 + c12 * r2) / det * frame_.unscale + frame_.centre.y,
                       (c02 * r0 + c12 * r1 + c22 * r2) / det * frame_.unscale + frame_.centre.z};
        const double reach = norm(minus(pb, pa));  // (infinite if the difference overflows: no limit)
        const bool near = std::fabs(p.x - mid.x) <= reach && std::fabs(p.y - mid.y) <= reach && std::fabs(p.z - mid.z) <= reach;
        if (near && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) {
            if (in_block(p, level, block)) {
                out = {p, q(local(p)), false};
                return true;
            }
            bound = true;
        }
    }
    // Otherwise the best of the two ends and the midpoint.
    out = {pa, q(local(pa)), false};
    const double cost_b = q(local(pb));
    if (cost_b < out.cost) out = {pb, cost_b, false};
    const double cost_mid = q(local(mid));
    if (cost_mid < out.cost) {
        if (in_block(mid, level, block)) {
            out = {mid, cost_mid, false};
        } else {
            bound = true;
        }
    }
    out.bound = bound;
    return true;
}

double Simplifier::error_of(const Placement& placement, std::uint32_t a, std::uint32_t b) const {
    const double area = quadric_[a].area + quadric_[b].area;
    // (In frame units, so back to coordinate units.)
    return area > 0 ? std::sqrt(std::max(placement.cost, 0.0) / area) * frame_.unscale : 0.0;
}

}  // namespace toposimp::mesh::detail
