// Nested scales in one run: level k keeps a subset of level k − 1's vertices. Each level is
// the simplifier run on the previous level's result (its kept vertices, the same control points),
// so every removal is decided by the same exact rules against a map that is itself topologically
// the input's: each level keeps every promise against the input, and the whole costs about one
// run to the finest level plus runs on ever smaller maps. A count target counts the input's
// vertices: --keep 5% as a level keeps as many vertices as a single --keep 5% run.
#pragma once

#include "core/map/simplify.hpp"

#include <span>
#include <vector>

namespace toposimp::map {

// The simplifications of `map` to each of `levels`, finest first (a level asking for more
// vertices than the previous one kept keeps them all). Each result's `kept` is over the vertices
// of `map`; its stats are those of the step from the previous level.
std::vector<SimplifyResult> simplify_levels(const MapData& map, const SimplifyOptions& options, std::span<const StopCriterion> levels);

}  // namespace toposimp::map
