// The grid of published coordinates: the multiples k·s of a decimal step s = m·10^e, each taken
// as the double nearest to k·s — the double a reader gets when it parses the decimal text of
// k·s. A coordinate put on this grid is written by a shortest round-trip printer as that short
// decimal (GeoJSON: 12.3457, not 12.345700000000001) and reads back bit for bit everywhere.
#pragma once

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace toposimp::map {

__extension__ using Int128 = __int128;            // (GCC and Clang)
__extension__ using UInt128 = unsigned __int128;

// The index among round(q) − 1, round(q), round(q) + 1 whose value at(k) is nearest to x (the
// lowest on a tie): q, the approximate index, may be off by the rounding of its computation.
template <class At>
std::int64_t nearest_index(double x, double q, At&& at) {
    const auto k = static_cast<std::int64_t>(std::llround(q));
    std::int64_t best = k - 1;
    double best_distance = std::abs(at(k - 1) - x);
    for (const std::int64_t c : {k, k + 1}) {
        const double distance = std::abs(at(c) - x);
        if (distance < best_distance) best = c, best_distance = distance;
    }
    return best;
}

struct GridStep {
    std::int64_t mantissa = 1;  // m > 0, at most 15 digits
    int exponent = 0;           // e

    // "0.0001", "1e-4", "25", "2.5E3": a positive decimal; nullopt for anything else (zero,
    // negative, not finite, more than 15 significant digits, exponent beyond ±300).
    static std::optional<GridStep> parse(std::string_view text) {
        std::string digits;
        int exponent = 0;
        bool point = false, any = false;
        std::size_t at = 0;
        for (; at < text.size(); ++at) {
            const char c = text[at];
            if (c >= '0' && c <= '9') {
                any = true;
                if (digits.empty() && c == '0') {
                    if (point) --exponent;
                    continue;
                }
                digits += c;
                if (point) --exponent;
            } else if (c == '.' && !point) {
                point = true;
            } else {
                break;
            }
        }
        if (!any) return std::nullopt;
        if (at < text.size()) {
            if (text[at] != 'e' && text[at] != 'E') return std::nullopt;
            std::string_view rest = text.substr(at + 1);
            if (!rest.empty() && rest.front() == '+') rest.remove_prefix(1);
            int written = 0;
            const auto result = std::from_chars(rest.data(), rest.data() + rest.size(), written);
            if (result.ec != std::errc() || result.ptr != rest.data() + rest.size() || written < -400 || written > 400) return std::nullopt;
            exponent += written;
        }
        while (!digits.empty() && digits.back() == '0') {
            digits.pop_back();
            ++exponent;
        }
        if (digits.empty() || digits.size() > 15 || exponent < -300 || exponent > 300) return std::nullopt;
        return GridStep{std::stoll(digits), exponent};
    }

    // A step of 10^-d: d decimals.
    static GridStep decimals(int d) { return {1, -d}; }

    // The double nearest to k·s.
    double at(std::int64_t k) const {
        // |k| < 2^62 and m < 10^15 < 2^50: the product fits in 128 bits.
        const Int128 product = static_cast<Int128>(k) * mantissa;
        // Clinger's fast path: k·m and 10^|e| both exact doubles, so one IEEE multiplication or
        // division, correctly rounded, gives the double nearest to k·m·10^e, as parsing would.
        constexpr Int128 kExact = Int128{1} << 53;
        if (product <= kExact && product >= -kExact && exponent >= -22 && exponent <= 22) {
            constexpr double kPowers[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                          1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
            const auto exact = static_cast<double>(product);
            return exponent >= 0 ? exact * kPowers[exponent] : exact / kPowers[-exponent];
        }
        return parsed_at(k);
    }

    // The same, by writing k·m·10^e as text and parsing it (any k, m and e).
    double parsed_at(std::int64_t k) const {
        const Int128 product = static_cast<Int128>(k) * mantissa;
        UInt128 magnitude = product < 0 ? static_cast<UInt128>(-product) : static_cast<UInt128>(product);
        // The digits of k·m backwards to the middle of the buffer, then "e" and the exponent.
        char text[96];
        char* const middle = text + 48;
        char* p = middle;
        do {
            *--p = static_cast<char>('0' + static_cast<int>(magnitude % 10));
            magnitude /= 10;
        } while (magnitude != 0);
        if (product < 0) *--p = '-';
        char* end = middle;
        *end++ = 'e';
        end = std::to_chars(end, text + sizeof text, exponent).ptr;
        double value = 0;
        std::from_chars(p, end, value);
        return value;
    }

    double step() const { return at(1); }

    // The index k of a grid value nearest to x (the lower on a tie); nullopt when |x| / s
    // reaches 2^62 (a grid too fine for the coordinates).
    std::optional<std::int64_t> nearest(double x) const {
        const double q = x / step();
        if (!(std::abs(q) < 0x1p62)) return std::nullopt;
        return nearest_index(x, q, [this](std::int64_t k) { return at(k); });
    }

    // The step as text, e.g. "0.0001" or "25".
    std::string text() const {
        std::string digits = std::to_string(mantissa);
        if (exponent >= 0) return digits + std::string(static_cast<std::size_t>(exponent), '0');
        const auto shift = static_cast<std::size_t>(-exponent);
        if (digits.size() <= shift) digits = std::string(shift - digits.size() + 1, '0') + digits;
        const std::size_t whole = digits.size() - shift;
        return digits.substr(0, whole) + "." + digits.substr(whole);
    }
};

// One axis of the grid of published coordinates: the decimal multiples of a step, or the
// positions a quantized TopoJSON decodes to — q·scale + translate, the product and the sum each
// rounded to double, as its clients compute them (no fused multiply-add: ISO C++ mode, and no
// FMA instructions in the baseline x86-64 target).
struct AxisGrid {
    std::optional<GridStep> decimal;  // the decimal grid, when set
    double scale = 1, translate = 0;  // otherwise the quantized one

    static AxisGrid of(const GridStep& step) {
        AxisGrid grid;
        grid.decimal = step;
        return grid;
    }
    static AxisGrid quantized(double scale, double translate) {
        AxisGrid grid;
        grid.scale = scale;
        grid.translate = translate;
        return grid;
    }

    double at(std::int64_t k) const {
        if (decimal) return decimal->at(k);
        const double product = static_cast<double>(k) * scale;
        return product + translate;
    }
    double step() const { return decimal ? decimal->step() : scale; }

    // The index of a grid value nearest to x; nullopt when the grid is too fine for it.
    std::optional<std::int64_t> nearest(double x) const {
        if (decimal) return decimal->nearest(x);
        const double q = (x - translate) / scale;
        if (!(std::abs(q) < 0x1p52)) return std::nullopt;
        return nearest_index(x, q, [this](std::int64_t k) { return at(k); });
    }

    // Is x a value of the grid?
    bool holds(double x) const {
        const std::optional<std::int64_t> k = nearest(x);
        return k && at(*k) == x;
    }
};

// The grid of published coordinates, per axis: one decimal step for both (--precision), or a
// TopoJSON quantization (its own scale and translate per axis).
struct OutputGrid {
    AxisGrid x, y;

    OutputGrid() = default;
    OutputGrid(const GridStep& step) : x(AxisGrid::of(step)), y(AxisGrid::of(step)) {}  // NOLINT: a step is a grid
    OutputGrid(const AxisGrid& along_x, const AxisGrid& along_y) : x(along_x), y(along_y) {}

    double step() const { return std::max(x.step(), y.step()); }
    std::string text() const {
        if (x.decimal) return x.decimal->text();
        char text[160];
        std::snprintf(text, sizeof text, "quantized: scale %.17g, %.17g; translate %.17g, %.17g", x.scale, y.scale, x.translate, y.translate);
        return text;
    }
};

}  // namespace toposimp::map
