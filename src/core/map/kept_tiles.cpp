// The rounds after the first from the first round's tiles kept (KeptTiles: core/map/tiles.hpp).
#include "core/map/tiles.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace toposimp::map {

KeptTiles::KeptTiles(const FirstRoundLead& lead, std::map<std::uint32_t, FirstTile> tiles) : lead_(lead), tiles_(std::move(tiles)) {
    for (const std::vector<std::uint32_t>& group : lead_.groups()) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
    if (lead_.marks()) {
        for (auto& [k, tile] : tiles_) tile.mark(lead_.bound_key(), lead_.bound_id());
    }
    gone_.assign(lead_.vertices(), 0);
}

void KeptTiles::note_removed(const TileOutcome& outcome) {
    for (std::size_t k = 0; k < outcome.ids.size(); ++k) {
        if (outcome.states[k] == static_cast<std::uint8_t>(VertexState::removed)) gone_.at(outcome.ids[k]) = 1;
    }
}

SimplifyResult KeptTiles::result() const {
    SimplifyResult result;
    result.stats = lead_.stats();
    SimplifyStats& stats = result.stats;
    stats.vertices_in = lead_.vertices();
    stats.vertices_out = stats.vertices_in - stats.removed;
    if (lead_.marks() || stats.swept_as_max) stats.target_reached = stats.removed >= lead_.goal();
    result.kept.resize(gone_.size());
    for (std::size_t v = 0; v < gone_.size(); ++v) result.kept[v] = gone_[v] ? 0 : 1;
    return result;
}

namespace {

// What the levels from T up did (their tile `top` and its outcome), for the kept tiles: the
// states they changed (into `states`), the vertices they removed with the live ones on either
// side after them, what they judged, their waits.
void add_top_news(const TileInput& top, const TileOutcome& outcome, TileNews& news, std::vector<std::pair<std::uint32_t, std::uint8_t>>& states) {
    constexpr auto removed = static_cast<std::uint8_t>(VertexState::removed);
    std::vector<std::uint8_t> state(top.state);
    for (std::size_t k = 0; k < outcome.ids.size(); ++k) {
        const auto at = std::lower_bound(top.vertex_id.begin(), top.vertex_id.end(), outcome.ids[k]);
        if (at == top.vertex_id.end() || *at != outcome.ids[k]) throw std::invalid_argument("the top's outcome names a vertex it did not hold");
        state[static_cast<std::size_t>(at - top.vertex_id.begin())] = outcome.states[k];
        states.emplace_back(outcome.ids[k], outcome.states[k]);
    }
    for (const Chain& chain : top.map.chains) {
        for (std::uint32_t i = chain.first; i <= chain.last; ++i) {
            if (state[i] != removed) continue;
            std::uint32_t before = i, after = i;
            while (before > chain.first && state[before] == removed) --before;
            while (after < chain.last && state[after] == removed) ++after;
            if (state[before] == removed || state[after] == removed) throw std::logic_error("the top removed a vertex at the end of its run");
            news.unlinked.push_back({top.vertex_id[i], top.vertex_id[before], top.vertex_id[after], top.map.vertices[before], top.map.vertices[after]});
        }
    }
    std::sort(news.unlinked.begin(), news.unlinked.end(), [](const Unlinked& a, const Unlinked& b) { return a.id < b.id; });
    for (std::size_t i = 0; i < top.vertex_id.size(); ++i) {
        if (top.cut_end.empty() || !top.cut_end[i]) news.judged.push_back(top.vertex_id[i]);
    }
    std::sort(news.judged.begin(), news.judged.end());
    news.top_waits = outcome.waits;
    std::sort(news.top_waits.begin(), news.top_waits.end());
}

}  // namespace

namespace {

// The last state given for each vertex (`states` in the order given).
std::vector<std::pair<std::uint32_t, std::uint8_t>> last_states(std::vector<std::pair<std::uint32_t, std::uint8_t>> states) {
    std::stable_sort(states.begin(), states.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::pair<std::uint32_t, std::uint8_t>> last;
    for (std::size_t i = 0; i < states.size(); ++i) {
        if (i + 1 < states.size() && states[i + 1].first == states[i].first) continue;
        last.push_back(states[i]);
    }
    return last;
}

}  // namespace

void KeptTiles::advance(TileNews& news, std::vector<std::pair<std::uint32_t, std::uint32_t>>& across) {
    news.distinct = lead_.distinct();
    news.orientation = lead_.orientation();
    const GridPlan& plan = lead_.plan();
    for (auto at = tiles_.begin(); at != tiles_.end();) {
        const bool ran = std::binary_search(running_.begin(), running_.end(), at->first);
        const FirstTile::Advanced done = at->second.advance(news, ran, plan, lead_.marks(), lead_.options().ranking);
        across.insert(across.end(), done.across.begin(), done.across.end());
        counts_.cut_ends_moved += done.cut_ends_moved;
        counts_.pieces_joined += done.pieces_joined;
        at = at->second.input.vertex_id.empty() ? tiles_.erase(at) : std::next(at);
    }
    std::sort(across.begin(), across.end());
    across.erase(std::unique(across.begin(), across.end()), across.end());
    cross_waits_ = std::move(across);
}

bool KeptTiles::finish_tiles(std::span<const TileOutcome> outcomes) {
    constexpr auto waiting = static_cast<std::uint8_t>(VertexState::waiting);
    constexpr auto removed = static_cast<std::uint8_t>(VertexState::removed);
    constexpr auto queued = static_cast<std::uint8_t>(VertexState::queued);
    const unsigned t = lead_.tile_level(), levels = lead_.plan().levels;
    TileNews news;
    std::vector<std::pair<std::uint32_t, std::uint8_t>> changed = changed_states(outcomes);
    later_.assign(levels - t, {});
    for (const TileOutcome& outcome : outcomes) {
        lead_.take(outcome);
        note_removed(outcome);
        removed_ += outcome.stats.removed;
        news.tile_waits.insert(news.tile_waits.end(), outcome.waits.begin(), outcome.waits.end());
        for (std::size_t k = 0; k < outcome.later.size() && t + k < levels; ++k) {
            later_[k].insert(later_[k].end(), outcome.later[k].begin(), outcome.later[k].end());
        }
    }
    std::sort(news.tile_waits.begin(), news.tile_waits.end());
    const auto now = [&](std::uint32_t id, std::uint8_t before) {
        const auto at = std::lower_bound(changed.begin(), changed.end(), std::pair{id, std::uint8_t{0}});
        return at != changed.end() && at->first == id ? at->second : before;
    };
    // The waits across tiles, as MapInParts::finish_tiles keeps them: while the waiter still waits
    // and its blocker is there; a waiter whose blocker went is queued again.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> across;
    std::vector<std::pair<std::uint32_t, std::uint8_t>> queued_again;
    for (const auto& [waiter, blocker] : cross_waits_) {
        if (now(waiter, waiting) != waiting) continue;
        if (now(blocker, queued) == removed) {
            queued_again.emplace_back(waiter, queued);
            ++counts_.queued_again;
        } else {
            across.emplace_back(waiter, blocker);
        }
    }
    changed.insert(changed.end(), queued_again.begin(), queued_again.end());
    news.states = last_states(std::move(changed));
    advance(news, across);  // (with the tiles' outcomes' waits on a cut end)
    running_.clear();
    return std::any_of(later_.begin(), later_.end(), [](const auto& list) { return !list.empty(); });
}

void KeptTiles::finish_top(const TileInput& top, const TileOutcome& outcome) {
    const GridPlan& plan = lead_.plan();
    const unsigned t = lead_.tile_level();
    lead_.take(outcome);
    note_removed(outcome);
    removed_ += outcome.stats.removed;
    TileNews news;
    std::vector<std::pair<std::uint32_t, std::uint8_t>> states;
    add_top_news(top, outcome, news, states);
    news.states = last_states(std::move(states));
    // What the top judged has the top's waits only; those between two tiles are the lead's.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> across;
    for (const auto& wait : cross_waits_) {
        if (!std::binary_search(news.judged.begin(), news.judged.end(), wait.first)) across.push_back(wait);
    }
    const auto tile_of = [&](std::uint32_t id) {
        const Point p = top.map.vertices[static_cast<std::size_t>(std::lower_bound(top.vertex_id.begin(), top.vertex_id.end(), id) - top.vertex_id.begin())];
        return std::pair{plan.block_column(p, t), plan.block_row(p, t)};
    };
    for (const auto& [waiter, blocker] : news.top_waits) {
        if (tile_of(waiter) != tile_of(blocker)) across.emplace_back(waiter, blocker);
    }
    advance(news, across);
    counts_.waits_across += cross_waits_.size();
    for (std::vector<std::uint32_t>& list : later_) std::vector<std::uint32_t>().swap(list);
}

bool KeptTiles::next_round() {
    if (!lead_.marks()) return false;
    const std::uint64_t goal = lead_.goal();
    if (!(removed_ < goal)) return false;
    std::vector<FirstTile*> all;
    std::uint64_t queued = 0;
    for (auto& [k, tile] : tiles_) {
        all.push_back(&tile);
        queued += tile.queued();
    }
    if (queued == 0) return false;
    lead_.next_bound(parallel::select_kth_by_digits(
        all.size(), std::min(goal - removed_, queued),
        [&](std::size_t part, int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) { all[part]->histogram(shift, high, counts); },
        [&](std::size_t part, std::uint64_t key, std::vector<std::uint32_t>& ids) { all[part]->ids_at(key, ids); }));
    // The split rings that their cut ends settle: ≥ 4 distinct locations over the tiles.
    std::map<std::uint32_t, std::vector<Point>> ends;
    for (const FirstTile* tile : all) {
        for (const RingLocations& ring : tile->crossing_locations()) {
            std::vector<Point>& at = ends[ring.chain];
            for (const Point q : ring.locations) {
                if (at.size() < 4 && std::none_of(at.begin(), at.end(), [&](Point e) { return same_location(e, q); })) at.push_back(q);
            }
        }
    }
    std::vector<std::uint32_t> settled;
    for (const auto& [chain, at] : ends) {
        if (at.size() == 4) settled.push_back(chain);
    }
    std::vector<FirstRoundLead::TileFacts> facts;
    for (FirstTile* tile : all) {
        tile->mark(lead_.bound_key(), lead_.bound_id());
        tile->settle(settled);
        facts.push_back({tile->number, tile->busy(lead_.bound_key(), lead_.bound_id()), tile->open_chains()});
    }
    for (const std::vector<std::uint32_t>& group : lead_.groups(std::move(facts))) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
    return true;
}

namespace {

constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

// What a top_subset learns of a live vertex from the tiles.
struct Learnt {
    Point point;
    std::uint32_t chain = 0;
    std::uint32_t prev = kNoVertex, next = kNoVertex;  // (kNoVertex at a chain's end)
    std::uint8_t state = 0, marked = 0;
    bool shared = false;    // another live vertex is at its location
    bool whole = false;     // learnt from its own tile (else a cut end or a point in a box: no neighbours)
};

// A kept tile's answers to a top_subset (the requests a distributed lead would send it): the
// pieces holding given vertices, the pieces of a ring, its vertices in a box, a ring's fixed
// locations outside the subset's runs.
class TileAnswers {
public:
    TileAnswers(const FirstTile& tile, const GridPlan& plan) : tile_(tile), plan_(plan) {
        const TileInput& in = tile.input;
        for (std::uint32_t p = 0; p < in.map.chains.size(); ++p) {
            for (std::uint32_t v = in.map.chains[p].first; v <= in.map.chains[p].last; ++v) {
                if (!tile.cut_end[v]) own_.push_back({in.vertex_id[v], v, p});
            }
        }
        std::sort(own_.begin(), own_.end(), [](const Own& a, const Own& b) { return a.id < b.id; });
        by_x_.resize(own_.size());
        for (std::uint32_t k = 0; k < own_.size(); ++k) by_x_[k] = own_[k].v;
        std::sort(by_x_.begin(), by_x_.end(), [&](std::uint32_t a, std::uint32_t b) {
            const Point pa = in.map.vertices[a], pb = in.map.vertices[b];
            return pa.x < pb.x || (pa.x == pb.x && pa.y < pb.y);
        });
        shared_.assign(in.vertex_id.size(), 0);
        for (std::size_t k = 1; k < by_x_.size(); ++k) {
            if (same_location(in.map.vertices[by_x_[k - 1]], in.map.vertices[by_x_[k]])) shared_[by_x_[k - 1]] = shared_[by_x_[k]] = 1;
        }
    }

    // The piece holding own vertex `id`, if any (its index).
    std::uint32_t piece_of(std::uint32_t id) const {
        const auto at = std::lower_bound(own_.begin(), own_.end(), id, [](const Own& o, std::uint32_t i) { return o.id < i; });
        return at != own_.end() && at->id == id ? at->piece : kNoVertex;
    }
    std::vector<std::uint32_t> pieces_of_chain(std::uint32_t chain) const {
        std::vector<std::uint32_t> out;
        for (std::uint32_t p = 0; p < tile_.input.chain_id.size(); ++p) {
            if (tile_.input.chain_id[p] == chain) out.push_back(p);
        }
        return out;
    }
    // Piece p's vertices into `learnt`: its own whole, its cut ends as points.
    void learn_piece(std::uint32_t p, std::unordered_map<std::uint32_t, Learnt>& learnt) const {
        const TileInput& in = tile_.input;
        const Chain piece = in.map.chains[p];
        for (std::uint32_t v = piece.first; v <= piece.last; ++v) {
            Learnt& at = learnt[in.vertex_id[v]];
            if (at.whole) continue;
            at.point = in.map.vertices[v];
            at.chain = in.chain_id[p];
            if (tile_.cut_end[v]) continue;
            at.prev = v > piece.first ? in.vertex_id[v - 1] : kNoVertex;
            at.next = v < piece.last ? in.vertex_id[v + 1] : kNoVertex;
            learn_own(v, at);
            at.whole = true;
        }
    }
    // Its own live vertices in the closed box (lone points: no neighbours), but those in `skip`.
    template <class Skip>
    void in_box(const Box& box, Skip&& skip, std::unordered_map<std::uint32_t, Learnt>& learnt, std::vector<std::uint32_t>& found) const {
        const TileInput& in = tile_.input;
        auto at = std::lower_bound(by_x_.begin(), by_x_.end(), box.min_x, [&](std::uint32_t v, double x) { return in.map.vertices[v].x < x; });
        for (; at != by_x_.end() && in.map.vertices[*at].x <= box.max_x; ++at) {
            const Point q = in.map.vertices[*at];
            if (q.y < box.min_y || q.y > box.max_y) continue;
            const std::uint32_t id = in.vertex_id[*at];
            if (skip(id)) continue;
            found.push_back(id);
            Learnt& here = learnt[id];
            if (here.whole) continue;
            here.point = q;
            here.chain = in.chain_id[piece_at(*at)];
            learn_own(*at, here);  // (no neighbours: not whole)
        }
    }
    // Ring `chain`'s first 4 distinct locations at each level in [from, to) among its pieces here
    // (in chain order, keyed by each piece's first own id): its vertices not in runs that are
    // fixed or above the level.
    template <class InRun>
    void outside(std::uint32_t chain, unsigned from, unsigned to, InRun&& in_run,
                 std::vector<std::pair<std::uint32_t, std::vector<std::vector<Point>>>>& pieces) const {
        const TileInput& in = tile_.input;
        for (const std::uint32_t p : pieces_of_chain(chain)) {
            const Chain piece = in.map.chains[p];
            const std::uint32_t first = piece.first + (tile_.cut_end[piece.first] ? 1 : 0);
            const std::uint32_t last = piece.last - (tile_.cut_end[piece.last] ? 1 : 0);
            std::vector<std::vector<Point>> levels(to - from);
            for (unsigned level = from; level < to; ++level) {
                std::vector<Point>& found = levels[level - from];
                for (std::uint32_t v = first; v <= last && found.size() < 4; ++v) {
                    if (in_run(in.vertex_id[v])) continue;
                    const bool fixed = in.state[v] == static_cast<std::uint8_t>(VertexState::fixed);
                    if (!fixed && level_of(v) <= level) continue;
                    const Point q = in.map.vertices[v];
                    if (std::none_of(found.begin(), found.end(), [&](Point e) { return same_location(e, q); })) found.push_back(q);
                }
            }
            pieces.emplace_back(in.vertex_id[first], std::move(levels));
        }
    }

private:
    struct Own {
        std::uint32_t id, v, piece;
    };
    const FirstTile& tile_;
    const GridPlan& plan_;
    std::vector<Own> own_;             // by id
    std::vector<std::uint32_t> by_x_;  // own vertices by (x, y)
    std::vector<std::uint8_t> shared_;

    std::uint32_t piece_at(std::uint32_t v) const { return piece_of(tile_.input.vertex_id[v]); }
    void learn_own(std::uint32_t v, Learnt& at) const {
        at.state = tile_.input.state[v];
        at.marked = tile_.marked.empty() ? 0 : tile_.marked[v];
        at.shared = shared_[v] != 0;
    }
    // The level own vertex v (not a chain's end) is removable at, given its live neighbours.
    unsigned level_of(std::uint32_t v) const {
        const auto level = [&](std::uint32_t a, std::uint32_t b) {
            const Point pa = tile_.input.map.vertices[a], pb = tile_.input.map.vertices[b];
            return static_cast<unsigned>(std::max(std::bit_width(plan_.block_column(pa, 0) ^ plan_.block_column(pb, 0)),
                                                  std::bit_width(plan_.block_row(pa, 0) ^ plan_.block_row(pb, 0))));
        };
        return std::max(level(v, v - 1), level(v, v + 1));
    }
};

}  // namespace

TileInput KeptTiles::top_subset(std::uint32_t runs) const {
    constexpr auto fixed = static_cast<std::uint8_t>(VertexState::fixed);
    constexpr auto queued = static_cast<std::uint8_t>(VertexState::queued);
    const GridPlan& plan = lead_.plan();
    const unsigned t = lead_.tile_level(), levels = plan.levels;
    const std::vector<std::uint8_t>& whole_level = lead_.whole_level();
    const std::vector<std::uint32_t>& distinct = lead_.distinct();
    std::vector<TileAnswers> answers;
    std::vector<std::uint32_t> numbers;
    for (const auto& [k, tile] : tiles_) {
        answers.emplace_back(tile, plan);
        numbers.push_back(k);
    }
    const auto columns = ((plan.grid.base_columns - 1) >> (plan.shift + t)) + 1;
    const auto tile_at = [&](Point p) -> std::size_t {  // (an index into answers, or none)
        const std::uint32_t k = plan.block_row(p, t) * columns + plan.block_column(p, t);
        const auto at = std::lower_bound(numbers.begin(), numbers.end(), k);
        return at != numbers.end() && *at == k ? static_cast<std::size_t>(at - numbers.begin()) : answers.size();
    };
    // The waits: the tiles' own and the lead's across tiles.
    std::unordered_map<std::uint32_t, std::uint32_t> blocker_of;
    std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> waiters_of;
    const auto wait = [&](std::uint32_t waiter, std::uint32_t blocker) {
        blocker_of[waiter] = blocker;
        waiters_of[blocker].push_back(waiter);
    };
    for (const auto& [k, tile] : tiles_) {
        for (const auto& [waiter, blocker] : tile.waits) wait(waiter, blocker);
    }
    for (const auto& [waiter, blocker] : cross_waits_) wait(waiter, blocker);
    const auto blocker = [&](std::uint32_t u) {
        const auto at = blocker_of.find(u);
        return at == blocker_of.end() ? kNoVertex : at->second;
    };
    // What the tiles told, asked for in waves: the pieces holding vertices (where a vertex's tile
    // is not known, every tile is asked), a ring's pieces.
    std::unordered_map<std::uint32_t, Learnt> learnt;
    std::set<std::pair<std::size_t, std::uint32_t>> pieces_learnt;  // (tile, piece)
    const auto whole = [&](std::uint32_t id) {
        const auto at = learnt.find(id);
        return at != learnt.end() && at->second.whole;
    };
    std::vector<std::uint32_t> gone;  // asked for and held by no tile: removed
    const auto ask = [&](std::vector<std::uint32_t> ids) {
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        for (const std::uint32_t id : ids) {
            const auto at = learnt.find(id);
            const std::size_t only = at != learnt.end() ? tile_at(at->second.point) : answers.size();
            bool found = false;
            for (std::size_t i = only < answers.size() ? only : 0; i < (only < answers.size() ? only + 1 : answers.size()); ++i) {
                const std::uint32_t p = answers[i].piece_of(id);
                if (p == kNoVertex) continue;
                found = true;
                if (pieces_learnt.insert({i, p}).second) answers[i].learn_piece(p, learnt);
            }
            if (!found) gone.push_back(id);
        }
        std::sort(gone.begin(), gone.end());
    };
    const auto is_gone = [&](std::uint32_t id) { return std::binary_search(gone.begin(), gone.end(), id); };
    const auto ask_ring = [&](std::uint32_t chain) {
        for (std::size_t i = 0; i < answers.size(); ++i) {
            for (const std::uint32_t p : answers[i].pieces_of_chain(chain)) {
                if (pieces_learnt.insert({i, p}).second) answers[i].learn_piece(p, learnt);
            }
        }
    };
    const auto prev = [&](std::uint32_t u) { return learnt.at(u).prev; };
    const auto next = [&](std::uint32_t u) { return learnt.at(u).next; };

    std::unordered_set<std::uint32_t> in_run, whole_rings;
    std::unordered_map<std::uint32_t, std::uint32_t> run_vertices_of;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> seeds, deferred;
    const std::uint32_t waiter_runs = runs >= (1u << 30) ? runs : runs / 8;
    {
        std::vector<std::uint32_t> later;
        for (const std::vector<std::uint32_t>& list : later_) later.insert(later.end(), list.begin(), list.end());
        ask(later);
        for (const std::vector<std::uint32_t>& list : later_) {
            for (const std::uint32_t v : list) {
                if (whole(v) && learnt.at(v).state == queued) seeds.emplace_back(v, runs);
            }
        }
    }
    const auto into_run = [&](std::uint32_t u) {
        if (!in_run.insert(u).second) return;
        if (const auto at = waiters_of.find(u); at != waiters_of.end()) {
            for (const std::uint32_t w : at->second) seeds.emplace_back(w, waiter_runs);
        }
        const std::uint32_t c = learnt.at(u).chain;
        if (whole_level[c] != kOpenChain) ++run_vertices_of[c];
    };
    std::unordered_set<std::uint32_t> cut, lone;
    std::vector<std::uint32_t> control;
    std::vector<std::uint32_t> sorted;
    std::vector<std::uint32_t> needed;
    for (;;) {
        while (!seeds.empty() || !deferred.empty()) {
            if (seeds.empty()) {
                ask(needed);
                needed.clear();
                seeds.swap(deferred);
            }
            while (!seeds.empty()) {
                const auto [v, k] = seeds.back();
                seeds.pop_back();
                if (is_gone(v)) continue;
                if (!whole(v)) {
                    needed.push_back(v);
                    deferred.emplace_back(v, k);
                    continue;
                }
                // (A walk that reaches a vertex not learnt whole waits for it: walked again.)
                bool stopped = false;
                into_run(v);
                std::uint32_t u = v;
                for (std::uint32_t i = 0; i < k && prev(u) != kNoVertex; ++i) {
                    into_run(u = prev(u));
                    if (i + 1 < k && !whole(u)) {
                        stopped = true;
                        break;
                    }
                }
                if (!stopped) {
                    u = v;
                    for (std::uint32_t i = 0; i < k && next(u) != kNoVertex; ++i) {
                        into_run(u = next(u));
                        if (i + 1 < k && !whole(u)) {
                            stopped = true;
                            break;
                        }
                    }
                }
                if (stopped) {
                    needed.push_back(u);
                    deferred.emplace_back(v, k);
                    continue;
                }
                if (!seeds.empty()) continue;
                for (const auto& [c, count] : run_vertices_of) {
                    if (distinct[c] > 4 + count || whole_rings.count(c)) continue;
                    whole_rings.insert(c);
                    ask_ring(c);
                    for (std::uint32_t w = lead_.chains_by_id()[c].first; w != kNoVertex; w = next(w)) seeds.emplace_back(w, 0);
                }
            }
        }
        // Every vertex of the runs, and those beyond them, learnt whole.
        needed.clear();
        for (const std::uint32_t u : in_run) {
            if (!whole(u)) needed.push_back(u);
        }
        ask(needed);
        needed.clear();
        for (const std::uint32_t u : in_run) {
            for (const std::uint32_t w : {prev(u), next(u)}) {
                if (w != kNoVertex && !whole(w)) needed.push_back(w);
            }
        }
        ask(needed);
        needed.clear();
        sorted.assign(in_run.begin(), in_run.end());
        std::sort(sorted.begin(), sorted.end());
        for (const std::uint32_t u : sorted) {  // (a lone vertex between two runs)
            const std::uint32_t n = next(u);
            if (n != kNoVertex && !in_run.count(n) && next(n) != kNoVertex && in_run.count(next(n))) seeds.emplace_back(n, 0);
        }
        if (!seeds.empty()) continue;
        cut.clear();
        lone.clear();
        control.clear();
        for (const std::uint32_t u : sorted) {
            for (const std::uint32_t w : {prev(u), next(u)}) {
                if (w != kNoVertex && !in_run.count(w)) cut.insert(w);
            }
        }
        // Each run's box (with its cut ends): the live vertices and control points in it.
        const auto skip = [&](std::uint32_t id) { return in_run.count(id) != 0 || cut.count(id) != 0; };
        const std::vector<Point>& points = lead_.control_points();
        for (std::size_t i = 0; i < sorted.size();) {
            std::size_t j = i + 1;
            while (j < sorted.size() && next(sorted[j - 1]) == sorted[j]) ++j;
            const Point p0 = learnt.at(sorted[i]).point;
            Box box{p0.x, p0.y, p0.x, p0.y};
            const auto widen = [&](std::uint32_t u) {
                if (u == kNoVertex) return;
                const Point q = learnt.at(u).point;
                box = {std::min(box.min_x, q.x), std::min(box.min_y, q.y), std::max(box.max_x, q.x), std::max(box.max_y, q.y)};
            };
            for (std::size_t k = i; k < j; ++k) widen(sorted[k]);
            widen(prev(sorted[i]));
            widen(next(sorted[j - 1]));
            std::vector<std::uint32_t> found;
            for (std::uint32_t row = plan.block_row({box.min_x, box.min_y}, t); row <= plan.block_row({box.max_x, box.max_y}, t); ++row) {
                for (std::uint32_t column = plan.block_column({box.min_x, box.min_y}, t); column <= plan.block_column({box.max_x, box.max_y}, t);
                     ++column) {
                    const auto at = std::lower_bound(numbers.begin(), numbers.end(), row * columns + column);
                    if (at != numbers.end() && *at == row * columns + column) {
                        answers[static_cast<std::size_t>(at - numbers.begin())].in_box(box, skip, learnt, found);
                    }
                }
            }
            lone.insert(found.begin(), found.end());
            for (std::uint32_t k = 0; k < points.size(); ++k) {
                const Point q = points[k];
                if (q.x >= box.min_x && q.x <= box.max_x && q.y >= box.min_y && q.y <= box.max_y) control.push_back(k);
            }
            i = j;
        }
        // (The coincidence rule reads the neighbours of the vertices at the location of a run's
        // vertex or cut end, where such a location is shared.)
        std::vector<Point> shared_here;
        for (const std::uint32_t u : sorted) {
            if (learnt.at(u).shared) shared_here.push_back(learnt.at(u).point);
        }
        for (const std::uint32_t u : cut) {
            if (learnt.at(u).shared) shared_here.push_back(learnt.at(u).point);
        }
        std::sort(shared_here.begin(), shared_here.end(), [](Point a, Point b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
        for (const std::uint32_t u : lone) {
            const Learnt& at = learnt.at(u);
            if (!at.shared) continue;
            if (std::binary_search(shared_here.begin(), shared_here.end(), at.point, [](Point a, Point b) { return a.x < b.x || (a.x == b.x && a.y < b.y); })) {
                seeds.emplace_back(u, 1);
            }
        }
        if (!seeds.empty()) continue;
        // The vertices the subset's vertices wait on (lone, unless there), and so on.
        std::vector<std::uint32_t> waiting(sorted);
        waiting.insert(waiting.end(), lone.begin(), lone.end());
        while (!waiting.empty()) {
            std::vector<std::uint32_t> fresh;
            for (const std::uint32_t u : waiting) {
                const std::uint32_t b = blocker(u);
                if (b != kNoVertex && !in_run.count(b) && !cut.count(b) && lone.insert(b).second) fresh.push_back(b);
            }
            ask(fresh);
            waiting = std::move(fresh);
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
    const bool marks = lead_.marks();
    const auto role = [&](std::uint32_t u) { return in_run.count(u) ? 2 : cut.count(u) ? 1 : 0; };
    for (std::size_t i = 0; i < all.size(); ++i) {
        const std::uint32_t u = all[i];
        const Learnt& at = learnt.at(u);
        const int here = role(u);
        bool goes_on = false;
        if (i > 0 && role(all[i - 1]) != 0 && next(all[i - 1]) == u) {
            const int before = role(all[i - 1]);
            goes_on = (before == 2 && here >= 1) || (before == 1 && here == 2);
        }
        if (!goes_on) {
            if (i > 0) input.map.chains.back().last = static_cast<std::uint32_t>(i - 1);
            const std::uint32_t c = at.chain;
            input.map.chains.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
            input.chain_id.push_back(c);
            const bool piece = here != 0 && whole_level[c] != kOpenChain;
            input.whole_level.push_back(piece ? whole_level[c] : kOpenChain);
            input.settled.push_back(0);
            input.distinct.push_back(piece ? distinct[c] : 0);
            input.orientation.push_back(piece ? lead_.orientation()[c] : std::int8_t{2});
        }
        input.map.vertices.push_back(at.point);
        input.vertex_id.push_back(u);
        input.state.push_back(here == 1 ? fixed : at.state);
        if (marks) input.marked.push_back(here == 1 ? std::uint8_t{0} : at.marked);
        input.cut_end.push_back(here == 1 ? 1 : 0);
    }
    if (!all.empty()) input.map.chains.back().last = static_cast<std::uint32_t>(all.size() - 1);
    std::sort(control.begin(), control.end());
    control.erase(std::unique(control.begin(), control.end()), control.end());
    for (const std::uint32_t k : control) input.map.control_points.push_back(lead_.control_points()[k]);
    const auto local = [&](std::uint32_t v) { return static_cast<std::uint32_t>(std::lower_bound(all.begin(), all.end(), v) - all.begin()); };
    for (const std::uint32_t u : all) {
        if (role(u) == 1) continue;
        if (const std::uint32_t b = blocker(u); b != kNoVertex) input.waits.emplace_back(local(u), local(b));
    }
    std::sort(input.waits.begin(), input.waits.end());
    for (unsigned level = t; level < levels; ++level) {
        std::vector<std::uint32_t>& list = input.later.emplace_back();
        for (const std::uint32_t v : later_[level - t]) {
            if (!is_gone(v) && whole(v) && learnt.at(v).state == queued) list.push_back(local(v));
        }
    }
    input.marks = marks;
    input.bound_key = lead_.bound_key();
    input.bound_id = lead_.bound_id();
    // The rings cut into runs: their fixed locations outside the runs, level by level, over
    // their pieces in every tile, in chain order.
    std::vector<std::uint32_t> cut_rings;
    for (const auto& [c, count] : run_vertices_of) {
        if (!whole_rings.count(c) && whole_level[c] > t) cut_rings.push_back(c);
    }
    std::sort(cut_rings.begin(), cut_rings.end());
    const auto running = [&](std::uint32_t id) { return in_run.count(id) != 0; };
    for (const std::uint32_t c : cut_rings) {
        std::vector<std::pair<std::uint32_t, std::vector<std::vector<Point>>>> pieces;
        for (const TileAnswers& tile : answers) tile.outside(c, t, whole_level[c], running, pieces);
        std::sort(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        for (unsigned level = t; level < whole_level[c]; ++level) {
            std::vector<Point> found;
            for (const auto& [first, at_levels] : pieces) {
                for (const Point q : at_levels[level - t]) {
                    if (found.size() < 4 && std::none_of(found.begin(), found.end(), [&](Point e) { return same_location(e, q); })) found.push_back(q);
                }
            }
            input.outside.push_back({c, level, std::move(found)});
        }
    }
    return input;
}

bool KeptTiles::finish_top_subset(const TileInput& top, const TileOutcome& outcome) {
    if (outcome.exhausted) return false;
    finish_top(top, outcome);
    return true;
}

std::vector<TileInput> KeptTiles::group(std::size_t k) const {
    std::vector<TileInput> out;
    for (const std::uint32_t number : lead_.groups().at(k)) {
        out.push_back(tiles_.at(number).run_input(lead_.marks(), lead_.bound_key(), lead_.bound_id(), lead_.points(number)));
    }
    return out;
}

}  // namespace toposimp::map
