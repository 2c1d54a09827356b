#include "core/exact/segments.hpp"

#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace toposimp::exact {
namespace {

bool improper(Point p, Point q, Point r, Point s) {
    PredicateStats stats;
    return improper_contact(p, q, r, s, Arithmetic::exact, stats);
}

TEST(ImproperContact, ClassifiesTheBasicCases) {
    EXPECT_TRUE(improper({0, 0}, {2, 2}, {0, 2}, {2, 0}));    // crossing
    EXPECT_FALSE(improper({0, 0}, {2, 2}, {2, 2}, {3, 0}));   // shared endpoint
    EXPECT_TRUE(improper({0, 0}, {2, 2}, {1, 1}, {3, 0}));    // T: endpoint inside the other
    EXPECT_TRUE(improper({0, 0}, {2, 0}, {1, 0}, {3, 0}));    // collinear overlap
    EXPECT_FALSE(improper({0, 0}, {1, 0}, {1, 0}, {3, 0}));   // collinear, end to end
    EXPECT_FALSE(improper({0, 0}, {1, 0}, {2, 0}, {3, 0}));   // collinear, apart
    EXPECT_TRUE(improper({0, 0}, {2, 0}, {2, 0}, {0, 0}));    // the same segment twice
    EXPECT_TRUE(improper({1, 0}, {1, 0}, {0, 0}, {2, 0}));    // a point inside a segment
    EXPECT_FALSE(improper({0, 0}, {0, 0}, {0, 0}, {2, 0}));   // a point at an end
    EXPECT_FALSE(improper({0, 0}, {1, 1}, {0, 1}, {0.4, 2})); // apart
}

TEST(ImproperContact, OneUlpFromTouching) {
    const double above = std::nextafter(1.0, 2.0), below = std::nextafter(1.0, 0.0);
    EXPECT_TRUE(improper({0, 0}, {2, 2}, {1, 1}, {1, 5}));
    EXPECT_FALSE(improper({0, 0}, {2, 2}, {1, above}, {1, 5}));
    EXPECT_TRUE(improper({0, 0}, {2, 2}, {1, below}, {1, 5}));
}

// Agrees with the tests' independent all-GMP version on random near-degenerate cases.
TEST(ImproperContact, AgreesWithIndependentChecker) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(-1, 1);
    int improper_cases = 0;
    for (int k = 0; k < 20000; ++k) {
        const double scale = k % 2 ? 1e6 : 1e-6;
        auto random_point = [&] { return Point{3e5 * (k % 3) + scale * unit(rng), scale * unit(rng)}; };
        const Point p = random_point(), q = random_point(), r = random_point();
        const double t = unit(rng);
        Point s{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};  // on or within rounding of pq's line
        if (k % 4 == 0) s = q;
        const bool ours = improper(p, q, r, s);
        ASSERT_EQ(ours, testing::improper_contact(p, q, r, s)) << k;
        improper_cases += ours;
    }
    EXPECT_GT(improper_cases, 1000);
}

}  // namespace
}  // namespace toposimp::exact
