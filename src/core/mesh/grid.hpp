// The uniform 3D grids of UGSimp: the block grid (cells grouped into the blocks of
// parallel/blocks.hpp, which the threads share out) and the face index's own finer cells
// (face_index.hpp). A cell is named by a key packing its three coordinates.
#pragma once

#include "core/geometry.hpp"
#include "core/parallel/blocks.hpp"

#include <array>
#include <cstdint>

namespace toposimp::mesh::detail {

// Cells of one size from `origin`, at most 2^20 per axis. Cell coordinates are a monotone
// function of each coordinate, so the points of a box of cells form a box (convex).
struct Grid {
    Point3 origin{};
    double inverse_size = 1.0;
    std::array<std::uint32_t, 3> cells = {1, 1, 1};

    // The floor of the scaled offset, clamped to the grid (NaN: cell 0). Truncation is the floor
    // for c >= 1, and it stays inline (std::floor is a library call on baseline x86-64).
    std::uint32_t cell(double value, double origin_value, int axis) const {
        const double c = (value - origin_value) * inverse_size;
        if (!(c >= 1)) return 0;
        return c >= cells[axis] - 1.0 ? cells[axis] - 1 : static_cast<std::uint32_t>(c);
    }
    // A coordinate in cells from the origin (unclamped, not floored).
    double units(double value, int axis) const { return (value - origin[axis]) * inverse_size; }
    std::uint64_t cell_key(Point3 p) const {
        return pack(cell(p.x, origin.x, 0), cell(p.y, origin.y, 1), cell(p.z, origin.z, 2));
    }
    static std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) { return x << 42 | y << 21 | z; }
    static std::uint32_t unpack(std::uint64_t key, int axis) {
        return static_cast<std::uint32_t>(key >> (42 - 21 * axis)) & 0x1fffff;
    }
};

// Every cell key of the box of cells from `first` to `last` (lowest and highest on every axis).
template <class Visit>
void for_cells(std::uint64_t first, std::uint64_t last, Visit visit) {
    for (std::uint32_t x = Grid::unpack(first, 0); x <= Grid::unpack(last, 0); ++x) {
        for (std::uint32_t y = Grid::unpack(first, 1); y <= Grid::unpack(last, 1); ++y) {
            for (std::uint32_t z = Grid::unpack(first, 2); z <= Grid::unpack(last, 2); ++z) visit(Grid::pack(x, y, z));
        }
    }
}

// The block grid: the cells and their block hierarchy. A block is named by a key packing its
// coordinates at its level, like a cell.
struct BlockGrid : Grid {
    parallel::BlockLevels<3> levels;

    // The key of the block holding a cell at `level`.
    std::uint64_t block_of(std::uint64_t cell_key, int level) const {
        return pack(levels.block(unpack(cell_key, 0), level), levels.block(unpack(cell_key, 1), level),
                    levels.block(unpack(cell_key, 2), level));
    }
    // The key of the block one level up holding a block.
    static std::uint64_t parent(std::uint64_t block) {
        using Levels = parallel::BlockLevels<3>;
        return pack(Levels::parent(unpack(block, 0)), Levels::parent(unpack(block, 1)), Levels::parent(unpack(block, 2)));
    }
};

}  // namespace toposimp::mesh::detail
