#include "core/mesh/plan_index.hpp"

namespace toposimp::mesh {

PlanIndex::PlanIndex(const Mesh& mesh) {
    first_.assign(2, 0);
    if (mesh.faces.empty()) return;
    const Point3& start = mesh.points[mesh.faces[0][0]];
    double lo_x = start.x, hi_x = start.x, lo_y = start.y, hi_y = start.y;
    for (const Face& f : mesh.faces) {
        for (std::uint32_t w : f) {
            lo_x = std::min(lo_x, mesh.points[w].x), hi_x = std::max(hi_x, mesh.points[w].x);
            lo_y = std::min(lo_y, mesh.points[w].y), hi_y = std::max(hi_y, mesh.points[w].y);
        }
    }
    lo_x_ = lo_x, lo_y_ = lo_y;
    const double cells = std::max(1.0, static_cast<double>(mesh.faces.size()) / 2.0);
    const double width = hi_x - lo_x, height = hi_y - lo_y;
    size_ = width > 0 && height > 0 ? std::sqrt(width * height / cells) : std::max({width, height, 1.0});
    n_x_ = std::min<std::int64_t>(static_cast<std::int64_t>(width / size_) + 1, 1 << 14);
    n_y_ = std::min<std::int64_t>(static_cast<std::int64_t>(height / size_) + 1, 1 << 14);
    // Two passes over the faces' cell ranges: count per cell, then fill (a counting sort).
    auto for_cells = [&](const Face& f, auto each) {
        double x0 = mesh.points[f[0]].x, x1 = x0, y0 = mesh.points[f[0]].y, y1 = y0;
        for (std::uint32_t w : f) {
            x0 = std::min(x0, mesh.points[w].x), x1 = std::max(x1, mesh.points[w].x);
            y0 = std::min(y0, mesh.points[w].y), y1 = std::max(y1, mesh.points[w].y);
        }
        for (std::int64_t x = cell(x0, lo_x_, n_x_); x <= cell(x1, lo_x_, n_x_); ++x) {
            for (std::int64_t y = cell(y0, lo_y_, n_y_); y <= cell(y1, lo_y_, n_y_); ++y) each(static_cast<std::size_t>(x * n_y_ + y));
        }
    };
    first_.assign(static_cast<std::size_t>(n_x_ * n_y_) + 1, 0);
    for (const Face& f : mesh.faces) for_cells(f, [&](std::size_t c) { ++first_[c + 1]; });
    for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
    faces_.resize(first_.back());
    std::vector<std::size_t> next(first_.begin(), first_.end() - 1);
    for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) for_cells(mesh.faces[f], [&](std::size_t c) { faces_[next[c]++] = f; });
}

}  // namespace toposimp::mesh
