// Plain geometry types shared by the whole engine.
#pragma once

#include <algorithm>
#include <cmath>
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
    // (The same choices as u < v ? (u < w ? u : w) : (v < w ? v : w), written as two of the
    // form x < y ? x : y, which compilers turn into min/max instructions instead of branches.)
    auto lo = [](double u, double v, double w) {
        const double m = u < v ? u : v;
        return m < w ? m : w;
    };
    auto hi = [](double u, double v, double w) {
        const double m = u > v ? u : v;
        return m > w ? m : w;
    };
    return {lo(a.x, b.x, c.x), lo(a.y, b.y, c.y), hi(a.x, b.x, c.x), hi(a.y, b.y, c.y)};
}

inline bool box_contains(const Box& box, Point p) {
    return p.x >= box.min_x && p.x <= box.max_x && p.y >= box.min_y && p.y <= box.max_y;
}

}  // namespace toposimp

namespace toposimp {

// A mesh vertex position. Coordinates are read as doubles and moved only by a collapse, which
// places the merged vertex at a double position checked afterwards with exact predicates.
struct Point3 {
    double x;
    double y;
    double z;

    double operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
};

inline bool same_location(Point3 a, Point3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Points as vectors, in doubles (measures and placements; never a predicate).
inline Point3 minus(Point3 a, Point3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Point3 cross(Point3 a, Point3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double dot(Point3 a, Point3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double norm(Point3 a) { return std::sqrt(dot(a, a)); }

// The plane projection that drops one axis: 0 drops x, 1 drops y, 2 drops z (the map plane).
inline Point drop_axis(Point3 p, int axis) {
    return axis == 0 ? Point{p.y, p.z} : (axis == 1 ? Point{p.z, p.x} : Point{p.x, p.y});
}

struct Box3 {
    Point3 lo;
    Point3 hi;

    void add(Point3 p) {
        lo = {p.x < lo.x ? p.x : lo.x, p.y < lo.y ? p.y : lo.y, p.z < lo.z ? p.z : lo.z};
        hi = {p.x > hi.x ? p.x : hi.x, p.y > hi.y ? p.y : hi.y, p.z > hi.z ? p.z : hi.z};
    }
    bool overlaps(const Box3& other) const {
        return lo.x <= other.hi.x && other.lo.x <= hi.x && lo.y <= other.hi.y && other.lo.y <= hi.y &&
               lo.z <= other.hi.z && other.lo.z <= hi.z;
    }
};

inline Box3 point_box(Point3 p) { return {p, p}; }

inline Box3 triangle_box(Point3 a, Point3 b, Point3 c) {
    Box3 box = point_box(a);
    box.add(b);
    box.add(c);
    return box;
}

// Coordinates for sums of products of lengths, whose terms grow with the coordinates' size and
// distance from the origin: origin at the centre of `box`, unit 2^e for its largest half-extent
// in [2^e, 2^(e+1)). Multiplying by a power of two is exact, so a model scaled by one gets the
// same frame coordinates.
struct PowerOfTwoFrame {
    Point3 centre{};
    double scale = 1.0;    // frame units per coordinate unit, 2^-e
    double unscale = 1.0;  // 2^e
    Point3 local(Point3 p) const { return {(p.x - centre.x) * scale, (p.y - centre.y) * scale, (p.z - centre.z) * scale}; }
};

inline PowerOfTwoFrame frame_around(const Box3& box) {
    // (Halves first: the sum or difference of two coordinates near the largest double overflows.)
    PowerOfTwoFrame frame;
    frame.centre = {0.5 * box.lo.x + 0.5 * box.hi.x, 0.5 * box.lo.y + 0.5 * box.hi.y, 0.5 * box.lo.z + 0.5 * box.hi.z};
    const double largest = std::max({0.5 * box.hi.x - 0.5 * box.lo.x, 0.5 * box.hi.y - 0.5 * box.lo.y, 0.5 * box.hi.z - 0.5 * box.lo.z});
    // (Both 2^±e normal doubles; an empty or degenerate box keeps the unit.)
    const int e = largest > 0 && std::isfinite(largest) ? std::clamp(std::ilogb(largest), -1000, 1000) : 0;
    frame.scale = std::ldexp(1.0, -e);
    frame.unscale = std::ldexp(1.0, e);
    return frame;
}

}  // namespace toposimp
