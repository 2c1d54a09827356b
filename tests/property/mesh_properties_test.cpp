// UGSimp on generated meshes: no self-intersection, no non-manifold edge, no flipped face or
// map-plane fold, whatever the target; the same result for any thread count. Every check is
// the independent brute-force checker's (tests/support/mesh_checker), not the engine's.
#include "core/mesh/simplify_mesh.hpp"
#include "support/mesh_checker.hpp"
#include "support/random_meshes.hpp"

#include <gtest/gtest.h>

#include <string>

namespace toposimp::mesh {
namespace {

using testing::find_defects;

MeshStats simplified(Mesh& m, MeshTarget target, double value, int threads, bool terrain = false, bool lock = false) {
    MeshOptions options;
    options.target = target;
    options.value = value;
    options.threads = threads;
    options.parallel_threshold = 0;  // every loop parallel, even on small meshes
    options.terrain = terrain;
    options.lock_boundary = lock;
    return simplify_mesh(m, options);
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
    Mesh lying = flat;
    lying.points.push_back({0.6, 0.1, 0});
    lying.points.push_back({0.9, 0.1, 0});
    lying.points.push_back({0.9, 0.4, 0});
    lying.faces.push_back({4, 5, 6});
    EXPECT_EQ(find_defects(lying).intersecting_pairs, 1u);
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
            const MeshStats stats = simplified(m, MeshTarget::keep_fraction, keep, 2);
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
    const MeshStats stats = simplified(m, MeshTarget::keep_faces, 1000, 3);
    ASSERT_TRUE(stats.target_reached);
    EXPECT_LE(m.faces.size(), 1000u);
    EXPECT_GE(m.faces.size(), 998u);  // a collapse removes two faces of a closed surface
}

TEST(MeshProperties, NoisyTerrainNeverFoldsInTheMapPlane) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
        for (bool lock : {true, false}) {
            Mesh m = testing::noisy_heightfield(40, seed % 2 == 0 ? 2.0 : 0.2, seed);
            const MeshStats stats = simplified(m, MeshTarget::keep_fraction, 0.05, 2, true, lock);
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
            const MeshStats stats = simplified(m, MeshTarget::keep_fraction, 0.05, 2);
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
        const MeshStats stats = simplified(m, MeshTarget::keep_fraction, 0.05, 2);
        expect_clean(m, "gap " + std::to_string(gap));
        EXPECT_GT(stats.collapses, 0u);
    }
}

TEST(MeshProperties, MaxErrorBoundsEveryCollapse) {
    Mesh m = testing::noisy_heightfield(40, 0.3, 9);
    const MeshStats stats = simplified(m, MeshTarget::max_error, 0.25, 2);
    EXPECT_GT(stats.collapses, 0u);
    EXPECT_LE(stats.max_error, 0.25);
    expect_clean(m, "max error");
}

TEST(MeshProperties, SameResultForAnyThreadCount) {
    const Mesh inputs[] = {testing::noisy_sphere(4, 0.05, 11), testing::noisy_heightfield(60, 1.0, 12),
                           testing::near_sheets(24, 2, 13), testing::folded_strip(60, 1e-3, 14)};
    int k = 0;
    for (const Mesh& input : inputs) {
        for (MeshTarget target : {MeshTarget::keep_fraction, MeshTarget::max_error}) {
            const double value = target == MeshTarget::keep_fraction ? 0.1 : 0.05;
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

}  // namespace
}  // namespace toposimp::mesh
