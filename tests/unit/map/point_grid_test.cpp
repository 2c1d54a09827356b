#include "core/map/point_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// Built in parallel, the grid is the same for any thread count: every id once, in the cell its
// coordinates map to, each cell sorted by x with ties by id.
TEST(PointGrid, SameCellsForAnyThreadCountEachSortedByXThenId) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Point> first(40000), second(30000);
    for (auto& p : first) p = {std::floor(unit(rng) * 300) / 3, unit(rng) * 50};  // many equal x
    for (auto& p : second) p = first[static_cast<std::size_t>(unit(rng) * 1000)];  // duplicates of the first
    const PointGrid one(first, second, 2.0, 1);
    std::vector<int> seen(first.size() + second.size(), 0);
    for (std::uint32_t y = 0; y < one.rows(); ++y) {
        for (std::uint32_t x = 0; x < one.columns(); ++x) {
            const auto ids = one.cell_ids(x, y);
            const auto points = one.cell_points(x, y);
            for (std::size_t k = 0; k < ids.size(); ++k) {
                ++seen[ids[k]];
                const Point p = ids[k] < first.size() ? first[ids[k]] : second[ids[k] - first.size()];
                ASSERT_TRUE(same_location(points[k], p));
                ASSERT_EQ(one.column(p.x), x);
                ASSERT_EQ(one.row(p.y), y);
                if (k > 0) {
                    ASSERT_TRUE(points[k - 1].x < p.x || (points[k - 1].x == p.x && ids[k - 1] < ids[k]));
                }
            }
        }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<std::ptrdiff_t>(seen.size()));
    for (const int threads : {2, 3, 7}) {
        const PointGrid other(first, second, 2.0, threads);
        ASSERT_EQ(other.columns(), one.columns());
        ASSERT_EQ(other.rows(), one.rows());
        for (std::uint32_t y = 0; y < one.rows(); ++y) {
            for (std::uint32_t x = 0; x < one.columns(); ++x) {
                const auto a = one.cell_ids(x, y), b = other.cell_ids(x, y);
                ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end())) << threads << " threads, cell " << x << ", " << y;
            }
        }
    }
}

}  // namespace
}  // namespace toposimp::map
