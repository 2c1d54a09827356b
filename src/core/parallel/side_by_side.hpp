// Items of work run side by side, a thread each, or one after the other on all threads: for work
// whose own threads wait on each other (a tile's levels, whose blocks are few and uneven), a
// thread an item wastes less when there are enough items.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <exception>
#include <numeric>
#include <vector>

namespace toposimp::parallel {

// Calls work(k, threads_each) for each k in [0, count). With at least as many items as `threads`
// (≥ 2; 0 or less: OpenMP's default), side by side, a thread each (threads_each = 1), the biggest first (by size(k)); else one
// after the other, each with all `threads`. An item that throws does not stop the others side by
// side; either way the first item's exception in order reaches the caller.
template <class Size, class Work>
void side_by_side(std::size_t count, int threads, Size&& size, Work&& work) {
    if (threads <= 0) threads = omp_get_max_threads();
    if (threads < 2 || count < static_cast<std::size_t>(threads)) {
        for (std::size_t k = 0; k < count; ++k) work(k, threads);
        return;
    }
    std::vector<std::size_t> sizes(count), order(count);
    for (std::size_t k = 0; k < count; ++k) sizes[k] = size(k);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
    std::vector<std::exception_ptr> failed(count);
    const auto items = static_cast<std::ptrdiff_t>(count);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (std::ptrdiff_t i = 0; i < items; ++i) {
        const std::size_t k = order[static_cast<std::size_t>(i)];
        try {
            work(k, 1);
        } catch (...) {
            failed[k] = std::current_exception();
        }
    }
    for (const std::exception_ptr& error : failed) {
        if (error) std::rethrow_exception(error);
    }
}

}  // namespace toposimp::parallel
