// count_locations (core/map/location_key.hpp): the rings' distinct locations, which the ring rule
// counts down from, against sorting the locations and dropping repeats.
#include "core/map/location_key.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace toposimp::map {
namespace {

std::uint32_t sorted_count(const std::vector<Point>& points) {
    std::vector<LocationKey> keys(points.begin(), points.end());
    std::sort(keys.begin(), keys.end());
    return static_cast<std::uint32_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

// Every size from none to past the pair-by-pair cut (8) and a few big ones, the points drawn
// from `pool` (so that repeats come often when it is small), one table reused throughout.
void expect_counts(const std::vector<Point>& pool, const std::string& what) {
    std::mt19937_64 rng(7);
    std::vector<std::uint32_t> table;
    for (const std::size_t n : {0, 1, 2, 3, 7, 8, 9, 10, 16, 17, 100, 1000, 65537}) {
        for (int round = 0; round < 3; ++round) {
            std::vector<Point> points(n);
            std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
            for (Point& p : points) p = pool[pick(rng)];
            EXPECT_EQ(count_locations(points, table), sorted_count(points)) << what << ", " << n << " points";
        }
    }
}

TEST(CountLocations, AgreesWithSortingOnRepeatsAndNeighbouringDoubles) {
    // Points an ulp apart, in x, in y or both, at ordinary, huge, tiny and subnormal sizes: all
    // distinct locations.
    for (const double at : {1.0, 1e300, 1e-300, std::numeric_limits<double>::denorm_min() * 3, 123456789.123}) {
        std::vector<Point> pool;
        for (const double x : {at, std::nextafter(at, 0.0), std::nextafter(at, INFINITY), -at}) {
            for (const double y : {at, std::nextafter(at, 0.0), -at, 0.5 * at}) pool.push_back({x, y});
        }
        expect_counts(pool, "around " + std::to_string(at));
    }
    // −0 and 0 are one location.
    expect_counts({{0.0, 0.0}, {-0.0, 0.0}, {0.0, -0.0}, {-0.0, -0.0}, {1, 0}}, "zeros");
    std::vector<Point> zeros(20, Point{0.0, 0.0});
    for (std::size_t k = 0; k < zeros.size(); k += 2) zeros[k] = {-0.0, -0.0};
    std::vector<std::uint32_t> table;
    EXPECT_EQ(count_locations(zeros, table), 1u);
    // One location repeated: 1; all distinct along a line (x alone differs, then y alone).
    EXPECT_EQ(count_locations(std::vector<Point>(1000, Point{5, 5}), table), 1u);
    std::vector<Point> row, column;
    for (int k = 0; k < 5000; ++k) {
        row.push_back({static_cast<double>(k), 7});
        column.push_back({7, k * 1e-3});
    }
    EXPECT_EQ(count_locations(row, table), 5000u);
    EXPECT_EQ(count_locations(column, table), 5000u);
    // A big pool: few repeats.
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::vector<Point> pool(50000);
    for (Point& p : pool) p = {unit(rng), unit(rng)};
    expect_counts(pool, "a big pool");
}

}  // namespace
}  // namespace toposimp::map
