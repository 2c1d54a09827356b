// The k-th smallest (key, id) of pairs held apart, found digit by digit from the parts'
// histograms (parallel::select_kth_by_digits), against sorting every pair.
#include "core/parallel/select.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

namespace toposimp::parallel {
namespace {

using Pair = std::pair<std::uint64_t, std::uint32_t>;

KeyedSelection select(const std::vector<std::vector<Pair>>& parts, std::uint64_t k, std::size_t& questions) {
    questions = 0;
    return select_kth_by_digits(
        parts.size(), k,
        [&](std::size_t part, int shift, std::uint64_t high, std::vector<std::uint64_t>& counts) {
            ++questions;
            for (const auto& [key, id] : parts[part]) {
                if (shift == 48 || key >> (shift + 16) == high) ++counts[key >> shift & 0xffff];
            }
        },
        [&](std::size_t part, std::uint64_t key, std::vector<std::uint32_t>& ids) {
            for (const auto& [own, id] : parts[part]) {
                if (own == key) ids.push_back(id);
            }
        });
}

TEST(SelectByDigits, FindsTheKthPairWhateverTheParts) {
    std::mt19937_64 rng(3);
    for (const int kind : {0, 1, 2, 3}) {
        // Keys spread over all 64 bits, crowded in a few values (ties by id), sharing their high
        // digits and differing in the lowest, or the extremes of the range.
        std::vector<Pair> pairs;
        for (std::uint32_t id = 0; id < 3000; ++id) {
            std::uint64_t key = rng();
            if (kind == 1) key = rng() % 5;
            if (kind == 2) key = 0x7ff0123400000000ull | (rng() % 70000);
            if (kind == 3) key = rng() % 2 == 0 ? 0 : ~std::uint64_t{0};
            pairs.push_back({key, id * 7 % 3001});  // (ids distinct, not in key order)
        }
        std::vector<Pair> sorted = pairs;
        std::sort(sorted.begin(), sorted.end());
        for (const std::size_t count : {std::size_t{1}, std::size_t{3}, std::size_t{40}}) {
            std::vector<std::vector<Pair>> parts(count);
            for (const Pair& pair : pairs) parts[rng() % count].push_back(pair);
            for (const std::uint64_t k : {std::uint64_t{1}, std::uint64_t{2}, std::uint64_t{1500}, std::uint64_t{2999}, std::uint64_t{3000}}) {
                std::size_t questions = 0;
                const KeyedSelection found = select(parts, k, questions);
                EXPECT_EQ(found.key, sorted[k - 1].first) << "kind " << kind << ", parts " << count << ", k " << k;
                EXPECT_EQ(found.id, sorted[k - 1].second) << "kind " << kind << ", parts " << count << ", k " << k;
                EXPECT_EQ(questions, 4 * count) << "four histograms a part";
            }
        }
    }
}

}  // namespace
}  // namespace toposimp::parallel
