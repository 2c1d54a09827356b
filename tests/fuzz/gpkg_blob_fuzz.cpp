// Fuzz target: the GeoPackage point blob decoder (GeoPackage binary header + ISO WKB Point or
// MultiPoint) that reads control points past OGR. Any bytes: decoded, refused or found
// non-finite, never read past their end; what is decoded is finite or the empty point.
#include "io/map/gpkg_points.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

using namespace toposimp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<Point> points;
    if (io::decode_point_blob(data, size, points) == io::PointBlob::ok) {
        for (const Point& p : points) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y)) std::abort();
        }
    }
    return 0;
}
