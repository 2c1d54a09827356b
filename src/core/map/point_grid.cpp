#include "core/map/point_grid.hpp"

#include <algorithm>
#include <cmath>

namespace toposimp::map {

PointGrid::PointGrid(std::span<const Point> removable, std::span<const Point> fixed, double points_per_cell) {
    const std::size_t r = removable.size(), n = r + fixed.size();
    auto point = [&](std::size_t i) { return i < r ? removable[i] : fixed[i - r]; };
    if (n == 0) {
        cell_start_.assign(2, 0);
        return;
    }
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
#pragma omp parallel for reduction(min : min_x, min_y) reduction(max : max_x, max_y) schedule(static) if (n >= 1 << 14)
    for (std::size_t i = 0; i < n; ++i) {
        const Point p = point(i);
        min_x = std::min(min_x, p.x);
        min_y = std::min(min_y, p.y);
        max_x = std::max(max_x, p.x);
        max_y = std::max(max_y, p.y);
    }
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
    columns_ = static_cast<std::uint32_t>(std::clamp(std::floor(columns), 1.0, kMaxSide));
    rows_ = static_cast<std::uint32_t>(std::clamp(std::floor(rows), 1.0, kMaxSide));
    origin_x_ = min_x;
    origin_y_ = min_y;
    // A width that overflows to infinity gives scale 0: one column, still correct.
    scale_x_ = width > 0 ? columns_ / width : 0.0;
    scale_y_ = height > 0 ? rows_ / height : 0.0;

    const std::size_t cell_count = std::size_t{columns_} * rows_;
    std::vector<std::uint32_t> cell_of_point(n);
#pragma omp parallel for schedule(static) if (n >= 1 << 14)
    for (std::size_t i = 0; i < n; ++i) {
        const Point p = point(i);
        cell_of_point[i] = row(p.y) * columns_ + column(p.x);
    }
    cell_start_.assign(cell_count + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++cell_start_[cell_of_point[i] + 1];
    for (std::size_t c = 0; c < cell_count; ++c) cell_start_[c + 1] += cell_start_[c];
    points_.resize(n);
    ids_.resize(n);
    slot_.resize(r);
    std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t slot = fill[cell_of_point[i]]++;
        points_[slot] = point(i);
        ids_[slot] = static_cast<std::uint32_t>(i);
    }
    // Sort each cell by x (ties by id), which sorts each row of cells by x.
    const auto cell_total = static_cast<std::ptrdiff_t>(cell_count);
#pragma omp parallel if (n >= 1 << 14)
    {
        std::vector<std::pair<Point, std::uint32_t>> cell;
#pragma omp for schedule(dynamic, 4096)
        for (std::ptrdiff_t c = 0; c < cell_total; ++c) {
            const std::uint32_t begin = cell_start_[static_cast<std::size_t>(c)], end = cell_start_[static_cast<std::size_t>(c) + 1];
            if (end - begin < 2) continue;
            cell.clear();
            for (std::uint32_t k = begin; k < end; ++k) cell.emplace_back(points_[k], ids_[k]);
            std::sort(cell.begin(), cell.end(), [](const auto& a, const auto& b) {
                return a.first.x < b.first.x || (a.first.x == b.first.x && a.second < b.second);
            });
            for (std::uint32_t k = begin; k < end; ++k) {
                points_[k] = cell[k - begin].first;
                ids_[k] = cell[k - begin].second;
            }
        }
    }
#pragma omp parallel for schedule(static) if (n >= 1 << 14)
    for (std::size_t k = 0; k < n; ++k) {
        if (ids_[k] < r) slot_[ids_[k]] = static_cast<std::uint32_t>(k);
    }
}

}  // namespace toposimp::map
