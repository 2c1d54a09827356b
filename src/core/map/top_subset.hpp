#pragma once
// The levels from the tile level T up as one more tile over a subset of the live map, instead of
// all of it (docs/distributed.md, "The levels from T up over a subset of the live map"). One
// algorithm over two sources: the live map one process holds (MapInParts), and the first round's
// tiles kept where they are, asked in waves (KeptTiles). Internal to the engine.
//
// The subset:
// - runs of `runs` live vertices on either side of each candidate of those levels, and of
//   runs / 8 around each vertex waiting on a vertex of a run (a waiter let go there is judged
//   there); two runs one vertex apart join; a ring that may come down to its last 4 locations
//   comes whole;
// - each run ends with a cut end, the live vertex beyond (fixed here: a removal next to one
//   exhausts the subset, and longer runs are the answer);
// - lone: the live vertices and control points in the runs' boxes, where every triangle the top
//   judges lies (its three corners are of one run), and the vertices the subset's vertices wait
//   on; a lone vertex at the location of a run's vertex or cut end comes with its neighbours (as a
//   run of one: the coincidence rule reads them);
// - per ring cut into runs, its fixed locations outside the runs at each level it is split at
//   (they do not change while the subset runs, or it is exhausted).
// The subset's vertices keep the whole map's order, so every tie breaks as before. Which vertices
// it holds is a closure (every seed's run, every run vertex's waiters, ...): the order in which a
// source answers does not change it.
#include "core/geometry.hpp"
#include "core/map/location_key.hpp"
#include "core/map/tiles.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace toposimp::map::subset {

inline constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

// What build() asks of a source, for a vertex u (the source's index: ascending in the whole map's
// order) or a whole-map chain c:
//   bool known(u)                 its neighbours and facts are here (the live map: always)
//   void learn(std::vector<std::uint32_t> ids)
//                                 one wave: the ids not known are asked for; those no tile holds
//                                 are gone after it
//   bool gone(u)                  removed
//   std::uint32_t prev(u), next(u)  its live neighbours (kNoVertex at a chain's end); if known(u)
//   std::uint32_t chain(u); Point point(u); std::uint8_t state(u), marked(u)
//   bool shared(u)                another live vertex is at its location
//   std::uint32_t blocker(u)      what it waits on, or kNoVertex
//   std::vector<std::uint32_t> waiters(u)
//   std::uint8_t whole_level(c); std::uint32_t distinct(c); std::int8_t orientation(c)
//   void learn_rings(const std::vector<std::uint32_t>& rings)  (sorted) every vertex of theirs known
//   std::uint32_t ring_first(c)
//   const std::vector<std::uint32_t>& later(k)  the candidates of level T + k
//   void in_boxes(const std::vector<Box>& boxes, const std::vector<std::uint32_t>& skip,
//                 std::unordered_set<std::uint32_t>& lone, std::vector<std::uint32_t>& control)
//                                 the live vertices in the boxes but `skip` (sorted), and the
//                                 control points' numbers
//   Point control_point(k); std::uint32_t id(u)  (the whole map's)
//   void ring_piece(c)            a piece of whole ring c goes into the subset
//   void outside(const std::vector<std::uint32_t>& rings, const std::vector<std::uint32_t>& runs,
//                unsigned t, TileInput& input)  the rings' fixed locations outside the runs
//   bool marks(); double bound_key(); std::uint32_t bound_id()
// `held` (optional): the subset's vertices but its cut ends.
template <class Source>
TileInput build(Source& source, std::uint32_t runs, unsigned t, unsigned levels, std::vector<std::uint32_t>* held = nullptr) {
    constexpr auto fixed = static_cast<std::uint8_t>(VertexState::fixed);
    constexpr auto queued = static_cast<std::uint8_t>(VertexState::queued);
    const auto learn = [&](std::vector<std::uint32_t> ids) {
        std::erase_if(ids, [&](std::uint32_t id) { return source.known(id); });
        if (ids.empty()) return;
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        source.learn(std::move(ids));
    };
    std::unordered_set<std::uint32_t> in_run, whole_rings;
    std::unordered_map<std::uint32_t, std::uint32_t> run_vertices_of;  // ring → its vertices in runs
    std::vector<std::pair<std::uint32_t, std::uint32_t>> seeds, deferred;  // (vertex, run length either side)
    // A waiter's run: shorter (a waiter is judged here only if its blocker goes, and the runs
    // around waiters of waiters would spread over the map), as long once runs hold any chain.
    const std::uint32_t waiter_runs = runs >= (1u << 30) ? runs : runs / 8;
    {
        std::vector<std::uint32_t> later;
        for (unsigned level = t; level < levels; ++level) later.insert(later.end(), source.later(level - t).begin(), source.later(level - t).end());
        learn(std::move(later));
        for (unsigned level = t; level < levels; ++level) {
            for (const std::uint32_t v : source.later(level - t)) {
                if (source.known(v) && source.state(v) == queued) seeds.emplace_back(v, runs);
            }
        }
    }
    std::vector<std::uint32_t> fresh;  // the run vertices added since the last pass over the runs' boxes
    const auto into_run = [&](std::uint32_t u) {
        if (!in_run.insert(u).second) return;
        fresh.push_back(u);
        for (const std::uint32_t w : source.waiters(u)) seeds.emplace_back(w, waiter_runs);
        const std::uint32_t c = source.chain(u);
        if (source.whole_level(c) != kOpenChain) ++run_vertices_of[c];
    };
    std::unordered_set<std::uint32_t> cut, lone;
    std::vector<std::uint32_t> control;  // the control points' numbers
    std::vector<std::uint32_t> sorted;   // the runs' vertices
    std::vector<std::uint32_t> needed;   // to learn before the deferred seeds walk again
    std::unordered_set<LocationKey, LocationKeyHash> shared_here;  // of the runs' vertices and cut ends
    std::unordered_map<LocationKey, std::vector<std::uint32_t>, LocationKeyHash> lone_at;  // the shared lone vertices
    for (;;) {
        while (!seeds.empty() || !deferred.empty()) {
            if (seeds.empty()) {
                learn(std::move(needed));
                needed.clear();
                seeds.swap(deferred);
            }
            while (!seeds.empty()) {
                const auto [v, k] = seeds.back();
                seeds.pop_back();
                if (source.gone(v)) continue;
                if (!source.known(v)) {
                    needed.push_back(v);
                    deferred.emplace_back(v, k);
                    continue;
                }
                // (A walk that reaches a vertex not known waits for it: walked again.)
                bool stopped = false;
                into_run(v);
                std::uint32_t u = v;
                for (std::uint32_t i = 0; i < k && source.prev(u) != kNoVertex; ++i) {
                    into_run(u = source.prev(u));
                    if (i + 1 < k && !source.known(u)) {
                        stopped = true;
                        break;
                    }
                }
                if (!stopped) {
                    u = v;
                    for (std::uint32_t i = 0; i < k && source.next(u) != kNoVertex; ++i) {
                        into_run(u = source.next(u));
                        if (i + 1 < k && !source.known(u)) {
                            stopped = true;
                            break;
                        }
                    }
                }
                if (stopped) {
                    needed.push_back(u);
                    deferred.emplace_back(v, k);
                }
            }
            if (!deferred.empty()) continue;
            // The rings that may come down to their last 4 locations, whole.
            std::vector<std::uint32_t> rings;
            for (const auto& [c, count] : run_vertices_of) {
                if (source.distinct(c) <= 4 + count && whole_rings.insert(c).second) rings.push_back(c);
            }
            if (rings.empty()) continue;
            std::sort(rings.begin(), rings.end());
            source.learn_rings(rings);
            for (const std::uint32_t c : rings) {
                for (std::uint32_t w = source.ring_first(c); w != kNoVertex; w = source.next(w)) seeds.emplace_back(w, 0);
            }
        }
        // Every new run vertex, and those beyond it, known.
        learn(fresh);
        for (const std::uint32_t u : fresh) {
            for (const std::uint32_t w : {source.prev(u), source.next(u)}) {
                if (w != kNoVertex) needed.push_back(w);
            }
        }
        learn(std::move(needed));
        needed.clear();
        for (const std::uint32_t u : fresh) {  // (a lone vertex between two runs)
            const std::uint32_t p = source.prev(u), n = source.next(u);
            if (n != kNoVertex && !in_run.count(n) && source.next(n) != kNoVertex && in_run.count(source.next(n))) seeds.emplace_back(n, 0);
            if (p != kNoVertex && !in_run.count(p) && source.prev(p) != kNoVertex && in_run.count(source.prev(p))) seeds.emplace_back(p, 0);
        }
        if (!seeds.empty()) continue;
        // The cut ends, and the shared locations of the new run vertices and cut ends (the
        // coincidence rule reads the neighbours of the lone vertices there).
        std::vector<LocationKey> new_here;
        const auto here = [&](std::uint32_t u) {
            if (source.shared(u) && shared_here.emplace(source.point(u)).second) new_here.emplace_back(source.point(u));
        };
        for (const std::uint32_t u : fresh) {
            cut.erase(u);
            here(u);
        }
        for (const std::uint32_t u : fresh) {
            for (const std::uint32_t w : {source.prev(u), source.next(u)}) {
                if (w != kNoVertex && !in_run.count(w) && cut.insert(w).second) here(w);
            }
        }
        // The box of each run with a new vertex (with its cut ends): the live vertices and control
        // points in it. (Its old box is in it: what was found there is kept.)
        std::vector<Box> boxes;
        std::vector<std::uint32_t> skip;
        {
            std::unordered_set<std::uint32_t> walked;
            for (const std::uint32_t u : fresh) {
                if (walked.count(u)) continue;
                std::uint32_t first = u, last = u;
                while (source.prev(first) != kNoVertex && in_run.count(source.prev(first))) first = source.prev(first);
                while (source.next(last) != kNoVertex && in_run.count(source.next(last))) last = source.next(last);
                const Point p0 = source.point(first);
                Box box{p0.x, p0.y, p0.x, p0.y};
                const auto widen = [&](std::uint32_t w) {
                    if (w == kNoVertex) return;
                    const Point q = source.point(w);
                    box = {std::min(box.min_x, q.x), std::min(box.min_y, q.y), std::max(box.max_x, q.x), std::max(box.max_y, q.y)};
                    skip.push_back(w);
                };
                for (std::uint32_t w = first;; w = source.next(w)) {
                    walked.insert(w);
                    widen(w);
                    if (w == last) break;
                }
                widen(source.prev(first));
                widen(source.next(last));
                boxes.push_back(box);
            }
        }
        fresh.clear();
        std::sort(skip.begin(), skip.end());
        std::unordered_set<std::uint32_t> found;
        source.in_boxes(boxes, skip, found, control);
        // A lone vertex at a shared location of a run's vertex or cut end comes as a run of one.
        // (A location comes in with a box that holds it: by then every vertex there was found.)
        for (const std::uint32_t u : found) {
            if (lone.insert(u).second && source.shared(u)) lone_at[LocationKey(source.point(u))].push_back(u);
        }
        for (const LocationKey key : new_here) {
            if (const auto at = lone_at.find(key); at != lone_at.end()) {
                for (const std::uint32_t u : at->second) {
                    if (!in_run.count(u) && !cut.count(u)) seeds.emplace_back(u, 1);
                }
            }
        }
        if (!seeds.empty()) continue;
        std::erase_if(lone, [&](std::uint32_t u) { return in_run.count(u) || cut.count(u); });
        sorted.assign(in_run.begin(), in_run.end());
        std::sort(sorted.begin(), sorted.end());
        // The vertices the subset's vertices wait on (lone, unless there), and so on.
        std::vector<std::uint32_t> waiting(sorted);
        waiting.insert(waiting.end(), lone.begin(), lone.end());
        while (!waiting.empty()) {
            std::vector<std::uint32_t> fresh_lone;
            for (const std::uint32_t u : waiting) {
                const std::uint32_t b = source.blocker(u);
                if (b != kNoVertex && !in_run.count(b) && !cut.count(b) && lone.insert(b).second) fresh_lone.push_back(b);
            }
            learn(fresh_lone);
            waiting = std::move(fresh_lone);
        }
        break;
    }
    // The subset in the whole map's order: each run with its cut ends a chain, each lone vertex one.
    std::vector<std::uint32_t> all(sorted);
    all.insert(all.end(), cut.begin(), cut.end());
    all.insert(all.end(), lone.begin(), lone.end());
    std::sort(all.begin(), all.end());
    TileInput input;
    input.level = levels;
    input.first_level = t;
    const std::size_t n = all.size();
    input.map.vertices.reserve(n);
    input.vertex_id.reserve(n);
    input.state.reserve(n);
    input.cut_end.reserve(n);
    const bool marks = source.marks();
    const auto role = [&](std::uint32_t u) { return in_run.count(u) ? 2 : cut.count(u) ? 1 : 0; };  // run, cut end, lone
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t u = all[i];
        const int here = role(u);
        bool goes_on = false;  // u continues the chain of all[i − 1]
        if (i > 0 && role(all[i - 1]) != 0 && source.next(all[i - 1]) == u) {
            const int before = role(all[i - 1]);
            goes_on = (before == 2 && here >= 1) || (before == 1 && here == 2);
        }
        if (!goes_on) {
            if (i > 0) input.map.chains.back().last = static_cast<std::uint32_t>(i - 1);
            const std::uint32_t c = source.chain(u);
            input.map.chains.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
            input.chain_id.push_back(c);
            const bool piece = here != 0 && source.whole_level(c) != kOpenChain;
            if (piece && whole_rings.count(c)) source.ring_piece(c);
            input.whole_level.push_back(piece ? source.whole_level(c) : kOpenChain);
            input.settled.push_back(0);
            input.distinct.push_back(piece ? source.distinct(c) : 0);
            input.orientation.push_back(piece ? source.orientation(c) : std::int8_t{2});
        }
        input.map.vertices.push_back(source.point(u));
        input.vertex_id.push_back(source.id(u));
        input.state.push_back(here == 1 ? fixed : source.state(u));
        if (marks) input.marked.push_back(here == 1 ? std::uint8_t{0} : source.marked(u));
        input.cut_end.push_back(here == 1 ? 1 : 0);
    }
    if (n > 0) input.map.chains.back().last = static_cast<std::uint32_t>(n - 1);
    std::sort(control.begin(), control.end());
    control.erase(std::unique(control.begin(), control.end()), control.end());
    for (const std::uint32_t k : control) input.map.control_points.push_back(source.control_point(k));
    const auto local = [&](std::uint32_t v) { return static_cast<std::uint32_t>(std::lower_bound(all.begin(), all.end(), v) - all.begin()); };
    for (const std::uint32_t u : all) {
        if (role(u) == 1) continue;
        if (held != nullptr) held->push_back(u);
        if (const std::uint32_t b = source.blocker(u); b != kNoVertex) input.waits.emplace_back(local(u), local(b));
    }
    std::sort(input.waits.begin(), input.waits.end());
    for (unsigned level = t; level < levels; ++level) {
        std::vector<std::uint32_t>& list = input.later.emplace_back();
        for (const std::uint32_t v : source.later(level - t)) {
            if (!source.gone(v) && source.known(v) && source.state(v) == queued) list.push_back(local(v));
        }
    }
    input.marks = marks;
    input.bound_key = source.bound_key();
    input.bound_id = source.bound_id();
    // The rings cut into runs: their fixed locations outside the runs, level by level.
    std::vector<std::uint32_t> cut_rings;
    for (const auto& [c, count] : run_vertices_of) {
        if (!whole_rings.count(c) && source.whole_level(c) > t) cut_rings.push_back(c);
    }
    std::sort(cut_rings.begin(), cut_rings.end());
    if (!cut_rings.empty()) source.outside(cut_rings, sorted, t, input);
    return input;
}

}  // namespace toposimp::map::subset
