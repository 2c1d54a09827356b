#include "core/map/tiles.hpp"

#include "core/parallel/blocks.hpp"

#include <algorithm>
#include <map>

namespace toposimp::map {

namespace {

// The tiles of a plan at one level, numbered row-major.
struct TileGrid {
    const GridPlan& plan;
    unsigned level;
    std::uint32_t columns;

    TileGrid(const GridPlan& p, unsigned l)
        : plan(p), level(l), columns(((p.grid.base_columns - 1) >> (p.shift + l)) + 1) {}

    std::uint32_t rows() const { return ((plan.grid.base_rows - 1) >> (plan.shift + level)) + 1; }
    std::uint32_t of(Point p) const { return plan.block_row(p, level) * columns + plan.block_column(p, level); }
};

// The finest level at which a closed chain lies in one block (as simplify() computes it), else kOpenChain.
std::uint8_t whole_level_of(const MapData& map, const GridPlan& plan, const Chain& chain) {
    if (!(chain.last > chain.first && same_location(map.vertices[chain.first], map.vertices[chain.last]))) return kOpenChain;
    std::uint32_t min_column = UINT32_MAX, max_column = 0, min_row = UINT32_MAX, max_row = 0;
    for (std::uint32_t v = chain.first; v <= chain.last; ++v) {
        const std::uint32_t column = plan.block_column(map.vertices[v], 0), row = plan.block_row(map.vertices[v], 0);
        min_column = std::min(min_column, column);
        max_column = std::max(max_column, column);
        min_row = std::min(min_row, row);
        max_row = std::max(max_row, row);
    }
    using Blocks = parallel::BlockLevels<2>;
    return static_cast<std::uint8_t>(std::max(Blocks::shared_level(min_column, max_column), Blocks::shared_level(min_row, max_row)));
}

}  // namespace

std::vector<TileInput> split_into_tiles(const MapData& map, const GridPlan& plan, unsigned tile_level,
                                        std::span<const std::uint8_t> pinned) {
    const TileGrid tiles(plan, tile_level);
    std::map<std::uint32_t, TileInput> by_tile;  // (row-major order)
    auto tile = [&](std::uint32_t k) -> TileInput& {
        TileInput& input = by_tile[k];
        input.level = tile_level;
        input.column = k % tiles.columns;
        input.row = k / tiles.columns;
        return input;
    };
    std::vector<std::uint32_t> tile_of(map.vertices.size());
    for (std::size_t v = 0; v < map.vertices.size(); ++v) tile_of[v] = tiles.of(map.vertices[v]);

    for (std::uint32_t c = 0; c < map.chains.size(); ++c) {
        const Chain& chain = map.chains[c];
        const std::uint8_t whole = whole_level_of(map, plan, chain);
        const bool split = whole != kOpenChain && whole > tile_level;
        // A split ring's cut ends (both ends of every segment across a tile border): if they alone
        // hold 4 distinct locations, the ring rule cannot bite below the tile level.
        bool settled = false;
        if (split) {
            std::vector<Point> ends;
            for (std::uint32_t v = chain.first; v < chain.last && ends.size() < 4; ++v) {
                if (tile_of[v] == tile_of[v + 1]) continue;
                for (const std::uint32_t u : {v, v + 1}) {
                    const Point q = map.vertices[u];
                    if (std::none_of(ends.begin(), ends.end(), [&](Point e) { return same_location(e, q); })) ends.push_back(q);
                }
            }
            settled = ends.size() >= 4;
        }
        for (std::uint32_t begin = chain.first; begin <= chain.last;) {
            std::uint32_t end = begin;
            while (end < chain.last && tile_of[end + 1] == tile_of[begin]) ++end;
            TileInput& input = tile(tile_of[begin]);
            const std::uint32_t from = begin > chain.first ? begin - 1 : begin;
            const std::uint32_t to = end < chain.last ? end + 1 : end;
            input.map.add_chain(std::span<const Point>(map.vertices.data() + from, to - from + 1));
            for (std::uint32_t v = from; v <= to; ++v) {
                input.vertex_id.push_back(v);
                input.pinned.push_back(pinned[v]);
            }
            input.chain_id.push_back(c);
            input.whole_level.push_back(whole);
            input.settled.push_back(settled ? 1 : 0);
            begin = end + 1;
        }
    }
    for (const Point p : map.control_points) {
        const std::uint32_t k = tiles.of(p);
        if (by_tile.count(k)) by_tile[k].map.control_points.push_back(p);  // (a tile with no vertex has nothing to do)
    }
    std::vector<TileInput> out;
    out.reserve(by_tile.size());
    for (auto& [k, input] : by_tile) out.push_back(std::move(input));
    return out;
}

std::vector<std::vector<TileInput>> group_tiles(std::vector<TileInput> tiles) {
    // Union-find over the tiles, joined by the chains of their unsettled split pieces.
    std::vector<std::size_t> parent(tiles.size());
    for (std::size_t k = 0; k < tiles.size(); ++k) parent[k] = k;
    auto root = [&](std::size_t k) {
        while (parent[k] != k) k = parent[k] = parent[parent[k]];
        return k;
    };
    std::map<std::uint32_t, std::size_t> holder;  // unsettled chain → a tile holding a piece
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const TileInput& tile = tiles[k];
        for (std::size_t c = 0; c < tile.chain_id.size(); ++c) {
            const bool open = tile.whole_level[c] != kOpenChain && tile.whole_level[c] > tile.level && !tile.settled[c];
            if (!open) continue;
            const auto [at, fresh] = holder.emplace(tile.chain_id[c], k);
            if (!fresh) parent[root(k)] = root(at->second);
        }
    }
    std::vector<std::vector<TileInput>> groups;
    std::map<std::size_t, std::size_t> group_of;  // root → group
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const auto [at, fresh] = group_of.emplace(root(k), groups.size());
        if (fresh) groups.emplace_back();
        groups[at->second].push_back(std::move(tiles[k]));
    }
    return groups;
}

std::vector<TileOutcome> run_tile_group(std::vector<TileInput> group, const GridPlan& plan, const SimplifyOptions& options) {
    if (group.empty()) return {};
    const unsigned tile_level = group.front().level;
    std::vector<TileRun> runs;
    runs.reserve(group.size());
    for (TileInput& input : group) runs.emplace_back(std::move(input), plan, options);
    for (unsigned level = 0; level < tile_level; ++level) {
        // The open rings' fixed locations over the group's tiles (which hold all their pieces):
        // clear when ≥ 4 distinct ones.
        std::map<std::uint32_t, std::vector<Point>> locations;
        for (TileRun& run : runs) {
            for (RingLocations& ring : run.open_rings(level)) {
                std::vector<Point>& all = locations[ring.chain];
                for (const Point q : ring.locations) {
                    if (std::none_of(all.begin(), all.end(), [&](Point e) { return same_location(e, q); })) all.push_back(q);
                }
            }
        }
        std::vector<std::uint32_t> clear;
        for (const auto& [chain, all] : locations) {
            if (all.size() >= 4) clear.push_back(chain);
        }
        for (TileRun& run : runs) run.run_level(level, clear);
    }
    std::vector<TileOutcome> outcomes;
    outcomes.reserve(runs.size());
    for (TileRun& run : runs) outcomes.push_back(run.finish());
    return outcomes;
}

SimplifyResult simplify_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level) {
    const GridPlan plan = plan_grid(map);
    tile_level = std::min(tile_level, plan.levels);
    SimplifyStats pinning;
    const std::vector<std::uint8_t> pinned = pinned_vertices(map, options, pinning);
    std::vector<TileOutcome> outcomes;
    for (std::vector<TileInput>& group : group_tiles(split_into_tiles(map, plan, tile_level, pinned))) {
        for (TileOutcome& outcome : run_tile_group(std::move(group), plan, options)) outcomes.push_back(std::move(outcome));
    }
    SimplifyResult result = simplify_from_tiles(map, options, tile_level, outcomes, pinned);
    result.stats.predicates += pinning.predicates;
    return result;
}

}  // namespace toposimp::map
