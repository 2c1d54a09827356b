// The rounds after the first from the first round's tiles kept (KeptTiles: core/map/tiles.hpp).
#include "core/map/tiles.hpp"
#include "core/map/top_subset.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace toposimp::map {

namespace {

// The tiles in this process.
class LocalStore : public KeptStore {
public:
    LocalStore(KeptBatch tiles, const GridPlan& plan, const SimplifyOptions& options) : tiles_(std::move(tiles)), plan_(plan), options_(options) {}

    FirstTile::Advanced advance(const TileNews& news, std::span<const std::uint32_t> ran) override {
        return tiles_.advance(news, ran, plan_, marks_, options_.ranking);
    }
    std::uint64_t queued() override { return tiles_.queued(); }
    parallel::KeyedSelection select(std::uint64_t wanted) override {
        return parallel::select_kth_by_digits(
            1, wanted, [&](std::size_t, int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) { tiles_.histogram(shift, high, counts); },
            [&](std::size_t, std::uint64_t key, std::vector<std::uint32_t>& ids) { tiles_.ids_at(key, ids); });
    }
    std::vector<RingLocations> crossing_locations() override { return tiles_.crossing_locations(); }
    std::vector<FirstRoundLead::TileFacts> begin_round(std::span<const std::uint32_t> settled, bool marks, double bound_key,
                                                       std::uint32_t bound_id) override {
        return tiles_.begin_round(settled, marks, bound_key, bound_id);
    }
    std::vector<TileOutcome> run(const std::vector<std::vector<std::uint32_t>>& groups, std::vector<std::vector<Point>> points, bool marks,
                                 double bound_key, std::uint32_t bound_id) override {
        std::vector<TileOutcome> outcomes;
        std::size_t k = 0;
        for (const std::vector<std::uint32_t>& group : groups) {
            std::vector<TileInput> inputs;
            for (const std::uint32_t number : group) inputs.push_back(tiles_.input(number, marks, bound_key, bound_id, std::move(points.at(k++))));
            for (TileOutcome& outcome : run_tile_group(std::move(inputs), plan_, options_)) outcomes.push_back(std::move(outcome));
        }
        return outcomes;
    }
    TileInput input(std::uint32_t number, bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) override {
        return tiles_.input(number, marks, bound_key, bound_id, std::move(points));
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits() override { return tiles_.waits(); }
    SubsetAnswer answer(const SubsetAsk& ask) override { return tiles_.answer(ask, plan_); }
    std::size_t tiles() override { return tiles_.tiles(); }

    bool marks_ = false;  // the lead's: a count target's keys kept (not one run as --max)

private:
    KeptBatch tiles_;
    GridPlan plan_;
    const SimplifyOptions& options_;
};

}  // namespace

KeptTiles::KeptTiles(FirstRoundLead lead, std::map<std::uint32_t, FirstTile> tiles) : lead_(std::move(lead)) {
    if (lead_.marks()) {
        for (auto& [k, tile] : tiles) tile.mark(lead_.bound_key(), lead_.bound_id());
    }
    auto store = std::make_unique<LocalStore>(KeptBatch(std::move(tiles)), lead_.plan(), lead_.options());
    store->marks_ = lead_.marks();
    tiles_ = std::move(store);
    for (const std::vector<std::uint32_t>& group : lead_.groups()) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
    gone_.assign(lead_.vertices(), 0);
}

KeptTiles::KeptTiles(FirstRoundLead lead, std::unique_ptr<KeptStore> tiles) : lead_(std::move(lead)), tiles_(std::move(tiles)) {
    for (const std::vector<std::uint32_t>& group : lead_.groups()) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
    gone_.assign(lead_.vertices(), 0);
}

KeptTiles::~KeptTiles() = default;
KeptTiles::KeptTiles(KeptTiles&&) noexcept = default;

std::vector<TileOutcome> KeptTiles::run_groups() {
    std::vector<std::vector<Point>> points;
    for (const std::vector<std::uint32_t>& group : lead_.groups()) {
        for (const std::uint32_t number : group) points.push_back(lead_.points(number));
    }
    return tiles_->run(lead_.groups(), std::move(points), lead_.marks(), lead_.bound_key(), lead_.bound_id());
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
    stats.threads = lead_.options().threads > 0 ? lead_.options().threads : omp_get_max_threads();  // (as the engine says it)
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
    const FirstTile::Advanced done = tiles_->advance(news, running_);
    across.insert(across.end(), done.across.begin(), done.across.end());
    counts_.cut_ends_moved += done.cut_ends_moved;
    counts_.pieces_joined += done.pieces_joined;
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
    // (The tiles' own outcomes' states apart: a store may have them where the tiles are.)
    news.outcome_states = std::move(changed);
    news.states = last_states(std::move(queued_again));
    news.after_tiles = true;
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
    const std::uint64_t queued = tiles_->queued();
    if (queued == 0) return false;
    lead_.next_bound(tiles_->select(std::min(goal - removed_, queued)));
    // The split rings that their cut ends settle: ≥ 4 distinct locations over the tiles.
    std::map<std::uint32_t, std::vector<Point>> ends;
    for (const RingLocations& ring : tiles_->crossing_locations()) {
        std::vector<Point>& at = ends[ring.chain];
        for (const Point q : ring.locations) {
            if (at.size() < 4 && std::none_of(at.begin(), at.end(), [&](Point e) { return same_location(e, q); })) at.push_back(q);
        }
    }
    std::vector<std::uint32_t> settled;
    for (const auto& [chain, at] : ends) {
        if (at.size() == 4) settled.push_back(chain);
    }
    std::vector<FirstRoundLead::TileFacts> facts = tiles_->begin_round(settled, lead_.marks(), lead_.bound_key(), lead_.bound_id());
    for (const std::vector<std::uint32_t>& group : lead_.groups(std::move(facts))) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
    return true;
}

// ---- the tiles' side (KeptBatch) -------------------------------------------------------------

FirstTile::Advanced KeptBatch::advance(const TileNews& news, std::span<const std::uint32_t> ran, const GridPlan& plan, bool marks,
                                       const Ranking& ranking) {
    index_.reset();
    FirstTile::Advanced all;
    for (auto at = tiles_.begin(); at != tiles_.end();) {
        FirstTile::Advanced done = at->second.advance(news, std::binary_search(ran.begin(), ran.end(), at->first), plan, marks, ranking);
        all.across.insert(all.across.end(), done.across.begin(), done.across.end());
        all.cut_ends_moved += done.cut_ends_moved;
        all.pieces_joined += done.pieces_joined;
        at = at->second.input.vertex_id.empty() ? tiles_.erase(at) : std::next(at);
    }
    return all;
}

std::uint64_t KeptBatch::queued() const {
    std::uint64_t count = 0;
    for (const auto& [k, tile] : tiles_) count += tile.queued();
    return count;
}

void KeptBatch::histogram(int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) const {
    for (const auto& [k, tile] : tiles_) tile.histogram(shift, high, counts);
}

void KeptBatch::ids_at(std::uint64_t key, std::vector<std::uint32_t>& ids) const {
    for (const auto& [k, tile] : tiles_) tile.ids_at(key, ids);
}

void KeptBatch::pairs_in(int shift, std::uint64_t prefix, std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& ids) const {
    for (const auto& [k, tile] : tiles_) tile.pairs_in(shift, prefix, keys, ids);
}

std::vector<RingLocations> KeptBatch::crossing_locations() const {
    std::vector<RingLocations> all;
    for (const auto& [k, tile] : tiles_) {
        for (RingLocations& ring : tile.crossing_locations()) all.push_back(std::move(ring));
    }
    return all;
}

std::vector<FirstRoundLead::TileFacts> KeptBatch::begin_round(std::span<const std::uint32_t> settled, bool marks, double bound_key,
                                                              std::uint32_t bound_id) {
    std::vector<FirstRoundLead::TileFacts> facts;
    for (auto& [k, tile] : tiles_) {
        if (marks) tile.mark(bound_key, bound_id);
        tile.settle(settled);
        facts.push_back({tile.number, marks && tile.busy(bound_key, bound_id), tile.open_chains()});
    }
    return facts;
}

TileInput KeptBatch::input(std::uint32_t number, bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) const {
    return tiles_.at(number).run_input(marks, bound_key, bound_id, std::move(points));
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> KeptBatch::waits() const {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> all;
    for (const auto& [k, tile] : tiles_) all.insert(all.end(), tile.waits.begin(), tile.waits.end());
    return all;
}

namespace {

constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

}  // namespace

// ---- a top_subset's questions, answered by the tiles ------------------------------------------

void SubsetAnswer::add(SubsetAnswer&& more) {
    const auto append = [](auto& to, auto& from) { to.insert(to.end(), from.begin(), from.end()); };
    append(ids, more.ids);
    append(chain, more.chain);
    append(prev, more.prev);
    append(next, more.next);
    append(points, more.points);
    append(state, more.state);
    append(marked, more.marked);
    append(flags, more.flags);
    append(in_boxes, more.in_boxes);
    for (Outside& piece : more.outside) outside.push_back(std::move(piece));
}

// A kept tile's answers (KeptBatch::answer): its own vertices by id and by (x, y), and whether
// another of them is at a vertex's location.
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
        std::vector<std::uint32_t> by_x(own_.size());  // (own vertices by (x, y): those at one location side by side)
        for (std::uint32_t k = 0; k < own_.size(); ++k) by_x[k] = own_[k].v;
        std::sort(by_x.begin(), by_x.end(), [&](std::uint32_t a, std::uint32_t b) {
            const Point pa = in.map.vertices[a], pb = in.map.vertices[b];
            return pa.x < pb.x || (pa.x == pb.x && pa.y < pb.y);
        });
        shared_.assign(in.vertex_id.size(), 0);
        for (std::size_t k = 1; k < by_x.size(); ++k) {
            if (same_location(in.map.vertices[by_x[k - 1]], in.map.vertices[by_x[k]])) shared_[by_x[k - 1]] = shared_[by_x[k]] = 1;
        }
        cells_ = PointCells(in.map.vertices, by_x);
    }

    void answer(const SubsetAsk& ask, unsigned tile_level, SubsetAnswer& out) const {
        const TileInput& in = tile_.input;
        // (Around each vertex asked for, `reach` vertices of its piece either side; where two
        // windows meet or overlap, one.)
        std::vector<std::pair<std::uint32_t, std::uint32_t>> windows;  // [from, to] in the tile's vertices
        for (const std::uint32_t id : ask.ids) {
            const auto at = std::lower_bound(own_.begin(), own_.end(), id, [](const Own& o, std::uint32_t i) { return o.id < i; });
            if (at == own_.end() || at->id != id) continue;
            const Chain piece = in.map.chains[at->piece];
            windows.emplace_back(at->v - std::min(at->v - piece.first, ask.reach), at->v + std::min(piece.last - at->v, ask.reach));
        }
        for (std::uint32_t p = 0; p < in.chain_id.size(); ++p) {
            if (std::binary_search(ask.rings.begin(), ask.rings.end(), in.chain_id[p])) windows.emplace_back(in.map.chains[p].first, in.map.chains[p].last);
        }
        std::sort(windows.begin(), windows.end());
        for (std::size_t i = 0; i < windows.size();) {
            auto [from, to] = windows[i];
            for (++i; i < windows.size() && windows[i].first <= to + 1; ++i) to = std::max(to, windows[i].second);
            learn_window(from, to, out);
        }
        for (const Box& box : ask.boxes) {
            const bool meets = plan_.block_column({box.min_x, box.min_y}, tile_level) <= in.column &&
                               in.column <= plan_.block_column({box.max_x, box.max_y}, tile_level) &&
                               plan_.block_row({box.min_x, box.min_y}, tile_level) <= in.row &&
                               in.row <= plan_.block_row({box.max_x, box.max_y}, tile_level);
            if (meets) in_box(box, ask.skip, ask.reach, out);
        }
        for (const std::uint32_t c : ask.outside_rings) outside(c, ask.from_level, ask.runs, out);
    }

private:
    struct Own {
        std::uint32_t id, v, piece;
    };
    const FirstTile& tile_;  // (in its batch's map, whose nodes stay put: the batch holds this index)
    // A copy: the index outlives the answer that built it, and its caller's plan may not (the
    // Python binding's is a local of each call: a reference here once read a dead frame, and
    // the answers then depended on the thread that asked: toposimp.dask, session 51).
    const GridPlan plan_;
    std::vector<Own> own_;             // by id
    PointCells cells_;  // own vertices (a sort by x read every vertex in a box's x range: a fifth of a kept run's work on a coverage)
    std::vector<std::uint8_t> shared_;

    // The piece holding own vertex `id`, if any.
    std::uint32_t piece_of(std::uint32_t id) const {
        const auto at = std::lower_bound(own_.begin(), own_.end(), id, [](const Own& o, std::uint32_t i) { return o.id < i; });
        return at != own_.end() && at->id == id ? at->piece : kNoVertex;
    }
    void add(std::uint32_t v, std::uint32_t chain, std::uint32_t prev, std::uint32_t next, std::uint8_t flags, SubsetAnswer& out) const {
        const bool own = (flags & SubsetAnswer::own) != 0;
        out.ids.push_back(tile_.input.vertex_id[v]);
        out.points.push_back(tile_.input.map.vertices[v]);
        out.chain.push_back(chain);
        out.prev.push_back(prev);
        out.next.push_back(next);
        out.state.push_back(own ? tile_.input.state[v] : std::uint8_t{0});
        out.marked.push_back(own && !tile_.marked.empty() ? tile_.marked[v] : std::uint8_t{0});
        out.flags.push_back(static_cast<std::uint8_t>(flags | (own && shared_[v] ? SubsetAnswer::shared : 0)));
    }
    // The tile's vertices [from, to] (of one piece, or of consecutive pieces): its own whole, with
    // their neighbours, and those neighbours beyond the window as points; its cut ends as points.
    void learn_window(std::uint32_t from, std::uint32_t to, SubsetAnswer& out) const {
        const TileInput& in = tile_.input;
        std::uint32_t p = piece_at(from);
        for (std::uint32_t v = from; v <= to; ++v) {
            while (in.map.chains[p].last < v) ++p;
            const Chain piece = in.map.chains[p];
            if (tile_.cut_end[v]) {
                add(v, in.chain_id[p], kNoVertex, kNoVertex, 0, out);
                continue;
            }
            if (v == from && v > piece.first) add(v - 1, in.chain_id[p], kNoVertex, kNoVertex, 0, out);
            add(v, in.chain_id[p], v > piece.first ? in.vertex_id[v - 1] : kNoVertex, v < piece.last ? in.vertex_id[v + 1] : kNoVertex,
                SubsetAnswer::whole | SubsetAnswer::own, out);
            if (v == to && v < piece.last) add(v + 1, in.chain_id[p], kNoVertex, kNoVertex, 0, out);
        }
    }
    // The piece holding the tile's vertex v (own or cut end).
    std::uint32_t piece_at(std::uint32_t v) const {
        const std::vector<Chain>& pieces = tile_.input.map.chains;
        return static_cast<std::uint32_t>(std::partition_point(pieces.begin(), pieces.end(), [&](const Chain& c) { return c.last < v; }) - pieces.begin());
    }
    // Its own live vertices in the closed box, but those in `skip` (sorted): points without their
    // neighbours; but one at a shared location with `reach` vertices of its piece either side, whole
    // (the coincidence rule may make it a run of one: its walk then needs no more questions).
    void in_box(const Box& box, std::span<const std::uint32_t> skip, std::uint32_t reach, SubsetAnswer& out) const {
        const TileInput& in = tile_.input;
        cells_.in_box(box, in.map.vertices, [&](std::uint32_t v) {
            const std::uint32_t id = in.vertex_id[v];
            if (std::binary_search(skip.begin(), skip.end(), id)) return;
            out.in_boxes.push_back(id);
            const std::uint32_t p = piece_of(id);
            if (reach > 0 && shared_[v]) {
                const Chain piece = in.map.chains[p];
                learn_window(v - std::min(v - piece.first, reach), v + std::min(piece.last - v, reach), out);
            } else {
                add(v, in.chain_id[p], kNoVertex, kNoVertex, SubsetAnswer::own, out);
            }
        });
    }

    // Ring `chain`'s pieces here: per level from `from` below the ring's whole level, the first 4
    // distinct locations, in chain order, of its own vertices not in `runs` (sorted) that are fixed
    // or above the level.
    void outside(std::uint32_t chain, unsigned from, std::span<const std::uint32_t> runs, SubsetAnswer& out) const {
        const TileInput& in = tile_.input;
        for (std::uint32_t p = 0; p < in.chain_id.size(); ++p) {
            if (in.chain_id[p] != chain) continue;
            const Chain piece = in.map.chains[p];
            const std::uint32_t first = piece.first + (tile_.cut_end[piece.first] ? 1 : 0);
            const std::uint32_t last = piece.last - (tile_.cut_end[piece.last] ? 1 : 0);
            const unsigned to = in.whole_level[p];
            SubsetAnswer::Outside& at = out.outside.emplace_back();
            at.chain = chain;
            at.first = in.vertex_id[first];
            for (unsigned level = from; level < to; ++level) {
                std::vector<Point>& found = at.levels.emplace_back();
                for (std::uint32_t v = first; v <= last && found.size() < 4; ++v) {
                    if (std::binary_search(runs.begin(), runs.end(), in.vertex_id[v])) continue;
                    const bool fixed = in.state[v] == static_cast<std::uint8_t>(VertexState::fixed);
                    if (!fixed && level_of(v) <= level) continue;
                    const Point q = in.map.vertices[v];
                    if (std::none_of(found.begin(), found.end(), [&](Point e) { return same_location(e, q); })) found.push_back(q);
                }
            }
        }
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

struct KeptBatch::Index {
    std::map<std::uint32_t, TileAnswers> tiles;
};

KeptBatch::KeptBatch(std::map<std::uint32_t, FirstTile> tiles) : tiles_(std::move(tiles)) {}
KeptBatch::KeptBatch() = default;
KeptBatch::~KeptBatch() = default;
KeptBatch::KeptBatch(KeptBatch&&) noexcept = default;
KeptBatch& KeptBatch::operator=(KeptBatch&&) noexcept = default;

SubsetAnswer KeptBatch::answer(const SubsetAsk& ask, const GridPlan& plan) const {
    if (!index_) {
        index_ = std::make_unique<Index>();
        for (const auto& [k, tile] : tiles_) index_->tiles.try_emplace(k, tile, plan);
    }
    SubsetAnswer out;
    for (const auto& [k, tile] : index_->tiles) tile.answer(ask, tiles_.at(k).input.level, out);
    return out;
}

namespace {

// What a top_subset learns of a live vertex from the tiles.
struct Learnt {
    Point point;
    std::uint32_t chain = 0;
    std::uint32_t prev = kNoVertex, next = kNoVertex;  // (kNoVertex at a chain's end)
    std::uint8_t state = 0, marked = 0;
    bool shared = false;  // another live vertex is at its location
    bool own = false;     // state, marked and shared told by its own tile
    bool whole = false;   // and its neighbours: learnt from its own piece
};

}  // namespace

TileInput KeptTiles::top_subset(std::uint32_t runs) const {
    // The subset (top_subset.hpp) over what the tiles tell, asked in waves: windows of `reach`
    // live vertices around the vertices asked for, whole rings, the live vertices in boxes, the
    // rings' fixed locations outside the runs.
    class Told {
    public:
        Told(const KeptTiles& kept, std::uint32_t runs) : kept_(kept), runs_(runs) {
            for (const auto& [waiter, blocker] : kept.tiles_->waits()) wait(waiter, blocker);
            for (const auto& [waiter, blocker] : kept.cross_waits_) wait(waiter, blocker);
        }
        bool known(std::uint32_t id) const {
            const auto at = learnt_.find(id);
            return at != learnt_.end() && at->second.whole;
        }
        // How far around a vertex asked for the tiles tell: a run, its cut end and the vertex beyond.
        std::uint32_t reach() const { return runs_ >= (1u << 30) ? runs_ : std::max(runs_, 2u) + 1; }
        void learn(std::vector<std::uint32_t> ids) {
            SubsetAsk question;
            question.ids = std::move(ids);
            question.reach = reach();
            take(kept_.ask(question));
            for (const std::uint32_t id : question.ids) {
                if (!known(id)) gone_.push_back(id);
            }
            std::sort(gone_.begin(), gone_.end());
        }
        bool gone(std::uint32_t id) const { return std::binary_search(gone_.begin(), gone_.end(), id); }
        std::uint32_t prev(std::uint32_t u) const { return learnt_.at(u).prev; }
        std::uint32_t next(std::uint32_t u) const { return learnt_.at(u).next; }
        std::uint32_t chain(std::uint32_t u) const { return learnt_.at(u).chain; }
        Point point(std::uint32_t u) const { return learnt_.at(u).point; }
        std::uint8_t state(std::uint32_t u) const { return learnt_.at(u).state; }
        std::uint8_t marked(std::uint32_t u) const { return learnt_.at(u).marked; }
        bool shared(std::uint32_t u) const { return learnt_.at(u).shared; }
        std::uint32_t blocker(std::uint32_t u) const {
            const auto at = blocker_of_.find(u);
            return at == blocker_of_.end() ? kNoVertex : at->second;
        }
        std::vector<std::uint32_t> waiters(std::uint32_t u) const {
            const auto at = waiters_of_.find(u);
            return at == waiters_of_.end() ? std::vector<std::uint32_t>{} : at->second;
        }
        std::uint8_t whole_level(std::uint32_t c) const { return kept_.lead_.whole_level()[c]; }
        std::uint32_t distinct(std::uint32_t c) const { return kept_.lead_.distinct()[c]; }
        std::int8_t orientation(std::uint32_t c) const { return kept_.lead_.orientation()[c]; }
        void learn_rings(const std::vector<std::uint32_t>& rings) {
            SubsetAsk question;
            question.rings = rings;
            take(kept_.ask(question));
        }
        std::uint32_t ring_first(std::uint32_t c) const { return kept_.lead_.chains_by_id()[c].first; }
        const std::vector<std::uint32_t>& later(unsigned k) const { return kept_.later_[k]; }
        void in_boxes(const std::vector<Box>& boxes, const std::vector<std::uint32_t>& skip, std::unordered_set<std::uint32_t>& lone,
                      std::vector<std::uint32_t>& control) {
            SubsetAsk question;
            question.boxes = boxes;
            question.skip = skip;
            question.reach = std::min(reach(), 2u);  // (a run of one, its cut ends: the coincidence rule's walk)
            const SubsetAnswer found = take(kept_.ask(question));
            lone.insert(found.in_boxes.begin(), found.in_boxes.end());
            const std::vector<Point>& points = kept_.lead_.control_points();
            PointCells& cells = kept_.point_cells_;
            if (!cells.built()) cells = PointCells::over_all(points);
            for (const Box& box : boxes) cells.in_box(box, points, [&](std::uint32_t k) { control.push_back(k); });
        }
        Point control_point(std::uint32_t k) const { return kept_.lead_.control_points()[k]; }
        std::uint32_t id(std::uint32_t u) const { return u; }
        void ring_piece(std::uint32_t) const {}
        // The rings' fixed locations outside the runs, level by level, over their pieces in
        // every tile, in chain order.
        void outside(const std::vector<std::uint32_t>& rings, const std::vector<std::uint32_t>& runs, unsigned t, TileInput& input) const {
            SubsetAsk question;
            question.outside_rings = rings;
            question.runs = runs;
            question.from_level = t;
            SubsetAnswer answer = kept_.ask(question);
            std::sort(answer.outside.begin(), answer.outside.end(), [](const auto& a, const auto& b) { return std::pair{a.chain, a.first} < std::pair{b.chain, b.first}; });
            std::size_t k = 0;
            for (const std::uint32_t c : rings) {
                const std::size_t from = k;
                while (k < answer.outside.size() && answer.outside[k].chain == c) ++k;
                for (unsigned level = t; level < whole_level(c); ++level) {
                    std::vector<Point> found;
                    for (std::size_t i = from; i < k; ++i) {
                        for (const Point q : answer.outside[i].levels[level - t]) {
                            if (found.size() < 4 && std::none_of(found.begin(), found.end(), [&](Point e) { return same_location(e, q); })) found.push_back(q);
                        }
                    }
                    input.outside.push_back({c, level, std::move(found)});
                }
            }
        }
        bool marks() const { return kept_.lead_.marks(); }
        double bound_key() const { return kept_.lead_.bound_key(); }
        std::uint32_t bound_id() const { return kept_.lead_.bound_id(); }

    private:
        void wait(std::uint32_t waiter, std::uint32_t blocker) {
            blocker_of_[waiter] = blocker;
            waiters_of_[blocker].push_back(waiter);
        }
        SubsetAnswer take(SubsetAnswer&& answer) {
            for (std::size_t k = 0; k < answer.ids.size(); ++k) {
                Learnt& at = learnt_[answer.ids[k]];
                if (at.whole) continue;
                at.point = answer.points[k];
                at.chain = answer.chain[k];
                if (answer.flags[k] & SubsetAnswer::own) {
                    at.own = true;
                    at.state = answer.state[k];
                    at.marked = answer.marked[k];
                    at.shared = (answer.flags[k] & SubsetAnswer::shared) != 0;
                }
                if (answer.flags[k] & SubsetAnswer::whole) {
                    at.prev = answer.prev[k];
                    at.next = answer.next[k];
                    at.whole = true;
                }
            }
            return std::move(answer);
        }

        const KeptTiles& kept_;
        std::uint32_t runs_;
        std::unordered_map<std::uint32_t, Learnt> learnt_;
        std::vector<std::uint32_t> gone_;  // asked for and held by no tile: removed
        std::unordered_map<std::uint32_t, std::uint32_t> blocker_of_;  // the tiles' own waits and the lead's across tiles
        std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> waiters_of_;
    };
    Told told(*this, runs);
    return subset::build(told, runs, lead_.tile_level(), lead_.plan().levels);
}

bool KeptTiles::finish_top_subset(const TileInput& top, const TileOutcome& outcome) {
    if (outcome.exhausted) return false;
    finish_top(top, outcome);
    return true;
}

std::vector<TileInput> KeptTiles::group(std::size_t k) const {
    std::vector<TileInput> out;
    for (const std::uint32_t number : lead_.groups().at(k)) {
        out.push_back(tiles_->input(number, lead_.marks(), lead_.bound_key(), lead_.bound_id(), lead_.points(number)));
    }
    return out;
}

}  // namespace toposimp::map
