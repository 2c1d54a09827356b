#include "core/map/crossings.hpp"

#include "core/exact/segments.hpp"
#include "core/fill_later.hpp"
#include "core/map/location_key.hpp"
#include "core/map/segment_cells.hpp"
#include "core/parallel/shares.hpp"

#include "core/cancel.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace toposimp::map {
namespace {

// A segment's ends in the fixed order of `before`.
std::pair<Point, Point> ends_of(const MapData& map, std::uint32_t v) {
    const Point a = map.vertices[v], b = map.vertices[v + 1];
    return before(b, a) ? std::pair{b, a} : std::pair{a, b};
}

// Calls visit(v) for each segment (named by its first vertex v) whose first vertex lies in
// [begin, end), chain by chain.
template <class Visit>
void for_each_segment(const MapData& map, std::uint32_t begin, std::uint32_t end, Visit&& visit) {
    auto chain = std::partition_point(map.chains.begin(), map.chains.end(), [&](const Chain& c) { return c.last < begin; });
    for (; chain != map.chains.end() && chain->first < end; ++chain) {
        for (std::uint32_t v = std::max(chain->first, begin); v < std::min(chain->last, end); ++v) visit(v);
    }
}

// A segment in a cell: its part in the row, the segment, and a hash of its ends (in either
// direction), so that copies of a segment sort together without looking its ends up.
struct Entry {
    Box part;
    std::uint32_t segment;
    std::uint32_t ends;
};
// One row's segments, cell after cell, a cell's entries sorted by left edge.
using CellEntries = std::vector<Entry>;

std::uint32_t ends_hash(const MapData& map, std::uint32_t v) {
    const auto [p, q] = ends_of(map, v);
    const std::size_t h = hash_words({LocationKey(p).x, LocationKey(p).y, LocationKey(q).x, LocationKey(q).y});
    return static_cast<std::uint32_t>(h ^ (h >> 32));
}

// How many times to split the rows of the square grid (`square`), joining as many columns, for
// the search: vertices crowded along lines fill few cells of it (GSHHG's shores, 91 a filled
// cell) and thin rows then pair far fewer segments in a cell; spread ones (Natural Earth's
// borders, 15) lose more to the wider cells, and segments as tall as a row or more are entered
// in more rows. ⌊log2(crowding / 11)⌋ in [0, 3] (the fastest of 0–5 on both; issue 34), less
// while the segments' mean height in the split rows would pass one row. The contacts found do
// not depend on it.
//
// Both are estimated from every 8th vertex of each chain (counting all costs a tenth of the
// search): if the vertices of a filled cell were a Poisson count of mean λ, the sample fills a
// cell with mean μ = λ/8 and holds μ / (1 − e^−μ) a cell it fills, which is solved for μ.
unsigned row_split(const MapData& map, const Grid& square, int threads) {
    constexpr std::uint32_t kStride = 8;
    if (!(square.row.scale > 0)) return 0;  // one row for all (a flat map): splitting it gains nothing
    const std::size_t cells = std::size_t{square.column.count} * square.row.count, words = (cells + 63) / 64;
    const auto chains = static_cast<std::int64_t>(map.chains.size());
    std::vector<std::uint64_t> filled(words, 0);
    std::uint64_t samples = 0, height = 0;  // height: the sampled segments' heights in rows, in 1/1024 (at most 4 rows each)
#pragma omp parallel num_threads(threads) reduction(+ : samples, height)
    {
        std::vector<std::uint64_t> mine(words, 0);
#pragma omp for schedule(dynamic, 256) nowait
        for (std::int64_t c = 0; c < chains; ++c) {
            const Chain& chain = map.chains[static_cast<std::size_t>(c)];
            for (std::uint32_t v = chain.first; v < chain.last; v += kStride) {
                const Point p = map.vertices[v], q = map.vertices[v + 1];
                const std::size_t cell = std::size_t{square.row(p.y)} * square.column.count + square.column(p.x);
                mine[cell / 64] |= std::uint64_t{1} << (cell % 64);
                const double rows = std::fabs(q.y - p.y) * square.row.scale;
                height += static_cast<std::uint64_t>(1024.0 * (rows < 4.0 ? rows : 4.0));  // (NaN: 4)
                ++samples;
            }
        }
#pragma omp critical(toposimp_segment_cells_filled)
        for (std::size_t w = 0; w < words; ++w) filled[w] |= mine[w];
    }
    if (samples == 0) return 0;
    std::size_t count = 0;
    for (const std::uint64_t word : filled) count += static_cast<std::size_t>(std::popcount(word));
    const double per_cell = static_cast<double>(samples) / static_cast<double>(count);  // ≥ 1
    double low = 0, high = per_cell;  // μ / (1 − e^−μ) rises from 1 at 0 and is below μ + 1
    for (int step = 0; step < 50; ++step) {
        const double mu = 0.5 * (low + high);
        (mu / -std::expm1(-mu) < per_cell ? low : high) = mu;
    }
    const double crowding = kStride * 0.5 * (low + high);
    const double mean_height = static_cast<double>(height) / 1024.0 / static_cast<double>(samples);
    unsigned split = 0;
    while (split < 3 && crowding >= 11.0 * static_cast<double>(2u << split) && mean_height * static_cast<double>(2u << split) <= 1.0) ++split;
    return split;
}

struct SearchGrid {
    Grid grid;
    std::uint32_t columns, rows;
    unsigned split;
};

// The search's grid: about segments / 2 cells over the map's extent, square but for row_split.
SearchGrid search_grid(const MapData& map, std::size_t segment_count, int threads) {
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
    const std::size_t vertex_count = map.vertices.size();
#pragma omp parallel for reduction(min : min_x, min_y) reduction(max : max_x, max_y) schedule(static) num_threads(threads)
    for (std::size_t v = 0; v < vertex_count; ++v) {
        const Point p = map.vertices[v];
        min_x = std::min(min_x, p.x);
        min_y = std::min(min_y, p.y);
        max_x = std::max(max_x, p.x);
        max_y = std::max(max_y, p.y);
    }
    const auto side = static_cast<std::uint32_t>(std::clamp(std::floor(std::sqrt(static_cast<double>(segment_count) / 2.0)), 1.0, 4096.0));
    const Box extent{min_x, min_y, max_x, max_y};
    const unsigned split = row_split(map, make_grid(extent, side), threads);
    const std::uint32_t rows = side << split, columns = std::max(1u, side >> split);
    return {make_grid(extent, columns, rows), columns, rows, split};
}

// A uniform grid over the map (see Grid), one row of cells at a time: the segments are first
// distributed to the rows their boxes span (a parallel counting sort), then each row, on its
// own, to the cells of their parts in it. Calls visit(worker, first, last, x, y, grid) for each
// cell of two or more segments, its entries sorted by left edge, on the thread that owns
// `worker` (one Worker per thread, made by make_worker(), handed to finish(worker) at the end,
// one thread at a time). Two segments that meet are both in the cell where they meet; a
// visitor that wants each pair once checks first_shared_cell.
// Once `cancel` is set, the rows left are passed over (the caller then stops).
template <class MakeWorker, class Visit, class Finish>
void for_each_cell(const MapData& map, int threads_wanted, MakeWorker make_worker, Visit visit, Finish finish,
                   const std::atomic<bool>* cancel = nullptr) {
    const auto vertex_count = static_cast<std::uint32_t>(map.vertices.size());
    std::size_t segment_count = 0;
    for (const Chain& chain : map.chains) segment_count += chain.last - chain.first;
    if (segment_count < 2) return;
    const bool parallel = segment_count >= (1u << 14);
    const int threads = !parallel ? 1 : threads_wanted > 0 ? threads_wanted : omp_get_max_threads();
    const auto share = static_cast<std::size_t>(threads);

    const SearchGrid search = search_grid(map, segment_count, threads);
    const Grid& grid = search.grid;
    const std::uint32_t rows = search.rows, columns = search.columns;
    const Axis& row = grid.row;
    const Axis& column = grid.column;
    auto box_of = [&](std::uint32_t v) { return segment_box(map.vertices[v], map.vertices[v + 1]); };
    auto part_of = [&](std::uint32_t v, std::uint32_t y) { return grid.part_in_row(map.vertices[v], map.vertices[v + 1], y); };
    auto vertices_of = [&](int t) {
        return std::pair{static_cast<std::uint32_t>(std::uint64_t{vertex_count} * static_cast<std::size_t>(t) / share),
                         static_cast<std::uint32_t>(std::uint64_t{vertex_count} * static_cast<std::size_t>(t + 1) / share)};
    };

    // Segments into the rows they span: row_start[row · threads + thread] is where that
    // thread's entries of that row begin.
    std::vector<std::size_t> row_start(std::size_t{rows} * share + 1, 0);
#pragma omp parallel num_threads(threads)
    parallel::for_my_shares(threads, [&](int t) {
        const auto [begin, end] = vertices_of(t);
        std::vector<std::size_t> count(rows, 0);
        for_each_segment(map, begin, end, [&](std::uint32_t v) {
            const Box box = box_of(v);
            for (std::uint32_t y = row(box.min_y), last = row(box.max_y); y <= last; ++y) ++count[y];
        });
        for (std::uint32_t y = 0; y < rows; ++y) row_start[std::size_t{y} * share + static_cast<std::size_t>(t) + 1] = count[y];
    });
    for (std::size_t k = 1; k < row_start.size(); ++k) row_start[k] += row_start[k - 1];
    FillLater<std::uint32_t> in_rows(row_start.back());
#pragma omp parallel num_threads(threads)
    parallel::for_my_shares(threads, [&](int t) {
        const auto [begin, end] = vertices_of(t);
        std::vector<std::size_t> fill(rows);
        for (std::uint32_t y = 0; y < rows; ++y) fill[y] = row_start[std::size_t{y} * share + static_cast<std::size_t>(t)];
        for_each_segment(map, begin, end, [&](std::uint32_t v) {
            const Box box = box_of(v);
            for (std::uint32_t y = row(box.min_y), last = row(box.max_y); y <= last; ++y) in_rows[fill[y]++] = v;
        });
    });

#pragma omp parallel num_threads(threads)
    {
        auto worker = make_worker();
        std::vector<std::uint32_t> cell_start(std::size_t{columns} + 1);
        CellEntries cells;  // the row's segments, cell after cell
#pragma omp for schedule(dynamic, 8) nowait
        for (std::uint32_t y = 0; y < rows; ++y) {
            const std::size_t begin = row_start[std::size_t{y} * share], end = row_start[std::size_t{y + 1} * share];
            if (end - begin < 2 || cancel_requested(cancel)) continue;
            std::fill(cell_start.begin(), cell_start.end(), 0);
            for (std::size_t k = begin; k < end; ++k) {
                const Box part = part_of(in_rows[k], y);
                for (std::uint32_t x = column(part.min_x), last = column(part.max_x); x <= last; ++x) ++cell_start[x + 1];
            }
            for (std::uint32_t x = 0; x < columns; ++x) cell_start[x + 1] += cell_start[x];
            cells.resize(cell_start[columns]);
            {
                std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
                for (std::size_t k = begin; k < end; ++k) {
                    const Box part = part_of(in_rows[k], y);
                    const std::uint32_t ends = ends_hash(map, in_rows[k]);
                    for (std::uint32_t x = column(part.min_x), last = column(part.max_x); x <= last; ++x) {
                        cells[fill[x]++] = {part, in_rows[k], ends};
                    }
                }
            }
            for (std::uint32_t x = 0; x < columns; ++x) {
                const auto first = cells.begin() + cell_start[x], last = cells.begin() + cell_start[x + 1];
                if (last - first < 2) continue;
                // By left edge: only boxes starting before one ends can overlap it in x. Then
                // by the hash of the ends, so copies of a segment (the same part, the same
                // ends) come together unless two hashes collide.
                std::sort(first, last, [](const Entry& a, const Entry& b) {
                    if (a.part.min_x != b.part.min_x) return a.part.min_x < b.part.min_x;
                    return a.ends != b.ends ? a.ends < b.ends : a.segment < b.segment;
                });
                visit(worker, first, last, x, y, grid);
            }
        }
#pragma omp critical(toposimp_segment_contacts)
        finish(worker);
    }
}

// Segments s and t one after the other in a chain (the second starts at the first's end vertex),
// with three distinct locations p, q, u not on one line: two segments sharing the end q and not
// collinear meet in q alone, an end of both. For the pair a cell holds most often, a comparison
// of coordinates or one orientation instead of improper_contact's several (issue 34). Anything
// else: false, and the full test decides.
bool only_their_shared_end(const MapData& map, std::uint32_t s, std::uint32_t t, exact::Arithmetic arithmetic,
                           exact::PredicateStats& stats) {
    if (t + 1 == s) std::swap(s, t);
    if (s + 1 != t) return false;  // (t a segment starting at s's end vertex: the same chain)
    const Point p = map.vertices[s], q = map.vertices[t], u = map.vertices[t + 1];
    // Strictly monotone through q in x (or y): p–q has x = q.x only at q, and so has q–u, so q
    // is all they share (most steps of a shoreline: 9.4 M of GSHHG's 13 M orientations went).
    if ((p.x < q.x && q.x < u.x) || (p.x > q.x && q.x > u.x) || (p.y < q.y && q.y < u.y) || (p.y > q.y && q.y > u.y)) return true;
    if (same_location(p, q) || same_location(q, u) || same_location(p, u)) return false;
    return exact::orientation(p, q, u, arithmetic, stats) != 0;
}

bool overlap(const Box& a, const Box& b) {
    return a.min_x <= b.max_x && b.min_x <= a.max_x && a.min_y <= b.max_y && b.min_y <= a.max_y;
}

// Is cell (x, y) the first the two segments share: the low column of their parts' overlap in
// row y, and their parts in row y − 1 apart (or one of them not yet there)? Each pair meets
// this in the first row where their parts overlap, so it is tested at least once; should the
// rows where the parts overlap have a gap (rounding), it is tested again later, and the
// caller drops the repeat.
bool first_shared_cell(const MapData& map, std::uint32_t s, const Box& sb, std::uint32_t t, const Box& tb, std::uint32_t x,
                       std::uint32_t y, const Grid& grid) {
    if (!overlap(sb, tb) || grid.column(std::max(sb.min_x, tb.min_x)) != x) return false;
    if (y == 0) return true;
    const Point p = map.vertices[s], q = map.vertices[s + 1], r = map.vertices[t], u = map.vertices[t + 1];
    if (grid.row(std::min(p.y, q.y)) == y || grid.row(std::min(r.y, u.y)) == y) return true;
    return !overlap(grid.part_in_row(p, q, y - 1), grid.part_in_row(r, u, y - 1));
}

}  // namespace

std::vector<SegmentContact> find_segment_contacts(const MapData& map, exact::Arithmetic arithmetic,
                                                  exact::PredicateStats& stats, int threads_wanted,
                                                  std::span<const std::uint32_t> line_of) {
    std::vector<SegmentContact> contacts;
    struct Worker {
        std::vector<SegmentContact> found;
        exact::PredicateStats counted;
    };
    for_each_cell(
        map, threads_wanted, [] { return Worker{}; },
        [&](Worker& worker, CellEntries::iterator first, CellEntries::iterator last, std::uint32_t x, std::uint32_t y,
            const Grid& grid) {
            for (auto i = first; i != last; ++i) {
                const auto& [sb, s, s_ends] = *i;
                for (auto j = i + 1; j != last && j->part.min_x <= sb.max_x; ++j) {
                    const auto& [tb, t, t_ends] = *j;
                    if (!line_of.empty() && line_of[s] != kNoLine && line_of[s] == line_of[t]) continue;
                    if (!first_shared_cell(map, s, sb, t, tb, x, y, grid)) continue;  // (tested in another cell)
                    const Point p = map.vertices[s], q = map.vertices[s + 1], r = map.vertices[t], u = map.vertices[t + 1];
                    if (!exact::improper_contact(p, q, r, u, arithmetic, worker.counted)) continue;
                    ContactKind kind = ContactKind::touching;
                    if ((same_location(p, r) && same_location(q, u)) || (same_location(p, u) && same_location(q, r))) {
                        kind = ContactKind::identical;
                    } else if (exact::proper_crossing(p, q, r, u, arithmetic, worker.counted)) {
                        kind = ContactKind::crossing;
                    }
                    worker.found.push_back({std::min(s, t), std::max(s, t), kind});
                }
            }
        },
        [&](Worker& worker) {
            contacts.insert(contacts.end(), worker.found.begin(), worker.found.end());
            stats += worker.counted;
        });
    // Sorted, so the result does not depend on which thread found what; a pair tested twice
    // (see first_shared_cell) once.
    std::sort(contacts.begin(), contacts.end(), [](const SegmentContact& a, const SegmentContact& b) {
        return a.s < b.s || (a.s == b.s && a.t < b.t);
    });
    contacts.erase(std::unique(contacts.begin(), contacts.end(),
                               [](const SegmentContact& a, const SegmentContact& b) { return a.s == b.s && a.t == b.t; }),
                   contacts.end());
    return contacts;
}

// Only whether each segment has a contact, not every contact: a line running back and forth over
// one stretch (a GPS track repeating a route) has contacts between nearly every pair of its
// segments, which the contact list held by the billion (issue 29: 100 000 vertices, 7 GB in
// 60 s and no end). In a cell, a pair of segments both already found improper there is not
// tested again, and the segments found improper are skipped over at once (a list of the next
// one not found, compressed as it is walked): a cell whose segments all meet one of them costs
// a pass, not the square. Copies of one segment (the same ends, either way) stand in a cell as
// one: they meet each other, unless a point, and what meets one meets all — a route driven
// 25 000 times is a few segments, not 25 000 copies each tested against the next stretch's
// copies. Each cell settles its segments on its own (a pair is tested in every cell both parts
// reach), so the predicates counted, like the result, do not depend on the threads.
std::vector<std::uint8_t> find_improper_segments(const MapData& map, exact::Arithmetic arithmetic,
                                                 exact::PredicateStats& stats, int threads, const std::atomic<bool>* cancel) {
    std::vector<std::uint8_t> improper(map.vertices.size(), 0);
    struct Worker {
        std::vector<std::uint32_t> found;  // segments found improper (with repeats across cells)
        exact::PredicateStats counted;
        CellEntries distinct;               // the cell's entries, copies of a segment once
        std::vector<std::uint32_t> copies;  // per distinct entry, where its copies begin among the entries (and the end)
        std::vector<std::uint8_t> here;     // per distinct entry: found improper in this cell
        std::vector<std::uint32_t> next;    // per entry found: a later entry, no later than the next one not found
    };
    for_each_cell(
        map, threads, [] { return Worker{}; },
        [&](Worker& worker, CellEntries::iterator entries, CellEntries::iterator entries_end, std::uint32_t, std::uint32_t,
            const Grid&) {
            worker.distinct.clear();
            worker.copies.clear();
            for (auto k = entries; k != entries_end;) {
                auto end = k + 1;
                if (end != entries_end && end->ends == k->ends) {
                    const auto [p, q] = ends_of(map, k->segment);
                    for (; end != entries_end && end->ends == k->ends; ++end) {
                        const auto [r, u] = ends_of(map, end->segment);
                        if (!same_location(p, r) || !same_location(q, u)) break;
                    }
                }
                worker.distinct.push_back(*k);
                worker.copies.push_back(static_cast<std::uint32_t>(k - entries));
                k = end;
            }
            worker.copies.push_back(static_cast<std::uint32_t>(entries_end - entries));
            const auto first = worker.distinct.begin();
            const auto count = static_cast<std::uint32_t>(worker.distinct.size());
            worker.here.assign(count, 0);
            for (std::uint32_t d = 0; d < count; ++d) {
                const std::uint32_t s = first[d].segment;
                if (worker.copies[d + 1] - worker.copies[d] > 1 && !same_location(map.vertices[s], map.vertices[s + 1])) worker.here[d] = 1;
            }
            worker.next.resize(std::size_t{count} + 1);
            for (std::uint32_t k = 0; k <= count; ++k) worker.next[k] = k;
            // The first entry at or after k not found improper yet; every entry passed on the
            // way then points there (path compression: each is passed over about once).
            auto open = [&worker, count](std::uint32_t k) {
                std::uint32_t at = k;
                while (at < count && worker.here[at]) at = worker.next[at] == at ? at + 1 : worker.next[at];
                while (k < count && worker.here[k] && k != at) {
                    const std::uint32_t step = worker.next[k] == k ? k + 1 : worker.next[k];
                    worker.next[k] = at;
                    k = step;
                }
                return at;
            };
            auto test = [&](std::uint32_t i, std::uint32_t j) {
                const auto& [sb, s, s_ends] = first[i];
                const auto& [tb, t, t_ends] = first[j];
                // Every cell the two share tests them (not only the one of their overlap's low
                // corner): a cell then settles its own segments, whatever the others do.
                if ((sb.min_y > tb.max_y) | (tb.min_y > sb.max_y) | (tb.min_x > sb.max_x)) return;  // (one branch, not three)
                if (only_their_shared_end(map, s, t, arithmetic, worker.counted)) return;
                if (exact::improper_contact(map.vertices[s], map.vertices[s + 1], map.vertices[t], map.vertices[t + 1], arithmetic,
                                            worker.counted)) {
                    worker.here[i] = worker.here[j] = 1;
                }
            };
            for (std::uint32_t i = 0; i < count; ++i) {
                const double reach = first[i].part.max_x;
                if (!worker.here[i]) {
                    for (std::uint32_t j = i + 1; j < count && first[j].part.min_x <= reach; ++j) test(i, j);
                } else {
                    for (std::uint32_t j = open(i + 1); j < count && first[j].part.min_x <= reach; j = open(j + 1)) test(i, j);
                }
            }
            for (std::uint32_t d = 0; d < count; ++d) {
                if (!worker.here[d]) continue;
                for (std::uint32_t k = worker.copies[d]; k < worker.copies[d + 1]; ++k) worker.found.push_back(entries[k].segment);
            }
        },
        [&](Worker& worker) {
            for (const std::uint32_t segment : worker.found) improper[segment] = 1;
            stats += worker.counted;
        },
        cancel);
    return improper;
}

unsigned search_row_split(const MapData& map) {
    std::size_t segment_count = 0;
    for (const Chain& chain : map.chains) segment_count += chain.last - chain.first;
    return search_grid(map, segment_count, 1).split;
}

}  // namespace toposimp::map
