#include "core/map/simplify.hpp"
#include "core/map/tiles.hpp"
#include "core/map/top_subset.hpp"

#include "core/cancel.hpp"
#include "core/fill_later.hpp"
#include "core/map/crossings.hpp"
#include "core/map/location_key.hpp"
#include "core/map/point_grid.hpp"
#include "core/parallel/blocks.hpp"
#include "core/parallel/select.hpp"
#include "core/parallel/shares.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

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

// Level-0 blocks are at least 2^kMinShift × 2^kMinShift point-grid cells and at most
// kMaxBlocksPerSide blocks span the grid (the dissertation started from 256² cells).
constexpr unsigned kMinShift = 3;
constexpr std::uint32_t kMaxBlocksPerSide = 256;

// The point grid's rows are split in 4 (PointGrid): on GSHHG's shorelines, 7 % off the sweep.
constexpr unsigned kRowSplit = 2;

// Points a cell of the point grid holds on average.
constexpr double kPointsPerCell = 2.0;

// whole_level_ of an open chain.
constexpr std::uint8_t kOpen = 0xff;

bool is_count_target(Target target) { return target != Target::max && target != Target::max_area; }

// At most how many vertices any run can remove from a map whose chains are `chains` (per chain:
// whole_level kOpen if open, else its distinct locations) when `queued` of their interior
// vertices (neither end of a chain) may go, the others pinned. Chain ends never go; a closed
// chain keeps min(3, d) of its d distinct locations (the ring rule), its ends at one of them,
// so at least m = min(2, d − 1) interior vertices, of which the pinned ones may be some. So at
// most queued − Σ max(0, m − pinned in the ring) go, and the sum is at least Σ m − (all pinned).
std::uint64_t removable_at_most(std::span<const Chain> chains, std::span<const std::uint8_t> whole_level,
                                std::span<const std::uint32_t> distinct, std::uint64_t queued) {
    std::uint64_t interior = 0, ring_minimum = 0;
    for (std::size_t c = 0; c < chains.size(); ++c) {
        if (chains[c].last > chains[c].first) interior += chains[c].last - chains[c].first - 1;
        if (whole_level[c] != kOpen && distinct[c] > 0) ring_minimum += std::min<std::uint32_t>(2, distinct[c] - 1);
    }
    const std::uint64_t pinned = interior - std::min(interior, queued);
    const std::uint64_t kept = ring_minimum > pinned ? ring_minimum - pinned : 0;
    return queued - std::min(queued, kept);
}

// The first N distinct locations among points given one by one (the ring rule's questions).
template <int N>
struct FirstLocations {
    Point at[N];
    int count = 0;

    // Takes q unless all N are taken or one of them is at q's location; whether it did.
    bool add(Point q) {
        if (count == N) return false;
        for (int k = 0; k < count; ++k) {
            if (same_location(at[k], q)) return false;
        }
        at[count++] = q;
        return true;
    }
};

// The groups of a round's tiles (indices 0 to tiles − 1, row-major): tiles joined by the split
// rings their cut ends do not settle (union-find over `open(i, join)`, which calls join(c) for
// each such chain c of tile i), in the order of their first tiles, each in index order; groups
// without a busy tile (busy(i)) have nothing to do in the round and are left out.
template <class Open, class Busy>
std::vector<std::vector<std::uint32_t>> group_tiles(std::uint32_t tiles, Open&& open, Busy&& busy) {
    std::vector<std::uint32_t> parent(tiles);
    for (std::uint32_t i = 0; i < tiles; ++i) parent[i] = i;
    const auto root = [&](std::uint32_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    std::unordered_map<std::uint32_t, std::uint32_t> holder;  // an open chain → a tile holding a piece of it
    for (std::uint32_t i = 0; i < tiles; ++i) {
        open(i, [&](std::uint32_t c) {
            const auto [at, fresh] = holder.emplace(c, i);
            if (!fresh) parent[root(i)] = root(at->second);
        });
    }
    std::vector<std::uint32_t> group_of(tiles, kNone);  // root → group
    std::vector<std::vector<std::uint32_t>> groups;
    std::vector<std::uint8_t> any_busy;
    for (std::uint32_t i = 0; i < tiles; ++i) {
        std::uint32_t& group = group_of[root(i)];
        if (group == kNone) {
            group = static_cast<std::uint32_t>(groups.size());
            groups.emplace_back();
            any_busy.push_back(0);
        }
        groups[group].push_back(i);
        if (busy(i)) any_busy[group] = 1;
    }
    std::vector<std::vector<std::uint32_t>> running;
    for (std::size_t g = 0; g < groups.size(); ++g) {
        if (any_busy[g]) running.push_back(std::move(groups[g]));
    }
    return running;
}


// What a vertex is doing. Only `queued` vertices are candidates for removal.
enum class State : std::uint8_t {
    fixed,    // a chain end or a pinned vertex: never removed
    queued,   // a candidate
    waiting,  // refused because a vertex lies in its triangle; queued again when that one goes
    refused,  // refused otherwise; queued again when its triangle changes
    removed,
};

// A vertex with its effective area; ordered by area, ties by id: a total order, so the order
// in which a queue hands out vertices depends only on which vertices it holds.
struct Ranked {
    double key;
    std::uint32_t id;
};

double effective_area(Point a, Point b, Point c) {
    // Ranking only (Visvalingam–Whyatt); no topological decision depends on this value. NaN
    // (from overflowing coordinates) ranks last, so the order stays total.
    const double area = 0.5 * std::fabs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
    return area >= 0.0 ? area : std::numeric_limits<double>::infinity();
}

struct Vector3 {
    double x, y, z;
};

Vector3 on_sphere(Point degrees) {
    constexpr double kRadius = 6371008.8;  // the Earth's mean radius (IUGG), metres
    constexpr double kRadians = 3.14159265358979323846 / 180.0;
    const double longitude = degrees.x * kRadians, latitude = degrees.y * kRadians;
    return {kRadius * std::cos(latitude) * std::cos(longitude), kRadius * std::cos(latitude) * std::sin(longitude),
            kRadius * std::sin(latitude)};
}

// The rank of vertex b between a and c (Ranking): the area of the triangle, in the plane or
// between the points on the sphere, weighted by 1 − k·cos of the angle at b. Plain doubles:
// an order, not a decision; NaN ranks last.
double rank_of(Point a, Point b, Point c, const Ranking& ranking) {
    if (!ranking.spherical && ranking.weighting == 0) return effective_area(a, b, c);
    double area = 0, cosine = 0;
    if (ranking.spherical) {
        const Vector3 p = on_sphere(a), q = on_sphere(b), r = on_sphere(c);
        const Vector3 u{p.x - q.x, p.y - q.y, p.z - q.z}, v{r.x - q.x, r.y - q.y, r.z - q.z};
        const Vector3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
        area = 0.5 * std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
        const double lengths = std::sqrt((u.x * u.x + u.y * u.y + u.z * u.z) * (v.x * v.x + v.y * v.y + v.z * v.z));
        cosine = lengths > 0 ? (u.x * v.x + u.y * v.y + u.z * v.z) / lengths : 0;
    } else {
        area = effective_area(a, b, c);
        const double ux = a.x - b.x, uy = a.y - b.y, vx = c.x - b.x, vy = c.y - b.y;
        const double lengths = std::sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy));
        cosine = lengths > 0 ? (ux * vx + uy * vy) / lengths : 0;
    }
    const double rank = area * (1.0 - ranking.weighting * cosine);
    // (+ 0.0: a zero area times a factor rounded below zero is −0, whose bits would order it
    // after every area where the comparisons of doubles put it with the zeros.)
    return rank >= 0.0 ? rank + 0.0 : std::numeric_limits<double>::infinity();
}

using Clock = std::chrono::steady_clock;

// Seconds since `start`, which moves on to now.
double lap(Clock::time_point& start) {
    const Clock::time_point now = Clock::now();
    const double seconds = std::chrono::duration<double>(now - start).count();
    start = now;
    return seconds;
}

enum class Verdict { remove, blocked_by_point, blocked_by_ring, blocked_by_coincidence, later };

// Vertices refused because a vertex lies in their triangle, waiting for it to go: a map under
// a lock, not arrays over all vertices — a few thousand waits per million removals.
class Waits {
public:
    void add(std::uint32_t waiter, std::uint32_t blocker) {
        const std::lock_guard lock(mutex_);
        blocker_of_[waiter] = blocker;
        waiters_of_[blocker].push_back(waiter);
    }

    // Forgets `waiter`'s wait, if it has one.
    void remove(std::uint32_t waiter) {
        const std::lock_guard lock(mutex_);
        const auto found = blocker_of_.find(waiter);
        if (found == blocker_of_.end()) return;
        std::vector<std::uint32_t>& list = waiters_of_[found->second];
        list.erase(std::find(list.begin(), list.end(), waiter));
        if (list.empty()) waiters_of_.erase(found->second);
        blocker_of_.erase(found);
    }

    bool waits(std::uint32_t waiter) {
        const std::lock_guard lock(mutex_);
        return blocker_of_.count(waiter) != 0;
    }

    void clear() {
        const std::lock_guard lock(mutex_);
        blocker_of_.clear();
        waiters_of_.clear();
    }

    // Every (waiter, blocker), in no order.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> all() {
        const std::lock_guard lock(mutex_);
        return {blocker_of_.begin(), blocker_of_.end()};
    }

    // The vertices waiting on `blocker`, in no order; their waits go on.
    std::vector<std::uint32_t> waiting_on(std::uint32_t blocker) {
        const std::lock_guard lock(mutex_);
        const auto found = waiters_of_.find(blocker);
        return found == waiters_of_.end() ? std::vector<std::uint32_t>{} : found->second;
    }

    // The vertex `waiter` waits on, or kNone.
    std::uint32_t blocker_of(std::uint32_t waiter) {
        const std::lock_guard lock(mutex_);
        const auto found = blocker_of_.find(waiter);
        return found == blocker_of_.end() ? kNone : found->second;
    }

    // The vertices waiting on `blocker`, in id order; their waits end.
    std::vector<std::uint32_t> take(std::uint32_t blocker) {
        const std::lock_guard lock(mutex_);
        std::vector<std::uint32_t> waiters;
        if (const auto found = waiters_of_.find(blocker); found != waiters_of_.end()) {
            waiters = std::move(found->second);
            waiters_of_.erase(found);
        }
        for (const std::uint32_t waiter : waiters) blocker_of_.erase(waiter);
        std::sort(waiters.begin(), waiters.end());
        return waiters;
    }

private:
    std::mutex mutex_;
    std::unordered_map<std::uint32_t, std::uint32_t> blocker_of_;
    std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> waiters_of_;
};

// A block's queue: a 4-ary min-heap over (area, id) holding each vertex once, with every
// vertex's place in it kept in `slot` (kNone when not queued), so that a vertex whose area
// changes moves in place. (A heap that took a new entry instead and skipped the stale ones as
// they came up popped each vertex two and a half times on GSHHG — issue 34.) Entries are
// unique and the order total, so the order of the pops is the same as with any other heap.
//
// What makes it cheap (issue 34: the heap was a fifth of the sweep's instructions and a fourth
// of its mispredicted branches on GSHHG): four children a node, half the levels of a binary
// heap for as many comparisons, so half the moves and slot writes; and each area kept as the
// bits of the double (non-negative, never −0: rank_of), which order as the values do, so that
// comparing two entries is integer arithmetic without a branch, and the least of four children
// is found by arithmetic on their indices, not by branches.
class BlockQueue {
public:
    bool empty() const { return heap_.empty(); }
    Ranked top() const { return {key_of(heap_.front()), id_of(heap_.front())}; }

    // Starts the queue with `vertices`, a vertex listed more than once taken once.
    template <class Area>
    void fill(std::span<const std::uint32_t> vertices, Area&& area, std::uint32_t* slot) {
        heap_.clear();
        for (const std::uint32_t v : vertices) {
            if (slot[v] != kNone) continue;
            slot[v] = static_cast<std::uint32_t>(heap_.size());
            heap_.push_back(entry_of({area(v), v}));
        }
        if (heap_.size() > 1) {
            for (std::size_t i = (heap_.size() - 2) / kArity + 1; i-- > 0;) sift_down(i, slot);
        }
    }

    // Queues v with `key`, or moves it there if it is queued.
    void set(Ranked ranked, std::uint32_t* slot) {
        const Entry entry = entry_of(ranked);
        std::size_t at = slot[ranked.id];
        if (at == kNone) {
            at = heap_.size();
            heap_.push_back(entry);
            sift_up(at, slot);
            return;
        }
        const bool up = entry < heap_[at];
        heap_[at] = entry;
        if (up) {
            sift_up(at, slot);
        } else {
            sift_down(at, slot);
        }
    }

    Ranked pop(std::uint32_t* slot) {
        const Ranked top = this->top();
        slot[top.id] = kNone;
        const Entry last = heap_.back();
        heap_.pop_back();
        if (!heap_.empty()) {
            heap_.front() = last;
            sift_down(0, slot);
        }
        return top;
    }

    // Empties the queue, its vertices no longer queued.
    void clear(std::uint32_t* slot) {
        for (const Entry entry : heap_) slot[id_of(entry)] = kNone;
        heap_.clear();
    }

private:
    // (area bits, id) as one number: id in the low 32 bits. Comparing two is a subtraction.
    __extension__ using Entry = unsigned __int128;
    static constexpr std::size_t kArity = 4;

    static Entry entry_of(Ranked ranked) { return Entry{std::bit_cast<std::uint64_t>(ranked.key)} << 32 | ranked.id; }
    static std::uint32_t id_of(Entry entry) { return static_cast<std::uint32_t>(entry); }
    static double key_of(Entry entry) { return std::bit_cast<double>(static_cast<std::uint64_t>(entry >> 32)); }

    void sift_up(std::size_t at, std::uint32_t* slot) {
        const Entry entry = heap_[at];
        while (at > 0) {
            const std::size_t parent = (at - 1) / kArity;
            if (!(entry < heap_[parent])) break;
            heap_[at] = heap_[parent];
            slot[id_of(heap_[at])] = static_cast<std::uint32_t>(at);
            at = parent;
        }
        heap_[at] = entry;
        slot[id_of(entry)] = static_cast<std::uint32_t>(at);
    }

    void sift_down(std::size_t at, std::uint32_t* slot) {
        const Entry entry = heap_[at];
        const std::size_t size = heap_.size();
        const Entry* const heap = heap_.data();
        for (;;) {
            const std::size_t first = kArity * at + 1;
            if (first >= size) break;
            std::size_t child;
            Entry least;
            if (first + kArity <= size) {
                // A full node: a tournament of indices, chosen by arithmetic (a choice between
                // two 128-bit values would be a branch).
                const std::size_t left = first + std::size_t{heap[first + 1] < heap[first]};
                const std::size_t right = first + 2 + std::size_t{heap[first + 3] < heap[first + 2]};
                const std::size_t far = std::size_t{0} - std::size_t{heap[right] < heap[left]};  // all ones or zero
                child = left ^ ((left ^ right) & far);
                least = heap[child];
            } else {
                child = first;
                least = heap[first];
                for (std::size_t c = first + 1; c < size; ++c) {
                    if (heap[c] < least) {
                        least = heap[c];
                        child = c;
                    }
                }
            }
            if (!(least < entry)) break;
            heap_[at] = least;
            slot[id_of(least)] = static_cast<std::uint32_t>(at);
            at = child;
        }
        heap_[at] = entry;
        slot[id_of(entry)] = static_cast<std::uint32_t>(at);
    }

    std::vector<Entry> heap_;
};

// What one thread accumulates while it works through blocks.
struct Worker {
    BlockQueue queue;                                // the block's queue
    std::vector<std::vector<std::uint32_t>> later;   // per level: vertices to queue there
    std::vector<std::uint32_t> released;             // waiters outside the block whose blocker went
    std::vector<std::uint32_t> touched;              // vertices queued again (Simplifier::few_)
    std::uint32_t block = 0;                         // the block being processed
    SimplifyStats stats;
    std::uint64_t reported = 0;  // removals already added to the progress count
};

// The blocks' shift for a grid of these base cells (parallel/blocks.hpp).
unsigned block_shift(std::uint32_t base_columns, std::uint32_t base_rows) {
    const std::uint32_t side = std::max(base_columns, base_rows);
    unsigned shift = kMinShift;
    while (((side - 1) >> shift) >= kMaxBlocksPerSide) ++shift;
    return shift;
}

// Per vertex, in place of `improper` (per segment by first vertex): 1 for an interior vertex at
// an end of an improper segment or on a frozen chain — never removed.
void pin_from_improper(const MapData& map, std::vector<std::uint8_t>& improper, int threads, bool parallel) {
    const auto chains = static_cast<std::uint32_t>(map.chains.size());
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) if (parallel)
    for (std::uint32_t c = 0; c < chains; ++c) {
        const Chain& chain = map.chains[c];
        const bool frozen = map.is_frozen(c);
        // Backwards, so improper[v − 1] is still the segment's own flag when v reads it.
        for (std::uint32_t v = chain.last; v > chain.first; --v) {
            improper[v] = v < chain.last && (frozen || improper[v] || improper[v - 1]);
        }
        improper[chain.first] = 0;
    }
}

}  // namespace

namespace detail {

class Simplifier {
public:
    // `owned_points`: the control points, if they are handed over (else the map's are used).
    Simplifier(const MapData& map, const SimplifyOptions& options, std::vector<Point> owned_points = {})
        : map_(map),
          owned_points_(std::move(owned_points)),
          control_points_(owned_points_.empty() ? std::span<const Point>(map.control_points) : owned_points_),
          options_(options),
          vertex_count_(static_cast<std::uint32_t>(map.vertices.size())),
          threads_(options.threads > 0 ? options.threads : omp_get_max_threads()),
          parallel_min_(options.parallel_threshold) {}

    // A tile of a run in parts (tiles.hpp): `tile` and `plan` outlive the simplifier.
    Simplifier(const TileInput& tile, const GridPlan& plan, const SimplifyOptions& options)
        : map_(tile.map),
          control_points_(tile.map.control_points),
          options_(options),
          vertex_count_(static_cast<std::uint32_t>(tile.map.vertices.size())),
          threads_(options.threads > 0 ? options.threads : omp_get_max_threads()),
          parallel_min_(options.parallel_threshold),
          tile_(&tile),
          plan_(&plan) {}

    SimplifyResult run() {
        auto start = Clock::now();
        set_up();
        stats_.seconds_index = lap(start);
        stop_if_cancelled(options_.cancel);
        {
            std::vector<std::uint8_t> pinned = find_improper_segments(map_, options_.arithmetic, stats_.predicates, threads_);
            pin_from_improper(map_, pinned, threads_, vertex_count_ >= parallel_min_);
            pin(pinned);
        }  // (a byte a vertex not held through the sweep)
        stats_.seconds_crossings = lap(start);
        simplify_vertices();
        stats_.seconds_sweep = lap(start);
        return finish();
    }

    // ---- runs in parts (tiles.hpp): a tile --------------------------------------------------

    // A tile: set up in the state the whole map gives, its candidates listed by level.
    void start_tile() {
        const TileInput& tile = *tile_;
        set_up();
        state_.resize(vertex_count_);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) state_[v] = static_cast<State>(tile.state[v]);
        has_waiters_.assign(vertex_count_, 0);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (state_[v] != State::removed) continue;  // (a tile gets live vertices only, but it may be told otherwise)
            grid_->remove(v);
            if (prev_[v] != kNone) next_[prev_[v]] = next_[v];
            if (next_[v] != kNone) prev_[next_[v]] = prev_[v];
        }
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) orientation_[c] = tile.orientation[c];
        later_.assign(levels_ + 1, {});
        work_ = static_cast<double>(vertex_count_);
        use_marks_ = tile.marks;
        marked_ = tile.marks ? tile.marked : std::vector<std::uint8_t>(vertex_count_, 0);
        bound_ = {tile.bound_key, kNone};  // (its id is compared as a whole-map id: past_bound)
        for (const auto& [waiter, blocker] : tile.waits) wait_on(waiter, blocker);
        if (tile.first_level == 0) {
            schedule_queued();
        } else {
            for (std::size_t k = 0; k < tile.later.size() && tile.first_level + k < levels_; ++k) later_[tile.first_level + k] = tile.later[k];
        }
        slot_.assign(vertex_count_, kNone);
        initial_distinct_ = distinct_;
        initial_orientation_ = orientation_;
        if (!tile.cut_end.empty()) {
            cut_end_ = tile.cut_end;
            for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
                if (whole_level_[c] != kOpen) pieces_of_[tile.chain_id[c]].push_back(c);
            }
            for (std::size_t k = 0; k < tile.outside.size(); ++k) outside_at_[std::uint64_t{tile.outside[k].chain} << 8 | tile.outside[k].level] = k;
        }
    }

    std::vector<RingLocations> open_rings(unsigned level) const {
        std::vector<RingLocations> open;
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            if (!split_over_tiles(c) || tile_->settled[c] || whole_level_[c] <= level) continue;
            RingLocations ring{tile_->chain_id[c], {}};
            for_each_fixed_location(c, level, 4, [&](Point q) { ring.locations.push_back(q); });
            open.push_back(std::move(ring));
        }
        return open;
    }

    void run_tile_level(unsigned level, std::span<const std::uint32_t> clear) {
        if (later_[level].empty()) return;
        outside_clear_ = clear;
        process_level(level);
        outside_clear_ = {};
        stop_if_cancelled(options_.cancel);
    }

    bool inside_tile(std::uint32_t v) const {
        const unsigned shift = tile_->level;
        return ((block_xy_[v] >> 16) >> shift) == tile_->column && ((block_xy_[v] & 0xffffu) >> shift) == tile_->row;
    }

    TileOutcome finish_tile() {
        TileOutcome out;
        const auto id = [&](std::uint32_t v) { return tile_->vertex_id[v]; };
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (!inside_tile(v) || static_cast<std::uint8_t>(state_[v]) == tile_->state[v]) continue;
            out.ids.push_back(id(v));
            out.states.push_back(static_cast<std::uint8_t>(state_[v]));
        }
        for (const auto& [waiter, blocker] : waits_.all()) out.waits.emplace_back(id(waiter), id(blocker));
        std::sort(out.waits.begin(), out.waits.end());
        for (unsigned level = tile_->level; level < levels_; ++level) {
            std::vector<std::uint32_t> list;
            for (const std::uint32_t v : later_[level]) list.push_back(id(v));
            out.later.push_back(std::move(list));
        }
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            const std::uint32_t lost = initial_distinct_[c] - distinct_[c];  // (modulo 2^32: pieces start at 0)
            if (whole_level_[c] != kOpen && lost != 0) out.locations_lost.emplace_back(tile_->chain_id[c], lost);
            if (orientation_[c] != initial_orientation_[c]) {
                out.oriented.push_back(tile_->chain_id[c]);
                out.orientations.push_back(orientation_[c]);
            }
        }
        out.stats = stats_;
        out.exhausted = exhausted_.load(std::memory_order_relaxed);
        return out;
    }

    // ---- runs in parts: the whole map (MapInParts) -----------------------------------------

    // Set up and pinned; `tile_level` capped at the levels.
    unsigned start_parts(unsigned tile_level) {
        set_up_parts();
        std::vector<std::uint8_t> pinned = find_improper_segments(map_, options_.arithmetic, stats_.predicates, threads_, options_.cancel);
        stop_if_cancelled(options_.cancel);
        pin_from_improper(map_, pinned, threads_, vertex_count_ >= parallel_min_);
        pin(pinned);
        tile_level_ = std::min(tile_level, levels_);
        goal_ = removal_goal(options_.stop, vertex_count_);
        if (!is_count_target(options_.stop.target) || sweeps_as_max(goal_)) {
            start_single_sweep();
        } else {
            marked_.assign(vertex_count_, 0);
            later_.assign(levels_ + 1, {});
            stats_.removal_goal = goal_;
            work_ = static_cast<double>(goal_);
            use_marks_ = true;
        }
        slot_.assign(vertex_count_, kNone);
        return tile_level_;
    }

    // Before the first round: the tile level start_parts set, changed (capped at the levels).
    unsigned set_tile_level(unsigned tile_level) {
        if (rounds_started_ != 0 || stats_.rounds != 0) throw std::logic_error("a run in parts' tile level changed after its first round");
        tile_level_ = std::min(tile_level, levels_);
        return tile_level_;
    }

    // `here_below`: a round of a count target whose budget is smaller runs here, whole.
    bool next_part_round(std::uint64_t here_below) {
        if (!use_marks_) return rounds_started_++ == 0;
        if (!(stats_.removed < goal_) || !mark_smallest(goal_ - stats_.removed)) return false;
        ++stats_.rounds;
        round_here_ = round_budget_ < here_below;
        return true;
    }

    // This round's tiles (split_round): per tile (numbers row-major) its pieces, control points
    // (indices) and waits (whole-map ids), each from its start; the groups that run (indices).
    struct TilePiece {
        enum Kind : std::uint8_t { run, ring };
        std::uint32_t chain;
        std::uint32_t start;   // a run's first live vertex
        std::uint32_t points;  // the vertices the tile gets for it (a run's with its cut ends)
        Kind kind;
        std::uint8_t settled;  // a run of a split ring that its cut ends settle
    };
    struct RoundSplit {
        std::vector<std::uint32_t> tiles, piece_start, point_start, points, wait_start;
        std::vector<TilePiece> pieces;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;
        std::vector<std::vector<std::uint32_t>> groups;
        std::vector<std::uint64_t> group_points;  // per group: its tiles' vertices and control points
    };

    // The round's tiles (those of the tile level holding a live vertex), found without building
    // them: each tile's pieces of chains and whole rings, its control points and the waits among
    // its vertices, and the groups that run (tiles sharing a split ring that its cut ends do not
    // settle run together; a group with nothing to do in the round is left out). Returns how many
    // groups run; round_group(k) then builds one (a copy of its tiles' share of the live map,
    // made when it is sent, so that the whole round's tiles never exist at once).
    std::size_t split_round() {
        split_ = {};
        if (round_here_) {
            set_running_tiles({});
            return 0;
        }
        const unsigned t = tile_level_;
        const auto marked = [&](std::uint32_t v) { return use_marks_ && marked_[v] != 0; };
        // Pieces in chain order, tagged with their tile; sorted by tile below (stably: each
        // tile's pieces stay in chain order).
        std::vector<std::pair<std::uint32_t, TilePiece>> tagged;
        std::vector<std::uint32_t> busy_tiles;  // (tile numbers with a marked vertex)
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            const Chain& chain = map_.chains[c];
            if (whole_level_[c] != kOpen && whole_level_[c] <= t) {
                // A ring inside one tile: its live vertices, and the input ring's orientation if
                // the round may bring it down to 4 distinct locations, where the ring rule asks.
                const std::uint32_t k = tile_of(chain.first);
                know_orientation_if_asked(c);
                TilePiece& piece = tagged.emplace_back(k, TilePiece{c, chain.first, 0, TilePiece::ring, 0}).second;
                bool any = false;
                for_each_piece_vertex(piece, k, [&](std::uint32_t v, bool) {
                    ++piece.points;
                    any = any || marked(v);
                });
                if (any) busy_tiles.push_back(k);
                continue;
            }
            // A split ring's cut ends: both ends of every live segment across a tile border.
            bool settled = false;
            if (whole_level_[c] != kOpen) {
                FirstLocations<4> ends;
                for (std::uint32_t u = chain.first; next_[u] != kNone && ends.count < 4; u = next_[u]) {
                    if (tile_of(u) == tile_of(next_[u])) continue;
                    for (const std::uint32_t w : {u, next_[u]}) ends.add(map_.vertices[w]);
                }
                settled = ends.count == 4;
            }
            // Runs of live vertices in one tile, each with its cut ends.
            for (std::uint32_t u = chain.first; u != kNone;) {
                const std::uint32_t k = tile_of(u);
                TilePiece& piece = tagged.emplace_back(k, TilePiece{c, u, 0, TilePiece::run, static_cast<std::uint8_t>(settled ? 1 : 0)}).second;
                bool any = false;
                std::uint32_t last = u;  // the run's last vertex in the tile
                for_each_piece_vertex(piece, k, [&](std::uint32_t v, bool cut_end) {
                    ++piece.points;
                    if (cut_end) return;
                    any = any || marked(v);
                    last = v;
                });
                if (any) busy_tiles.push_back(k);
                u = next_[last];
            }
        }
        std::stable_sort(tagged.begin(), tagged.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        RoundSplit& split = split_;
        for (std::size_t i = 0; i < tagged.size(); ++i) {
            if (i == 0 || tagged[i].first != tagged[i - 1].first) {
                split.tiles.push_back(tagged[i].first);
                split.piece_start.push_back(static_cast<std::uint32_t>(i));
            }
            split.pieces.push_back(tagged[i].second);
        }
        split.piece_start.push_back(static_cast<std::uint32_t>(split.pieces.size()));
        std::vector<std::pair<std::uint32_t, TilePiece>>().swap(tagged);
        const auto tiles = static_cast<std::uint32_t>(split.tiles.size());
        const auto index_of = [&](std::uint32_t k) {  // a tile number's index in split.tiles, or kNone
            const auto at = std::lower_bound(split.tiles.begin(), split.tiles.end(), k);
            return at != split.tiles.end() && *at == k ? static_cast<std::uint32_t>(at - split.tiles.begin()) : kNone;
        };
        // The control points in each tile, in order (a counting sort of their indices).
        {
            const std::uint32_t columns = blocks_.blocks(0, static_cast<int>(t));
            std::vector<std::uint32_t> tile_index(std::size_t{columns} * blocks_.blocks(1, static_cast<int>(t)), kNone);
            for (std::uint32_t i = 0; i < tiles; ++i) tile_index[split.tiles[i]] = i;
            const auto point_tile = [&](Point p) { return tile_index[(block_row(p) >> t) * columns + (block_column(p) >> t)]; };
            split.point_start.assign(std::size_t{tiles} + 1, 0);
            for (const Point p : map_.control_points) {
                if (const std::uint32_t i = point_tile(p); i != kNone) ++split.point_start[i + 1];
            }
            for (std::uint32_t i = 0; i < tiles; ++i) split.point_start[i + 1] += split.point_start[i];
            split.points.resize(split.point_start[tiles]);
            std::vector<std::uint32_t> fill(split.point_start.begin(), split.point_start.end() - 1);
            for (std::uint32_t j = 0; j < map_.control_points.size(); ++j) {
                if (const std::uint32_t i = point_tile(map_.control_points[j]); i != kNone) split.points[fill[i]++] = j;
            }
        }
        // The waits among each tile's vertices (across tiles: settled in finish_round).
        {
            std::vector<std::pair<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>>> waits;
            for (const auto& [waiter, blocker] : waits_.all()) {
                if (tile_of(waiter) == tile_of(blocker)) waits.push_back({index_of(tile_of(waiter)), {waiter, blocker}});
            }
            std::stable_sort(waits.begin(), waits.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
            split.wait_start.assign(std::size_t{tiles} + 1, 0);
            for (const auto& wait : waits) {
                ++split.wait_start[wait.first + 1];
                split.waits.push_back(wait.second);
            }
            for (std::uint32_t i = 0; i < tiles; ++i) split.wait_start[i + 1] += split.wait_start[i];
        }
        // The groups: tiles joined by the chains of their unsettled split pieces; in a round of a
        // count target only marked vertices go, so a group without any has nothing to do.
        std::sort(busy_tiles.begin(), busy_tiles.end());
        std::vector<std::uint8_t> busy(tiles, use_marks_ ? 0 : 1);
        for (const std::uint32_t k : busy_tiles) busy[index_of(k)] = 1;
        const auto open = [&](std::uint32_t i, auto&& join) {
            for (std::uint32_t j = split.piece_start[i]; j < split.piece_start[i + 1]; ++j) {
                const TilePiece& piece = split.pieces[j];
                if (piece.kind == TilePiece::run && whole_level_[piece.chain] != kOpen && !piece.settled) join(piece.chain);
            }
        };
        std::vector<std::uint32_t> running;
        for (std::vector<std::uint32_t>& group : group_tiles(tiles, open, [&](std::uint32_t i) { return busy[i] != 0; })) {
            std::uint64_t points = 0;
            for (const std::uint32_t i : group) {
                running.push_back(split.tiles[i]);
                points += split.point_start[i + 1] - split.point_start[i];
                for (std::uint32_t j = split.piece_start[i]; j < split.piece_start[i + 1]; ++j) points += split.pieces[j].points;
            }
            split.groups.push_back(std::move(group));
            split.group_points.push_back(points);
        }
        set_running_tiles(std::move(running));
        return split.groups.size();
    }

    // Group k of the round (split_round): its tiles' inputs.
    std::vector<TileInput> round_group(std::size_t k) const {
        std::vector<TileInput> group;
        for (const std::uint32_t i : split_.groups.at(k)) group.push_back(tile_input(i));
        return group;
    }

    // Calls visit(v, cut_end) for each vertex tile k gets for `piece`, in order: a whole ring's
    // live ones, or a run of live vertices in the tile with the live vertex beyond it on either
    // side (its cut ends).
    template <class Visit>
    void for_each_piece_vertex(const TilePiece& piece, std::uint32_t k, Visit&& visit) const {
        const Chain& chain = map_.chains[piece.chain];
        if (piece.kind == TilePiece::ring) {
            for (std::uint32_t u = chain.first; u != kNone; u = next_[u]) visit(u, false);
            return;
        }
        const std::uint32_t u = piece.start;
        if (prev_[u] != kNone) visit(prev_[u], true);
        std::uint32_t w = u;
        for (;;) {
            visit(w, false);
            if (next_[w] == kNone || tile_of(next_[w]) != k) break;
            w = next_[w];
        }
        if (next_[w] != kNone) visit(next_[w], true);
    }

    std::uint32_t tile_of(std::uint32_t v) const {
        const unsigned t = tile_level_;
        return tile_number(block_xy_[v] >> 16 >> t, (block_xy_[v] & 0xffffu) >> t);
    }

    std::size_t round_group_size(std::size_t k) const { return split_.groups.at(k).size(); }
    std::uint64_t round_group_points(std::size_t k) const { return split_.group_points.at(k); }

    TileInput tile_input(std::uint32_t i) const {
        const RoundSplit& split = split_;
        const unsigned t = tile_level_;
        const std::uint32_t columns = blocks_.blocks(0, static_cast<int>(t));
        const std::uint32_t k = split.tiles[i];
        TileInput input;
        input.level = t;
        input.column = k % columns;
        input.row = k / columns;
        // The tile's ids of the vertices its waits name (sorted by whole-map id, found as added).
        std::vector<std::pair<std::uint32_t, std::uint32_t>> local;
        for (std::uint32_t j = split.wait_start[i]; j < split.wait_start[i + 1]; ++j) {
            local.push_back({split.waits[j].first, kNone});
            local.push_back({split.waits[j].second, kNone});
        }
        std::sort(local.begin(), local.end());
        local.erase(std::unique(local.begin(), local.end()), local.end());
        auto add = [&](std::uint32_t v, bool cut_end) {
            if (!cut_end && !local.empty()) {
                const auto at = std::lower_bound(local.begin(), local.end(), std::pair{v, std::uint32_t{0}});
                if (at != local.end() && at->first == v) at->second = static_cast<std::uint32_t>(input.vertex_id.size());
            }
            input.map.vertices.push_back(map_.vertices[v]);
            input.vertex_id.push_back(global(v));
            input.state.push_back(static_cast<std::uint8_t>(cut_end ? State::fixed : state_[v]));
            if (use_marks_) input.marked.push_back(cut_end ? 0 : marked_[v]);
        };
        // Every array at its size before it is filled (no growing copies: the round's tiles hold
        // every live vertex).
        std::size_t vertices = 0;
        for (std::uint32_t j = split.piece_start[i]; j < split.piece_start[i + 1]; ++j) vertices += split.pieces[j].points;
        const std::size_t chains = split.piece_start[i + 1] - split.piece_start[i];
        input.map.vertices.reserve(vertices);
        input.vertex_id.reserve(vertices);
        input.state.reserve(vertices);
        if (use_marks_) input.marked.reserve(vertices);
        input.map.chains.reserve(chains);
        input.chain_id.reserve(chains);
        input.whole_level.reserve(chains);
        input.settled.reserve(chains);
        input.distinct.reserve(chains);
        input.orientation.reserve(chains);
        input.map.control_points.reserve(split.point_start[i + 1] - split.point_start[i]);
        for (std::uint32_t j = split.piece_start[i]; j < split.piece_start[i + 1]; ++j) {
            const TilePiece& piece = split.pieces[j];
            const std::uint32_t c = piece.chain;
            const auto first = static_cast<std::uint32_t>(input.vertex_id.size());
            for_each_piece_vertex(piece, k, add);
            const auto last = static_cast<std::uint32_t>(input.vertex_id.size() - 1);
            input.map.chains.push_back({first, last});
            input.chain_id.push_back(c);
            input.whole_level.push_back(whole_level_[c] == kOpen ? kOpenChain : whole_level_[c]);
            input.settled.push_back(piece.settled);
            const bool whole = piece.kind != TilePiece::run;
            input.distinct.push_back(whole ? distinct_[c] : 0);
            input.orientation.push_back(whole ? orientation_[c] : std::int8_t{2});
        }
        for (std::uint32_t j = split.point_start[i]; j < split.point_start[i + 1]; ++j) {
            input.map.control_points.push_back(map_.control_points[split.points[j]]);
        }
        const auto local_id = [&](std::uint32_t v) {
            return std::lower_bound(local.begin(), local.end(), std::pair{v, std::uint32_t{0}})->second;
        };
        for (std::uint32_t j = split.wait_start[i]; j < split.wait_start[i + 1]; ++j) {
            input.waits.emplace_back(local_id(split.waits[j].first), local_id(split.waits[j].second));
        }
        std::sort(input.waits.begin(), input.waits.end());
        input.marks = use_marks_;
        input.bound_key = bound_.key;
        input.bound_id = bound_.id;
        return input;
    }

    // The tiles' outcomes into the whole map and the waits across tiles settled (or, for a round
    // run here, the whole round). Returns whether the levels from the tile level up have
    // candidates (top_input); if not, the round is over.
    bool finish_part_tiles(std::span<const TileOutcome> outcomes) {
        if (round_here_) {
            // The single process's round.
            ensure_grid();
            schedule_queued();
            sweep();
            keep_undecided();
            return false;
        }
        const unsigned t = tile_level_;
        // The waits the tiles did not hold (across tiles), or whose tile did not run this round.
        std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;
        for (const auto& [waiter, blocker] : waits_.all()) {
            const std::uint32_t k = tile_of(waiter);
            if (k != tile_of(blocker) || !std::binary_search(running_.begin(), running_.end(), k)) waits.emplace_back(waiter, blocker);
        }
        for (const TileOutcome& tile : outcomes) {
            take_outcome(tile);
            for (const auto& [waiter, blocker] : tile.waits) waits.emplace_back(local_id(waiter), local_id(blocker));
            for (std::size_t k = 0; k < tile.later.size() && t + k < levels_; ++k) {
                for (const std::uint32_t v : tile.later[k]) later_[t + k].push_back(local_id(v));
            }
        }
        // A wait across tiles holds while its waiter still waits (else its triangle changed) and
        // its blocker is there; a waiter whose blocker went is queued again.
        waits_.clear();
        std::sort(waits.begin(), waits.end());
        for (const auto& [waiter, blocker] : waits) {
            if (state_[waiter] != State::waiting) continue;
            if (state_[blocker] == State::removed) {
                state_[waiter] = State::queued;
            } else {
                wait_on(waiter, blocker);
            }
        }
        const bool top = std::any_of(later_.begin() + t, later_.begin() + levels_, [](const auto& list) { return !list.empty(); });
        if (!top && use_marks_) keep_undecided();
        return top;
    }

    // A tile's outcome into the whole map: its vertices' states, rings and counts.
    void take_outcome(const TileOutcome& tile) {
        for (std::size_t k = 0; k < tile.ids.size(); ++k) {
            const std::uint32_t v = local_id(tile.ids[k]);
            const auto now = static_cast<State>(tile.states[k]);
            if (now == State::removed && state_[v] != State::removed) {
                if (grid_) grid_->remove(v);
                next_[prev_[v]] = next_[v];
                prev_[next_[v]] = prev_[v];
            }
            state_[v] = now;
        }
        for (const auto& [chain, lost] : tile.locations_lost) distinct_[chain] -= lost;
        for (std::size_t k = 0; k < tile.oriented.size(); ++k) orientation_[tile.oriented[k]] = tile.orientations[k];
        add(stats_, tile.stats);
    }

    // The levels from the tile level up as one more tile: the block of the level above the top
    // (the whole map), over the live vertices only (with a ring's input orientation when the ring
    // rule may ask for it), with the candidates the tiles left for those levels and the control
    // points that can lie in a triangle there (`every_point`: all of them). Every such triangle is three
    // consecutive live vertices of a run of unfixed ones between two fixed ones (fixed vertices
    // never go): a control point outside the boxes of those runs never counts, and one inside
    // is kept (the boxes are marked on the level-0 blocks, a superset).
    TileInput top_input(bool every_point = false) {
        const unsigned t = tile_level_;
        TileInput input;
        input.level = levels_;
        input.first_level = t;
        const auto mark_of = [&](std::uint32_t v) { return use_marks_ ? marked_[v] : std::uint8_t{0}; };
        const std::uint32_t columns = blocks_.blocks(0, 0), rows = blocks_.blocks(1, 0);
        std::vector<std::int32_t> cover(every_point ? 0 : std::size_t{columns + 1} * (rows + 1), 0);  // 2D differences over level-0 blocks
        const auto add_box = [&](std::uint32_t c0, std::uint32_t r0, std::uint32_t c1, std::uint32_t r1) {
            const std::size_t w = columns + 1;
            ++cover[r0 * w + c0];
            --cover[r0 * w + c1 + 1];
            --cover[(r1 + 1) * w + c0];
            ++cover[(r1 + 1) * w + c1 + 1];
        };
        for (std::uint32_t c = 0; c < map_.chains.size(); ++c) {
            const Chain& chain = map_.chains[c];
            const auto first = static_cast<std::uint32_t>(input.vertex_id.size());
            const auto take = [&](std::uint32_t v) {
                input.map.vertices.push_back(map_.vertices[v]);
                input.vertex_id.push_back(global(v));
                input.state.push_back(static_cast<std::uint8_t>(state_[v]));
                if (use_marks_) input.marked.push_back(mark_of(v));
            };
            // (The live vertices only: a ring whose input orientation may be asked for, or, for a
            // run going on over the live vertices, every ring, gets it now.)
            if (whole_level_[c] != kOpen) {
                if (every_point) {
                    know_orientation(c);
                } else {
                    know_orientation_if_asked(c);
                }
            }
            for (std::uint32_t u = chain.first; u != kNone; u = next_[u]) take(u);
            // The runs of unfixed live vertices, each with the fixed vertex on either side.
            std::uint32_t c0 = kNone, r0 = kNone, c1 = 0, r1 = 0;
            bool open = false;
            for (std::uint32_t u = every_point ? kNone : chain.first; u != kNone; u = next_[u]) {
                const std::uint32_t xy = block_xy_[u];
                c0 = std::min(c0, xy >> 16);
                c1 = std::max(c1, xy >> 16);
                r0 = std::min(r0, xy & 0xffffu);
                r1 = std::max(r1, xy & 0xffffu);
                if (state_[u] != State::fixed) {
                    open = true;
                    continue;
                }
                if (open) add_box(c0, r0, c1, r1);
                c0 = c1 = xy >> 16;
                r0 = r1 = xy & 0xffffu;
                open = false;
            }
            input.map.chains.push_back({first, static_cast<std::uint32_t>(input.vertex_id.size() - 1)});
            input.chain_id.push_back(c);
            input.whole_level.push_back(whole_level_[c] == kOpen ? kOpenChain : whole_level_[c]);
            input.settled.push_back(0);
            input.distinct.push_back(distinct_[c]);
            input.orientation.push_back(orientation_[c]);
        }
        if (every_point) {
            input.map.control_points.assign(indexed_points_.begin(), indexed_points_.end());
        } else {
            const std::size_t w = columns + 1;
            for (std::uint32_t r = 0; r <= rows; ++r) {
                for (std::uint32_t c = 0; c <= columns; ++c) {
                    std::int32_t& at = cover[r * w + c];
                    if (c > 0) at += cover[r * w + c - 1];
                    if (r > 0) at += cover[(r - 1) * w + c];
                    if (c > 0 && r > 0) at -= cover[(r - 1) * w + c - 1];
                }
            }
            for (const Point p : indexed_points_) {
                if (cover[block_row(p) * w + block_column(p)] > 0) input.map.control_points.push_back(p);
            }
        }
        const auto local = [&](std::uint32_t v) {  // (an engine id: its index in the input)
            const std::uint32_t id = global(v);
            const auto at = std::lower_bound(input.vertex_id.begin(), input.vertex_id.end(), id);
            return at != input.vertex_id.end() && *at == id ? static_cast<std::uint32_t>(at - input.vertex_id.begin()) : kNone;
        };
        for (const auto& [waiter, blocker] : waits_.all()) input.waits.emplace_back(local(waiter), local(blocker));
        std::sort(input.waits.begin(), input.waits.end());
        for (unsigned level = t; level < levels_; ++level) {
            std::vector<std::uint32_t>& list = input.later.emplace_back();
            for (const std::uint32_t v : later_[level]) {
                if (state_[v] != State::removed) list.push_back(local(v));
            }
        }
        input.marks = use_marks_;
        input.bound_key = bound_.key;
        input.bound_id = bound_.id;
        return input;
    }

    // The levels from the tile level up as one more tile over a subset of the live vertices
    // (top_subset.hpp), instead of all of them (top_input).
    TileInput top_subset_input(std::uint32_t runs) {
        ensure_grid();
        // The live map as the subset's source: every live vertex known.
        class Live {
        public:
            explicit Live(Simplifier& s) : s_(s) {}
            bool known(std::uint32_t) const { return true; }
            void learn(std::vector<std::uint32_t>) const {}
            bool gone(std::uint32_t u) const { return s_.state_[u] == State::removed; }
            std::uint32_t prev(std::uint32_t u) const { return s_.prev_[u]; }
            std::uint32_t next(std::uint32_t u) const { return s_.next_[u]; }
            std::uint32_t chain(std::uint32_t u) const { return s_.chain_of_[u]; }
            Point point(std::uint32_t u) const { return s_.map_.vertices[u]; }
            std::uint8_t state(std::uint32_t u) const { return static_cast<std::uint8_t>(s_.state_[u]); }
            std::uint8_t marked(std::uint32_t u) const { return s_.marked_[u]; }
            bool shared(std::uint32_t u) const { return s_.shared_[u] != 0; }
            std::uint32_t blocker(std::uint32_t u) const { return s_.waits_.blocker_of(u); }
            std::vector<std::uint32_t> waiters(std::uint32_t u) const { return s_.waits_.waiting_on(u); }
            std::uint8_t whole_level(std::uint32_t c) const { return s_.whole_level_[c]; }
            std::uint32_t distinct(std::uint32_t c) const { return s_.distinct_[c]; }
            std::int8_t orientation(std::uint32_t c) const { return s_.orientation_[c]; }
            void learn_rings(const std::vector<std::uint32_t>&) const {}
            std::uint32_t ring_first(std::uint32_t c) const { return s_.map_.chains[c].first; }
            const std::vector<std::uint32_t>& later(unsigned k) const { return s_.later_[s_.tile_level_ + k]; }
            void in_boxes(const std::vector<Box>& boxes, const std::vector<std::uint32_t>& skip, std::unordered_set<std::uint32_t>& lone,
                          std::vector<std::uint32_t>& control) const {
                for (const Box& box : boxes) {
                    s_.grid_->any_in_cells(box, [&](std::uint32_t id, Point q) {
                        if (q.y < box.min_y || q.y > box.max_y) return false;
                        if (id >= s_.vertex_count_) {
                            control.push_back(id - s_.vertex_count_);
                        } else if (!std::binary_search(skip.begin(), skip.end(), id)) {
                            lone.insert(id);
                        }
                        return false;
                    });
                }
            }
            Point control_point(std::uint32_t k) const { return s_.indexed_points_[k]; }
            std::uint32_t id(std::uint32_t u) const { return s_.global(u); }
            void ring_piece(std::uint32_t c) const {
                if (!s_.resumed_) s_.know_orientation_if_asked(c);
            }
            // A cut ring's fixed locations outside the runs, walked.
            void outside(const std::vector<std::uint32_t>& rings, const std::vector<std::uint32_t>& runs, unsigned t, TileInput& input) const {
                for (const std::uint32_t c : rings) {
                    for (unsigned level = t; level < s_.whole_level_[c]; ++level) {
                        FirstLocations<4> found;
                        for (std::uint32_t u = s_.map_.chains[c].first; u != kNone && found.count < 4; u = s_.next_[u]) {
                            if (!std::binary_search(runs.begin(), runs.end(), u) && (s_.state_[u] == State::fixed || s_.level_of(u) > level)) {
                                found.add(s_.map_.vertices[u]);
                            }
                        }
                        input.outside.push_back({c, level, std::vector<Point>(found.at, found.at + found.count)});
                    }
                }
            }
            bool marks() const { return s_.use_marks_; }
            double bound_key() const { return s_.bound_.key; }
            std::uint32_t bound_id() const { return s_.bound_.id; }

        private:
            Simplifier& s_;
        };
        Live live(*this);
        subset_waiters_.clear();
        return subset::build(live, runs, tile_level_, levels_, &subset_waiters_);
    }

    // The outcome of top_subset_input's tile into the whole map, the round then over; false
    // (nothing taken) if its runs were too short.
    bool finish_part_top_subset(const TileOutcome& top) {
        if (top.exhausted) return false;
        take_outcome(top);
        for (const std::uint32_t u : subset_waiters_) waits_.remove(u);
        for (const auto& [waiter, blocker] : top.waits) wait_on(local_id(waiter), local_id(blocker));
        subset_waiters_.clear();
        for (unsigned level = tile_level_; level < levels_; ++level) std::vector<std::uint32_t>().swap(later_[level]);
        if (use_marks_) keep_undecided();
        return true;
    }

    // The levels from the tile level up here, over the whole map (instead of top_input); the
    // round is over.
    void run_part_top_here() {
        for (unsigned level = tile_level_; level < levels_; ++level) {
            if (later_[level].empty()) continue;
            ensure_grid();
            process_level(level);
            stop_if_cancelled(options_.cancel);
        }
        if (use_marks_) keep_undecided();
    }

    // ---- runs in parts over the live vertices only ------------------------------------------

    // This engine, over the live vertices and every control point of a run in parts (its
    // engine's top_input(true), this engine's tile), takes over that run (parts_progress: where
    // it stands), in a round whose tiles are done: the levels from the tile level up are next.
    // Its ids are indices into the live vertices, in the whole map's order, so every tie breaks
    // as before; ids it hands out or takes in (tiles, outcomes, the round's bound) are the whole
    // map's. Every ring's input orientation is known (it has none of the removed vertices).
    struct PartsProgress {
        unsigned tile_level;
        std::uint64_t goal, round_budget;
        unsigned rounds_started;
        SimplifyStats stats;
        Ranked bound;
        double work;
    };
    PartsProgress parts_progress() const { return {tile_level_, goal_, round_budget_, rounds_started_, stats_, bound_, work_}; }

    void resume_parts(const PartsProgress& before) {
        resumed_ = true;
        start_tile();
        tile_level_ = before.tile_level;
        goal_ = before.goal;
        rounds_started_ = before.rounds_started;
        round_budget_ = before.round_budget;
        stats_ = before.stats;
        bound_ = before.bound;
        work_ = before.work;
        compacted_at_ = stats_.removed;
    }

    std::uint32_t vertex_count() const { return vertex_count_; }
    const SimplifyOptions& options() const { return options_; }

    // A vertex's whole-map id, and back (after resume_parts: a live vertex's index).
    std::uint32_t global(std::uint32_t v) const { return resumed_ ? tile_->vertex_id[v] : v; }
    std::uint32_t local_id(std::uint32_t id) const {
        if (!resumed_) return id;
        return static_cast<std::uint32_t>(std::lower_bound(tile_->vertex_id.begin(), tile_->vertex_id.end(), id) - tile_->vertex_id.begin());
    }

    // The top's outcome (top_input) into the whole map; the round is over.
    void finish_part_top(const TileOutcome& top) {
        take_outcome(top);
        waits_.clear();
        for (const auto& [waiter, blocker] : top.waits) wait_on(local_id(waiter), local_id(blocker));
        for (unsigned level = tile_level_; level < levels_; ++level) std::vector<std::uint32_t>().swap(later_[level]);
        if (use_marks_) keep_undecided();
    }

    // The tiles of the round that run (split_round leaves the idle ones out), by their numbers in
    // row-major order.
    void set_running_tiles(std::vector<std::uint32_t> tiles) {
        std::sort(tiles.begin(), tiles.end());
        running_ = std::move(tiles);
    }

    std::uint32_t tile_number(std::uint32_t column, std::uint32_t row) const {
        return row * blocks_.blocks(0, static_cast<int>(tile_level_)) + column;
    }

    SimplifyResult part_result() {
        if (use_marks_ || stats_.swept_as_max) stats_.target_reached = stats_.removed >= goal_;
        return finish();
    }

    // ---- set-up --------------------------------------------------------------------------

    // (Ctrl-C is heard between the steps, and inside the grid's build: a user stopping a big map
    // waits for none of them to finish.)
    void set_up() {
        index_points();
        stop_if_cancelled(options_.cancel);
        set_up_levels();
        find_shared_locations();
        stop_if_cancelled(options_.cancel);
        build_chains();
    }

    // A run in parts (MapInParts) sets up without the whole map's grid: the tiles build their
    // own, and ensure_grid one over the live vertices when the levels from the tile level up
    // first run here. Only the grid's geometry is needed now (the blocks); the rings' distinct
    // locations are counted ring by ring instead of from shared_ (which ensure_grid finds).
    // On GSHHG with 1 worker, round 1's first task then went out at 1.76–2.19 s into the run
    // instead of 2.09–2.70 s (the grid took 0.33–0.43 s of that).
    void set_up_parts() {
        geometry_ = PointGrid::Geometry::of(map_.vertices, control_points_, kPointsPerCell, kRowSplit, threads_);
        take_control_points();
        set_up_levels();
        build_chains();
    }

    // One grid over vertices (ids [0, n), removable) and control points (ids [n, n+m)); a tile's
    // over the whole map's cells that hold its points.
    void index_points() {
        if (tile_) {
            index_tile_points();
        } else {
            grid_.emplace(map_.vertices, control_points_, kPointsPerCell, threads_, kRowSplit, options_.cancel);
        }
        geometry_ = grid_->geometry();
        take_control_points();
    }

    // The control points from now on in indexed_points_ (in the grid too, once built).
    void take_control_points() {
        stats_.control_points = control_points_.size();
        indexed_points_ = control_points_;
        control_points_ = {};
        if (!owned_points_.empty()) {
            // Freed: the grid has them. (Handed over only to simplify(), which never reads them
            // again; a run in parts, which does, views the map's.)
            indexed_points_ = {};
            owned_points_ = std::vector<Point>();
        }
    }

    // A run in parts: the whole map's grid is needed only for the rounds run here and the levels
    // from the tile level up. It is built over the live vertices when first needed (after the
    // first round of tiles, a fraction of the map), answering as the grid over all of them with
    // the removed ones taken out would (PointGrid), and shared_ with it: live vertices sharing a
    // location, all that rule 3 and the subsets of the top ask (coincides_with_other_segment,
    // top_subset.hpp). Later removals leave a flag set, which only costs a look.
    void ensure_grid() {
        if (grid_) return;
        std::vector<std::uint8_t> removed(vertex_count_);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) removed[v] = state_[v] == State::removed ? 1 : 0;
        grid_.emplace(geometry_, map_.vertices, indexed_points_, removed, threads_);
        compacted_at_ = stats_.removed;
        find_shared_locations();
    }

    // Removed vertices stay in the grid, taken out, and every query reads past them; once they are
    // most of what it holds (after the first level of the first round, two thirds of GSHHG at
    // 10 %), they go.
    void compact_grid() {
        if (!grid_) return;
        const std::uint64_t gone = stats_.removed - compacted_at_;
        if (gone * 2 <= grid_->held()) return;
        grid_->compact(vertex_count_ >= parallel_min_ ? threads_ : 1);
        compacted_at_ = stats_.removed;
    }

    // The point grid's cells grouped into blocks (parallel/blocks.hpp, axis 0 the columns, axis
    // 1 the rows): 2^shift × 2^shift cells at level 0, levels up to one block.
    void set_up_levels() {
        blocks_.cells = {geometry_.base_columns, geometry_.base_rows};
        blocks_.shift = static_cast<int>(block_shift(geometry_.base_columns, geometry_.base_rows));
        levels_ = static_cast<unsigned>(blocks_.top_level()) + 1;
        stats_.levels = levels_;
    }

    // The window of the plan's cells that the tile's own points (vertices inside it and control
    // points) fall in; cut ends beyond the border are held in its edge cells (PointGrid).
    void index_tile_points() {
        const PointGrid::Geometry& g = plan_->grid;
        PointGrid::Window window{kNone, kNone, 0, 0};
        auto take = [&](Point p) {
            const std::uint32_t x = g.column(p.x), y = g.row(p.y);
            window = {std::min(window.first_column, x), std::min(window.first_row, y), std::max(window.last_column, x),
                      std::max(window.last_row, y)};
        };
        for (const Point p : map_.vertices) {
            if (plan_->block_column(p, tile_->level) == tile_->column && plan_->block_row(p, tile_->level) == tile_->row) take(p);
        }
        for (const Point p : control_points_) take(p);
        if (window.first_column == kNone) window = {0, 0, 0, 0};
        grid_.emplace(g, window, map_.vertices, control_points_, threads_);
    }

    std::uint32_t block_column(Point p) const { return blocks_.block(geometry_.base_column(p.x), 0); }
    std::uint32_t block_row(Point p) const { return blocks_.block(geometry_.base_row(p.y), 0); }

    // The finest level at which two vertices fall in one block.
    unsigned shared_level(std::uint32_t u, std::uint32_t w) const {
        const std::uint32_t a = block_xy_[u], b = block_xy_[w];
        return static_cast<unsigned>(std::max(Blocks::shared_level(a >> 16, b >> 16), Blocks::shared_level(a & 0xffffu, b & 0xffffu)));
    }

    // The level an interior vertex is removable at, given its current neighbours. Removals at a
    // level only bring in neighbours from the same block: a vertex removable at the level being
    // processed stays so, and one above it stays above it (it may drop below it).
    unsigned level_of(std::uint32_t v) const { return std::max(shared_level(v, prev_[v]), shared_level(v, next_[v])); }

    // Vertex v's block of `level`, numbered row-major: over the whole map, or in a tile (whose
    // levels are below its own) over the tile's blocks only, so that the work per level scales
    // with the tile, not with the whole map (a map cut into a thousand tiles otherwise spent most
    // of each task walking the whole map's empty blocks).
    std::uint32_t block_at(std::uint32_t v, unsigned level) const {
        const std::uint32_t column = (block_xy_[v] >> 16) >> level, row = (block_xy_[v] & 0xffffu) >> level;
        const BlockSpan span = blocks_of(level);
        return (row - span.first_row) * span.columns + (column - span.first_column);
    }

    std::uint32_t blocks_at(unsigned level) const {
        const BlockSpan span = blocks_of(level);
        return span.columns * span.rows;
    }

    // The blocks of `level` that block_at numbers: the whole map's, or those of the whole map's
    // that lie in the tile.
    struct BlockSpan {
        std::uint32_t first_column, first_row, columns, rows;
    };
    BlockSpan blocks_of(unsigned level) const {
        const auto l = static_cast<int>(level);
        if (!tile_) return {0, 0, blocks_.blocks(0, l), blocks_.blocks(1, l)};
        const unsigned shift = tile_->level - level;
        const std::uint32_t column = tile_->column << shift, row = tile_->row << shift;
        return {column, row, std::min(std::uint32_t{1} << shift, blocks_.blocks(0, l) - column),
                std::min(std::uint32_t{1} << shift, blocks_.blocks(1, l) - row)};
    }

    // Linked lists over the vertices and ring bookkeeping: distinct locations, and the level
    // from which the whole ring lies in one block.
    void build_chains() {
        prev_.assign(vertex_count_, kNone);
        next_.assign(vertex_count_, kNone);
        chain_of_.assign(vertex_count_, 0);
        block_xy_.resize(vertex_count_);
        const auto chains = static_cast<std::uint32_t>(map_.chains.size());
        distinct_.assign(chains, 0);
        orientation_.assign(chains, 2);  // 2: not computed yet
        whole_level_.assign(chains, kOpen);
        ring_clear_.assign(chains, 0);
#pragma omp parallel num_threads(threads_) if (vertex_count_ >= parallel_min_)
        {
            std::vector<std::uint32_t> table;  // (count_locations' scratch)
#pragma omp for schedule(dynamic, 64)
            for (std::uint32_t c = 0; c < chains; ++c) {
                const Chain& chain = map_.chains[c];
                std::uint32_t min_column = kNone, max_column = 0, min_row = kNone, max_row = 0;
                for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
                    chain_of_[v] = c;
                    if (v > chain.first) prev_[v] = v - 1;
                    if (v < chain.last) next_[v] = v + 1;
                    const std::uint32_t column = block_column(map_.vertices[v]), row = block_row(map_.vertices[v]);
                    block_xy_[v] = column << 16 | row;
                    min_column = std::min(min_column, column);
                    max_column = std::max(max_column, column);
                    min_row = std::min(min_row, row);
                    max_row = std::max(max_row, row);
                }
                if (tile_ && tile_->whole_level[c] != kOpen) {
                    whole_level_[c] = tile_->whole_level[c];  // the whole map's chain's
                    if (!split_over_tiles(c)) distinct_[c] = tile_->distinct[c];
                } else if (!tile_ && is_closed(c)) {
                    distinct_[c] = count_distinct_locations(chain, table);
                    whole_level_[c] = static_cast<std::uint8_t>(
                        std::max(Blocks::shared_level(min_column, max_column), Blocks::shared_level(min_row, max_row)));
                }
            }
        }
        split_rings_.clear();
        for (std::uint32_t c = 0; c < chains; ++c) {
            if (whole_level_[c] != kOpen && whole_level_[c] > 0) split_rings_.push_back(c);
        }
    }

    bool is_closed(std::uint32_t c) const {
        const Chain& chain = map_.chains[c];
        return chain.last > chain.first && same_location(map_.vertices[chain.first], map_.vertices[chain.last]);
    }

    // A ring's distinct locations: all its vertices but the closing one when none of the others
    // shares its location with any vertex (shared_, which says so for every vertex of the map,
    // when found: not in a run in parts' set-up); else counted.
    std::uint32_t count_distinct_locations(const Chain& chain, std::vector<std::uint32_t>& table) const {
        if (!shared_.empty()) {
            bool alone = true;
            for (std::uint32_t v = chain.first + 1; v < chain.last && alone; ++v) alone = !shared_[v];
            if (alone) return chain.last - chain.first;
        }
        return count_locations(std::span<const Point>(map_.vertices.data() + chain.first, chain.last - chain.first), table);
    }

    // Vertices whose location another vertex holds too (a node, a ring's closing vertex, a
    // duplicate, a touch), found cell by cell in the grid: only segments ending at such a
    // location can ever coincide with another segment. A cell is sorted by x, so points at one
    // location lie in one run of equal x (−0 and 0 alike), nearly always a run of one.
    void find_shared_locations() {
        shared_.assign(vertex_count_, 0);
        const std::uint32_t columns = grid_->columns(), rows = grid_->rows();
#pragma omp parallel num_threads(threads_) if (vertex_count_ >= parallel_min_)
        {
            std::vector<std::pair<std::uint64_t, std::uint32_t>> by_y;  // scratch of mark_shared
#pragma omp for schedule(dynamic, 16)
            for (std::uint32_t y = 0; y < rows; ++y) {
                for (std::uint32_t x = 0; x < columns; ++x) {
                    const auto ids = grid_->cell_ids(x, y);
                    const auto points = grid_->cell_points(x, y);
                    for (std::size_t i = 0; i < ids.size();) {
                        std::size_t j = i + 1;
                        while (j < ids.size() && LocationKey(points[j]).x == LocationKey(points[i]).x) ++j;
                        if (j - i > 1) mark_shared(ids.subspan(i, j - i), points.subspan(i, j - i), by_y);
                        i = j;
                    }
                }
            }
        }
    }

    // Points of one cell with one x: the vertices among them at one y share a location (a few
    // compared pair by pair, more sorted by y).
    void mark_shared(std::span<const std::uint32_t> ids, std::span<const Point> points,
                     std::vector<std::pair<std::uint64_t, std::uint32_t>>& by_y) {
        if (ids.size() <= 8) {
            for (std::size_t a = 0; a < ids.size(); ++a) {
                for (std::size_t b = a + 1; b < ids.size(); ++b) {
                    if (ids[a] < vertex_count_ && ids[b] < vertex_count_ && LocationKey(points[a]) == LocationKey(points[b])) {
                        shared_[ids[a]] = shared_[ids[b]] = 1;
                    }
                }
            }
            return;
        }
        by_y.clear();
        for (std::size_t k = 0; k < ids.size(); ++k) {
            if (ids[k] < vertex_count_) by_y.emplace_back(LocationKey(points[k]).y, ids[k]);
        }
        std::sort(by_y.begin(), by_y.end());
        for (std::size_t k = 0; k + 1 < by_y.size(); ++k) {
            if (by_y[k].first == by_y[k + 1].first) shared_[by_y[k].second] = shared_[by_y[k + 1].second] = 1;
        }
    }

    // Vertices at either end of a segment that crosses or touches another one improperly in the
    // input are never removed (see crossings.hpp for why that is enough); nor are frozen chains'.
    // `pinned`: per vertex, from pin_from_improper (or the whole map's, for a tile).
    void pin(std::span<const std::uint8_t> pinned) {
        state_.assign(vertex_count_, State::fixed);
        std::uint64_t pinned_count = 0, queued = 0;
#pragma omp parallel for schedule(static) num_threads(threads_) reduction(+ : pinned_count, queued) if (vertex_count_ >= parallel_min_)
        for (std::uint32_t v = 0; v < vertex_count_; ++v) {
            if (prev_[v] == kNone || next_[v] == kNone) continue;
            if (pinned[v]) {
                ++pinned_count;
            } else {
                state_[v] = State::queued;
                ++queued;
            }
        }
        stats_.pinned_by_crossing = pinned_count;
        queued_at_start_ = queued;
        has_waiters_.assign(vertex_count_, 0);
    }

    double area_of(std::uint32_t v) const {
        const Point a = map_.vertices[prev_[v]], b = map_.vertices[v], c = map_.vertices[next_[v]];
        // (The plain area inline: rank_of is not, and the sweep asks for an area about 3 times a removal.)
        return plain_ranking_ ? effective_area(a, b, c) : rank_of(a, b, c, options_.ranking);
    }

    // ---- the sweep -----------------------------------------------------------------------

    void simplify_vertices() {
        const std::uint64_t goal = removal_goal(options_.stop, vertex_count_);
        marked_.assign(vertex_count_, 0);
        later_.assign(levels_ + 1, {});
        if (!is_count_target(options_.stop.target) || sweeps_as_max(goal)) {
            start_single_sweep();
            schedule_queued(true);
            sweep();
            if (stats_.swept_as_max) stats_.target_reached = stats_.removed >= goal;
            return;
        }
        stats_.removal_goal = goal;
        work_ = static_cast<double>(goal);
        use_marks_ = true;
        auto start = Clock::now();
        while (stats_.removed < goal && select_round(goal - stats_.removed)) {
            ++stats_.rounds;
            RoundTimes& round = stats_.round_times.emplace_back();
            round.removed = stats_.removed;
            round.seconds_select = lap(start);
            schedule_queued(true);
            narrow_split_rings();
            round.seconds_schedule = lap(start);
            sweep();
            narrowed_ = false;
            collect_touched_ = false;
            keep_undecided();
            round.seconds_sweep = lap(start);
            round.removed = stats_.removed - round.removed;
        }
        stats_.target_reached = stats_.removed >= goal;
    }

    // --max and --max-area: one sweep up to a fixed bound (--max's for a count target that
    // sweeps_as_max).
    void start_single_sweep() {
        marked_.assign(vertex_count_, 0);
        later_.assign(levels_ + 1, {});
        use_marks_ = false;
        const Target target = options_.stop.target;
        bound_ = {target == Target::max_area ? options_.stop.value : std::numeric_limits<double>::infinity(), kNone};
        work_ = static_cast<double>(vertex_count_);
    }

    // Whether a count target asks for at least as many removals as any run could make
    // (removable_at_most, after pin): then no round could ever stop it before every vertex that
    // can go has gone, and it runs as --max, one sweep, instead of rounds that each pay a
    // selection and the levels to end where nothing can go (GSHHG at 1 %: 22 rounds, the last 21
    // removing 0.3 % of the vertices). The result is --max's; the count is not reached unless
    // the bound is met exactly. Every way of running a map (one process, in parts, the first
    // round in stages) decides it from the same counts.
    bool sweeps_as_max(std::uint64_t goal) {
        stats_.removal_goal = goal;
        stats_.swept_as_max = goal >= removable_at_most(map_.chains, whole_level_, distinct_, queued_at_start_);
        return stats_.swept_as_max;
    }

    // Marks the `budget` queued vertices smallest in (area, id) order (all if fewer) and sets
    // the round's threshold to the largest of them. Returns false if nothing is queued.
    //
    // No (area, id) pool is kept: the areas of the queued vertices, in id order, take 8 bytes
    // each as keys (bit patterns of non-negative doubles order as the values), and the
    // budget-th smallest, K, is selected from them (parallel/select.hpp, the same selection as
    // the mesh engine's round threshold). Then every queued vertex with a smaller area is marked,
    // and of those with area K, the first ones in id order up to the budget.
    //
    // `keep_few` (one process's rounds): when the budget is a small part of the queued vertices,
    // also keep what the next round's selection needs to look at a few vertices only (few_).
    bool mark_smallest(std::uint64_t budget, bool keep_few = false) {
        few_.valid = false;
        few_.ranked.clear();
        few_.marked.clear();
        few_.touched.clear();
        const int threads = vertex_count_ >= parallel_min_ ? threads_ : 1;
        const auto share = static_cast<std::size_t>(threads);
        // Each thread's keys from offset[t], with room for every vertex its share looks at (the
        // queued ones are most of them: counting them first was a pass of its own).
        std::vector<std::size_t> offset(share + 1, 0), filled(share, 0);
        for (std::size_t t = 0; t < share; ++t) offset[t + 1] = offset[t] + undecided_count(static_cast<int>(t), threads);
        FillLater<std::uint64_t> keys(offset.back());
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            std::size_t k = offset[static_cast<std::size_t>(t)];
            for_each_undecided(t, threads, [&](std::uint32_t v) {
                marked_[v] = 0;
                if (state_[v] == State::queued) keys[k++] = std::bit_cast<std::uint64_t>(area_of(v));
            });
            filled[static_cast<std::size_t>(t)] = k - offset[static_cast<std::size_t>(t)];
        });
        std::size_t queued = 0;
        for (const std::size_t count : filled) queued += count;
        if (queued == 0) return false;
        // The budget-th smallest key (the largest when the budget takes them all), and of those
        // equal to it the first `rank` in id order: each thread's run of keys is a list.
        std::vector<std::span<const std::uint64_t>> runs(share);
        for (std::size_t t = 0; t < share; ++t) runs[t] = {keys.data() + offset[t], filled[t]};
        const std::uint64_t wanted = std::min<std::uint64_t>(budget, queued);
        round_budget_ = wanted;
        const parallel::Selection kth = parallel::select_kth(runs, wanted, threads, [](std::uint64_t own) { return own; });
        const std::uint64_t key = kth.key;
        std::uint64_t rank = wanted;
        for (const std::uint64_t less : kth.less) rank -= less;
        // The next round's: the unmarked queued vertices up to the key of rank 2 · wanted.
        const bool listed = keep_few && wanted <= queued / kFewShare;
        const std::uint64_t few_bound =
            listed ? parallel::select_kth(runs, std::min<std::uint64_t>(2 * wanted, queued), threads, [](std::uint64_t own) { return own; }).key : 0;
        std::vector<std::vector<std::uint32_t>> marked_parts(listed ? share : 0), ranked_parts(listed ? share : 0);
        // Mark: areas below the key, and the first `rank` vertices (in id order) at the key.
        std::vector<std::uint64_t> at_key(share + 1, 0);  // keys at the key in the runs before
        for (std::size_t t = 0; t < share; ++t) at_key[t + 1] = at_key[t] + kth.equal[t];
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            std::uint64_t seen = at_key[static_cast<std::size_t>(t)];
            std::size_t k = offset[static_cast<std::size_t>(t)];
            for_each_undecided(t, threads, [&](std::uint32_t v) {
                if (state_[v] != State::queued) return;
                const std::uint64_t own = keys[k++];
                if (own < key) {
                    marked_[v] = 1;
                } else if (own == key && seen < rank) {
                    marked_[v] = 1;
                    if (++seen == rank) bound_ = {std::bit_cast<double>(key), global(v)};
                }
                if (!listed) return;
                if (marked_[v]) {
                    marked_parts[static_cast<std::size_t>(t)].push_back(v);
                } else if (own <= few_bound) {
                    ranked_parts[static_cast<std::size_t>(t)].push_back(v);
                }
            });
        });
        if (listed) {
            for (std::size_t t = 0; t < share; ++t) {
                few_.marked.insert(few_.marked.end(), marked_parts[t].begin(), marked_parts[t].end());
                few_.ranked.insert(few_.ranked.end(), ranked_parts[t].begin(), ranked_parts[t].end());
            }
            few_.bound = few_bound;
            few_.valid = true;
        }
        return true;
    }

    // A round's selection in one process: from the few vertices it can be among when the last
    // round's left them (mark_few), else from every queued vertex.
    bool select_round(std::uint64_t budget) {
        if (few_.valid && mark_few(budget)) {
            ++stats_.rounds_from_few;
            collect_touched_ = true;
            return true;
        }
        const bool found = mark_smallest(budget, true);
        collect_touched_ = few_.valid;
        return found;
    }

    // mark_smallest's marks, from few_ instead of every queued vertex. A queued vertex no round
    // touched since the last selection (touched: queued again by requeue or queue_released, the
    // only ways a vertex becomes queued or its area changes) was queued then, with the key it
    // has now: marked then, or, if its key is at most few_.bound, ranked. So every queued vertex
    // of key ≤ few_.bound is ranked, marked or touched, and if at least `budget` of those are
    // queued with such a key, the budget smallest (area, id) of all queued vertices are among
    // them: the same marks, and the same bound, as the full selection. Otherwise (false) nothing
    // changed and the full selection runs. The next round's few are kept as mark_smallest keeps
    // them, from these candidates, under a bound no higher.
    bool mark_few(std::uint64_t budget) {
        std::vector<std::uint32_t>& ids = few_.ids;
        ids.clear();
        ids.insert(ids.end(), few_.ranked.begin(), few_.ranked.end());
        ids.insert(ids.end(), few_.marked.begin(), few_.marked.end());
        ids.insert(ids.end(), few_.touched.begin(), few_.touched.end());
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        std::vector<std::pair<std::uint64_t, std::uint32_t>>& ranked = few_.pairs;  // (key, id)
        ranked.clear();
        std::size_t below = 0;  // the first `below` have keys ≤ few_.bound
        for (const std::uint32_t v : ids) {
            if (state_[v] != State::queued) continue;
            const std::uint64_t key = std::bit_cast<std::uint64_t>(area_of(v));
            ranked.push_back({key, v});
            if (key <= few_.bound) std::swap(ranked[below++], ranked.back());
        }
        if (below < budget || budget == 0) {
            few_.valid = false;
            return false;
        }
        const auto first = ranked.begin(), wanted_end = first + static_cast<std::ptrdiff_t>(budget);
        const auto below_end = first + static_cast<std::ptrdiff_t>(below);
        std::nth_element(first, wanted_end - 1, below_end);
        // The marks: the last round's cleared (those still undecided, as mark_smallest clears
        // them), this round's set.
        for (const std::uint32_t v : few_.marked) {
            if (state_[v] != State::fixed && state_[v] != State::removed) marked_[v] = 0;
        }
        std::uint64_t key = 0;
        std::uint32_t last = 0;
        few_.marked.clear();
        for (auto it = first; it != wanted_end; ++it) {
            marked_[it->second] = 1;
            few_.marked.push_back(it->second);
            if (*it >= std::pair{key, last}) std::tie(key, last) = *it;
        }
        std::sort(few_.marked.begin(), few_.marked.end());
        bound_ = {std::bit_cast<double>(key), global(last)};
        round_budget_ = budget;
        // The next round's few: the unmarked up to the key of rank 2 · budget among them.
        if (below_end - wanted_end > static_cast<std::ptrdiff_t>(budget)) {
            const auto at = wanted_end + static_cast<std::ptrdiff_t>(budget) - 1;
            std::nth_element(wanted_end, at, below_end);
            few_.bound = at->first;
        }
        few_.ranked.clear();
        for (auto it = wanted_end; it != below_end; ++it) {
            if (it->first <= few_.bound) few_.ranked.push_back(it->second);
        }
        few_.touched.clear();
        return true;
    }

    // The split rings a round of a count target can ask about: those holding one of its marked
    // vertices, the only ones it judges (they are on the levels' lists once scheduled). Late
    // rounds mark a few hundred vertices where a map has a hundred thousand split rings, and
    // deciding them all (a walk along each ring, at each level) was then most of such a round's
    // time (issue 34). Used where shorter than the list of every split ring.
    void narrow_split_rings() {
        std::size_t marked = grouped_ahead_ ? grouped_.size() : 0;
        for (unsigned level = 0; level < levels_; ++level) marked += later_[level].size();
        narrowed_ = marked < split_rings_.size();
        if (!narrowed_) return;
        round_rings_.clear();
        auto add = [&](const std::vector<std::uint32_t>& candidates) {
            for (const std::uint32_t v : candidates) {
                const std::uint32_t c = chain_of_[v];
                if (whole_level_[c] != kOpen && whole_level_[c] > 0) round_rings_.push_back(c);
            }
        };
        if (grouped_ahead_) add(grouped_);
        for (unsigned level = 0; level < levels_; ++level) add(later_[level]);
        std::sort(round_rings_.begin(), round_rings_.end());
        round_rings_.erase(std::unique(round_rings_.begin(), round_rings_.end()), round_rings_.end());
    }

    // Puts every queued (and, in rounds, marked) vertex on its level's list, in id order.
    // `group_first` (one process's sweeps): level 0's go straight to grouped_ instead, grouped by
    // block as group_by_block would group them (grouped_ahead_), not through a list of their own
    // first: the biggest level's list and its grouped copy were both held when the first round
    // began, at the run's peak (33 MB of GSHHG's).
    void schedule_queued(bool group_first = false) {
        if (use_marks_ && few_.valid) {  // (this round's marks are listed, in id order)
            for (const std::uint32_t v : few_.marked) later_[level_of(v)].push_back(v);
            return;
        }
        const int threads = vertex_count_ >= parallel_min_ ? threads_ : 1;
        const auto share = static_cast<std::size_t>(threads);
        std::vector<std::vector<std::vector<std::uint32_t>>> parts(share, std::vector<std::vector<std::uint32_t>>(levels_));
        // Room for level 0 (most go there: no growing copies), taken here, not by each thread
        // from its own malloc arena, which keeps it once freed: on GSHHG at 10 % on 2 threads,
        // the run's peak 31 MiB lower and this pass 20–28 ms instead of 58–67.
        for (std::size_t t = 0; t < share; ++t) parts[t][0].reserve(undecided_count(static_cast<int>(t), threads));
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            auto& part = parts[static_cast<std::size_t>(t)];
            for_each_undecided(t, threads, [&](std::uint32_t v) {
                if (state_[v] == State::queued && (!use_marks_ || marked_[v])) part[level_of(v)].push_back(v);
            });
        });
        if (group_first && later_[0].empty()) group_ahead(parts, threads);
        // Appended in thread order, so each list stays in id order; copied on all threads.
        std::vector<std::size_t> at(share * levels_);
        for (unsigned level = 0; level < levels_; ++level) {
            std::size_t end = later_[level].size();
            for (std::size_t t = 0; t < share; ++t) {
                at[t * levels_ + level] = end;
                end += parts[t][level].size();
            }
            later_[level].resize(end);
        }
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            const auto& part = parts[static_cast<std::size_t>(t)];
            for (unsigned level = 0; level < levels_; ++level) {
                std::copy(part[level].begin(), part[level].end(),
                          later_[level].begin() + static_cast<std::ptrdiff_t>(at[static_cast<std::size_t>(t) * levels_ + level]));
            }
        });
    }

    // The counting sort's middle (group_by_block, group_ahead): `place`, the candidates each
    // thread counted per block ([block][thread]), becomes where each thread's first of a block
    // goes; start_ gets where each block's candidates begin; grouped_ is sized. Returns how many.
    std::size_t place_blocks(std::vector<std::size_t>& place, std::uint32_t blocks, std::size_t share) {
        start_.resize(std::size_t{blocks} + 1);
        std::size_t total = 0;
        for (std::uint32_t b = 0; b < blocks; ++b) {
            start_[b] = static_cast<std::uint32_t>(total);
            for (std::size_t t = 0; t < share; ++t) {
                const std::size_t here = place[std::size_t{b} * share + t];
                place[std::size_t{b} * share + t] = total;
                total += here;
            }
        }
        start_[blocks] = static_cast<std::uint32_t>(total);
        grouped_.resize(total);
        return total;
    }

    // Level 0's candidates, parts[t][0] of each thread t in id order, into grouped_ and start_ as
    // group_by_block(0) would place them (all are queued and of level 0), taken out of parts.
    void group_ahead(std::vector<std::vector<std::vector<std::uint32_t>>>& parts, int threads) {
        const auto share = static_cast<std::size_t>(threads);
        const std::uint32_t blocks = blocks_at(0);
        std::vector<std::size_t> place(std::size_t{blocks} * share, 0);  // [block][thread]
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            std::vector<std::size_t> mine(blocks, 0);
            for (const std::uint32_t v : parts[static_cast<std::size_t>(t)][0]) ++mine[block_at(v, 0)];
            for (std::uint32_t b = 0; b < blocks; ++b) place[std::size_t{b} * share + static_cast<std::size_t>(t)] = mine[b];
        });
        const std::size_t total = place_blocks(place, blocks, share);
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            std::vector<std::size_t> fill(blocks);
            for (std::uint32_t b = 0; b < blocks; ++b) fill[b] = place[std::size_t{b} * share + static_cast<std::size_t>(t)];
            std::vector<std::uint32_t>& mine = parts[static_cast<std::size_t>(t)][0];
            for (const std::uint32_t v : mine) grouped_[fill[block_at(v, 0)]++] = v;
            std::vector<std::uint32_t>().swap(mine);
        });
        grouped_ahead_ = total > 0;
    }

    // Calls visit(v) for the vertices a round looks at in share `part` of `parts` (contiguous,
    // in id order): every vertex until a round has run, then only those neither fixed nor
    // removed, kept as a bitmap (after the first round of GSHHG at 10 %, a third of them), so
    // that the rounds that follow do not scan the whole map again and again. A bitmap, not a
    // list: 1.2 MB for GSHHG's 9.7 M vertices where a list took 20 MB at the peak (issue 34).
    template <class Visit>
    void for_each_undecided(int part, int parts, Visit&& visit) const {
        const auto [first, last] = share_words(part, parts);
        if (undecided_.empty()) {
            const auto end = static_cast<std::uint32_t>(std::min<std::size_t>(vertex_count_, 64 * last));
            for (auto v = static_cast<std::uint32_t>(64 * first); v < end; ++v) visit(v);
            return;
        }
        for (std::size_t w = first; w < last; ++w) {
            for (std::uint64_t bits = undecided_[w]; bits != 0; bits &= bits - 1) {
                visit(static_cast<std::uint32_t>(64 * w + static_cast<std::size_t>(std::countr_zero(bits))));
            }
        }
    }

    // Share `part` of `parts` of the undecided bitmap's words (all vertices' words before the
    // first round), [first, last).
    std::pair<std::size_t, std::size_t> share_words(int part, int parts) const {
        const std::size_t words = (std::size_t{vertex_count_} + 63) / 64;
        return {words * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts),
                words * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts)};
    }

    // How many vertices for_each_undecided(part, parts) visits.
    std::size_t undecided_count(int part, int parts) const {
        const auto [first, last] = share_words(part, parts);
        if (undecided_.empty()) return std::min<std::size_t>(vertex_count_, 64 * last) - std::min<std::size_t>(vertex_count_, 64 * first);
        std::size_t count = 0;
        for (std::size_t w = first; w < last; ++w) count += static_cast<std::size_t>(std::popcount(undecided_[w]));
        return count;
    }

    void keep_undecided() {
        const std::size_t words = (std::size_t{vertex_count_} + 63) / 64;
        const bool first = undecided_.empty();
        if (first) undecided_.assign(words, 0);
        const int threads = vertex_count_ >= parallel_min_ ? threads_ : 1;
#pragma omp parallel for schedule(static) num_threads(threads)
        for (std::size_t w = 0; w < words; ++w) {
            auto open = [&](std::size_t v) { return state_[v] != State::fixed && state_[v] != State::removed; };
            std::uint64_t bits = 0;
            if (first) {
                for (std::size_t v = 64 * w; v < std::min<std::size_t>(vertex_count_, 64 * w + 64); ++v) {
                    if (open(v)) bits |= std::uint64_t{1} << (v % 64);
                }
            } else {
                for (std::uint64_t left = undecided_[w]; left != 0; left &= left - 1) {
                    const auto bit = static_cast<std::size_t>(std::countr_zero(left));
                    if (open(64 * w + bit)) bits |= std::uint64_t{1} << bit;
                }
            }
            undecided_[w] = bits;
        }
    }

    void sweep() {
        if (slot_.empty()) slot_.assign(vertex_count_, kNone);  // (after the first round's selection, not beside it)
        for (unsigned level = 0; level < levels_; ++level) {
            if (later_[level].empty() && !(level == 0 && grouped_ahead_)) continue;  // (late rounds leave most levels empty)
            compact_grid();
            process_level(level);
            stop_if_cancelled(options_.cancel);
        }
    }

    void process_level(unsigned level) {
        decide_split_rings(level);
        const bool ahead = level == 0 && grouped_ahead_;  // (then later_[0] is empty)
        grouped_ahead_ = false;
        const std::size_t kept = ahead ? grouped_.size() : group_by_block(level);
        std::vector<std::uint32_t>& start = start_;
        std::vector<std::uint32_t>& grouped = grouped_;
        const std::uint32_t blocks = blocks_at(level);
        std::vector<std::uint32_t>().swap(later_[level]);  // (its memory back before the blocks run)
        std::vector<std::uint32_t> busy;  // blocks with candidates
        for (std::uint32_t b = 0; b < blocks; ++b) {
            if (start[b + 1] > start[b]) busy.push_back(b);
        }

        std::vector<Worker> workers(static_cast<std::size_t>(threads_));
        for (Worker& worker : workers) worker.later.assign(levels_ + 1, {});
        const auto busy_count = static_cast<std::ptrdiff_t>(busy.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads_) if (kept >= parallel_min_ && busy.size() > 1)
        for (std::ptrdiff_t i = 0; i < busy_count; ++i) {
            const std::uint32_t b = busy[static_cast<std::size_t>(i)];
            Worker& worker = workers[static_cast<std::size_t>(omp_get_thread_num())];
            worker.block = b;
            process_block(level, {grouped.data() + start[b], grouped.data() + start[b + 1]}, worker);
        }
        std::vector<std::uint32_t>().swap(grouped_);  // (the first level of the first round holds most; the rest need less)
        queue_released(workers);
        for (Worker& worker : workers) {
            for (unsigned l = level + 1; l < levels_; ++l) {
                later_[l].insert(later_[l].end(), worker.later[l].begin(), worker.later[l].end());
            }
            few_.touched.insert(few_.touched.end(), worker.touched.begin(), worker.touched.end());
            add(stats_, worker.stats);
        }
        progress_.store(0, std::memory_order_relaxed);
        report_progress();
    }

    // The candidates of this level still queued at it (else they are on a later list), grouped
    // by block into grouped_, block b's from start_[b]: a counting sort, each thread counting and
    // then placing a contiguous share of the list. Returns how many there are.
    std::size_t group_by_block(unsigned level) {
        std::vector<std::uint32_t>& candidates = later_[level];
        const std::uint32_t blocks = blocks_at(level);
        const std::size_t count = candidates.size();
        const int threads = count >= parallel_min_ ? threads_ : 1;
        const auto share = static_cast<std::size_t>(threads);
        auto range = [&](int t) { return std::pair{count * static_cast<std::size_t>(t) / share, count * static_cast<std::size_t>(t + 1) / share}; };
        std::vector<std::size_t> place(std::size_t{blocks} * share);  // [block][thread]: where the thread's entries go
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            const auto [begin, end] = range(t);
            std::vector<std::size_t> mine(blocks, 0);
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t v = candidates[i];
                if (state_[v] != State::queued || level_of(v) > level) {
                    candidates[i] = kNone;
                } else {
                    ++mine[block_at(v, level)];
                }
            }
            for (std::uint32_t b = 0; b < blocks; ++b) place[std::size_t{b} * share + static_cast<std::size_t>(t)] = mine[b];
        });
        const std::size_t total = place_blocks(place, blocks, share);
#pragma omp parallel num_threads(threads)
        parallel::for_my_shares(threads, [&](int t) {
            const auto [begin, end] = range(t);
            std::vector<std::size_t> fill(blocks);
            for (std::uint32_t b = 0; b < blocks; ++b) fill[b] = place[std::size_t{b} * share + static_cast<std::size_t>(t)];
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t v = candidates[i];
                if (v != kNone) grouped_[fill[block_at(v, level)]++] = v;
            }
        });
        return total;
    }

    // For each ring not within one block at this level: can its fixed vertices alone keep it
    // at 4 or more distinct locations? Then the ring rule cannot bite here.
    void decide_split_rings(unsigned level) {
        const std::vector<std::uint32_t>& split = narrowed_ ? round_rings_ : split_rings_;
        const auto rings = static_cast<std::ptrdiff_t>(split.size());
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads_) if (rings >= 256)
        for (std::ptrdiff_t i = 0; i < rings; ++i) {
            const std::uint32_t c = split[static_cast<std::size_t>(i)];
            if (whole_level_[c] <= level) continue;
            if (!cut_end_.empty()) {
                ring_clear_[c] = subset_ring_clear(c, level);
                continue;
            }
            if (split_over_tiles(c)) {
                // A piece: its cut ends settle it, or the tiles' fixed locations together do.
                ring_clear_[c] = tile_->settled[c] ||
                                 std::binary_search(outside_clear_.begin(), outside_clear_.end(), tile_->chain_id[c]);
                continue;
            }
            int count = 0;
            for_each_fixed_location(c, level, 4, [&](Point) { ++count; });
            ring_clear_[c] = count >= 4;
        }
    }

    // A subset of the live map (top_subset_input): whether ring piece c's whole ring holds ≥ 4
    // distinct locations at its fixed vertices at `level` — those of all its pieces here, cut
    // ends left out (their neighbour beyond is not here), and those outside the runs, which the
    // input lists (they do not change while the subset runs: a change would exhaust it).
    bool subset_ring_clear(std::uint32_t c, unsigned level) const {
        FirstLocations<4> found;
        const std::uint32_t ring = tile_->chain_id[c];
        if (const auto at = outside_at_.find(std::uint64_t{ring} << 8 | level); at != outside_at_.end()) {
            for (const Point q : tile_->outside[at->second].locations) found.add(q);
        }
        for (const std::uint32_t piece : pieces_of_.at(ring)) {
            for (std::uint32_t u = map_.chains[piece].first; u != kNone && found.count < 4; u = next_[u]) {
                if (!cut_end_[u] && (state_[u] == State::fixed || level_of(u) > level)) found.add(map_.vertices[u]);
            }
        }
        return found.count >= 4;
    }

    // Calls visit(q) for the first `most` distinct locations of chain c's fixed vertices at
    // `level` (pinned, ends, or of a coarser level), in chain order.
    template <class Visit>
    void for_each_fixed_location(std::uint32_t c, unsigned level, int most, Visit&& visit) const {
        FirstLocations<4> found;
        for (std::uint32_t u = map_.chains[c].first; u != kNone && found.count < most; u = next_[u]) {
            const bool fixed = state_[u] == State::fixed || level_of(u) > level;
            if (fixed && found.add(map_.vertices[u])) visit(map_.vertices[u]);
        }
    }

    // A tile's piece of a ring that other tiles hold pieces of.
    bool split_over_tiles(std::uint32_t c) const {
        return tile_ && tile_->whole_level[c] != kOpen && tile_->whole_level[c] > tile_->level;
    }

    // Is `top` ranked after the round's threshold? A tile compares whole-map ids.
    bool past_bound(const Ranked& top) const {
        if (!tile_ || resumed_) return bound_.key < top.key || (bound_.key == top.key && bound_.id < global(top.id));
        return bound_.key < top.key || (bound_.key == top.key && tile_->bound_id < tile_->vertex_id[top.id]);
    }

    // One block: remove its queued vertices smallest area first, up to the round's threshold.
    void process_block(unsigned level, std::span<const std::uint32_t> candidates, Worker& worker) {
        std::uint32_t* const slot = slot_.data();
        worker.queue.fill(candidates, [&](std::uint32_t v) { return area_of(v); }, slot);
        std::uint64_t pops = 0;
        while (!worker.queue.empty() && !past_bound(worker.queue.top())) {
            const std::uint32_t v = worker.queue.pop(slot).id;
            if ((++pops & 0xfff) == 0) {
                if (cancel_requested(options_.cancel)) break;  // the level's end throws
                progress_.fetch_add(worker.stats.removed - worker.reported, std::memory_order_relaxed);
                worker.reported = worker.stats.removed;
                report_progress();
            }
            std::uint32_t blocker = kNone;
            switch (judge(v, level, blocker, worker.stats)) {
                case Verdict::remove: remove(v, level, worker); break;
                case Verdict::blocked_by_point:
                    ++worker.stats.blocked_by_point;
                    if (blocker < vertex_count_) {
                        wait_on(v, blocker);
                    } else {
                        state_[v] = State::refused;
                    }
                    break;
                case Verdict::blocked_by_ring:
                    ++worker.stats.blocked_by_ring;
                    state_[v] = State::refused;
                    break;
                case Verdict::blocked_by_coincidence:
                    ++worker.stats.blocked_by_coincidence;
                    state_[v] = State::refused;
                    break;
                case Verdict::later: worker.later[level + 1].push_back(v); break;
            }
        }
        worker.queue.clear(slot);
    }

    Verdict judge(std::uint32_t v, unsigned level, std::uint32_t& blocker, SimplifyStats& stats) {
        const std::uint32_t p = prev_[v], n = next_[v];
        const Point a = map_.vertices[p], b = map_.vertices[v], c = map_.vertices[n];
        if (const auto ring = ring_verdict(v, level, a, b, c, stats); ring != Verdict::remove) return ring;

        const Box box = triangle_box(a, b, c);
        std::optional<exact::ClosedTriangle> triangle;  // prepared at the first candidate point
        // The blocker a vertex waits on is the first point in the triangle in the grid's base
        // order, as the split rows do not change it.
        blocker = grid_->first_in_cells(box, [&](std::uint32_t id, Point q) {
            // A point that can block: live, not v, inside the box, not at a or c. Most points the
            // rows give fail one of these in no order a predictor can learn, so the cheap ones
            // are one test without a branch per condition: not p, v or n themselves (the usual
            // points at a or c), inside the box (its x is in the box's range: first_in_cells
            // reads no other). Then the rare others at a or c.
            const bool other = (id != PointGrid::kRemoved) & (id != v) & (id != p) & (id != n) & (q.y >= box.min_y) &
                               (q.y <= box.max_y);
            if (!other || same_location(q, a) || same_location(q, c)) return false;
            if (!triangle) triangle.emplace(a, b, c, options_.arithmetic, stats.predicates);
            return triangle->contains(q);
        });
        if (blocker != PointGrid::kRemoved) return Verdict::blocked_by_point;

        if (coincides_with_other_segment(p, v, n)) return Verdict::blocked_by_coincidence;
        return Verdict::remove;
    }

    // Rule 2: a closed chain keeps ≥ 3 distinct locations, and its last triangle keeps the
    // input ring's orientation (so non-zero area).
    Verdict ring_verdict(std::uint32_t v, unsigned level, Point a, Point b, Point c, SimplifyStats& stats) {
        const std::uint32_t chain = chain_of_[v];
        if (whole_level_[chain] == kOpen) return Verdict::remove;  // open chain
        if (same_location(b, a) || same_location(b, c)) return Verdict::remove;  // a duplicate: no location lost
        if (whole_level_[chain] > level) return ring_clear_[chain] ? Verdict::remove : Verdict::later;
        if (distinct_[chain] <= 3) return Verdict::blocked_by_ring;
        if (distinct_[chain] > 4) return Verdict::remove;
        FirstLocations<3> corners;
        for (std::uint32_t u = map_.chains[chain].first; u != kNone && corners.count < 3; u = next_[u]) {
            if (u != v) corners.add(map_.vertices[u]);
        }
        if (corners.count < 3) return Verdict::blocked_by_ring;
        const int turn = options_.arithmetic == exact::Arithmetic::floating
                             ? orient_float(corners.at[0], corners.at[1], corners.at[2])
                             : exact::orient2d(corners.at[0], corners.at[1], corners.at[2], stats.predicates);
        return turn != 0 && turn == ring_orientation(chain, stats.predicates) ? Verdict::remove : Verdict::blocked_by_ring;
    }

    static int orient_float(Point a, Point b, Point c) {
        const double det = (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x);
        return (det > 0) - (det < 0);
    }

    // Sign of the input ring's signed area, exactly (computed once, only for rings that get
    // down to their last triangle, by the one thread that owns the whole ring; or known before,
    // see know_orientation).
    int ring_orientation(std::uint32_t chain, exact::PredicateStats& stats) {
        std::int8_t& known = orientation_[chain];
        if (known >= kOrientedByFilter - 1) {
            // Known before: counted now, where the single process computes it.
            ++(known >= kOrientedByGmp - 1 ? stats.gmp_fallbacks : stats.filter_decided);
            known = static_cast<std::int8_t>(known - (known >= kOrientedByGmp - 1 ? kOrientedByGmp : kOrientedByFilter));
        }
        if (orientation_[chain] != 2) return orientation_[chain];
        const Chain& range = map_.chains[chain];
        const std::span<const Point> ring(map_.vertices.data() + range.first, range.last - range.first + 1);
        orientation_[chain] = static_cast<std::int8_t>(options_.arithmetic == exact::Arithmetic::rational
                                                           ? exact::ring_area_sign_gmp(ring)
                                                           : exact::ring_area_sign(ring, stats));
        return orientation_[chain];
    }

    // A run in parts sends a ring's live vertices only, so the input ring's orientation goes with
    // it when the ring rule may ask for it: computed here, but counted in the predicates' stats
    // where it is asked for (as the single process counts it), kept until then as the sign plus
    // kOrientedByFilter or kOrientedByGmp (the counter it goes to; 2 stays "unknown").
    static constexpr std::int8_t kOrientedByFilter = 4, kOrientedByGmp = 8;
    void know_orientation(std::uint32_t c) {
        if (orientation_[c] != 2) return;
        if (resumed_) throw std::logic_error("a run over the live vertices only cannot compute an input ring's orientation");
        const Chain& range = map_.chains[c];
        const std::span<const Point> ring(map_.vertices.data() + range.first, range.last - range.first + 1);
        if (options_.arithmetic == exact::Arithmetic::rational) {
            orientation_[c] = static_cast<std::int8_t>(exact::ring_area_sign_gmp(ring));  // (never counted)
            return;
        }
        exact::PredicateStats counted;
        const int sign = exact::ring_area_sign(ring, counted);
        orientation_[c] = static_cast<std::int8_t>(sign + (counted.gmp_fallbacks != 0 ? kOrientedByGmp : kOrientedByFilter));
    }
    // When a round's budget may bring the ring down to 4 distinct locations.
    void know_orientation_if_asked(std::uint32_t c) {
        if (orientation_[c] != 2) return;
        std::uint32_t budget = 0;
        for (std::uint32_t u = map_.chains[c].first; u != kNone; u = next_[u]) budget += use_marks_ ? marked_[u] : 1;
        if (distinct_[c] <= 4 + budget) know_orientation(c);
    }

    // Rule 3: would the new segment p–n lie on another live segment with the same end locations?
    // Every such segment has a live vertex at p's location, which the grid lists (all of them in
    // this block). v's own segments p–v and v–n disappear with it and do not count (they can
    // have the same locations when v duplicates a neighbour).
    bool coincides_with_other_segment(std::uint32_t p, std::uint32_t v, std::uint32_t n) const {
        const Point from = map_.vertices[p], to = map_.vertices[n];
        if ((!shared_[p] && !shared_[n]) || same_location(from, to)) return false;
        return grid_->any_in_cells({from.x, from.y, from.x, from.y}, [&](std::uint32_t u, Point q) {
            if (u >= vertex_count_ || !same_location(q, from)) return false;
            for (const std::uint32_t w : {prev_[u], next_[u]}) {
                if (w == kNone || !same_location(map_.vertices[w], to)) continue;
                const bool own = (u == p && w == v) || (u == v && w == n);  // p–v or v–n
                if (!own) return true;
            }
            return false;
        });
    }

    void remove(std::uint32_t v, unsigned level, Worker& worker) {
        const std::uint32_t p = prev_[v], n = next_[v];
        const std::uint32_t chain = chain_of_[v];
        const Point a = map_.vertices[p], b = map_.vertices[v], c = map_.vertices[n];
        if (whole_level_[chain] != kOpen && !same_location(b, a) && !same_location(b, c)) {
            if (whole_level_[chain] > level) {
                // A split ring: other blocks may count down too; only the total matters later.
                std::atomic_ref<std::uint32_t>(distinct_[chain]).fetch_sub(1, std::memory_order_relaxed);
            } else {
                --distinct_[chain];
            }
        }
        state_[v] = State::removed;
        grid_->remove(v);
        next_[p] = n;
        prev_[n] = p;
        // A subset's runs too short: the cut end beyond would be queued again here, with a
        // neighbour the subset lacks (top_subset_input).
        if (!cut_end_.empty() && (cut_end_[p] | cut_end_[n])) exhausted_.store(true, std::memory_order_relaxed);
        ++worker.stats.removed;
        release_waiting_on(v, level, worker);
        requeue(p, level, worker);
        requeue(n, level, worker);
    }

    // A vertex whose triangle changed (or whose blocker went) is a candidate again: in this
    // block's queue if it belongs to this level or a finer one, else on its level's list.
    void requeue(std::uint32_t u, unsigned level, Worker& worker) {
        if (state_[u] == State::fixed || state_[u] == State::removed) return;
        if (state_[u] == State::waiting) stop_waiting(u);
        state_[u] = State::queued;
        if (collect_touched_) worker.touched.push_back(u);
        if (use_marks_ && !marked_[u]) return;  // not this round's
        const unsigned at = level_of(u);
        if (at <= level) {
            worker.queue.set({area_of(u), u}, slot_.data());
        } else {
            worker.later[at].push_back(u);
        }
    }

    void wait_on(std::uint32_t v, std::uint32_t blocker) {
        state_[v] = State::waiting;
        waits_.add(v, blocker);
        has_waiters_[blocker] = 1;  // the blocker lies in v's triangle: in this block
    }

    void stop_waiting(std::uint32_t v) {
        waits_.remove(v);
        state_[v] = State::queued;
    }

    // The blocker goes: its waiters are candidates again. A waiter may lie outside this block
    // when its wait began at a coarser level of an earlier round; it is another thread's to
    // touch, so it is set aside and queued after the level, for the next round.
    void release_waiting_on(std::uint32_t blocker, unsigned level, Worker& worker) {
        if (!has_waiters_[blocker]) return;
        has_waiters_[blocker] = 0;
        for (const std::uint32_t u : waits_.take(blocker)) {
            if (block_at(u, level) == worker.block) {
                requeue(u, level, worker);
            } else {
                worker.released.push_back(u);
            }
        }
    }

    // After a level: the waiters set aside are queued, unless they have been dealt with since
    // (queued again, or waiting on another vertex).
    void queue_released(std::vector<Worker>& workers) {
        std::vector<std::uint32_t> released;
        for (Worker& worker : workers) {
            released.insert(released.end(), worker.released.begin(), worker.released.end());
            worker.released.clear();
        }
        std::sort(released.begin(), released.end());
        for (const std::uint32_t u : released) {
            if (state_[u] == State::waiting && !waits_.waits(u)) {
                state_[u] = State::queued;
                if (collect_touched_) few_.touched.push_back(u);
            }
        }
    }

    static void add(SimplifyStats& total, const SimplifyStats& part) {
        total.removed += part.removed;
        total.blocked_by_point += part.blocked_by_point;
        total.blocked_by_ring += part.blocked_by_ring;
        total.blocked_by_coincidence += part.blocked_by_coincidence;
        total.predicates += part.predicates;
    }

    // Progress comes from the first thread only, as a share of the removals asked for.
    void report_progress() {
        if (!options_.progress || omp_get_thread_num() != 0 || work_ <= 0) return;
        const double done = static_cast<double>(stats_.removed + progress_.load(std::memory_order_relaxed));
        options_.progress(std::min(1.0, done / work_));
    }

    SimplifyResult finish() {
        stats_.vertices_in = vertex_count_;
        stats_.vertices_out = vertex_count_ - stats_.removed;
        stats_.threads = threads_;
        std::vector<std::uint8_t> kept(vertex_count_);
        for (std::uint32_t v = 0; v < vertex_count_; ++v) kept[v] = state_[v] != State::removed;
        return {std::move(kept), stats_};
    }

    const MapData& map_;
    std::vector<Point> owned_points_;
    std::span<const Point> control_points_;  // until indexed
    const SimplifyOptions& options_;
    const bool plain_ranking_ = !options_.ranking.spherical && options_.ranking.weighting == 0;  // (area_of)
    const std::uint32_t vertex_count_;
    const int threads_;
    const std::size_t parallel_min_;  // below this many items a loop runs on one thread
    std::optional<PointGrid> grid_;
    std::uint64_t compacted_at_ = 0;  // vertices removed when the grid last dropped them
    PointGrid::Geometry geometry_;           // the grid's cells (also while a run in parts has dropped it)
    std::span<const Point> indexed_points_;  // the control points the grid was built over
    using Blocks = parallel::BlockLevels<2>;
    Blocks blocks_;
    unsigned levels_ = 1;
    std::vector<std::uint32_t> prev_, next_, chain_of_;
    std::vector<std::uint8_t> shared_;     // per vertex: another vertex is at its location (ensure_grid: another live one)
    std::vector<std::uint32_t> block_xy_;  // per vertex: level-0 block, column << 16 | row
    std::vector<State> state_;
    std::vector<std::uint8_t> marked_;       // count targets: this round's budget
    std::vector<std::uint32_t> distinct_;    // per closed chain: distinct live locations; 0 if open
    std::vector<std::int8_t> orientation_;   // per chain: input ring orientation, 2 = unknown
    std::vector<std::uint32_t> split_rings_;  // the rings not in one level-0 block (whole_level_ above 0)
    std::vector<std::uint32_t> round_rings_;  // of those, the ones this round judges a vertex of (narrow_split_rings)
    bool narrowed_ = false;                   // decide_split_rings decides round_rings_ only
    // Count targets in one process (mark_smallest's keep_few, mark_few): what the next round's
    // selection looks at, when a round's budget is at most a kFewShare-th of the queued vertices.
    static constexpr std::uint64_t kFewShare = 16;
    struct Few {
        bool valid = false;
        std::uint64_t bound = 0;             // a key: every unmarked queued vertex of key ≤ bound is ranked
        std::vector<std::uint32_t> ranked;   // at the last selection
        std::vector<std::uint32_t> marked;   // by the last selection, in id order
        std::vector<std::uint32_t> touched;  // queued again (or anew) since
        std::vector<std::uint32_t> ids;                            // (mark_few's scratch)
        std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;  // (mark_few's scratch)
    } few_;
    bool collect_touched_ = false;  // requeue and queue_released list into few_.touched
    bool grouped_ahead_ = false;    // grouped_ and start_ hold level 0's candidates (schedule_queued's group_first)
    std::vector<std::uint8_t> whole_level_;  // per chain: first level where the ring is in one block; kOpen
    std::vector<std::uint8_t> ring_clear_;   // per split ring, this level: ≥ 4 fixed locations
    Waits waits_;
    std::vector<std::uint8_t> has_waiters_;  // per vertex: some vertex may wait on it (written by its block only)
    std::vector<std::uint32_t> slot_;        // per vertex: its place in its block's queue, or kNone
    std::vector<std::uint64_t> undecided_;   // see for_each_undecided(); empty until a round has run
    std::vector<std::vector<std::uint32_t>> later_;  // per level: vertices to queue there
    std::vector<std::uint32_t> start_, grouped_;  // scratch of process_level
    const TileInput* tile_ = nullptr;  // a tile of a run in parts, with the whole map's plan
    const GridPlan* plan_ = nullptr;
    std::span<const std::uint32_t> outside_clear_;  // this level: split rings clear over all tiles
    // A subset of the live map (top_subset_input): per vertex, a cut end; each ring's pieces; set
    // when a vertex next to a cut end went.
    std::vector<std::uint8_t> cut_end_;
    std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> pieces_of_;
    std::unordered_map<std::uint64_t, std::size_t> outside_at_;  // (ring << 8 | level) → its entry in the input's `outside`
    std::atomic<bool> exhausted_{false};
    // The whole map's side: the vertices whose waits a subset's outcome replaces (its runs' and
    // lone vertices, not its cut ends).
    std::vector<std::uint32_t> subset_waiters_;
    std::vector<std::uint32_t> initial_distinct_;  // a tile's distinct_ at the start
    std::vector<std::int8_t> initial_orientation_;  // a tile's orientation_ at the start
    bool resumed_ = false;            // a run in parts over the live vertices only (resume_parts)
    unsigned tile_level_ = 0;         // the whole map's side of a run in parts: its tile level
    std::uint64_t goal_ = 0;          // and removal goal
    std::uint64_t queued_at_start_ = 0;  // (pin: the interior vertices not pinned)
    unsigned rounds_started_ = 0;     // (--max and --max-area: one)
    std::uint64_t round_budget_ = 0;  // count targets: this round's marked vertices
    bool round_here_ = false;         // this round runs here, not in tiles
    std::vector<std::uint32_t> running_;  // this round's tiles that run, sorted
    RoundSplit split_;  // this round's tiles (split_round)
    bool use_marks_ = false;
    Ranked bound_{0, 0};  // the round's threshold: vertices ranked above it wait
    double work_ = 0;
    std::atomic<std::uint64_t> progress_{0};  // removals in this level so far, roughly
    SimplifyStats stats_;
};

}  // namespace detail

SimplifyResult simplify(const MapData& map, const SimplifyOptions& options) {
    return detail::Simplifier(map, options).run();
}

SimplifyResult simplify_releasing_points(MapData& map, const SimplifyOptions& options) {
    std::vector<Point> points = std::move(map.control_points);
    map.control_points.clear();
    return detail::Simplifier(map, options, std::move(points)).run();
}

// ---- runs in parts (tiles.hpp) ------------------------------------------------------------------

GridPlan plan_grid(const MapData& map) {
    const std::size_t n = map.vertices.size() + map.control_points.size();
    if (n == 0) return {};
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
    for (const auto* points : {&map.vertices, &map.control_points}) {
        for (const Point p : *points) {
            min_x = std::min(min_x, p.x);
            min_y = std::min(min_y, p.y);
            max_x = std::max(max_x, p.x);
            max_y = std::max(max_y, p.y);
        }
    }
    return plan_grid(min_x, min_y, max_x, max_y, n);
}

GridPlan plan_grid(double min_x, double min_y, double max_x, double max_y, std::size_t points) {
    GridPlan plan;
    if (points == 0) return plan;
    plan.grid = PointGrid::Geometry::plan(min_x, min_y, max_x, max_y, points, kPointsPerCell, kRowSplit);
    plan.shift = block_shift(plan.grid.base_columns, plan.grid.base_rows);
    parallel::BlockLevels<2> blocks;
    blocks.cells = {plan.grid.base_columns, plan.grid.base_rows};
    blocks.shift = static_cast<int>(plan.shift);
    plan.levels = static_cast<unsigned>(blocks.top_level()) + 1;
    return plan;
}

struct TileRun::Parts {
    TileInput input;
    GridPlan plan;
    SimplifyOptions options;
    std::optional<detail::Simplifier> engine;
};

TileRun::TileRun(TileInput input, const GridPlan& plan, const SimplifyOptions& options)
    : parts_(new Parts{std::move(input), plan, options, std::nullopt}) {
    parts_->engine.emplace(parts_->input, parts_->plan, parts_->options);
    parts_->engine->start_tile();
}

TileRun::~TileRun() = default;
TileRun::TileRun(TileRun&&) noexcept = default;
TileRun& TileRun::operator=(TileRun&&) noexcept = default;

std::vector<RingLocations> TileRun::open_rings(unsigned level) { return parts_->engine->open_rings(level); }

void TileRun::run_level(unsigned level, std::span<const std::uint32_t> clear) { parts_->engine->run_tile_level(level, clear); }

TileOutcome TileRun::finish() { return parts_->engine->finish_tile(); }

MapInParts::MapInParts(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint64_t here_below)
    : engine_(std::make_unique<detail::Simplifier>(map, options)), plan_(plan_grid(map)), here_below_(here_below) {
    tile_level_ = engine_->start_parts(tile_level);
}

MapInParts::~MapInParts() = default;

const GridPlan& MapInParts::plan() const { return plan_; }

unsigned MapInParts::tile_level() const { return tile_level_; }

void MapInParts::set_tile_level(unsigned tile_level) { tile_level_ = engine_->set_tile_level(tile_level); }

bool MapInParts::next_round() { return engine_->next_part_round(here_below_); }

std::size_t MapInParts::split_round() { return engine_->split_round(); }

std::vector<TileInput> MapInParts::group(std::size_t k) const { return engine_->round_group(k); }

std::size_t MapInParts::group_size(std::size_t k) const { return engine_->round_group_size(k); }

std::uint64_t MapInParts::group_points(std::size_t k) const { return engine_->round_group_points(k); }

std::vector<std::vector<TileInput>> MapInParts::tile_groups() {
    std::vector<std::vector<TileInput>> groups(split_round());
    for (std::size_t k = 0; k < groups.size(); ++k) groups[k] = group(k);
    return groups;
}

void MapInParts::finish_round(std::span<const TileOutcome> outcomes) {
    if (finish_tiles(outcomes)) engine_->run_part_top_here();
}

bool MapInParts::finish_tiles(std::span<const TileOutcome> outcomes) { return engine_->finish_part_tiles(outcomes); }

void MapInParts::run_top_here() { engine_->run_part_top_here(); }

void MapInParts::keep_live_only() {
    if (live_ == nullptr) input_vertices_ = engine_->vertex_count();
    auto live = std::make_unique<TileInput>(engine_->top_input(true));
    const auto progress = engine_->parts_progress();
    const SimplifyOptions& options = engine_->options();  // (the caller's)
    engine_.reset();  // the engine before goes before the new one is built (it may use live_, which goes next)
    live_ = std::move(live);
    engine_ = std::make_unique<detail::Simplifier>(*live_, plan_, options);
    engine_->resume_parts(progress);
}

TileInput MapInParts::top() { return engine_->top_input(); }

TileInput MapInParts::top_subset(std::uint32_t runs) { return engine_->top_subset_input(runs); }

bool MapInParts::finish_top_subset(const TileOutcome& outcome) { return engine_->finish_part_top_subset(outcome); }

void MapInParts::finish_top(const TileOutcome& outcome) { engine_->finish_part_top(outcome); }

SimplifyResult MapInParts::result() {
    SimplifyResult result = engine_->part_result();
    if (live_ == nullptr) return result;
    // Back to the whole map's vertices: those not among the live ones went before.
    std::vector<std::uint8_t> kept(input_vertices_, 0);
    for (std::size_t i = 0; i < live_->vertex_id.size(); ++i) kept[live_->vertex_id[i]] = result.kept[i];
    result.kept = std::move(kept);
    result.stats.vertices_in = input_vertices_;
    result.stats.vertices_out = input_vertices_ - result.stats.removed;
    return result;
}

MapInParts::MapInParts(TileInput live, std::size_t input_vertices, const GridPlan& plan, const SimplifyOptions& options,
                       unsigned tile_level, std::uint64_t here_below, const PartsSoFar& so_far)
    : live_(std::make_unique<TileInput>(std::move(live))),
      input_vertices_(input_vertices),
      engine_(std::make_unique<detail::Simplifier>(*live_, plan, options)),
      plan_(plan),
      tile_level_(tile_level),
      here_below_(here_below) {
    detail::Simplifier::PartsProgress progress{tile_level, so_far.goal, so_far.round_budget, so_far.rounds_started,
                                               so_far.stats, {so_far.bound_key, so_far.bound_id}, so_far.work};
    engine_->resume_parts(progress);
}

// ---- The first round in stages (tiles.hpp: FirstTile, cut_part, FirstRoundLead, FirstRound)

namespace {

// cut_part's work for one part.
struct Cutter {
    const GridPlan& plan;
    unsigned t;
    const SimplifyOptions& options;
    CutPart out;
    std::map<std::uint32_t, FirstTile> tiles;
    std::vector<std::uint32_t> table;  // (count_locations' scratch)

    std::uint32_t columns() const { return ((plan.grid.base_columns - 1) >> (plan.shift + t)) + 1; }
    std::uint32_t tile_of(Point p) const { return plan.block_row(p, t) * columns() + plan.block_column(p, t); }

    FirstTile& tile(std::uint32_t k) {
        const auto [at, fresh] = tiles.try_emplace(k);
        if (fresh) {
            at->second.number = k;
            at->second.input.level = t;
            at->second.input.column = k % columns();
            at->second.input.row = k / columns();
        }
        return at->second;
    }

    // A piece of chain c (part chain `own`, whole-map ids first_id + i for points[i]) in tile k:
    // points [from, to] with the cut ends beyond them, if any.
    void add_piece(std::uint32_t k, std::uint32_t c, std::size_t own, std::span<const Point> points, std::uint32_t first_id,
                   std::size_t from, std::size_t to, bool whole_ring, bool settled) {
        FirstTile& at = tile(k);
        TileInput& in = at.input;
        const auto first = static_cast<std::uint32_t>(in.vertex_id.size());
        auto take = [&](std::size_t i, bool cut) {
            in.map.vertices.push_back(points[i]);
            in.vertex_id.push_back(first_id + static_cast<std::uint32_t>(i));
            at.cut_end.push_back(cut ? 1 : 0);
        };
        if (from > 0) take(from - 1, true);
        for (std::size_t i = from; i <= to; ++i) take(i, false);
        if (to + 1 < points.size()) take(to + 1, true);
        const ChainFacts& facts = out.facts;
        in.map.chains.push_back({first, static_cast<std::uint32_t>(in.vertex_id.size() - 1)});
        in.chain_id.push_back(c);
        in.whole_level.push_back(facts.whole_level[own]);
        in.settled.push_back(settled ? 1 : 0);
        in.distinct.push_back(whole_ring ? facts.distinct[own] : 0);
        in.orientation.push_back(whole_ring ? facts.orientation[own] : std::int8_t{2});
        at.frozen.push_back(facts.frozen[own]);
    }

    void add_chain(std::span<const Point> points, std::uint32_t c, std::uint32_t first_id, bool is_frozen) {
        ChainFacts& facts = out.facts;
        const std::size_t own = facts.chains.size();
        const auto last = static_cast<std::uint32_t>(points.size() - 1);
        facts.chains.push_back({first_id, first_id + last});
        facts.frozen.push_back(is_frozen ? 1 : 0);
        const bool closed = last > 0 && same_location(points.front(), points.back());
        std::uint8_t level = kOpenChain;
        std::uint32_t count = 0;
        std::int8_t turn = 2;
        if (closed) {
            std::uint32_t c0 = kNone, c1 = 0, r0 = kNone, r1 = 0;
            for (const Point p : points) {
                c0 = std::min(c0, plan.block_column(p, 0));
                c1 = std::max(c1, plan.block_column(p, 0));
                r0 = std::min(r0, plan.block_row(p, 0));
                r1 = std::max(r1, plan.block_row(p, 0));
            }
            using Blocks = parallel::BlockLevels<2>;
            level = static_cast<std::uint8_t>(std::max(Blocks::shared_level(c0, c1), Blocks::shared_level(r0, r1)));
            count = count_locations(points.first(last), table);
            // The input orientation, counted where asked (Simplifier::know_orientation).
            if (options.arithmetic == exact::Arithmetic::rational) {
                turn = static_cast<std::int8_t>(exact::ring_area_sign_gmp(points));
            } else {
                exact::PredicateStats counted;
                const int sign = exact::ring_area_sign(points, counted);
                turn = static_cast<std::int8_t>(sign + (counted.gmp_fallbacks != 0 ? 8 : 4));
            }
        }
        facts.whole_level.push_back(level);
        facts.distinct.push_back(count);
        facts.orientation.push_back(turn);
        std::vector<std::uint32_t> tile_at(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) tile_at[i] = tile_of(points[i]);
        if (closed && level <= t) {
            add_piece(tile_at[0], c, own, points, first_id, 0, last, true, false);
            return;
        }
        // A split ring's cut ends: both ends of every segment across a tile border.
        bool settled = false;
        if (closed) {
            FirstLocations<4> ends;
            for (std::size_t i = 0; i < last && ends.count < 4; ++i) {
                if (tile_at[i] == tile_at[i + 1]) continue;
                for (const Point q : {points[i], points[i + 1]}) ends.add(q);
            }
            settled = ends.count == 4;
        }
        for (std::size_t i = 0; i <= last;) {
            std::size_t j = i;
            while (j < last && tile_at[j + 1] == tile_at[i]) ++j;
            add_piece(tile_at[i], c, own, points, first_id, i, j, false, settled);
            i = j + 1;
        }
        // Segments that leave their tile go to every other tile their boxes meet too.
        for (std::size_t i = 0; i < last; ++i) {
            if (tile_at[i] == tile_at[i + 1]) continue;
            const Point a = points[i], b = points[i + 1];
            const Point lo{std::min(a.x, b.x), std::min(a.y, b.y)}, hi{std::max(a.x, b.x), std::max(a.y, b.y)};
            for (std::uint32_t row = plan.block_row(lo, t); row <= plan.block_row(hi, t); ++row) {
                for (std::uint32_t column = plan.block_column(lo, t); column <= plan.block_column(hi, t); ++column) {
                    const std::uint32_t k = row * columns() + column;
                    if (k == tile_at[i] || k == tile_at[i + 1]) continue;
                    FirstTile& at = tile(k);
                    at.passing.push_back(a);
                    at.passing.push_back(b);
                    at.passing_id.push_back(first_id + static_cast<std::uint32_t>(i));
                }
            }
        }
    }
};

template <class T>
void append(std::vector<T>& to, std::vector<T>&& from) {
    if (to.empty()) {
        to = std::move(from);
    } else {
        to.insert(to.end(), from.begin(), from.end());
    }
}

}  // namespace

CutPart cut_part(const MapData& part, std::uint32_t first_vertex, std::uint32_t first_chain, const GridPlan& plan, unsigned tile_level,
                 const SimplifyOptions& options) {
    Cutter cutter{plan, std::min(tile_level, plan.levels), options, {}, {}, {}};
    for (std::uint32_t c = 0; c < part.chains.size(); ++c) {
        const Chain& chain = part.chains[c];
        cutter.add_chain(std::span<const Point>(part.vertices.data() + chain.first, chain.last - chain.first + 1), first_chain + c,
                         first_vertex + chain.first, part.is_frozen(c));
    }
    for (auto& [k, tile] : cutter.tiles) cutter.out.tiles.push_back(std::move(tile));
    return std::move(cutter.out);
}

void FirstTile::add(FirstTile&& part) {
    TileInput& in = input;
    const auto offset = static_cast<std::uint32_t>(in.vertex_id.size());
    for (const Chain& chain : part.input.map.chains) in.map.chains.push_back({chain.first + offset, chain.last + offset});
    append(in.map.vertices, std::move(part.input.map.vertices));
    append(in.vertex_id, std::move(part.input.vertex_id));
    append(in.chain_id, std::move(part.input.chain_id));
    append(in.whole_level, std::move(part.input.whole_level));
    append(in.settled, std::move(part.input.settled));
    append(in.distinct, std::move(part.input.distinct));
    append(in.orientation, std::move(part.input.orientation));
    append(cut_end, std::move(part.cut_end));
    append(frozen, std::move(part.frozen));
    append(passing, std::move(part.passing));
    append(passing_id, std::move(part.passing_id));
}

std::vector<std::uint32_t> FirstTile::search(exact::Arithmetic arithmetic, exact::PredicateStats& predicates) {
    MapData search;
    search.vertices = input.map.vertices;
    search.chains = input.map.chains;
    const auto own = static_cast<std::uint32_t>(search.vertices.size());
    for (std::size_t j = 0; j < passing_id.size(); ++j) search.add_chain(std::span<const Point>(passing.data() + 2 * j, 2));
    const std::vector<std::uint8_t> flags = find_improper_segments(search, arithmetic, predicates, 1);
    improper.assign(flags.begin(), flags.begin() + own);
    std::vector<std::uint32_t> found;
    for (const Chain& chain : input.map.chains) {
        for (std::uint32_t v = chain.first; v < chain.last; ++v) {
            if (flags[v] && (cut_end[v] || cut_end[v + 1])) found.push_back(input.vertex_id[v]);
        }
    }
    for (std::size_t j = 0; j < passing_id.size(); ++j) {
        if (flags[own + 2 * j]) found.push_back(passing_id[j]);
    }
    std::vector<Point>().swap(passing);
    std::vector<std::uint32_t>().swap(passing_id);
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
}

std::uint64_t FirstTile::queue(std::span<const std::uint32_t> border, bool marks, const Ranking& ranking) {
    const auto improper_segment = [&](std::uint32_t s, bool local) { return local || std::binary_search(border.begin(), border.end(), s); };
    TileInput& in = input;
    in.state.assign(in.vertex_id.size(), static_cast<std::uint8_t>(VertexState::fixed));
    keys.clear();
    std::uint64_t pinned = 0;
    for (std::uint32_t p = 0; p < in.map.chains.size(); ++p) {
        const Chain& piece = in.map.chains[p];
        // (A piece's ends are its chain's ends or cut ends: fixed. Inside, v has the vertices before and after it.)
        for (std::uint32_t v = piece.first + 1; v < piece.last; ++v) {
            const std::uint32_t id = in.vertex_id[v];
            if (frozen[p] || improper_segment(id, improper[v] != 0) || improper_segment(id - 1, improper[v - 1] != 0)) {
                ++pinned;
                continue;
            }
            in.state[v] = static_cast<std::uint8_t>(VertexState::queued);
            if (marks) {
                const Point* q = in.map.vertices.data();
                keys.push_back(std::bit_cast<std::uint64_t>(rank_of(q[v - 1], q[v], q[v + 1], ranking)));
            }
        }
    }
    return pinned;
}

namespace {

// A count target's tile: f(v, key) for each of its queued vertices in order (none if it has no
// keys: a tile queued without marks).
template <class F>
void for_each_keyed(const FirstTile& tile, F&& f) {
    if (tile.keys.empty()) return;
    const TileInput& in = tile.input;
    std::size_t k = 0;
    for (std::uint32_t v = 0; v < in.state.size(); ++v) {
        if (in.state[v] == static_cast<std::uint8_t>(VertexState::queued)) f(v, tile.keys[k++]);
    }
}

}  // namespace

void FirstTile::histogram(int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) const {
    for (const std::uint64_t key : keys) {
        if (shift == 48 || key >> (shift + 16) == high) ++counts[key >> shift & 0xffff];
    }
}

void FirstTile::ids_at(std::uint64_t key, std::vector<std::uint32_t>& ids) const {
    for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) {
        if (area == key) ids.push_back(input.vertex_id[v]);
    });
}

bool FirstTile::busy(double bound_key, std::uint32_t bound_id) const {
    const std::pair last{std::bit_cast<std::uint64_t>(bound_key), bound_id};
    bool any = false;
    for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) { any = any || std::pair{area, input.vertex_id[v]} <= last; });
    return any;
}

std::pair<std::uint64_t, std::uint32_t> FirstTile::smallest() const {
    std::pair<std::uint64_t, std::uint32_t> least{~std::uint64_t{0}, kNone};
    if (keys.empty()) return least;
    for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) { least = std::min(least, std::pair{area, input.vertex_id[v]}); });
    return least;
}

void FirstTile::pairs_in(int shift, std::uint64_t prefix, std::vector<std::uint64_t>& keys_found, std::vector<std::uint32_t>& ids) const {
    if (keys.empty()) return;
    for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) {
        if (area >> shift == prefix) {
            keys_found.push_back(area);
            ids.push_back(input.vertex_id[v]);
        }
    });
}

std::vector<std::uint32_t> FirstTile::open_chains() const {
    std::vector<std::uint32_t> open;
    for (std::size_t p = 0; p < input.chain_id.size(); ++p) {
        if (input.whole_level[p] != kOpenChain && input.whole_level[p] > input.level && !input.settled[p]) open.push_back(input.chain_id[p]);
    }
    return open;
}

TileInput FirstTile::run_input(bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) const {
    TileInput in = input;
    in.map.control_points = std::move(points);
    in.marks = marks;
    in.bound_key = bound_key;
    in.bound_id = bound_id;
    if (marks) {
        const std::pair last{std::bit_cast<std::uint64_t>(bound_key), bound_id};
        in.marked.assign(in.vertex_id.size(), 0);
        for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) {
            if (std::pair{area, input.vertex_id[v]} <= last) in.marked[v] = 1;
        });
    }
    if (!waits.empty()) {
        // (By the tile's own vertices' indices; a wait names no cut end.)
        std::vector<std::pair<std::uint32_t, std::uint32_t>> own;  // (id, index)
        for (std::uint32_t v = 0; v < in.vertex_id.size(); ++v) {
            if (!cut_end[v]) own.emplace_back(in.vertex_id[v], v);
        }
        std::sort(own.begin(), own.end());
        const auto index = [&](std::uint32_t id) { return std::lower_bound(own.begin(), own.end(), std::pair{id, std::uint32_t{0}})->second; };
        for (const auto& [waiter, blocker] : waits) in.waits.emplace_back(index(waiter), index(blocker));
        std::sort(in.waits.begin(), in.waits.end());
    }
    return in;
}

namespace {

// Searches of a list sorted by id for ids that mostly come in ascending order (a piece's vertex
// ids are its chain's, ascending but at a ring's start): each search gallops on from where the
// last one ended, so a tile reads the round's news, millions of states early on, near where it
// read last instead of a binary search's cache misses (most of an advance's time on GSHHG).
class SortedWalk {
public:
    explicit SortedWalk(std::span<const std::pair<std::uint32_t, std::uint8_t>> list) : list_(list) {}
    // The entry for `id`, or none.
    const std::pair<std::uint32_t, std::uint8_t>* find(std::uint32_t id) {
        const auto below = [](const std::pair<std::uint32_t, std::uint8_t>& e, std::uint32_t i) { return e.first < i; };
        const std::size_t n = list_.size();
        std::size_t lo = 0, hi = n;  // the first entry ≥ id is in [lo, hi]
        if (at_ > 0 && list_[at_ - 1].first >= id) {
            hi = at_ - 1;
        } else {
            lo = at_;
            hi = std::min(n, lo + 1);
            for (std::size_t step = 1; lo + step <= n && list_[lo + step - 1].first < id; step *= 2) {
                lo += step;  // (all before it are below id; the next look is at lo + 2 step − 1)
                hi = std::min(n, lo + 2 * step);
            }
        }
        at_ = static_cast<std::size_t>(std::lower_bound(list_.begin() + static_cast<std::ptrdiff_t>(lo), list_.begin() + static_cast<std::ptrdiff_t>(hi), id, below) - list_.begin());
        return at_ < n && list_[at_].first == id ? &list_[at_] : nullptr;
    }

private:
    std::span<const std::pair<std::uint32_t, std::uint8_t>> list_;
    std::size_t at_ = 0;
};

}  // namespace

FirstTile::Advanced FirstTile::advance(const TileNews& news, bool ran, const GridPlan& plan, bool marks, const Ranking& ranking) {
    constexpr auto removed = static_cast<std::uint8_t>(VertexState::removed);
    constexpr auto fixed = static_cast<std::uint8_t>(VertexState::fixed);
    const TileInput& in = input;
    SortedWalk states(news.states), outcome_states(news.outcome_states);
    const auto state_of = [&](std::uint32_t v) {
        const std::uint32_t id = in.vertex_id[v];
        if (const auto* at = states.find(id)) return at->second;
        if (const auto* at = outcome_states.find(id)) return at->second;
        return in.state[v];
    };
    const auto unlinked = [&](std::uint32_t id) -> const Unlinked* {
        const auto at = std::lower_bound(news.unlinked.begin(), news.unlinked.end(), id, [](const Unlinked& u, std::uint32_t i) { return u.id < i; });
        return at != news.unlinked.end() && at->id == id ? &*at : nullptr;
    };
    const auto here = [&](Point p) { return plan.block_column(p, in.level) == in.column && plan.block_row(p, in.level) == in.row; };
    // The pieces again: each piece's live vertices; a cut end that went (only the levels from T up
    // remove one: its segment into the tile crosses the border) gives way to the live vertex
    // beyond it, which, if in the tile, is the next piece's first (the two join).
    TileInput out;
    out.level = in.level;
    out.column = in.column;
    out.row = in.row;
    std::vector<std::uint8_t> cuts, frozen_now, marked_now;
    const auto take = [&](std::uint32_t id, Point p, std::uint8_t state, bool cut, std::uint8_t mark = 0) {
        out.map.vertices.push_back(p);
        out.vertex_id.push_back(id);
        out.state.push_back(state);
        cuts.push_back(cut ? 1 : 0);
        marked_now.push_back(mark);
    };
    const auto start = [&](std::uint32_t p) {
        const auto first = static_cast<std::uint32_t>(out.vertex_id.size());
        const std::uint32_t c = in.chain_id[p];
        const bool whole = in.whole_level[p] != kOpenChain && in.whole_level[p] <= in.level;
        out.map.chains.push_back({first, first});
        out.chain_id.push_back(c);
        out.whole_level.push_back(in.whole_level[p]);
        out.settled.push_back(0);
        out.distinct.push_back(whole ? news.distinct.at(c) : 0);
        out.orientation.push_back(whole ? news.orientation.at(c) : std::int8_t{2});
        frozen_now.push_back(frozen[p]);
    };
    const auto joined = [] { return std::logic_error("a kept tile's pieces do not join as their cut ends say"); };
    Advanced done;
    bool open = false;  // the last piece goes on into the next piece of its chain here
    std::vector<std::uint32_t> live;
    for (std::uint32_t p = 0; p < in.map.chains.size(); ++p) {
        const Chain piece = in.map.chains[p];
        const bool before = cut_end[piece.first] != 0, after = cut_end[piece.last] != 0;
        live.clear();
        for (std::uint32_t v = piece.first + (before ? 1 : 0); v + (after ? 1 : 0) <= piece.last; ++v) {
            if (state_of(v) != removed) live.push_back(v);
        }
        if (live.empty()) continue;  // (the pieces on either side have their cut ends past it)
        if (before) {
            const std::uint32_t c = in.vertex_id[piece.first];
            const Unlinked* gone = unlinked(c);
            if (gone != nullptr && here(gone->prev_point)) {
                if (!open || out.vertex_id.back() != gone->prev || out.chain_id.back() != in.chain_id[p]) throw joined();
                ++done.pieces_joined;
            } else {
                if (open) throw joined();
                start(p);
                if (gone != nullptr) {
                    ++done.cut_ends_moved;
                    take(gone->prev, gone->prev_point, fixed, true);
                } else {
                    take(c, in.map.vertices[piece.first], fixed, true);
                }
            }
        } else {
            if (open) throw joined();
            start(p);
        }
        for (const std::uint32_t v : live) take(in.vertex_id[v], in.map.vertices[v], state_of(v), false, marked.empty() ? 0 : marked[v]);
        open = false;
        if (after) {
            const std::uint32_t c = in.vertex_id[piece.last];
            if (const Unlinked* gone = unlinked(c); gone == nullptr) {
                take(c, in.map.vertices[piece.last], fixed, true);
            } else if (here(gone->next_point)) {
                open = true;
            } else {
                ++done.cut_ends_moved;
                take(gone->next, gone->next_point, fixed, true);
            }
        }
        if (!open) out.map.chains.back().last = static_cast<std::uint32_t>(out.vertex_id.size() - 1);
    }
    if (open) throw joined();
    // The waits among its own vertices: its outcome's if it ran, then the top's for what the top
    // judged; its outcome's on a vertex outside (a cut end) go to the lead.
    std::vector<std::uint32_t> own;
    for (std::size_t v = 0; v < out.vertex_id.size(); ++v) {
        if (!cuts[v]) own.push_back(out.vertex_id[v]);
    }
    std::sort(own.begin(), own.end());
    const auto mine = [&](std::uint32_t id) { return std::binary_search(own.begin(), own.end(), id); };
    if (ran) {
        waits.clear();
        for (const auto& wait : news.tile_waits) {
            if (!mine(wait.first)) continue;
            (mine(wait.second) ? waits : done.across).push_back(wait);
        }
    }
    std::erase_if(waits, [&](const auto& wait) { return std::binary_search(news.judged.begin(), news.judged.end(), wait.first); });
    for (const auto& wait : news.top_waits) {
        if (mine(wait.first) && mine(wait.second)) waits.push_back(wait);
    }
    std::sort(waits.begin(), waits.end());
    input = std::move(out);
    cut_end = std::move(cuts);
    frozen = std::move(frozen_now);
    if (!marked.empty()) marked = std::move(marked_now);
    std::vector<std::uint8_t>().swap(improper);
    // A count target's keys: its queued vertices' ranks between their live neighbours now.
    keys.clear();
    if (marks) {
        const Point* q = input.map.vertices.data();
        for (std::uint32_t v = 0; v < input.state.size(); ++v) {
            if (input.state[v] == static_cast<std::uint8_t>(VertexState::queued)) {
                keys.push_back(std::bit_cast<std::uint64_t>(rank_of(q[v - 1], q[v], q[v + 1], ranking)));
            }
        }
    }
    return done;
}

void FirstTile::mark(double bound_key, std::uint32_t bound_id) {
    const std::pair last{std::bit_cast<std::uint64_t>(bound_key), bound_id};
    marked.assign(input.vertex_id.size(), 0);
    for_each_keyed(*this, [&](std::uint32_t v, std::uint64_t area) {
        if (std::pair{area, input.vertex_id[v]} <= last) marked[v] = 1;
    });
}

std::vector<RingLocations> FirstTile::crossing_locations() const {
    const TileInput& in = input;
    std::vector<RingLocations> rings;
    for (std::uint32_t p = 0; p < in.map.chains.size(); ++p) {
        if (in.whole_level[p] == kOpenChain || in.whole_level[p] <= in.level) continue;
        if (rings.empty() || rings.back().chain != in.chain_id[p]) rings.push_back({in.chain_id[p], {}});
        std::vector<Point>& at = rings.back().locations;
        const auto add = [&](std::uint32_t v) {
            const Point q = in.map.vertices[v];
            if (at.size() < 4 && std::none_of(at.begin(), at.end(), [&](Point e) { return same_location(e, q); })) at.push_back(q);
        };
        const Chain piece = in.map.chains[p];
        if (cut_end[piece.first]) {
            add(piece.first);
            add(piece.first + 1);
        }
        if (cut_end[piece.last]) {
            add(piece.last - 1);
            add(piece.last);
        }
    }
    return rings;
}

void FirstTile::settle(std::span<const std::uint32_t> settled) {
    for (std::size_t p = 0; p < input.chain_id.size(); ++p) {
        const bool split = input.whole_level[p] != kOpenChain && input.whole_level[p] > input.level;
        input.settled[p] = split && std::binary_search(settled.begin(), settled.end(), input.chain_id[p]) ? 1 : 0;
    }
}

std::vector<std::pair<std::uint32_t, std::uint8_t>> changed_states(std::span<const TileOutcome> outcomes) {
    std::vector<std::pair<std::uint32_t, std::uint8_t>> changed;
    for (const TileOutcome& outcome : outcomes) {
        for (std::size_t k = 0; k < outcome.ids.size(); ++k) changed.emplace_back(outcome.ids[k], outcome.states[k]);
    }
    std::sort(changed.begin(), changed.end());
    return changed;
}

LiveVertices live_vertices(const FirstTile& tile, std::span<const std::pair<std::uint32_t, std::uint8_t>> changed, bool marks,
                           double bound_key, std::uint32_t bound_id) {
    const TileInput& in = tile.input;
    std::vector<std::uint8_t> marked;
    if (marks) {
        const std::pair last{std::bit_cast<std::uint64_t>(bound_key), bound_id};
        marked.assign(in.vertex_id.size(), 0);
        for_each_keyed(tile, [&](std::uint32_t v, std::uint64_t area) {
            if (std::pair{area, in.vertex_id[v]} <= last) marked[v] = 1;
        });
    }
    // The tile's own vertices, ascending: its pieces come in the map's order, each in its chain's.
    LiveVertices live;
    for (std::uint32_t v = 0; v < in.vertex_id.size(); ++v) {
        if (tile.cut_end[v]) continue;
        std::uint8_t state = in.state[v];
        const auto now = std::lower_bound(changed.begin(), changed.end(), std::pair{in.vertex_id[v], std::uint8_t{0}});
        if (now != changed.end() && now->first == in.vertex_id[v]) state = now->second;
        if (state == static_cast<std::uint8_t>(VertexState::removed)) continue;
        live.ids.push_back(in.vertex_id[v]);
        live.points.push_back(in.map.vertices[v]);
        live.states.push_back(state);
        if (marks) live.marked.push_back(marked[v]);
    }
    return live;
}

FirstRoundLead::FirstRoundLead(const GridPlan& plan, unsigned tile_level, const SimplifyOptions& options, std::uint64_t vertices)
    : plan_(plan), t_(std::min(tile_level, plan.levels)), options_(options), vertices_(vertices) {
    const Target target = options.stop.target;
    marks_ = target != Target::max && target != Target::max_area;
}

FirstRoundLead::~FirstRoundLead() = default;

void FirstRoundLead::add_facts(const ChainFacts& facts, std::uint32_t first_chain) {
    if (first_chain != chains_.size()) throw std::invalid_argument("FirstRound: the parts' chains are not in order");
    chains_.insert(chains_.end(), facts.chains.begin(), facts.chains.end());
    whole_level_.insert(whole_level_.end(), facts.whole_level.begin(), facts.whole_level.end());
    distinct_.insert(distinct_.end(), facts.distinct.begin(), facts.distinct.end());
    orientation_.insert(orientation_.end(), facts.orientation.begin(), facts.orientation.end());
}

void FirstRoundLead::add_control_points(std::span<const Point> points) {
    control_points_.insert(control_points_.end(), points.begin(), points.end());
}

void FirstRoundLead::found(std::span<const std::uint32_t> border, const exact::PredicateStats& predicates) {
    border_.insert(border_.end(), border.begin(), border.end());
    border_sorted_ = false;
    so_far_.stats.predicates += predicates;
}

const std::vector<std::uint32_t>& FirstRoundLead::border() {
    if (!border_sorted_) {
        std::sort(border_.begin(), border_.end());
        border_.erase(std::unique(border_.begin(), border_.end()), border_.end());
        border_sorted_ = true;
    }
    return border_;
}

void FirstRoundLead::queued(std::uint64_t pinned, std::uint64_t keys) {
    so_far_.stats.pinned_by_crossing += pinned;
    queued_ += keys;
}

std::uint64_t FirstRoundLead::wanted() {
    SimplifyStats& stats = so_far_.stats;
    stats.control_points = control_points_.size();
    stats.levels = plan_.levels;
    const Target target = options_.stop.target;
    so_far_.bound_key = marks_ ? 0 : target == Target::max ? std::numeric_limits<double>::infinity() : options_.stop.value;
    so_far_.bound_id = kNone;
    so_far_.work = static_cast<double>(vertices_);
    so_far_.rounds_started = 1;
    if (!marks_) return 0;
    so_far_.goal = removal_goal(options_.stop, vertices_);
    stats.removal_goal = so_far_.goal;
    so_far_.work = static_cast<double>(so_far_.goal);
    if (so_far_.goal >= removable_at_most(chains_, whole_level_, distinct_, queued_)) {
        // As the single process decides it (sweeps_as_max): --max's one sweep; the tiles' keys
        // are not asked for.
        stats.swept_as_max = true;
        marks_ = false;
        so_far_.bound_key = std::numeric_limits<double>::infinity();
        so_far_.work = static_cast<double>(vertices_);
        return 0;
    }
    if (so_far_.goal == 0 || queued_ == 0) return 0;
    so_far_.round_budget = std::min<std::uint64_t>(so_far_.goal, queued_);
    return so_far_.round_budget;
}

void FirstRoundLead::bound(parallel::KeyedSelection selection) {
    so_far_.bound_key = std::bit_cast<double>(selection.key);
    so_far_.bound_id = selection.id;
    so_far_.stats.rounds = 1;
}

void FirstRoundLead::next_bound(parallel::KeyedSelection selection) {
    so_far_.bound_key = std::bit_cast<double>(selection.key);
    so_far_.bound_id = selection.id;
    ++so_far_.stats.rounds;
}

const std::vector<std::vector<std::uint32_t>>& FirstRoundLead::groups(std::vector<TileFacts> tiles) {
    // Tiles joined by the split rings their cut ends do not settle, in the order of their first
    // tiles; those without a busy tile sit the round out.
    std::sort(tiles.begin(), tiles.end(), [](const TileFacts& a, const TileFacts& b) { return a.number < b.number; });
    const auto open = [&](std::uint32_t i, auto&& join) {
        for (const std::uint32_t c : tiles[i].open_chains) join(c);
    };
    groups_ = group_tiles(static_cast<std::uint32_t>(tiles.size()), open, [&](std::uint32_t i) { return !marks_ || tiles[i].busy; });
    for (std::vector<std::uint32_t>& group : groups_) {
        for (std::uint32_t& i : group) i = tiles[i].number;
    }
    // Control points to their tiles, once (only those of tiles holding vertices are asked for).
    if (point_tiles_.size() != control_points_.size()) {
        const auto columns = ((plan_.grid.base_columns - 1) >> (plan_.shift + t_)) + 1;
        point_tiles_.clear();
        point_tiles_.reserve(control_points_.size());
        for (std::uint32_t j = 0; j < control_points_.size(); ++j) {
            const Point p = control_points_[j];
            point_tiles_.emplace_back(plan_.block_row(p, t_) * columns + plan_.block_column(p, t_), j);
        }
        std::sort(point_tiles_.begin(), point_tiles_.end());
    }
    return groups_;
}

std::vector<Point> FirstRoundLead::points(std::uint32_t tile) const {
    std::vector<Point> out;
    auto at = std::lower_bound(point_tiles_.begin(), point_tiles_.end(), std::pair{tile, std::uint32_t{0}});
    for (; at != point_tiles_.end() && at->first == tile; ++at) out.push_back(control_points_[at->second]);
    return out;
}

std::uint64_t FirstRoundLead::points_in(std::uint32_t tile) const {
    const auto from = std::lower_bound(point_tiles_.begin(), point_tiles_.end(), std::pair{tile, std::uint32_t{0}});
    const auto to = std::lower_bound(from, point_tiles_.end(), std::pair{tile + 1, std::uint32_t{0}});
    return static_cast<std::uint64_t>(to - from);
}

std::unique_ptr<MapInParts> FirstRoundLead::finish(std::vector<LiveVertices> live, std::span<const TileOutcome> outcomes,
                                                   std::uint64_t here_below) {
    SimplifyStats& stats = so_far_.stats;
    for (const TileOutcome& outcome : outcomes) take(outcome);
    // The tiles' live vertices merged by id (each tile's ascending, the tiles' disjoint).
    std::size_t count = 0;
    for (const LiveVertices& tile : live) count += tile.ids.size();
    if (count + stats.removed != vertices_) throw std::invalid_argument("the tiles' live vertices and removals do not add up to the map's");
    std::vector<std::pair<std::uint32_t, std::uint32_t>> order;  // (id, tile)
    order.reserve(count);
    for (std::uint32_t k = 0; k < live.size(); ++k) {
        for (const std::uint32_t id : live[k].ids) order.emplace_back(id, k);
    }
    std::sort(order.begin(), order.end());
    TileInput top;
    top.level = plan_.levels;
    top.first_level = t_;
    top.map.vertices.reserve(count);
    top.vertex_id.reserve(count);
    top.state.reserve(count);
    if (marks_) top.marked.reserve(count);
    std::vector<std::size_t> next(live.size(), 0);
    for (const auto& [id, k] : order) {
        const LiveVertices& from = live[k];
        const std::size_t i = next[k]++;
        top.map.vertices.push_back(from.points[i]);
        top.vertex_id.push_back(id);
        top.state.push_back(from.states[i]);
        if (marks_) top.marked.push_back(from.marked[i]);
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>>().swap(order);
    std::vector<LiveVertices>().swap(live);
    // (Every id the tiles name must be a live vertex's, and the chains' ends must be live: chain
    // ends never go. A tile's live vertices missing, or an outcome of another map, is refused.)
    const auto local = [&](std::uint32_t id) {
        const auto at = std::lower_bound(top.vertex_id.begin(), top.vertex_id.end(), id);
        if (at == top.vertex_id.end() || *at != id) throw std::invalid_argument("the tiles' outcomes and live vertices do not agree");
        return static_cast<std::uint32_t>(at - top.vertex_id.begin());
    };
    for (std::size_t i = 1; i < top.vertex_id.size(); ++i) {
        if (top.vertex_id[i] == top.vertex_id[i - 1]) throw std::invalid_argument("a live vertex comes from two tiles");
    }
    for (std::uint32_t c = 0; c < chains_.size(); ++c) {
        top.map.chains.push_back({local(chains_[c].first), local(chains_[c].last)});  // (chain ends never go)
        if (top.map.chains.back().first != (c == 0 ? 0 : top.map.chains[c - 1].last + 1)) {
            throw std::invalid_argument("the tiles' live vertices do not cover the map's chains");
        }
        top.chain_id.push_back(c);
        top.whole_level.push_back(whole_level_[c]);
        top.settled.push_back(0);
        top.distinct.push_back(distinct_[c]);
        top.orientation.push_back(orientation_[c]);
    }
    if (top.vertex_id.size() != (chains_.empty() ? 0 : top.map.chains.back().last + 1)) {
        throw std::invalid_argument("the tiles' live vertices do not cover the map's chains");
    }
    top.map.control_points = std::move(control_points_);
    top.later.assign(plan_.levels - t_, {});
    for (const TileOutcome& outcome : outcomes) {
        for (const auto& [waiter, blocker] : outcome.waits) top.waits.emplace_back(local(waiter), local(blocker));
        for (std::size_t k = 0; k < outcome.later.size() && t_ + k < plan_.levels; ++k) {
            for (const std::uint32_t v : outcome.later[k]) top.later[k].push_back(local(v));
        }
    }
    std::sort(top.waits.begin(), top.waits.end());
    top.marks = marks_;
    top.bound_key = so_far_.bound_key;
    top.bound_id = so_far_.bound_id;
    return std::unique_ptr<MapInParts>(new MapInParts(std::move(top), vertices_, plan_, options_, t_, here_below, so_far_));
}

void FirstRoundLead::take(const TileOutcome& outcome) {
    SimplifyStats& stats = so_far_.stats;
    for (const auto& [chain, lost] : outcome.locations_lost) distinct_[chain] -= lost;
    for (std::size_t k = 0; k < outcome.oriented.size(); ++k) orientation_[outcome.oriented[k]] = outcome.orientations[k];
    stats.removed += outcome.stats.removed;
    stats.blocked_by_point += outcome.stats.blocked_by_point;
    stats.blocked_by_ring += outcome.stats.blocked_by_ring;
    stats.blocked_by_coincidence += outcome.stats.blocked_by_coincidence;
    stats.predicates += outcome.stats.predicates;
}

FirstRound::FirstRound(const GridPlan& plan, unsigned tile_level, const SimplifyOptions& options, std::uint64_t vertices)
    : lead_(plan, tile_level, options, vertices) {}

FirstRound::~FirstRound() = default;

void FirstRound::add_chains(const MapData& part, std::uint32_t first_vertex, std::uint32_t first_chain) {
    CutPart cut = cut_part(part, first_vertex, first_chain, lead_.plan(), lead_.tile_level(), lead_.options());
    lead_.add_facts(cut.facts, first_chain);
    for (FirstTile& tile : cut.tiles) {
        const auto [at, fresh] = tiles_.try_emplace(tile.number);
        if (fresh) {
            at->second = std::move(tile);
        } else {
            at->second.add(std::move(tile));
        }
    }
}

void FirstRound::add_control_points(std::span<const Point> points) { lead_.add_control_points(points); }

std::size_t FirstRound::split() {
    const SimplifyOptions& options = lead_.options();
    // The crossing search, tile by tile (on all threads, a tile each).
    std::vector<FirstTile*> all;
    for (auto& [k, tile] : tiles_) all.push_back(&tile);
    const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
    const auto count = static_cast<std::ptrdiff_t>(all.size());
    std::vector<std::vector<std::uint32_t>> found(all.size());
    std::vector<exact::PredicateStats> predicates(all.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (std::ptrdiff_t i = 0; i < count; ++i) {
        const auto k = static_cast<std::size_t>(i);
        found[k] = all[k]->search(options.arithmetic, predicates[k]);
    }
    for (std::size_t k = 0; k < all.size(); ++k) lead_.found(found[k], predicates[k]);
    const std::vector<std::uint32_t>& border = lead_.border();
    for (FirstTile* tile : all) {
        const std::uint64_t pinned = tile->queue(border, lead_.marks(), options.ranking);
        lead_.queued(pinned, tile->queued());
    }
    // The first budget, selected digit by digit from the tiles' histograms (no keys gathered).
    if (const std::uint64_t wanted = lead_.wanted(); wanted > 0) {
        lead_.bound(parallel::select_kth_by_digits(
            all.size(), wanted,
            [&](std::size_t part, int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) { all[part]->histogram(shift, high, counts); },
            [&](std::size_t part, std::uint64_t key, std::vector<std::uint32_t>& ids) { all[part]->ids_at(key, ids); }));
    } else if (lead_.marks()) {
        return 0;  // nothing to go
    }
    std::vector<FirstRoundLead::TileFacts> facts;
    for (const FirstTile* tile : all) {
        if (tile->input.vertex_id.empty()) continue;
        facts.push_back({tile->number, lead_.marks() && tile->busy(lead_.bound_key(), lead_.bound_id()), tile->open_chains()});
    }
    return lead_.groups(std::move(facts)).size();
}

std::vector<TileInput> FirstRound::group(std::size_t k) const {
    std::vector<TileInput> out;
    for (const std::uint32_t number : lead_.groups().at(k)) {
        out.push_back(tiles_.at(number).run_input(lead_.marks(), lead_.bound_key(), lead_.bound_id(), lead_.points(number)));
    }
    return out;
}

std::size_t FirstRound::group_size(std::size_t k) const { return lead_.groups().at(k).size(); }

std::uint64_t FirstRound::group_points(std::size_t k) const {
    std::uint64_t points = 0;
    for (const std::uint32_t number : lead_.groups().at(k)) points += tiles_.at(number).input.vertex_id.size() + lead_.points_in(number);
    return points;
}

std::unique_ptr<MapInParts> FirstRound::finish(std::span<const TileOutcome> outcomes, std::uint64_t here_below) {
    // The tiles' vertices are read once, the removed ones left out, each tile freed as it is read.
    std::vector<std::pair<std::uint32_t, std::uint8_t>> changed = changed_states(outcomes);
    std::vector<LiveVertices> live;
    for (auto& [k, tile] : tiles_) {
        live.push_back(live_vertices(tile, changed, lead_.marks(), lead_.bound_key(), lead_.bound_id()));
        tile = FirstTile();
    }
    tiles_.clear();
    std::vector<std::pair<std::uint32_t, std::uint8_t>>().swap(changed);
    return lead_.finish(std::move(live), outcomes, here_below);
}

}  // namespace toposimp::map
