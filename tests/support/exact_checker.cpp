#include "support/exact_checker.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <sstream>

namespace toposimp::testing {

int exact_orient(Point a, Point b, Point c) {
    const mpq_class ax(a.x), ay(a.y), bx(b.x), by(b.y), cx(c.x), cy(c.y);
    return sgn((bx - ax) * (cy - ay) - (by - ay) * (cx - ax));
}

namespace {

bool same(Point a, Point b) { return a.x == b.x && a.y == b.y; }

bool in_box(Point p, Point a, Point b) {
    return p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) && p.y >= std::min(a.y, b.y) &&
           p.y <= std::max(a.y, b.y);
}

// Is p on the closed segment ab?
bool on_segment(Point p, Point a, Point b) { return in_box(p, a, b) && exact_orient(a, b, p) == 0; }

bool boxes_meet(Point p, Point q, Point r, Point s) {
    return std::max(std::min(p.x, q.x), std::min(r.x, s.x)) <= std::min(std::max(p.x, q.x), std::max(r.x, s.x)) &&
           std::max(std::min(p.y, q.y), std::min(r.y, s.y)) <= std::min(std::max(p.y, q.y), std::max(r.y, s.y));
}

bool endpoint_of(Point x, Point a, Point b) { return same(x, a) || same(x, b); }

std::string text(Point p) {
    std::ostringstream out;
    out.precision(17);
    out << '(' << p.x << ", " << p.y << ')';
    return out.str();
}

}  // namespace

bool improper_contact(Point p, Point q, Point r, Point s) {
    if (!boxes_meet(p, q, r, s)) return false;
    // Every point of pq ∩ rs must be an endpoint location of both segments.
    const int o1 = exact_orient(p, q, r), o2 = exact_orient(p, q, s);
    const int o3 = exact_orient(r, s, p), o4 = exact_orient(r, s, q);
    const bool pq_point = same(p, q), rs_point = same(r, s);
    if (!pq_point && !rs_point && o1 * o2 < 0 && o3 * o4 < 0) return true;  // proper crossing
    if (!pq_point && !rs_point && o1 == 0 && o2 == 0) {
        // Collinear: the overlap is an interval; project on the axis along which pq extends.
        const bool along_x = p.x != q.x;
        auto coordinate = [&](Point u) { return along_x ? u.x : u.y; };
        const double lo = std::max(std::min(coordinate(p), coordinate(q)), std::min(coordinate(r), coordinate(s)));
        const double hi = std::min(std::max(coordinate(p), coordinate(q)), std::max(coordinate(r), coordinate(s)));
        if (lo < hi) return true;  // overlap of positive length
        if (lo > hi) return false;
    }
    // Touching: each endpoint lying on the other segment must be an endpoint of it too.
    for (const Point x : {r, s}) {
        if (on_segment(x, p, q) && !endpoint_of(x, p, q)) return true;
    }
    for (const Point x : {p, q}) {
        if (on_segment(x, r, s) && !endpoint_of(x, r, s)) return true;
    }
    return false;
}

std::string CheckReport::summary() const {
    std::string out = std::to_string(violations.size()) + " violation(s)";
    for (std::size_t i = 0; i < violations.size() && i < 5; ++i) out += "\n  " + violations[i];
    return out;
}

namespace {

struct Segment {
    Point a, b;
    std::uint32_t chain;
    bool original;  // joins two vertices that were consecutive in the input
};

std::vector<Segment> segments_of(const map::MapData& map, const std::vector<std::uint8_t>& kept) {
    std::vector<Segment> segments;
    for (std::uint32_t c = 0; c < map.chains.size(); ++c) {
        std::uint32_t last = map.chains[c].first;
        for (std::uint32_t v = map.chains[c].first + 1; v <= map.chains[c].last; ++v) {
            if (!kept[v]) continue;
            segments.push_back({map.vertices[last], map.vertices[v], c, v == last + 1});
            last = v;
        }
    }
    return segments;
}

void check_contacts(const std::vector<Segment>& segments, bool allow_input_contacts, CheckReport& report) {
    std::vector<std::size_t> order(segments.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    auto min_x = [&](std::size_t i) { return std::min(segments[i].a.x, segments[i].b.x); };
    auto max_x = [&](std::size_t i) { return std::max(segments[i].a.x, segments[i].b.x); };
    std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return min_x(i) < min_x(j); });
    for (std::size_t i = 0; i < order.size(); ++i) {
        const Segment& s = segments[order[i]];
        for (std::size_t j = i + 1; j < order.size() && min_x(order[j]) <= max_x(order[i]); ++j) {
            const Segment& t = segments[order[j]];
            // Two input segments met the same way in the input: not a new contact.
            if (s.original && t.original && allow_input_contacts) continue;
            if (improper_contact(s.a, s.b, t.a, t.b)) {
                report.violations.push_back("segments " + text(s.a) + "-" + text(s.b) + " (chain " +
                                            std::to_string(s.chain) + ") and " + text(t.a) + "-" + text(t.b) +
                                            " (chain " + std::to_string(t.chain) + ") meet improperly");
            }
        }
    }
}

// Winding number and crossing parity of p around the closed polygon `ring` (p not on it).
bool inside_polygon(Point p, const std::vector<Point>& ring) {
    int winding = 0;
    bool odd = false;
    for (std::size_t i = 0; i < ring.size(); ++i) {
        const Point a = ring[i], b = ring[(i + 1) % ring.size()];
        // Half-open rule on y, exact comparisons and exact orientation.
        if ((a.y <= p.y) != (b.y <= p.y)) {
            const int side = exact_orient(a, b, p);
            if (b.y > a.y ? side > 0 : side < 0) odd = !odd;
            if (a.y <= p.y && side > 0) ++winding;
            if (a.y > p.y && side < 0) --winding;
        }
    }
    return winding != 0 || odd;
}

}  // namespace

CheckReport check_planar(const map::MapData& input) {
    CheckReport report;
    check_contacts(segments_of(input, std::vector<std::uint8_t>(input.vertices.size(), 1)), false, report);
    return report;
}

CheckReport check_simplification(const map::MapData& input, const std::vector<std::uint8_t>& kept) {
    CheckReport report;
    std::vector<Point> obstacles = input.control_points;
    for (std::uint32_t v = 0; v < input.vertices.size(); ++v) {
        if (kept[v]) obstacles.push_back(input.vertices[v]);
    }
    for (std::uint32_t c = 0; c < input.chains.size(); ++c) {
        const map::Chain chain = input.chains[c];
        if (!kept[chain.first] || !kept[chain.last]) {
            report.violations.push_back("chain " + std::to_string(c) + " lost an endpoint");
            continue;
        }
        std::uint32_t start = chain.first;
        for (std::uint32_t v = chain.first + 1; v <= chain.last; ++v) {
            if (!kept[v]) continue;
            if (v > start + 1) {
                // The detour: input vertices start..v, closed by the new segment v→start.
                std::vector<Point> detour(input.vertices.begin() + start, input.vertices.begin() + v + 1);
                const Point a = detour.front(), b = detour.back();
                Point lo = a, hi = a;
                for (const Point q : detour) {
                    lo = {std::min(lo.x, q.x), std::min(lo.y, q.y)};
                    hi = {std::max(hi.x, q.x), std::max(hi.y, q.y)};
                }
                for (const Point q : obstacles) {
                    if (!in_box(q, lo, hi) || same(q, a) || same(q, b)) continue;
                    bool on_boundary = false;
                    for (std::size_t k = 0; k < detour.size() && !on_boundary; ++k) {
                        on_boundary = on_segment(q, detour[k], detour[(k + 1) % detour.size()]);
                    }
                    if (on_boundary || inside_polygon(q, detour)) {
                        report.violations.push_back("chain " + std::to_string(c) + ": detour " + text(a) + "…" +
                                                    text(b) + " holds " + text(q) +
                                                    (on_boundary ? " on its boundary" : " inside"));
                    }
                }
            }
            start = v;
        }
    }
    check_contacts(segments_of(input, kept), true, report);
    return report;
}

std::vector<std::uint64_t> crossings_between_chains(const map::MapData& map, const std::vector<std::uint8_t>& kept) {
    const std::size_t n = map.chains.size();
    std::vector<std::uint64_t> counts(n * n, 0);
    const std::vector<Segment> segments = segments_of(map, kept);
    for (std::size_t i = 0; i < segments.size(); ++i) {
        for (std::size_t j = i + 1; j < segments.size(); ++j) {
            const Segment& s = segments[i];
            const Segment& t = segments[j];
            if (s.chain == t.chain || !boxes_meet(s.a, s.b, t.a, t.b)) continue;
            if (exact_orient(s.a, s.b, t.a) * exact_orient(s.a, s.b, t.b) < 0 &&
                exact_orient(t.a, t.b, s.a) * exact_orient(t.a, t.b, s.b) < 0) {
                ++counts[std::min(s.chain, t.chain) * n + std::max(s.chain, t.chain)];
            }
        }
    }
    return counts;
}

}  // namespace toposimp::testing
