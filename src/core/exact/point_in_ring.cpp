#include "core/exact/point_in_ring.hpp"

#include <algorithm>

namespace toposimp::exact {

RingLocation locate_in_ring(std::span<const Point> ring, Point p, PredicateStats& stats) {
    const std::size_t n = ring.size();
    if (n == 0) return RingLocation::outside;
    bool odd = false;
    for (std::size_t i = 0; i < n; ++i) {
        const Point a = ring[i], b = ring[(i + 1) % n];
        const bool in_box = p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) && p.y >= std::min(a.y, b.y) &&
                            p.y <= std::max(a.y, b.y);
        const bool straddles = (a.y <= p.y) != (b.y <= p.y);  // half-open rule: each crossing counted once
        if (!in_box && !straddles) continue;
        const int side = orient2d(a, b, p, stats);
        if (in_box && side == 0) return RingLocation::boundary;
        // Upward edge with p to its left, or downward edge with p to its right: the ray to +x crosses.
        if (straddles && (b.y > a.y ? side > 0 : side < 0)) odd = !odd;
    }
    return odd ? RingLocation::inside : RingLocation::outside;
}

}  // namespace toposimp::exact
