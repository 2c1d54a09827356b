// GEOS, the only part of toposimp that uses it: polygon validity (IsValidOp) and where two
// segments meet, for `toposimp check`. Never a yes/no question about contacts or sides: the
// exact predicates decide those.
#pragma once

#include "core/geometry.hpp"

#include <geos_c.h>
#include <ogr_geometry.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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
        return invalid_reason(geometry.exportToGEOS(handle_), where);
    }

    // The same for polygons given as rings, `rings_per_polygon[i]` rings (shell first) for
    // polygon i: a polygon if there is one, else a multipolygon.
    std::optional<std::string> invalid_reason(const std::vector<std::vector<Point>>& rings,
                                              const std::vector<std::uint32_t>& rings_per_polygon, Point& where) const {
        return invalid_reason(polygons(rings, rings_per_polygon), where);
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
    // Takes `g` (null: GEOS could not make it).
    std::optional<std::string> invalid_reason(GEOSGeometry* g, Point& where) const {
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

    // GEOS polygons from rings (as invalid_reason takes them); null if GEOS refuses a ring (not
    // closed, too few points: as it refuses them in a geometry OGR hands it).
    GEOSGeometry* polygons(const std::vector<std::vector<Point>>& rings, const std::vector<std::uint32_t>& rings_per_polygon) const {
        std::vector<GEOSGeometry*> made;
        auto drop = [&] {
            for (GEOSGeometry* g : made) GEOSGeom_destroy_r(handle_, g);
            return nullptr;
        };
        std::size_t next = 0;
        for (const std::uint32_t count : rings_per_polygon) {
            std::vector<GEOSGeometry*> ring_geometries;
            for (std::uint32_t k = 0; k < count; ++k) {
                const std::vector<Point>& ring = rings.at(next++);
                GEOSCoordSequence* sequence = GEOSCoordSeq_create_r(handle_, static_cast<unsigned>(ring.size()), 2);
                for (std::size_t i = 0; i < ring.size(); ++i) GEOSCoordSeq_setXY_r(handle_, sequence, static_cast<unsigned>(i), ring[i].x, ring[i].y);
                GEOSGeometry* linear = sequence ? GEOSGeom_createLinearRing_r(handle_, sequence) : nullptr;
                if (linear == nullptr) {
                    for (GEOSGeometry* g : ring_geometries) GEOSGeom_destroy_r(handle_, g);
                    return drop();
                }
                ring_geometries.push_back(linear);
            }
            GEOSGeometry* polygon = ring_geometries.empty()
                                        ? nullptr
                                        : GEOSGeom_createPolygon_r(handle_, ring_geometries[0], ring_geometries.data() + 1,
                                                                   static_cast<unsigned>(ring_geometries.size() - 1));
            if (polygon == nullptr) return drop();  // (GEOS has destroyed the rings it was given)
            made.push_back(polygon);
        }
        if (made.size() == 1) return made[0];
        // (GEOS owns the polygons from here, made or not.)
        return GEOSGeom_createCollection_r(handle_, GEOS_MULTIPOLYGON, made.data(), static_cast<unsigned>(made.size()));
    }

    GEOSContextHandle_t handle_;
};

}  // namespace toposimp::validate
