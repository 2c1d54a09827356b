#include "core/mesh/height_field.hpp"

#include "core/exact/predicates.hpp"
#include "core/exact/segments.hpp"
#include "core/mesh/plan_index.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace toposimp::mesh {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

}  // namespace

std::vector<DirectedEdge> border_edges(const Mesh& mesh, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    // The corners of each vertex (a counting sort).
    const std::size_t n = mesh.points.size();
    std::vector<std::size_t> first(n + 1, 0);
    for (const Face& f : mesh.faces) {
        for (std::uint32_t v : f) ++first[v + 1];
    }
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
    std::vector<std::uint32_t> corners(first[n]);
    {
        std::vector<std::size_t> next(first.begin(), first.end() - 1);
        for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
            for (std::uint32_t k = 0; k < 3; ++k) corners[next[mesh.faces[f][k]]++] = 3 * f + k;
        }
    }
    // Around each vertex v: its faces' edges out of v (v, w) and into it (u, v), a few: scans. An
    // edge out of v with no edge into v from the same neighbour is a border edge.
    std::vector<std::vector<DirectedEdge>> parts(static_cast<std::size_t>(threads));
    const auto vertices = static_cast<std::int64_t>(n);
#pragma omp parallel num_threads(threads)
    {
        auto& part = parts[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
        for (std::int64_t v = 0; v < vertices; ++v) {
            auto out_of = [&](std::size_t i) { return mesh.faces[corners[i] / 3][(corners[i] % 3 + 1) % 3]; };
            auto into = [&](std::size_t i) { return mesh.faces[corners[i] / 3][(corners[i] % 3 + 2) % 3]; };
            for (std::size_t i = first[v]; i < first[v + 1]; ++i) {
                const std::uint32_t w = out_of(i);
                bool inner = false;
                for (std::size_t j = first[v]; j < first[v + 1]; ++j) inner = inner || into(j) == w;
                if (!inner) part.emplace_back(static_cast<std::uint32_t>(v), w);
            }
        }
    }
    std::vector<DirectedEdge> edges;
    for (const auto& part : parts) edges.insert(edges.end(), part.begin(), part.end());
    std::sort(edges.begin(), edges.end());
    return edges;
}

bool covers_once_by_border(const Mesh& mesh, int turn, const std::vector<DirectedEdge>& edges) {
    if (edges.empty()) return false;  // a closed surface: never all turned one way, but not shown here
    auto plan = [&](std::uint32_t v) { return Point{mesh.points[v].x, mesh.points[v].y}; };
    exact::PredicateStats stats;

    // Simple loops: at most one border edge out of and into each vertex. This also shows the faces
    // consistently oriented: two faces with the same edge the same way (on one side of it) would
    // make two border edges out of its start (an edge has two faces at most).
    std::vector<std::uint32_t> out(mesh.points.size(), kNone), previous(mesh.points.size(), kNone);
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        const auto [v, w] = edges[e];
        if (out[v] != kNone || previous[w] != kNone) return false;
        out[v] = e;
        previous[w] = v;
    }

    // Pairwise apart: edges meet only where one follows the other, at their shared end. Edges are
    // bucketed in a uniform grid of about one cell per edge over the border's box.
    double x0 = plan(edges[0].first).x, x1 = x0, y0 = plan(edges[0].first).y, y1 = y0;
    for (const auto& [v, w] : edges) {
        x0 = std::min(x0, plan(v).x), x1 = std::max(x1, plan(v).x);
        y0 = std::min(y0, plan(v).y), y1 = std::max(y1, plan(v).y);
    }
    const auto side = static_cast<std::int64_t>(std::clamp(std::ceil(std::sqrt(static_cast<double>(edges.size()))), 1.0, 4096.0));
    const double size = std::max(x1 - x0, y1 - y0) / static_cast<double>(side);
    auto cell = [&](double value, double origin) {
        const double c = size > 0 ? std::floor((value - origin) / size) : 0.0;
        return c >= 0 ? std::min(static_cast<std::int64_t>(c), side - 1) : std::int64_t{0};
    };
    std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(side * side));
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        const Point a = plan(edges[e].first), b = plan(edges[e].second);
        for (std::int64_t x = cell(std::min(a.x, b.x), x0); x <= cell(std::max(a.x, b.x), x0); ++x) {
            for (std::int64_t y = cell(std::min(a.y, b.y), y0); y <= cell(std::max(a.y, b.y), y0); ++y) {
                grid[static_cast<std::size_t>(x * side + y)].push_back(e);
            }
        }
    }
    std::uint64_t tests = 0;
    for (const auto& list : grid) {
        tests += list.size() * (list.size() - (list.empty() ? 0 : 1)) / 2;
        if (tests > (std::uint64_t{1} << 26)) return false;  // crowded: leave it to the face test
        for (std::size_t i = 0; i < list.size(); ++i) {
            for (std::size_t j = i + 1; j < list.size(); ++j) {
                const auto [a, b] = edges[list[i]];
                const auto [c, d] = edges[list[j]];
                const bool follows = b == c || d == a;
                if (!follows) {
                    for (std::uint32_t p : {a, b}) {
                        for (std::uint32_t q : {c, d}) {
                            if (plan(p).x == plan(q).x && plan(p).y == plan(q).y) return false;  // loops touch
                        }
                    }
                }
                if (exact::improper_contact(plan(a), plan(b), plan(c), plan(d), exact::Arithmetic::exact, stats)) return false;
            }
        }
    }

    // The loops, each with its lowest corner (least x, then y).
    std::vector<std::uint32_t> loop_of(edges.size(), kNone);
    std::vector<std::uint32_t> lowest;
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        if (loop_of[e] != kNone) continue;
        const auto id = static_cast<std::uint32_t>(lowest.size());
        std::uint32_t low = edges[e].first;
        for (std::uint32_t v = edges[e].first;;) {
            if (out[v] == kNone) return false;  // (cannot happen: as many border edges in as out)
            loop_of[out[v]] = id;
            const Point p = plan(v), l = plan(low);
            if (p.x < l.x || (p.x == l.x && p.y < l.y)) low = v;
            v = edges[out[v]].second;
            if (v == edges[e].first) break;
        }
        lowest.push_back(low);
    }
    if (static_cast<double>(lowest.size()) * static_cast<double>(edges.size()) > 2e7) return false;  // leave it to the face test

    // At each loop's lowest corner r: the faces there number turn × (the loop's own winding on
    // their side + the other loops' winding numbers around r), and must number one. The loop
    // turns as its corners at r do (at a lowest corner of a simple polygon they are not collinear).
    for (std::uint32_t id = 0; id < lowest.size(); ++id) {
        const std::uint32_t r = lowest[id];
        const Point q = plan(r);
        const int turns = exact::orient2d(plan(previous[r]), q, plan(edges[out[r]].second), stats);
        if (turns == 0) return false;
        int winding = turn > 0 ? (turns > 0 ? 1 : 0) : (turns > 0 ? 0 : -1);  // on the faces' side (left if turn > 0)
        for (std::uint32_t e = 0; e < edges.size(); ++e) {
            if (loop_of[e] == id) continue;
            const Point a = plan(edges[e].first), b = plan(edges[e].second);
            if (a.y <= q.y && b.y > q.y && exact::orient2d(a, b, q, stats) > 0) ++winding;
            if (b.y <= q.y && a.y > q.y && exact::orient2d(a, b, q, stats) < 0) --winding;
        }
        if (turn * winding != 1) return false;
    }
    return true;
}

std::optional<std::array<std::uint32_t, 2>> plan_overlap(const Mesh& mesh, int turn, const std::vector<DirectedEdge>& border,
                                                         int threads) {
    if (covers_once_by_border(mesh, turn, border)) return std::nullopt;
    return PlanIndex(mesh).overlapping_faces(mesh, turn, threads);
}

}  // namespace toposimp::mesh
