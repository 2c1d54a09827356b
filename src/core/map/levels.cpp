#include "core/map/levels.hpp"

#include <cstdint>
#include <numeric>

namespace toposimp::map {

std::vector<SimplifyResult> simplify_levels(const MapData& map, const SimplifyOptions& options, std::span<const StopCriterion> levels) {
    std::vector<SimplifyResult> results;
    const std::uint64_t input = map.vertices.size();
    MapData current;  // the previous level's result (the first level runs on `map` itself)
    std::vector<std::uint32_t> source(map.vertices.size());  // per vertex of `current`: its vertex in `map`
    std::iota(source.begin(), source.end(), 0u);
    for (const StopCriterion& level : levels) {
        const MapData& from = results.empty() ? map : current;
        SimplifyOptions step = options;
        step.stop = level;
        if (level.target == Target::keep_fraction || level.target == Target::keep_points || level.target == Target::remove_points) {
            // Counted against the input, as a single run would count.
            step.stop = {Target::keep_points, static_cast<double>(input - removal_goal(level, input))};
        }
        SimplifyResult done = simplify(from, step);
        SimplifyResult result;
        result.stats = done.stats;
        result.kept.assign(map.vertices.size(), 0);
        for (std::size_t v = 0; v < done.kept.size(); ++v) {
            if (done.kept[v]) result.kept[source[v]] = 1;
        }
        results.push_back(std::move(result));
        // The next level starts from this one.
        MapData next;
        std::vector<std::uint32_t> next_source;
        std::vector<Point> points;
        for (std::uint32_t c = 0; c < from.chains.size(); ++c) {
            points.clear();
            for (std::uint32_t v = from.chains[c].first; v <= from.chains[c].last; ++v) {
                if (!done.kept[v]) continue;
                points.push_back(from.vertices[v]);
                next_source.push_back(source[v]);
            }
            next.add_chain(points);
            if (from.is_frozen(c)) next.freeze(c);
        }
        // The control points never change: moved on from the previous level, copied once from `map`.
        next.control_points = results.size() == 1 ? map.control_points : std::move(current.control_points);
        current = std::move(next);
        source = std::move(next_source);
    }
    return results;
}

}  // namespace toposimp::map
