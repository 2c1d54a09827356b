// The k-th smallest of many keys held in several lists, in parallel: the round threshold of both
// engines' count targets (the map's smallest effective areas, the mesh's cheapest collapses).
//
// Keys are 64-bit unsigned integers (ordered_bits() turns doubles into such keys, in their
// order). A histogram of the keys' top 16 bits is counted in parallel, one list at a time per
// thread; the bucket holding the k-th key is found; then, in parallel again, each list counts its
// keys in lower buckets and collects those in that bucket, among which the k-th is selected
// (std::nth_element). The answer depends only on the keys, never on the thread count or on how
// the keys are split into lists.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace toposimp::parallel {

// A double as an unsigned integer in the same order: bigger doubles, bigger keys (never for
// NaN; −0 is taken as +0, which it equals).
inline std::uint64_t ordered_bits(double value) {
    const auto bits = std::bit_cast<std::uint64_t>(value + 0.0);
    return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

// The double of an ordered_bits() key.
inline double from_ordered_bits(std::uint64_t key) {
    return std::bit_cast<double>((key >> 63) != 0 ? key & ~(std::uint64_t{1} << 63) : ~key);
}

struct Selection {
    std::uint64_t key = 0;             // the k-th smallest key
    std::vector<std::uint64_t> less;   // per list: how many of its keys are smaller
    std::vector<std::uint64_t> equal;  // per list: how many equal it
};

// The k-th smallest (k from 1 to the number of keys) of the keys key_of(item) of every item of
// every list of `lists` (a vector of ranges), with each list's counts below and at it.
template <class Lists, class KeyOf>
Selection select_kth(const Lists& lists, std::size_t k, int threads, KeyOf key_of) {
    constexpr int kShift = 48;  // the histogram's digit: the keys' top 16 bits
    const auto n = static_cast<std::int64_t>(lists.size());
    std::vector<std::uint64_t> histogram(std::size_t{1} << (64 - kShift), 0);
#pragma omp parallel num_threads(threads)
    {
        std::vector<std::uint64_t> mine(histogram.size(), 0);
#pragma omp for schedule(dynamic, 1) nowait
        for (std::int64_t i = 0; i < n; ++i) {
            for (const auto& item : lists[static_cast<std::size_t>(i)]) ++mine[key_of(item) >> kShift];
        }
#pragma omp critical(toposimp_select_histogram)
        for (std::size_t d = 0; d < histogram.size(); ++d) histogram[d] += mine[d];
    }
    std::uint64_t digit = 0, below = 0;
    while (below + histogram[digit] < k) below += histogram[digit++];

    Selection selection;
    selection.less.assign(lists.size(), 0);
    selection.equal.assign(lists.size(), 0);
    std::vector<std::vector<std::uint64_t>> in_bucket(lists.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (std::int64_t i = 0; i < n; ++i) {
        const auto l = static_cast<std::size_t>(i);
        for (const auto& item : lists[l]) {
            const std::uint64_t key = key_of(item), d = key >> kShift;
            if (d < digit) ++selection.less[l];
            if (d == digit) in_bucket[l].push_back(key);
        }
    }
    std::vector<std::uint64_t> bucket;
    bucket.reserve(histogram[digit]);
    for (const auto& list : in_bucket) bucket.insert(bucket.end(), list.begin(), list.end());
    const auto at = bucket.begin() + static_cast<std::ptrdiff_t>(k - below - 1);
    std::nth_element(bucket.begin(), at, bucket.end());
    selection.key = *at;
    for (std::size_t l = 0; l < lists.size(); ++l) {
        for (const std::uint64_t key : in_bucket[l]) {
            selection.less[l] += key < selection.key;
            selection.equal[l] += key == selection.key;
        }
    }
    return selection;
}

// The k-th smallest (key, id) pair (k from 1 to the number of pairs; ids distinct) of pairs held
// apart, in parts that are only asked questions — tiles on other processes, each question one
// reduction over them, none ever gathering the keys: four passes over the keys' 16-bit digits,
// high to low, each the sum of one histogram per part of the digit among the keys whose higher
// digits the passes before fixed; then the ids of the keys equal to the one found, from every
// part (ties: few), of which the rank-th.
//   histogram(part, shift, high, counts): adds to counts[d] (65 536 of them), for each of the
//     part's keys whose bits above shift + 16 equal `high` (all keys when shift is 48), one
//     where d is its 16 bits from `shift`;
//   ids_at(part, key, ids): appends the ids of the part's pairs with that key.
struct KeyedSelection {
    std::uint64_t key = 0;
    std::uint32_t id = 0;
};

// select_kth_by_digits a step at a time, for parts asked by messages: while counting(), sum
// every part's histogram(shift(), high()) and give it to counted(); then choose() among every
// part's ids_at(key()).
class DigitSelector {
public:
    explicit DigitSelector(std::uint64_t k) : k_(k) {}
    bool counting() const { return shift_ >= 0; }
    int shift() const { return shift_; }
    std::uint64_t high() const { return high_; }
    // The pass's histogram, summed over the parts (65 536 counts).
    void counted(const std::vector<std::uint64_t>& total) {
        std::uint64_t digit = 0;
        while (digit + 1 < total.size() && total[digit] < k_) k_ -= total[digit++];
        high_ = high_ << 16 | digit;
        shift_ -= 16;
    }
    std::uint64_t key() const { return high_; }
    std::uint64_t rank() const { return k_; }  // among the ids at key(), once counting is over
    KeyedSelection choose(std::vector<std::uint32_t> ids) const {
        const auto at = ids.begin() + static_cast<std::ptrdiff_t>(k_ - 1);
        std::nth_element(ids.begin(), at, ids.end());
        return {high_, *at};
    }

private:
    std::uint64_t k_;
    int shift_ = 48;
    std::uint64_t high_ = 0;  // the digits fixed so far
};

template <class Histogram, class IdsAt>
KeyedSelection select_kth_by_digits(std::size_t parts, std::uint64_t k, Histogram&& histogram, IdsAt&& ids_at) {
    DigitSelector selector(k);
    std::vector<std::uint64_t> total(std::size_t{1} << 16), counts(total.size());
    while (selector.counting()) {
        std::fill(total.begin(), total.end(), 0);
        for (std::size_t part = 0; part < parts; ++part) {
            std::fill(counts.begin(), counts.end(), 0);
            histogram(part, selector.shift(), selector.high(), counts);
            for (std::size_t d = 0; d < total.size(); ++d) total[d] += counts[d];
        }
        selector.counted(total);
    }
    std::vector<std::uint32_t> ids;
    for (std::size_t part = 0; part < parts; ++part) ids_at(part, selector.key(), ids);
    return selector.choose(std::move(ids));
}

}  // namespace toposimp::parallel
