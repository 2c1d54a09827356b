#include "core/exact/point_in_ring.hpp"

#include <algorithm>

namespace toposimp::exact {
namespace {

// What edge a→b says of p: it holds p (boundary), or the ray from p to +x crosses it (toggles the
// parity), or nothing. Edges whose y range does not hold p.y say nothing.
enum class EdgeSays { nothing, crossed, boundary };

EdgeSays edge_says(Point a, Point b, Point p, PredicateStats& stats) {
    const bool in_box = p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) && p.y >= std::min(a.y, b.y) && p.y <= std::max(a.y, b.y);
    const bool straddles = (a.y <= p.y) != (b.y <= p.y);  // half-open rule: each crossing counted once
    if (!in_box && !straddles) return EdgeSays::nothing;
    const int side = orient2d(a, b, p, stats);
    if (in_box && side == 0) return EdgeSays::boundary;
    // Upward edge with p to its left, or downward edge with p to its right: the ray to +x crosses.
    return straddles && (b.y > a.y ? side > 0 : side < 0) ? EdgeSays::crossed : EdgeSays::nothing;
}

}  // namespace

RingLocation locate_in_ring(std::span<const Point> ring, Point p, PredicateStats& stats) {
    const std::size_t n = ring.size();
    if (n == 0) return RingLocation::outside;
    bool odd = false;
    for (std::size_t i = 0; i < n; ++i) {
        const EdgeSays says = edge_says(ring[i], ring[(i + 1) % n], p, stats);
        if (says == EdgeSays::boundary) return RingLocation::boundary;
        if (says == EdgeSays::crossed) odd = !odd;
    }
    return odd ? RingLocation::inside : RingLocation::outside;
}

RingLocator::RingLocator(std::span<const Point> ring) : ring_(ring) {
    const std::size_t n = ring.size();
    if (n == 0) {
        start_.assign(2, 0);
        return;
    }
    min_y_ = max_y_ = ring[0].y;
    for (const Point q : ring) {
        min_y_ = std::min(min_y_, q.y);
        max_y_ = std::max(max_y_, q.y);
    }
    // Each edge in every row from its lower end's to its upper end's: row() is monotone, so a
    // point whose y the edge's range holds finds the edge in its row. About two edges a row, but
    // fewer rows where edges spanning many of them would fill more than 8 entries an edge (a ring
    // zigzagging over its whole height): never more than that, at worst one row, as
    // locate_in_ring. (A height that overflows to infinity gives scale 0: one row, still right.)
    const double height = max_y_ - min_y_;
    auto rows_of = [&](std::size_t i) {
        const Point a = ring[i], b = ring[(i + 1) % n];
        return std::pair{row(std::min(a.y, b.y)), row(std::max(a.y, b.y))};
    };
    for (rows_ = static_cast<std::uint32_t>(std::clamp<std::size_t>(n / 2, 1, std::size_t{1} << 16));; rows_ /= 2) {
        scale_ = height > 0 ? static_cast<double>(rows_) / height : 0.0;
        std::size_t entries = 0;
        for (std::size_t i = 0; i < n && entries <= 8 * n; ++i) {
            const auto [low, high] = rows_of(i);
            entries += high - low + 1;
        }
        if (entries <= 8 * n || rows_ == 1) break;
    }
    start_.assign(std::size_t{rows_} + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const auto [low, high] = rows_of(i);
        for (std::uint32_t r = low; r <= high; ++r) ++start_[r + 1];
    }
    for (std::uint32_t r = 0; r < rows_; ++r) start_[r + 1] += start_[r];
    edges_.resize(start_.back());
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
        const auto [low, high] = rows_of(i);
        for (std::uint32_t r = low; r <= high; ++r) edges_[fill[r]++] = static_cast<std::uint32_t>(i);
    }
}

std::uint32_t RingLocator::row(double y) const {
    double t = (y - min_y_) * scale_;
    if (!(t >= 0.0)) t = 0.0;
    if (t >= static_cast<double>(rows_)) return rows_ - 1;
    return static_cast<std::uint32_t>(t);
}

RingLocation RingLocator::locate(Point p, PredicateStats& stats) const {
    const std::size_t n = ring_.size();
    if (n == 0 || !(p.y >= min_y_ && p.y <= max_y_)) return RingLocation::outside;  // (no edge's y range holds p.y)
    const std::uint32_t r = row(p.y);
    bool odd = false;
    for (std::size_t k = start_[r]; k < start_[r + 1]; ++k) {
        const std::uint32_t i = edges_[k];
        const EdgeSays says = edge_says(ring_[i], ring_[(i + 1) % n], p, stats);
        if (says == EdgeSays::boundary) return RingLocation::boundary;
        if (says == EdgeSays::crossed) odd = !odd;
    }
    return odd ? RingLocation::inside : RingLocation::outside;
}

}  // namespace toposimp::exact
