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
#include "core/map/point_cells.hpp"
#include "core/map/point_grid.hpp"
#include "core/map/simplify.hpp"

#include "core/parallel/select.hpp"

#include <cstdint>
#include <map>
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

// A ring's fixed locations outside a subset of the live map at one level (up to 4 distinct):
// MapInParts::top_subset.
struct RingOutside {
    std::uint32_t chain;  // the whole map's chain
    unsigned level;
    std::vector<Point> locations;
};

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
    // The levels from T up over a subset of the live map (MapInParts::top_subset); else empty.
    // Per vertex: 1 for a cut end (the live vertex beyond a run, fixed here). The ring pieces'
    // fixed locations outside the runs, per level from first_level below the ring's whole_level.
    std::vector<std::uint8_t> cut_end;
    std::vector<RingOutside> outside;
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
    // A subset of the live map whose runs were too short (a vertex next to a cut end went): the
    // rest of this outcome must not be taken.
    bool exhausted = false;
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

// Runs several groups of tiles (each as run_tile_group does), their outcomes per group in order.
// With at least as many groups as threads (options.threads; 0: OpenMP's default), the groups run
// side by side, a thread each, the biggest first; else one after the other, each on all the
// threads. The outcomes are the same either way (a tile's run does not depend on its threads),
// and so is the memory bound of a task: its groups together hold at most the round's biggest
// group (python/toposimp/dask.py: _batches). Why: within one tile the levels' blocks are few
// and uneven (GSHHG's first round's tiles, in one process, ran only 1.27 times as fast on 2 threads
// as on 1); side by side, a thread waits less on the other. On a Dask worker with glibc's malloc
// that cut the first round's compute from 5.33 to 4.68 s; with jemalloc it changed nothing
// (BENCHMARKS.md, session 56). A group that throws does not stop the others; the first group's
// exception in order is rethrown once all have run. `options.progress` is not called.
std::vector<std::vector<TileOutcome>> run_tile_groups(std::vector<std::vector<TileInput>> groups, const GridPlan& plan,
                                                      const SimplifyOptions& options);

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
    // Another tile level (capped at the plan's levels), before the first round: the set-up and
    // the crossing search, which the constructor runs, do not depend on it.
    void set_tile_level(unsigned tile_level);
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
    // Or the same tile over a subset of the live vertices, a small part of them (what the levels
    // from T up read: docs/distributed.md, "What is left", item 4): runs of `runs` live vertices
    // on either side of those levels' candidates (and of the vertices waiting on a vertex of a
    // run), each with its cut ends, the live vertices and control points in the runs' boxes, the
    // rings that may come down to their last locations whole. finish_top_subset takes its
    // outcome and ends the round; or, if a vertex next to a cut end went (the runs were too
    // short), takes nothing and returns false: then again with longer runs (with runs longer
    // than any chain there is no cut end).
    TileInput top_subset(std::uint32_t runs);
    bool finish_top_subset(const TileOutcome& outcome);
    // The levels from T up here, after finish_tiles returned true.
    void run_top_here();
    // From here on, the run holds the live vertices only (and every control point): the whole
    // map's engine goes, and with it every use of `map`. Call after finish_tiles returned true
    // (the levels from T up are then still to run). The result is the same; ids in tiles and
    // outcomes stay the whole map's.
    void keep_live_only();
    SimplifyResult result();

private:
    friend class FirstRoundLead;
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
// whole map (the start of a run that never holds the whole map: docs/distributed.md), in stages
// that a distributed run spreads over its processes:
// 1. cut_part, a part of the map's chains at a time (in order): each chain's facts for the lead,
//    and its pieces by tile. Each chain goes to the tiles holding its vertices, cut into pieces
//    with their cut ends as MapInParts cuts it, and every segment that leaves a tile also to the
//    tiles its box meets.
// 2. FirstTile: a tile's pieces from every part (add, in the parts' order), then search(): the
//    crossing search over them. A segment inside a tile meets only segments that reach the tile;
//    the segments that leave a tile found to meet another go to the lead (found), which or-es them
//    over the tiles (border), so that every vertex is pinned as the whole map's search pins it.
// 3. Each tile's queue(border): its vertices' states, and a count target's keys.
// 4. The lead's wanted(): a count target's first budget, selected over the tiles' keys (area,
//    then id) by a DigitSelector asking every tile's histogram() and ids_at(); bound().
// 5. The lead's groups from every tile's busy() (or smallest()) and open_chains(): the tiles that
//    share a ring their cut ends do not settle run together, as in split_round.
// 6. Each group runs (run_tile_group over its tiles' run_input(), with the lead's points());
//    every tile's live_vertices() and the outcomes go to the lead's finish: a MapInParts over the
//    live vertices goes on (keep_live_only's). The result is simplify()'s, stats included but the
//    predicates the crossing search counts (a pair of segments met in several tiles is decided
//    in each).

// Per chain of a part of the map: what the first round keeps of it.
struct ChainFacts {
    std::vector<Chain> chains;               // its whole-map vertex ids (first, last)
    std::vector<std::uint8_t> whole_level;   // kOpenChain if not closed
    std::vector<std::uint32_t> distinct;     // a ring's distinct locations (0 for an open chain)
    std::vector<std::int8_t> orientation;    // a ring's input orientation (as know_orientation keeps it), else 2
    std::vector<std::uint8_t> frozen;        // (for the cut itself: the lead keeps the rest)
};

// A vertex the levels from T up removed, with the live vertices on either side of it once they
// are over (KeptTiles: a tile's cut end that went is replaced by the next live vertex beyond).
struct Unlinked {
    std::uint32_t id;
    std::uint32_t prev, next;  // whole-map ids
    Point prev_point, next_point;
};

// What every kept tile learns at a round's end (KeptTiles::finish_tiles, finish_top).
struct TileNews {
    // After the tiles' levels: the tiles' own outcomes' states (`outcome_states`, by id) and waits
    // (`tile_waits`); a store whose tiles are elsewhere may take those from the outcomes where the
    // tiles ran instead.
    bool after_tiles = false;
    std::vector<std::pair<std::uint32_t, std::uint8_t>> outcome_states;
    // The states the lead changed (the waiters it queued again) or the levels from T up, by id, one
    // per id; over outcome_states.
    std::vector<std::pair<std::uint32_t, std::uint8_t>> states;
    std::vector<Unlinked> unlinked;                                   // sorted by id
    std::vector<std::pair<std::uint32_t, std::uint32_t>> tile_waits;  // the tiles' outcomes' waits (sorted)
    std::vector<std::uint32_t> judged;                                // sorted: what the levels from T up held (not cut ends)
    std::vector<std::pair<std::uint32_t, std::uint32_t>> top_waits;   // their outcome's waits (sorted)
    std::vector<std::uint32_t> distinct;                              // per whole-map chain, the lead's now
    std::vector<std::int8_t> orientation;
};

// A tile of the first round: its chains' pieces (from one part, or from every part once added)
// without states, then what the stages add. Kept for the rounds after the first (KeptTiles), it
// holds the tile's live vertices, each piece with its cut ends, and the waits among them.
struct FirstTile {
    std::uint32_t number = 0;           // row-major among the blocks of level T
    TileInput input;                    // states (and marks) only after queue()
    std::vector<std::uint8_t> cut_end;  // per vertex of input.map
    std::vector<std::uint8_t> frozen;   // per chain of input.map
    std::vector<Point> passing;         // segments (pairs of points) of other tiles' chains whose boxes meet the tile
    std::vector<std::uint32_t> passing_id;  // and their first vertices' whole-map ids (until search)
    std::vector<std::uint8_t> improper;  // per vertex: its segment to the next meets another, by this tile's search
    std::vector<std::uint64_t> keys;     // a count target's: its queued vertices' area keys, in order (after queue)

    // The next part's pieces of this tile.
    void add(FirstTile&& part);
    // The crossing search: the segments that leave the tile found to meet another (their first
    // vertices' whole-map ids, sorted). Drops the passing segments.
    std::vector<std::uint32_t> search(exact::Arithmetic arithmetic, exact::PredicateStats& predicates);
    // The states, with `border` the lead's border() (sorted): chain ends, cut ends, frozen chains
    // and the ends of segments meeting another fixed, the rest queued; with `marks`, the queued
    // vertices' keys. Returns how many were pinned (by a crossing or frozen).
    std::uint64_t queue(std::span<const std::uint32_t> border, bool marks, const Ranking& ranking);
    std::uint64_t queued() const { return keys.size(); }  // (a count target's: its keys)
    // For the lead's DigitSelector (select_kth_by_digits's histogram and ids_at).
    void histogram(int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) const;
    void ids_at(std::uint64_t key, std::vector<std::uint32_t>& ids) const;
    // A count target's: whether one of its vertices is in the round's budget.
    bool busy(double bound_key, std::uint32_t bound_id) const;
    // A count target's: its smallest (key, id) pair (all bits set if it has none): busy iff it is at
    // most the bound.
    std::pair<std::uint64_t, std::uint32_t> smallest() const;
    // The (key, id) pairs whose keys' bits from `shift` up equal `prefix` (the bucket a
    // DigitSelector pass ended in, gathered when small).
    void pairs_in(int shift, std::uint64_t prefix, std::vector<std::uint64_t>& keys_found, std::vector<std::uint32_t>& ids) const;
    // The whole-map rings it holds pieces of that their cut ends do not settle.
    std::vector<std::uint32_t> open_chains() const;
    // The tile to run: marked up to the bound (count targets), with its control points.
    TileInput run_input(bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) const;

    // Kept for the next rounds (KeptTiles): (waiter, blocker) whole-map ids, both its own vertices;
    // per vertex, in the round's budget (a count target's, as marked when the round began).
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits;
    std::vector<std::uint8_t> marked;
    void mark(double bound_key, std::uint32_t bound_id);
    // A round over: the removed vertices out, the states now, a cut end that went replaced by the
    // live vertex beyond it (two pieces joined where that one is in the tile), the waits now (its
    // own outcome's if `ran`, the top's for what the top judged), its whole rings' counts from
    // the lead; a count target's keys again (`marks`). Returns the waits of its own outcome on a
    // vertex outside it (a cut end), which the lead holds, and what it did.
    struct Advanced {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> across;
        std::size_t cut_ends_moved = 0, pieces_joined = 0;
    };
    Advanced advance(const TileNews& news, bool ran, const GridPlan& plan, bool marks, const Ranking& ranking);
    // Per split ring it holds a piece of: up to 4 distinct locations among the ends of its segments
    // that cross the tile's border (the lead's union over the tiles settles the ring, or not).
    std::vector<RingLocations> crossing_locations() const;
    // `settled`: the split rings that their cut ends settle, sorted.
    void settle(std::span<const std::uint32_t> settled);
};

// A part's chains: their facts, and their pieces by tile (ascending numbers).
struct CutPart {
    ChainFacts facts;
    std::vector<FirstTile> tiles;
};
// Vertex v and chain c of `part` are the whole map's first_vertex + v and first_chain + c.
CutPart cut_part(const MapData& part, std::uint32_t first_vertex, std::uint32_t first_chain, const GridPlan& plan, unsigned tile_level,
                 const SimplifyOptions& options);

// A tile's live vertices after its group ran: its own (not its cut ends), not removed, with their
// states and marks.
struct LiveVertices {
    std::vector<std::uint32_t> ids;  // ascending
    std::vector<Point> points;
    std::vector<std::uint8_t> states;
    std::vector<std::uint8_t> marked;  // count targets only
};
// The states that outcomes changed, by id: those of a tile's group (or more) for live_vertices.
std::vector<std::pair<std::uint32_t, std::uint8_t>> changed_states(std::span<const TileOutcome> outcomes);
// `changed`: as changed_states gives it (empty if the tile's group sat the round out).
LiveVertices live_vertices(const FirstTile& tile, std::span<const std::pair<std::uint32_t, std::uint8_t>> changed, bool marks,
                           double bound_key, std::uint32_t bound_id);

// The whole map's side of the first round (stages 2 to 6 above): what it holds is per chain and
// per control point, never per vertex but the live ones at the end.
class FirstRoundLead {
public:
    // `vertices`: the whole map's. `options` outlives this and the MapInParts it makes.
    FirstRoundLead(const GridPlan& plan, unsigned tile_level, const SimplifyOptions& options, std::uint64_t vertices);
    ~FirstRoundLead();
    FirstRoundLead(const FirstRoundLead&) = default;
    FirstRoundLead(FirstRoundLead&&) = default;
    const GridPlan& plan() const { return plan_; }
    unsigned tile_level() const { return t_; }
    const SimplifyOptions& options() const { return options_; }
    std::uint32_t chains() const { return static_cast<std::uint32_t>(chains_.size()); }
    // The parts' facts, in order (first_chain checked).
    void add_facts(const ChainFacts& facts, std::uint32_t first_chain);
    void add_control_points(std::span<const Point> points);
    // A tile's search: what it found and what its predicates cost.
    void found(std::span<const std::uint32_t> border, const exact::PredicateStats& predicates);
    // The segments leaving a tile that meet another, over every tile (sorted; after every found).
    const std::vector<std::uint32_t>& border();
    // Whether the tiles run on marks (a count target's budget): asked of queue(), and again after
    // wanted(), which turns it off for a count target that runs as --max (swept_as_max).
    bool marks() const { return marks_; }
    // The tiles' queue(): what each pinned and queued.
    void queued(std::uint64_t pinned, std::uint64_t keys);
    // How many of the smallest keys the first budget takes: 0 when no selection is to be made
    // (--max, --max-area; a count target with nothing to go, or run as --max).
    std::uint64_t wanted();
    void bound(parallel::KeyedSelection selection);
    // A later round's (KeptTiles): its bound, one more round.
    void next_bound(parallel::KeyedSelection selection);
    const SimplifyStats& stats() const { return so_far_.stats; }
    std::uint64_t vertices() const { return vertices_; }
    double bound_key() const { return so_far_.bound_key; }
    std::uint32_t bound_id() const { return so_far_.bound_id; }
    // Every tile holding vertices: its number, whether busy, its open chains (open_chains());
    // the groups that run, each its tiles' numbers (in split_round's order).
    struct TileFacts {
        std::uint32_t number;
        bool busy;
        std::vector<std::uint32_t> open_chains;
    };
    const std::vector<std::vector<std::uint32_t>>& groups(std::vector<TileFacts> tiles);
    const std::vector<std::vector<std::uint32_t>>& groups() const { return groups_; }
    // A tile's control points (after groups).
    std::vector<Point> points(std::uint32_t tile) const;
    std::uint64_t points_in(std::uint32_t tile) const;
    // Every tile's live vertices and the groups' outcomes (each tile's once, in any order): the
    // run over the live vertices, its first round's levels from the tile level up next.
    std::unique_ptr<MapInParts> finish(std::vector<LiveVertices> live, std::span<const TileOutcome> outcomes, std::uint64_t here_below = 0);

    // For the rounds after the first (KeptTiles): a count target's removal goal (after wanted());
    // an outcome (a tile's, or the levels from T up's) into the chains' facts and the counts; the
    // rings' distinct locations and orientations now.
    std::uint64_t goal() const { return so_far_.goal; }
    void take(const TileOutcome& outcome);
    const std::vector<std::uint32_t>& distinct() const { return distinct_; }
    const std::vector<std::int8_t>& orientation() const { return orientation_; }
    const std::vector<Chain>& chains_by_id() const { return chains_; }
    const std::vector<std::uint8_t>& whole_level() const { return whole_level_; }
    const std::vector<Point>& control_points() const { return control_points_; }

private:
    GridPlan plan_;
    unsigned t_;
    const SimplifyOptions& options_;
    std::uint64_t vertices_;
    std::vector<Chain> chains_;  // the whole map's vertex ranges, and per chain its facts
    std::vector<std::uint8_t> whole_level_;
    std::vector<std::uint32_t> distinct_;
    std::vector<std::int8_t> orientation_;
    std::vector<Point> control_points_;
    std::vector<std::uint32_t> border_;
    bool border_sorted_ = false;
    std::uint64_t queued_ = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> point_tiles_;  // (tile, control point), sorted
    std::vector<std::vector<std::uint32_t>> groups_;
    PartsSoFar so_far_;
    bool marks_ = false;
};

// A top_subset's questions to the kept tiles, a wave of them: the vertices around `ids` in their
// pieces (learnt whole; the cut ends and the vertices beyond as points); every piece of `rings`;
// the own live vertices in `boxes` but those in `skip`; per ring in `outside_rings`, the fixed
// locations of its pieces outside the runs (`runs`), at each level from `from_level` below its
// whole level.
struct SubsetAsk {
    std::vector<std::uint32_t> ids, rings;
    std::uint32_t reach = 0;  // around each of `ids` (and each vertex at a shared location in `boxes`), this many vertices of its piece either side
    std::vector<Box> boxes;
    std::vector<std::uint32_t> skip;           // sorted
    std::vector<std::uint32_t> outside_rings;  // sorted
    std::vector<std::uint32_t> runs;           // sorted
    unsigned from_level = 0;
};

// The tiles' answers to a SubsetAsk.
struct SubsetAnswer {
    // Vertices learnt: whole (from their own tile: their neighbours, state, mark, whether another
    // live vertex is at their location), or a cut end's point and chain only, or a point in a box
    // (no neighbours).
    enum Flags : std::uint8_t { shared = 1, own = 2, whole = 4 };  // (own: state, marked and shared told; whole: and neighbours)
    std::vector<std::uint32_t> ids, chain, prev, next;  // (prev, next: kNone at a chain's end or not known)
    std::vector<Point> points;
    std::vector<std::uint8_t> state, marked, flags;
    std::vector<std::uint32_t> in_boxes;  // the ids found in the boxes
    // Per piece of an outside ring (keyed by its first own id): per level, its first 4 distinct
    // fixed locations outside the runs, in chain order.
    struct Outside {
        std::uint32_t chain, first;
        std::vector<std::vector<Point>> levels;
    };
    std::vector<Outside> outside;
    void add(SubsetAnswer&& more);
};

// Kept tiles where they are (KeptTiles's own in this process; a batch of them on a distributed
// run's worker): what the lead asks of them, round after round.
class KeptBatch {
public:
    KeptBatch();
    explicit KeptBatch(std::map<std::uint32_t, FirstTile> tiles);
    ~KeptBatch();
    KeptBatch(KeptBatch&&) noexcept;
    KeptBatch& operator=(KeptBatch&&) noexcept;
    // A round's end: every tile told `news`, those among `ran` (sorted) having run; the tiles left
    // without vertices go. The waits their own outcomes begin on a cut end (the lead's), and counts.
    FirstTile::Advanced advance(const TileNews& news, std::span<const std::uint32_t> ran, const GridPlan& plan, bool marks,
                                const Ranking& ranking);
    // A count target's next round: its queued vertices, their keys (the budget selected over the
    // batches: select_kth_by_digits's histogram and ids_at).
    std::uint64_t queued() const;
    void histogram(int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) const;
    void ids_at(std::uint64_t key, std::vector<std::uint32_t>& ids) const;
    void pairs_in(int shift, std::uint64_t prefix, std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& ids) const;
    // Per split ring it holds pieces of: up to 4 distinct locations at the ends of its segments
    // across tile borders.
    std::vector<RingLocations> crossing_locations() const;
    // The round begun: its marks (count targets), its settled rings (sorted); each tile's facts.
    std::vector<FirstRoundLead::TileFacts> begin_round(std::span<const std::uint32_t> settled, bool marks, double bound_key,
                                                       std::uint32_t bound_id);
    // Tile `number`'s input for the round, with its control points.
    TileInput input(std::uint32_t number, bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) const;
    std::size_t tiles() const { return tiles_.size(); }
    const std::map<std::uint32_t, FirstTile>& all() const { return tiles_; }
    KeptBatch clone() const { return KeptBatch(tiles_); }
    // Every wait among its tiles' vertices.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits() const;
    SubsetAnswer answer(const SubsetAsk& ask, const GridPlan& plan) const;

private:
    std::map<std::uint32_t, FirstTile> tiles_;  // by number, those holding live vertices
    struct Index;                               // (for answer: built at the first question after a change)
    mutable std::unique_ptr<Index> index_;
};

// Where KeptTiles's tiles are: a KeptBatch in this process (KeptTiles's own), or batches of them on
// a distributed run's workers (toposimp.dask). What the lead asks of them, as KeptBatch answers it.
class KeptStore {
public:
    virtual ~KeptStore() = default;
    virtual FirstTile::Advanced advance(const TileNews& news, std::span<const std::uint32_t> ran) = 0;
    virtual std::uint64_t queued() = 0;
    // The wanted-th smallest (key, id) over the tiles' queued vertices.
    virtual parallel::KeyedSelection select(std::uint64_t wanted) = 0;
    virtual std::vector<RingLocations> crossing_locations() = 0;
    virtual std::vector<FirstRoundLead::TileFacts> begin_round(std::span<const std::uint32_t> settled, bool marks, double bound_key,
                                                               std::uint32_t bound_id) = 0;
    // The round's groups (tile numbers) run where their tiles are, with their tiles' control
    // points (`points`, tile after tile): the outcomes, group after group, tile after tile.
    virtual std::vector<TileOutcome> run(const std::vector<std::vector<std::uint32_t>>& groups, std::vector<std::vector<Point>> points,
                                         bool marks, double bound_key, std::uint32_t bound_id) = 0;
    virtual TileInput input(std::uint32_t number, bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) = 0;
    virtual std::vector<std::pair<std::uint32_t, std::uint32_t>> waits() = 0;
    virtual SubsetAnswer answer(const SubsetAsk& ask) = 0;
    virtual std::size_t tiles() = 0;
};

// The rounds after the first from the first round's tiles, kept (docs/distributed.md, "What is
// left", items 4 and 5), instead of built again from the live map each round: each tile told what
// the round changed (TileNews: the states, the cut ends that went, the waits, the rings' counts),
// its count target's keys its own again, each round's budget selected over them and its groups
// found as in the first round (FirstRoundLead). What it holds beside the tiles is per chain, per
// control point and per wait across tiles. Each round's tiles are MapInParts's, input for input.
//
//     FirstRound first(...);  ...  first.split();
//     KeptTiles kept = first.keep();
//     do {
//         // the round's groups run: kept.run_groups(), or kept.group(k) for k < kept.groups() (outcomes)
//         if (kept.finish_tiles(outcomes)) run_kept_top(kept, plan, options, runs);  // (top_subset, finish_top_subset)
//     } while (kept.next_round());
//     SimplifyResult result = kept.result();
class KeptTiles {
public:
    // The tiles here (marked for the first round's budget).
    KeptTiles(FirstRoundLead lead, std::map<std::uint32_t, FirstTile> tiles);
    // Or elsewhere, marked.
    KeptTiles(FirstRoundLead lead, std::unique_ptr<KeptStore> tiles);
    ~KeptTiles();
    KeptTiles(KeptTiles&&) noexcept;
    // The round's tiles' outcomes (each tile's once, in any order); whether the levels from T up
    // have candidates (else the round is over).
    bool finish_tiles(std::span<const TileOutcome> outcomes);
    // Then the levels from T up: their tile's input and outcome (MapInParts::top's, or a
    // top_subset's not exhausted). The round is over.
    void finish_top(const TileInput& top, const TileOutcome& outcome);
    // A count target's next round: its budget selected over the tiles' keys, the split rings
    // settled or not, the groups that run; false when no round is left.
    bool next_round();
    std::size_t groups() const { return lead_.groups().size(); }
    std::vector<TileInput> group(std::size_t k) const;
    // Or every group run where its tiles are: the outcomes, group after group.
    std::vector<TileOutcome> run_groups();
    // After finish_tiles returned true: the levels from T up over a subset of the live map, as
    // MapInParts::top_subset builds it (input for input), gathered from the tiles — the pieces
    // holding the vertices it walks, the live vertices in its runs' boxes, the rings' fixed
    // locations outside its runs — and what the lead holds (control points, waits across tiles,
    // the rings' counts). finish_top_subset takes its outcome, or nothing (false) if its runs were
    // too short: then again with longer runs.
    TileInput top_subset(std::uint32_t runs) const;
    bool finish_top_subset(const TileInput& top, const TileOutcome& outcome);
    // When no round is left: simplify()'s result, every vertex kept but those the outcomes removed.
    SimplifyResult result() const;
    std::size_t tiles() const { return tiles_->tiles(); }
    // What the news did so far: cut ends moved on, pieces joined, waits across tiles (summed over
    // the rounds' ends), waiters queued again by the lead.
    struct Counts {
        std::size_t cut_ends_moved = 0, pieces_joined = 0, waits_across = 0, queued_again = 0;
        Counts& operator+=(const Counts& more) {
            cut_ends_moved += more.cut_ends_moved;
            pieces_joined += more.pieces_joined;
            waits_across += more.waits_across;
            queued_again += more.queued_again;
            return *this;
        }
    };
    const Counts& counts() const { return counts_; }

private:
    FirstRoundLead lead_;
    std::unique_ptr<KeptStore> tiles_;
    std::vector<std::uint32_t> running_;                                 // the round's tiles that ran, sorted
    std::vector<std::pair<std::uint32_t, std::uint32_t>> cross_waits_;  // (waiter, blocker) in two tiles, sorted
    std::uint64_t removed_ = 0;
    std::vector<std::uint8_t> gone_;  // per vertex of the map: removed
    std::vector<std::vector<std::uint32_t>> later_;  // [level − T]: the candidates the tiles left for the levels from T up
    // The control points in cells (top_subset's boxes), built at the first box. (A sort by x
    // alone read every point in a box's x range: minutes a round with 2 M points. Not a PointGrid:
    // that copies the points, and this lead must stay small: 609 against 648 MiB at its peak with
    // 2 M points, BENCHMARKS.md, session 50.)
    mutable PointCells point_cells_;
    Counts counts_;

    void note_removed(const TileOutcome& outcome);
    // Every tile told `news`; `across`: the waits across tiles now, but those the tiles' own
    // outcomes begin on a cut end (advance adds them).
    void advance(TileNews& news, std::vector<std::pair<std::uint32_t, std::uint32_t>>& across);
    // A top_subset's questions, answered by the tiles.
    SubsetAnswer ask(const SubsetAsk& ask) const { return tiles_->answer(ask); }
};

// The stages in one process: the first round built from parts of the map, its groups run by the
// caller.
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
    // After split() and before finish: the tiles and the lead copied, for the rounds after.
    KeptTiles keep() const { return KeptTiles(lead_, tiles_); }
    // Or moved (this is then spent): the first round's groups run from KeptTiles::group too.
    KeptTiles kept() && { return KeptTiles(std::move(lead_), std::move(tiles_)); }

private:
    FirstRoundLead lead_;
    std::map<std::uint32_t, FirstTile> tiles_;  // by number
};

// The levels from T up (after finish_tiles returned true) as top_subset's tile, run here: runs
// of `runs` vertices, twice as long each time they fall short. Returns the tiles it took.
unsigned run_top_over_subsets(MapInParts& parts, const SimplifyOptions& options, std::uint32_t runs);

// The levels from T up of a round of `kept` (after finish_tiles returned true) over subsets of the
// live map gathered from its tiles, run here: runs of `runs` vertices (at least 1), twice as long
// each time they fall short. Returns the subsets it took.
unsigned run_kept_top(KeptTiles& kept, const GridPlan& plan, const SimplifyOptions& options, std::uint32_t runs);

// simplify() run in parts in this process with nothing over the whole map's vertices: the first
// round built from parts of about `part_vertices` vertices (FirstRound), every round's tiles kept
// (KeptTiles), the levels from T up over subsets gathered from them, with runs of `runs` at first.
// The reference for a distributed run whose lead holds no live map (docs/distributed.md).
SimplifyResult simplify_with_kept_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::size_t part_vertices,
                                        std::uint32_t runs);

// simplify() run in parts in this process, every group of tiles in turn (rounds with a budget
// under `here_below` whole, as MapInParts says), and the levels from T up as one more tile (top)
// or, with `top_here`, over the whole map's engine (finish_round). With `live_only`, the run keeps
// only the live vertices from the first round's tiles on (keep_live_only). With `top_runs` (> 0,
// without `top_here`), the levels from T up run over a subset of the live vertices (top_subset),
// with runs of top_runs vertices, twice as long each time they fall short. For tests and as the
// reference for a distributed run.
SimplifyResult simplify_in_tiles(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::uint64_t here_below = 0,
                                 bool top_here = false, bool live_only = false, std::uint32_t top_runs = 0);
// The same with the first round built by FirstRound from parts of about `part_vertices`
// vertices (its crossing search's predicates counted as FirstRound says).
SimplifyResult simplify_by_parts(const MapData& map, const SimplifyOptions& options, unsigned tile_level, std::size_t part_vertices,
                                 std::uint64_t here_below = 0);

}  // namespace toposimp::map
