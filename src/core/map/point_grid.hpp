// A uniform grid over points (dissertation §2.3.1): each cell lists the points in it (id and
// coordinates), stored compactly (counting sort into one array, no per-cell allocation).
// Points of the first span can be taken out; queries then skip them without looking further.
//
// Cell lookup is a monotone function of each coordinate, so every point inside a query box is
// in one of the cells the box's corners map to: the grid never misses a point, whatever the
// rounding in the cell computation. Exactness of the final answer is the caller's predicate.
// Monotonicity also makes the set of locations mapping to a block of cells convex (a product of
// two intervals), which the parallel simplifier relies on.
#pragma once

#include "core/fill_later.hpp"
#include "core/geometry.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace toposimp::map {

class PointGrid {
public:
    static constexpr std::uint32_t kRemoved = 0xffffffffu;

    // Where the cells are: what a grid over part of the points must share with the grid over all
    // of them to put every point in the same cell (core/map/tiles.hpp).
    struct Geometry {
        double origin_x = 0, origin_y = 0, scale_x = 0, scale_y = 0;
        std::uint32_t columns = 1, rows = 1;
        double base_scale_x = 0, base_scale_y = 0;
        std::uint32_t base_columns = 1, base_rows = 1;
        unsigned row_split = 0;

        // The cells of a grid over `points` points spanning [min_x, max_x] × [min_y, max_y]
        // (see the constructor below).
        static Geometry plan(double min_x, double min_y, double max_x, double max_y, std::size_t points,
                             double points_per_cell, unsigned row_split);

        // The cells the first constructor below gives a grid over `first` and `second` (their
        // bounds found on `threads` threads, 0: OpenMP's default), without building it.
        static Geometry of(std::span<const Point> first, std::span<const Point> second, double points_per_cell,
                           unsigned row_split, int threads = 0);

        std::uint32_t column(double x) const { return cell_of(x, origin_x, scale_x, columns); }
        std::uint32_t row(double y) const { return cell_of(y, origin_y, scale_y, rows); }
        std::uint32_t base_column(double x) const { return cell_of(x, origin_x, base_scale_x, base_columns); }
        std::uint32_t base_row(double y) const { return cell_of(y, origin_y, base_scale_y, base_rows); }
    };

    // A rectangle of a Geometry's cells, inclusive.
    struct Window {
        std::uint32_t first_column, first_row, last_column, last_row;
    };

    // Indexes `first` as ids [0, f) and `second` as ids [f, f + s). About `points_per_cell`
    // points share a cell on average. Built on `threads` threads (0: OpenMP's default) when
    // big; the grid is the same for any number. Once `cancel` is set (core/cancel.hpp) the
    // build passes over the rows left and the grid is incomplete: the caller must then stop.
    //
    // The cells are first laid out square-ish (the *base* cells); `row_split` k then cuts each
    // base row into 2^k rows and joins columns 2^k at a time, keeping the number of cells: thin
    // rows read fewer points outside a small query box when points crowd along lines (shores,
    // borders). Base row r is rows r·2^k to r·2^k + 2^k − 1 exactly (row(y) >> k == base_row(y)).
    explicit PointGrid(std::span<const Point> first, std::span<const Point> second = {}, double points_per_cell = 2.0,
                       int threads = 0, unsigned row_split = 0, const std::atomic<bool>* cancel = nullptr);

    // A grid with the cells of `geometry` in `window` only (a tile of a bigger grid): every point
    // inside the window lands in the cell the bigger grid puts it in, with the same order within
    // its cell as long as ids keep the bigger grid's order; a point outside is kept in the
    // window's nearest cell, where a query for a box inside the window reads it but never finds
    // it in the box.
    PointGrid(const Geometry& geometry, const Window& window, std::span<const Point> first,
              std::span<const Point> second = {}, int threads = 0);

    // A grid with all of `geometry`'s cells over `first` (ids [0, f)) but those marked in
    // `skip_first` (points already taken out: the grid then answers as the grid over all of them
    // would once they are taken out), and `second` (ids [f, f + s)).
    PointGrid(const Geometry& geometry, std::span<const Point> first, std::span<const Point> second,
              std::span<const std::uint8_t> skip_first, int threads = 0);

    const Geometry& geometry() const { return geometry_; }

    // Calls visit(id, point) for each point not taken out whose x lies in the box's x range,
    // within the rows of cells the box overlaps (a superset of the points inside it), until
    // visit returns true; returns whether it did. Each cell's points are sorted by x, so a row
    // of cells is sorted by x: a query binary-searches its x range and reads memory sequentially.
    template <class Visit>
    bool any_in_cells(const Box& box, Visit&& visit) const {
        const std::uint32_t x0 = column(box.min_x), x1 = column(box.max_x);
        const std::uint32_t y0 = row(box.min_y), y1 = row(box.max_y);
        for (std::uint32_t y = y0; y <= y1; ++y) {
            const auto [from, last] = row_part(y, x0, x1, box.min_x);
            for (const Point* p = from; p != last && p->x <= box.max_x; ++p) {
                const std::uint32_t id = load(ids_[static_cast<std::size_t>(p - points_.data())]);
                if (id != kRemoved && visit(id, *p)) return true;
            }
        }
        return false;
    }

    // The point accept(id, point) takes that comes first in the order (base row, x, id), or
    // kRemoved: the point any_in_cells would stop at on a grid without row_split, whatever the
    // split. Each row is sorted by (x, id), so its first accepted point is its least; rows of
    // one base row are all read once one of them has a point. accept is also asked about the
    // taken-out points, with id kRemoved (it must refuse them), so that it can fold that test
    // into its own without a branch.
    template <class Accept>
    std::uint32_t first_in_cells(const Box& box, Accept&& accept) const {
        std::uint32_t best = kRemoved, best_row = 0;
        Point best_point{};
        const std::uint32_t x0 = column(box.min_x), x1 = column(box.max_x);
        const std::uint32_t y0 = row(box.min_y), y1 = row(box.max_y);
        for (std::uint32_t y = y0; y <= y1; ++y) {
            if (best != kRemoved && ((y + first_row_) >> row_split_) != ((best_row + first_row_) >> row_split_)) break;
            const auto [from, last] = row_part(y, x0, x1, box.min_x);
            for (const Point* p = from; p != last && p->x <= box.max_x; ++p) {
                if (best != kRemoved && best_point.x < p->x) break;  // (nothing later in this row comes first)
                const std::uint32_t id = load(ids_[static_cast<std::size_t>(p - points_.data())]);
                if (!accept(id, *p)) continue;
                if (best == kRemoved || p->x < best_point.x || (p->x == best_point.x && id < best)) {
                    best = id;
                    best_point = *p;
                    best_row = y;
                }
                break;
            }
        }
        return best;
    }

    // Takes point `id` of the first span out, once: queries skip it from now on. Points that other
    // threads may be taking out at the same time can lie in the cells a query scans (outside
    // its box), hence the relaxed atomic accesses to ids.
    void remove(std::uint32_t id) { std::atomic_ref<std::uint32_t>(ids_[slot_[id]]).store(kRemoved, std::memory_order_relaxed); }

    // Drops the taken-out points from the cells, keeping the order of the others: queries give
    // the same answers and read less. On `threads` threads (0: OpenMP's default).
    void compact(int threads = 0);

    // Points held, taken-out ones included until compact().
    std::size_t held() const { return cell_start_[cell_start_.size() - 1]; }

    // The base cells (see the constructor).
    std::uint32_t base_columns() const { return geometry_.base_columns; }
    std::uint32_t base_rows() const { return geometry_.base_rows; }
    std::uint32_t base_column(double x) const { return geometry_.base_column(x); }
    std::uint32_t base_row(double y) const { return geometry_.base_row(y); }

    // The cells held (all of the geometry's, or a window's), numbered from the window's corner.
    // column() and row() are for coordinates inside the window (every query's box must be).
    std::uint32_t columns() const { return columns_; }
    std::uint32_t rows() const { return rows_; }
    std::uint32_t column(double x) const { return geometry_.column(x) - first_column_; }
    std::uint32_t row(double y) const { return geometry_.row(y) - first_row_; }

    // The ids and points of cell (column x, row y), sorted by x (ties by id); kRemoved for taken-out points.
    std::span<const std::uint32_t> cell_ids(std::uint32_t x, std::uint32_t y) const {
        const std::size_t cell = std::size_t{y} * columns_ + x;
        return {ids_.data() + cell_start_[cell], ids_.data() + cell_start_[cell + 1]};
    }
    std::span<const Point> cell_points(std::uint32_t x, std::uint32_t y) const {
        const std::size_t cell = std::size_t{y} * columns_ + x;
        return {points_.data() + cell_start_[cell], points_.data() + cell_start_[cell + 1]};
    }

private:
    // Row y's points in columns x0 to x1, from the first with x ≥ min_x on.
    std::pair<const Point*, const Point*> row_part(std::uint32_t y, std::uint32_t x0, std::uint32_t x1, double min_x) const {
        const std::size_t row_start = std::size_t{y} * columns_;
        const Point* p = points_.data() + cell_start_[row_start + x0];
        const Point* last = points_.data() + cell_start_[row_start + x1 + 1];
        // The first point with x ≥ min_x is in cell x0, or it is the next cell's first (a point
        // in a later column is not left of min_x, column() being monotone).
        const Point* end = points_.data() + cell_start_[row_start + x0 + 1];
        // Few points per cell on average: a short linear skip.
        if (end - p <= 16) {
            while (p != end && p->x < min_x) ++p;
            return {p, last};
        }
        // A crowded cell: points along a line spread over its width, so start where min_x would
        // be if they were even, and gallop from there to the exact place.
        const double left = geometry_.origin_x + static_cast<double>(x0 + first_column_) / geometry_.scale_x;
        const double at = (min_x - left) * geometry_.scale_x;
        const std::ptrdiff_t count = end - p;
        const double share = at > 0 ? (at < 1 ? at : 1) : 0;  // (NaN, from a grid of no width: 0)
        const auto guess = static_cast<std::ptrdiff_t>(share * static_cast<double>(count));
        auto before = [&](const Point& q) { return q.x < min_x; };
        const Point* from = p + guess;
        if (from != end && before(*from)) {
            std::ptrdiff_t step = 1;
            const Point* lo = from + 1;  // lo − 1 is before min_x
            while (end - lo > step && before(lo[step - 1])) {
                lo += step;
                step *= 2;
            }
            return {std::partition_point(lo, std::min(end, lo + step), before), last};
        }
        std::ptrdiff_t step = 1;
        const Point* hi = from;  // *hi is not before min_x (or hi is the end)
        while (hi - p > step && !before(hi[-step])) {
            hi -= step;
            step *= 2;
        }
        return {std::partition_point(std::max(p, hi - step), hi, before), last};
    }

    static std::uint32_t load(const std::uint32_t& id) {
        return std::atomic_ref<const std::uint32_t>(id).load(std::memory_order_relaxed);
    }

    static std::uint32_t in_window(std::uint32_t cell, std::uint32_t first, std::uint32_t count) {
        const std::uint32_t offset = cell < first ? 0 : cell - first;
        return offset < count ? offset : count - 1;
    }

    template <bool Windowed>
    void build(std::span<const Point> first, std::span<const Point> second, int threads_wanted,
               std::span<const std::uint8_t> skip_first = {}, const std::atomic<bool>* cancel = nullptr);

    static std::uint32_t cell_of(double value, double origin, double scale, std::uint32_t count) {
        double t = (value - origin) * scale;
        if (!(t >= 0.0)) t = 0.0;  // also catches NaN from 0·∞ in a zero-width grid
        if (t >= static_cast<double>(count)) return count - 1;
        return static_cast<std::uint32_t>(t);
    }

    Geometry geometry_;
    std::uint32_t first_column_ = 0, first_row_ = 0;  // the window's corner in the geometry's cells
    std::uint32_t columns_ = 1, rows_ = 1;            // the window's size
    unsigned row_split_ = 0;
    FillLater<std::uint32_t> cell_start_;  // cells are row-major, so a row's cells are contiguous
    FillLater<Point> points_;              // in cell order
    FillLater<std::uint32_t> ids_;         // parallel to points_; kRemoved once taken out
    FillLater<std::uint32_t> slot_;        // per point of the first span: its entry
};

}  // namespace toposimp::map
