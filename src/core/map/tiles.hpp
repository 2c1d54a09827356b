// The map engine in parts (issue 32, docs/distributed.md): its block hierarchy cut at a *tile
// level* T. A tile is a block of level T. At the levels below T every block lies inside one tile,
// so each tile can be simplified there from its own vertices and control points alone, by a
// process that holds nothing else; the levels from T up then run over what the tiles leave. The
// result is simplify()'s, vertex for vertex and count for count:
//
// - Every part uses the single process's grid and blocks (GridPlan), so every vertex has the
//   same block at every level, and a tile's grid orders the points of each cell as the whole
//   map's grid does (ids keep the whole map's order).
// - A tile holds its chains cut at its border: each piece runs over the vertices inside the tile
//   and ends with the vertex beyond the border on either side (a *cut end*). A segment that
//   crosses the border never changes below T (its ends are of level T or above), so the cut ends
//   are fixed there, and they give the inside vertices their true levels.
// - What a block consults below T lies inside its tile (its triangles, the points in them, the
//   waits); the only facts from outside are constants: which vertices are pinned by the whole
//   map's crossings, and whether a ring split over several tiles keeps ≥ 4 distinct locations at
//   its fixed vertices (the ring rule's question at each level). The cut ends are fixed below T,
//   so a ring whose cut ends alone hold 4 distinct locations is settled at planning; for any
//   other split ring, the tiles tell their fixed locations level by level (TileRun::open_rings)
//   and the caller gives back the union's answer.
//
// Count targets (rounds with a global selection) are not run in parts yet: only --max and
// --max-area.
#pragma once

#include "core/map/map_data.hpp"
#include "core/map/point_grid.hpp"
#include "core/map/simplify.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace toposimp::map {

namespace detail {
class Simplifier;
}

// The whole_level of a chain that is not closed.
inline constexpr std::uint8_t kOpenChain = 0xff;

// The grid and blocks simplify() uses for a map: what every part of a run in parts shares.
struct GridPlan {
    PointGrid::Geometry grid;
    unsigned shift = 0;   // level-0 blocks are 2^shift × 2^shift base cells
    unsigned levels = 1;  // levels of blocks, the top one a single block

    // The block of `level` holding p: its column and row.
    std::uint32_t block_column(Point p, unsigned level) const { return grid.base_column(p.x) >> (shift + level); }
    std::uint32_t block_row(Point p, unsigned level) const { return grid.base_row(p.y) >> (shift + level); }
};

// The plan simplify() makes for `map` (its vertices and control points).
GridPlan plan_grid(const MapData& map);

// One tile's share of a map: everything a tile needs to run the levels below T.
struct TileInput {
    unsigned level = 0;                // T
    std::uint32_t column = 0, row = 0; // the tile: this block of level T
    // The pieces of the chains that have vertices in the tile, in the map's order, each with its
    // cut ends; the control points in the tile, in the map's order.
    MapData map;
    std::vector<std::uint32_t> vertex_id;   // per vertex of `map`: its id in the whole map
    std::vector<std::uint8_t> pinned;       // per vertex: never removed (crossings of the whole map, frozen chains)
    std::vector<std::uint32_t> chain_id;    // per chain of `map`: the whole map's chain it is part of
    // Per chain: the finest level at which the whole map's chain lies in one block (kOpenChain if
    // it is not closed). A closed chain inside the tile has whole_level ≤ T and comes whole.
    std::vector<std::uint8_t> whole_level;
    // Per chain split over tiles (whole_level > T): 1 if its cut ends alone hold ≥ 4 distinct
    // locations, which settles the ring rule at every level below T.
    std::vector<std::uint8_t> settled;
};

// A split ring's fixed locations in one tile at one level (up to 4 distinct).
struct RingLocations {
    std::uint32_t chain;  // the whole map's chain
    std::vector<Point> locations;
};

// What a tile leaves after the levels below T, in whole-map ids.
struct TileOutcome {
    std::vector<std::uint32_t> removed;
    std::vector<std::uint32_t> refused;                          // refused until their triangle changes
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;  // (waiter, blocker): refused until the blocker goes
    std::vector<std::vector<std::uint32_t>> later;               // [level − T]: candidates of that level
    std::vector<std::pair<std::uint32_t, std::uint32_t>> locations_lost;  // (chain, count): split rings' distinct locations removed
    SimplifyStats stats;  // removals and refusals in the tile
};

// Runs a tile, level by level.
class TileRun {
public:
    TileRun(TileInput input, const GridPlan& plan, const SimplifyOptions& options);
    ~TileRun();
    TileRun(TileRun&&) noexcept;
    TileRun& operator=(TileRun&&) noexcept;

    // The split rings not settled by their cut ends, with their fixed locations in this tile at
    // the start of `level` (call it right before run_level(level)).
    std::vector<RingLocations> open_rings(unsigned level);
    // Runs `level` (< T, in order from 0). `clear`: the whole-map chains among open_rings(level)
    // whose fixed locations over all tiles are ≥ 4 distinct ones, sorted.
    void run_level(unsigned level, std::span<const std::uint32_t> clear);
    // After the last level below T.
    TileOutcome finish();

private:
    struct Parts;  // the input, plan, options and engine, at a fixed address
    std::unique_ptr<Parts> parts_;
};

// Cuts `map` into the tiles of level `tile_level` that hold any vertex or control point, in
// row-major order; `pinned` is per vertex of the map (see TileInput). Builds each tile's input
// from the whole map: a reference for what a run reading the map by parts must give each tile.
std::vector<TileInput> split_into_tiles(const MapData& map, const GridPlan& plan, unsigned tile_level,
                                        std::span<const std::uint8_t> pinned);

// Per vertex of `map`: never removed — an end of a segment with an improper contact, or on a
// frozen chain (what simplify() pins).
std::vector<std::uint8_t> pinned_vertices(const MapData& map, const SimplifyOptions& options, SimplifyStats& stats);

// The levels from `tile_level` up over the whole map, from the tiles' outcomes (each tile that
// has any vertex, once) and the pinned vertices. Gives what simplify(map, options) gives, but for
// the crossing search's share of the stats (pinned_vertices has it).
SimplifyResult simplify_from_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level,
                                   std::span<const TileOutcome> tiles, std::span<const std::uint8_t> pinned);

// The tiles that must run together, level by level: those sharing a split ring that its cut
// ends do not settle (most tiles are alone). In the order of the tiles' first members.
std::vector<std::vector<TileInput>> group_tiles(std::vector<TileInput> tiles);

// Runs a group of tiles through the levels below their tile level, deciding their open rings
// together; one outcome per tile, in order. Each tile task of a distributed run is one call.
std::vector<TileOutcome> run_tile_group(std::vector<TileInput> group, const GridPlan& plan, const SimplifyOptions& options);

// simplify() run in parts in this process: split, every tile level by level (open rings decided
// over all tiles), then the levels above. For tests and as the reference for a distributed run.
SimplifyResult simplify_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level);

}  // namespace toposimp::map
