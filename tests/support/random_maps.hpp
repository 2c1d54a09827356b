// Random maps for property tests: planar ones (`roads` = 0), made of lines that meet only at shared vertices (nodes,
// touches), rings, duplicate vertices, collinear runs, pairs of lines with the same endpoints,
// and control points placed on, beside (one ulp away) and between the lines.
#pragma once

#include "core/map/map_data.hpp"

#include <cstdint>
#include <random>

namespace toposimp::testing {

struct RandomMapOptions {
    double origin_x = 0;   // where the map sits: 0 (mixed signs), 1e6 (UTM-like), …
    double origin_y = 0;
    double extent = 100;   // size of the map
    int chains = 12;
    int max_steps = 20;
    int rings = 3;
    int control_points = 30;
    bool near_degenerate = true;  // collinear runs and points within ulps of segments
    int roads = 0;                // lines laid over the map with no regard for it: they cross
};

map::MapData random_planar_map(std::mt19937_64& rng, const RandomMapOptions& options);

}  // namespace toposimp::testing
