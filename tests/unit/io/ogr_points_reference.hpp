// The reference the fast control-point readers are checked against: the points of a layer as
// OGR reads them, feature by feature; and the bit-for-bit comparison with it.
#pragma once

#include "core/geometry.hpp"
#include "io/ogr/gdal_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

namespace toposimp::io {

inline std::vector<Point> points_read_by_ogr(const std::string& path) {
    std::vector<Point> points;
    DatasetPtr dataset = open_vector(path);
    OGRLayer* layer = dataset->GetLayer(0);
    while (OGRFeatureUniquePtr feature{layer->GetNextFeature()}) {
        const OGRGeometry* geometry = feature->GetGeometryRef();
        if (geometry == nullptr) continue;
        auto add = [&](const OGRPoint& p) {
            if (!p.IsEmpty()) points.push_back({p.getX(), p.getY()});
        };
        if (wkbFlatten(geometry->getGeometryType()) == wkbPoint) {
            add(*geometry->toPoint());
        } else {
            for (const OGRPoint* p : *geometry->toMultiPoint()) add(*p);
        }
    }
    return points;
}

inline void expect_same_points(const std::vector<Point>& got, const std::vector<Point>& want) {
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
        EXPECT_TRUE(std::memcmp(&got[i], &want[i], sizeof(Point)) == 0)
            << "point " << i << ": (" << got[i].x << ", " << got[i].y << ") != (" << want[i].x << ", " << want[i].y << ")";
    }
}

}  // namespace toposimp::io
