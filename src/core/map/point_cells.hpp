// Indices of points in a grid of cells, about 4 points a cell: the points a box holds are read
// from the cells it meets, not from every point in its x range. The points stay where they are
// (4 bytes an indexed point): for indexes kept beside data that must stay small (a kept-tiles
// run's lead and its tiles). PointGrid (point_grid.hpp) copies the points in cell order instead,
// 24 bytes a point, for the engine's hot loops.
#pragma once

#include "core/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::map {

class PointCells {
public:
    PointCells() = default;

    // Over points[k] for each k of `indices`.
    PointCells(std::span<const Point> points, std::span<const std::uint32_t> indices) {
        if (!indices.empty()) {
            Box box{points[indices[0]].x, points[indices[0]].y, points[indices[0]].x, points[indices[0]].y};
            for (const std::uint32_t k : indices) {
                const Point p = points[k];
                box = {std::min(box.min_x, p.x), std::min(box.min_y, p.y), std::max(box.max_x, p.x), std::max(box.max_y, p.y)};
            }
            const auto side = static_cast<std::uint32_t>(std::clamp(std::sqrt(static_cast<double>(indices.size()) / 4), 1.0, 4096.0));
            min_x_ = box.min_x;
            min_y_ = box.min_y;
            columns_ = box.max_x > box.min_x ? side : 1;
            rows_ = box.max_y > box.min_y ? side : 1;
            scale_x_ = box.max_x > box.min_x ? columns_ / (box.max_x - box.min_x) : 0;
            scale_y_ = box.max_y > box.min_y ? rows_ / (box.max_y - box.min_y) : 0;
        }
        const std::size_t count = std::size_t{columns_} * rows_;
        start_.assign(count + 1, 0);
        const auto cell = [&](Point p) { return std::size_t{row(p.y)} * columns_ + column(p.x); };
        for (const std::uint32_t k : indices) ++start_[cell(points[k]) + 1];
        for (std::size_t c = 0; c < count; ++c) start_[c + 1] += start_[c];
        order_.resize(indices.size());
        std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
        for (const std::uint32_t k : indices) order_[next[cell(points[k])]++] = k;
    }

    // Over every point.
    static PointCells over_all(std::span<const Point> points) {
        std::vector<std::uint32_t> all(points.size());
        for (std::uint32_t k = 0; k < all.size(); ++k) all[k] = k;
        return PointCells(points, all);
    }

    bool built() const { return !start_.empty(); }

    // visit(k) for each indexed point in the closed box (the points it was built over), cell by cell.
    template <class Visit>
    void in_box(const Box& box, std::span<const Point> points, Visit&& visit) const {
        if (order_.empty()) return;
        const std::uint32_t c0 = column(box.min_x), c1 = column(box.max_x);
        for (std::uint32_t r = row(box.min_y), r1 = row(box.max_y);; ++r) {
            const std::size_t from = std::size_t{r} * columns_;
            for (std::uint32_t k = start_[from + c0]; k < start_[from + c1 + 1]; ++k) {
                if (box_contains(box, points[order_[k]])) visit(order_[k]);
            }
            if (r == r1) break;
        }
    }

private:
    // (Monotone in x and y: a point in a box is in the cells of the box's corners. Not a number: 0.)
    std::uint32_t column(double x) const {
        const double at = (x - min_x_) * scale_x_;
        return !(at > 0) ? 0 : at >= columns_ - 1 ? columns_ - 1 : static_cast<std::uint32_t>(at);
    }
    std::uint32_t row(double y) const {
        const double at = (y - min_y_) * scale_y_;
        return !(at > 0) ? 0 : at >= rows_ - 1 ? rows_ - 1 : static_cast<std::uint32_t>(at);
    }

    double min_x_ = 0, min_y_ = 0, scale_x_ = 0, scale_y_ = 0;  // cells per unit
    std::uint32_t columns_ = 1, rows_ = 1;
    std::vector<std::uint32_t> start_;  // per cell, and one past the last
    std::vector<std::uint32_t> order_;  // the points' indices, cell after cell (rows of columns)
};

}  // namespace toposimp::map
