#include "core/map/crossings.hpp"

#include "core/exact/segments.hpp"
#include "core/fill_later.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace toposimp::map {
namespace {

Box segment_box(Point a, Point b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
}

// Cell index along one axis: monotone in the coordinate, so a box's cells are those between
// its corners' cells whatever the rounding.
struct Axis {
    double origin = 0, scale = 0;
    std::uint32_t count = 1;

    std::uint32_t operator()(double value) const {
        double t = (value - origin) * scale;
        if (!(t >= 0.0)) t = 0.0;
        if (t >= static_cast<double>(count)) return count - 1;
        return static_cast<std::uint32_t>(t);
    }
};

// Calls visit(v) for each segment (named by its first vertex v) whose first vertex lies in
// [begin, end), chain by chain.
template <class Visit>
void for_each_segment(const MapData& map, std::uint32_t begin, std::uint32_t end, Visit&& visit) {
    auto chain = std::partition_point(map.chains.begin(), map.chains.end(), [&](const Chain& c) { return c.last < begin; });
    for (; chain != map.chains.end() && chain->first < end; ++chain) {
        for (std::uint32_t v = std::max(chain->first, begin); v < std::min(chain->last, end); ++v) visit(v);
    }
}

}  // namespace

// A uniform grid over the segments' boxes, one row of cells at a time: the segments are first
// distributed to the rows their boxes span (a parallel counting sort), then each row, on its
// own, to its cells, where the pairs are tested. A pair is tested only in the cell holding the
// low corner of its boxes' overlap, so once.
std::vector<SegmentContact> find_segment_contacts(const MapData& map, exact::Arithmetic arithmetic,
                                                  exact::PredicateStats& stats, int threads_wanted) {
    std::vector<SegmentContact> contacts;
    const auto vertex_count = static_cast<std::uint32_t>(map.vertices.size());
    std::size_t segment_count = 0;
    for (const Chain& chain : map.chains) segment_count += chain.last - chain.first;
    if (segment_count < 2) return contacts;
    const bool parallel = segment_count >= (1u << 14);
    const int threads = !parallel ? 1 : threads_wanted > 0 ? threads_wanted : omp_get_max_threads();
    const auto share = static_cast<std::size_t>(threads);

    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
#pragma omp parallel for reduction(min : min_x, min_y) reduction(max : max_x, max_y) schedule(static) num_threads(threads)
    for (std::uint32_t v = 0; v < vertex_count; ++v) {
        const Point p = map.vertices[v];
        min_x = std::min(min_x, p.x);
        min_y = std::min(min_y, p.y);
        max_x = std::max(max_x, p.x);
        max_y = std::max(max_y, p.y);
    }
    const auto side = static_cast<std::uint32_t>(std::clamp(std::floor(std::sqrt(static_cast<double>(segment_count) / 2.0)), 1.0, 4096.0));
    const double width = max_x - min_x, height = max_y - min_y;
    const Axis column{min_x, width > 0 ? side / width : 0.0, side}, row{min_y, height > 0 ? side / height : 0.0, side};
    auto box_of = [&](std::uint32_t v) { return segment_box(map.vertices[v], map.vertices[v + 1]); };
    auto vertices_of = [&](int t) {
        return std::pair{static_cast<std::uint32_t>(std::uint64_t{vertex_count} * static_cast<std::size_t>(t) / share),
                         static_cast<std::uint32_t>(std::uint64_t{vertex_count} * static_cast<std::size_t>(t + 1) / share)};
    };

    // Segments into the rows they span: row_start[row · threads + thread] is where that
    // thread's entries of that row begin.
    std::vector<std::size_t> row_start(std::size_t{side} * share + 1, 0);
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num();
        const auto [begin, end] = vertices_of(t);
        std::vector<std::size_t> count(side, 0);
        for_each_segment(map, begin, end, [&](std::uint32_t v) {
            const Box box = box_of(v);
            for (std::uint32_t y = row(box.min_y), last = row(box.max_y); y <= last; ++y) ++count[y];
        });
        for (std::uint32_t y = 0; y < side; ++y) row_start[std::size_t{y} * share + static_cast<std::size_t>(t) + 1] = count[y];
    }
    for (std::size_t k = 1; k < row_start.size(); ++k) row_start[k] += row_start[k - 1];
    FillLater<std::uint32_t> in_rows(row_start.back());
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num();
        const auto [begin, end] = vertices_of(t);
        std::vector<std::size_t> fill(side);
        for (std::uint32_t y = 0; y < side; ++y) fill[y] = row_start[std::size_t{y} * share + static_cast<std::size_t>(t)];
        for_each_segment(map, begin, end, [&](std::uint32_t v) {
            const Box box = box_of(v);
            for (std::uint32_t y = row(box.min_y), last = row(box.max_y); y <= last; ++y) in_rows[fill[y]++] = v;
        });
    }

#pragma omp parallel num_threads(threads)
    {
        std::vector<SegmentContact> found;
        exact::PredicateStats counted;
        std::vector<std::uint32_t> cell_start(std::size_t{side} + 1);
        std::vector<std::pair<Box, std::uint32_t>> cells;  // the row's segments, cell after cell
#pragma omp for schedule(dynamic, 8) nowait
        for (std::uint32_t y = 0; y < side; ++y) {
            const std::size_t begin = row_start[std::size_t{y} * share], end = row_start[std::size_t{y + 1} * share];
            if (end - begin < 2) continue;
            std::fill(cell_start.begin(), cell_start.end(), 0);
            for (std::size_t k = begin; k < end; ++k) {
                const Box box = box_of(in_rows[k]);
                for (std::uint32_t x = column(box.min_x), last = column(box.max_x); x <= last; ++x) ++cell_start[x + 1];
            }
            for (std::uint32_t x = 0; x < side; ++x) cell_start[x + 1] += cell_start[x];
            cells.resize(cell_start[side]);
            {
                std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
                for (std::size_t k = begin; k < end; ++k) {
                    const Box box = box_of(in_rows[k]);
                    for (std::uint32_t x = column(box.min_x), last = column(box.max_x); x <= last; ++x) {
                        cells[fill[x]++] = {box, in_rows[k]};
                    }
                }
            }
            for (std::uint32_t x = 0; x < side; ++x) {
                const auto first = cells.begin() + cell_start[x], last = cells.begin() + cell_start[x + 1];
                if (last - first < 2) continue;
                // By left edge: only boxes starting before one ends can overlap it in x.
                std::sort(first, last, [](const auto& a, const auto& b) {
                    return a.first.min_x < b.first.min_x || (a.first.min_x == b.first.min_x && a.second < b.second);
                });
                for (auto i = first; i != last; ++i) {
                    const auto& [sb, s] = *i;
                    for (auto j = i + 1; j != last && j->first.min_x <= sb.max_x; ++j) {
                        const auto& [tb, t] = *j;
                        const double low_x = std::max(sb.min_x, tb.min_x), low_y = std::max(sb.min_y, tb.min_y);
                        if (low_x > std::min(sb.max_x, tb.max_x) || low_y > std::min(sb.max_y, tb.max_y)) continue;
                        if (column(low_x) != x || row(low_y) != y) continue;  // tested in another cell
                        const Point p = map.vertices[s], q = map.vertices[s + 1], r = map.vertices[t], u = map.vertices[t + 1];
                        if (!exact::improper_contact(p, q, r, u, arithmetic, counted)) continue;
                        ContactKind kind = ContactKind::touching;
                        if ((same_location(p, r) && same_location(q, u)) || (same_location(p, u) && same_location(q, r))) {
                            kind = ContactKind::identical;
                        } else if (exact::proper_crossing(p, q, r, u, arithmetic, counted)) {
                            kind = ContactKind::crossing;
                        }
                        found.push_back({std::min(s, t), std::max(s, t), kind});
                    }
                }
            }
        }
#pragma omp critical(toposimp_segment_contacts)
        {
            contacts.insert(contacts.end(), found.begin(), found.end());
            stats += counted;
        }
    }
    // Sorted, so the result does not depend on which thread found what.
    std::sort(contacts.begin(), contacts.end(), [](const SegmentContact& a, const SegmentContact& b) {
        return a.s < b.s || (a.s == b.s && a.t < b.t);
    });
    return contacts;
}

std::vector<std::uint8_t> find_improper_segments(const MapData& map, exact::Arithmetic arithmetic,
                                                 exact::PredicateStats& stats, int threads) {
    std::vector<std::uint8_t> improper(map.vertices.size(), 0);
    for (const SegmentContact& contact : find_segment_contacts(map, arithmetic, stats, threads)) {
        improper[contact.s] = improper[contact.t] = 1;
    }
    return improper;
}

}  // namespace toposimp::map
