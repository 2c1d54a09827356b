// Vertices and faces numbered along a Z-order (Morton) curve while simplifying, and back to the
// input's numbering for the output: what lies together in space then lies together in memory.
#include "core/mesh/simplifier.hpp"

#include <numeric>
#include <type_traits>

namespace toposimp::mesh::detail {

namespace {

// Item i (a row of `width` values) becomes the one at order[i]: the items copied aside into
// `scratch`, then gathered back in parallel. Measured on the 2 M terrain (before such inputs
// were left in their order), 2 threads: a new array for each, quadrics included, raised the
// peak memory from 327 to 419 MB; moving the items along the permutation's cycles, in place,
// reads memory at random one item at a time: +0.6 s. One scratch buffer for every array, the
// quadrics rebuilt rather than moved: 351 MB.
template <class T>
void permute(T* items, std::size_t rows, std::size_t width, const std::vector<std::uint32_t>& order, unsigned char* scratch,
             int threads) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (width == 0) return;
    T* aside = reinterpret_cast<T*>(scratch);
    std::copy_n(items, rows * width, aside);
    const auto count = static_cast<std::int64_t>(order.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::int64_t i = 0; i < count; ++i) {
        std::copy_n(aside + std::size_t{order[static_cast<std::size_t>(i)]} * width, width, items + static_cast<std::size_t>(i) * width);
    }
}

// The bits of x (10 of them) spread to every third bit: one axis of a Morton code.
std::uint64_t every_third_bit(std::uint64_t x) {
    x &= 0x3ff;
    x = (x | x << 16) & 0x30000ffULL;
    x = (x | x << 8) & 0x300f00fULL;
    x = (x | x << 4) & 0x30c30c3ULL;
    x = (x | x << 2) & 0x9249249ULL;
    return x;
}

}  // namespace

void Simplifier::renumber(const std::vector<std::uint32_t>& vertex_from, const std::vector<std::uint32_t>& face_from,
                          const std::vector<std::uint32_t>& corner_to) {
    const std::size_t n = pos_.size(), m = face_.size();
    const Attributes &vertex_rows = mesh_.vertex_attributes, &face_rows = mesh_.face_attributes;
    const std::size_t bytes = std::max({n * sizeof(Point3), m * sizeof(Face), n * vertex_rows.width * sizeof(double),
                                        m * face_rows.width * sizeof(double)});
    const auto scratch = std::make_unique_for_overwrite<unsigned char[]>(bytes);
    permute(pos_.data(), n, 1, vertex_from, scratch.get(), threads_);
    permute(mesh_.vertex_attributes.values.data(), n, vertex_rows.width, vertex_from, scratch.get(), threads_);
    permute(face_.data(), m, 1, face_from, scratch.get(), threads_);
    permute(mesh_.face_attributes.values.data(), m, face_rows.width, face_from, scratch.get(), threads_);
    for (Face& c : face_) {
        for (std::uint32_t& v : c) v = corner_to[v];
    }
}

// The mean difference of a face's corner numbers up to which a mesh's numbering counts as local.
constexpr std::uint64_t kLocalSpread = 4096;

// A vertex's number is where its data lie in memory, and meshes come numbered in any order: in
// the CGAL demo models an edge joins vertices a tenth to a third of the model apart in number
// (their mean). A block's collapses then read and write all over every per-vertex array, which
// for a model of a million faces are far bigger than the caches. Numbered along a Z-order curve
// instead, the vertices of a cube of space mostly have neighbouring numbers, and the faces,
// numbered by their lowest corner, too. Measured on two Loop subdivisions of the CGAL armadillo
// (832 k faces), 2 threads: see BENCHMARKS.md.
void Simplifier::spatial_order() {
    const std::size_t n = pos_.size(), m = face_.size();
    if (n == 0) return;
    // Already local, as a grid read row by row (a face's corners a row apart, and a row's data
    // within the caches up to some thousands of vertices): left as it is. Renumbering costs
    // about 0.1 s on the 2 M terrain and gained nothing there.
    std::uint64_t spread = 0;
    const auto faces = static_cast<std::int64_t>(m);
#pragma omp parallel for schedule(static) reduction(+ : spread) num_threads(threads_)
    for (std::int64_t f = 0; f < faces; ++f) {
        const Face& c = face_[static_cast<std::size_t>(f)];
        spread += std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]});
    }
    if (spread <= kLocalSpread * m) return;
    Box3 box = point_box(pos_[0]);
    for (const Point3& p : pos_) box.add(p);
    // 10 bits per axis (about a vertex per cell at a million vertices; more share a cell, in
    // input order), on one scale for all three: a flat terrain is ordered in its map plane. (An
    // extent that overflows, or NaN, gives every vertex the code 0: the input order.)
    const double extent = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    const double scale = extent > 0 && std::isfinite(extent) ? 0x1p10 / extent : 0.0;
    auto units = [scale](double value, double lo) -> std::uint64_t {
        const double u = (value - lo) * scale;
        if (!(u >= 1)) return 0;  // (NaN too)
        return u >= 0x1p10 - 1 ? 0x3ff : static_cast<std::uint64_t>(u);
    };
    // Code and number in one word, sorted by the code in three stable passes of 10 bits.
    std::vector<std::uint64_t> keyed(n), other(n);
    const auto count = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (std::int64_t i = 0; i < count; ++i) {
        const Point3 p = pos_[static_cast<std::size_t>(i)];
        const std::uint64_t code = every_third_bit(units(p.x, box.lo.x)) | every_third_bit(units(p.y, box.lo.y)) << 1 |
                                   every_third_bit(units(p.z, box.lo.z)) << 2;
        keyed[static_cast<std::size_t>(i)] = code << 32 | static_cast<std::uint64_t>(i);
    }
    for (int shift = 32; shift < 62; shift += 10) {
        std::vector<std::size_t> first(1025, 0);
        for (const std::uint64_t k : keyed) ++first[((k >> shift) & 0x3ff) + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());
        for (const std::uint64_t k : keyed) other[first[(k >> shift) & 0x3ff]++] = k;
        keyed.swap(other);
    }
    input_vertex_.resize(n);
    std::vector<std::uint32_t> number(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<std::uint32_t>(keyed[i]);
        input_vertex_[i] = v;
        number[v] = static_cast<std::uint32_t>(i);
    }
    // Faces by their lowest new corner number, in input order among those of one corner (a
    // counting sort).
    std::vector<std::uint32_t> first(n + 1, 0);
    auto lowest = [&](const Face& c) { return std::min({number[c[0]], number[c[1]], number[c[2]]}); };
    for (const Face& c : face_) ++first[lowest(c) + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    input_face_.resize(m);
    for (std::size_t f = 0; f < m; ++f) input_face_[first[lowest(face_[f])]++] = static_cast<std::uint32_t>(f);

    renumber(input_vertex_, input_face_, number);
    // The topology and the quadrics afresh (quicker than moving them, and their old arrays go
    // before the new ones come).
    quadric_.reset();
    build_topology();
    build_quadrics();
}

// The live faces in the order of their numbers in the input, the vertices numbered as in the
// input (drop_unused then keeps that order).
void Simplifier::input_order() {
    if (input_vertex_.empty()) return;
    std::vector<std::uint32_t> order(face_.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [this](std::uint32_t f, std::uint32_t g) { return input_face_[f] < input_face_[g]; });
    std::vector<std::uint32_t> number(input_vertex_.size());  // the inverse: where each input vertex is now
    for (std::size_t i = 0; i < input_vertex_.size(); ++i) number[input_vertex_[i]] = static_cast<std::uint32_t>(i);
    renumber(number, order, input_vertex_);
    input_vertex_.clear();
    input_face_.clear();
}

}  // namespace toposimp::mesh::detail
