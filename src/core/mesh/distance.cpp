#include "core/mesh/distance.hpp"

#include "core/exact/predicates.hpp"
#include "core/mesh/plan_index.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
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

// Faces of a mesh in a uniform grid, for nearest-face queries by growing shells of cells. A face
// is listed in the cells of its box that it may meet (triangle_meets_box), not in all of them:
// the long thin faces of a fan (a polygon triangulated from one corner) span boxes of hundreds of
// cells each, and listing them there made every query near the fan test most of its faces (a
// 5 000-corner polygon: 1.8 s of measurement, issue 29). The search below stays exact: a face not
// listed in the cells searched has no point in them.
class FaceGrid {
public:
    explicit FaceGrid(const Mesh& m) : mesh_(m) {
        if (m.faces.empty()) return;
        lo_ = hi_ = v(m.points[m.faces[0][0]]);
        double edges = 0;
        for (const Face& f : m.faces) {
            for (int k = 0; k < 3; ++k) {
                const V p = v(m.points[f[k]]);
                lo_ = {std::min(lo_.x, p.x), std::min(lo_.y, p.y), std::min(lo_.z, p.z)};
                hi_ = {std::max(hi_.x, p.x), std::max(hi_.y, p.y), std::max(hi_.z, p.z)};
                const V e = p - v(m.points[f[(k + 1) % 3]]);
                edges += std::sqrt(dot(e, e));
            }
        }
        // Cells two thirds of the mean edge, or twice the side of a face's mean area if that is
        // smaller: long thin faces (a fan) have long edges and little area, and cells as long
        // as their edges would each list most of them.
        double area = 0;
        for (const Face& f : m.faces) {
            const V n = cross(v(m.points[f[1]]) - v(m.points[f[0]]), v(m.points[f[2]]) - v(m.points[f[0]]));
            area += 0.5 * std::sqrt(dot(n, n));
        }
        size_ = 2.0 * edges / (3.0 * static_cast<double>(m.faces.size()));
        const double by_area = 2.0 * std::sqrt(area / static_cast<double>(m.faces.size()));
        if (by_area > 0 && by_area < size_) size_ = by_area;
        const double largest = std::max({hi_.x - lo_.x, hi_.y - lo_.y, hi_.z - lo_.z});
        if (!(size_ > 0)) size_ = largest > 0 ? largest : 1.0;
        // At most ~2^24 cells in all.
        for (;;) {
            for (int k = 0; k < 3; ++k) n_[k] = static_cast<std::int64_t>(extent(k) / size_) + 1;
            if (static_cast<double>(n_[0]) * static_cast<double>(n_[1]) * static_cast<double>(n_[2]) <= 16777216.0) break;
            size_ *= 1.5;
        }
        std::vector<std::pair<std::int64_t, std::uint32_t>> entries;
        for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
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
            const bool one_cell = lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2];
            const V a = v(m.points[m.faces[f][0]]), b = v(m.points[m.faces[f][1]]), c = v(m.points[m.faces[f][2]]);
            // Half a cell, and a millionth more (with the cells' clamping at the grid's edges,
            // a cell of the edge row may hold points beyond it: those rows take the whole box).
            const double half = 0.5 * size_ * (1.0 + 1e-6);
            for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
                    for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                        const bool edge = x == n_[0] - 1 || y == n_[1] - 1 || z == n_[2] - 1 || x == 0 || y == 0 || z == 0;
                        const V centre{lo_.x + (static_cast<double>(x) + 0.5) * size_, lo_.y + (static_cast<double>(y) + 0.5) * size_,
                                       lo_.z + (static_cast<double>(z) + 0.5) * size_};
                        if (one_cell || edge || triangle_meets_box(a, b, c, centre, {half, half, half})) {
                            entries.emplace_back(key(x, y, z), f);
                        }
                    }
                }
            }
        }
        std::sort(entries.begin(), entries.end());
        keys_.resize(entries.size());
        faces_.resize(entries.size());
        for (std::size_t i = 0; i < entries.size(); ++i) keys_[i] = entries[i].first, faces_[i] = entries[i].second;
    }

    double nearest(V p) const {
        double best = std::numeric_limits<double>::infinity();
        if (mesh_.faces.empty()) return best;
        const std::int64_t c[3] = {cell(p.x, 0), cell(p.y, 1), cell(p.z, 2)};
        const std::int64_t most = std::max({n_[0], n_[1], n_[2]});
        for (std::int64_t r = 0; r <= most; ++r) {
            for (std::int64_t x = c[0] - r; x <= c[0] + r; ++x) {
                for (std::int64_t y = c[1] - r; y <= c[1] + r; ++y) {
                    for (std::int64_t z = c[2] - r; z <= c[2] + r; ++z) {
                        const bool shell = std::max({std::llabs(x - c[0]), std::llabs(y - c[1]), std::llabs(z - c[2])}) == r;
                        if (!shell || x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) continue;
                        const std::int64_t k = key(x, y, z);
                        for (auto it = std::lower_bound(keys_.begin(), keys_.end(), k); it != keys_.end() && *it == k; ++it) {
                            const Face& f = mesh_.faces[faces_[static_cast<std::size_t>(it - keys_.begin())]];
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
                const double at = k == 0 ? p.x : (k == 1 ? p.y : p.z), origin = k == 0 ? lo_.x : (k == 1 ? lo_.y : lo_.z);
                if (c[k] - r > 0) reach = std::min(reach, at - (origin + static_cast<double>(c[k] - r) * size_));
                if (c[k] + r + 1 < n_[k]) reach = std::min(reach, origin + static_cast<double>(c[k] + r + 1) * size_ - at);
            }
            if (best <= reach * reach) break;  // (reach infinite: all searched)
        }
        return std::sqrt(best);
    }

private:
    static double coordinate(const Point3& p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }
    double extent(int k) const { return k == 0 ? hi_.x - lo_.x : (k == 1 ? hi_.y - lo_.y : hi_.z - lo_.z); }
    std::int64_t cell(double value, int k) const {
        const double origin = k == 0 ? lo_.x : (k == 1 ? lo_.y : lo_.z);
        const double c = std::floor((value - origin) / size_);
        return static_cast<std::int64_t>(std::clamp(c, 0.0, static_cast<double>(n_[k] - 1)));
    }
    std::int64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const { return (x * n_[1] + y) * n_[2] + z; }

    const Mesh& mesh_;
    V lo_{0, 0, 0}, hi_{0, 0, 0};
    double size_ = 1.0;
    std::int64_t n_[3] = {1, 1, 1};
    std::vector<std::int64_t> keys_;
    std::vector<std::uint32_t> faces_;
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

OneWayDistance one_way(const Mesh& from, const Mesh& to, std::size_t face_samples, int threads) {
    const FaceGrid grid(to);
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
        const Point a2{a.x, a.y}, b2{b.x, b.y}, c2{c.x, c.y};
        const int turn = exact::orient2d(a2, b2, c2, unused);
        if (turn == 0) continue;
        if (exact::orient2d(a2, b2, p, unused) * turn < 0 || exact::orient2d(b2, c2, p, unused) * turn < 0 ||
            exact::orient2d(c2, a2, p, unused) * turn < 0) {
            continue;
        }
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
