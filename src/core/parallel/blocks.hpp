// The block hierarchy both engines run on (dissertation §3.5): a uniform grid's cells grouped
// into blocks of 2^shift cells per side at level 0, each block of level l + 1 made of 2 × … × 2
// blocks of level l, up to the top level, where one block holds the whole grid. A cell's block at
// level l is its coordinates shifted right by shift + l on every axis, so the blocks of a level
// are boxes of cells (convex when cell coordinates grow with the point coordinates, as they do in
// both grids) and nest. Blocks of one level are independent work; a level runs after the ones
// below it.
//
// The map engine uses it in 2D (axis 0: columns, x; axis 1: rows, y), the mesh engine in 3D.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

namespace toposimp::parallel {

template <int Axes>
struct BlockLevels {
    std::array<std::uint32_t, Axes> cells{};  // cells per axis, each at least 1
    int shift = 0;                            // level-0 blocks are 2^shift cells per side

    // A cell coordinate's block coordinate at `level`.
    std::uint32_t block(std::uint32_t cell, int level) const { return cell >> (shift + level); }
    // Blocks per axis at `level`.
    std::uint32_t blocks(int axis, int level) const { return ((cells[axis] - 1) >> (shift + level)) + 1; }
    // Blocks in all at `level`.
    double block_count(int level) const {
        double count = 1;
        for (int axis = 0; axis < Axes; ++axis) count *= static_cast<double>(blocks(axis, level));
        return count;
    }
    // The coarsest level: one block.
    int top_level() const {
        int level = 0;
        for (int axis = 0; axis < Axes; ++axis) level = std::max(level, static_cast<int>(std::bit_width(blocks(axis, 0) - 1)));
        return level;
    }
    // The finest level at which two level-0 block coordinates fall in one block.
    static int shared_level(std::uint32_t a, std::uint32_t b) { return static_cast<int>(std::bit_width(a ^ b)); }
    // The block of the next level up holding block coordinate b.
    static std::uint32_t parent(std::uint32_t b) { return b >> 1; }
};

}  // namespace toposimp::parallel
