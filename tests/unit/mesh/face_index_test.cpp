// The mesh face index stands in front of the exact contact tests: a face it fails to return for
// a box is a contact never checked. It may return more (boxes are rounded outward to each cell's
// 8-bit coordinates), never fewer, and each face once. Checked here against a scan of every face,
// on the hard cases: corners exactly on cell boundaries and one ulp either side, boxes that only
// touch, points, faces beyond the grid (clamped into its border cells), and grids far from the
// origin or of tiny cells.
#include "core/mesh/face_index.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

namespace toposimp::mesh::detail {
namespace {

struct Scene {
    Grid grid;
    std::vector<Point3> points;
    std::vector<Face> faces;
    std::vector<std::uint8_t> alive;
};

// Coordinates in cells from the grid's origin: on a boundary, an ulp beside one, or anywhere
// (also outside the grid's 16 cells a side).
class Coordinates {
public:
    Coordinates(const Grid& grid, unsigned seed) : grid_(grid), random_(seed) {}

    double at(int axis) {
        const double cell = std::uniform_int_distribution<int>(-1, 17)(random_);
        double units = cell;
        switch (std::uniform_int_distribution<int>(0, 3)(random_)) {
            case 0: break;  // on a boundary
            case 1: units = std::uniform_real_distribution<double>(-1.5, 17.5)(random_); break;
            default: break;
        }
        double value = grid_.origin[axis] + units / grid_.inverse_size;
        switch (std::uniform_int_distribution<int>(0, 3)(random_)) {
            case 0: value = std::nextafter(value, -INFINITY); break;
            case 1: value = std::nextafter(value, INFINITY); break;
            default: break;
        }
        return value;
    }
    // Near `from`: up to `reach` cells away on each axis, sometimes exactly on it.
    double near(double from, int axis, double reach) {
        if (std::uniform_int_distribution<int>(0, 4)(random_) == 0) return from;
        const double step = std::uniform_real_distribution<double>(-reach, reach)(random_) / grid_.inverse_size;
        return std::uniform_int_distribution<int>(0, 2)(random_) == 0 ? at(axis) : from + step;
    }
    Point3 point() { return {at(0), at(1), at(2)}; }
    Point3 near(Point3 p, double reach) { return {near(p.x, 0, reach), near(p.y, 1, reach), near(p.z, 2, reach)}; }
    bool one_in(int n) { return std::uniform_int_distribution<int>(0, n - 1)(random_) == 0; }
    std::size_t index(std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(random_); }

private:
    const Grid& grid_;
    std::mt19937 random_;
};

Scene scene(Point3 origin, double cell_size, unsigned seed) {
    Scene s;
    s.grid.origin = origin;
    s.grid.inverse_size = 1 / cell_size;
    s.grid.cells = {16, 16, 16};
    Coordinates at(s.grid, seed);
    for (int f = 0; f < 3000; ++f) {
        const Point3 a = at.point();
        const double reach = at.one_in(10) ? 6 : 1.5;  // most faces span one or two cells, some many
        const Point3 b = at.one_in(20) ? a : at.near(a, reach), c = at.one_in(20) ? a : at.near(a, reach);
        const auto first = static_cast<std::uint32_t>(s.points.size());
        s.points.insert(s.points.end(), {a, b, c});
        s.faces.push_back({first, first + 1, first + 2});
        s.alive.push_back(at.one_in(10) ? 0 : 1);
    }
    return s;
}

Box3 box_of(const Scene& s, std::uint32_t f) {
    const Face& c = s.faces[f];
    return triangle_box(s.points[c[0]], s.points[c[1]], s.points[c[2]]);
}

// Every query box: the faces whose box meets it (`box_now` of each live face) are all returned,
// none twice.
template <class BoxNow>
void expect_complete(const Scene& s, const FaceIndex& index, const Overlay& overlay, unsigned seed, BoxNow box_now) {
    Coordinates at(s.grid, seed);
    std::vector<std::uint32_t> found;
    for (int q = 0; q < 600; ++q) {
        Box3 query;
        if (at.one_in(3)) {
            // Touching a face's box: a corner of the query on one of its sides.
            const Box3 target = box_now(static_cast<std::uint32_t>(at.index(s.faces.size())));
            const Point3 corner = at.one_in(2) ? target.hi : target.lo;
            query = triangle_box(corner, at.near(corner, 1.5), at.one_in(4) ? corner : at.near(corner, 1.5));
        } else {
            const Point3 p = at.point();
            query = triangle_box(p, at.one_in(5) ? p : at.near(p, 2), at.near(p, 2));
        }
        index.query(query, overlay, found);
        const std::set<std::uint32_t> returned(found.begin(), found.end());
        ASSERT_EQ(returned.size(), found.size()) << "a face returned twice, query " << q;
        for (std::uint32_t f = 0; f < s.faces.size(); ++f) {
            if (!s.alive[f] || !box_now(f).overlaps(query)) continue;
            ASSERT_TRUE(returned.count(f)) << "face " << f << " meets query " << q << " and was not returned";
        }
    }
}

void check_grid(Point3 origin, double cell_size, unsigned seed) {
    Scene s = scene(origin, cell_size, seed);
    for (const int threads : {1, 2}) {
        FaceIndex index;
        index.build(s.grid, s.faces, s.points, s.alive, threads);
        const Overlay none;
        expect_complete(s, index, none, seed + 1, [&](std::uint32_t f) { return box_of(s, f); });
    }
    // Faces a block changes: some move (found by their box now, from the overlay, not by the one
    // the index has), some die (never returned).
    FaceIndex index;
    index.build(s.grid, s.faces, s.points, s.alive, 2);
    Overlay overlay;
    Coordinates at(s.grid, seed + 2);
    for (int k = 0; k < 400; ++k) {
        const auto f = static_cast<std::uint32_t>(at.index(s.faces.size()));
        if (!s.alive[f]) continue;
        index.leave_overlay(f, box_of(s, f), overlay);
        if (at.one_in(4)) {
            s.alive[f] = 0;
            index.mark_changed(f);
            continue;
        }
        s.points[s.faces[f][at.index(3)]] = at.near(s.points[s.faces[f][0]], 1.5);
        index.enter_overlay(f, box_of(s, f), overlay);
    }
    expect_complete(s, index, overlay, seed + 3, [&](std::uint32_t f) { return box_of(s, f); });
}

TEST(FaceIndex, ReturnsEveryFaceWhoseBoxMeetsTheQuery) { check_grid({0, 0, 0}, 1.0, 11); }

TEST(FaceIndex, ReturnsEveryFaceFarFromTheOrigin) { check_grid({6.0e12, -3.0e11, 1.0e10}, 0.375, 12); }

TEST(FaceIndex, ReturnsEveryFaceInTinyCells) { check_grid({1e-290, -2e-290, 0}, 3e-300, 13); }

TEST(FaceIndex, ReturnsEveryFaceInHugeCells) { check_grid({-1e300, 0, 1e300}, 1e299, 14); }

// The 8-bit cell coordinates round outward: where a box begins is never after where it does, nor
// where it ends before, in every cell of its span.
TEST(FaceIndex, CellCoordinatesRoundOutward) {
    std::mt19937 random(5);
    std::uniform_real_distribution<double> where(0, 1);
    for (int k = 0; k < 100000; ++k) {
        const std::uint32_t c = std::uniform_int_distribution<std::uint32_t>(0, 1u << 20)(random);
        const double lo = c + where(random), hi = std::min(lo + where(random), c + 1.0);
        const double other = c + where(random);  // another box's end in the same cell
        // Ordered as the real values are.
        if (lo <= other) {
            ASSERT_LE(cell_lo(lo, c, c), cell_hi(other, c, c)) << lo << " " << other;
        }
        if (other <= hi) {
            ASSERT_LE(cell_lo(other, c, c), cell_hi(hi, c, c)) << other << " " << hi;
        }
        ASSERT_GE(cell_lo(lo, c, c), 1);
        ASSERT_LE(cell_hi(hi, c, c), 255);
    }
    EXPECT_EQ(cell_lo(7.0, 6, 7), 0);     // begins in an earlier cell
    EXPECT_EQ(cell_hi(7.5, 8, 7), 255);   // ends in a later one
    EXPECT_EQ(cell_lo(7.0, 7, 7), 1);     // on the cell's low boundary
    EXPECT_EQ(cell_hi(7.0, 7, 7), 1);     // a box ending there touches one beginning there
    EXPECT_EQ(cell_hi(8.0, 7, 7), 255);   // (the last cell of a clamped grid)
    EXPECT_EQ(cell_lo(std::nan(""), 7, 7), 1);
    EXPECT_EQ(cell_hi(std::nan(""), 7, 7), 255);
}

}  // namespace
}  // namespace toposimp::mesh::detail
