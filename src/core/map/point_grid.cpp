#include "core/map/point_grid.hpp"

#include "core/cancel.hpp"
#include "core/parallel/shares.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <omp.h>

namespace toposimp::map {

PointGrid::Geometry PointGrid::Geometry::plan(double min_x, double min_y, double max_x, double max_y, std::size_t n,
                                              double points_per_cell, unsigned row_split) {
    Geometry g;
    const double width = max_x - min_x;
    const double height = max_y - min_y;
    // Square-ish cells, total count ≈ n / points_per_cell, each side capped to keep indices small.
    const double cells = std::max(1.0, static_cast<double>(n) / points_per_cell);
    double columns = 1, rows = 1;
    if (width > 0 && height > 0 && std::isfinite(width / height)) {
        const double aspect = width / height;
        columns = std::sqrt(cells * aspect);
        rows = std::sqrt(cells / aspect);
    } else if (width > 0) {
        columns = cells;
    } else if (height > 0) {
        rows = cells;
    }
    constexpr double kMaxSide = 1 << 15;
    g.columns = static_cast<std::uint32_t>(std::clamp(std::floor(columns), 1.0, kMaxSide));
    g.rows = static_cast<std::uint32_t>(std::clamp(std::floor(rows), 1.0, kMaxSide));
    g.origin_x = min_x;
    g.origin_y = min_y;
    // A width that overflows to infinity gives scale 0: one column, still correct.
    g.scale_x = width > 0 ? g.columns / width : 0.0;
    g.scale_y = height > 0 ? g.rows / height : 0.0;
    g.base_columns = g.columns;
    g.base_rows = g.rows;
    g.base_scale_x = g.scale_x;
    g.base_scale_y = g.scale_y;
    // Thin rows: 2^k of them per base row, at exactly 2^k times the base scale (so a row's
    // base row is its index shifted; a power of two scales a double exactly).
    if (row_split > 0 && g.scale_y > 0) {
        g.row_split = row_split;
        g.rows = g.base_rows << row_split;
        g.scale_y = std::ldexp(g.base_scale_y, static_cast<int>(row_split));
        g.columns = std::max(1u, g.base_columns >> row_split);
        g.scale_x = width > 0 ? g.columns / width : 0.0;
    }
    return g;
}

PointGrid::Geometry PointGrid::Geometry::of(std::span<const Point> first, std::span<const Point> second, double points_per_cell,
                                            unsigned row_split, int threads_wanted) {
    const std::size_t f = first.size(), n = f + second.size();
    if (n == 0) return {};
    auto point = [&](std::size_t i) { return i < f ? first[i] : second[i - f]; };
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
#pragma omp parallel for reduction(min : min_x, min_y) reduction(max : max_x, max_y) schedule(static) \
    num_threads(threads_wanted > 0 ? threads_wanted : omp_get_max_threads()) if (n >= 1 << 14)
    for (std::size_t i = 0; i < n; ++i) {
        const Point p = point(i);
        min_x = std::min(min_x, p.x);
        min_y = std::min(min_y, p.y);
        max_x = std::max(max_x, p.x);
        max_y = std::max(max_y, p.y);
    }
    return plan(min_x, min_y, max_x, max_y, n, points_per_cell, row_split);
}

PointGrid::PointGrid(std::span<const Point> first, std::span<const Point> second, double points_per_cell, int threads_wanted,
                     unsigned row_split, const std::atomic<bool>* cancel)
    : geometry_(Geometry::of(first, second, points_per_cell, row_split, threads_wanted)),
      columns_(geometry_.columns),
      rows_(geometry_.rows),
      row_split_(geometry_.row_split) {
    if (first.size() + second.size() == 0) {
        cell_start_.assign(2, 0);
        return;
    }
    build<false>(first, second, threads_wanted, {}, cancel);
}

PointGrid::PointGrid(const Geometry& geometry, const Window& window, std::span<const Point> first, std::span<const Point> second,
                     int threads_wanted)
    : geometry_(geometry),
      first_column_(window.first_column),
      first_row_(window.first_row),
      columns_(window.last_column - window.first_column + 1),
      rows_(window.last_row - window.first_row + 1),
      row_split_(geometry.row_split) {
    if (first.size() + second.size() == 0) {
        columns_ = rows_ = 1;
        cell_start_.assign(2, 0);
        return;
    }
    build<true>(first, second, threads_wanted);
}

PointGrid::PointGrid(const Geometry& geometry, std::span<const Point> first, std::span<const Point> second,
                     std::span<const std::uint8_t> skip_first, int threads_wanted)
    : geometry_(geometry), columns_(geometry.columns), rows_(geometry.rows), row_split_(geometry.row_split) {
    build<false>(first, second, threads_wanted, skip_first);
}

template <bool Windowed>
void PointGrid::build(std::span<const Point> first, std::span<const Point> second, int threads_wanted,
                      std::span<const std::uint8_t> skip_first, const std::atomic<bool>* cancel) {
    const std::size_t f = first.size(), n = f + second.size();
    auto point = [&](std::size_t i) { return i < f ? first[i] : second[i - f]; };
    auto kept = [&](std::size_t i) { return skip_first.empty() || i >= f || skip_first[i] == 0; };
    // Where a point is stored: its cell, or the window's nearest one.
    auto cell_column = [&](double x) { return Windowed ? in_window(geometry_.column(x), first_column_, columns_) : geometry_.column(x); };
    auto cell_row = [&](double y) { return Windowed ? in_window(geometry_.row(y), first_row_, rows_) : geometry_.row(y); };

    // Two counting sorts, both parallel: points into rows (each thread its own contiguous range
    // of ids, so a row keeps id order), then each row on its own into cells, each cell sorted by
    // x (ties by id) — which sorts each row by x.
    const bool parallel = n >= (1u << 14);
    const int threads = !parallel ? 1 : threads_wanted > 0 ? threads_wanted : omp_get_max_threads();
    const auto share = static_cast<std::size_t>(threads);
    std::vector<std::size_t> row_start(share * rows_ + 1, 0);  // [row][thread]: where each thread's part of a row starts
    auto chunk = [&](int t) { return std::pair{n * static_cast<std::size_t>(t) / share, n * static_cast<std::size_t>(t + 1) / share}; };
#pragma omp parallel num_threads(threads) if (parallel)
    parallel::for_my_shares(threads, [&](int t) {
        const auto [begin, end] = chunk(t);
        std::vector<std::size_t> count(rows_, 0);
        for (std::size_t i = begin; i < end; ++i) {
            if (kept(i)) ++count[cell_row(point(i).y)];
        }
        for (std::uint32_t y = 0; y < rows_; ++y) row_start[std::size_t{y} * share + static_cast<std::size_t>(t) + 1] = count[y];
    });
    for (std::size_t k = 1; k < row_start.size(); ++k) row_start[k] += row_start[k - 1];
    const std::size_t held = row_start.back();  // (n less the points skipped)
    points_.resize(held);
    ids_.resize(held);
#pragma omp parallel num_threads(threads) if (parallel)
    parallel::for_my_shares(threads, [&](int t) {
        const auto [begin, end] = chunk(t);
        std::vector<std::size_t> fill(rows_);
        for (std::uint32_t y = 0; y < rows_; ++y) fill[y] = row_start[std::size_t{y} * share + static_cast<std::size_t>(t)];
        for (std::size_t i = begin; i < end; ++i) {
            if (!kept(i)) continue;
            const Point p = point(i);
            const std::size_t slot = fill[cell_row(p.y)]++;
            points_[slot] = p;
            ids_[slot] = static_cast<std::uint32_t>(i);
        }
    });
    cell_start_.resize(std::size_t{columns_} * rows_ + 1);
    cell_start_.back() = static_cast<std::uint32_t>(held);
#pragma omp parallel num_threads(threads) if (parallel)
    {
        std::vector<std::pair<Point, std::uint32_t>> entries;
        std::vector<std::uint32_t> start(columns_ + 1);
#pragma omp for schedule(dynamic, 16)
        for (std::uint32_t y = 0; y < rows_; ++y) {
            if (cancel_requested(cancel)) continue;  // (most of the build: a second in a debug build for 2 M points)
            const std::size_t begin = row_start[std::size_t{y} * share], end = row_start[std::size_t{y + 1} * share];
            entries.clear();
            std::fill(start.begin(), start.end(), 0);
            for (std::size_t k = begin; k < end; ++k) ++start[cell_column(points_[k].x) + 1];
            for (std::uint32_t x = 0; x < columns_; ++x) {
                start[x + 1] += start[x];
                cell_start_[std::size_t{y} * columns_ + x] = static_cast<std::uint32_t>(begin + start[x]);
            }
            entries.resize(end - begin);
            for (std::size_t k = begin; k < end; ++k) entries[start[cell_column(points_[k].x)]++] = {points_[k], ids_[k]};
            // Cells now follow each other in column order, ids in order within each: sort each
            // cell by x, ties by id, and write the row back.
            for (std::size_t a = 0; a < entries.size();) {
                std::size_t b = a + 1;
                const std::uint32_t x = cell_column(entries[a].first.x);
                while (b < entries.size() && cell_column(entries[b].first.x) == x) ++b;
                if (b - a > 1) {
                    std::sort(entries.begin() + static_cast<std::ptrdiff_t>(a), entries.begin() + static_cast<std::ptrdiff_t>(b),
                              [](const auto& u, const auto& v) {
                                  return u.first.x < v.first.x || (u.first.x == v.first.x && u.second < v.second);
                              });
                }
                a = b;
            }
            for (std::size_t k = begin; k < end; ++k) {
                points_[k] = entries[k - begin].first;
                ids_[k] = entries[k - begin].second;
            }
        }
    }
    slot_.resize(f);
#pragma omp parallel for schedule(static) num_threads(threads) if (parallel)
    for (std::size_t k = 0; k < held; ++k) {
        if (ids_[k] < f) slot_[ids_[k]] = static_cast<std::uint32_t>(k);
    }
}

void PointGrid::compact(int threads_wanted) {
    const std::size_t cells = std::size_t{columns_} * rows_;
    const bool parallel = held() >= (1u << 16);
    const int threads = !parallel ? 1 : threads_wanted > 0 ? threads_wanted : omp_get_max_threads();
    const auto share = static_cast<std::size_t>(threads);
    // Each thread moves the points it keeps in its own run of cells to the run's start (never
    // past a point it has yet to read), then the runs are moved together in order.
    std::vector<std::size_t> first_cell(share + 1), run_start(share + 1), kept(share, 0);
    for (std::size_t t = 0; t <= share; ++t) {
        first_cell[t] = cells * t / share;
        run_start[t] = cell_start_[first_cell[t]];
    }
#pragma omp parallel num_threads(threads) if (parallel)
    parallel::for_my_shares(threads, [&](int thread) {
        const auto t = static_cast<std::size_t>(thread);
        std::size_t write = run_start[t];
        std::size_t from = run_start[t];
        for (std::size_t cell = first_cell[t]; cell < first_cell[t + 1]; ++cell) {
            const std::size_t to = cell + 1 < first_cell[t + 1] ? cell_start_[cell + 1] : run_start[t + 1];
            cell_start_[cell] = static_cast<std::uint32_t>(write);
            for (std::size_t k = from; k < to; ++k) {
                if (ids_[k] == kRemoved) continue;
                points_[write] = points_[k];
                ids_[write] = ids_[k];
                ++write;
            }
            from = to;
        }
        kept[t] = write - run_start[t];
    });
    std::vector<std::size_t> moved_to(share + 1, 0);
    for (std::size_t t = 0; t < share; ++t) {
        moved_to[t + 1] = moved_to[t] + kept[t];
        if (moved_to[t] == run_start[t]) continue;
        std::memmove(points_.data() + moved_to[t], points_.data() + run_start[t], kept[t] * sizeof(Point));
        std::memmove(ids_.data() + moved_to[t], ids_.data() + run_start[t], kept[t] * sizeof(std::uint32_t));
    }
#pragma omp parallel num_threads(threads) if (parallel)
    parallel::for_my_shares(threads, [&](int thread) {
        const auto t = static_cast<std::size_t>(thread);
        const auto shift = static_cast<std::uint32_t>(run_start[t] - moved_to[t]);
        for (std::size_t cell = first_cell[t]; cell < first_cell[t + 1]; ++cell) cell_start_[cell] -= shift;
    });
    cell_start_[cells] = static_cast<std::uint32_t>(moved_to[share]);
    const std::size_t f = slot_.size(), total = moved_to[share];
#pragma omp parallel for schedule(static) num_threads(threads) if (parallel)
    for (std::size_t k = 0; k < total; ++k) {
        if (ids_[k] < f) slot_[ids_[k]] = static_cast<std::uint32_t>(k);
    }
}

}  // namespace toposimp::map
