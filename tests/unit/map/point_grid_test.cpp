#include "core/map/point_grid.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace toposimp::map {
namespace {

std::set<std::uint32_t> in_cells(const PointGrid& grid, const Box& box) {
    std::set<std::uint32_t> ids;
    grid.any_in_cells(box, [&](std::uint32_t id, Point) {
        ids.insert(id);
        return false;
    });
    return ids;
}

void expect_no_point_missed(const std::vector<Point>& points, const Box& box) {
    const PointGrid grid(points);
    const auto found = in_cells(grid, box);
    for (std::uint32_t i = 0; i < points.size(); ++i) {
        if (box_contains(box, points[i])) {
            EXPECT_TRUE(found.count(i)) << "point " << i << " missed";
        }
    }
}

TEST(PointGrid, NeverMissesAPointInsideAQueryBox) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Point> points(2000);
    for (auto& p : points) p = {unit(rng) * 1e3, unit(rng) * 10};
    for (int k = 0; k < 200; ++k) {
        const double x = unit(rng) * 1e3, y = unit(rng) * 10;
        expect_no_point_missed(points, {x, y, x + unit(rng) * 50, y + unit(rng)});
    }
    // Boxes whose edges are exactly points' coordinates.
    for (int k = 0; k < 200; ++k) {
        const Point p = points[k], q = points[k + 1];
        expect_no_point_missed(points, triangle_box(p, q, p));
    }
}

TEST(PointGrid, HandlesDegenerateAndExtremeExtents) {
    expect_no_point_missed({{1, 1}, {1, 1}, {1, 1}}, {1, 1, 1, 1});
    expect_no_point_missed({{0, 0}, {0, 5}, {0, 9}}, {0, 4, 0, 9});
    const double big = 1.7e308;
    expect_no_point_missed({{-big, -big}, {big, big}, {0, 0}, {1e-300, 1e-300}}, {0, 0, 1e-300, 1e-300});
    expect_no_point_missed({{-big, 0}, {big, 0}, {0, 0}}, {-big, 0, big, 0});
}

TEST(PointGrid, RemovedPointsAreNotVisited) {
    const std::vector<Point> points{{0, 0}, {1, 1}, {2, 2}};
    PointGrid grid(points);
    grid.remove(1);
    const auto found = in_cells(grid, {0, 0, 2, 2});
    EXPECT_EQ(found, (std::set<std::uint32_t>{0, 2}));
}

}  // namespace
}  // namespace toposimp::map
