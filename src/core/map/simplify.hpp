// EPLSimp / TopoVW map simplification (dissertation chapters 2–3).
//
// Interior vertices are ranked by Visvalingam–Whyatt effective area and removed smallest first,
// but a vertex v with chain neighbours a, c is removed only when
//   1. the closed triangle (a, v, c) holds no other live vertex and no control point, except
//      points at the very locations of a and c (they stay where they are; see 3 for the one
//      way such a point could still matter);
//   2. a closed chain keeps at least 3 distinct locations and, when only 3 remain, they turn
//      the same way as the input ring (non-zero area, same orientation);
//   3. the new segment (a, c) does not coincide with another live segment with the same two
//      end locations (two lines with the same endpoints, or a chain folding back on itself).
// and never removes a vertex at either end of a segment that crosses or touches another segment
// improperly in the input (crossings.hpp). These rules keep every topological relation: no new
// contact between segments, crossings of the input kept as they are, no control point changes
// side (the detour a…c swept by the removals is a union of such empty triangles). Predicates
// are exact unless Arithmetic::floating is asked for.
//
// Parallel, and the same result for any number of threads (dissertation §3.5, Algorithm 3,
// refined from chains to vertices): the point grid's cells are grouped into blocks, level 0
// the finest, each level's blocks 2×2 of the level below, up to one block. A vertex belongs to
// the finest level at which it and both its neighbours lie in one block; its triangle then lies
// in that block (a block's locations form a convex set), and so does every point the rules
// consult. Levels are processed finest first; the blocks of a level are independent and run in
// parallel, each with its own queue, so the order of removals inside a block, and so the result,
// never depends on the threads. Rings split over several blocks are handled without shared
// state: a split ring whose fixed vertices (those not removable at this level) hold at least 4
// distinct locations can never reach the ring rule's limit here; any other waits for a coarser
// level, where it is whole.
//
// Stopping: --max and an area bound sweep the levels once. Count targets run rounds: each takes
// the `missing` smallest current areas as its budget (a threshold plus a mark on exactly those
// vertices) and lets every block remove marked vertices up to the threshold; a round never
// removes more than it marked, and the next round starts from what is left. So the count lands
// exactly on the target when the target can be reached at all. A count target that asks for at
// least as many removals as the rules could ever allow (SimplifyStats::swept_as_max) cannot be
// reached by any run: it runs as --max.
#pragma once

#include "core/exact/predicates.hpp"
#include "core/map/map_data.hpp"

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace toposimp::map {

// When to stop removing vertices.
enum class Target {
    keep_fraction,  // keep ceil(value · input vertices) vertices
    keep_points,    // keep `value` vertices in total
    remove_points,  // remove `value` vertices (GIS Cup 2014 convention)
    max_area,       // remove while the smallest effective area is ≤ value (map units²)
    max,            // remove every vertex that can be removed
};

struct StopCriterion {
    Target target = Target::keep_fraction;
    double value = 0.1;
};

// The order of removals (never whether one is safe: the rules above decide that, exactly).
struct Ranking {
    // Weighted Visvalingam (mapshaper's default method): the effective area times 1 − k·cos θ,
    // θ the angle at the vertex, so vertices at sharp angles (spikes) go earlier; 0 is plain
    // Visvalingam–Whyatt, the default here (the dissertation's order). mapshaper uses k = 0.7.
    double weighting = 0;
    // The vertices are longitude, latitude in degrees: areas (and angles) are taken between the
    // points on a sphere of the Earth's mean radius (6 371 008.8 m), in m², so a triangle near a
    // pole ranks by its true size, not by its size in degrees².
    bool spherical = false;
};

struct SimplifyOptions {
    StopCriterion stop;
    Ranking ranking;  // the order of removals; a max_area stop compares with these values
    exact::Arithmetic arithmetic = exact::Arithmetic::exact;
    // Threads to use; 0 = OpenMP's default (all cores unless OMP_NUM_THREADS says otherwise).
    // The result does not depend on it.
    int threads = 0;
    // Loops over fewer items than this run on one thread (waking threads costs more). Tests set
    // it to 0 to run every loop in parallel on small maps.
    std::size_t parallel_threshold = 1 << 14;
    // Called now and then with the share of the work done (0…1); may be empty. Only reports.
    std::function<void(double done)> progress;
    // Set by the caller to stop: the engine then throws Cancelled (core/cancel.hpp). May be null.
    const std::atomic<bool>* cancel = nullptr;
};

// One round of a count target in one process (-vv prints them): what it removed and where its
// time went.
struct RoundTimes {
    std::uint64_t removed = 0;
    double seconds_select = 0;    // choosing the round's vertices (mark_smallest or mark_few)
    double seconds_schedule = 0;  // queuing them by level and block
    double seconds_sweep = 0;     // the levels' blocks, and what the round leaves for the next
};

struct SimplifyStats {
    std::uint64_t vertices_in = 0;
    std::uint64_t vertices_out = 0;
    std::uint64_t control_points = 0;
    std::uint64_t removed = 0;
    std::uint64_t removal_goal = 0;          // for count targets; 0 otherwise
    bool target_reached = true;              // false if a count target could not be met
    // A count target asking for at least as many removals as the rules could ever allow (chain
    // ends stay, rings keep 3 locations, pinned vertices stay): run as --max, in one sweep.
    bool swept_as_max = false;
    std::uint64_t blocked_by_point = 0;      // removals refused: a point in the triangle
    std::uint64_t blocked_by_ring = 0;       // refused: a ring would lose area or orientation
    std::uint64_t blocked_by_coincidence = 0;  // refused: two segments would coincide
    std::uint64_t pinned_by_crossing = 0;    // interior vertices kept: ends of crossing segments
    std::uint32_t rounds = 0;                // count targets: rounds of parallel sweeps
    std::uint32_t rounds_from_few = 0;       // of those, selected among the few the round before left (one process only)
    std::uint32_t levels = 0;                // levels of the block grid
    int threads = 1;                         // threads used
    // Wall time of the phases (dissertation Table 3.1: initialize = index + crossings).
    double seconds_index = 0;      // point grid, chains, shared locations
    double seconds_crossings = 0;  // improper contacts of the input
    double seconds_sweep = 0;      // removing vertices
    exact::PredicateStats predicates;
    std::vector<RoundTimes> round_times;  // count targets in one process: each round's removals and times

    std::uint64_t blocked() const { return blocked_by_point + blocked_by_ring + blocked_by_coincidence; }
};

struct SimplifyResult {
    std::vector<std::uint8_t> kept;  // per input vertex: 1 if it is in the output
    SimplifyStats stats;
};

// How many removals a count target asks for on a map with `vertices` vertices.
std::uint64_t removal_goal(const StopCriterion& stop, std::uint64_t vertices);

SimplifyResult simplify(const MapData& map, const SimplifyOptions& options);

// The same for a caller that needs the control points no more: they are moved out of `map`
// (left empty; nothing else in it changes) and freed once the engine has indexed them, which
// keeps its own copy in grid order — for 10 M points, 160 MB less at the peak.
SimplifyResult simplify_releasing_points(MapData& map, const SimplifyOptions& options);

}  // namespace toposimp::map
