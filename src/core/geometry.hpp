// Plain geometry types shared by the whole engine.
#pragma once

#include <cstdint>

namespace toposimp {

// A point with the double coordinates read from the input, never rounded or moved.
struct Point {
    double x;
    double y;
};

// Exact coordinate equality (-0.0 equals 0.0: they are the same location).
inline bool same_location(Point a, Point b) { return a.x == b.x && a.y == b.y; }

struct Box {
    double min_x;
    double min_y;
    double max_x;
    double max_y;
};

inline Box triangle_box(Point a, Point b, Point c) {
    auto lo = [](double u, double v, double w) { return u < v ? (u < w ? u : w) : (v < w ? v : w); };
    auto hi = [](double u, double v, double w) { return u > v ? (u > w ? u : w) : (v > w ? v : w); };
    return {lo(a.x, b.x, c.x), lo(a.y, b.y, c.y), hi(a.x, b.x, c.x), hi(a.y, b.y, c.y)};
}

inline bool box_contains(const Box& box, Point p) {
    return p.x >= box.min_x && p.x <= box.max_x && p.y >= box.min_y && p.y <= box.max_y;
}

}  // namespace toposimp
