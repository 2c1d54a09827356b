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

// Crowded cells (hundreds of points along lines, clusters at one x, equal x runs) are searched
// from where the query's left edge would fall if their points were even: the points in the box
// are still all found, and the first point in (base row, x, id) order is the one brute force
// finds — whole grid and window, with and without split rows.
TEST(PointGrid, CrowdedCellsAnswerAsBruteForce) {
    std::mt19937_64 rng(35);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Point> points;
    for (int k = 0; k < 3000; ++k) points.push_back({unit(rng) * 100, 30 + unit(rng) * 1e-3});  // a thin band
    for (int k = 0; k < 3000; ++k) points.push_back({70 + unit(rng) * 1e-9, unit(rng) * 100});  // almost one x
    for (int k = 0; k < 1000; ++k) points.push_back({std::floor(unit(rng) * 4) * 25, unit(rng) * 100});  // equal x
    for (int k = 0; k < 2000; ++k) points.push_back({unit(rng) * 100, unit(rng) * 100});
    points.push_back({0, 0});
    points.push_back({100, 100});
    for (const unsigned split : {0u, 2u}) {
        const PointGrid whole(points, {}, 2.0, 1, split);
        const PointGrid::Window window{whole.columns() / 4, whole.rows() / 4, whole.columns() * 3 / 4, whole.rows() * 3 / 4};
        const PointGrid part(whole.geometry(), window, points, {}, 1);
        const PointGrid::Geometry& g = whole.geometry();
        for (int k = 0; k < 3000; ++k) {
            const bool windowed = k % 2 == 1;
            const double span = k % 3 == 0 ? 1e-6 : k % 3 == 1 ? 0.5 : 20;
            Point a{unit(rng) * 100, unit(rng) * 100};
            if (k % 5 == 0) a = points[static_cast<std::size_t>(unit(rng) * static_cast<double>(points.size()))];  // on a point
            if (k % 7 == 0) a.x = 70;
            Box box{a.x, a.y, a.x + unit(rng) * span, a.y + unit(rng) * span};
            if (windowed) {
                // Keep the box inside the window's cells (queries of a window must be).
                const double x0 = g.origin_x + (window.first_column + 1) / g.scale_x, x1 = g.origin_x + window.last_column / g.scale_x;
                const double y0 = g.origin_y + (window.first_row + 1) / g.scale_y, y1 = g.origin_y + window.last_row / g.scale_y;
                box = {std::clamp(box.min_x, x0, x1), std::clamp(box.min_y, y0, y1), std::clamp(box.max_x, x0, x1),
                       std::clamp(box.max_y, y0, y1)};
            }
            const PointGrid& grid = windowed ? part : whole;
            std::set<std::uint32_t> inside;
            std::uint32_t first = PointGrid::kRemoved;
            auto earlier = [&](std::uint32_t i, std::uint32_t j) {
                const std::uint32_t ri = g.base_row(points[i].y), rj = g.base_row(points[j].y);
                if (ri != rj) return ri < rj;
                return points[i].x < points[j].x || (points[i].x == points[j].x && i < j);
            };
            for (std::uint32_t i = 0; i < points.size(); ++i) {
                if (!box_contains(box, points[i])) continue;
                inside.insert(i);
                if (first == PointGrid::kRemoved || earlier(i, first)) first = i;
            }
            std::set<std::uint32_t> found;
            grid.any_in_cells(box, [&](std::uint32_t id, Point q) {
                if (box_contains(box, q)) found.insert(id);
                return false;
            });
            ASSERT_EQ(found, inside) << "split " << split << ", query " << k;
            ASSERT_EQ(grid.first_in_cells(box, [&](std::uint32_t, Point q) { return box_contains(box, q); }), first)
                << "split " << split << ", query " << k;
        }
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

// Split rows (issue 34): no point inside a box is missed, a row's base row is its index shifted,
// and first_in_cells picks the point any_in_cells stops at on the unsplit grid — points crowded
// on lines, on equal x, at extreme and at one-ulp-apart coordinates, some taken out.
TEST(PointGrid, Issue34SplitRowsFindTheSameFirstPointAsTheBaseGrid) {
    std::mt19937_64 rng(34);
    std::uniform_real_distribution<double> unit(0, 1);
    for (const auto& [offset, scale] : {std::pair{0.0, 1.0}, std::pair{1e9, 1e-6}, std::pair{-1e300, 1e299}}) {
        std::vector<Point> points;
        for (int k = 0; k < 3000; ++k) {  // a "shoreline" and a scatter, many sharing x
            const double t = unit(rng);
            points.push_back({offset + scale * t * 100, offset + scale * (50 + 20 * std::sin(t * 40))});
            points.push_back({offset + scale * std::floor(unit(rng) * 60), offset + scale * unit(rng) * 100});
        }
        points.push_back({std::nextafter(points[0].x, INFINITY), points[0].y});
        const PointGrid base(points, {}, 2.0, 1, 0);
        for (const unsigned split : {1u, 2u, 3u}) {
            PointGrid grid(points, {}, 2.0, 1, split);
            PointGrid plain(points, {}, 2.0, 1, 0);
            for (std::uint32_t id = 0; id < points.size(); id += 7) {
                grid.remove(id);
                plain.remove(id);
            }
            for (const Point& p : points) ASSERT_EQ(grid.row(p.y) >> split, base.row(p.y));
            for (const Point& p : points) ASSERT_EQ(grid.base_column(p.x), base.column(p.x));
            for (int k = 0; k < 300; ++k) {
                const Point& corner = points[static_cast<std::size_t>(unit(rng) * static_cast<double>(points.size()))];
                const Box box{corner.x, corner.y, corner.x + scale * unit(rng) * 20, corner.y + scale * unit(rng) * 20};
                // (first_in_cells asks about taken-out points too, which accept refuses)
                auto accept = [&](std::uint32_t id, Point q) { return id != PointGrid::kRemoved && box_contains(box, q) && id % 3 != 0; };
                std::uint32_t expected = PointGrid::kRemoved;
                plain.any_in_cells(box, [&](std::uint32_t id, Point q) {
                    if (!accept(id, q)) return false;
                    expected = id;
                    return true;
                });
                EXPECT_EQ(grid.first_in_cells(box, accept), expected) << "split " << split << ", box " << k;
                std::set<std::uint32_t> inside;
                for (const std::uint32_t id : in_cells(grid, box)) {
                    if (box_contains(box, points[id])) inside.insert(id);
                }
                std::set<std::uint32_t> wanted;
                for (const std::uint32_t id : in_cells(plain, box)) {
                    if (box_contains(box, points[id])) wanted.insert(id);
                }
                EXPECT_EQ(inside, wanted);
            }
        }
    }
}

// A grid over a window of another grid's cells (a tile, core/map/tiles.hpp), holding the points
// inside the window in order and some outside it (kept in the window's edge cells): for boxes
// inside the window, the same first point and the same points as the whole grid.
TEST(PointGrid, AWindowAnswersAsTheWholeGridInsideIt) {
    std::mt19937_64 rng(26);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Point> points;
    for (int k = 0; k < 4000; ++k) {
        const double t = unit(rng);
        points.push_back({t * 100, 50 + 20 * std::sin(t * 40)});
        points.push_back({std::floor(unit(rng) * 60), unit(rng) * 100});
    }
    for (const unsigned split : {0u, 2u}) {
        const PointGrid whole(points, {}, 2.0, 1, split);
        const PointGrid::Geometry& g = whole.geometry();
        for (int trial = 0; trial < 20; ++trial) {
            const std::uint32_t c0 = static_cast<std::uint32_t>(unit(rng) * g.columns / 2), r0 = static_cast<std::uint32_t>(unit(rng) * g.rows / 2);
            const PointGrid::Window window{c0, r0, std::min(g.columns - 1, c0 + 1 + static_cast<std::uint32_t>(unit(rng) * g.columns / 2)),
                                           std::min(g.rows - 1, r0 + 1 + static_cast<std::uint32_t>(unit(rng) * g.rows / 2))};
            auto inside = [&](Point p) {
                const std::uint32_t x = g.column(p.x), y = g.row(p.y);
                return x >= window.first_column && x <= window.last_column && y >= window.first_row && y <= window.last_row;
            };
            std::vector<Point> part;
            std::vector<std::uint32_t> id_of;  // the part's points by id: their ids in `points`
            for (std::uint32_t id = 0; id < points.size(); ++id) {
                if (inside(points[id]) || id % 97 == 0) {  // (and a few from outside, as cut ends come)
                    part.push_back(points[id]);
                    id_of.push_back(id);
                }
            }
            const PointGrid tile(g, window, part, {}, 1);
            std::vector<std::uint32_t> in;
            for (std::uint32_t k = 0; k < part.size(); ++k) {
                if (inside(part[k])) in.push_back(k);
            }
            ASSERT_FALSE(in.empty());
            for (int k = 0; k < 100; ++k) {
                // A box between two points inside the window lies inside it (cells are monotone).
                const Point a = part[in[static_cast<std::size_t>(unit(rng) * static_cast<double>(in.size()))]];
                const Point b = part[in[static_cast<std::size_t>(unit(rng) * static_cast<double>(in.size()))]];
                const Box box{std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
                auto accept_whole = [&](std::uint32_t id, Point q) { return box_contains(box, q) && id % 3 != 0; };
                auto accept_tile = [&](std::uint32_t id, Point q) { return box_contains(box, q) && id_of[id] % 3 != 0; };
                const std::uint32_t expected = whole.first_in_cells(box, accept_whole);
                const std::uint32_t found = tile.first_in_cells(box, accept_tile);
                ASSERT_EQ(found == PointGrid::kRemoved ? PointGrid::kRemoved : id_of[found], expected) << "split " << split;
                std::set<std::uint32_t> from_tile, from_whole;
                for (const std::uint32_t id : in_cells(tile, box)) {
                    if (box_contains(box, part[id])) from_tile.insert(id_of[id]);
                }
                for (const std::uint32_t id : in_cells(whole, box)) {
                    if (box_contains(box, points[id])) from_whole.insert(id);
                }
                EXPECT_EQ(from_tile, from_whole);
            }
        }
    }
}

// `pairs` points on a wavy line across the map and as many in 60 columns of equal x (the first
// span), and 500 scattered ones (the second): crowded cells, equal x, and points alone.
std::pair<std::vector<Point>, std::vector<Point>> shore_and_columns(std::mt19937_64& rng, int pairs) {
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<Point> points, others;
    for (int k = 0; k < pairs; ++k) {
        const double t = unit(rng);
        points.push_back({t * 100, 50 + 20 * std::sin(t * 40)});
        points.push_back({std::floor(unit(rng) * 60), unit(rng) * 100});
    }
    for (int k = 0; k < 500; ++k) others.push_back({unit(rng) * 100, unit(rng) * 100});
    return {points, others};
}

// A grid built without the points already taken out answers every query as the grid over all of
// them does once they are taken out: the same points, the same first point, the same ids (the
// second span's too).
TEST(PointGrid, SkippingPointsIsTakingThemOut) {
    std::mt19937_64 rng(27);
    std::uniform_real_distribution<double> unit(0, 1);
    const auto drawn = shore_and_columns(rng, 4000);
    const std::vector<Point>& points = drawn.first;
    const std::vector<Point>& others = drawn.second;
    for (const unsigned split : {0u, 2u}) {
        for (const double share : {0.0, 0.7, 1.0}) {
            PointGrid whole(points, others, 2.0, 1, split);
            std::vector<std::uint8_t> skip(points.size(), 0);
            for (std::uint32_t id = 0; id < points.size(); ++id) {
                if (unit(rng) < share) {
                    skip[id] = 1;
                    whole.remove(id);
                }
            }
            PointGrid live(whole.geometry(), points, others, skip, 2);
            for (int k = 0; k < 200; ++k) {
                const Point a{unit(rng) * 100, unit(rng) * 100}, b{unit(rng) * 100, unit(rng) * 100};
                const Box box{std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
                // (first_in_cells asks about taken-out points too, which accept refuses)
                auto accept = [&](std::uint32_t id, Point q) { return id != PointGrid::kRemoved && box_contains(box, q) && id % 3 != 0; };
                ASSERT_EQ(live.first_in_cells(box, accept), whole.first_in_cells(box, accept)) << "split " << split << ", share " << share;
                EXPECT_EQ(in_cells(live, box), in_cells(whole, box));
            }
            // Taking out a point of the live grid works as in the whole one.
            for (std::uint32_t id = 0; id < points.size(); id += 7) {
                if (skip[id]) continue;
                live.remove(id);
                whole.remove(id);
            }
            const Box all{0, 0, 100, 100};
            EXPECT_EQ(in_cells(live, all), in_cells(whole, all));
        }
    }
}

// compact() drops the taken-out points: every cell then holds the others in the same order, so
// queries answer as before, and points can still be taken out afterwards. The split and the
// thread counts move where each thread's run of cells ends.
TEST(PointGrid, CompactingKeepsTheAnswers) {
    std::mt19937_64 rng(34);
    std::uniform_real_distribution<double> unit(0, 1);
    const auto drawn = shore_and_columns(rng, 40000);
    const std::vector<Point>& points = drawn.first;
    const std::vector<Point>& others = drawn.second;
    for (const unsigned split : {0u, 2u}) {
        for (const int threads : {1, 2, 3}) {
            for (const double share : {0.0, 0.7, 1.0}) {
                PointGrid whole(points, others, 2.0, 1, split);
                PointGrid compacted(points, others, 2.0, 1, split);
                std::size_t live = points.size() + others.size();
                std::vector<std::uint8_t> out(points.size(), 0);
                for (std::uint32_t id = 0; id < points.size(); ++id) {
                    if (unit(rng) < share) {
                        out[id] = 1;
                        whole.remove(id);
                        compacted.remove(id);
                        --live;
                    }
                }
                compacted.compact(threads);
                ASSERT_EQ(compacted.held(), live) << "split " << split << ", threads " << threads << ", share " << share;
                for (std::uint32_t y = 0; y < compacted.rows(); ++y) {
                    for (std::uint32_t x = 0; x < compacted.columns(); ++x) {
                        std::vector<std::uint32_t> kept;
                        for (const std::uint32_t id : whole.cell_ids(x, y)) {
                            if (id != PointGrid::kRemoved) kept.push_back(id);
                        }
                        const auto ids = compacted.cell_ids(x, y);
                        ASSERT_EQ(std::vector<std::uint32_t>(ids.begin(), ids.end()), kept) << "cell " << x << ", " << y;
                    }
                }
                for (int k = 0; k < 100; ++k) {
                    const Point a{unit(rng) * 100, unit(rng) * 100}, b{a.x + unit(rng) * 10, a.y + unit(rng) * 10};
                    const Box box{std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
                    // (first_in_cells asks about taken-out points too, which accept refuses)
                    auto accept = [&](std::uint32_t id, Point q) { return id != PointGrid::kRemoved && box_contains(box, q) && id % 3 != 0; };
                    ASSERT_EQ(compacted.first_in_cells(box, accept), whole.first_in_cells(box, accept));
                    EXPECT_EQ(in_cells(compacted, box), in_cells(whole, box));
                }
                for (std::uint32_t id = 0; id < points.size(); id += 7) {
                    if (out[id]) continue;  // (a point is taken out once)
                    compacted.remove(id);
                    whole.remove(id);
                }
                const Box all{0, 0, 100, 100};
                EXPECT_EQ(in_cells(compacted, all), in_cells(whole, all));
            }
        }
    }
}

}  // namespace
}  // namespace toposimp::map
