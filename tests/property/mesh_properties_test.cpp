// UGSimp on generated meshes: no self-intersection, no non-manifold edge, no flipped face or
// map-plane fold, whatever the target; the same result for any thread count. Every check is
// the independent brute-force checker's (tests/support/mesh_checker), not the engine's.
#include "core/mesh/distance.hpp"
#include "core/mesh/simplify.hpp"
#include "support/mesh_checker.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>

namespace toposimp::mesh {
namespace {

using testing::find_defects;

SimplifyStats simplified(Mesh& m, Target target, double value, int threads, bool terrain = false, bool lock = false) {
    SimplifyOptions options;
    options.stop.target = target;
    options.stop.value = value;
    options.threads = threads;
    options.parallel_threshold = 0;  // every loop parallel, even on small meshes
    options.terrain = terrain;
    options.lock_boundary = lock;
    return simplify(m, options);
}

void expect_clean(const Mesh& m, const std::string& what) {
    const auto defects = find_defects(m);
    EXPECT_EQ(defects.total(), 0u) << what << ": " << defects.first;
}

bool same(const Mesh& a, const Mesh& b) {
    if (a.points.size() != b.points.size() || a.faces != b.faces) return false;
    for (std::size_t i = 0; i < a.points.size(); ++i) {
        if (!same_location(a.points[i], b.points[i])) return false;
    }
    return true;
}

TEST(MeshProperties, CheckerFindsCoplanarAndCrossingContacts) {
    // A flat square of two faces: clean. Fold one over its diagonal (coplanar overlap), or add a
    // face piercing it, or one lying flat inside it: each is an intersecting pair.
    Mesh flat{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}};
    EXPECT_EQ(find_defects(flat).total(), 0u) << find_defects(flat).first;
    Mesh folded = flat;
    folded.points[3] = {0.8, 0.2, 0};  // now on the same side of the diagonal as corner 1
    EXPECT_EQ(find_defects(folded).intersecting_pairs, 1u);
    Mesh pierced = flat;
    pierced.points.push_back({0.5, 0.4, -1});
    pierced.points.push_back({0.5, 0.4, 1});
    pierced.points.push_back({3, 3, 3});
    pierced.faces.push_back({4, 5, 6});
    EXPECT_EQ(find_defects(pierced).intersecting_pairs, 1u);
    // Two faces meeting in one corner only: a pinch (two fans around that vertex).
    Mesh bowtie{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {{0, 1, 2}, {0, 3, 4}}};
    EXPECT_EQ(find_defects(bowtie).non_manifold_vertices, 1u);
    EXPECT_EQ(find_defects(flat).non_manifold_vertices, 0u);
    Mesh lying = flat;
    lying.points.push_back({0.6, 0.1, 0});
    lying.points.push_back({0.9, 0.1, 0});
    lying.points.push_back({0.9, 0.4, 0});
    lying.faces.push_back({4, 5, 6});
    EXPECT_EQ(find_defects(lying).intersecting_pairs, 1u);
}

// A bumpy n × n grid with square holes of h × h cells every h + gap cells: border loops `gap`
// cells apart (1: a strip one face wide between two holes).
Mesh holed_sheet(int n, int h, int gap, double bump, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> noise(-bump, bump);
    Mesh m;
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) m.points.push_back({i + 0.1 * noise(random), j + 0.1 * noise(random), std::sin(0.3 * i) * std::cos(0.2 * j) + noise(random)});
    }
    auto hole = [&](int i, int j) { return i % (h + gap) >= gap && j % (h + gap) >= gap && i < n - gap && j < n - gap; };
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            if (hole(i, j)) continue;
            const auto a = static_cast<std::uint32_t>(j * (n + 1) + i);
            const auto w = static_cast<std::uint32_t>(n + 1);
            m.faces.push_back({a, a + 1, a + w + 1});
            m.faces.push_back({a, a + w + 1, a + w});
        }
    }
    drop_unused(m);
    return m;
}

// Issue 33: border loops close together must never be pinched into one vertex, nor the strips
// between them crossed, whatever the target (in space and as a terrain, border free or locked).
TEST(MeshProperties, Issue33BorderLoopsCloseTogetherAreNeverPinched) {
    for (const int gap : {1, 2}) {
        for (const std::uint64_t seed : {1u, 2u}) {
            const Mesh input = holed_sheet(30, 2, gap, 0.3, seed);
            {
                const auto defects = find_defects(input);
                ASSERT_EQ(defects.total(), 0u) << defects.first;
            }
            for (const bool terrain : {false, true}) {
                for (const bool lock : {false, true}) {
                    for (const double keep : {0.1, 0.0}) {
                        Mesh m = input;
                        simplified(m, Target::keep_fraction, keep, 2, terrain, lock);
                        const auto defects = find_defects(m);
                        EXPECT_EQ(defects.total(), 0u) << "gap " << gap << " seed " << seed << " terrain " << terrain << " lock "
                                                       << lock << " keep " << keep << ": " << defects.first;
                    }
                }
            }
        }
    }
}

// The connected pieces of a mesh (faces joined through shared vertices), each a mesh of its own.
std::vector<Mesh> pieces(const Mesh& m) {
    std::vector<std::uint32_t> root(m.points.size());
    for (std::uint32_t v = 0; v < root.size(); ++v) root[v] = v;
    auto find = [&](std::uint32_t v) {
        while (root[v] != v) v = root[v] = root[root[v]];
        return v;
    };
    for (const Face& f : m.faces) {
        root[find(f[1])] = find(f[0]);
        root[find(f[2])] = find(f[0]);
    }
    std::map<std::uint32_t, Mesh> by_root;
    for (const Face& f : m.faces) by_root[find(f[0])].faces.push_back(f);
    std::vector<Mesh> out;
    for (auto& [r, piece] : by_root) {
        piece.points = m.points;
        drop_unused(piece);
        out.push_back(std::move(piece));
    }
    return out;
}

// Issue 33: parts that already cross each other (two interpenetrating spheres, a sphere through
// a sheet) simplify as far as clean ones: a contact a collapse inherits from the faces it
// replaces is not a new one. Each part stays free of contacts with itself, manifold, whole; the
// parts still cross (they did); the target is reached.
TEST(MeshProperties, Issue33InterpenetratingPartsSimplifyAsFarAsCleanOnes) {
    for (const std::uint64_t seed : {1u, 2u}) {
        const Mesh first = toposimp::testing::noisy_sphere(4, 0.02, seed);
        const Mesh second = toposimp::testing::noisy_sphere(4, 0.02, seed + 10, {0.9, 0.3, 0.1});
        Mesh both = first;
        for (const Point3& p : second.points) both.points.push_back(p);
        const auto offset = static_cast<std::uint32_t>(first.points.size());
        for (const Face& f : second.faces) both.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
        ASSERT_GT(find_defects(both).intersecting_pairs, 0u);
        for (const double keep : {0.1, 0.02}) {
            Mesh m = both;
            const SimplifyStats stats = simplified(m, Target::keep_fraction, keep, 2);
            EXPECT_TRUE(stats.target_reached) << "seed " << seed << " keep " << keep << ": " << stats.faces_out << " faces";
            const std::vector<Mesh> parts = pieces(m);
            ASSERT_EQ(parts.size(), 2u);
            for (const Mesh& part : parts) {
                const auto defects = find_defects(part);
                EXPECT_EQ(defects.total(), 0u) << "seed " << seed << " keep " << keep << ": " << defects.first;
                EXPECT_EQ(static_cast<long>(part.points.size()) - static_cast<long>(part.faces.size()) / 2, 2) << "a sphere stays one";
            }
            const auto whole = find_defects(m);
            EXPECT_GT(whole.intersecting_pairs, 0u) << "the parts crossed and still do";
            EXPECT_EQ(whole.non_manifold_edges + whole.non_manifold_vertices + whole.degenerate_faces + whole.duplicate_faces, 0u)
                << whole.first;
            // The same for any number of threads.
            Mesh one = both;
            simplified(one, Target::keep_fraction, keep, 1);
            EXPECT_TRUE(same(one, m)) << "seed " << seed << " keep " << keep;
        }
    }
}

TEST(MeshProperties, GeneratedInputsAreClean) {
    expect_clean(testing::noisy_sphere(3, 0.05, 1), "sphere");
    expect_clean(testing::noisy_heightfield(30, 0.5, 1), "heightfield");
    expect_clean(testing::near_sheets(20, 3, 1), "sheets");
    expect_clean(testing::folded_strip(30, 0.01, 1), "strip");
}

TEST(MeshProperties, SpheresStayClosedManifoldAndUnbroken) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
        for (double keep : {0.5, 0.1, 0.02}) {
            Mesh m = testing::noisy_sphere(3, seed % 2 == 0 ? 0.3 : 0.02, seed);
            const std::size_t faces = m.faces.size();
            const SimplifyStats stats = simplified(m, Target::keep_fraction, keep, 2);
            const std::string what = "seed " + std::to_string(seed) + " keep " + std::to_string(keep);
            expect_clean(m, what);
            EXPECT_EQ(testing::volume_sign(m), 1) << what;
            EXPECT_LT(m.faces.size(), faces) << what;
            EXPECT_EQ(stats.faces_out, m.faces.size());
            // Closed surface: Euler characteristic 2 (V − E + F with E = 3F/2).
            EXPECT_EQ(static_cast<long>(m.points.size()) - static_cast<long>(m.faces.size()) / 2, 2) << what;
            if (stats.target_reached) {
                EXPECT_LE(m.faces.size(), stats.target_faces) << what;
            }
        }
    }
}

TEST(MeshProperties, CountTargetsLandWithinOneCollapse) {
    Mesh m = testing::noisy_sphere(4, 0.01, 3);
    const SimplifyStats stats = simplified(m, Target::keep_faces, 1000, 3);
    ASSERT_TRUE(stats.target_reached);
    EXPECT_LE(m.faces.size(), 1000u);
    EXPECT_GE(m.faces.size(), 998u);  // a collapse removes two faces of a closed surface
}

TEST(MeshProperties, NoisyTerrainNeverFoldsInTheMapPlane) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
        for (bool lock : {true, false}) {
            Mesh m = testing::noisy_heightfield(40, seed % 2 == 0 ? 2.0 : 0.2, seed);
            const SimplifyStats stats = simplified(m, Target::keep_fraction, 0.05, 2, true, lock);
            const std::string what = "seed " + std::to_string(seed) + (lock ? " locked" : " free");
            expect_clean(m, what);
            EXPECT_EQ(testing::count_map_plane_folds(m, 1), 0u) << what;
            EXPECT_GT(stats.collapses, 0u);
            if (lock) {
                // The border of the grid is still all there.
                std::size_t border = 0;
                for (const Point3& p : m.points) border += p.x == 0 || p.y == 0 || p.x == 40 || p.y == 40;
                EXPECT_EQ(border, 160u) << what;
            }
        }
    }
}

TEST(MeshProperties, SheetsUlpsApartNeverTouch) {
    for (int ulps : {1, 4, 64}) {
        for (std::uint64_t seed = 1; seed <= 3; ++seed) {
            Mesh m = testing::near_sheets(16, ulps, seed);
            const SimplifyStats stats = simplified(m, Target::keep_fraction, 0.05, 2);
            const std::string what = std::to_string(ulps) + " ulps, seed " + std::to_string(seed);
            expect_clean(m, what);
            EXPECT_GT(stats.collapses, 0u) << what;
            EXPECT_GT(stats.refused_intersection, 0u) << what;
        }
    }
}

TEST(MeshProperties, FoldedStripLayersNeverCross) {
    for (double gap : {0.5, 1e-3, 1e-9}) {
        Mesh m = testing::folded_strip(40, gap, 5);
        const SimplifyStats stats = simplified(m, Target::keep_fraction, 0.05, 2);
        expect_clean(m, "gap " + std::to_string(gap));
        EXPECT_GT(stats.collapses, 0u);
    }
}

TEST(MeshProperties, MaxErrorBoundsEveryCollapse) {
    Mesh m = testing::noisy_heightfield(40, 0.3, 9);
    const SimplifyStats stats = simplified(m, Target::max_error, 0.25, 2);
    EXPECT_GT(stats.collapses, 0u);
    EXPECT_LE(stats.max_error, 0.25);
    expect_clean(m, "max error");
}

TEST(MeshProperties, SameResultForAnyThreadCount) {
    const Mesh inputs[] = {testing::noisy_sphere(4, 0.05, 11), testing::noisy_heightfield(60, 1.0, 12),
                           testing::near_sheets(24, 2, 13), testing::folded_strip(60, 1e-3, 14)};
    int k = 0;
    for (const Mesh& input : inputs) {
        for (Target target : {Target::keep_fraction, Target::max_error}) {
            const double value = target == Target::keep_fraction ? 0.1 : 0.05;
            Mesh serial = input;
            simplified(serial, target, value, 1, k == 1);
            for (int threads : {2, 3, 4, 7}) {
                Mesh parallel = input;
                simplified(parallel, target, value, threads, k == 1);
                EXPECT_TRUE(same(serial, parallel)) << "mesh " << k << ", " << threads << " threads";
            }
        }
        ++k;
    }
}

// Georeferenced meshes sit far from the origin (UTM: x ~ 5·10^5, y ~ 4·10^6 metres). The quadrics
// must not care: computed about the origin, their costs were rounding noise at that offset, the
// collapse order random, the result many times further from the input.
TEST(MeshProperties, FarFromTheOriginSimplifiesAsWellAsAtIt) {
    const Point3 far{500000.0, 4000000.0, 100.0};
    double distance[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
        Mesh input = testing::noisy_sphere(5, 0.002, 21, k == 0 ? Point3{0, 0, 0} : far);
        Mesh m = input;
        const SimplifyStats stats = simplified(m, Target::keep_fraction, 0.1, 2);
        EXPECT_TRUE(stats.target_reached);
        expect_clean(m, k == 0 ? "at the origin" : "far from it");
        distance[k] = hausdorff(input, m).max();
    }
    EXPECT_GT(distance[0], 0.0);
    EXPECT_LT(distance[1], 1.5 * distance[0]) << "at the origin " << distance[0] << ", far from it " << distance[1];
}

// A cost goes with the fourth power of the size: a mesh 2^500 units across overflowed it, one
// 2^-500 across underflowed it, and the order was noise. Scaled by a power of two, every step
// of the simplification scales exactly (the quadrics' frame takes the scale out, the exact
// predicates decide the same signs): the same faces, every point 2^k times the unscaled one.
TEST(MeshProperties, ScaledByAPowerOfTwoSimplifiesTheSame) {
    const Mesh input = testing::noisy_sphere(4, 0.05, 23);
    Mesh unit = input;
    const SimplifyStats unit_stats = simplified(unit, Target::keep_fraction, 0.1, 2);
    for (int k : {-500, 500}) {
        Mesh m = input;
        for (Point3& p : m.points) p = {std::ldexp(p.x, k), std::ldexp(p.y, k), std::ldexp(p.z, k)};
        const SimplifyStats stats = simplified(m, Target::keep_fraction, 0.1, 2);
        ASSERT_EQ(m.faces, unit.faces) << k;
        ASSERT_EQ(m.points.size(), unit.points.size()) << k;
        for (std::size_t i = 0; i < m.points.size(); ++i) {
            const Point3 p = unit.points[i];
            ASSERT_TRUE(same_location(m.points[i], {std::ldexp(p.x, k), std::ldexp(p.y, k), std::ldexp(p.z, k)})) << k << ' ' << i;
        }
        EXPECT_EQ(stats.max_error, std::ldexp(unit_stats.max_error, k)) << k;
    }
}

// Near the largest double (a sphere of radius 2^1020 around x = 1.5·2^1023) the sum of two
// coordinates overflows, and so would any cost taken in coordinate units: still clean, at the
// target, and as close to the input as at size 1.
TEST(MeshProperties, NearTheLargestDoubleSimplifiesAsWellAsAtSizeOne) {
    const Mesh input = testing::noisy_sphere(4, 0.05, 27);
    Mesh unit = input;
    simplified(unit, Target::keep_fraction, 0.1, 2);
    const double unit_distance = hausdorff(input, unit).max();
    Mesh huge = input;
    for (Point3& p : huge.points) p = {0x1.8p1023 + std::ldexp(p.x, 1020), std::ldexp(p.y, 1020), std::ldexp(p.z, 1020)};
    ASSERT_FALSE(std::isfinite(huge.points[0].x + huge.points[1].x));  // (the premise)
    const Mesh huge_input = huge;
    const SimplifyStats stats = simplified(huge, Target::keep_fraction, 0.1, 2);
    EXPECT_TRUE(stats.target_reached);
    expect_clean(huge, "near the largest double");
    const double huge_distance = std::ldexp(hausdorff(huge_input, huge).max(), -1020);
    EXPECT_LT(huge_distance, 1.5 * unit_distance) << "at size 1 " << unit_distance << ", near the largest double " << huge_distance;
}

// A closed box, each side an n×n grid of unit cells (flat regions meeting at creases), faces
// turned outward.
Mesh grid_box(int n) {
    Mesh m;
    auto side = [&](Point3 origin, Point3 u, Point3 v) {
        const auto first = static_cast<std::uint32_t>(m.points.size());
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                m.points.push_back({origin.x + i * u.x + j * v.x, origin.y + i * u.y + j * v.y, origin.z + i * u.z + j * v.z});
            }
        }
        auto at = [&](int i, int j) { return first + static_cast<std::uint32_t>(j * (n + 1) + i); };
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
                m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
            }
        }
    };
    const double s = n;
    side({0, 0, 0}, {0, 1, 0}, {1, 0, 0});  // z = 0, facing −z
    side({0, 0, s}, {1, 0, 0}, {0, 1, 0});  // z = n, facing +z
    side({0, 0, 0}, {1, 0, 0}, {0, 0, 1});  // y = 0, facing −y
    side({0, s, 0}, {0, 0, 1}, {1, 0, 0});  // y = n, facing +y
    side({0, 0, 0}, {0, 0, 1}, {0, 1, 0});  // x = 0, facing −x
    side({s, 0, 0}, {0, 1, 0}, {0, 0, 1});  // x = n, facing +x
    // Weld the sides' shared border vertices.
    std::vector<std::uint32_t> index(m.points.size());
    std::vector<Point3> kept;
    for (std::size_t v = 0; v < m.points.size(); ++v) {
        std::size_t k = 0;
        while (k < kept.size() && !same_location(kept[k], m.points[v])) ++k;
        if (k == kept.size()) kept.push_back(m.points[v]);
        index[v] = static_cast<std::uint32_t>(k);
    }
    for (Face& f : m.faces) {
        for (std::uint32_t& v : f) v = index[v];
    }
    m.points = kept;
    return m;
}

// A flat n×n grid (z = 0) with a thin triangle standing on some interior grid points: its foot
// is a separate vertex at the grid point's location, so the two touch only there (allowed), and
// a collapse that moves the grid point from under it would make the foot touch a new face inside.
Mesh grid_with_spikes(int n) {
    Mesh m;
    auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) m.points.push_back({static_cast<double>(i), static_cast<double>(j), 0});
    }
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    for (int j = 2; j < n - 1; j += 3) {
        for (int i = 2; i < n - 1; i += 3) {
            const auto foot = static_cast<std::uint32_t>(m.points.size());
            const double x = i, y = j;
            m.points.push_back({x, y, 0});
            m.points.push_back({x + 0.3, y + 0.1, 2});
            m.points.push_back({x - 0.2, y + 0.3, 2.5});
            m.faces.push_back({foot, foot + 1, foot + 2});
        }
    }
    return m;
}

// A flat grid with a square of two faces lying in it (its own vertices): coplanar overlaps, an
// input that self-intersects already.
Mesh grid_with_lying_square(int n) {
    Mesh m = grid_with_spikes(n);
    m.faces.resize(static_cast<std::size_t>(2 * n * n));
    m.points.resize(static_cast<std::size_t>((n + 1) * (n + 1)));
    const auto first = static_cast<std::uint32_t>(m.points.size());
    m.points.insert(m.points.end(), {{5.5, 5.25, 0}, {8.5, 5.25, 0}, {8.5, 8.75, 0}, {5.5, 8.75, 0}});
    m.faces.push_back({first, first + 1, first + 2});
    m.faces.push_back({first, first + 2, first + 3});
    return m;
}

TEST(MeshProperties, FlatRegionsSkipTheSearchButDecideTheSame) {
    // Every collapse the flat-region argument accepts without a search must be one the search
    // accepts too: the results with and without it are the same mesh, with no new contact.
    struct Input {
        const char* name;
        Mesh mesh;
        bool flat;
    };
    const Input inputs[] = {{"box", grid_box(12), true},
                            {"grid with spikes", grid_with_spikes(18), true},
                            {"grid with a square lying in it", grid_with_lying_square(18), true},
                            {"sphere", testing::noisy_sphere(3, 0.02, 4), false}};
    for (const Input& input : inputs) {
        const auto before = find_defects(input.mesh);
        for (double keep : {0.3, 0.1}) {
            for (int threads : {1, 3}) {
                const std::string what = std::string(input.name) + ", keep " + std::to_string(keep) + ", " +
                                         std::to_string(threads) + " threads";
                Mesh searched = input.mesh, shortcut = input.mesh;
                SimplifyOptions options;
                options.stop.value = keep;
                options.threads = threads;
                options.parallel_threshold = 0;
                options.contacts = ContactCheck::every_collapse;  // (the shortcut belongs to the search)
                options.flat_shortcut = false;
                const SimplifyStats plain = simplify(searched, options);
                options.flat_shortcut = true;
                const SimplifyStats fast = simplify(shortcut, options);
                EXPECT_EQ(plain.flat_unsearched, 0u) << what;
                if (input.flat) {
                    EXPECT_GT(fast.flat_unsearched, 0u) << what;
                } else {
                    EXPECT_EQ(fast.flat_unsearched, 0u) << what;
                }
                EXPECT_TRUE(same(searched, shortcut)) << what;
                EXPECT_EQ(plain.refused_intersection, fast.refused_intersection) << what;
                // No worse: only pairs of faces the input had can still meet.
                const auto after = find_defects(shortcut);
                EXPECT_LE(after.intersecting_pairs, before.intersecting_pairs) << what << ": " << after.first;
                EXPECT_EQ(after.total() - after.intersecting_pairs, 0u) << what << ": " << after.first;
            }
        }
    }
    EXPECT_EQ(find_defects(inputs[0].mesh).total(), 0u);
    EXPECT_EQ(find_defects(inputs[1].mesh).total(), 0u);
    EXPECT_GT(find_defects(inputs[2].mesh).intersecting_pairs, 0u);
}

// Two bumpy terrain grids of n × n cells side by side, `gap` apart along x, their facing border
// columns jittered towards each other by up to 0.45 gap: border collapses there can push one
// grid's border over the other's in the map plane.
Mesh facing_terrains(int n, double gap, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(0, 1);
    Mesh m;
    for (int part = 0; part < 2; ++part) {
        const auto first = static_cast<std::uint32_t>(m.points.size());
        const double x0 = part == 0 ? 0 : n + gap;
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                double x = x0 + i, y = j;
                const bool facing = (part == 0 && i == n) || (part == 1 && i == 0);
                if (facing) {
                    x += (part == 0 ? 1 : -1) * 0.45 * gap * unit(random);
                } else if (i > 0 && i < n && j > 0 && j < n) {
                    x += 0.2 * (unit(random) - 0.5);
                    y += 0.2 * (unit(random) - 0.5);
                }
                m.points.push_back({x, y, std::sin(0.4 * x) * std::cos(0.3 * y) + 0.3 * unit(random)});
            }
        }
        const auto w = static_cast<std::uint32_t>(n + 1);
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const std::uint32_t a = first + static_cast<std::uint32_t>(j) * w + static_cast<std::uint32_t>(i);
                m.faces.push_back({a, a + 1, a + w + 1});
                m.faces.push_back({a, a + w + 1, a + w});
            }
        }
    }
    return m;
}

// ContactCheck::at_the_end against every_collapse on clean and self-intersecting inputs: its
// result never meets itself where the input did not (the independent checker's count); it is
// every_collapse's result when that refuses no collapse for a contact, and when the first
// result met itself (then simplified again); the same for any thread count.
TEST(MeshProperties, ContactsCheckedAfterTheRunAreNeverWorse) {
    struct Input {
        std::string name;
        Mesh mesh;
        bool terrain = false;  // simplified as a terrain, its border free (checked in the map plane)
    };
    Mesh crossing = testing::noisy_sphere(3, 0.02, 7);
    {
        const Mesh second = testing::noisy_sphere(3, 0.02, 8, {0.9, 0.3, 0.1});
        const auto offset = static_cast<std::uint32_t>(crossing.points.size());
        for (const Point3& p : second.points) crossing.points.push_back(p);
        for (const Face& f : second.faces) crossing.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
    }
    const Input inputs[] = {{"smooth sphere", testing::noisy_sphere(3, 0.02, 1)},
                            {"rough sphere", testing::noisy_sphere(3, 0.3, 2)},
                            {"holed sheet", holed_sheet(30, 2, 1, 0.3, 3)},
                            {"sheets 1 ulp apart", testing::near_sheets(16, 1, 4)},
                            {"sheets 64 ulps apart", testing::near_sheets(16, 64, 5)},
                            {"folded strip", testing::folded_strip(40, 1e-3, 6)},
                            {"crossing spheres", crossing},
                            {"grid with spikes", grid_with_spikes(18)},
                            {"grid with a square lying in it", grid_with_lying_square(18)},
                            {"holed terrain", holed_sheet(30, 2, 1, 0.3, 9), true},
                            {"holed terrain, strips of two", holed_sheet(30, 2, 2, 0.3, 10), true},
                            {"noisy terrain", testing::noisy_heightfield(40, 2.0, 11), true},
                            {"terrains 1e-3 apart", facing_terrains(20, 1e-3, 12), true},
                            {"terrains 1e-9 apart", facing_terrains(20, 1e-9, 13), true}};
    int again = 0, same_without_refusal = 0, terrain_again = 0, terrain_kept = 0;
    for (const Input& input : inputs) {
        const std::uint64_t before = find_defects(input.mesh).intersecting_pairs;
        for (const double keep : {0.1, 0.02}) {
            const std::string what = input.name + ", keep " + std::to_string(keep);
            SimplifyOptions options;
            options.stop.value = keep;
            options.threads = 2;
            options.parallel_threshold = 0;
            options.terrain = input.terrain;
            Mesh each = input.mesh, after = input.mesh;
            options.contacts = ContactCheck::every_collapse;
            const SimplifyStats each_stats = simplify(each, options);
            options.contacts = ContactCheck::at_the_end;
            const SimplifyStats after_stats = simplify(after, options);
            EXPECT_FALSE(each_stats.contacts_checked_after) << what;
            EXPECT_TRUE(after_stats.contacts_checked_after) << what;
            EXPECT_EQ(after_stats.terrain, input.terrain) << what;
            if (input.terrain) {
                EXPECT_EQ(testing::count_map_plane_folds(after, 1), 0u) << what;
                ++(after_stats.simplified_again ? terrain_again : terrain_kept);
            }
            const auto defects = find_defects(after);
            EXPECT_EQ(defects.total() - defects.intersecting_pairs, 0u) << what << ": " << defects.first;
            if (after_stats.simplified_again) {
                ++again;
                EXPECT_TRUE(after_stats.contact_near.has_value()) << what;
                EXPECT_TRUE(same(after, each)) << what;
                EXPECT_EQ(after_stats.refused_intersection, each_stats.refused_intersection) << what;
            } else {
                EXPECT_FALSE(after_stats.contact_near.has_value()) << what;
                // The check was right: no face a collapse made meets another (pairs of the input's
                // faces that still meet are the input's).
                if (before == 0) {
                    EXPECT_EQ(defects.intersecting_pairs, 0u) << what << ": " << defects.first;
                }
                if (each_stats.refused_intersection == 0) {
                    ++same_without_refusal;
                    EXPECT_TRUE(same(after, each)) << what;
                }
            }
            EXPECT_LE(defects.intersecting_pairs, before) << what;
            Mesh three = input.mesh;
            options.threads = 3;
            simplify(three, options);
            EXPECT_TRUE(same(after, three)) << what << ", 3 threads";
        }
    }
    // Both ways out were taken.
    EXPECT_GT(again, 0);
    EXPECT_GT(same_without_refusal, 0);
    EXPECT_GT(terrain_again, 0);  // (the terrains side by side: their borders crossed in the map plane)
    EXPECT_GT(terrain_kept, 0);
}

TEST(MeshProperties, VerticalErrorIsTheHeightDifferenceAboveOrBelow) {
    // A unit square flat at z = 0, and the same square with a centre vertex lifted to z = 1: the
    // lifted vertex is 1 above the flat one's surface; the flat one's samples are below the
    // pyramid by 2·(distance to the border), less than 1 but more than 0.
    const Mesh flat{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}};
    const Mesh lifted{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}}, {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}};
    const VerticalError e = vertical_error(flat, lifted, 1000);
    EXPECT_EQ(e.backward.max, 1.0);
    EXPECT_GT(e.forward.max, 0.5);
    EXPECT_LT(e.forward.max, 1.0);
    EXPECT_EQ(e.outside, 0u);
    // A sample outside the other's plan is counted, not measured.
    Mesh wider = flat;
    wider.points[1].x = wider.points[2].x = 2;
    EXPECT_GT(vertical_error(wider, flat, 1000).outside, 0u);
}

TEST(MeshProperties, VerticalErrorOfASimplifiedTerrainBoundsItsHausdorffDistance) {
    // Straight above or below is one way to reach the other surface: from the same samples the
    // vertical error is never less than the distance. Locked border: the same plan, all inside.
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const Mesh input = testing::noisy_heightfield(30, 0.5, seed);
        Mesh output = input;
        simplified(output, Target::keep_fraction, 0.1, 2, true, true);
        const VerticalError vertical = vertical_error(input, output, 20000);
        const HausdorffDistance distance = hausdorff(input, output, 20000);
        EXPECT_EQ(vertical.outside, 0u);
        EXPECT_EQ(vertical.forward.samples, distance.forward.samples);
        EXPECT_EQ(vertical.backward.samples, distance.backward.samples);
        EXPECT_GE(vertical.forward.max, distance.forward.max);
        EXPECT_GE(vertical.backward.max, distance.backward.max);
        EXPECT_GE(vertical.forward.mean, distance.forward.mean);
        EXPECT_GT(vertical.max(), 0.0);
    }
}

TEST(MeshProperties, TerrainMaxErrorBoundsTheVerticalGapEverywhere) {
    // The brute-force checker clips every output face to every input face: the gap is at most
    // the bound at every corner of every piece, so everywhere. The border stays as it was.
    std::uint64_t refused = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        for (double noise : {0.2, 2.0}) {
            for (double bound : {0.0, 0.05, 0.4, 1.5}) {
                const Mesh input = testing::noisy_heightfield(16, noise, seed);
                Mesh output = input;
                const SimplifyStats stats = simplified(output, Target::max_error, bound, 2, true, false);
                const std::string what =
                    "seed " + std::to_string(seed) + ", noise " + std::to_string(noise) + ", bound " + std::to_string(bound);
                EXPECT_TRUE(stats.vertical_bound) << what;
                double largest = 0;
                EXPECT_TRUE(testing::within_vertical_gap(input, output, bound, &largest)) << what << ": gap " << largest;
                expect_clean(output, what);
                EXPECT_EQ(testing::count_map_plane_folds(output, 1), 0u) << what;
                std::size_t border = 0;
                for (const Point3& p : output.points) border += p.x == 0 || p.y == 0 || p.x == 16 || p.y == 16;
                EXPECT_EQ(border, 64u) << what;
                if (bound >= 0.4) {
                    // It does simplify, and up to near the bound, not timidly below it.
                    EXPECT_GT(stats.collapses, 20u) << what;
                    EXPECT_GT(largest, 0.5 * bound) << what;
                }
                refused += stats.refused_vertical;
            }
        }
    }
    EXPECT_GT(refused, 0u);
}

TEST(MeshProperties, TerrainMaxErrorSameResultForAnyThreadCount) {
    const Mesh input = testing::noisy_heightfield(60, 1.0, 21);
    Mesh one = input, three = input;
    const SimplifyStats a = simplified(one, Target::max_error, 0.5, 1, true, true);
    const SimplifyStats b = simplified(three, Target::max_error, 0.5, 3, true, true);
    EXPECT_GT(a.collapses, 1000u);
    EXPECT_EQ(a.collapses, b.collapses);
    EXPECT_TRUE(same(one, three));
}

}  // namespace
}  // namespace toposimp::mesh
