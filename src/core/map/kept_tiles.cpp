// The rounds after the first from the first round's tiles kept (KeptTiles: core/map/tiles.hpp).
#include "core/map/tiles.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace toposimp::map {

KeptTiles::KeptTiles(const FirstRoundLead& lead, std::map<std::uint32_t, FirstTile> tiles) : lead_(lead), tiles_(std::move(tiles)) {
    for (const std::vector<std::uint32_t>& group : lead_.groups()) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
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
    lead_.bound(parallel::select_kth_by_digits(
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
        tile->settle(settled);
        facts.push_back({tile->number, tile->busy(lead_.bound_key(), lead_.bound_id()), tile->open_chains()});
    }
    for (const std::vector<std::uint32_t>& group : lead_.groups(std::move(facts))) running_.insert(running_.end(), group.begin(), group.end());
    std::sort(running_.begin(), running_.end());
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
