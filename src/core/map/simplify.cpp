#include "core/map/simplify.hpp"

#include "core/map/crossings.hpp"
#include "core/map/indexed_heap.hpp"
#include "core/map/location_key.hpp"
#include "core/map/point_grid.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>

namespace toposimp::map {

std::uint64_t removal_goal(const StopCriterion& stop, std::uint64_t vertices) {
    const double all = static_cast<double>(vertices);
    auto keep = [&](double count) -> std::uint64_t {
        if (!(count < all)) return 0;
        return vertices - static_cast<std::uint64_t>(std::max(0.0, count));
    };
    switch (stop.target) {
        case Target::keep_fraction: return keep(std::ceil(stop.value * all));
        case Target::keep_points: return keep(stop.value);
        case Target::remove_points: return stop.value < all ? static_cast<std::uint64_t>(std::max(0.0, stop.value)) : vertices;
        case Target::max_area:
        case Target::max: return std::numeric_limits<std::uint64_t>::max();
    }
    return 0;
}

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// An undirected segment between two locations.
struct SegmentKey {
    LocationKey lo, hi;
    SegmentKey(Point a, Point b) : lo(a), hi(b) {
        if (hi < lo) std::swap(lo, hi);
    }
    friend bool operator==(const SegmentKey&, const SegmentKey&) = default;
};

struct SegmentKeyHash {
    std::size_t operator()(const SegmentKey& k) const { return hash_words({k.lo.x, k.lo.y, k.hi.x, k.hi.y}); }
};

double effective_area(Point a, Point b, Point c) {
    // Ranking only (Visvalingam–Whyatt); no topological decision depends on this value.
    return 0.5 * std::fabs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

enum class Verdict { remove, blocked_by_point, blocked_by_ring, blocked_by_coincidence };

class Simplifier {
public:
    Simplifier(const MapData& map, const SimplifyOptions& options)
        : map_(map),
          options_(options),
          vertex_count_(static_cast<std::uint32_t>(map.vertices.size())),
          heap_(map.vertices.size()) {}

    SimplifyResult run() {
        build_chains();
        index_points();
        find_shared_locations();
        pin_crossings();
        rank_vertices();
        simplify_vertices();
        return finish();
    }

private:
    // Linked lists over the vertices, ring bookkeeping and the current segments at shared
    // locations.
    void build_chains() {
        prev_.assign(vertex_count_, kNone);
        next_.assign(vertex_count_, kNone);
        alive_.assign(vertex_count_, 1);
        chain_of_.assign(vertex_count_, 0);
        distinct_.assign(map_.chains.size(), 0);
        orientation_.assign(map_.chains.size(), 2);  // 2: not computed yet
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            const Chain& chain = map_.chains[c];
            for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
                chain_of_[v] = c;
                if (v > chain.first) prev_[v] = v - 1;
                if (v < chain.last) next_[v] = v + 1;
            }
            if (is_closed(c)) distinct_[c] = count_distinct_locations(chain);
        }
    }

    bool is_closed(std::uint32_t c) const {
        const Chain& chain = map_.chains[c];
        return chain.last > chain.first && same_location(map_.vertices[chain.first], map_.vertices[chain.last]);
    }

    std::uint32_t count_distinct_locations(const Chain& chain) const {
        std::vector<LocationKey> keys;
        keys.reserve(chain.last - chain.first);
        for (std::uint32_t v = chain.first; v < chain.last; ++v) keys.emplace_back(map_.vertices[v]);
        std::sort(keys.begin(), keys.end());
        return static_cast<std::uint32_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
    }

    // One grid over vertices and control points: ids [0, n) are vertices, [n, n+m) control points.
    void index_points() {
        std::vector<Point> points;
        points.reserve(map_.vertices.size() + map_.control_points.size());
        points.insert(points.end(), map_.vertices.begin(), map_.vertices.end());
        points.insert(points.end(), map_.control_points.begin(), map_.control_points.end());
        grid_.emplace(points);
    }

    // A location held by two or more vertices (a node, a ring's closing vertex, a duplicate, a
    // touch): only segments ending at such locations can ever coincide with another segment.
    void find_shared_locations() {
        shared_.assign(vertex_count_, 0);
        std::vector<std::uint32_t> order(vertex_count_);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) order[v] = v;
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const LocationKey ka(map_.vertices[a]), kb(map_.vertices[b]);
            return ka < kb || (ka == kb && a < b);
        });
        for (std::size_t i = 1; i < order.size(); ++i) {
            if (same_location(map_.vertices[order[i - 1]], map_.vertices[order[i]])) {
                shared_[order[i - 1]] = shared_[order[i]] = 1;
            }
        }
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (next_[v] != kNone) add_segment(v, next_[v]);
        }
    }

    bool tracks_segment(std::uint32_t u, std::uint32_t w) const {
        return (shared_[u] || shared_[w]) && !same_location(map_.vertices[u], map_.vertices[w]);
    }

    void add_segment(std::uint32_t u, std::uint32_t w) {
        if (tracks_segment(u, w)) ++segments_[SegmentKey(map_.vertices[u], map_.vertices[w])];
    }

    void drop_segment(std::uint32_t u, std::uint32_t w) {
        if (!tracks_segment(u, w)) return;
        const auto it = segments_.find(SegmentKey(map_.vertices[u], map_.vertices[w]));
        if (--it->second == 0) segments_.erase(it);
    }

    // Vertices at either end of a segment that crosses or touches another one improperly in the
    // input are never removed (see crossings.hpp for why that is enough); nor are frozen chains'.
    void pin_crossings() {
        const std::vector<std::uint8_t> improper = find_improper_segments(map_, options_.arithmetic, stats_.predicates);
        pinned_.assign(vertex_count_, 0);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (improper[v]) pinned_[v] = pinned_[next_[v]] = 1;
            if (map_.is_frozen(chain_of_[v])) pinned_[v] = 1;
        }
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (pinned_[v] && is_interior(v)) ++stats_.pinned_by_crossing;
        }
    }

    bool is_interior(std::uint32_t v) const { return prev_[v] != kNone && next_[v] != kNone; }

    double area_of(std::uint32_t v) const {
        return effective_area(map_.vertices[prev_[v]], map_.vertices[v], map_.vertices[next_[v]]);
    }

    void rank_vertices() {
        blocked_head_.assign(vertex_count_, kNone);
        blocked_on_.assign(vertex_count_, kNone);
        blocked_prev_.assign(vertex_count_, kNone);
        blocked_next_.assign(vertex_count_, kNone);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (is_interior(v) && !pinned_[v]) heap_.set(v, area_of(v));
        }
        queued_at_start_ = heap_.size();
    }

    // Remove vertices smallest effective area first until the stop criterion holds. A vertex
    // refused because some vertex lies in its triangle waits on that vertex: when it goes, the
    // refused one is queued again. Any vertex whose triangle changes is re-ranked.
    void simplify_vertices() {
        const std::uint64_t goal = removal_goal(options_.stop, vertex_count_);
        const bool by_area = options_.stop.target == Target::max_area;
        stats_.removal_goal = by_area || options_.stop.target == Target::max ? 0 : goal;
        // Work estimate for progress: the removals asked for, or every queued vertex.
        const double work = static_cast<double>(std::min<std::uint64_t>(goal, heap_size_at_start()));
        std::uint64_t pops = 0;
        while (!heap_.empty() && stats_.removed < goal) {
            if (by_area && heap_.top_key() > options_.stop.value) break;
            if (options_.progress && (++pops & 0x3fff) == 0 && work > 0) {
                options_.progress(std::min(1.0, static_cast<double>(stats_.removed) / work));
            }
            const std::uint32_t v = heap_.pop();
            std::uint32_t blocker = kNone;
            switch (judge(v, blocker)) {
                case Verdict::remove: remove(v); break;
                case Verdict::blocked_by_point:
                    ++stats_.blocked_by_point;
                    if (blocker < vertex_count_) wait_on(v, blocker);
                    break;
                case Verdict::blocked_by_ring: ++stats_.blocked_by_ring; break;
                case Verdict::blocked_by_coincidence: ++stats_.blocked_by_coincidence; break;
            }
        }
        if (!by_area && options_.stop.target != Target::max) stats_.target_reached = stats_.removed >= goal;
    }

    std::uint64_t heap_size_at_start() const { return queued_at_start_; }

    Verdict judge(std::uint32_t v, std::uint32_t& blocker) {
        const std::uint32_t p = prev_[v], n = next_[v];
        const Point a = map_.vertices[p], b = map_.vertices[v], c = map_.vertices[n];
        if (!keeps_ring_valid(v, a, b, c)) return Verdict::blocked_by_ring;

        const Box box = triangle_box(a, b, c);
        std::optional<exact::ClosedTriangle> triangle;  // prepared at the first candidate point
        const bool hit = grid_->any_in_cells(box, [&](std::uint32_t id, Point q) {
            if (id == v || !box_contains(box, q) || same_location(q, a) || same_location(q, c)) return false;
            if (!triangle) triangle.emplace(a, b, c, options_.arithmetic, stats_.predicates);
            if (!triangle->contains(q)) return false;
            blocker = id;
            return true;
        });
        if (hit) return Verdict::blocked_by_point;

        if (tracks_segment(p, n) && coincides_with_other_segment(p, v, n)) return Verdict::blocked_by_coincidence;
        return Verdict::remove;
    }

    // Rule 3: would the new segment p–n lie on another live segment with the same end locations?
    // v's own segments p–v and v–n disappear with it and do not count (they can have the same
    // locations when v duplicates a neighbour).
    bool coincides_with_other_segment(std::uint32_t p, std::uint32_t v, std::uint32_t n) const {
        const SegmentKey key(map_.vertices[p], map_.vertices[n]);
        const auto it = segments_.find(key);
        if (it == segments_.end()) return false;
        std::uint32_t own = 0;
        if (tracks_segment(p, v) && SegmentKey(map_.vertices[p], map_.vertices[v]) == key) ++own;
        if (tracks_segment(v, n) && SegmentKey(map_.vertices[v], map_.vertices[n]) == key) ++own;
        return it->second > own;
    }

    // Rule 2: a closed chain keeps ≥ 3 distinct locations, and its last triangle keeps the
    // input ring's orientation (so non-zero area).
    bool keeps_ring_valid(std::uint32_t v, Point a, Point b, Point c) {
        const std::uint32_t chain = chain_of_[v];
        if (distinct_[chain] == 0) return true;  // open chain
        if (same_location(b, a) || same_location(b, c)) return true;  // a duplicate: no location lost
        if (distinct_[chain] <= 3) return false;
        if (distinct_[chain] > 4) return true;
        Point corners[3];
        int found = 0;
        for (std::uint32_t u = map_.chains[chain].first; u != kNone && found < 3; u = next_[u]) {
            if (u == v) continue;
            const Point q = map_.vertices[u];
            bool seen = false;
            for (int k = 0; k < found; ++k) seen = seen || same_location(corners[k], q);
            if (!seen) corners[found++] = q;
        }
        if (found < 3) return false;
        const int turn = options_.arithmetic == exact::Arithmetic::floating
                             ? orient_float(corners[0], corners[1], corners[2])
                             : exact::orient2d(corners[0], corners[1], corners[2], stats_.predicates);
        return turn != 0 && turn == ring_orientation(chain);
    }

    static int orient_float(Point a, Point b, Point c) {
        const double det = (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x);
        return (det > 0) - (det < 0);
    }

    // Sign of the input ring's signed area, exactly (computed once, only for rings that get
    // down to their last triangle).
    int ring_orientation(std::uint32_t chain) {
        if (orientation_[chain] != 2) return orientation_[chain];
        const Chain& range = map_.chains[chain];
        mpq_class twice_area = 0;
        for (std::uint32_t v = range.first; v < range.last; ++v) {
            const Point p = map_.vertices[v], q = map_.vertices[v + 1];
            twice_area += mpq_class(p.x) * mpq_class(q.y) - mpq_class(q.x) * mpq_class(p.y);
        }
        orientation_[chain] = static_cast<std::int8_t>(sgn(twice_area));
        return orientation_[chain];
    }

    void remove(std::uint32_t v) {
        const std::uint32_t p = prev_[v], n = next_[v];
        const std::uint32_t chain = chain_of_[v];
        const Point a = map_.vertices[p], b = map_.vertices[v], c = map_.vertices[n];
        drop_segment(p, v);
        drop_segment(v, n);
        add_segment(p, n);
        if (distinct_[chain] != 0 && !same_location(b, a) && !same_location(b, c)) --distinct_[chain];
        alive_[v] = 0;
        grid_->remove(v);
        next_[p] = n;
        prev_[n] = p;
        ++stats_.removed;
        release_waiting_on(v);
        for (const std::uint32_t u : {p, n}) {
            if (!is_interior(u) || pinned_[u]) continue;
            stop_waiting(u);
            heap_.set(u, area_of(u));
        }
    }

    // Lists of vertices refused because of one blocking vertex (doubly linked, intrusive).
    void wait_on(std::uint32_t v, std::uint32_t blocker) {
        blocked_on_[v] = blocker;
        blocked_prev_[v] = kNone;
        blocked_next_[v] = blocked_head_[blocker];
        if (blocked_head_[blocker] != kNone) blocked_prev_[blocked_head_[blocker]] = v;
        blocked_head_[blocker] = v;
    }

    void stop_waiting(std::uint32_t v) {
        const std::uint32_t blocker = blocked_on_[v];
        if (blocker == kNone) return;
        if (blocked_prev_[v] != kNone) {
            blocked_next_[blocked_prev_[v]] = blocked_next_[v];
        } else {
            blocked_head_[blocker] = blocked_next_[v];
        }
        if (blocked_next_[v] != kNone) blocked_prev_[blocked_next_[v]] = blocked_prev_[v];
        blocked_on_[v] = kNone;
    }

    void release_waiting_on(std::uint32_t blocker) {
        while (blocked_head_[blocker] != kNone) {
            const std::uint32_t w = blocked_head_[blocker];
            stop_waiting(w);
            heap_.set(w, area_of(w));
        }
    }

    SimplifyResult finish() {
        stats_.vertices_in = vertex_count_;
        stats_.vertices_out = vertex_count_ - stats_.removed;
        stats_.control_points = map_.control_points.size();
        return {std::move(alive_), stats_};
    }

    const MapData& map_;
    const SimplifyOptions& options_;
    const std::uint32_t vertex_count_;
    std::vector<std::uint32_t> prev_, next_, chain_of_;
    std::vector<std::uint8_t> alive_, shared_, pinned_;
    std::vector<std::uint32_t> distinct_;    // per closed chain: distinct live locations; 0 if open
    std::vector<std::int8_t> orientation_;   // per chain: input ring orientation, 2 = unknown
    std::optional<PointGrid> grid_;
    std::unordered_map<SegmentKey, std::uint32_t, SegmentKeyHash> segments_;
    IndexedHeap heap_;
    std::vector<std::uint32_t> blocked_head_, blocked_on_, blocked_prev_, blocked_next_;
    SimplifyStats stats_;
    std::uint64_t queued_at_start_ = 0;
};

}  // namespace

SimplifyResult simplify(const MapData& map, const SimplifyOptions& options) {
    return Simplifier(map, options).run();
}

}  // namespace toposimp::map
