#include "core/map/tiles.hpp"

#include "core/parallel/side_by_side.hpp"

#include <algorithm>
#include <limits>
#include <map>

namespace toposimp::map {

namespace {

// `map` into `first`, its chains a part of about part_vertices vertices at a time, each part a
// map of its own; then its control points.
void add_by_parts(FirstRound& first, const MapData& map, std::size_t part_vertices) {
    const auto chains = static_cast<std::uint32_t>(map.chains.size());
    for (std::uint32_t c = 0; c < chains;) {
        MapData part;
        const std::uint32_t first_chain = c, first_vertex = map.chains[c].first;
        while (c < chains && (part.vertices.empty() || part.vertices.size() < part_vertices)) {
            const Chain& chain = map.chains[c];
            const std::uint32_t own = part.add_chain(std::span<const Point>(map.vertices.data() + chain.first, chain.last - chain.first + 1));
            if (map.is_frozen(c)) part.freeze(own);
            ++c;
        }
        first.add_chains(part, first_vertex, first_chain);
    }
    first.add_control_points(map.control_points);
}

}  // namespace

std::vector<TileOutcome> run_tile_group(std::vector<TileInput> group, const GridPlan& plan, const SimplifyOptions& options) {
    if (group.empty()) return {};
    const unsigned tile_level = group.front().level, first_level = group.front().first_level;
    std::vector<TileRun> runs;
    runs.reserve(group.size());
    for (TileInput& input : group) runs.emplace_back(std::move(input), plan, options);
    for (unsigned level = first_level; level < tile_level; ++level) {
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

std::vector<std::vector<TileOutcome>> run_tile_groups(std::vector<std::vector<TileInput>> groups, const GridPlan& plan,
                                                      const SimplifyOptions& options) {
    std::vector<std::vector<TileOutcome>> outcomes(groups.size());
    const auto points = [&](std::size_t k) {
        std::size_t sum = 0;
        for (const TileInput& tile : groups[k]) sum += tile.map.vertices.size() + tile.map.control_points.size();
        return sum;
    };
    parallel::side_by_side(groups.size(), options.threads, points,
                           [&](std::size_t k, int threads) {
                               SimplifyOptions mine = options;
                               mine.threads = threads;
                               mine.progress = {};
                               outcomes[k] = run_tile_group(std::move(groups[k]), plan, mine);
                           });
    return outcomes;
}

unsigned run_top_over_subsets(MapInParts& parts, const SimplifyOptions& options, std::uint32_t runs) {
    runs = std::max(runs, 1u);  // (runs of 0 would never grow)
    for (unsigned tries = 1;; ++tries) {
        std::vector<TileInput> top;
        top.push_back(parts.top_subset(runs));
        if (parts.finish_top_subset(run_tile_group(std::move(top), parts.plan(), options).front())) return tries;
        runs = runs >= (1u << 30) ? std::numeric_limits<std::uint32_t>::max() : 2 * runs;  // (no chain is longer: no cut end)
    }
}

SimplifyResult simplify_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint64_t here_below,
                                 bool top_here, bool live_only, std::uint32_t top_runs) {
    MapInParts parts(map, options, tile_level, here_below);
    bool whole = true;  // the whole map's engine still runs
    while (parts.next_round()) {
        std::vector<TileOutcome> outcomes;
        const std::size_t groups = parts.split_round();
        for (std::size_t k = 0; k < groups; ++k) {
            for (TileOutcome& outcome : run_tile_group(parts.group(k), parts.plan(), options)) outcomes.push_back(std::move(outcome));
        }
        if (!parts.finish_tiles(outcomes)) continue;
        if (live_only && whole && groups > 0) {
            parts.keep_live_only();
            whole = false;
        }
        if (top_here) {
            parts.run_top_here();
        } else if (top_runs > 0) {
            run_top_over_subsets(parts, options, top_runs);
        } else {
            std::vector<TileInput> top;
            top.push_back(parts.top());
            parts.finish_top(run_tile_group(std::move(top), parts.plan(), options).front());
        }
    }
    return parts.result();
}

SimplifyResult simplify_with_kept_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::size_t part_vertices,
                                        std::uint32_t runs) {
    const GridPlan plan = plan_grid(map);
    FirstRound first(plan, tile_level, options, map.vertices.size());
    add_by_parts(first, map, part_vertices);
    first.split();
    KeptTiles kept = std::move(first).kept();
    do {
        if (kept.finish_tiles(kept.run_groups())) run_kept_top(kept, plan, options, runs);
    } while (kept.next_round());
    return kept.result();
}

unsigned run_kept_top(KeptTiles& kept, const GridPlan& plan, const SimplifyOptions& options, std::uint32_t runs) {
    runs = std::max(runs, 1u);  // (runs of 0 would never grow)
    for (unsigned tries = 1;; ++tries) {
        TileInput top = kept.top_subset(runs);
        std::vector<TileInput> one{top};
        if (kept.finish_top_subset(top, run_tile_group(std::move(one), plan, options).front())) return tries;
        runs = runs >= (1u << 30) ? std::numeric_limits<std::uint32_t>::max() : 2 * runs;  // (no chain is longer: no cut end)
    }
}

SimplifyResult simplify_by_parts(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::size_t part_vertices,
                                 std::uint64_t here_below) {
    const GridPlan plan = plan_grid(map);
    FirstRound first(plan, tile_level, options, map.vertices.size());
    add_by_parts(first, map, part_vertices);
    std::vector<TileOutcome> outcomes;
    const std::size_t groups = first.split();
    for (std::size_t k = 0; k < groups; ++k) {
        for (TileOutcome& outcome : run_tile_group(first.group(k), plan, options)) outcomes.push_back(std::move(outcome));
    }
    std::unique_ptr<MapInParts> parts = first.finish(outcomes, here_below);
    const auto run_top = [&] {
        std::vector<TileInput> top;
        top.push_back(parts->top());
        parts->finish_top(run_tile_group(std::move(top), plan, options).front());
    };
    run_top();
    while (parts->next_round()) {
        outcomes.clear();
        const std::size_t count = parts->split_round();
        for (std::size_t k = 0; k < count; ++k) {
            for (TileOutcome& outcome : run_tile_group(parts->group(k), plan, options)) outcomes.push_back(std::move(outcome));
        }
        if (parts->finish_tiles(outcomes)) run_top();
    }
    return parts->result();
}

}  // namespace toposimp::map
