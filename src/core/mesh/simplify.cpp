// UGSimp's driver (simplify.hpp): the block grid, then level by level, finest first, rounds
// in which every block collapses its cheapest edges in parallel — read as the method goes:
//   drop unused → topology → quadrics → terrain? → spatial order → border planes → grid →
//   for each level: blocks → candidates → rounds (index → threshold → collapse blocks) →
//   compact → input order.
// The steps live in the files simplifier.hpp lists.
#include "core/mesh/simplify.hpp"

#include "core/cancel.hpp"

#include "core/mesh/height_field.hpp"
#include "core/mesh/self_contact.hpp"
#include "core/mesh/simplifier.hpp"
#include "core/parallel/select.hpp"

#include <omp.h>

#include <chrono>
#include <numeric>
#include <stdexcept>
#include <string>

namespace toposimp::mesh {
namespace detail {

using Clock = std::chrono::steady_clock;

Grid Simplifier::grid_over_faces(double factor, Point3 seed) const {
    constexpr std::int64_t kChunk = std::int64_t{1} << 14;
    const auto m = static_cast<std::int64_t>(face_.size());
    const std::int64_t chunks = (m + kChunk - 1) / kChunk;
    struct Part {
        double edges = 0;
        std::uint64_t count = 0;
        Box3 box;
    };
    std::vector<Part> parts(static_cast<std::size_t>(chunks), Part{0, 0, point_box(seed)});
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (std::int64_t k = 0; k < chunks; ++k) {
        Part& part = parts[static_cast<std::size_t>(k)];
        for (std::int64_t f = k * kChunk; f < std::min(m, (k + 1) * kChunk); ++f) {
            if (!alive_[f]) continue;
            const Face& c = face_[f];
            for (int i = 0; i < 3; ++i) {
                part.edges += norm(minus(pos_[c[i]], pos_[c[(i + 1) % 3]]));
                part.box.add(pos_[c[i]]);
            }
            part.count += 3;
        }
    }
    double edges = 0;
    std::uint64_t count = 0;
    Box3 all = point_box(seed);
    for (const Part& part : parts) {
        edges += part.edges;
        count += part.count;
        all.add(part.box.lo);
        all.add(part.box.hi);
    }
    const double extent[3] = {all.hi.x - all.lo.x, all.hi.y - all.lo.y, all.hi.z - all.lo.z};
    const double largest = std::max({extent[0], extent[1], extent[2]});
    double size = count > 0 ? factor * edges / static_cast<double>(count) : 1.0;
    if (!(size > 0) || !std::isfinite(size)) size = largest > 0 ? largest : 1.0;
    // At most 2^20 cells per side (keys pack 21 bits per axis).
    if (largest / size > 1048575.0) size = largest / 1048575.0;
    Grid grid;
    grid.origin = all.lo;
    grid.inverse_size = 1.0 / size;
    for (int axis = 0; axis < 3; ++axis) {
        grid.cells[axis] = static_cast<std::uint32_t>(std::min(1048576.0, std::floor(extent[axis] / size) + 1));
    }
    return grid;
}

void Simplifier::choose_grid() {
    // Cells 1.5 times the mean edge.
    static_cast<Grid&>(grid_) = grid_over_faces(1.5, pos_.empty() ? Point3{0, 0, 0} : pos_[0]);
    // Level-0 blocks: the fewest cells per block side (a power of two) that leaves at most one
    // block per 2 048 faces, between 8 and 512 (the dissertation's best resolution, for meshes of
    // millions of faces). Smaller blocks cost quality: on an 89 k-face model 512 blocks made the
    // Hausdorff distance 20× worse than one block. Blocks per 2 048 faces (23 on that model, 8 per
    // 4 096) kept the Hausdorff distance of every model and terrain of the benchmark, and left
    // less to the last level's single block: 0.95 → 0.74 s there on 2 threads. Never a function
    // of the thread count: the result must not depend on it.
    const double most_blocks = std::clamp(static_cast<double>(face_.size()) / 2048.0, 8.0, 512.0);
    grid_.levels.cells = grid_.cells;
    grid_.levels.shift = 0;
    while (grid_.levels.block_count(0) > most_blocks) ++grid_.levels.shift;
    cell_.resize(pos_.size());
    const auto n = static_cast<std::int64_t>(pos_.size());
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (std::int64_t v = 0; v < n; ++v) cell_[static_cast<std::size_t>(v)] = grid_.cell_key(pos_[static_cast<std::size_t>(v)]);
}

void Simplifier::check_terrain() {
    terrain_ = false;
    if (!options_.terrain) return;
    if (face_.empty()) return;
    // Every face turned the same way in the map plane, none degenerate there, and no two
    // overlapping there (height_field.hpp); otherwise not a planar triangulation: 3D tests.
    auto turn_of = [this](const Face& f) {
        exact::PredicateStats unused;
        return exact::orient_projected(pos_[f[0]], pos_[f[1]], pos_[f[2]], 2, unused);
    };
    const int turn = turn_of(face_[0]);
    if (turn == 0) return;
    const auto m = static_cast<std::int64_t>(face_.size());
    bool same = true;
#pragma omp parallel for schedule(static) reduction(&& : same) num_threads(threads_)
    for (std::int64_t f = 1; f < m; ++f) same = same && turn_of(face_[static_cast<std::size_t>(f)]) == turn;
    terrain_turn_ = turn;
    if (!same) return;
    if (!options_.height_field) {
        plan_overlap_ = plan_overlap(mesh_, turn, border_, threads_);
        if (plan_overlap_) return;
    }
    terrain_ = true;
}

void Simplifier::build_face_index() {
    // The index has its own cells, about six times the current mean edge: stars grow as the
    // mesh gets coarser, and a query should span few cells (a cell visited costs two table
    // lookups, more than the extra faces a bigger cell lists: 4 measured ~10 % faster than 2 on
    // the elephant, 1 ~50 % slower; 6 ~5 % faster than 4 on the scan-sized models and the 2 M
    // terrain in space, the same on the small models, 8 no better, 12 slower; issue 33). Cells
    // only filter (the search decides on the faces themselves, whatever their order): the
    // result is the same for any size. Each face's box is kept as it is now; see
    // FaceIndex::query() for why that makes reading other blocks' faces unnecessary.
    if (use_index_) index_.build(grid_over_faces(6.0, grid_.origin), face_, pos_, alive_, threads_);
}

template <class Wanted>
void Simplifier::place_edges(std::uint32_t v, std::span<const std::uint32_t> around, Wanted wanted, int level,
                             std::uint64_t block, std::vector<Candidate>& out) const {
    // The neighbours' quadrics are scattered: start loading them all before the first is needed.
    for (std::uint32_t w : around) {
        __builtin_prefetch(&quadric_[w]);
        __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[w]) + sizeof(Quadric) - 1);
    }
    for (std::uint32_t w : around) {
        if ((flags_[w] & kInside) == 0 || !wanted(w)) continue;
        const std::uint32_t a = std::min(v, w), b = std::max(v, w);
        Placement placement;
        if (!place(a, b, level, block, placement)) continue;
        out.push_back(candidate(a, b, placement));
    }
}

std::vector<Candidate> Simplifier::block_candidates(int level, const std::uint32_t* vertices, std::size_t count,
                                                     std::uint64_t block,
                                                     const std::vector<std::vector<Candidate>*>& before) {
    std::vector<std::uint32_t> scratch, around;
    // Which vertices have their whole star in the block (fixed for the level: a collapse only
    // merges two inside vertices, so no neighbour outside the block appears or disappears). A
    // vertex inside at the level before stays inside: its block holds the one it was in. The
    // neighbours of those newly inside are kept for their edges below: (vertex, first, count).
    std::vector<std::uint32_t> neighbours;
    std::vector<std::array<std::uint32_t, 3>> newly;
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint32_t v = vertices[i];
        if ((flags_[v] & (kDead | kInside)) != 0) continue;
        faces_of(v, scratch);
        bool inside = true;
        for (std::uint32_t f : scratch) {
            for (std::uint32_t w : face_[f]) inside = inside && grid_.block_of(cell_[w], level) == block;
        }
        if (!inside) continue;
        corners_but(scratch, v, around);
        flags_[v] |= kInside | kNewlyInside;
        newly.push_back({v, static_cast<std::uint32_t>(neighbours.size()), static_cast<std::uint32_t>(around.size())});
        neighbours.insert(neighbours.end(), around.begin(), around.end());
    }
    // Edges between vertices inside before: their candidates from the finer blocks, which keep
    // one valid candidate for each (see collapse_block). The placement is the same in the bigger
    // block unless the smaller one held it back.
    std::vector<Candidate> heap;
    for (std::vector<Candidate>* list : before) {
        for (const Candidate& c : *list) {
            if (stale(c)) continue;
            if (!c.bound()) {
                heap.push_back(c);
                continue;
            }
            Placement placement;
            if (place(c.a, c.b, level, block, placement)) heap.push_back(candidate(c.a, c.b, placement));
        }
        std::vector<Candidate>().swap(*list);
    }
    // Edges with a newly inside end: each once.
    for (const auto& [v, first, size] : newly) {
        place_edges(v, std::span(neighbours).subspan(first, size), [&, self = v](std::uint32_t w) { return (flags_[w] & kNewlyInside) == 0 || w > self; }, level, block, heap);
    }
    for (std::size_t i = 0; i < count; ++i) flags_[vertices[i]] &= static_cast<std::uint8_t>(~kNewlyInside);
    return heap;
}

BlockResult Simplifier::collapse_block(int level, std::uint64_t block, std::vector<Candidate>& candidates,
                                       std::uint64_t budget, double cost_limit) {
    BlockResult result;
    Overlay overlay;
    std::vector<Candidate> fresh;
    std::vector<std::uint32_t> around;
    // `candidates` keeps every live edge of the block's inside vertices (a collapse adds the
    // edges it changes and stamps make the old ones stale), so a later round of the level starts
    // from them instead of from scratch. Those under the round's cost limit are sorted and taken
    // in order, merged with a small heap of the new edges under the limit: the cheapest (cost, a,
    // b) first, as from one heap, but a candidate gone stale costs a step, not a heap pop. Those
    // refused and those dearer than the limit, which cannot be taken in this round, wait after
    // them; at the end the taken ones are dropped and the heap's rest joins the others.
    auto dear = [cost_limit](const Candidate& c) { return c.cost > cost_limit; };
    const auto cheap = static_cast<std::size_t>(
        std::partition(candidates.begin(), candidates.end(), [&](const Candidate& c) { return !dear(c); }) - candidates.begin());
    // Sorted a part at a time: a block with a small budget among many candidates (the last
    // level's one block) needs the first few only.
    const auto earlier = [](const Candidate& x, const Candidate& y) { return later(y, x); };
    const auto at = [&](std::size_t i) { return candidates.begin() + static_cast<std::ptrdiff_t>(i); };
    std::size_t sorted = 0;  // candidates[0, sorted) are the cheapest, in order
    std::vector<Candidate> heap;
    std::size_t next = 0;  // the first sorted one not taken
    while (result.faces_removed < budget) {
        if (next == sorted && sorted < cheap) {
            const std::uint64_t step = budget >= cheap ? cheap : 4 * budget + 256;  // (a budget may be unlimited)
            const std::size_t until = std::min<std::uint64_t>(cheap, std::max<std::uint64_t>(2 * sorted, sorted + step));
            if (until < cheap) std::nth_element(at(sorted), at(until), at(cheap), earlier);
            std::sort(at(sorted), at(until), earlier);
            sorted = until;
        }
        Candidate c;
        if (next < sorted && (heap.empty() || !later(candidates[next], heap.front()))) {
            c = candidates[next++];
        } else if (!heap.empty()) {
            std::pop_heap(heap.begin(), heap.end(), later);
            c = heap.back();
            heap.pop_back();
        } else {
            break;
        }
        // The sorted ones come in cost order, their vertices anywhere in the block: start loading
        // what the next one needs while this one is done.
        if (next + 4 < sorted) {
            __builtin_prefetch(&stamp_[candidates[next + 4].a]);
            __builtin_prefetch(&stamp_[candidates[next + 4].b]);
        }
        if (next < sorted) {
            for (const std::uint32_t v : {candidates[next].a, candidates[next].b}) {
                __builtin_prefetch(&head_[v]);
                __builtin_prefetch(&pos_[v]);
                __builtin_prefetch(&quadric_[v]);
                __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + sizeof(Quadric) - 1);
            }
        }
        if (stale(c)) continue;
        if (vertical_ && c.refused_touches == touches(c)) {
            candidates.push_back(c);
            continue;
        }
        if (!try_collapse(c.a, c.b, level, block, result, around, overlay)) {
            if (vertical_) c.refused_touches = touches(c);
            candidates.push_back(c);
            continue;
        }
        fresh.clear();
        place_edges(c.a, around, [](std::uint32_t) { return true; }, level, block, fresh);
        for (const Candidate& e : fresh) {
            if (dear(e)) {
                candidates.push_back(e);
            } else {
                heap.push_back(e);
                std::push_heap(heap.begin(), heap.end(), later);
            }
        }
    }
    candidates.erase(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(next));
    candidates.insert(candidates.end(), heap.begin(), heap.end());
    return result;
}

void Simplifier::reopen(std::vector<Candidate>& candidates) const {
    std::erase_if(candidates, [this](const Candidate& c) { return stale(c); });
}

// The mesh made ready: unused vertices and faces with a repeated corner dropped, corner lists,
// quadrics, the terrain test, the spatial numbering, locked or weighted borders, the block grid.
// False if the mesh has a non-manifold edge (in stats: it is not simplified).
bool Simplifier::prepare(SimplifyStats& stats) {
    // Each kept face's number in the input, if drop_unused drops some (for messages).
    std::vector<std::uint32_t> input_face;
    if (count_repeated_corner_faces(mesh_) > 0) {
        for (std::uint32_t f = 0; f < face_.size(); ++f) {
            const Face& c = face_[f];
            if (c[0] != c[1] && c[1] != c[2] && c[0] != c[2]) input_face.push_back(f);
        }
    }
    std::vector<std::uint32_t> input_vertex;  // likewise for vertices
    drop_unused(mesh_, &input_vertex);
    stats.vertices_in = pos_.size();
    stats.faces_in = face_.size();
    threads_ = options_.threads > 0 ? options_.threads : omp_get_max_threads();
    if (face_.size() < options_.parallel_threshold) threads_ = 1;
    stats.threads = threads_;
    by_count_ = options_.stop.target != Target::max_error;
    if (options_.stop.target == Target::keep_fraction) {
        target_ = static_cast<std::uint64_t>(std::llround(options_.stop.value * static_cast<double>(face_.size())));
    } else if (options_.stop.target == Target::keep_faces) {
        target_ = static_cast<std::uint64_t>(std::max(0.0, options_.stop.value));
    }
    stats.target_faces = target_;
    build_topology();
    build_quadrics();
    if (non_manifold_) {
        NonManifoldEdge& edge = *non_manifold_;
        if (!input_vertex.empty()) edge.a = input_vertex[edge.a], edge.b = input_vertex[edge.b];
        if (!input_face.empty()) {
            for (std::uint32_t& f : edge.faces) f = input_face[f];
        }
        stats.non_manifold = std::move(non_manifold_);
        return false;
    }
    check_terrain();
    // (A terrain with its border kept searches for nothing: nothing to check after.)
    quick_ = options_.contacts == ContactCheck::at_the_end && (!terrain_ || !lock_);
    stats.contacts_checked_after = quick_;
    // The mesh as it came but for drop_unused (which finds nothing more to drop in it), before it
    // is renumbered: a second run from it is the same as from the input.
    if (quick_ && input_copy_ != nullptr) *input_copy_ = mesh_;
    spatial_order();
    if (terrain_ && options_.stop.target == Target::max_error && std::isfinite(options_.stop.value)) {
        vertical_ = std::make_unique<VerticalBound>(mesh_, options_.stop.value);
    }
    lock_ = options_.lock_boundary || vertical_;
    stats.terrain = terrain_;
    if (plan_overlap_) {
        stats.plan_overlap = plan_overlap_;
        if (!input_face.empty()) {
            for (std::uint32_t& f : *stats.plan_overlap) f = input_face[f];
        }
    }
    stats.vertical_bound = vertical_ != nullptr;
    if (vertical_) touch_.assign(pos_.size(), 0);
    add_border_planes();
    choose_grid();
    if (!terrain_ && !quick_) find_twins();
    use_index_ = !quick_ && (!terrain_ || !lock_);
    return true;
}

// The live vertices grouped by block at `level`, blocks in key order, each block's in id order
// (a counting sort over the level's blocks, numbered densely in key order: x, then y, then z),
// and for each block the candidate lists of the blocks of `finer` it is made of.
Simplifier::Level Simplifier::group_by_block(int level, Level& finer, std::vector<std::uint32_t>& live) const {
    Level next;
    next.level = level;
    const std::uint64_t last = grid_.block_of(Grid::pack(grid_.cells[0] - 1, grid_.cells[1] - 1, grid_.cells[2] - 1), level);
    std::size_t span[3];
    for (int axis = 0; axis < 3; ++axis) span[axis] = std::size_t{Grid::unpack(last, axis)} + 1;
    auto dense = [&](std::uint64_t cell) {
        const std::uint64_t key = grid_.block_of(cell, level);
        return (Grid::unpack(key, 0) * span[1] + Grid::unpack(key, 1)) * span[2] + Grid::unpack(key, 2);
    };
    std::erase_if(live, [this](std::uint32_t v) { return (flags_[v] & kDead) != 0; });
    std::vector<std::size_t> first(span[0] * span[1] * span[2] + 1, 0);
    for (const std::uint32_t v : live) ++first[dense(cell_[v]) + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    next.vertices.resize(first.back());
    for (std::size_t id = 0; id + 1 < first.size(); ++id) {
        if (first[id + 1] == first[id]) continue;
        const std::size_t z = id % span[2], y = id / span[2] % span[1], x = id / span[2] / span[1];
        next.blocks.push_back({Grid::pack(x, y, z), first[id], first[id + 1] - first[id], 0});
    }
    for (const std::uint32_t v : live) next.vertices[first[dense(cell_[v])]++] = v;
    // Each block of the level before lies in one block of this level.
    next.before.resize(next.blocks.size());
    for (std::size_t j = 0; j < finer.blocks.size(); ++j) {
        const std::uint64_t parent = BlockGrid::parent(finer.blocks[j].key);
        const auto it = std::lower_bound(next.blocks.begin(), next.blocks.end(), parent,
                                         [](const Block& block, std::uint64_t k) { return block.key < k; });
        if (it == next.blocks.end() || it->key != parent) continue;  // (no live vertex left there)
        next.before[static_cast<std::size_t>(it - next.blocks.begin())].push_back(&finer.candidates[j]);
    }
    next.candidates.resize(next.blocks.size());
    return next;
}

// Every block's candidates: at a level's first round gathered (block_candidates), later ones
// reopened.
void Simplifier::find_candidates(Level& level, int round) {
    const auto block_count = static_cast<std::int64_t>(level.blocks.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads_)
    for (std::int64_t i = 0; i < block_count; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const Block& block = level.blocks[k];
        if (round == 0) {
            level.candidates[k] = block_candidates(level.level, level.vertices.data() + block.first, block.count, block.key,
                                                   level.before[k]);
        } else {
            reopen(level.candidates[k]);
        }
    }
}

// The round's cost limit and each block's budget of faces to remove. With a count target below
// the last level, the limit is the cost of the k-th cheapest candidate of all blocks, k the
// collapses still needed, and each block gets a share of the faces still to go in proportion to
// its candidates under the limit: no block is pushed into dear collapses while cheap ones wait
// elsewhere. Otherwise no limit, and every block may remove all that is left.
double Simplifier::share_work(Level& level, std::uint64_t left, bool top) const {
    double limit = std::numeric_limits<double>::infinity();
    if (!by_count_ || top) {
        for (Block& block : level.blocks) block.budget = left;
        return limit;
    }
    const std::vector<std::vector<Candidate>>& candidates = level.candidates;
    std::size_t total = 0;
    for (const auto& list : candidates) total += list.size();
    const std::size_t needed = static_cast<std::size_t>((left + 1) / 2);  // a collapse removes ~2 faces
    std::vector<std::uint64_t> share(level.blocks.size(), 0);  // candidates at most the limit
    if (needed > 0 && needed < total) {
        const parallel::Selection kth =
            parallel::select_kth(candidates, needed, threads_, [](const Candidate& c) { return parallel::ordered_bits(c.cost); });
        limit = parallel::from_ordered_bits(kth.key);
        for (std::size_t k = 0; k < level.blocks.size(); ++k) share[k] = kth.less[k] + kth.equal[k];
    } else {
        for (std::size_t k = 0; k < level.blocks.size(); ++k) share[k] = candidates[k].size();
    }
    std::uint64_t under = 0;
    for (std::uint64_t n : share) under += n;
    for (std::size_t i = 0; i < level.blocks.size(); ++i) {
        level.blocks[i].budget = under == 0 ? 0
                                            : static_cast<std::uint64_t>(static_cast<long double>(left) * share[i] /
                                                                         static_cast<long double>(under));
    }
    return limit;
}

// Every block's round, in parallel; what they did summed into `stats`. The faces removed.
std::uint64_t Simplifier::collapse_blocks(Level& level, double limit, SimplifyStats& stats) {
    const auto block_count = static_cast<std::int64_t>(level.blocks.size());
    std::vector<BlockResult> results(level.blocks.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads_)
    for (std::int64_t i = 0; i < block_count; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const Block& block = level.blocks[k];
        results[k] = collapse_block(level.level, block.key, level.candidates[k], block.budget, limit);
    }
    std::uint64_t removed = 0;
    for (const BlockResult& r : results) {
        const SimplifyStats& s = r.stats;
        stats.collapses += s.collapses;
        stats.refused_link += s.refused_link;
        stats.refused_boundary += s.refused_boundary;
        stats.refused_flip += s.refused_flip;
        stats.refused_degenerate += s.refused_degenerate;
        stats.refused_intersection += s.refused_intersection;
        stats.refused_vertical += s.refused_vertical;
        stats.flat_unsearched += s.flat_unsearched;
        stats.max_error = std::max(stats.max_error, s.max_error);
        stats.predicates += s.predicates;
        removed += r.faces_removed;
    }
    return removed;
}

// UGSimp (dissertation chapter 4): levels of blocks, finest first; at each, rounds in which
// every block collapses its cheapest edges in parallel, while they make progress.
SimplifyStats Simplifier::run() {
    const auto start = Clock::now();
    SimplifyStats stats;
    if (!prepare(stats)) return stats;
    stats.seconds_setup = std::chrono::duration<double>(Clock::now() - start).count();
    const auto sweep = Clock::now();

    auto target_met = [&] { return by_count_ && live_faces_ <= target_; };
    std::vector<std::uint32_t> live(pos_.size());  // the live vertices, in id order
    std::iota(live.begin(), live.end(), 0u);
    Level blocks;  // the current level's blocks, then the level before's (candidates handed down)
    const int top = grid_.levels.top_level();
    for (int level = 0; level <= top && !target_met(); ++level) {
        ++stats.levels;
        // After a level's collapses a vertex's corners lie far apart (a merge appends the other
        // end's): walking them would miss the cache at every step. (Measured: compacting at every
        // round, not only every level, saves nothing more.)
        if (level > 0) compact_faces();
        Level finer = std::move(blocks);
        blocks = group_by_block(level, finer, live);
        for (int round = 0; round < 3 && !target_met(); ++round) {
            // The index and its start-of-round boxes are what FaceIndex::query() relies on: faces
            // a block moved in an earlier round must be indexed where they are now.
            build_face_index();
            find_candidates(blocks, round);
            const std::uint64_t left = by_count_ ? live_faces_ - target_ : std::numeric_limits<std::uint64_t>::max();
            const double limit = share_work(blocks, left, level == top);
            const std::uint64_t removed = collapse_blocks(blocks, limit, stats);
            live_faces_ -= removed;
            ++stats.rounds;
            stop_if_cancelled(options_.cancel);
            if (options_.progress) {
                const double work = by_count_ ? static_cast<double>(stats.faces_in - std::min(target_, stats.faces_in)) : top + 1.0;
                const double done = by_count_ ? static_cast<double>(stats.faces_in - live_faces_) : level + 1.0;
                options_.progress(work > 0 ? std::min(1.0, done / work) : 1.0);
            }
            // Unlimited rounds do all they can at once; limited ones stop when they stall.
            if (!std::isfinite(limit) || removed * 8 < left) break;
        }
    }
    stats.target_reached = !by_count_ || live_faces_ <= target_;

    // Compact: surviving faces and vertices in input order (checked first, with quick_, while
    // clean_ still tells the faces collapses made).
    drop_dead_faces(nullptr);
    if (quick_) {
        if (options_.phase) options_.phase("checking the result for contacts");
        const auto check = Clock::now();
        stats.contact_near = result_contact(stats.predicates);
        stats.seconds_check = std::chrono::duration<double>(Clock::now() - check).count();
        if (options_.progress) options_.progress(1.0);
    }
    input_order();
    drop_unused(mesh_);

    stats.vertices_out = pos_.size();
    stats.faces_out = face_.size();
    stats.seconds_collapse = std::chrono::duration<double>(Clock::now() - sweep).count();
    return stats;
}

std::optional<Point3> Simplifier::result_contact(exact::PredicateStats& predicates) const {
    // The faces collapses made (clean_ not kUnknown, which is 0): only pairs with one of them can
    // be new.
    static_assert(kUnknown == 0);
    const std::span<const std::uint8_t> made = clean_;
    auto near = [&](const SelfContact& found) -> std::optional<Point3> {
        if (!found.first) return std::nullopt;
        return pos_[face_[(*found.first)[0]][0]];
    };
    if (!terrain_) return near(find_self_contact(mesh_, threads_, predicates, made));
    // A terrain: its faces all still turn its way in the map plane (every collapse kept them so,
    // and none made a face without area there). If the border is simple loops that wind right
    // (covers_once_by_border), they cover each point of the plane at most once and meet only
    // along shared edges and corners: a planar triangulation, which the heights cannot make
    // cross itself. Otherwise the faces flattened to the plane are tested pair by pair, as a
    // collapse moving the border tests them (search_contacts with `flatten`).
    if (covers_once_by_border(mesh_, terrain_turn_, border_edges(mesh_, threads_))) return std::nullopt;
    Mesh flat{pos_, face_};
    for (Point3& p : flat.points) p.z = 0;
    return near(find_self_contact(flat, threads_, predicates, made));
}

}  // namespace detail

SimplifyStats simplify(Mesh& mesh, const SimplifyOptions& options) {
    // The readers promise these; a library caller may not: refuse rather than read out of range.
    const std::size_t n = mesh.points.size();
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        for (const std::uint32_t v : mesh.faces[f]) {
            if (v >= n) {
                throw std::invalid_argument("mesh::simplify: face " + std::to_string(f) + " has corner " + std::to_string(v) +
                                            ", beyond the " + std::to_string(n) + " vertices");
            }
        }
    }
    auto check = [](const Attributes& attributes, std::size_t rows, const char* what) {
        if (attributes.values.size() != rows * attributes.width) {
            throw std::invalid_argument(std::string("mesh::simplify: ") + what + " attributes hold " +
                                        std::to_string(attributes.values.size()) + " values, not " + std::to_string(rows) +
                                        " rows of " + std::to_string(attributes.width));
        }
    };
    check(mesh.vertex_attributes, n, "vertex");
    check(mesh.face_attributes, mesh.faces.size(), "face");
    if (options.contacts == ContactCheck::every_collapse) return detail::Simplifier(mesh, options).run();

    // Collapses without a contact search, the result checked (Simplifier::run); if it meets
    // itself, the input (kept) simplified again with every collapse checked.
    const auto start = detail::Clock::now();
    Mesh input;
    SimplifyStats stats = detail::Simplifier(mesh, options, &input).run();
    if (!stats.contact_near) return stats;
    stop_if_cancelled(options.cancel);
    if (options.phase) options.phase("simplifying again, every collapse checked");
    const double first_run = std::chrono::duration<double>(detail::Clock::now() - start).count();
    mesh = std::move(input);
    SimplifyOptions careful = options;
    careful.contacts = ContactCheck::every_collapse;
    SimplifyStats again = detail::Simplifier(mesh, careful).run();
    again.contacts_checked_after = true;
    again.simplified_again = true;
    again.contact_near = stats.contact_near;
    again.seconds_first_run = first_run;
    again.seconds_check = stats.seconds_check;
    again.predicates += stats.predicates;  // (all the exact tests made)
    return again;
}

}  // namespace toposimp::mesh
