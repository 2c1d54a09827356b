// The engine's view of a map: chains of vertices (lines and rings) and control points.
#pragma once

#include "core/geometry.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::map {

// A chain is the inclusive vertex range [first, last] of MapData::vertices. A chain whose first
// and last vertex are at the same location is closed (a ring, or a line that closes on itself).
struct Chain {
    std::uint32_t first;
    std::uint32_t last;
};

struct MapData {
    std::vector<Point> vertices;        // all chains' vertices, chain after chain
    std::vector<Chain> chains;          // in input order
    std::vector<Point> control_points;  // points whose side of every chain must not change
    std::vector<std::uint8_t> frozen;   // per chain (or empty): 1 = keep every vertex, an obstacle only

    // Appends a chain made of `points`; returns its index.
    std::uint32_t add_chain(const std::vector<Point>& points) { return add_chain(std::span<const Point>(points)); }
    std::uint32_t add_chain(std::span<const Point> points) {
        const auto first = static_cast<std::uint32_t>(vertices.size());
        vertices.insert(vertices.end(), points.begin(), points.end());
        chains.push_back({first, static_cast<std::uint32_t>(vertices.size() - 1)});
        return static_cast<std::uint32_t>(chains.size() - 1);
    }

    void freeze(std::uint32_t chain) {
        if (frozen.size() < chains.size()) frozen.resize(chains.size(), 0);
        frozen[chain] = 1;
    }

    bool is_frozen(std::uint32_t chain) const { return chain < frozen.size() && frozen[chain]; }
};

}  // namespace toposimp::map
