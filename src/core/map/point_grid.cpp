#include "core/map/point_grid.hpp"

#include <algorithm>
#include <cmath>

namespace toposimp::map {

PointGrid::PointGrid(std::span<const Point> points, double points_per_cell) {
    if (points.empty()) {
        cell_start_.assign(2, 0);
        return;
    }
    Box bounds{points[0].x, points[0].y, points[0].x, points[0].y};
    for (const Point& p : points) {
        bounds.min_x = std::min(bounds.min_x, p.x);
        bounds.min_y = std::min(bounds.min_y, p.y);
        bounds.max_x = std::max(bounds.max_x, p.x);
        bounds.max_y = std::max(bounds.max_y, p.y);
    }
    const double width = bounds.max_x - bounds.min_x;
    const double height = bounds.max_y - bounds.min_y;
    // Square-ish cells, total count ≈ n / points_per_cell, each side capped to keep indices small.
    const double cells = std::max(1.0, static_cast<double>(points.size()) / points_per_cell);
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
    origin_x_ = bounds.min_x;
    origin_y_ = bounds.min_y;
    // A width that overflows to infinity gives scale 0: one column, still correct.
    scale_x_ = width > 0 ? columns_ / width : 0.0;
    scale_y_ = height > 0 ? rows_ / height : 0.0;

    const std::size_t cell_count = std::size_t{columns_} * rows_;
    std::vector<std::uint32_t> cell_of_point(points.size());
    cell_start_.assign(cell_count + 1, 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const std::uint32_t cell = row(points[i].y) * columns_ + column(points[i].x);
        cell_of_point[i] = cell;
        ++cell_start_[cell + 1];
    }
    for (std::size_t c = 0; c < cell_count; ++c) cell_start_[c + 1] += cell_start_[c];
    entries_.resize(points.size());
    slot_.resize(points.size());
    std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const std::uint32_t slot = fill[cell_of_point[i]]++;
        entries_[slot] = {points[i], static_cast<std::uint32_t>(i)};
        slot_[i] = slot;
    }
}

}  // namespace toposimp::map
