// The faces of a terrain bucketed by their x–y bounding boxes in a uniform grid (about two
// faces per cell), for finding the faces over a point of the map plane, and for checking that
// no two of them overlap there.
#pragma once

#include "core/mesh/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace toposimp::mesh {

// A box in the map plane.
struct PlanExtent {
    double x0, x1, y0, y1;
};

// The box of a mesh's faces in the map plane (of their corners: not of vertices no face uses).
PlanExtent faces_plan_extent(const Mesh& mesh, int threads = 1);

class PlanIndex {
public:
    explicit PlanIndex(const Mesh& mesh);
    // Only the cells within `reach` cells of one holding a point of `near` are filled (at()
    // elsewhere says nothing): for queries at those points alone, without listing every face of
    // a big mesh.
    // Built on `threads` threads (0: OpenMP's default) when big; the index is the same for any.
    // `faces_box`, if the caller has it, must be faces_plan_extent(mesh) (one pass over the faces
    // fewer).
    PlanIndex(const Mesh& mesh, std::span<const Point> near, std::int64_t reach = 0, int threads = 0,
              const PlanExtent* faces_box = nullptr);

    // The faces whose boxes meet the cell holding (x, y) (clamped to the grid): every face over
    // that point among them.
    std::span<const std::uint32_t> at(double x, double y) const {
        const std::size_t c = static_cast<std::size_t>(cell(x, lo_x_, n_x_) * n_y_ + cell(y, lo_y_, n_y_));
        return {faces_.data() + first_[c], faces_.data() + first_[c + 1]};
    }

    // Calls visit(face) for the faces listed in the cells that meet the square of half-side `r`
    // around (x, y) (a face more than once if it is listed in several): every face whose box
    // meets the square among them. With `near`, false (and no call) if the square reaches
    // beyond the `reach` cells filled around (x, y)'s cell.
    template <class Visit>
    bool visit_square(double x, double y, double r, Visit visit) const {
        const std::int64_t cx = cell(x, lo_x_, n_x_), cy = cell(y, lo_y_, n_y_);
        const std::int64_t x0 = cell(x - r, lo_x_, n_x_), x1 = cell(x + r, lo_x_, n_x_);
        const std::int64_t y0 = cell(y - r, lo_y_, n_y_), y1 = cell(y + r, lo_y_, n_y_);
        if (reach_ >= 0 && (cx - x0 > reach_ || x1 - cx > reach_ || cy - y0 > reach_ || y1 - cy > reach_)) return false;
        for (std::int64_t i = x0; i <= x1; ++i) {
            for (std::int64_t j = y0; j <= y1; ++j) {
                const auto c = static_cast<std::size_t>(i * n_y_ + j);
                for (std::size_t k = first_[c]; k < first_[c + 1]; ++k) visit(faces_[k]);
            }
        }
        return true;
    }

    // Two faces whose interiors overlap in the map plane, the first such pair (f < g, ordered),
    // if any. `mesh`: the one indexed, its faces all turned `turn` (±1) in the map plane, none
    // degenerate there. None overlapping means the faces cover each point at most once: the mesh
    // is a height field over a planar triangulation, and stays one under collapses that keep
    // every face's turn and its border (the number of faces over a point is the winding number
    // of the border around it).
    std::optional<std::array<std::uint32_t, 2>> overlapping_faces(const Mesh& mesh, int turn, int threads = 0) const;

private:
    std::int64_t cell(double value, double origin, std::int64_t n) const {
        // (Truncation floors what is not negative; the rest, NaN too, is cell 0.)
        const double c = (value - origin) * per_size_;
        if (!(c >= 0)) return 0;
        return c >= static_cast<double>(n - 1) ? n - 1 : static_cast<std::int64_t>(c);
    }

    double lo_x_ = 0, lo_y_ = 0, size_ = 1;
    double per_size_ = 1;  // 1 / size_ (any monotone rounding of a position to cells will do)
    std::int64_t reach_ = -1;  // with `near`: the cells filled around each point's
    std::int64_t n_x_ = 1, n_y_ = 1;
    std::vector<std::size_t> first_;  // per cell (x-major), where its faces start; one more at the end
    std::vector<std::uint32_t> faces_;
};

}  // namespace toposimp::mesh
