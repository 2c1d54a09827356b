#include "core/exact/segments.hpp"

#include <algorithm>

namespace toposimp::exact {
namespace {

struct Orienter {
    Arithmetic arithmetic;
    PredicateStats& stats;

    int operator()(Point a, Point b, Point c) const {
        switch (arithmetic) {
            case Arithmetic::rational: return orient2d_gmp(a, b, c);
            case Arithmetic::floating: {
                const double det = (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x);
                return (det > 0) - (det < 0);
            }
            case Arithmetic::exact: break;
        }
        return orient2d(a, b, c, stats);
    }
};

bool in_box(Point p, Point a, Point b) {
    return p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) && p.y >= std::min(a.y, b.y) &&
           p.y <= std::max(a.y, b.y);
}

bool endpoint_of(Point x, Point a, Point b) { return same_location(x, a) || same_location(x, b); }

}  // namespace

int orientation(Point a, Point b, Point c, Arithmetic arithmetic, PredicateStats& stats) { return Orienter{arithmetic, stats}(a, b, c); }

bool improper_contact(Point p, Point q, Point r, Point s, Arithmetic arithmetic, PredicateStats& stats) {
    // Disjoint boxes: no contact (exact comparisons).
    if (std::max(p.x, q.x) < std::min(r.x, s.x) || std::max(r.x, s.x) < std::min(p.x, q.x) ||
        std::max(p.y, q.y) < std::min(r.y, s.y) || std::max(r.y, s.y) < std::min(p.y, q.y)) {
        return false;
    }
    const Orienter orient{arithmetic, stats};
    const bool pq_point = same_location(p, q), rs_point = same_location(r, s);
    const int o1 = pq_point ? 0 : orient(p, q, r), o2 = pq_point ? 0 : orient(p, q, s);
    int o3 = 0, o4 = 0;  // orientations of p and q against rs, once computed
    bool rs_known = rs_point;
    if (!pq_point && !rs_point) {
        if (o1 * o2 > 0) return false;  // r and s strictly on one side of pq
        o3 = orient(r, s, p);
        o4 = orient(r, s, q);
        rs_known = true;
        if (o3 * o4 > 0) return false;
        if (o1 * o2 < 0 && o3 * o4 < 0) return true;  // proper crossing
        if (o1 == 0 && o2 == 0) {
            // Collinear: the contact is an interval along the axis on which pq extends.
            const bool along_x = p.x != q.x;
            auto at = [&](Point u) { return along_x ? u.x : u.y; };
            const double lo = std::max(std::min(at(p), at(q)), std::min(at(r), at(s)));
            const double hi = std::min(std::max(at(p), at(q)), std::max(at(r), at(s)));
            if (lo < hi) return true;  // overlap of positive length
            if (lo > hi) return false;
        }
    }
    // Touching: an endpoint lying on the other segment must be an endpoint of it as well.
    auto on_segment = [&](Point x, Point a, Point b, int side) {
        return in_box(x, a, b) && (same_location(a, b) ? same_location(x, a) : side == 0);
    };
    if (on_segment(r, p, q, o1) && !endpoint_of(r, p, q)) return true;
    if (on_segment(s, p, q, o2) && !endpoint_of(s, p, q)) return true;
    if (!rs_known) {
        o3 = orient(r, s, p);
        o4 = orient(r, s, q);
    }
    if (on_segment(p, r, s, o3) && !endpoint_of(p, r, s)) return true;
    if (on_segment(q, r, s, o4) && !endpoint_of(q, r, s)) return true;
    return false;
}

bool proper_crossing(Point p, Point q, Point r, Point s, Arithmetic arithmetic, PredicateStats& stats) {
    const Orienter orient{arithmetic, stats};
    return orient(p, q, r) * orient(p, q, s) < 0 && orient(r, s, p) * orient(r, s, q) < 0;
}

}  // namespace toposimp::exact
