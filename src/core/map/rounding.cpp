#include "core/map/rounding.hpp"

#include "core/exact/segments.hpp"
#include "core/map/location_key.hpp"
#include "core/map/point_grid.hpp"
#include "core/map/segment_cells.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <unordered_map>

namespace toposimp::map {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

Box box_of(std::initializer_list<Point> points) {
    Box box{INFINITY, INFINITY, -INFINITY, -INFINITY};
    for (const Point p : points) box = {std::min(box.min_x, p.x), std::min(box.min_y, p.y), std::max(box.max_x, p.x), std::max(box.max_y, p.y)};
    return box;
}

Box widened(const Box& box, double by) { return {box.min_x - by, box.min_y - by, box.max_x + by, box.max_y + by}; }

bool inside(Point p, const Box& box) { return p.x >= box.min_x && p.x <= box.max_x && p.y >= box.min_y && p.y <= box.max_y; }

// The live segments, each named by its first vertex, found through the cells their original
// geometry was entered in (segment_cells.hpp). A segment whose ends have moved by at most D
// lies within D of where it was, so a query box widened by D finds it. A segment made by a
// removal is entered, by its ends' original locations, in cells of its own.
class SegmentIndex {
public:
    SegmentIndex(const Grid& grid, std::uint32_t side, std::size_t ids) : grid_(grid), side_(side), seen_(ids, 0) {}

    template <class Segments>
    void build(const Segments& segments) {  // segments(visit): visit(id, a, b) for each
        start_.assign(std::size_t{side_} * side_ + 1, 0);
        segments([&](std::uint32_t, Point a, Point b) { for_cells(a, b, [&](std::size_t cell) { ++start_[cell + 1]; }); });
        for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
        ids_.resize(start_.back());
        std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
        segments([&](std::uint32_t id, Point a, Point b) { for_cells(a, b, [&](std::size_t cell) { ids_[fill[cell]++] = id; }); });
    }

    void add(std::uint32_t id, Point a, Point b) {
        for_cells(a, b, [&](std::size_t cell) { added_[cell].push_back(id); });
    }

    // Calls visit(id) once for each segment entered in a cell of the box, until it returns true.
    template <class Visit>
    bool any(const Box& box, Visit&& visit) {
        if (++stamp_ == 0) {
            std::fill(seen_.begin(), seen_.end(), 0);
            stamp_ = 1;
        }
        auto once = [&](std::uint32_t id) {
            if (seen_[id] == stamp_) return false;
            seen_[id] = stamp_;
            return visit(id);
        };
        for (std::uint32_t y = grid_.row(box.min_y), y1 = grid_.row(box.max_y); y <= y1; ++y) {
            for (std::uint32_t x = grid_.column(box.min_x), x1 = grid_.column(box.max_x); x <= x1; ++x) {
                const std::size_t cell = std::size_t{y} * side_ + x;
                for (std::size_t k = start_[cell]; k < start_[cell + 1]; ++k) {
                    if (once(ids_[k])) return true;
                }
                if (added_.empty()) continue;
                const auto found = added_.find(cell);
                if (found == added_.end()) continue;
                for (const std::uint32_t id : found->second) {
                    if (once(id)) return true;
                }
            }
        }
        return false;
    }

private:
    template <class Visit>
    void for_cells(Point a, Point b, Visit&& visit) const {
        const Box box = segment_box(a, b);
        for (std::uint32_t y = grid_.row(box.min_y), y1 = grid_.row(box.max_y); y <= y1; ++y) {
            const Box part = grid_.part_in_row(a, b, y);
            for (std::uint32_t x = grid_.column(part.min_x), x1 = grid_.column(part.max_x); x <= x1; ++x) {
                visit(std::size_t{y} * side_ + x);
            }
        }
    }

    Grid grid_;
    std::uint32_t side_;
    std::vector<std::size_t> start_;
    std::vector<std::uint32_t> ids_;
    std::unordered_map<std::size_t, std::vector<std::uint32_t>> added_;
    std::vector<std::uint32_t> seen_;
    std::uint32_t stamp_ = 0;
};

class Rounder {
public:
    Rounder(const MapData& map, const std::vector<std::uint8_t>& kept, const RoundingOptions& options)
        : map_(map), options_(options), kept_(kept) {
        link_chains();
        group_locations();
        index();
    }

    RoundingResult run() {
        RoundingStats& stats = result_.stats;
        stats.locations = orig_.size();
        std::vector<std::uint32_t> pending;
        for (std::uint32_t l = 0; l < orig_.size(); ++l) {
            if (frozen_[l]) {
                ++stats.frozen;
                continue;
            }
            const Point target = nearest(orig_[l]);
            if (same_location(target, orig_[l])) {
                ++stats.already_on_grid;
            } else {
                pending.push_back(l);
            }
        }
        // Passes: the nearest grid point first, then the 3×3 around it as neighbours settle; for
        // what is left, the 5×5, and, last, taking the vertex out where the simplifier's rules
        // allow (a vertex not written needs no grid point); then the grid points again, since
        // a removal frees its neighbours.
        const int wide_from = options_.passes;
        for (int pass = 0; pass < options_.passes + 3 && !pending.empty(); ++pass) {
            ++stats.passes;
            std::vector<std::uint32_t> left;
            const bool removing = pass == wide_from + 1;
            for (const std::uint32_t l : pending) {
                const Point near = nearest(orig_[l]);
                bool done = false;
                if (removing) {
                    if (vertex_start_[l + 1] - vertex_start_[l] == 1 && try_remove(vertices_[vertex_start_[l]])) {
                        ++stats.removed;
                        ++stats.removed_off_grid;
                        continue;
                    }
                    left.push_back(l);
                    continue;
                }
                for (const Point target : pass == 0 ? std::vector<Point>{near} : candidates(l, pass >= wide_from ? 2 : 1)) {
                    const std::optional<bool> moved = attempt(l, target);
                    if (!moved) continue;
                    done = true;
                    if (!*moved) ++stats.removed;
                    else if (same_location(target, near)) ++stats.moved_nearest;
                    else ++stats.moved_other;
                    break;
                }
                if (!done) left.push_back(l);
            }
            const bool progress = left.size() < pending.size();
            pending = std::move(left);
            if (!progress && pass > 0 && pass < wide_from) pass = wide_from - 1;  // on to the 5×5
        }
        round_points();
        stats.off_grid = pending.size();
        for (const std::uint32_t l : pending) result_.off_grid.push_back(vertices_[vertex_start_[l]]);
        result_.at = map_.vertices;
        for (std::uint32_t v = 0; v < kept_.size(); ++v) {
            if (kept_[v]) result_.at[v] = pos_[location_[v]];
        }
        result_.kept = std::move(kept_);
        result_.points.assign(point_at_.begin(), point_at_.begin() + static_cast<std::ptrdiff_t>(options_.written_points));
        result_.stats.predicates = predicates_;
        return std::move(result_);
    }

private:
    // Live chain neighbours over the kept vertices.
    void link_chains() {
        const std::size_t n = map_.vertices.size();
        prev_.assign(n, kNone);
        next_.assign(n, kNone);
        chain_of_.assign(n, kNone);
        live_.assign(map_.chains.size(), 0);
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            const Chain chain = map_.chains[c];
            std::uint32_t last = kNone;
            for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
                if (!kept_[v]) continue;
                chain_of_[v] = c;
                ++live_[c];
                if (last != kNone) {
                    next_[last] = v;
                    prev_[v] = last;
                }
                last = v;
            }
        }
    }

    // Kept vertices by location, locations numbered in input order.
    void group_locations() {
        location_.assign(map_.vertices.size(), kNone);
        std::unordered_map<LocationKey, std::uint32_t, LocationKeyHash> ids;
        std::vector<std::uint32_t> count;
        for (std::uint32_t v = 0; v < kept_.size(); ++v) {
            if (!kept_[v]) continue;
            const auto [at, added] = ids.try_emplace(LocationKey(map_.vertices[v]), static_cast<std::uint32_t>(orig_.size()));
            if (added) {
                orig_.push_back(map_.vertices[v]);
                count.push_back(0);
            }
            location_[v] = at->second;
            ++count[at->second];
        }
        vertex_start_.assign(orig_.size() + 1, 0);
        for (std::size_t l = 0; l < count.size(); ++l) vertex_start_[l + 1] = vertex_start_[l] + count[l];
        vertices_.resize(vertex_start_.back());
        std::vector<std::uint32_t> fill(vertex_start_.begin(), vertex_start_.end() - 1);
        for (std::uint32_t v = 0; v < kept_.size(); ++v) {
            if (kept_[v]) vertices_[fill[location_[v]]++] = v;
        }
        pos_ = orig_;
        dead_.assign(orig_.size(), 0);
        frozen_.assign(orig_.size(), 0);
        for (std::uint32_t v = 0; v < kept_.size(); ++v) {
            if (kept_[v] && map_.is_frozen(chain_of_[v])) frozen_[location_[v]] = 1;
        }
    }

    void index() {
        Box extent{INFINITY, INFINITY, -INFINITY, -INFINITY};
        for (const Point p : orig_) extent = {std::min(extent.min_x, p.x), std::min(extent.min_y, p.y), std::max(extent.max_x, p.x), std::max(extent.max_y, p.y)};
        if (orig_.empty()) extent = {0, 0, 0, 0};
        const double magnitude = std::max({std::abs(extent.min_x), std::abs(extent.max_x), std::abs(extent.min_y), std::abs(extent.max_y)});
        for (const Point p : orig_) {
            if (!options_.grid.x.nearest(p.x) || !options_.grid.y.nearest(p.y)) {
                throw std::invalid_argument("the grid " + options_.grid.text() + " is too fine for coordinates as large as " +
                                            std::to_string(magnitude));
            }
        }
        // The farthest a location moves: a grid point of the 5×5 around its nearest one, within
        // 2.5 steps in x and in y, plus the rounding of grid values to doubles.
        reach_ = 2.75 * options_.grid.step() + std::ldexp(magnitude, -48);
        std::size_t segments = 0;
        for (std::uint32_t v = 0; v < next_.size(); ++v) segments += next_[v] != kNone;
        // About a quarter of a segment per cell: coastlines crowd some cells, and a query tests
        // every segment of its cells.
        const auto side = static_cast<std::uint32_t>(std::clamp(std::floor(std::sqrt(static_cast<double>(segments) * 4.0)), 1.0, 8192.0));
        segments_.emplace(make_grid(extent, side), side, map_.vertices.size());
        segments_->build([&](auto visit) {
            for (std::uint32_t v = 0; v < next_.size(); ++v) {
                if (next_[v] != kNone) visit(v, map_.vertices[v], map_.vertices[next_[v]]);
            }
        });
        locations_.emplace(std::span<const Point>(orig_));
        if (!map_.control_points.empty()) controls_.emplace(std::span<const Point>(map_.control_points));
        point_at_ = map_.control_points;
        for (std::size_t k = 0; k < options_.written_points; ++k) {
            const Point p = map_.control_points[k];
            if (!options_.grid.x.nearest(p.x) || !options_.grid.y.nearest(p.y)) {
                throw std::invalid_argument("the grid " + options_.grid.text() + " is too fine for coordinates as large as (" +
                                            std::to_string(p.x) + ", " + std::to_string(p.y) + ")");
            }
        }
    }

    Point nearest(Point p) const {
        const OutputGrid& grid = options_.grid;
        return {grid.x.at(*grid.x.nearest(p.x)), grid.y.at(*grid.y.nearest(p.y))};
    }

    // The grid points of the (2·radius + 1)² around the nearest one, nearest first.
    std::vector<Point> candidates(std::uint32_t l, std::int64_t radius) const {
        const OutputGrid& grid = options_.grid;
        const Point p = orig_[l];
        const std::int64_t kx = *grid.x.nearest(p.x), ky = *grid.y.nearest(p.y);
        std::vector<std::pair<double, Point>> around;
        for (std::int64_t dy = -radius; dy <= radius; ++dy) {
            for (std::int64_t dx = -radius; dx <= radius; ++dx) {
                const Point q{grid.x.at(kx + dx), grid.y.at(ky + dy)};
                around.push_back({(q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y), q});
            }
        }
        std::stable_sort(around.begin(), around.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<Point> out;
        for (const auto& [distance, q] : around) {
            if (!same_location(q, pos_[l])) out.push_back(q);
        }
        return out;
    }

    // The written control points, each to its nearest grid point when the path there touches no
    // live segment (closed: not even at an end) — it then crosses nothing and leaves no line it
    // was on. After the lines, so that they see the points where they were.
    void round_points() {
        for (std::size_t k = 0; k < options_.written_points; ++k) {
            const Point p = point_at_[k], t = nearest(p);
            if (same_location(p, t)) {
                ++result_.stats.points_moved;
                continue;
            }
            const bool touched = segments_->any(widened(box_of({p, t}), reach_), [&](std::uint32_t s) {
                const std::uint32_t e = next_[s];
                if (!kept_[s] || e == kNone) return false;
                const Point u = pos_[location_[s]], w = pos_[location_[e]];
                return exact::improper_contact(p, t, u, w, options_.arithmetic, predicates_) || same_location(p, u) ||
                       same_location(p, w) || same_location(t, u) || same_location(t, w);
            });
            if (touched) {
                ++result_.stats.points_off_grid;
            } else {
                point_at_[k] = t;
                ++result_.stats.points_moved;
            }
        }
    }

    // Puts location l at `target`: true if moved, false if its vertex was removed instead,
    // nullopt if neither was safe.
    std::optional<bool> attempt(std::uint32_t l, Point target) {
        for (std::uint32_t k = vertex_start_[l]; k < vertex_start_[l + 1]; ++k) {
            const std::uint32_t v = vertices_[k];
            for (const std::uint32_t w : {prev_[v], next_[v]}) {
                if (w == kNone || !same_location(pos_[location_[w]], target)) continue;
                // The grid point is a neighbour's: the vertex goes, if it may.
                if (vertex_start_[l + 1] - vertex_start_[l] == 1 && try_remove(v)) return false;
                return std::nullopt;
            }
        }
        if (try_move(l, target)) return true;
        return std::nullopt;
    }

    bool try_move(std::uint32_t l, Point target) {
        const Point p = pos_[l];
        for (std::uint32_t k = vertex_start_[l]; k < vertex_start_[l + 1]; ++k) {
            const std::uint32_t v = vertices_[k];
            for (const std::uint32_t w : {prev_[v], next_[v]}) {
                // (A segment of no length, to L itself, moves with L.)
                if (w == kNone || location_[w] == l) continue;
                if (!triangle_clear(pos_[location_[w]], p, target, {location_[w], l}, {pos_[location_[w]]})) return false;
            }
        }
        // And a location on no segment but of no length: nothing may be where it goes.
        const bool taken = locations_->any_in_cells(widened(box_of({target}), reach_), [&](std::uint32_t id, Point) {
            return id != l && !dead_[id] && same_location(pos_[id], target);
        });
        if (taken || (controls_ && controls_->any_in_cells(widened(box_of({p}), reach_), [&](std::uint32_t id, Point) {
                          return same_location(point_at_[id], p);
                      }))) {
            return false;
        }
        const bool crossed = segments_->any(widened(box_of({p, target}), reach_), [&](std::uint32_t s) {
            const std::uint32_t t = next_[s];
            if (!kept_[s] || t == kNone || location_[s] == l || location_[t] == l) return false;
            return exact::improper_contact(p, target, pos_[location_[s]], pos_[location_[t]], options_.arithmetic, predicates_);
        });
        if (crossed) return false;
        for (std::uint32_t k = vertex_start_[l]; k < vertex_start_[l + 1]; ++k) {
            if (!ring_keeps_shape(chain_of_[vertices_[k]], l, target, kNone)) return false;
        }
        pos_[l] = target;
        return true;
    }

    bool try_remove(std::uint32_t v) {
        const std::uint32_t l = location_[v], before = prev_[v], after = next_[v], chain = chain_of_[v];
        if (before == kNone || after == kNone || frozen_[l]) return false;
        const std::uint32_t la = location_[before], lc = location_[after];
        if (la == lc) return false;
        const Point a = pos_[la], p = pos_[l], c = pos_[lc];
        if (!triangle_clear(a, p, c, {la, lc, l}, {a, c})) return false;
        // Its two segments meet nothing (but each other).
        for (const std::array<Point, 2> segment : {std::array{a, p}, std::array{p, c}}) {
            const bool met = segments_->any(widened(box_of({segment[0], segment[1]}), reach_), [&](std::uint32_t s) {
                const std::uint32_t t = next_[s];
                if (!kept_[s] || t == kNone || s == before || s == v) return false;
                return exact::improper_contact(segment[0], segment[1], pos_[location_[s]], pos_[location_[t]], options_.arithmetic,
                                               predicates_);
            });
            if (met) return false;
        }
        // No segment may come to coincide with (a, c).
        for (std::uint32_t k = vertex_start_[la]; k < vertex_start_[la + 1]; ++k) {
            const std::uint32_t u = vertices_[k];
            if ((next_[u] != kNone && location_[next_[u]] == lc) || (prev_[u] != kNone && location_[prev_[u]] == lc)) return false;
        }
        if (!ring_keeps_shape(chain, kNone, {}, v)) return false;
        kept_[v] = 0;
        next_[before] = after;
        prev_[after] = before;
        prev_[v] = next_[v] = kNone;
        dead_[l] = 1;
        --live_[chain];
        segments_->add(before, orig_[la], orig_[lc]);
        return true;
    }

    // Is the closed triangle abc free of live locations but `allowed`, and of control points
    // but at the locations `points_allowed`?
    bool triangle_clear(Point a, Point b, Point c, std::initializer_list<std::uint32_t> allowed,
                        std::initializer_list<Point> points_allowed) {
        const Box box = box_of({a, b, c});
        exact::ClosedTriangle triangle(a, b, c, options_.arithmetic, predicates_);
        const bool location_inside = locations_->any_in_cells(widened(box, reach_), [&](std::uint32_t id, Point) {
            if (dead_[id] || std::find(allowed.begin(), allowed.end(), id) != allowed.end()) return false;
            return inside(pos_[id], box) && triangle.contains(pos_[id]);
        });
        if (location_inside) return false;
        if (!controls_) return true;
        return !controls_->any_in_cells(widened(box, reach_), [&](std::uint32_t id, Point) {
            const Point q = point_at_[id];
            if (!inside(q, box)) return false;
            for (const Point at : points_allowed) {
                if (same_location(q, at)) return false;
            }
            return triangle.contains(q);
        });
    }

    // A closed chain left with 3 or 4 corners after location `moved` goes to `target` (or vertex
    // `removed` goes) keeps 3 distinct locations and the input ring's orientation.
    bool ring_keeps_shape(std::uint32_t chain, std::uint32_t moved, Point target, std::uint32_t removed) {
        const Chain c = map_.chains[chain];
        if (!same_location(map_.vertices[c.first], map_.vertices[c.last]) || c.last - c.first < 3) return true;
        const std::uint32_t corners = live_[chain] - 1 - (removed != kNone ? 1 : 0);
        if (corners > 4) return true;
        std::vector<Point> ring;
        std::vector<std::uint32_t> distinct;
        for (std::uint32_t v = c.first; v != kNone; v = next_[v]) {
            if (v == removed) continue;
            const std::uint32_t l = location_[v];
            ring.push_back(l == moved ? target : pos_[l]);
            if (std::find(distinct.begin(), distinct.end(), l) == distinct.end()) distinct.push_back(l);
        }
        if (distinct.size() < 3) return false;
        if (ring_sign_.empty()) ring_sign_.assign(map_.chains.size(), 2);
        if (ring_sign_[chain] == 2) {
            const std::span<const Point> input(map_.vertices.data() + c.first, c.last - c.first + 1);
            ring_sign_[chain] = static_cast<std::int8_t>(exact::ring_area_sign(input, predicates_));
        }
        return exact::ring_area_sign(ring, predicates_) == ring_sign_[chain];
    }

    const MapData& map_;
    RoundingOptions options_;
    std::vector<std::uint8_t> kept_;
    std::vector<std::uint32_t> prev_, next_, chain_of_, live_;
    std::vector<std::uint32_t> location_;       // per kept vertex
    std::vector<Point> orig_, pos_;             // per location: where it was, where it is
    std::vector<std::uint32_t> vertex_start_, vertices_;  // per location, its vertices
    std::vector<std::uint8_t> dead_, frozen_;
    std::vector<std::int8_t> ring_sign_;  // per chain: the input ring's area sign, 2 until needed
    double reach_ = 0;
    std::optional<SegmentIndex> segments_;
    std::optional<PointGrid> locations_, controls_;
    std::vector<Point> point_at_;  // per control point: where it is (the written ones move)
    exact::PredicateStats predicates_;
    RoundingResult result_;
};

}  // namespace

RoundingResult round_to_grid(const MapData& map, const std::vector<std::uint8_t>& kept, const RoundingOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    RoundingResult result = Rounder(map, kept, options).run();
    result.grid = options.grid;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace toposimp::map
