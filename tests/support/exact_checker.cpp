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

namespace toposimp::testing {
namespace {

int ring_sign(const std::vector<Point>& ring) {
    mpq_class twice_area = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        twice_area += mpq_class(ring[i].x) * mpq_class(ring[i + 1].y) - mpq_class(ring[i + 1].x) * mpq_class(ring[i].y);
    }
    return sgn(twice_area);
}

// 2 inside, 1 on, 0 outside the closed ring.
int where_in_ring(Point p, const std::vector<Point>& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        if (on_segment(p, ring[i], ring[i + 1])) return 1;
    }
    return inside_polygon(p, ring) ? 2 : 0;
}

bool on_polyline(Point p, const std::vector<Point>& line) {
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
        if (on_segment(p, line[i], line[i + 1])) return true;
    }
    return line.size() == 1 && same(p, line.front());
}

// Per pair of chains (i·n + j, i < j): proper crossings and other improper contacts.
std::pair<std::vector<std::uint64_t>, std::vector<std::uint64_t>> contacts_between_chains(const std::vector<std::vector<Point>>& chains) {
    const std::size_t n = chains.size();
    std::vector<std::uint64_t> crossings(n * n, 0), touchings(n * n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i; j < n; ++j) {
            for (std::size_t a = 0; a + 1 < chains[i].size(); ++a) {
                for (std::size_t b = i == j ? a + 2 : 0; b + 1 < chains[j].size(); ++b) {
                    const Point p = chains[i][a], q = chains[i][a + 1], r = chains[j][b], s = chains[j][b + 1];
                    if (!improper_contact(p, q, r, s)) continue;
                    const bool crossing = exact_orient(p, q, r) * exact_orient(p, q, s) < 0 && exact_orient(r, s, p) * exact_orient(r, s, q) < 0;
                    ++(crossing ? crossings : touchings)[i * n + j];
                }
            }
        }
    }
    return {crossings, touchings};
}

}  // namespace

CheckReport check_rounded(const map::MapData& input, const std::vector<std::uint8_t>& kept, const std::vector<Point>& at,
                          const std::function<bool(Point)>& on_grid) {
    CheckReport report;
    std::vector<std::vector<Point>> before, after;
    for (std::uint32_t c = 0; c < input.chains.size(); ++c) {
        const map::Chain chain = input.chains[c];
        before.emplace_back(input.vertices.begin() + chain.first, input.vertices.begin() + chain.last + 1);
        after.emplace_back();
        if (!kept[chain.first] || !kept[chain.last]) report.violations.push_back("chain " + std::to_string(c) + " lost an endpoint");
        for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
            if (!kept[v]) continue;
            after.back().push_back(at[v]);
            if (!on_grid(at[v]) && !same(at[v], input.vertices[v])) {
                report.violations.push_back("vertex " + std::to_string(v) + " at " + text(at[v]) + " is neither on the grid nor where it was");
            }
        }
    }
    const auto [crossings_before, touchings_before] = contacts_between_chains(before);
    const auto [crossings_after, touchings_after] = contacts_between_chains(after);
    const std::size_t n = before.size();
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i; j < n; ++j) {
            if (crossings_before[i * n + j] != crossings_after[i * n + j] || touchings_before[i * n + j] != touchings_after[i * n + j]) {
                report.violations.push_back("chains " + std::to_string(i) + " and " + std::to_string(j) + ": " +
                                            std::to_string(crossings_before[i * n + j]) + " crossings and " +
                                            std::to_string(touchings_before[i * n + j]) + " other contacts before, " +
                                            std::to_string(crossings_after[i * n + j]) + " and " +
                                            std::to_string(touchings_after[i * n + j]) + " after");
            }
        }
    }
    for (std::size_t c = 0; c < n; ++c) {
        const bool closed = before[c].size() > 3 && same(before[c].front(), before[c].back());
        if (closed) {
            std::vector<Point> corners;
            for (std::size_t k = 0; k + 1 < after[c].size(); ++k) {
                if (std::none_of(corners.begin(), corners.end(), [&](Point q) { return same(q, after[c][k]); })) corners.push_back(after[c][k]);
            }
            if (corners.size() < 3) report.violations.push_back("ring " + std::to_string(c) + " kept fewer than 3 corners");
            if (ring_sign(before[c]) != ring_sign(after[c])) report.violations.push_back("ring " + std::to_string(c) + " changed orientation");
            for (const Point q : input.control_points) {
                if (where_in_ring(q, before[c]) != where_in_ring(q, after[c])) {
                    report.violations.push_back("control point " + text(q) + " changed place against ring " + std::to_string(c));
                }
            }
            continue;
        }
        // The loop: input forward, output back.
        std::vector<Point> loop = before[c];
        loop.insert(loop.end(), after[c].rbegin(), after[c].rend());
        for (const Point q : input.control_points) {
            const bool on_both = on_polyline(q, before[c]) && on_polyline(q, after[c]);
            if (on_both) continue;
            bool on_loop = false;
            for (std::size_t k = 0; k < loop.size() && !on_loop; ++k) on_loop = on_segment(q, loop[k], loop[(k + 1) % loop.size()]);
            if (on_loop || inside_polygon(q, loop)) {
                report.violations.push_back("control point " + text(q) + " was passed over by chain " + std::to_string(c));
            }
        }
    }
    return report;
}

}  // namespace toposimp::testing
