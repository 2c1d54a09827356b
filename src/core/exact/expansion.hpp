// Exact sums and products of doubles as floating-point expansions (Shewchuk, "Adaptive
// precision floating-point arithmetic and fast robust geometric predicates", 1997): a number is
// kept as a sum of non-overlapping doubles ordered by increasing magnitude, and its sign is the
// sign of its largest component. No allocation, no rounding — as long as nothing overflows or
// underflows, which the callers ensure by bounding the inputs' exponents (see in_range).
//
// Needs IEEE binary64 with round-to-nearest-even and no contraction into FMAs: only the exact
// predicates' target includes this header, compiled with -ffp-contract=off.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace toposimp::exact::expansion {

// Inputs whose non-zero magnitudes lie in [2^-150, 2^150] keep every component of the
// predicates' expansions (degree ≤ 3 in differences of inputs) far from underflow and overflow,
// and within the splitter's reach (|x| < 2^996).
inline bool in_range(double x) {
    const double m = std::fabs(x);
    return m == 0.0 || (m >= 0x1p-150 && m <= 0x1p150);
}

// The binary exponent of a finite non-zero x (std::ilogb, inline but for subnormals).
inline int exponent_of(double x) {
    const int biased = static_cast<int>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff);
    return biased != 0 ? biased - 1023 : std::ilogb(x);
}

// x·2^k, exact when the result is a normal double (std::ldexp, inline when 2^k is one).
inline double times_power_of_two(double x, int k) {
    if (k >= -1022 && k <= 1023) return x * std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52);
    return std::ldexp(x, k);
}

// Inputs beyond that range (coordinates of 10^±45 and more) would go to GMP, tens of times
// slower. The predicates whose sign is that of a polynomial homogeneous in differences of the
// inputs (orient2d, orient3d, the dot product of two normals) keep it when every input is
// multiplied by one positive number, and multiplying by a power of two is exact unless a result
// overflows or is subnormal. The exponent k that puts the largest magnitude among `values` in
// [1, 2), if 2^k scales every value exactly; 0 if not, if k is 0 (nothing to gain) or a value
// is not finite. Scale with times_power_of_two.
template <class Values>
int exact_rescaling(const Values& values) {
    double largest = 0.0;
    for (const double v : values) {
        const double m = std::fabs(v);
        if (!(m <= std::numeric_limits<double>::max())) return 0;  // (infinite or NaN)
        largest = m > largest ? m : largest;
    }
    if (largest == 0.0) return 0;
    const int k = -exponent_of(largest);
    for (const double v : values) {
        if (v != 0.0 && exponent_of(v) + k < -1022) return 0;  // would be subnormal: bits lost
    }
    return k;
}

// x + y == a + b exactly, x = fl(a + b).
inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double b_virtual = x - a;
    const double a_virtual = x - b_virtual;
    y = (a - a_virtual) + (b - b_virtual);
}

// x + y == a - b exactly, x = fl(a - b).
inline void two_diff(double a, double b, double& x, double& y) {
    x = a - b;
    const double b_virtual = a - x;
    const double a_virtual = x + b_virtual;
    y = (a - a_virtual) + (b_virtual - b);
}

// x + y == a + b exactly; requires |a| ≥ |b| (or a == 0).
inline void fast_two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    y = b - (x - a);
}

// Dekker's split: a == hi + lo with each half fitting in 26 bits.
inline void split(double a, double& hi, double& lo) {
    const double c = 134217729.0 * a;  // 2^27 + 1
    hi = c - (c - a);
    lo = a - hi;
}

// x + y == a · b exactly, with b already split.
inline void two_product_split(double a, double b, double b_hi, double b_lo, double& x, double& y) {
    x = a * b;
    double a_hi, a_lo;
    split(a, a_hi, a_lo);
    const double err1 = x - a_hi * b_hi;
    const double err2 = err1 - a_lo * b_hi;
    const double err3 = err2 - a_hi * b_lo;
    y = a_lo * b_lo - err3;
}

// A number as at most N non-overlapping components, smallest first, zeros left out.
template <int N>
struct Expansion {
    double c[N];
    int n = 0;

    int sign() const { return n == 0 ? 0 : (c[n - 1] > 0) - (c[n - 1] < 0); }
};

// a − b as an expansion of at most two components.
inline Expansion<2> difference(double a, double b) {
    Expansion<2> e;
    double x, y;
    two_diff(a, b, x, y);
    if (y != 0.0) e.c[e.n++] = y;
    if (x != 0.0) e.c[e.n++] = x;
    return e;
}

// e · b (Shewchuk's Scale-Expansion with zero elimination).
template <int N>
Expansion<2 * N> scale(const Expansion<N>& e, double b) {
    Expansion<2 * N> h;
    if (e.n == 0 || b == 0.0) return h;
    double b_hi, b_lo;
    split(b, b_hi, b_lo);
    double q, low;
    two_product_split(e.c[0], b, b_hi, b_lo, q, low);
    if (low != 0.0) h.c[h.n++] = low;
    for (int i = 1; i < e.n; ++i) {
        double product_hi, product_lo, sum;
        two_product_split(e.c[i], b, b_hi, b_lo, product_hi, product_lo);
        two_sum(q, product_lo, sum, low);
        if (low != 0.0) h.c[h.n++] = low;
        fast_two_sum(product_hi, sum, q, low);
        if (low != 0.0) h.c[h.n++] = low;
    }
    if (q != 0.0) h.c[h.n++] = q;
    return h;
}

// e + f (Shewchuk's Fast-Expansion-Sum with zero elimination): merge by magnitude, then
// accumulate.
template <int N, int M>
Expansion<N + M> sum(const Expansion<N>& e, const Expansion<M>& f) {
    Expansion<N + M> h;
    if (e.n == 0 && f.n == 0) return h;
    int i = 0, j = 0;
    // The next component of the merged sequence, by increasing magnitude.
    auto next = [&]() {
        if (j >= f.n || (i < e.n && std::fabs(e.c[i]) < std::fabs(f.c[j]))) return e.c[i++];
        return f.c[j++];
    };
    double q = next();
    const int total = e.n + f.n;
    if (total > 1) {
        double q_new, low;
        fast_two_sum(next(), q, q_new, low);
        q = q_new;
        if (low != 0.0) h.c[h.n++] = low;
        for (int k = 2; k < total; ++k) {
            two_sum(q, next(), q_new, low);
            q = q_new;
            if (low != 0.0) h.c[h.n++] = low;
        }
    }
    if (q != 0.0) h.c[h.n++] = q;
    return h;
}

template <int N>
Expansion<N> negate(Expansion<N> e) {
    for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
    return e;
}

// e · f for a two-component f.
template <int N>
Expansion<4 * N> product(const Expansion<N>& e, const Expansion<2>& f) {
    if (f.n == 0) return {};
    if (f.n == 1) {
        const Expansion<2 * N> only = scale(e, f.c[0]);
        Expansion<4 * N> h;
        for (int i = 0; i < only.n; ++i) h.c[i] = only.c[i];
        h.n = only.n;
        return h;
    }
    return sum(scale(e, f.c[0]), scale(e, f.c[1]));
}

}  // namespace toposimp::exact::expansion
