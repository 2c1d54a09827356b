// locate_in_ring on the hard cases, and RingLocator (its edges found by rows of y) giving the same
// answer as locate_in_ring for every point: on vertices, on edges, on horizontal edges, at the
// y of a vertex, an ulp away, outside the ring's y range; rings with edges spanning every row.
#include "core/exact/point_in_ring.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace toposimp::exact {
namespace {

RingLocation locate(const std::vector<Point>& ring, Point p) {
    PredicateStats stats;
    return locate_in_ring(ring, p, stats);
}

TEST(LocateInRing, BasicAndOneUlpCases) {
    const std::vector<Point> square = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {0, 0}};
    EXPECT_EQ(locate(square, {1, 1}), RingLocation::inside);
    EXPECT_EQ(locate(square, {3, 1}), RingLocation::outside);
    EXPECT_EQ(locate(square, {2, 1}), RingLocation::boundary);
    EXPECT_EQ(locate(square, {0, 0}), RingLocation::boundary);
    EXPECT_EQ(locate(square, {1, 2}), RingLocation::boundary);  // on a horizontal edge
    EXPECT_EQ(locate(square, {std::nextafter(2.0, 3.0), 1}), RingLocation::outside);
    EXPECT_EQ(locate(square, {std::nextafter(2.0, 1.0), 1}), RingLocation::inside);
    // The diagonal 0,0–3,1 of a triangle: 1/3 is not a double, so the point nearest it is off the
    // edge, on one side or the other, and the exact test says which.
    const std::vector<Point> triangle = {{0, 0}, {3, 1}, {0, 1}};
    const Point below{1, std::nextafter(1.0 / 3.0, 0.0)}, above{1, std::nextafter(1.0 / 3.0, 1.0)};
    EXPECT_EQ(locate(triangle, below), RingLocation::outside);
    EXPECT_EQ(locate(triangle, above), RingLocation::inside);
}

// Every point of a lattice covering the ring (vertices, edge points and ulp neighbours among them)
// gets the same answer from both.
void expect_same_answers(const std::vector<Point>& ring, const std::vector<Point>& points) {
    const RingLocator locator(ring);
    PredicateStats stats;
    for (const Point p : points) {
        ASSERT_EQ(locator.locate(p, stats), locate_in_ring(ring, p, stats)) << "point (" << p.x << ", " << p.y << ")";
    }
}

std::vector<Point> probes(const std::vector<Point>& ring) {
    std::vector<Point> points;
    for (const Point q : ring) {
        for (const double dx : {-1.0, 0.0, 1.0}) {
            for (const double dy : {-1.0, 0.0, 1.0}) {
                points.push_back({dx < 0 ? std::nextafter(q.x, -INFINITY) : dx > 0 ? std::nextafter(q.x, INFINITY) : q.x,
                                  dy < 0 ? std::nextafter(q.y, -INFINITY) : dy > 0 ? std::nextafter(q.y, INFINITY) : q.y});
            }
        }
    }
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {  // midpoints (on or next to the edges)
        points.push_back({0.5 * (ring[i].x + ring[i + 1].x), 0.5 * (ring[i].y + ring[i + 1].y)});
    }
    return points;
}

TEST(RingLocator, SameAnswersAsLocateInRingOnRandomRings) {
    std::mt19937_64 rng(25);
    for (int trial = 0; trial < 16; ++trial) {
        // A star-shaped ring around the origin (radii random, some repeated: horizontal and
        // collinear runs), on an integer lattice so that many probes fall exactly on edges.
        const int n = 8 + trial * 50;
        std::uniform_int_distribution<int> radius(1, 60);
        std::vector<Point> ring;
        for (int k = 0; k < n; ++k) {
            const double angle = 2 * M_PI * k / n;
            const double r = radius(rng);
            ring.push_back({std::round(r * std::cos(angle)), std::round(r * std::sin(angle))});
        }
        if (trial % 2 == 0) ring.push_back(ring.front());  // closing vertex, or not
        std::vector<Point> points = probes(ring);
        std::uniform_int_distribution<int> lattice(-62, 62);
        for (int k = 0; k < 600; ++k) points.push_back({static_cast<double>(lattice(rng)), static_cast<double>(lattice(rng))});
        for (int k = 0; k < 200; ++k) points.push_back({lattice(rng) * 0.5, lattice(rng) * 0.5});
        expect_same_answers(ring, points);
    }
}

// Edges spanning the whole height (a zigzag): rows are reduced until each edge is in few; the
// answers stay those of locate_in_ring. Huge and tiny coordinates too.
TEST(RingLocator, ZigzagsAndExtremeCoordinates) {
    for (const double scale : {1.0, 1e300, 1e-300}) {
        std::vector<Point> zigzag;
        for (int k = 0; k < 200; ++k) zigzag.push_back({k * scale, (k % 2 == 0 ? 0.0 : 1000.0) * scale});
        zigzag.push_back({199 * scale, -10 * scale});
        zigzag.push_back({0, -10 * scale});
        std::vector<Point> points = probes(zigzag);
        for (int k = 0; k < 1000; ++k) points.push_back({(k % 203) * scale * 0.99, ((k * 37) % 1013 - 5) * scale});
        expect_same_answers(zigzag, points);
    }
    // A flat ring (every vertex at one y): one row, no height.
    const std::vector<Point> flat = {{0, 5}, {4, 5}, {9, 5}, {2, 5}};
    expect_same_answers(flat, {{1, 5}, {10, 5}, {-1, 5}, {3, 5.5}, {3, std::nextafter(5.0, 6.0)}});
    expect_same_answers({}, {{0, 0}});
}

}  // namespace
}  // namespace toposimp::exact
