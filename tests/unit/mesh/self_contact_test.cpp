// find_self_contact is the only contact check a mesh simplified with ContactCheck::at_the_end
// gets: a pair it misses is a self-intersection shipped. Checked against every pair tested
// directly (random soups of small and long faces, shared corners and corners at one location),
// and on the hard cases: a corner exactly on a face or one ulp (the smallest double) off it,
// folds within a plane, faces at 1e300 and 1e-300 and on both sides of the origin near the
// largest double, degenerate faces.
#include "core/mesh/self_contact.hpp"

#include "core/exact/predicates3d.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace toposimp::mesh {
namespace {

SelfContact by_every_pair(const Mesh& m, const std::vector<std::uint8_t>& changed = {}) {
    exact::PredicateStats stats;
    SelfContact out;
    auto triangle = [&](std::uint32_t f) {
        const Face& c = m.faces[f];
        return exact::Triangle3{m.points[c[0]], m.points[c[1]], m.points[c[2]]};
    };
    std::vector<bool> degenerate(m.faces.size());
    for (std::uint32_t f = 0; f < m.faces.size(); ++f) degenerate[f] = exact::degenerate(triangle(f), stats);
    auto is_changed = [&](std::uint32_t f) { return changed.empty() || changed[f] != 0; };
    for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
        if (degenerate[f]) {
            if (is_changed(f)) {
                ++out.pairs;
                if (!out.first) out.first = {f, f};
            }
            continue;
        }
        for (std::uint32_t g = f + 1; g < m.faces.size(); ++g) {
            if (degenerate[g] || !(is_changed(f) || is_changed(g))) continue;
            if (!exact::faces_conflict(triangle(f), triangle(g), stats)) continue;
            ++out.pairs;
            if (!out.first) out.first = {f, g};
        }
    }
    return out;
}

SelfContact found(const Mesh& m, int threads = 2, const std::vector<std::uint8_t>& changed = {}) {
    exact::PredicateStats stats;
    return find_self_contact(m, threads, stats, changed);
}

void expect_same(const SelfContact& got, const SelfContact& want, const std::string& what) {
    EXPECT_EQ(got.pairs, want.pairs) << what;
    EXPECT_EQ(got.first, want.first) << what;
}

// Random faces in a 10-unit box: most about one unit, some ten times longer (across many cells
// of the check's grid), some sharing corners, some with a corner at another's location.
Mesh soup(int faces, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> anywhere(0, 10), near(-0.6, 0.6), far(-6, 6);
    Mesh m;
    for (int f = 0; f < faces; ++f) {
        const auto first = static_cast<std::uint32_t>(m.points.size());
        const Point3 a{anywhere(random), anywhere(random), anywhere(random)};
        const bool longer = random() % 10 == 0;
        auto around = [&] {
            auto& spread = longer ? far : near;
            return Point3{a.x + spread(random), a.y + spread(random), a.z + spread(random)};
        };
        Face face{first, first + 1, first + 2};
        m.points.push_back(a);
        m.points.push_back(around());
        m.points.push_back(around());
        if (f > 0 && random() % 4 == 0) face[0] = m.faces[random() % m.faces.size()][random() % 3];  // a shared corner
        if (f > 0 && random() % 8 == 0) m.points[first + 1] = m.points[m.faces[random() % m.faces.size()][0]];  // a twin
        m.faces.push_back(face);
    }
    return m;
}

TEST(SelfContact, EveryPairTestedAgreesOnRandomSoups) {
    for (unsigned seed = 1; seed <= 12; ++seed) {
        const Mesh m = soup(seed % 3 == 0 ? 40 : 300, seed);
        const SelfContact want = by_every_pair(m);
        if (m.faces.size() == 300) {
            EXPECT_GT(want.pairs, 10u) << "seed " << seed;  // (crowded: many pairs meet)
        }
        for (int threads : {1, 3}) expect_same(found(m, threads), want, "seed " + std::to_string(seed));
        // Only the pairs with a changed face (a third of them, at random): the others are listed
        // only where a changed face is.
        std::vector<std::uint8_t> changed(m.faces.size());
        std::mt19937 pick(seed);
        for (std::uint8_t& c : changed) c = pick() % 3 == 0;
        const SelfContact some = by_every_pair(m, changed);
        if (m.faces.size() == 300) {
            EXPECT_GT(some.pairs, 0u) << "seed " << seed;
            EXPECT_LT(some.pairs, want.pairs) << "seed " << seed;
        }
        for (int threads : {1, 3}) expect_same(found(m, threads, changed), some, "changed, seed " + std::to_string(seed));
    }
}

TEST(SelfContact, SharedCornersAndEdgesAreNoContact) {
    // A fan of four faces around a vertex, and a second fan whose corner lies at the first's
    // centre (another vertex, the same location): faces meet only at corner locations.
    Mesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, 0}, {1, 1, 1}, {-1, 1, 1}},
           {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}, {5, 6, 7}}};
    EXPECT_EQ(found(m).pairs, 0u);
    expect_same(found(m), by_every_pair(m), "fans");
    // Folded within the plane: face 1 turned over onto face 0.
    Mesh folded = m;
    folded.points[3] = {0.5, 0.25, 0};
    EXPECT_GT(found(folded).pairs, 0u);
    expect_same(found(folded), by_every_pair(folded), "folded");
}

TEST(SelfContact, ACornerOnAFaceOrTheSmallestDoubleOffIt) {
    const double tiny = std::numeric_limits<double>::denorm_min();
    for (const double z : {0.0, tiny, -tiny}) {
        // A face standing on the flat one's interior at (0.25, 0.25, z), rising upward.
        Mesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, z}, {0.25, 0.5, 1}, {0.5, 0.25, 1}}, {{0, 1, 2}, {3, 4, 5}}};
        const SelfContact got = found(m);
        // On the face: a touch; above it: apart; below it: the face pierces the flat one.
        EXPECT_EQ(got.pairs, z > 0 ? 0u : 1u) << z;
        expect_same(got, by_every_pair(m), "z = " + std::to_string(z));
    }
}

TEST(SelfContact, HugeTinyAndOppositeCoordinates) {
    const double largest = std::numeric_limits<double>::max();
    for (const double scale : {1e300, 1e-300, 1.0}) {
        for (const double lift : {0.0, 0.5}) {
            // Two faces crossing each other (lift 0) or one above the other (lift 0.5).
            Mesh m{{{0, 0, 0}, {scale, 0, 0}, {0, scale, 0}, {0.2 * scale, 0.2 * scale, (lift - 0.25) * scale},
                    {0.2 * scale, 0.2 * scale, (lift + 0.25) * scale}, {0.6 * scale, 0.6 * scale, (lift + 0.25) * scale}},
                   {{0, 1, 2}, {3, 4, 5}}};
            const SelfContact got = found(m);
            EXPECT_EQ(got.pairs, lift == 0 ? 1u : 0u) << scale << " " << lift;
            expect_same(got, by_every_pair(m), "scale " + std::to_string(scale));
        }
    }
    // Faces from near −max to near +max (their extent overflows a double): two far apart, and a
    // small pair crossing at the origin.
    Mesh wide{{{-largest, -largest, 0}, {-largest / 2, -largest, 0}, {-largest, -largest / 2, 0},
               {largest, largest, 0}, {largest / 2, largest, 0}, {largest, largest / 2, 0},
               {-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}, {0, 5, 1}},
              {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}}};
    const SelfContact got = found(wide);
    EXPECT_EQ(got.pairs, 1u);
    expect_same(got, by_every_pair(wide), "wide");
}

TEST(SelfContact, DegenerateFacesArePairedWithThemselves) {
    Mesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}}, {{0, 1, 2}, {3, 4, 5}}};
    const SelfContact got = found(m);
    EXPECT_EQ(got.pairs, 1u);
    ASSERT_TRUE(got.first.has_value());
    EXPECT_EQ((*got.first)[0], 1u);
    EXPECT_EQ((*got.first)[1], 1u);
    expect_same(got, by_every_pair(m), "degenerate");
}

TEST(SelfContact, ADuplicateFaceIsAContact) {
    Mesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 1, 2}, {3, 4, 5}}};
    EXPECT_EQ(found(m).pairs, 1u);
}

}  // namespace
}  // namespace toposimp::mesh
