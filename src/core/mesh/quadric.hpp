// Garland–Heckbert error quadrics (Garland & Heckbert 1997): the sum of squared distances to a
// set of planes, as a symmetric 4×4 matrix, which a collapse adds and minimises.
#pragma once

#include "core/geometry.hpp"

namespace toposimp::mesh::detail {

// A symmetric 4×4 quadric (Garland & Heckbert 1997) plus the area it was built from. Zero when
// value-initialised (`Quadric q{}`); default-initialised, undefined, so that the per-vertex array
// can be first written in parallel.
struct Quadric {
    double xx, xy, xz, xw, yy, yz, yw, zz, zw, ww, area;

    void add_plane(double a, double b, double c, double d, double weight) {
        xx += weight * a * a, xy += weight * a * b, xz += weight * a * c, xw += weight * a * d;
        yy += weight * b * b, yz += weight * b * c, yw += weight * b * d;
        zz += weight * c * c, zw += weight * c * d, ww += weight * d * d;
    }
    Quadric& operator+=(const Quadric& q) {
        xx += q.xx, xy += q.xy, xz += q.xz, xw += q.xw, yy += q.yy, yz += q.yz, yw += q.yw;
        zz += q.zz, zw += q.zw, ww += q.ww, area += q.area;
        return *this;
    }
    double operator()(Point3 p) const {
        const double x = p.x, y = p.y, z = p.z;
        return x * (xx * x + 2 * (xy * y + xz * z + xw)) + y * (yy * y + 2 * (yz * z + yw)) + z * (zz * z + 2 * zw) + ww;
    }
};

inline Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

}  // namespace toposimp::mesh::detail
