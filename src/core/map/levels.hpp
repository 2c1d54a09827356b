// Nested scales in one run: level k keeps a subset of level k − 1's vertices. Each level is
// the simplifier run on the previous level's result (its kept vertices, the same control points),
// so every removal is decided by the same exact rules against a map that is itself topologically
// the input's: each level keeps every promise against the input, and the whole costs about one
// run to the finest level plus runs on ever smaller maps. A count target counts the input's
// vertices: --keep 5% as a level keeps as many vertices as a single --keep 5% run.
//
// Published on a grid (rounding.hpp), the first level is rounded as a single run would be, and
// the coarser levels are simplified from the rounded first level: they keep its positions, so
// every level is on the grid wherever the first is, and a subset of the level before to the
// location. The promises compose: the rounded first level keeps them against the input, and the
// simplifier keeps them against the map it is given.
#pragma once

#include "core/map/rounding.hpp"
#include "core/map/simplify.hpp"

#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace toposimp::map {

struct LevelRounding {
    // The grid, given the first level's kept vertices (a quantized grid spans what is written).
    std::function<OutputGrid(const std::vector<std::uint8_t>& first_kept)> grid;
    RoundingOptions options;  // its grid is set from `grid`
};

struct Levels {
    std::vector<SimplifyResult> results;     // finest first; each `kept` over the vertices of the input
    std::optional<RoundingResult> rounding;  // the first level's rounding, when asked: where every level is written
};

// The simplifications of `map` to each of `levels`, finest first (a level asking for more
// vertices than the previous one kept keeps them all), rounded if `rounding` is given. Each
// result's stats are those of the step from the previous level. `engine`, if given, runs each
// step in place of simplify() and must give what it gives (a run in parts: tiles.hpp).
Levels simplify_levels(const MapData& map, const SimplifyOptions& options, std::span<const StopCriterion> levels,
                       const LevelRounding* rounding = nullptr,
                       const std::function<SimplifyResult(const MapData&, const SimplifyOptions&)>& engine = {});

}  // namespace toposimp::map
