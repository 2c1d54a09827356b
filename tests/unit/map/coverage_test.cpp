#include "core/map/coverage.hpp"

#include "core/map/simplify.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>

#include <gmpxx.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <random>

namespace toposimp::map {
namespace {

std::vector<Point> points_of(const MapData& map, const std::vector<std::uint32_t>& ids) {
    std::vector<Point> points;
    for (const std::uint32_t v : ids) points.push_back(map.vertices[v]);
    return points;
}

int area_sign(const std::vector<Point>& ring) {
    mpq_class twice = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        twice += mpq_class(ring[i].x) * mpq_class(ring[i + 1].y) - mpq_class(ring[i + 1].x) * mpq_class(ring[i].y);
    }
    return sgn(twice);
}

SimplifyResult simplify_max(const MapData& map) {
    SimplifyOptions options;
    options.stop.target = Target::max;
    return simplify(map, options);
}

// Two squares sharing the border x = 1, with a wiggle on it that both rings carry.
TEST(Coverage, SharedBorderIsOneArcSimplifiedOnce) {
    Coverage coverage;
    const std::vector<Point> left{{0, 0}, {1, 0}, {1.1, 0.5}, {1, 1}, {0, 1}, {0, 0}};
    const std::vector<Point> right{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1.1, 0.5}, {1, 0}};
    coverage.add_ring(left);
    coverage.add_ring(right);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.arc_count(), 3u);
    EXPECT_EQ(coverage.shared_arc_count(), 1u);
    const SimplifyResult result = simplify_max(map);
    EXPECT_TRUE(testing::check_simplification(map, result.kept).ok());
    const auto a = points_of(map, coverage.ring_vertices(0, result.kept));
    const auto b = points_of(map, coverage.ring_vertices(1, result.kept));
    // Both keep or both lose the wiggle: the border stays shared.
    const bool a_has = std::any_of(a.begin(), a.end(), [](Point p) { return p.x == 1.1; });
    const bool b_has = std::any_of(b.begin(), b.end(), [](Point p) { return p.x == 1.1; });
    EXPECT_EQ(a_has, b_has);
    EXPECT_TRUE(same_location(a.front(), a.back()));
    EXPECT_TRUE(same_location(a.front(), {0, 0})) << "the ring starts where it started";
    EXPECT_EQ(area_sign(a), area_sign(left));
    EXPECT_EQ(area_sign(b), area_sign(right));
}

TEST(Coverage, IslandIsOneClosedArcAndKeepsThreeCorners) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {2, 0}, {2, 2}, {1, 2.1}, {0, 2}});  // not closed: closed on output
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.arc_count(), 1u);
    const SimplifyResult result = simplify_max(map);
    const auto ring = points_of(map, coverage.ring_vertices(0, result.kept));
    EXPECT_EQ(ring.size(), 4u);
    EXPECT_TRUE(same_location(ring.front(), ring.back()));
    EXPECT_EQ(area_sign(ring), 1);
}

TEST(Coverage, DegenerateRingsComeBackAsTheyWere) {
    Coverage coverage;
    const std::vector<Point> flat{{0, 0}, {1, 0}, {2, 0}, {0, 0}};
    const std::vector<Point> dot{{5, 5}, {5, 5}, {5, 5}};
    coverage.add_ring(flat);
    coverage.add_ring(dot);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.degenerate_ring_count(), 2u);
    const SimplifyResult result = simplify_max(map);
    EXPECT_EQ(result.stats.removed, 0u);
    EXPECT_EQ(points_of(map, coverage.ring_vertices(0, result.kept)).size(), flat.size());
    EXPECT_EQ(points_of(map, coverage.ring_vertices(1, result.kept)).size(), dot.size());
}

// Neighbours that share a border geometrically but not vertex for vertex: the T-contact and the
// overlapping edges are kept as they are, so no gap or overlap can open.
TEST(Coverage, BorderWithoutSharedVerticesIsKept) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {0.5, -0.1}, {1, 0}, {1, 1}, {0.5, 1.1}, {0, 1}, {0, 0}});
    coverage.add_ring(std::vector<Point>{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 0.5}, {1, 0}});  // (1, 0.5) lies on the left square's edge
    MapData map;
    coverage.build(map);
    const SimplifyResult result = simplify_max(map);
    EXPECT_TRUE(testing::check_simplification(map, result.kept).ok());
    const auto left = points_of(map, coverage.ring_vertices(0, result.kept));
    const auto right = points_of(map, coverage.ring_vertices(1, result.kept));
    auto has = [](const std::vector<Point>& ring, Point p) {
        return std::any_of(ring.begin(), ring.end(), [&](Point q) { return same_location(p, q); });
    };
    EXPECT_TRUE(has(left, {1, 0}) && has(left, {1, 1})) << "the left square's border edge stays";
    EXPECT_TRUE(has(right, {1, 0.5})) << "the T-contact stays";
    EXPECT_GT(result.stats.pinned_by_crossing, 0u);
}

TEST(Coverage, DuplicateVerticesDoNotSplitArcs) {
    Coverage coverage;
    coverage.add_ring(std::vector<Point>{{0, 0}, {1, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}});
    coverage.add_ring(std::vector<Point>{{1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 0}});
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.shared_arc_count(), 1u);
}

// Random coverages: a jittered grid of quadrilateral cells whose borders wiggle, each border
// carried identically by both cells. Every ring comes back closed, with its orientation, and
// the arcs pass the independent checker.
TEST(Coverage, RandomGridCoveragesStayValid) {
    for (std::uint64_t seed = 0; seed < 30; ++seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> jitter(-0.25, 0.25);
        const int n = 6;
        std::vector<Point> corner((n + 1) * (n + 1));
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; j <= n; ++j) corner[i * (n + 1) + j] = {i + (i % n ? jitter(rng) : 0), j + (j % n ? jitter(rng) : 0)};
        }
        // Wiggly border between two corners, the same points for both cells.
        std::map<std::pair<int, int>, std::vector<Point>> borders;
        auto border = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            auto it = borders.find(key);
            if (it == borders.end()) {
                std::vector<Point> line;
                const Point p = corner[key.first], q = corner[key.second];
                for (int k = 1; k < 6; ++k) {
                    const double t = k / 6.0;
                    line.push_back({p.x + t * (q.x - p.x) + jitter(rng) * 0.1, p.y + t * (q.y - p.y) + jitter(rng) * 0.1});
                }
                it = borders.emplace(key, line).first;
            }
            std::vector<Point> line = it->second;
            if (a > b) std::reverse(line.begin(), line.end());
            return line;
        };
        Coverage coverage;
        std::vector<std::vector<Point>> input;
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < n; ++j) {
                const int c[4] = {i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1};
                std::vector<Point> ring;
                for (int k = 0; k < 4; ++k) {
                    ring.push_back(corner[c[k]]);
                    const auto line = border(c[k], c[(k + 1) % 4]);
                    ring.insert(ring.end(), line.begin(), line.end());
                }
                ring.push_back(ring.front());
                input.push_back(ring);
                coverage.add_ring(ring);
            }
        }
        MapData map;
        coverage.build(map);
        ASSERT_TRUE(testing::check_planar(map).ok()) << "seed " << seed;
        EXPECT_EQ(coverage.shared_arc_count(), 2u * n * (n - 1));
        const SimplifyResult result = simplify_max(map);
        ASSERT_TRUE(testing::check_simplification(map, result.kept).ok()) << "seed " << seed;
        for (std::uint32_t r = 0; r < coverage.ring_count(); ++r) {
            const auto ring = points_of(map, coverage.ring_vertices(r, result.kept));
            ASSERT_GE(ring.size(), 4u);
            ASSERT_TRUE(same_location(ring.front(), ring.back()));
            ASSERT_EQ(area_sign(ring), area_sign(input[r])) << "seed " << seed << " ring " << r;
        }
        EXPECT_GT(result.stats.removed, 0u);
    }
}

// A coverage of more than 65 536 ring points groups the points by location a bucket of
// locations at a time (coverage.cpp): a 60 × 60 grid of cells with five points on each border
// gets a node at every corner where three or more cells (or two and the outside) meet, one arc
// per border (the corner cells' two outer borders one), and every ring comes back as it was
// given.
TEST(Coverage, BigGridHasTheArcsOfItsBorders) {
    const int n = 60;
    auto corner = [&](int i, int j) { return Point{i * 10.0, j * 10.0}; };
    auto border = [&](int i0, int j0, int i1, int j1) {
        std::vector<Point> line;
        const Point p = corner(i0, j0), q = corner(i1, j1);
        for (int k = 1; k < 6; ++k) {
            const double t = k / 6.0;
            // A wiggle that depends on the border alone, so both cells carry the same points.
            const double wiggle = 0.5 * std::sin(0.7 * (p.x + q.x) + 1.3 * (p.y + q.y) + k);
            line.push_back({p.x + t * (q.x - p.x) + (p.y == q.y ? 0.0 : wiggle), p.y + t * (q.y - p.y) + (p.x == q.x ? 0.0 : wiggle)});
        }
        return line;
    };
    Coverage coverage;
    std::vector<std::vector<Point>> input;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            const int c[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
            std::vector<Point> ring;
            for (int k = 0; k < 4; ++k) {
                const auto [a0, a1] = c[k];
                const auto [b0, b1] = c[(k + 1) % 4];
                ring.push_back(corner(a0, a1));
                std::vector<Point> line = a0 < b0 || a1 < b1 ? border(a0, a1, b0, b1) : border(b0, b1, a0, a1);
                if (!(a0 < b0 || a1 < b1)) std::reverse(line.begin(), line.end());
                ring.insert(ring.end(), line.begin(), line.end());
            }
            ring.push_back(ring.front());
            input.push_back(ring);
            coverage.add_ring(ring);
        }
    }
    ASSERT_GT(coverage.point_count(), 65536u);
    MapData map;
    coverage.build(map);
    EXPECT_EQ(coverage.point_count(), static_cast<std::uint32_t>(n * n * 25));
    EXPECT_EQ(coverage.shared_arc_count(), 2u * n * (n - 1));
    EXPECT_EQ(coverage.arc_count(), 2u * n * (n - 1) + 4u * n - 4u);
    const std::vector<std::uint8_t> all(map.vertices.size(), 1);
    for (std::uint32_t r = 0; r < coverage.ring_count(); ++r) {
        const auto ring = points_of(map, coverage.ring_vertices(r, all));
        ASSERT_EQ(ring.size(), input[r].size()) << "ring " << r;
        for (std::size_t k = 0; k < ring.size(); ++k) ASSERT_TRUE(same_location(ring[k], input[r][k])) << "ring " << r << ", point " << k;
    }
}

// Rings streamed from where they are (a file, for a run in parts): the plan gives the chains
// build() gives, with their ids, without holding the rings, in one pass or in many; and each run
// of rings makes its own chains with their vertices from its rings alone (arcs_of).
std::vector<std::vector<Point>> snapped_rings(std::uint64_t seed) {
    // Rings through the points of a 5 × 5 lattice (and -0.0, and cells of a grid): locations
    // meet everywhere, so there are nodes, shared arcs, spikes, rings through a location twice,
    // repeated rings, duplicates in a row, and degenerate rings.
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int> coordinate(0, 4), length(2, 9), coin(0, 5);
    std::vector<std::vector<Point>> rings;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            rings.push_back({{2.0 * i, 2.0 * j}, {2.0 * i + 2, 2.0 * j}, {2.0 * i + 2, 2.0 * j + 2}, {2.0 * i, 2.0 * j + 2}, {2.0 * i, 2.0 * j}});
        }
    }
    const int random_rings = 40;
    for (int r = 0; r < random_rings; ++r) {
        std::vector<Point> ring;
        const int n = length(rng);
        for (int k = 0; k < n; ++k) {
            Point p{static_cast<double>(coordinate(rng)), static_cast<double>(coordinate(rng))};
            if (p.x == 0 && coin(rng) == 0) p.x = -0.0;
            ring.push_back(p);
            if (coin(rng) == 0) ring.push_back(p);  // a duplicate in a row
        }
        if (coin(rng) < 3) ring.push_back(ring.front());  // closed, or not
        rings.push_back(ring);
        if (coin(rng) == 0) rings.push_back(ring);  // the same ring again
        if (coin(rng) == 0) rings.push_back(std::vector<Point>(ring.rbegin(), ring.rend()));
    }
    std::shuffle(rings.begin(), rings.end(), rng);
    return rings;
}

RingSource stream(const std::vector<std::vector<Point>>& rings, std::size_t first = 0, std::size_t end = SIZE_MAX) {
    return [&rings, first, end](const std::function<void(std::span<const Point>)>& visit) {
        for (std::size_t r = first; r < std::min(end, rings.size()); ++r) visit(rings[r]);
    };
}

TEST(Coverage, PlannedFromStreamedRingsIsTheBuild) {
    for (std::uint64_t seed = 0; seed < 60; ++seed) {
        const std::vector<std::vector<Point>> rings = snapped_rings(seed);
        MapData built;
        built.add_chain(std::vector<Point>{{-5, -5}, {-4, -4}, {-3, -5}});  // a line first: the arcs' ids come after its
        Coverage whole;
        for (const auto& ring : rings) whole.add_ring(ring);
        whole.build(built);
        std::mt19937_64 rng(seed);
        std::vector<std::uint8_t> kept(built.vertices.size());
        for (auto& k : kept) k = static_cast<std::uint8_t>(rng() % 3 != 0);
        for (const Chain& chain : built.chains) kept[chain.first] = 1;  // (every ring keeps a vertex, as the engine's do)
        for (const std::size_t pass_bytes : {std::size_t{1} << 20, std::size_t{56 * 7}, std::size_t{1}}) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", pass_bytes " + std::to_string(pass_bytes));
            MapData planned;
            planned.chains.push_back(built.chains[0]);
            Coverage streamed;
            streamed.plan(stream(rings), planned, pass_bytes);
            ASSERT_TRUE(planned.vertices.empty());
            ASSERT_EQ(planned.chains.size(), built.chains.size());
            for (std::size_t c = 0; c < built.chains.size(); ++c) {
                ASSERT_EQ(planned.chains[c].first, built.chains[c].first) << "chain " << c;
                ASSERT_EQ(planned.chains[c].last, built.chains[c].last) << "chain " << c;
                ASSERT_EQ(planned.is_frozen(static_cast<std::uint32_t>(c)), built.is_frozen(static_cast<std::uint32_t>(c))) << "chain " << c;
            }
            EXPECT_EQ(streamed.arc_count(), whole.arc_count());
            EXPECT_EQ(streamed.shared_arc_count(), whole.shared_arc_count());
            EXPECT_EQ(streamed.degenerate_ring_count(), whole.degenerate_ring_count());
            EXPECT_EQ(streamed.point_count(), whole.point_count());
            ASSERT_EQ(streamed.ring_count(), whole.ring_count());
            for (std::uint32_t r = 0; r < whole.ring_count(); ++r) {
                const auto a = whole.ring_arcs(r), b = streamed.ring_arcs(r);
                ASSERT_EQ(a.size(), b.size()) << "ring " << r;
                for (std::size_t k = 0; k < a.size(); ++k) {
                    ASSERT_EQ(a[k].chain, b[k].chain) << "ring " << r;
                    ASSERT_EQ(a[k].reversed, b[k].reversed) << "ring " << r;
                }
                for (const bool arc_order : {false, true}) {
                    const std::vector<std::uint32_t> vertices = whole.ring_vertices(r, kept, arc_order);
                    ASSERT_EQ(vertices, streamed.ring_vertices(r, kept, arc_order)) << "ring " << r;
                    // The ring from its own points: the arcs' points bit for bit (a -0.0
                    // where the arc's vertex has one, though the ring has 0.0, and the reverse).
                    const std::vector<Coverage::RingPoint> own = streamed.ring_points_from(r, rings[r], kept, arc_order);
                    ASSERT_EQ(own.size(), vertices.size()) << "ring " << r;
                    for (std::size_t k = 0; k < own.size(); ++k) {
                        const Point want = built.vertices[vertices[k]];
                        ASSERT_TRUE(std::bit_cast<std::uint64_t>(own[k].point.x) == std::bit_cast<std::uint64_t>(want.x) &&
                                    std::bit_cast<std::uint64_t>(own[k].point.y) == std::bit_cast<std::uint64_t>(want.y))
                            << "ring " << r << ", point " << k;
                    }
                }
            }
        }
        EXPECT_GT(whole.shared_arc_count(), 0u);
        EXPECT_GT(whole.degenerate_ring_count(), 0u);
        // Any run of rings makes its chains, with the build's vertices, from its own rings.
        for (int trial = 0; trial < 20; ++trial) {
            std::uint32_t first = static_cast<std::uint32_t>(rng() % (rings.size() + 1));
            std::uint32_t end = static_cast<std::uint32_t>(rng() % (rings.size() + 1));
            if (first > end) std::swap(first, end);
            const CoverageSlice slice = whole.slice(first, end);
            const MapData part = arcs_of(slice, stream(rings, first, end));
            ASSERT_EQ(part.chains.size(), slice.end_chain - slice.first_chain);
            for (std::uint32_t c = 0; c < part.chains.size(); ++c) {
                const Chain want = built.chains[slice.first_chain + c], got = part.chains[c];
                ASSERT_EQ(got.last - got.first, want.last - want.first) << "rings " << first << "–" << end << ", chain " << c;
                ASSERT_EQ(part.is_frozen(c), built.is_frozen(slice.first_chain + c));
                for (std::uint32_t k = 0; k <= want.last - want.first; ++k) {
                    const Point p = part.vertices[got.first + k], q = built.vertices[want.first + k];
                    ASSERT_TRUE(std::bit_cast<std::uint64_t>(p.x) == std::bit_cast<std::uint64_t>(q.x) &&
                                std::bit_cast<std::uint64_t>(p.y) == std::bit_cast<std::uint64_t>(q.y))
                        << "rings " << first << "–" << end << ", chain " << c << ", vertex " << k;
                }
            }
        }
    }
}

// Rings with tags (Z and M) streamed to the plan: each ring's points as ring_points_from gives
// them, with their own tags but where the plan noted an arc vertex's (arc_tag), carry the tags
// build() gives the map's vertices (those of the points they come from: source_of).
using Tags = std::vector<std::vector<PointTag>>;

TaggedRingSource tagged_stream(const std::vector<std::vector<Point>>& rings, const Tags& tags) {
    return [&rings, &tags](const std::function<void(std::span<const Point>, std::span<const PointTag>)>& visit) {
        for (std::size_t r = 0; r < rings.size(); ++r) visit(rings[r], tags[r]);
    };
}

// A tag for each location (the same for 0.0 and -0.0, as for the location); `salt` changes it.
PointTag tag_at(Point p, std::uint64_t salt = 0) {
    return {std::bit_cast<std::uint64_t>(p.x == 0 ? 0.0 : p.x) * 3 + 1 + salt, std::bit_cast<std::uint64_t>(p.y == 0 ? 0.0 : p.y) ^ 0x5555};
}

// Each point's tag by its location, or (`differ`, an rng) by its location and a coin, so that
// rings at a location may differ.
Tags tags_by_location(const std::vector<std::vector<Point>>& rings, std::mt19937_64* differ = nullptr) {
    Tags tags;
    for (const auto& ring : rings) {
        tags.emplace_back();
        for (const Point p : ring) tags.back().push_back(tag_at(p, differ != nullptr ? (*differ)() % 2 : 0));
    }
    return tags;
}

// Plans the rings with their tags (pass_bytes) and expects every ring's written tags to be
// build()'s; returns the locations where tags differ.
std::uint64_t expect_written_tags_are_the_builds(const std::vector<std::vector<Point>>& rings, const Tags& tags,
                                                 std::size_t pass_bytes = std::size_t{1} << 20) {
    MapData built, planned;
    Coverage whole, coverage;
    std::vector<PointTag> source_tags;  // (every ring point's, in add_ring order: source_of's numbering)
    for (std::size_t r = 0; r < rings.size(); ++r) {
        whole.add_ring(rings[r]);
        source_tags.insert(source_tags.end(), tags[r].begin(), tags[r].end());
    }
    whole.build(built);
    coverage.plan(tagged_stream(rings, tags), planned, pass_bytes);
    std::mt19937_64 rng(rings.size());
    std::vector<std::uint8_t> kept(built.vertices.size());
    for (auto& k : kept) k = static_cast<std::uint8_t>(rng() % 3 != 0);
    for (const Chain& chain : built.chains) kept[chain.first] = 1;
    for (std::uint32_t r = 0; r < whole.ring_count(); ++r) {
        for (const bool arc_order : {false, true}) {
            const std::vector<std::uint32_t> vertices = whole.ring_vertices(r, kept, arc_order);
            const std::vector<Coverage::RingPoint> points = coverage.ring_points_from(r, rings[r], kept, arc_order);
            EXPECT_EQ(points.size(), vertices.size()) << "ring " << r;
            for (std::size_t k = 0; k < std::min(points.size(), vertices.size()); ++k) {
                EXPECT_EQ(points[k].vertex, vertices[k]) << "ring " << r << ", point " << k;
                EXPECT_LT(points[k].position, rings[r].size());
                EXPECT_TRUE(same_location(rings[r][points[k].position], points[k].point));
                const PointTag* arc = coverage.arc_tag(points[k].vertex);
                const PointTag written = arc != nullptr ? *arc : tags[r][points[k].position];
                EXPECT_EQ(written, source_tags[whole.source_of(vertices[k])]) << "ring " << r << ", point " << k;
            }
        }
    }
    return coverage.tag_conflicts();
}

TEST(Coverage, TaggedRingsWrittenCarryTheArcVerticesTags) {
    // Two squares sharing the edge (1,0)–(1,1); the second with a duplicate in a row at (2,1).
    // A third ring too thin to split (degenerate) touches them at (2,0).
    const std::vector<std::vector<Point>> rings = {
        {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}},
        {{1, 0}, {2, 0}, {2, 1}, {2, 1}, {1, 1}, {1, 0}},
        {{2, 0}, {3, 0}, {2, 0}},
    };
    const Tags same = tags_by_location(rings);
    // The tags with ring r's point k's Z (or M) changed.
    auto changed = [&](std::size_t r, std::size_t k, bool m = false) {
        Tags tags = same;
        (m ? tags[r][k].m : tags[r][k].z) ^= 1;
        return tags;
    };
    for (const std::size_t pass_bytes : {std::size_t{1} << 20, std::size_t{1}}) {
        EXPECT_EQ(expect_written_tags_are_the_builds(rings, same, pass_bytes), 0u);
        // (1,1) in the second ring differs from the first's, which made the shared arc: the second
        // is written with the first's there. And (1,0)'s M in the first ring.
        EXPECT_EQ(expect_written_tags_are_the_builds(rings, changed(1, 4), pass_bytes), 1u);
        EXPECT_EQ(expect_written_tags_are_the_builds(rings, changed(0, 1, true), pass_bytes), 1u);
    }
    // Points that make no vertex of their own are not compared: a closing point, the second of
    // a duplicate in a row (clean_ring keeps the first), and a degenerate ring's, whose chain
    // is its own. Nor a point of one ring only: nothing to compare it with.
    for (const auto& [r, k] : {std::pair{0, 4}, {1, 3}, {2, 0}, {0, 3}}) {
        EXPECT_EQ(expect_written_tags_are_the_builds(rings, changed(r, k)), 0u) << r << ", " << k;
    }
}

TEST(Coverage, TaggedPlanIsThePlanAndItsRingsCarryTheBuildsTags) {
    std::uint64_t conflicts = 0;
    for (std::uint64_t seed = 0; seed < 30; ++seed) {
        const std::vector<std::vector<Point>> rings = snapped_rings(seed);
        std::mt19937_64 coin(seed);
        const Tags by_location = tags_by_location(rings), differing = tags_by_location(rings, &coin);
        MapData plain_map;
        Coverage plain;
        plain.plan(stream(rings), plain_map, 1 << 20);
        for (const std::size_t pass_bytes : {std::size_t{1} << 20, std::size_t{72 * 7}, std::size_t{1}}) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", pass_bytes " + std::to_string(pass_bytes));
            MapData map;
            Coverage coverage;
            coverage.plan(tagged_stream(rings, differing), map, pass_bytes);
            ASSERT_EQ(map.chains.size(), plain_map.chains.size());
            for (std::size_t c = 0; c < map.chains.size(); ++c) {
                ASSERT_EQ(map.chains[c].first, plain_map.chains[c].first);
                ASSERT_EQ(map.chains[c].last, plain_map.chains[c].last);
            }
            EXPECT_EQ(expect_written_tags_are_the_builds(rings, by_location, pass_bytes), 0u);
            conflicts += expect_written_tags_are_the_builds(rings, differing, pass_bytes);
        }
    }
    EXPECT_GT(conflicts, 0u);
}

// Rings that are not what they were: the plan's later passes, or a slice given other rings,
// say so instead of planning or making other chains.
TEST(Coverage, StreamedRingsThatChangeAreRefused) {
    std::vector<std::vector<Point>> rings = snapped_rings(3);
    int passes = 0;
    const RingSource changing = [&](const std::function<void(std::span<const Point>)>& visit) {
        ++passes;
        for (std::size_t r = 0; r < rings.size(); ++r) {
            if (passes > 1 && r == rings.size() / 2) {
                std::vector<Point> other = rings[r];
                other.push_back(other.back());
                visit(other);
            } else {
                visit(rings[r]);
            }
        }
    };
    MapData map;
    Coverage coverage;
    EXPECT_THROW(coverage.plan(changing, map, 1 << 20), std::invalid_argument);

    Coverage whole;
    for (const auto& ring : rings) whole.add_ring(ring);
    MapData built;
    whole.build(built);
    const CoverageSlice slice = whole.slice(0, static_cast<std::uint32_t>(rings.size()));
    EXPECT_NO_THROW(arcs_of(slice, stream(rings)));
    EXPECT_THROW(arcs_of(slice, stream(rings, 1)), std::invalid_argument);  // a ring short
    std::vector<std::vector<Point>> one_longer = rings;
    one_longer[1].insert(one_longer[1].begin() + 1, Point{0.5, 0.25});
    EXPECT_THROW(arcs_of(slice, stream(one_longer)), std::invalid_argument);
    const std::vector<std::uint8_t> all_kept(built.vertices.size(), 1);
    EXPECT_NO_THROW(whole.ring_points_from(1, rings[1], all_kept));
    EXPECT_THROW(whole.ring_points_from(1, one_longer[1], all_kept), std::invalid_argument);
    std::vector<std::vector<Point>> degenerate_longer = rings;  // a frozen ring, one point longer
    const auto frozen = std::find_if(built.frozen.begin(), built.frozen.end(), [](std::uint8_t f) { return f != 0; }) - built.frozen.begin();
    ASSERT_LT(static_cast<std::size_t>(frozen), built.chains.size());
    std::uint32_t frozen_ring = 0;
    while (whole.ring_arcs(frozen_ring)[0].chain != frozen) ++frozen_ring;
    degenerate_longer[frozen_ring].push_back(degenerate_longer[frozen_ring].back());
    EXPECT_THROW(arcs_of(slice, stream(degenerate_longer)), std::invalid_argument);
}

}  // namespace
}  // namespace toposimp::map
