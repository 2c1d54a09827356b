#include "core/mesh/distance.hpp"

#include "core/exact/predicates.hpp"
#include "core/mesh/plan_index.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

namespace toposimp::mesh {
namespace {

struct V {
    double x, y, z;
};
V operator-(V a, V b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V operator+(V a, V b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V operator*(double s, V a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V a, V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V cross(V a, V b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V v(Point3 p) { return {p.x, p.y, p.z}; }

// Squared distance from p to triangle abc (closest point by Voronoi regions: Ericson,
// Real-Time Collision Detection, §5.1.5).
double distance2(V p, V a, V b, V c) {
    const V ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    auto len2 = [](V x) { return dot(x, x); };
    if (d1 <= 0 && d2 <= 0) return len2(ap);
    const V bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return len2(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return len2(p - (a + (d1 / (d1 - d3)) * ab));
    const V cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return len2(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return len2(p - (a + (d2 / (d2 - d6)) * ac));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return len2(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
    const double denominator = va + vb + vc;
    if (!(denominator != 0)) return std::min({len2(ap), len2(bp), len2(cp)});
    const double s = vb / denominator, t = vc / denominator;
    return len2(p - (a + s * ab + t * ac));
}

// Might triangle abc meet the box centred at `centre` with half-sides `half`? The separating axis
// test (Akenine-Möller 2001): the box's axes are left to the caller (the cells tried lie in the
// triangle's box), then the triangle's normal and the nine cross products of its edges with the
// axes. A measurement's filter, not a predicate: `half` comes in enlarged, so rounding can only
// keep a cell, never drop one the triangle touches.
bool triangle_meets_box(V a, V b, V c, V centre, V half) {
    a = a - centre, b = b - centre, c = c - centre;
    const V edges[3] = {b - a, c - b, a - c};
    const double h[3] = {half.x, half.y, half.z};
    auto separated = [&](V axis) {
        const double pa = dot(axis, a), pb = dot(axis, b), pc = dot(axis, c);
        const double r = h[0] * std::fabs(axis.x) + h[1] * std::fabs(axis.y) + h[2] * std::fabs(axis.z);
        return std::min({pa, pb, pc}) > r || std::max({pa, pb, pc}) < -r;
    };
    for (const V& e : edges) {
        if (separated({0, -e.z, e.y}) || separated({e.z, 0, -e.x}) || separated({-e.y, e.x, 0})) return false;
    }
    return !separated(cross(edges[0], edges[1]));
}

// A uniform grid of cubic cells over a mesh's points, for nearest-face searches: FaceGrid's, and
// the sweep's of one_way_near. Points beyond it (of another mesh) fall in its edge cells.
struct Cells {
    V lo{0, 0, 0}, hi{0, 0, 0};
    double size = 1.0, inverse = 1.0;  // (cells are found by multiplying: a division per coordinate cost more)
    std::int64_t n[3] = {1, 1, 1};

    Cells() = default;
    // Sized for `m` (not empty), on `team` threads; the same cells for any thread count.
    Cells(const Mesh& m, int team) {
        constexpr std::size_t kChunk = 1 << 12;
        const std::size_t faces = m.faces.size();
        const std::size_t points = m.points.size(), point_chunks = (points + kChunk - 1) / kChunk;
        // The box of the points, and the mean edge and area of up to 8 192 faces spread over the
        // mesh (the cell size needs no more; the distances do not depend on it), in fixed chunks
        // on all threads, the chunks' sums added in order: the same numbers for any thread count.
        std::vector<std::pair<V, V>> boxes(point_chunks);
#pragma omp parallel for schedule(static) num_threads(team) if (point_chunks > 1)
        for (std::int64_t k = 0; k < static_cast<std::int64_t>(point_chunks); ++k) {
            const std::size_t first = static_cast<std::size_t>(k) * kChunk, last = std::min(points, first + kChunk);
            V low = v(m.points[first]), high = low;
            for (std::size_t i = first; i < last; ++i) {
                const V p = v(m.points[i]);
                low = {std::min(low.x, p.x), std::min(low.y, p.y), std::min(low.z, p.z)};
                high = {std::max(high.x, p.x), std::max(high.y, p.y), std::max(high.z, p.z)};
            }
            boxes[static_cast<std::size_t>(k)] = {low, high};
        }
        lo = boxes[0].first, hi = boxes[0].second;
        for (const auto& [low, high] : boxes) {
            lo = {std::min(lo.x, low.x), std::min(lo.y, low.y), std::min(lo.z, low.z)};
            hi = {std::max(hi.x, high.x), std::max(hi.y, high.y), std::max(hi.z, high.z)};
        }
        const std::size_t stride = std::max<std::size_t>(1, faces / 8192);
        double edges = 0, area = 0;
        std::size_t measured = 0;
        for (std::size_t i = 0; i < faces; i += stride, ++measured) {
            const Face& f = m.faces[i];
            for (int c = 0; c < 3; ++c) {
                const V e = v(m.points[f[c]]) - v(m.points[f[(c + 1) % 3]]);
                edges += std::sqrt(dot(e, e));
            }
            const V normal = cross(v(m.points[f[1]]) - v(m.points[f[0]]), v(m.points[f[2]]) - v(m.points[f[0]]));
            area += 0.5 * std::sqrt(dot(normal, normal));
        }
        // Cells two thirds of the mean edge, or twice the side of a face's mean area if that is
        // smaller: long thin faces (a fan) have long edges and little area, and cells as long
        // as their edges would each list most of them.
        size = 2.0 * edges / (3.0 * static_cast<double>(measured));
        const double by_area = 2.0 * std::sqrt(area / static_cast<double>(measured));
        if (by_area > 0 && by_area < size) size = by_area;
        const double largest = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
        if (!(size > 0)) size = largest > 0 ? largest : 1.0;
        // At most ~2^24 cells in all.
        for (;;) {
            for (int k = 0; k < 3; ++k) n[k] = static_cast<std::int64_t>(extent(k) / size) + 1;
            if (static_cast<double>(n[0]) * static_cast<double>(n[1]) * static_cast<double>(n[2]) <= 16777216.0) break;
            size *= 1.5;
        }
        inverse = 1.0 / size;
    }

    static double coordinate(V p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }
    double origin(int k) const { return coordinate(lo, k); }
    double extent(int k) const { return coordinate(hi, k) - coordinate(lo, k); }
    std::int64_t cell(double value, int k) const {
        // (Truncation floors what is not negative.)
        const double c = (value - origin(k)) * inverse;
        if (!(c >= 0)) return 0;
        return c >= static_cast<double>(n[k] - 1) ? n[k] - 1 : static_cast<std::int64_t>(c);
    }
    std::int64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const { return (x * n[1] + y) * n[2] + z; }
    double count() const { return static_cast<double>(n[0]) * static_cast<double>(n[1]) * static_cast<double>(n[2]); }
};

// Faces of a mesh in a uniform grid, for nearest-face queries by growing shells of cells. A face
// is listed in the cells of its box that it may meet (triangle_meets_box), not in all of them:
// the long thin faces of a fan (a polygon triangulated from one corner) span boxes of hundreds of
// cells each, and listing them there made every query near the fan test most of its faces (a
// 5 000-corner polygon: 1.8 s of measurement, issue 29). The search below stays exact: a face not
// listed in the cells searched has no point in them.
// With `near` (and `radius`), only the cells within `radius` cells of one of those points are
// filled: nearest() is then exact for those points while its search stays within `radius`
// shells, and returns NaN when it would have to go further. (When those cells would be most of
// the grid, every cell is filled.)
class FaceGrid {
public:
    // Built on `threads` threads (0: OpenMP's default) when big; the grid is the same for any.
    explicit FaceGrid(const Mesh& m, std::span<const V> near = {}, std::int64_t radius = 0, int threads = 0) : mesh_(m) {
        if (m.faces.empty()) return;
        const std::size_t faces = m.faces.size(), chunks = (faces + kChunk - 1) / kChunk;
        const int team = threads > 0 ? threads : omp_get_max_threads();
        cells_ = Cells(m, team);
        // With `near`: the cells wanted, and the same at 8 × 8 × 8 coarser (small enough to stay in
        // cache), to pass over the faces far from every point with one look each.
        std::vector<std::uint8_t> wanted, coarse;
        const std::int64_t coarse_n[3] = {(cells_.n[0] + 7) / 8, (cells_.n[1] + 7) / 8, (cells_.n[2] + 7) / 8};
        auto coarse_key = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
            return static_cast<std::size_t>(((x / 8) * coarse_n[1] + y / 8) * coarse_n[2] + z / 8);
        };
        const double side = 2.0 * static_cast<double>(radius) + 1.0;
        const double cells_wanted = static_cast<double>(near.size()) * side * side * side;
        if (!near.empty() && cells_wanted < static_cast<double>(cells_.n[0]) * static_cast<double>(cells_.n[1]) * static_cast<double>(cells_.n[2])) {
            limit_ = radius;
            coarse.assign(static_cast<std::size_t>(coarse_n[0] * coarse_n[1] * coarse_n[2]), 0);
            wanted.assign(static_cast<std::size_t>(cells_.n[0] * cells_.n[1] * cells_.n[2]), 0);
            for (const V& p : near) {
                const std::int64_t c[3] = {cell(p.x, 0), cell(p.y, 1), cell(p.z, 2)};
                for (std::int64_t x = std::max<std::int64_t>(0, c[0] - radius); x <= std::min(cells_.n[0] - 1, c[0] + radius); ++x) {
                    for (std::int64_t y = std::max<std::int64_t>(0, c[1] - radius); y <= std::min(cells_.n[1] - 1, c[1] + radius); ++y) {
                        for (std::int64_t z = std::max<std::int64_t>(0, c[2] - radius); z <= std::min(cells_.n[2] - 1, c[2] + radius); ++z) {
                            wanted[static_cast<std::size_t>(key(x, y, z))] = 1;
                            coarse[coarse_key(x, y, z)] = 1;
                        }
                    }
                }
            }
        }
        std::vector<std::vector<std::pair<std::int64_t, std::uint32_t>>> listed(chunks);
#pragma omp parallel for schedule(dynamic, 1) num_threads(team) if (chunks > 1)
        for (std::int64_t chunk = 0; chunk < static_cast<std::int64_t>(chunks); ++chunk) {
            auto& entries = listed[static_cast<std::size_t>(chunk)];
            const auto first = static_cast<std::uint32_t>(static_cast<std::size_t>(chunk) * kChunk);
            const auto last = static_cast<std::uint32_t>(std::min(faces, static_cast<std::size_t>(first) + kChunk));
            for (std::uint32_t f = first; f < last; ++f) {
                std::int64_t lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    double a = coordinate(m.points[m.faces[f][0]], k), b = a;
                    for (int c = 1; c < 3; ++c) {
                        a = std::min(a, coordinate(m.points[m.faces[f][c]], k));
                        b = std::max(b, coordinate(m.points[m.faces[f][c]], k));
                    }
                    lo[k] = cell(a, k);
                    hi[k] = cell(b, k);
                }
                if (!coarse.empty()) {
                    bool near_one = false;
                    for (std::int64_t x = lo[0] / 8; x <= hi[0] / 8 && !near_one; ++x) {
                        for (std::int64_t y = lo[1] / 8; y <= hi[1] / 8 && !near_one; ++y) {
                            for (std::int64_t z = lo[2] / 8; z <= hi[2] / 8 && !near_one; ++z) near_one = coarse[coarse_key(8 * x, 8 * y, 8 * z)];
                        }
                    }
                    if (!near_one) continue;
                }
                // (A face whose box spans 2 × 2 × 2 cells or fewer is listed in all of them: the
                // separating axis test costs more than the few extra faces a search then measures.)
                const bool few_cells = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1) <= 8;
                const V a = v(m.points[m.faces[f][0]]), b = v(m.points[m.faces[f][1]]), c = v(m.points[m.faces[f][2]]);
                // Half a cell, and a millionth more (with the cells' clamping at the grid's edges,
                // a cell of the edge row may hold points beyond it: those rows take the whole box).
                const double half = 0.5 * cells_.size * (1.0 + 1e-6);
                for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                            const bool edge = x == cells_.n[0] - 1 || y == cells_.n[1] - 1 || z == cells_.n[2] - 1 || x == 0 || y == 0 || z == 0;
                            const V centre{cells_.lo.x + (static_cast<double>(x) + 0.5) * cells_.size, cells_.lo.y + (static_cast<double>(y) + 0.5) * cells_.size,
                                           cells_.lo.z + (static_cast<double>(z) + 0.5) * cells_.size};
                            if (!wanted.empty() && !wanted[static_cast<std::size_t>(key(x, y, z))]) continue;
                            if (few_cells || edge || triangle_meets_box(a, b, c, centre, {half, half, half})) {
                                entries.emplace_back(key(x, y, z), f);
                            }
                        }
                    }
                }
            }
        }
        // By cell, and by face within a cell (the chunks are in face order): a counting sort.
        std::size_t total = 0;
        for (const auto& part : listed) total += part.size();
        const auto cells = static_cast<std::size_t>(cells_.n[0] * cells_.n[1] * cells_.n[2]);
        faces_.resize(total);
        // (A count per cell: at most 16 MB more than the entries, or 16 bytes a cell per entry.)
        if ((cells <= 4 * total || cells <= (std::size_t{1} << 22)) && total < std::numeric_limits<std::uint32_t>::max()) {
            // Kept: cell c's faces are faces_[start_[c], start_[c + 1]).
            start_.assign(cells + 1, 0);
            for (const auto& part : listed) {
                for (const auto& [cell_key, face] : part) ++start_[static_cast<std::size_t>(cell_key) + 1];
            }
            for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
            for (const auto& part : listed) {
                for (const auto& [cell_key, face] : part) faces_[start_[static_cast<std::size_t>(cell_key)]++] = face;
            }
            // (Each start_[c] moved on to where cell c + 1 begins: one place back.)
            for (std::size_t c = cells; c > 0; --c) start_[c] = start_[c - 1];
            start_[0] = 0;
        } else {
            // Sorted by cell in passes of 12 bits of the key, each stable (a counting sort), so
            // each cell's faces stay in face order. (std::sort took 0.08 s of the quick measure's
            // 0.13 s on armadillo-832k, 1.4 M entries in 8.5 M cells; these passes, two, ~0.01 s.)
            keys_.resize(total);
            std::vector<std::pair<std::int64_t, std::uint32_t>> entries, other(total);
            entries.reserve(total);
            for (const auto& part : listed) entries.insert(entries.end(), part.begin(), part.end());
            for (int shift = 0; shift < 63 && (std::uint64_t{1} << shift) < cells; shift += 12) {
                std::vector<std::size_t> first(4097, 0);
                for (const auto& entry : entries) ++first[((static_cast<std::uint64_t>(entry.first) >> shift) & 4095) + 1];
                std::partial_sum(first.begin(), first.end(), first.begin());
                for (const auto& entry : entries) other[first[(static_cast<std::uint64_t>(entry.first) >> shift) & 4095]++] = entry;
                entries.swap(other);
            }
            for (std::size_t i = 0; i < entries.size(); ++i) keys_[i] = entries[i].first, faces_[i] = entries[i].second;
        }
    }

    // The distance from p to the nearest face; with `near` (see above), NaN if the search would
    // leave the cells filled.
    double nearest(V p) const {
        double best = std::numeric_limits<double>::infinity();
        if (mesh_.faces.empty()) return best;
        const std::int64_t c[3] = {cell(p.x, 0), cell(p.y, 1), cell(p.z, 2)};
        const std::int64_t most = std::max({cells_.n[0], cells_.n[1], cells_.n[2]});
        for (std::int64_t r = 0; r <= most; ++r) {
            if (limit_ >= 0 && r > limit_) return std::numeric_limits<double>::quiet_NaN();
            for (std::int64_t x = c[0] - r; x <= c[0] + r; ++x) {
                for (std::int64_t y = c[1] - r; y <= c[1] + r; ++y) {
                    for (std::int64_t z = c[2] - r; z <= c[2] + r; ++z) {
                        const bool shell = std::max({std::llabs(x - c[0]), std::llabs(y - c[1]), std::llabs(z - c[2])}) == r;
                        if (!shell || x < 0 || y < 0 || z < 0 || x >= cells_.n[0] || y >= cells_.n[1] || z >= cells_.n[2]) continue;
                        if (r > 0 && beyond(p, x, y, z, best)) continue;
                        const auto [first, last] = listed_in(key(x, y, z));
                        for (std::size_t i = first; i < last; ++i) {
                            const Face& f = mesh_.faces[faces_[i]];
                            best = std::min(best, distance2(p, v(mesh_.points[f[0]]), v(mesh_.points[f[1]]), v(mesh_.points[f[2]])));
                        }
                    }
                }
            }
            // A face listed in no cell searched has its box, so all its points, in the grid
            // outside the block of cells within r of p's: at least as far from p as the nearest
            // side of that block with grid beyond it (p lies within such a side's slab; a side
            // with no grid beyond it bounds nothing). No such side: every face was searched.
            double reach = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 3; ++k) {
                const double at = k == 0 ? p.x : (k == 1 ? p.y : p.z), origin = k == 0 ? cells_.lo.x : (k == 1 ? cells_.lo.y : cells_.lo.z);
                if (c[k] - r > 0) reach = std::min(reach, at - (origin + static_cast<double>(c[k] - r) * cells_.size));
                if (c[k] + r + 1 < cells_.n[k]) reach = std::min(reach, origin + static_cast<double>(c[k] + r + 1) * cells_.size - at);
            }
            if (best <= reach * reach) break;  // (reach infinite: all searched)
        }
        return std::sqrt(best);
    }

private:
    static double coordinate(const Point3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }
    std::int64_t cell(double value, int k) const { return cells_.cell(value, k); }
    std::int64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const { return cells_.key(x, y, z); }
    // Is every point of cell (x, y, z), widened by the margin the faces were listed with, farther
    // from p than a squared distance `best`, by more than a rounding of distance2 on a face near p
    // (a millionth of a cell's side, squared)? Then no face listed there comes nearer than `best`
    // where it meets the cell, and one meeting nearer cells is measured there: skipping the cell
    // leaves the minimum as it is.
    bool beyond(V p, std::int64_t x, std::int64_t y, std::int64_t z, double best) const {
        const double at[3] = {p.x, p.y, p.z}, origin[3] = {cells_.lo.x, cells_.lo.y, cells_.lo.z};
        const std::int64_t c[3] = {x, y, z};
        const double margin = 1e-6 * cells_.size;
        double gap2 = 0;
        for (int k = 0; k < 3; ++k) {
            // (Edge cells also hold what lies beyond the grid: no gap on that side.)
            const double low = c[k] == 0 ? -INFINITY : origin[k] + static_cast<double>(c[k]) * cells_.size - margin;
            const double high = c[k] == cells_.n[k] - 1 ? INFINITY : origin[k] + static_cast<double>(c[k] + 1) * cells_.size + margin;
            const double gap = at[k] < low ? low - at[k] : (at[k] > high ? at[k] - high : 0.0);
            gap2 += gap * gap;
        }
        return gap2 > best + 1e-12 * cells_.size * cells_.size;
    }

    // Where cell k's faces are in faces_.
    std::pair<std::size_t, std::size_t> listed_in(std::int64_t k) const {
        if (!start_.empty()) return {start_[static_cast<std::size_t>(k)], start_[static_cast<std::size_t>(k) + 1]};
        const auto begin = std::lower_bound(keys_.begin(), keys_.end(), k);
        const auto end = std::upper_bound(begin, keys_.end(), k);
        return {static_cast<std::size_t>(begin - keys_.begin()), static_cast<std::size_t>(end - keys_.begin())};
    }

    static constexpr std::size_t kChunk = 1 << 12;

    const Mesh& mesh_;
    std::int64_t limit_ = -1;  // with `near`: the shells filled around those points
    Cells cells_;
    std::vector<std::uint32_t> faces_;   // by cell, in face order within a cell
    std::vector<std::uint32_t> start_;   // per cell, where its faces begin (and one past the last cell)
    std::vector<std::int64_t> keys_;     // or, for a grid of many more cells than entries: each entry's cell
};

std::vector<V> samples_of(const Mesh& m, std::size_t face_samples) {
    std::vector<V> out;
    for (const Point3& p : m.points) out.push_back(v(p));
    double total = 0;
    for (const Face& f : m.faces) {
        const V n = cross(v(m.points[f[1]]) - v(m.points[f[0]]), v(m.points[f[2]]) - v(m.points[f[0]]));
        total += std::sqrt(dot(n, n));
    }
    if (!(total > 0)) return out;
    for (const Face& f : m.faces) {
        const V a = v(m.points[f[0]]), b = v(m.points[f[1]]), c = v(m.points[f[2]]);
        const V n = cross(b - a, c - a);
        const double share = std::sqrt(dot(n, n)) / total * static_cast<double>(face_samples);
        // A triangular lattice of r(r+1)/2 interior points, r from the face's share.
        const int r = std::max(1, static_cast<int>(std::ceil((std::sqrt(8.0 * share + 1.0) - 1.0) / 2.0)));
        for (int i = 0; i < r; ++i) {
            for (int j = 0; i + j < r; ++j) {
                const double s = (i + 1.0 / 3.0) / r, t = (j + 1.0 / 3.0) / r;
                out.push_back(a + s * (b - a) + t * (c - a));
            }
        }
    }
    return out;
}

// The largest and mean of measure(sample, d) over the samples that it measures (returns true
// for), in parallel over fixed chunks, summed in order: the same for any thread count.
template <class Measure>
OneWayDistance over_samples(const std::vector<V>& samples, int threads, Measure measure) {
    constexpr std::size_t kChunk = 4096;
    const std::size_t chunks = (samples.size() + kChunk - 1) / kChunk;
    std::vector<double> sums(chunks, 0.0), maxima(chunks, 0.0);
    std::vector<std::size_t> measured(chunks, 0);
    const auto count = static_cast<std::int64_t>(chunks);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (std::int64_t c = 0; c < count; ++c) {
        const std::size_t first = static_cast<std::size_t>(c) * kChunk, last = std::min(samples.size(), first + kChunk);
        double sum = 0, most = 0;
        std::size_t n = 0;
        for (std::size_t i = first; i < last; ++i) {
            double d = 0;
            if (!measure(samples[i], d)) continue;
            sum += d;
            most = std::max(most, d);
            ++n;
        }
        sums[static_cast<std::size_t>(c)] = sum;
        maxima[static_cast<std::size_t>(c)] = most;
        measured[static_cast<std::size_t>(c)] = n;
    }
    OneWayDistance result;
    double sum = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        sum += sums[c];
        result.max = std::max(result.max, maxima[c]);
        result.samples += measured[c];
    }
    result.mean = result.samples == 0 ? 0.0 : sum / static_cast<double>(result.samples);
    return result;
}

// `count` points of a mesh spread over it by area, stratified: the k-th lies where the running sum
// of the faces' areas reaches (k + ½)/count of the whole, placed inside its face by the R2
// low-discrepancy sequence (Roberts 2018), so the points are deterministic and even.
// `box`, if given, receives faces_plan_extent(m), from the same pass over the faces.
std::vector<V> spread_samples(const Mesh& m, std::size_t count, int threads, PlanExtent* box = nullptr) {
    std::vector<V> out;
    if (box) *box = {0, 0, 0, 0};
    if (m.faces.empty()) return out;
    // Each face's (twice) area on all threads, in fixed chunks (with their boxes if asked), then
    // their running sum in face order.
    std::vector<double> running(m.faces.size());
    constexpr std::size_t kChunk = 1 << 13;
    const std::size_t faces = m.faces.size();
    const auto chunks = static_cast<std::int64_t>((faces + kChunk - 1) / kChunk);
    std::vector<PlanExtent> boxes(box ? static_cast<std::size_t>(chunks) : 0);
#pragma omp parallel for schedule(static) num_threads(threads) if (faces >= 4 * kChunk)
    for (std::int64_t k = 0; k < chunks; ++k) {
        const std::size_t first = static_cast<std::size_t>(k) * kChunk, last = std::min(faces, first + kChunk);
        const Point3& start = m.points[m.faces[first][0]];
        PlanExtent all{start.x, start.x, start.y, start.y};
        for (std::size_t f = first; f < last; ++f) {
            const Face& face = m.faces[f];
            const Point3 &a = m.points[face[0]], &b = m.points[face[1]], &c = m.points[face[2]];
            const V n = cross(v(b) - v(a), v(c) - v(a));
            running[f] = std::sqrt(dot(n, n));
            if (box) {
                all = {std::min({all.x0, a.x, b.x, c.x}), std::max({all.x1, a.x, b.x, c.x}), std::min({all.y0, a.y, b.y, c.y}),
                       std::max({all.y1, a.y, b.y, c.y})};
            }
        }
        if (box) boxes[static_cast<std::size_t>(k)] = all;
    }
    if (box) {
        *box = boxes[0];
        for (const PlanExtent& b : boxes) {
            *box = {std::min(box->x0, b.x0), std::max(box->x1, b.x1), std::min(box->y0, b.y0), std::max(box->y1, b.y1)};
        }
    }
    if (count == 0) return out;
    double total = 0;
    for (double& area : running) {
        total += area;
        area = total;
    }
    if (!(total > 0)) {
        for (std::size_t k = 0; k < count; ++k) out.push_back(v(m.points[m.faces[k * m.faces.size() / count][0]]));
        return out;
    }
    out.reserve(count);
    constexpr double kA = 0.7548776662466927, kB = 0.5698402909980532;  // 1/g, 1/g² (g: the plastic number)
    std::size_t f = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const double at = (static_cast<double>(k) + 0.5) / static_cast<double>(count) * total;
        while (f + 1 < running.size() && running[f] < at) ++f;
        // (The fractional parts: x − ⌊x⌋ is exact, as fmod(x, 1) is, and cheaper.)
        const double u = 0.5 + kA * static_cast<double>(k + 1), w = 0.5 + kB * static_cast<double>(k + 1);
        double s = u - std::floor(u), t = w - std::floor(w);
        if (s + t > 1) s = 1 - s, t = 1 - t;
        const Face& face = m.faces[f];
        const V a = v(m.points[face[0]]), b = v(m.points[face[1]]), c = v(m.points[face[2]]);
        out.push_back(a + s * (b - a) + t * (c - a));
    }
    return out;
}

// A face's corners and box, read once for the passes over the faces below.
struct FaceBox {
    V a, b, c, low, high;
    double extent;  // the box's longest side

    FaceBox(const Mesh& m, const Face& f)
        : a(v(m.points[f[0]])), b(v(m.points[f[1]])), c(v(m.points[f[2]])),
          low{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
          high{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})},
          extent(std::max(std::max(high.x - low.x, high.y - low.y), high.z - low.z)) {}

    // Is the face farther from p than a squared distance `best`, by its box, beyond what
    // distance2 could round it to? Then measuring it cannot lower `best`: skipping it leaves every
    // minimum as it is, whatever the order of the faces. (The gap to the box bounds the distance
    // to the face; distance2 rounds its differences of corners, within the box's extent and the
    // gap of p, to a few ulps: 1e-10 of their square is far more.)
    bool far(V p, double best) const {
        const double gx = std::max(std::max(low.x - p.x, p.x - high.x), 0.0), gy = std::max(std::max(low.y - p.y, p.y - high.y), 0.0),
                     gz = std::max(std::max(low.z - p.z, p.z - high.z), 0.0);
        const double gap2 = gx * gx + gy * gy + gz * gz;
        const double scale = std::max(std::max(gx, gy), gz) + 2 * extent;
        return gap2 > best * (1 + 1e-9) + 1e-10 * scale * scale;
    }
    // best, or the squared distance from p to the face if nearer.
    double nearer(V p, double best) const { return far(p, best) ? best : std::min(best, distance2(p, a, b, c)); }
};

// The least of `start` and each thread's value for sample i.
double least(const std::vector<std::vector<double>>& per_thread, std::size_t i, double start) {
    for (const std::vector<double>& mine : per_thread) {
        if (!mine.empty()) start = std::min(start, mine[i]);
    }
    return start;
}

// Cells, by key, each with a run of values (open addressing, linear probing): the blocks of cells
// the sweep below measures samples in.
class CellRuns {
public:
    // `pairs`: (cell key, value); a cell's values stay in their order there.
    // `cells`: one more than the largest key.
    CellRuns(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs, std::size_t cells) : here_((cells + 63) / 64, 0) {
        for (const auto& [key, value] : pairs) here_[key >> 6] |= std::uint64_t{1} << (key & 63);
        std::size_t size = 16;
        while (size < 2 * pairs.size()) size *= 2;
        mask_ = size - 1;
        slots_.assign(size, Slot{kEmpty, 0, 0});
        std::vector<std::uint32_t> slot_of(pairs.size());
        for (std::size_t j = 0; j < pairs.size(); ++j) {
            std::size_t at = hash(pairs[j].first);
            while (slots_[at].key != kEmpty && slots_[at].key != pairs[j].first) at = (at + 1) & mask_;
            slots_[at].key = pairs[j].first;
            ++slots_[at].last;
            slot_of[j] = static_cast<std::uint32_t>(at);
        }
        std::uint32_t first = 0;
        for (Slot& slot : slots_) {
            slot.first = first;
            first += slot.last;
            slot.last = slot.first;
        }
        values_.resize(pairs.size());
        for (std::size_t j = 0; j < pairs.size(); ++j) values_[slots_[slot_of[j]].last++] = pairs[j].second;
    }

    // Where the values of cell `key` are in values() (an empty run if it is not here).
    std::pair<std::uint32_t, std::uint32_t> at(std::uint32_t key) const {
        if (!(here_[key >> 6] >> (key & 63) & 1)) return {0, 0};
        for (std::size_t at = hash(key);; at = (at + 1) & mask_) {
            const Slot& slot = slots_[at];
            if (slot.key == key) return {slot.first, slot.last};
            if (slot.key == kEmpty) return {0, 0};
        }
    }
    // Every cell's values, cell after cell.
    const std::vector<std::uint32_t>& values() const { return values_; }

private:
    static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
    struct Slot {
        std::uint32_t key, first, last;
    };
    std::size_t hash(std::uint32_t key) const { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask_; }

    std::vector<std::uint64_t> here_;  // a bit per cell: is it here? (most cells a face spans are not)
    std::size_t mask_ = 0;
    std::vector<Slot> slots_;
    std::vector<std::uint32_t> values_;
};

// From the samples `open` (places in `samples`) to the nearest face of `to`, in one pass over its
// faces, keeping no index of them: each sample's block is the cells of `cells` that meet the cube
// of half-side `half` around it, and each face is measured from the samples whose blocks share a
// cell with its box. A sample whose nearest face so measured is no farther than the walls of its
// block (those with grid beyond) has its distance: a face not measured has its box, so all its
// points, beyond one of those walls (a millionth of a cell is left for the rounding of the cells'
// bounds). The others stay in `open`. Every face is read once, in order, where it lies; the
// samples' memory is all the pass needs. (The faces of the 89 k-face elephant near 8 192 points,
// listed by cell instead, made 325 k entries whose sort and lookups took most of the measure.)
// `bounds` receives, for each sample left open, the squared distance of the nearest face it
// measured (infinite if none).
void sweep(const std::vector<V>& samples, const Mesh& to, const Cells& cells, double half, std::vector<std::size_t>& open,
           std::vector<double>& distance, std::vector<double>& bounds, int team) {
    struct Block {
        std::int64_t lo[3], hi[3];
    };
    std::vector<Block> blocks(open.size());
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::size_t i = 0; i < open.size(); ++i) {
        const V p = samples[open[i]];
        Block& block = blocks[i];
        for (int k = 0; k < 3; ++k) {
            block.lo[k] = cells.cell(Cells::coordinate(p, k) - half, k);
            block.hi[k] = cells.cell(Cells::coordinate(p, k) + half, k);
        }
        for (std::int64_t x = block.lo[0]; x <= block.hi[0]; ++x) {
            for (std::int64_t y = block.lo[1]; y <= block.hi[1]; ++y) {
                for (std::int64_t z = block.lo[2]; z <= block.hi[2]; ++z) {
                    pairs.emplace_back(static_cast<std::uint32_t>(cells.key(x, y, z)), static_cast<std::uint32_t>(i));
                }
            }
        }
    }
    const CellRuns runs(pairs, static_cast<std::size_t>(cells.count()));
    pairs = {};
    // The samples of each run, in its order: a face's candidates are read one after the other.
    std::vector<V> points(runs.values().size());
    for (std::size_t j = 0; j < points.size(); ++j) points[j] = samples[open[runs.values()[j]]];
    // Per thread: each sample's nearest squared distance, and the last face measured from it (a
    // face whose box spans several cells of a block is measured once).
    std::vector<std::vector<double>> nearest(static_cast<std::size_t>(team));
    std::vector<std::vector<std::uint32_t>> last(static_cast<std::size_t>(team));
    constexpr std::size_t kChunk = 1 << 12;
    const std::size_t faces = to.faces.size();
    const auto chunks = static_cast<std::int64_t>((faces + kChunk - 1) / kChunk);
#pragma omp parallel num_threads(team) if (chunks > 1)
    {
        const auto t = static_cast<std::size_t>(omp_get_thread_num());
        std::vector<double>& mine = nearest[t];
        std::vector<std::uint32_t>& seen = last[t];
        mine.assign(open.size(), std::numeric_limits<double>::infinity());
        seen.assign(open.size(), std::numeric_limits<std::uint32_t>::max());
#pragma omp for schedule(dynamic, 1)
        for (std::int64_t chunk = 0; chunk < chunks; ++chunk) {
            const auto first = static_cast<std::uint32_t>(static_cast<std::size_t>(chunk) * kChunk);
            const auto end = static_cast<std::uint32_t>(std::min(faces, static_cast<std::size_t>(first) + kChunk));
            for (std::uint32_t f = first; f < end; ++f) {
                const FaceBox face(to, to.faces[f]);
                const std::int64_t lo[3] = {cells.cell(face.low.x, 0), cells.cell(face.low.y, 1), cells.cell(face.low.z, 2)};
                const std::int64_t hi[3] = {cells.cell(face.high.x, 0), cells.cell(face.high.y, 1), cells.cell(face.high.z, 2)};
                for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                            const auto [begin, end_of_run] = runs.at(static_cast<std::uint32_t>(cells.key(x, y, z)));
                            for (std::uint32_t j = begin; j < end_of_run; ++j) {
                                const std::uint32_t i = runs.values()[j];
                                if (seen[i] == f) continue;
                                seen[i] = f;
                                mine[i] = face.nearer(points[j], mine[i]);
                            }
                        }
                    }
                }
            }
        }
    }
    std::vector<std::size_t> still;
    bounds.clear();
    for (std::size_t i = 0; i < open.size(); ++i) {
        const double best = least(nearest, i, std::numeric_limits<double>::infinity());
        const V p = samples[open[i]];
        double reach = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
            const double at = Cells::coordinate(p, k), origin = cells.origin(k);
            if (blocks[i].lo[k] > 0) reach = std::min(reach, at - (origin + static_cast<double>(blocks[i].lo[k]) * cells.size));
            if (blocks[i].hi[k] + 1 < cells.n[k]) reach = std::min(reach, origin + static_cast<double>(blocks[i].hi[k] + 1) * cells.size - at);
        }
        reach -= 1e-6 * cells.size;
        if (std::isinf(reach) || (reach > 0 && best <= reach * reach)) {
            distance[open[i]] = std::sqrt(best);
        } else {
            still.push_back(open[i]);
            bounds.push_back(best);
        }
    }
    open.swap(still);
}

// The few samples a sweep left open, each with the squared distance of a face it measured:
// one more pass over the faces, measuring from each sample only the faces whose boxes come
// nearer than the nearest so far (FaceBox::far), finds its nearest face wherever it is. For a
// handful of samples this costs less than indexing the faces near them (the armadillo's 3 of
// 1 300: 0.86 and 0.46 ms on one and two threads, against 1.28 and 1.03 ms).
void finish_few(const std::vector<V>& samples, const Mesh& to, const std::vector<std::size_t>& open, const std::vector<double>& bounds,
                std::vector<double>& distance, int team) {
    std::vector<std::vector<double>> nearest(static_cast<std::size_t>(team));
    constexpr std::size_t kChunk = 1 << 12;
    const std::size_t faces = to.faces.size();
    const auto chunks = static_cast<std::int64_t>((faces + kChunk - 1) / kChunk);
#pragma omp parallel num_threads(team) if (chunks > 1)
    {
        std::vector<double>& mine = nearest[static_cast<std::size_t>(omp_get_thread_num())];
        mine = bounds;
#pragma omp for schedule(dynamic, 1)
        for (std::int64_t chunk = 0; chunk < chunks; ++chunk) {
            const std::size_t first = static_cast<std::size_t>(chunk) * kChunk, end = std::min(faces, first + kChunk);
            for (std::size_t f = first; f < end; ++f) {
                const FaceBox face(to, to.faces[f]);
                for (std::size_t k = 0; k < open.size(); ++k) mine[k] = face.nearer(samples[open[k]], mine[k]);
            }
        }
    }
    for (std::size_t k = 0; k < open.size(); ++k) distance[open[k]] = std::sqrt(least(nearest, k, bounds[k]));
}

// From each sample to the nearest face of `to`: where `to` has many more faces than there are
// samples, first one pass over its faces (sweep); then, for the samples left, indexing only the
// faces near them: the cells within one shell of each, then, for samples whose search must go
// further, wider shells around those alone until every one is measured (a measure bounded by the
// samples and one pass over the faces, not by the size of an index of `to`).
// `each`, if given, receives every sample's distance, in order.
OneWayDistance one_way_near(const std::vector<V>& samples, const Mesh& to, int threads, std::vector<double>* each = nullptr) {
    std::vector<double> distance(samples.size(), std::numeric_limits<double>::quiet_NaN());
    std::vector<std::size_t> open(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) open[i] = i;
    // Many more faces than samples, eight times or more (the input, measured from the points of
    // the output): one pass over the faces, with blocks of a quarter cell around each point,
    // measures nearly all of them (all but 3 of 1 300 on the armadillo) for less than indexing the
    // faces near them; up to 8 left open, each with a face measured, finish in one more pass.
    if (!samples.empty() && to.faces.size() >= 8 * samples.size()) {
        const Cells cells(to, threads);
        std::vector<double> bounds;
        sweep(samples, to, cells, cells.size / 4, open, distance, bounds, threads);
        if (!open.empty() && open.size() <= 8 && std::none_of(bounds.begin(), bounds.end(), [](double b) { return std::isinf(b); })) {
            finish_few(samples, to, open, bounds, distance, threads);
            open.clear();
        }
    }
    for (std::int64_t radius = 1; !open.empty(); radius *= 4) {
        std::vector<V> near;
        for (const std::size_t i : open) near.push_back(samples[i]);
        const FaceGrid grid(to, near, radius, threads);
        const auto count = static_cast<std::int64_t>(open.size());
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads) if (count > 1024)
        for (std::int64_t k = 0; k < count; ++k) {
            distance[open[static_cast<std::size_t>(k)]] = grid.nearest(near[static_cast<std::size_t>(k)]);
        }
        std::erase_if(open, [&](std::size_t i) { return !std::isnan(distance[i]); });
    }
    OneWayDistance result;
    double sum = 0;
    for (const double d : distance) {
        sum += d;
        result.max = std::max(result.max, d);
    }
    result.samples = samples.size();
    result.mean = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
    if (each) *each = std::move(distance);
    return result;
}

OneWayDistance one_way(const Mesh& from, const Mesh& to, std::size_t face_samples, int threads) {
    const FaceGrid grid(to, {}, 0, threads);
    return over_samples(samples_of(from, face_samples), threads, [&grid](V p, double& d) {
        d = grid.nearest(p);
        return true;
    });
}

// The height of a terrain at (x, y), if a face holds that point (closed faces: on an edge either
// neighbour gives the same height).
bool height_at(const Mesh& mesh, const PlanIndex& index, double x, double y, double& z) {
    exact::PredicateStats unused;
    const Point p{x, y};
    for (std::uint32_t face : index.at(x, y)) {
        const Face& f = mesh.faces[face];
        const Point3 &a = mesh.points[f[0]], &b = mesh.points[f[1]], &c = mesh.points[f[2]];
        // Most faces listed in the cell are not over p: their boxes say so without a predicate.
        if (x < std::min({a.x, b.x, c.x}) || x > std::max({a.x, b.x, c.x}) || y < std::min({a.y, b.y, c.y}) ||
            y > std::max({a.y, b.y, c.y})) {
            continue;
        }
        // The three signed areas p makes with the edges sum to the face's, exactly: the face is
        // proper and holds p (on its border too) if and only if those not zero share one sign
        // and one is not zero.
        const Point a2{a.x, a.y}, b2{b.x, b.y}, c2{c.x, c.y};
        const int s_ab = exact::orient2d(a2, b2, p, unused), s_bc = exact::orient2d(b2, c2, p, unused);
        if (s_ab * s_bc < 0) continue;
        const int s_ca = exact::orient2d(c2, a2, p, unused);
        if (s_ca * s_ab < 0 || s_ca * s_bc < 0 || (s_ab == 0 && s_bc == 0 && s_ca == 0)) continue;
        // Barycentric weights from areas in the plane.
        const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if (area == 0) continue;  // (a sliver whose area rounds to zero)
        const double wb = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / area;
        const double wc = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / area;
        z = a.z + wb * (b.z - a.z) + wc * (c.z - a.z);
        return true;
    }
    return false;
}

OneWayDistance one_way_vertical(const Mesh& from, const Mesh& to, std::size_t face_samples, std::size_t& outside, int threads) {
    const PlanIndex index(to);
    const std::vector<V> samples = samples_of(from, face_samples);
    const OneWayDistance result = over_samples(samples, threads, [&](V p, double& d) {
        double z = 0;
        if (!height_at(to, index, p.x, p.y, z)) return false;
        d = std::fabs(p.z - z);
        return true;
    });
    outside += samples.size() - result.samples;
    return result;
}

// The two meshes' points and faces in the frame of all their points (geometry.hpp): products
// of squared lengths (distance2 takes them) neither overflow nor underflow, however large or
// small the meshes. `unscale` takes a length back to the meshes' units.
struct Framed {
    Mesh a, b;
    double unscale = 1.0;
};
Framed framed(const Mesh& a, const Mesh& b) {
    Framed out;
    std::optional<Box3> box;
    for (const Mesh* m : {&a, &b}) {
        for (const Point3& p : m->points) {
            if (box) {
                box->add(p);
            } else {
                box = point_box(p);
            }
        }
    }
    const PowerOfTwoFrame frame = box ? frame_around(*box) : PowerOfTwoFrame{};
    out.unscale = frame.unscale;
    for (auto [from, to] : {std::pair{&a, &out.a}, std::pair{&b, &out.b}}) {
        to->faces = from->faces;
        to->points.reserve(from->points.size());
        for (const Point3& p : from->points) to->points.push_back(frame.local(p));
    }
    return out;
}

OneWayDistance unscaled(OneWayDistance d, double unscale) {
    d.max *= unscale;
    d.mean *= unscale;
    return d;
}

}  // namespace

VerticalError vertical_error(const Mesh& a, const Mesh& b, std::size_t face_samples, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    VerticalError e;
    e.forward = one_way_vertical(a, b, face_samples, e.outside, threads);
    e.backward = one_way_vertical(b, a, face_samples, e.outside, threads);
    return e;
}

namespace {

// Every coordinate zero or of a magnitude whose squares, and their products with each other
// (distance2's), stay normal doubles: within 2^±120.
bool in_safe_range(const Mesh& m) {
    auto safe = [](double c) { return c == 0 || (std::fabs(c) < 0x1p120 && std::fabs(c) > 0x1p-120); };
    for (const Point3& p : m.points) {
        if (!safe(p.x) || !safe(p.y) || !safe(p.z)) return false;
    }
    return true;
}

double diagonal_of(const Mesh& m) {
    if (m.points.empty()) return 0.0;
    V lo = v(m.points[0]), hi = lo;
    for (const Point3& p : m.points) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    return std::sqrt(dot(hi - lo, hi - lo));
}

}  // namespace

HausdorffDistance spread_hausdorff(const Mesh& a, const Mesh& b, std::size_t count, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    // Framed (a copy of both meshes) only where squared lengths could overflow or underflow.
    std::optional<Framed> in;
    if (!in_safe_range(a) || !in_safe_range(b)) in = framed(a, b);
    const Mesh& first = in ? in->a : a;
    const Mesh& second = in ? in->b : b;
    const double unscale = in ? in->unscale : 1.0;
    HausdorffDistance d;
    d.forward = unscaled(one_way_near(spread_samples(first, count, threads), second, threads), unscale);
    d.backward = unscaled(one_way_near(spread_samples(second, count, threads), first, threads), unscale);
    d.diagonal = diagonal_of(first) * unscale;
    return d;
}

VerticalError spread_vertical_error(const Mesh& a, const Mesh& b, std::size_t count, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    VerticalError e;
    for (const auto& [from_mesh, to_mesh, one_side] : {std::tuple{&a, &b, &e.forward}, std::tuple{&b, &a, &e.backward}}) {
        // (Plain locals: clang 14 does not capture structured bindings in lambdas.)
        const Mesh* from = from_mesh;
        const Mesh* to = to_mesh;
        OneWayDistance* side = one_side;
        const std::vector<V> samples = spread_samples(*from, count, threads);
        std::vector<Point> near;
        near.reserve(samples.size());
        for (const V& p : samples) near.push_back({p.x, p.y});
        const PlanIndex index(*to, near, 0, threads);
        *side = over_samples(samples, threads, [&](V p, double& d) {
            double z = 0;
            if (!height_at(*to, index, p.x, p.y, z)) return false;
            d = std::fabs(p.z - z);
            return true;
        });
        e.outside += samples.size() - side->samples;
    }
    return e;
}

std::size_t quick_points(std::size_t faces) { return std::clamp<std::size_t>(faces / 40, 1024, 8192); }

double share_beyond(std::size_t points) { return points == 0 ? 1.0 : -std::expm1(std::log(0.001) / static_cast<double>(points)); }

std::vector<Point3> spread_points(const Mesh& m, std::size_t count) {
    std::vector<Point3> out;
    for (const V& p : spread_samples(m, count, 1)) out.push_back({p.x, p.y, p.z});
    return out;
}

TerrainMeasure spread_terrain_measure(const Mesh& a, const Mesh& b, std::size_t count, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    if (!in_safe_range(a) || !in_safe_range(b)) {
        return {spread_hausdorff(a, b, count, threads), spread_vertical_error(a, b, count, threads)};
    }
    TerrainMeasure out;
    out.distance.diagonal = diagonal_of(a);
    // Both meshes' samples first: spreading them passes over each mesh's faces, and finds the
    // box the other direction's index needs.
    PlanExtent box_a, box_b;
    const std::vector<V> samples_a = spread_samples(a, count, threads, &box_a);
    const std::vector<V> samples_b = spread_samples(b, count, threads, &box_b);
    for (const auto& [from_samples, to_mesh, to_box, forward] :
         {std::tuple{&samples_a, &b, &box_b, true}, std::tuple{&samples_b, &a, &box_a, false}}) {
        // (Plain locals: clang 14 does not capture structured bindings in lambdas.)
        const Mesh* to = to_mesh;
        const std::vector<V>& samples = *from_samples;
        std::vector<Point> near;
        near.reserve(samples.size());
        for (const V& p : samples) near.push_back({p.x, p.y});
        const PlanIndex index(*to, near, 1, threads, to_box);
        const auto n = static_cast<std::int64_t>(samples.size());
        std::vector<double> vertical(samples.size(), std::numeric_limits<double>::quiet_NaN());
        std::vector<double> distance(samples.size(), std::numeric_limits<double>::quiet_NaN());
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads) if (n > 1024)
        for (std::int64_t k = 0; k < n; ++k) {
            const V p = samples[static_cast<std::size_t>(k)];
            double z = 0;
            if (!height_at(*to, index, p.x, p.y, z)) continue;
            const double dz = std::fabs(p.z - z);
            vertical[static_cast<std::size_t>(k)] = dz;
            // The nearest point of `to` is no farther than the one straight above or below, so
            // its face's box meets the square of that half-side around (x, y) (a little wider:
            // z above was interpolated in doubles).
            double best = std::numeric_limits<double>::infinity();
            const bool searched = index.visit_square(p.x, p.y, dz * (1 + 1e-6) + 1e-300, [&](std::uint32_t face) {
                const Face& f = to->faces[face];
                best = std::min(best, distance2(p, v(to->points[f[0]]), v(to->points[f[1]]), v(to->points[f[2]])));
            });
            if (searched) distance[static_cast<std::size_t>(k)] = std::sqrt(best);
        }
        // Samples with no face straight above or below, or whose square reaches beyond the cells
        // filled: measured in space.
        std::vector<V> rest;
        std::vector<std::size_t> rest_at;
        for (std::size_t i = 0; i < samples.size(); ++i) {
            if (std::isnan(distance[i])) rest.push_back(samples[i]), rest_at.push_back(i);
        }
        if (!rest.empty()) {
            std::vector<double> measured;
            one_way_near(rest, *to, threads, &measured);
            for (std::size_t i = 0; i < rest.size(); ++i) distance[rest_at[i]] = measured[i];
        }
        OneWayDistance& side = forward ? out.distance.forward : out.distance.backward;
        OneWayDistance& up = forward ? out.vertical.forward : out.vertical.backward;
        double sum = 0, sum_up = 0;
        for (std::size_t i = 0; i < samples.size(); ++i) {
            sum += distance[i];
            side.max = std::max(side.max, distance[i]);
            if (std::isnan(vertical[i])) {
                ++out.vertical.outside;
                continue;
            }
            sum_up += vertical[i];
            up.max = std::max(up.max, vertical[i]);
            ++up.samples;
        }
        side.samples = samples.size();
        side.mean = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
        up.mean = up.samples == 0 ? 0.0 : sum_up / static_cast<double>(up.samples);
    }
    return out;
}

HausdorffDistance hausdorff(const Mesh& a, const Mesh& b, std::size_t face_samples, int threads) {
    if (threads <= 0) threads = omp_get_max_threads();
    const Framed in = framed(a, b);
    HausdorffDistance d;
    d.forward = unscaled(one_way(in.a, in.b, face_samples, threads), in.unscale);
    d.backward = unscaled(one_way(in.b, in.a, face_samples, threads), in.unscale);
    if (!a.points.empty()) {
        V lo = v(in.a.points[0]), hi = lo;
        for (const Point3& p : in.a.points) {
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        d.diagonal = std::sqrt(dot(hi - lo, hi - lo)) * in.unscale;
    }
    return d;
}

}  // namespace toposimp::mesh
