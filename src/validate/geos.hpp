// GEOS, the only part of toposimp that uses it: polygon validity (IsValidOp) and where two
// segments meet, for `toposimp check`. Never a yes/no question about contacts or sides: the
// exact predicates decide those.
#pragma once

#include "core/geometry.hpp"

#include <geos_c.h>
#include <ogr_geometry.h>

#include <optional>
#include <string>

namespace toposimp::validate {

// GEOS, once per check.
class Geos {
public:
    Geos() : handle_(GEOS_init_r()) {}
    ~Geos() { GEOS_finish_r(handle_); }
    Geos(const Geos&) = delete;
    Geos& operator=(const Geos&) = delete;
    GEOSContextHandle_t handle() const { return handle_; }

    // IsValidOp on a polygon geometry: empty if valid, else the reason; `where` gets the location.
    std::optional<std::string> invalid_reason(const OGRGeometry& geometry, Point& where) const {
        GEOSGeometry* g = geometry.exportToGEOS(handle_);
        if (g == nullptr) return std::string("GEOS cannot read the geometry");
        char* reason = nullptr;
        GEOSGeometry* location = nullptr;
        const char valid = GEOSisValidDetail_r(handle_, g, 0, &reason, &location);
        std::optional<std::string> result;
        if (valid == 0) {
            result = reason ? reason : "invalid";
            if (location) {
                GEOSGeomGetX_r(handle_, location, &where.x);
                GEOSGeomGetY_r(handle_, location, &where.y);
            }
        }
        if (reason) GEOSFree_r(handle_, reason);
        if (location) GEOSGeom_destroy_r(handle_, location);
        GEOSGeom_destroy_r(handle_, g);
        return result;
    }

    // Where segments pq and rs meet (a point of their intersection).
    Point meeting_point(Point p, Point q, Point r, Point s) const {
        auto segment = [&](Point a, Point b) {
            GEOSCoordSequence* sequence = GEOSCoordSeq_create_r(handle_, 2, 2);
            GEOSCoordSeq_setXY_r(handle_, sequence, 0, a.x, a.y);
            GEOSCoordSeq_setXY_r(handle_, sequence, 1, b.x, b.y);
            return GEOSGeom_createLineString_r(handle_, sequence);
        };
        GEOSGeometry* a = segment(p, q);
        GEOSGeometry* b = segment(r, s);
        Point where{(p.x + q.x) / 2, (p.y + q.y) / 2};
        if (GEOSGeometry* meet = GEOSIntersection_r(handle_, a, b)) {
            if (!GEOSisEmpty_r(handle_, meet)) {
                if (GEOSGeometry* centre = GEOSGetCentroid_r(handle_, meet)) {
                    GEOSGeomGetX_r(handle_, centre, &where.x);
                    GEOSGeomGetY_r(handle_, centre, &where.y);
                    GEOSGeom_destroy_r(handle_, centre);
                }
            }
            GEOSGeom_destroy_r(handle_, meet);
        }
        GEOSGeom_destroy_r(handle_, a);
        GEOSGeom_destroy_r(handle_, b);
        return where;
    }

private:
    GEOSContextHandle_t handle_;
};

}  // namespace toposimp::validate
