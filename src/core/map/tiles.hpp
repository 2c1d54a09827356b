// The map engine in parts (issue 32, docs/distributed.md): its block hierarchy cut at a *tile
// level* T. A tile is a block of level T. At the levels below T every block lies inside one tile,
// so each tile can be simplified there from its own vertices and control points alone, by a
// process that holds nothing else; the levels from T up then run over what the tiles leave. The
// result is simplify()'s, vertex for vertex and count for count:
//
// - Every part uses the single process's grid and blocks (GridPlan), so every vertex has the
//   same block at every level, and a tile's grid orders the points of each cell as the whole
//   map's grid does (ids keep the whole map's order).
// - A tile holds its chains cut at its border: each piece runs over the live vertices inside the
//   tile and ends with the live vertex beyond the border on either side (a *cut end*). A segment
//   that crosses the border never changes below T (its ends are of level T or above), so the cut
//   ends are fixed there, and they give the inside vertices their true levels. A ring inside the
//   tile comes whole (its live vertices), with the input ring's orientation when the tile may
//   need it (the ring rule's last test).
// - What a block consults below T lies inside its tile (its triangles, the points in them, the
//   waits between its vertices); the only facts from outside are the vertices' states, and whether
//   a ring split over several tiles keeps ≥ 4 distinct locations at its fixed vertices (the ring
//   rule's question at each level). The cut ends are fixed below T, so a ring whose cut ends alone
//   hold 4 distinct locations is settled at the split; the tiles holding pieces of any other split
//   ring run together as a group, and tell each other their fixed locations level by level.
// - Count targets run rounds: each round's budget is selected over the whole map (MapInParts),
//   the tiles run the levels below T on it, and the levels above follow. A wait across tiles
//   (begun at level T or above) ends when its blocker goes in another tile; the waiter is then
//   queued after the round's levels below T, where the single process queues it after the level
//   the blocker went at — the same, as a waiter outside a round's budget is not looked at again
//   before the next round's selection.
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
// The same for a map whose vertices and control points, `points` of them, span [min_x, max_x] ×
// [min_y, max_y]: from a pass over the map that holds none of it.
GridPlan plan_grid(double min_x, double min_y, double max_x, double max_y, std::size_t points);

// What a vertex is doing (the engine's own states).
enum class VertexState : std::uint8_t { fixed, queued, waiting, refused, removed };

// One tile's share of a map in one round: everything a tile needs to run the levels below T.
//
// The levels from T up run as one more tile (MapInParts::top): the single block of the level
// above the top, holding the live vertices only, from first_level = T with the candidates the
// tiles left for those levels.
struct TileInput {
    unsigned level = 0;                // T
    std::uint32_t column = 0, row = 0; // the tile: this block of level T
    unsigned first_level = 0;          // the levels it runs: [first_level, level)
    // The pieces of the chains that have live vertices in the tile, in the map's order, each with
    // its cut ends, and the rings inside it (whole); the control points in the tile, in order.
    // Only live vertices.
    MapData map;
    std::vector<std::uint32_t> vertex_id;  // per vertex of `map`: its id in the whole map
    std::vector<std::uint8_t> state;       // per vertex: a VertexState (cut ends fixed)
    std::vector<std::uint8_t> marked;      // per vertex: in this round's budget (count targets), else empty
    std::vector<std::uint32_t> chain_id;   // per chain of `map`: the whole map's chain it is (part of)
    // Per chain: the finest level at which the whole map's chain lies in one block (kOpenChain if
    // it is not closed). A closed chain inside the tile has whole_level ≤ T and comes whole.
    std::vector<std::uint8_t> whole_level;
    // Per chain split over tiles (whole_level > T): 1 if its cut ends alone hold ≥ 4 distinct
    // locations, which settles the ring rule at every level below T.
    std::vector<std::uint8_t> settled;
    std::vector<std::uint32_t> distinct;   // per chain: a whole ring's distinct live locations (the engine's count)
    // Per chain: a whole ring's input orientation: −1, 0 or 1; 2 if not known; or known but not yet
    // counted in the predicates' stats (core/map/simplify.cpp: know_orientation).
    std::vector<std::int8_t> orientation;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;  // (waiter, blocker) among the tile's vertices
    // From first_level > 0: per level from first_level, the vertices to queue there (else the tile
    // lists its queued vertices by their levels).
    std::vector<std::vector<std::uint32_t>> later;
    bool marks = false;                    // count targets: only marked vertices go, up to the bound
    double bound_key = 0;                  // the round's bound: (area, whole-map id)
    std::uint32_t bound_id = 0;
};

// A split ring's fixed locations in one tile at one level (up to 4 distinct).
struct RingLocations {
    std::uint32_t chain;  // the whole map's chain
    std::vector<Point> locations;
};

// What a tile leaves after the levels below T, in whole-map ids.
struct TileOutcome {
    std::vector<std::uint32_t> ids;                              // the vertices inside the tile whose state changed
    std::vector<std::uint8_t> states;                            // and their VertexStates now
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;  // (waiter, blocker) among them
    std::vector<std::vector<std::uint32_t>> later;               // [level − T]: candidates of that level
    std::vector<std::pair<std::uint32_t, std::uint32_t>> locations_lost;  // (chain, count): rings' distinct locations removed
    std::vector<std::uint32_t> oriented;                         // whole rings whose orientation the tile computed
    std::vector<std::int8_t> orientations;                       // and that orientation
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

// Runs a group of tiles through the levels below their tile level, deciding their open rings
// together; one outcome per tile, in order. Each tile task of a distributed run is one call.
std::vector<TileOutcome> run_tile_group(std::vector<TileInput> group, const GridPlan& plan, const SimplifyOptions& options);

class FirstRound;

// Where a run in parts stands when its engine changes hands (MapInParts from FirstRound).
struct PartsSoFar {
    std::uint64_t goal = 0;          // the removals a count target asks for (removal_goal)
    std::uint64_t round_budget = 0;  // this round's
    unsigned rounds_started = 0;
    SimplifyStats stats;
    double bound_key = 0;            // this round's bound, a whole-map id
    std::uint32_t bound_id = 0;
    double work = 0;                 // the progress's whole
};

// The whole map's side of a run in parts: the plan, the crossing search, each round's budget and
// tiles, and the levels from T up. It holds the whole map's engine (the part that a distributed
// run has yet to spread: docs/distributed.md).
//
//     MapInParts parts(map, options, tile_level);
//     while (parts.next_round()) {
//         std::vector<TileOutcome> outcomes = /* run_tile_group on each parts.group(k), k < parts.split_round() */;
//         parts.finish_round(outcomes);  // or: if (parts.finish_tiles(outcomes)) parts.finish_top(/* run_tile_group on {parts.top()} */);
//     }
//     SimplifyResult result = parts.result();
class MapInParts {
public:
    // `map` and `options` outlive this. tile_level is capped at the plan's levels. A round of a
    // count target whose budget is under `here_below` vertices runs here, whole, as the single
    // process runs it (split_round() is then 0): cheaper than tasks when little is to go.
    MapInParts(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint64_t here_below = 0);
    ~MapInParts();

    const GridPlan& plan() const;
    unsigned tile_level() const;
    // Starts a round (one for --max and --max-area; count targets: while vertices are to go and
    // can); false when there is none left.
    bool next_round();
    // Starts the round's tiles: returns how many groups of them run (0 when the round runs here).
    // The tiles that must run together form a group: those sharing a split ring that its cut
    // ends do not settle (most tiles are alone). Groups are in row-major order of their first
    // tiles, each in row-major order; groups with nothing to do in the round are left out.
    std::size_t split_round();
    // Group k (< split_round()) of the round: its tiles' inputs, built now (the round's tiles
    // are never all built at once; a group may be built again, e.g. for a task run again).
    std::vector<TileInput> group(std::size_t k) const;
    std::size_t group_size(std::size_t k) const;       // its tiles
    std::uint64_t group_points(std::size_t k) const;   // its tiles' vertices (with cut ends) and control points
    // split_round() and every group.
    std::vector<std::vector<TileInput>> tile_groups();
    // The round's outcomes (each tile's once, in any order), then the levels from T up, here,
    // over the whole map's engine.
    void finish_round(std::span<const TileOutcome> outcomes);
    // Or in steps, the levels from T up run elsewhere: the outcomes in; if the levels from T up
    // have candidates (else the round is over), they run as one more tile, top() (the live
    // vertices and the control points that can count), whose outcome ends the round.
    bool finish_tiles(std::span<const TileOutcome> outcomes);
    TileInput top();
    void finish_top(const TileOutcome& outcome);
    // The levels from T up here, after finish_tiles returned true.
    void run_top_here();
    // From here on, the run holds the live vertices only (and every control point): the whole
    // map's engine goes, and with it every use of `map`. Call after finish_tiles returned true
    // (the levels from T up are then still to run). The result is the same; ids in tiles and
    // outcomes stay the whole map's.
    void keep_live_only();
    SimplifyResult result();

private:
    friend class FirstRound;
    // Over `live` (the live vertices and every control point, as keep_live_only makes them) of a
    // map of `input_vertices`, in a round whose tiles are done.
    MapInParts(TileInput live, std::size_t input_vertices, const GridPlan& plan, const SimplifyOptions& options,
               unsigned tile_level, std::uint64_t here_below, const PartsSoFar& so_far);

    std::unique_ptr<TileInput> live_;  // after keep_live_only: the live vertices the engine runs over
    std::size_t input_vertices_ = 0;   // and the whole map's vertex count
    std::unique_ptr<detail::Simplifier> engine_;
    GridPlan plan_;
    unsigned tile_level_;
    std::uint64_t here_below_;
};

// The first round of a run in parts built from the map a part at a time, by no engine over the
// whole map (the start of a run that never holds the whole map: docs/distributed.md):
// - each chain goes to the tiles holding its vertices, cut into pieces with their cut ends as
//   MapInParts cuts it, and every segment that leaves a tile also to the tiles its box meets;
// - the crossing search runs tile by tile over those segments: a segment inside a tile meets
//   only segments that reach the tile, and the flags of the segments that leave a tile are
//   or-ed over the tiles, so every vertex is pinned as the whole map's search pins it;
// - a count target's first budget is selected over the tiles' queued vertices (area, then id);
// - the tiles that share a ring their cut ends do not settle form a group, as in split_round.
// The outcomes and the tiles then give the live vertices, over which a MapInParts goes on
// (keep_live_only's). The result is simplify()'s, stats included but the predicates the crossing
// search counts (a pair of segments met in several tiles is decided in each).
//
//     FirstRound first(plan, tile_level, options, vertices);
//     for (each part of the chains, in order) first.add_chains(part, first_vertex, first_chain);
//     first.add_control_points(points);
//     for (std::size_t k = 0; k < first.split(); ++k) outcomes += run_tile_group(first.group(k), plan, options);
//     std::unique_ptr<MapInParts> parts = first.finish(outcomes, here_below);
//     parts->run_top_here();  // (or top() / finish_top)
//     while (parts->next_round()) ...
class FirstRound {
public:
    // `vertices`: the whole map's. `options` outlives this and the MapInParts it makes.
    FirstRound(const GridPlan& plan, unsigned tile_level, const SimplifyOptions& options, std::uint64_t vertices);
    ~FirstRound();
    // The map's chains in order, a part at a time: vertex v and chain c of `part` are the whole
    // map's first_vertex + v and first_chain + c.
    void add_chains(const MapData& part, std::uint32_t first_vertex, std::uint32_t first_chain);
    void add_control_points(std::span<const Point> points);
    // After the last part: the crossings, the budget and the groups; how many groups run.
    std::size_t split();
    std::vector<TileInput> group(std::size_t k) const;
    std::size_t group_size(std::size_t k) const;       // its tiles
    std::uint64_t group_points(std::size_t k) const;   // its tiles' vertices (with cut ends) and control points
    // The groups' outcomes (each tile's once, in any order): the run over the live vertices, its
    // first round's levels from the tile level up next (run_top_here, or top and finish_top).
    std::unique_ptr<MapInParts> finish(std::span<const TileOutcome> outcomes, std::uint64_t here_below = 0);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// simplify() run in parts in this process, every group of tiles in turn (rounds with a budget
// under `here_below` whole, as MapInParts says), and the levels from T up as one more tile (top)
// or, with `top_here`, over the whole map's engine (finish_round). With `live_only`, the run keeps
// only the live vertices from the first round's tiles on (keep_live_only). For tests and as the
// reference for a distributed run.
SimplifyResult simplify_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint64_t here_below = 0,
                                 bool top_here = false, bool live_only = false);
// The same with the first round built by FirstRound from parts of about `part_vertices`
// vertices (its crossing search's predicates counted as FirstRound says).
SimplifyResult simplify_by_parts(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::size_t part_vertices,
                                 std::uint64_t here_below = 0);

}  // namespace toposimp::map
