// A uniform grid of cells over a map's segments: which cells a segment is entered in, such that
// two segments that meet are both in the cell where they meet, and any point of a segment
// inside a box lies in a cell of the box's range. Used by the input-crossing search and by
// rounding's segment index.
#pragma once

#include "core/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace toposimp::map {

inline Box segment_box(Point a, Point b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
}

// A fixed order of locations (by y, then x): a segment's ends taken lower first are the same
// for its copies in either direction, so they are computed alike and sort together.
inline bool before(Point a, Point b) { return a.y < b.y || (a.y == b.y && a.x < b.x); }

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

// The cells of a grid over the map, and which of them a segment is entered in. A segment is
// entered in every cell of the rows its box spans, but within a row only in the columns of
// its part in that row: a line as long as the map, diagonal, is in about 2·side cells, not in
// side² (issue 29: a track running back and forth along a diagonal).
//
// Why no contact is missed: a point P of the segment with row(P.y) = r has (P.y − origin)·scale
// in [r, r + 1) up to rounding of a few ulps of side, far below a quarter row; so P.y lies in
// the band widened by a quarter row each way, computed with an error of a few ulps of the
// coordinates, which `clip` requires to be below 2⁻³⁶ of a cell. The segment's x over that
// band is interpolated between the band's ends; the interpolation errs by a few ulps of the
// coordinates plus the slope times the error in y, and the quarter row of slack in y and a
// quarter column in x cover both. So P.x lies in the part, and P's cell is one the segment is
// entered in; two segments that meet at P are both in P's cell. A segment within two rows,
// or a grid too fine for its coordinates, keeps its whole box.
struct Grid {
    Axis column, row;
    double cell_width = 0, cell_height = 0;
    bool clip = false;

    Box part_in_row(Point a, Point b, std::uint32_t r) const {
        const Box box = segment_box(a, b);
        if (!clip || row(box.max_y) - row(box.min_y) < 2) return box;
        if (before(b, a)) std::swap(a, b);  // (here only: which end comes first is a coin toss a predictor loses)
        const double low = std::max(box.min_y, row.origin + (static_cast<double>(r) - 0.25) * cell_height);
        const double high = std::min(box.max_y, row.origin + (static_cast<double>(r) + 1.25) * cell_height);
        const double dy = b.y - a.y;  // not zero: the segment spans three rows or more
        const double t_low = std::clamp((low - a.y) / dy, 0.0, 1.0), t_high = std::clamp((high - a.y) / dy, 0.0, 1.0);
        const double x_low = a.x + t_low * (b.x - a.x), x_high = a.x + t_high * (b.x - a.x);
        const double slack = 0.25 * cell_width;
        return {std::max(box.min_x, std::min(x_low, x_high) - slack), low, std::min(box.max_x, std::max(x_low, x_high) + slack), high};
    }
};

// A grid of columns × rows cells over `extent`.
inline Grid make_grid(const Box& extent, std::uint32_t columns, std::uint32_t rows) {
    const double width = extent.max_x - extent.min_x, height = extent.max_y - extent.min_y;
    Grid grid{{extent.min_x, width > 0 ? columns / width : 0.0, columns}, {extent.min_y, height > 0 ? rows / height : 0.0, rows},
              width / columns, height / rows};
    const double magnitude = std::max({std::abs(extent.min_x), std::abs(extent.max_x), std::abs(extent.min_y), std::abs(extent.max_y)});
    grid.clip = std::min(grid.cell_width, grid.cell_height) >= std::ldexp(magnitude, -36);
    return grid;
}

// A grid of about side × side cells over `extent`.
inline Grid make_grid(const Box& extent, std::uint32_t side) { return make_grid(extent, side, side); }

}  // namespace toposimp::map
