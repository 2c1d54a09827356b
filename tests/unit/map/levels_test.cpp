// Nested levels: each level's kept vertices are a subset of the level before, each keeps every
// promise against the input (independent checker), a count level keeps what a single run to the
// same target keeps, and the result is the same on any number of threads.
#include "core/map/levels.hpp"

#include "support/exact_checker.hpp"
#include "support/random_maps.hpp"

#include <gtest/gtest.h>

#include <random>

namespace toposimp::map {
namespace {

TEST(Levels, NestedEachCleanAndCountedAgainstTheInput) {
    const std::vector<StopCriterion> levels{{Target::keep_fraction, 0.6}, {Target::keep_fraction, 0.3}, {Target::keep_points, 40}};
    for (std::uint64_t seed = 1; seed <= 25; ++seed) {
        std::mt19937_64 rng(seed);
        testing::RandomMapOptions random;
        random.roads = seed % 3 == 0 ? 2 : 0;
        const MapData map = testing::random_planar_map(rng, random);
        SimplifyOptions options;
        options.parallel_threshold = 0;
        options.threads = 1;
        const std::vector<SimplifyResult> one = simplify_levels(map, options, levels);
        options.threads = 3;
        const std::vector<SimplifyResult> three = simplify_levels(map, options, levels);
        ASSERT_EQ(one.size(), levels.size());
        for (std::size_t k = 0; k < levels.size(); ++k) {
            SCOPED_TRACE("seed " + std::to_string(seed) + ", level " + std::to_string(k));
            EXPECT_EQ(one[k].kept, three[k].kept) << "depends on the threads";
            const testing::CheckReport report = testing::check_simplification(map, one[k].kept);
            EXPECT_TRUE(report.ok()) << report.summary();
            if (k > 0) {
                for (std::size_t v = 0; v < map.vertices.size(); ++v) EXPECT_LE(one[k].kept[v], one[k - 1].kept[v]) << v;
            }
            // Where a single run reaches the target, the level keeps as many vertices.
            SimplifyOptions single = options;
            single.stop = levels[k];
            const SimplifyResult alone = simplify(map, single);
            std::uint64_t kept = 0;
            for (const std::uint8_t flag : one[k].kept) kept += flag;
            if (alone.stats.target_reached && one[k].stats.target_reached) {
                EXPECT_EQ(kept, alone.stats.vertices_out);
            }
        }
    }
}

}  // namespace
}  // namespace toposimp::map
