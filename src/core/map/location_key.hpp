// Coordinates as a hashable, totally ordered key for exact location equality.
#pragma once

#include "core/geometry.hpp"

#include <compare>
#include <cstdint>
#include <cstring>
#include <initializer_list>

namespace toposimp::map {

// -0.0 is folded into 0.0: they are the same location.
struct LocationKey {
    std::uint64_t x, y;
    explicit LocationKey(Point p) {
        const double px = p.x == 0.0 ? 0.0 : p.x, py = p.y == 0.0 ? 0.0 : p.y;
        std::memcpy(&x, &px, sizeof x);
        std::memcpy(&y, &py, sizeof y);
    }
    Point point() const {
        Point p;
        std::memcpy(&p.x, &x, sizeof x);
        std::memcpy(&p.y, &y, sizeof y);
        return p;
    }
    friend bool operator==(const LocationKey&, const LocationKey&) = default;
    friend auto operator<=>(const LocationKey&, const LocationKey&) = default;
};

inline std::size_t hash_words(std::initializer_list<std::uint64_t> words) {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const std::uint64_t word : words) h ^= word + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
}

struct LocationKeyHash {
    std::size_t operator()(const LocationKey& k) const { return hash_words({k.x, k.y}); }
};

}  // namespace toposimp::map
