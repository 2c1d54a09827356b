// Big arrays that parallel loops fill: resize() leaves their elements uninitialized instead of
// zeroing them on one thread first, so each page is first touched (and faulted in) by the
// thread that fills it. Only for trivial element types, and every element must be written
// before it is read.
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace toposimp {

template <class T>
struct NoInitAllocator : std::allocator<T> {
    static_assert(std::is_trivially_default_constructible_v<T>);

    NoInitAllocator() = default;
    template <class U>
    NoInitAllocator(const NoInitAllocator<U>&) noexcept {}

    template <class U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;  // default-initialization: no value written
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

template <class T>
using FillLater = std::vector<T, NoInitAllocator<T>>;

}  // namespace toposimp
