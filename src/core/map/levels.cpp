#include "core/map/levels.hpp"

#include <cstdint>
#include <numeric>

namespace toposimp::map {

Levels simplify_levels(const MapData& map, const SimplifyOptions& options, std::span<const StopCriterion> levels,
                       const LevelRounding* rounding, const std::function<SimplifyResult(const MapData&, const SimplifyOptions&)>& engine) {
    Levels out;
    const std::uint64_t input = map.vertices.size();
    MapData current;  // the previous level's result (the first level runs on `map` itself)
    std::vector<std::uint32_t> source(map.vertices.size());  // per vertex of `current`: its vertex in `map`
    std::iota(source.begin(), source.end(), 0u);
    for (const StopCriterion& level : levels) {
        const bool first = out.results.empty();
        const MapData& from = first ? map : current;
        SimplifyOptions step = options;
        step.stop = level;
        if (level.target == Target::keep_fraction || level.target == Target::keep_points || level.target == Target::remove_points) {
            // Counted against the input, as a single run would count.
            step.stop = {Target::keep_points, static_cast<double>(input - removal_goal(level, input))};
        }
        SimplifyResult done = engine ? engine(from, step) : simplify(from, step);
        if (first && rounding) {
            RoundingOptions round = rounding->options;
            round.grid = rounding->grid(done.kept);
            out.rounding = round_to_grid(map, done.kept, round);
            done.kept = out.rounding->kept;
            done.stats.vertices_out -= out.rounding->stats.removed;
        }
        SimplifyResult result;
        result.stats = done.stats;
        result.kept.assign(map.vertices.size(), 0);
        for (std::size_t v = 0; v < done.kept.size(); ++v) {
            if (done.kept[v]) result.kept[source[v]] = 1;
        }
        out.results.push_back(std::move(result));
        if (out.results.size() == levels.size()) break;
        // The next level starts from this one, where it is written.
        const std::vector<Point>& at = first && out.rounding ? out.rounding->at : from.vertices;
        MapData next;
        std::vector<std::uint32_t> next_source;
        std::vector<Point> points;
        for (std::uint32_t c = 0; c < from.chains.size(); ++c) {
            points.clear();
            for (std::uint32_t v = from.chains[c].first; v <= from.chains[c].last; ++v) {
                if (!done.kept[v]) continue;
                points.push_back(at[v]);
                next_source.push_back(source[v]);
            }
            next.add_chain(points);
            if (from.is_frozen(c)) next.freeze(c);
        }
        // The control points never change but for the written ones put on the grid: moved on
        // from the previous level, copied once from `map`.
        next.control_points = first ? map.control_points : std::move(current.control_points);
        if (first && out.rounding) std::copy(out.rounding->points.begin(), out.rounding->points.end(), next.control_points.begin());
        current = std::move(next);
        source = std::move(next_source);
    }
    return out;
}

}  // namespace toposimp::map
