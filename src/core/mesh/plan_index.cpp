#include "core/mesh/plan_index.hpp"

#include "core/exact/predicates.hpp"

#include <omp.h>

namespace toposimp::mesh {
namespace {

// A face's box in the map plane.
inline PlanExtent plan_box(const Mesh& mesh, const Face& f) {
    const Point3 &a = mesh.points[f[0]], &b = mesh.points[f[1]], &c = mesh.points[f[2]];
    return {std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y})};
}

// Do two triangles, both turned `turn` in the map plane, overlap there beyond their borders?
// Convex sets with disjoint interiors are separated by a line through an edge of one of them
// (the separating axis theorem: the edges of their Minkowski difference are theirs), so they
// overlap exactly when no edge has the other triangle on its outer side or on its line. Faces
// sharing an edge are decided by its directions: traversed both ways, they lie on either side.
bool overlap_in_plan(const Mesh& mesh, const Face& f, const Face& g, int turn, exact::PredicateStats& stats) {
    int shared = 0;
    for (std::uint32_t v : f) shared += v == g[0] || v == g[1] || v == g[2];
    if (shared == 3) return true;  // the same triangle twice
    if (shared == 2) {
        for (int k = 0; k < 3; ++k) {
            for (int j = 0; j < 3; ++j) {
                if (f[k] == g[j] && f[(k + 1) % 3] == g[(j + 1) % 3]) return true;  // both go the same way
            }
        }
        return false;
    }
    auto plan = [&](std::uint32_t v) { return Point{mesh.points[v].x, mesh.points[v].y}; };
    auto separates = [&](const Face& t, int k, const Face& other) {
        const std::uint32_t p = t[k], q = t[(k + 1) % 3];
        for (std::uint32_t r : other) {
            if (r != p && r != q && turn * exact::orient2d(plan(p), plan(q), plan(r), stats) > 0) return false;
        }
        return true;
    };
    for (int k = 0; k < 3; ++k) {
        if (separates(f, k, g) || separates(g, k, f)) return false;
    }
    return true;
}

PlanExtent united(const PlanExtent& p, const PlanExtent& q) {
    return {std::min(p.x0, q.x0), std::max(p.x1, q.x1), std::min(p.y0, q.y0), std::max(p.y1, q.y1)};
}

}  // namespace

PlanExtent faces_plan_extent(const Mesh& mesh, int threads) {
    if (mesh.faces.empty()) return {0, 0, 0, 0};
    // The faces in fixed chunks (minima and maxima: the same in any order).
    constexpr std::size_t kChunk = 1 << 15;
    const std::size_t faces = mesh.faces.size(), chunks = (faces + kChunk - 1) / kChunk;
    std::vector<PlanExtent> boxes(chunks);
#pragma omp parallel for schedule(static) num_threads(threads) if (chunks > 1)
    for (std::int64_t k = 0; k < static_cast<std::int64_t>(chunks); ++k) {
        const std::size_t first = static_cast<std::size_t>(k) * kChunk, last = std::min(faces, first + kChunk);
        PlanExtent all = plan_box(mesh, mesh.faces[first]);
        for (std::size_t f = first; f < last; ++f) all = united(all, plan_box(mesh, mesh.faces[f]));
        boxes[static_cast<std::size_t>(k)] = all;
    }
    PlanExtent all = boxes[0];
    for (const PlanExtent& box : boxes) all = united(all, box);
    return all;
}

PlanIndex::PlanIndex(const Mesh& mesh) : PlanIndex(mesh, std::span<const Point>{}, 0) {}

PlanIndex::PlanIndex(const Mesh& mesh, std::span<const Point> near, std::int64_t reach, int threads, const PlanExtent* faces_box) {
    first_.assign(2, 0);
    if (mesh.faces.empty()) return;
    const std::size_t faces = mesh.faces.size();
    // (Every face, for the engine: on the calling thread, as before near points existed.)
    const bool parallel = !near.empty() && faces > (1u << 15);
    const int team = threads > 0 ? threads : omp_get_max_threads();
    const PlanExtent all = faces_box != nullptr ? *faces_box : faces_plan_extent(mesh, parallel ? team : 1);
    const double lo_x = all.x0, hi_x = all.x1, lo_y = all.y0, hi_y = all.y1;
    lo_x_ = lo_x, lo_y_ = lo_y;
    const double cells = std::max(1.0, static_cast<double>(mesh.faces.size()) / 2.0);
    const double width = hi_x - lo_x, height = hi_y - lo_y;
    size_ = width > 0 && height > 0 ? std::sqrt(width * height / cells) : std::max({width, height, 1.0});
    per_size_ = 1.0 / size_;
    n_x_ = std::min<std::int64_t>(static_cast<std::int64_t>(width / size_) + 1, 1 << 14);
    n_y_ = std::min<std::int64_t>(static_cast<std::int64_t>(height / size_) + 1, 1 << 14);
    first_.assign(static_cast<std::size_t>(n_x_ * n_y_) + 1, 0);
    if (near.empty()) {
        // Every face: two passes over their cell ranges, count per cell then fill (a counting
        // sort), with no more memory than the index.
        auto for_cells = [&](const Face& f, auto each) {
            const PlanExtent box = plan_box(mesh, f);
            for (std::int64_t x = cell(box.x0, lo_x_, n_x_); x <= cell(box.x1, lo_x_, n_x_); ++x) {
                for (std::int64_t y = cell(box.y0, lo_y_, n_y_); y <= cell(box.y1, lo_y_, n_y_); ++y) each(static_cast<std::size_t>(x * n_y_ + y));
            }
        };
        for (const Face& f : mesh.faces) for_cells(f, [&](std::size_t c) { ++first_[c + 1]; });
        for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
        faces_.resize(first_.back());
        std::vector<std::size_t> next(first_.begin(), first_.end() - 1);
        for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) for_cells(mesh.faces[f], [&](std::size_t c) { faces_[next[c]++] = f; });
        return;
    }
    reach_ = reach;
    std::vector<std::uint8_t> wanted(static_cast<std::size_t>(n_x_ * n_y_), 0);
    for (const Point p : near) {
        const std::int64_t cx = cell(p.x, lo_x_, n_x_), cy = cell(p.y, lo_y_, n_y_);
        for (std::int64_t x = std::max<std::int64_t>(0, cx - reach); x <= std::min(n_x_ - 1, cx + reach); ++x) {
            for (std::int64_t y = std::max<std::int64_t>(0, cy - reach); y <= std::min(n_y_ - 1, cy + reach); ++y) {
                wanted[static_cast<std::size_t>(x * n_y_ + y)] = 1;
            }
        }
    }
    // The wanted cells only (few faces listed), a counting sort on all threads: each thread
    // counts, then places, the entries of a contiguous run of faces, its entries in a cell after
    // those of the runs before it, so that a cell lists its faces in face order for any team.
    const int workers = parallel ? team : 1;
    const auto cell_count = static_cast<std::size_t>(n_x_ * n_y_);
    std::vector<std::vector<std::uint32_t>> counts(static_cast<std::size_t>(workers));
    auto faces_of = [&](int t) {
        return std::pair{faces * static_cast<std::size_t>(t) / static_cast<std::size_t>(workers),
                         faces * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(workers)};
    };
    // Each point's cell, x and y in 16 bits each (at most 2^14 cells a side): the cells a face's
    // box spans run from its corners' lowest to their highest (cell() is monotone), read from
    // an array a sixth the size of the points. `each(cell, in)`: in = 0 for a cell visited but
    // not in the box.
    const std::size_t points = mesh.points.size();
    std::vector<std::uint32_t> point_cell(points);
    auto for_cells = [&](std::size_t f, auto each) {
        const Face& corners = mesh.faces[f];
        const std::uint32_t p = point_cell[corners[0]], q = point_cell[corners[1]], r = point_cell[corners[2]];
        const std::uint32_t x0 = std::min({p >> 16, q >> 16, r >> 16}), x1 = std::max({p >> 16, q >> 16, r >> 16});
        const std::uint32_t y0 = std::min({p & 0xffff, q & 0xffff, r & 0xffff}), y1 = std::max({p & 0xffff, q & 0xffff, r & 0xffff});
        const auto row = static_cast<std::size_t>(n_y_);
        if (x1 - x0 <= 1 && y1 - y0 <= 1) [[likely]] {
            // At most 2 × 2 cells (nearly every face: a cell holds about two): all four visited,
            // those beyond the box with `in` = 0, so that no branch depends on the box's size.
            const std::uint32_t wide = x1 != x0, tall = y1 != y0;
            each(x0 * row + y0, 1u);
            each(x1 * row + y0, wide);
            each(x0 * row + y1, tall);
            each(x1 * row + y1, wide & tall);
            return;
        }
        for (std::uint32_t x = x0; x <= x1; ++x) {
            for (std::uint32_t y = y0; y <= y1; ++y) each(x * row + y, 1u);
        }
    };
#pragma omp parallel num_threads(workers)
    {
        const int t = omp_get_thread_num();
#pragma omp for schedule(static)
        for (std::size_t v = 0; v < points; ++v) {
            const Point3& at = mesh.points[v];
            point_cell[v] = static_cast<std::uint32_t>(cell(at.x, lo_x_, n_x_) << 16 | cell(at.y, lo_y_, n_y_));
        }
        std::vector<std::uint32_t>& mine = counts[static_cast<std::size_t>(t)];
        mine.assign(cell_count, 0);
        const auto [first, last] = faces_of(t);
        std::vector<std::uint32_t> listed;  // this run's faces in a wanted cell, to place
        // (Without branches on `wanted`, which about half the cells are: a branch would be
        // mispredicted every other cell.)
        for (std::size_t f = first; f < last; ++f) {
            std::uint32_t any = 0;
            for_cells(f, [&](std::size_t c, std::uint32_t in) {
                const std::uint32_t here = wanted[c] & in;
                mine[c] += here;
                any |= here;
            });
            if (any) listed.push_back(static_cast<std::uint32_t>(f));
        }
#pragma omp barrier
#pragma omp single
        {
            // Where each thread's entries of each cell go (counts become offsets).
            std::size_t at = 0;
            for (std::size_t c = 0; c < cell_count; ++c) {
                first_[c] = at;
                for (auto& count : counts) {
                    const std::uint32_t here = count[c];
                    count[c] = static_cast<std::uint32_t>(at - first_[c]);
                    at += here;
                }
            }
            first_[cell_count] = at;
            // (One more per thread at the end: where its entries for cells not wanted are dropped.)
            faces_.resize(at + static_cast<std::size_t>(workers));
        }
        const std::size_t dropped = first_[cell_count] + static_cast<std::size_t>(t);
        for (const std::uint32_t f : listed) {
            for_cells(f, [&](std::size_t c, std::uint32_t in) {
                const std::uint32_t here = wanted[c] & in;
                faces_[here ? first_[c] + mine[c] : dropped] = f;
                mine[c] += here;
            });
        }
    }
    faces_.resize(first_[cell_count]);
}

std::optional<std::array<std::uint32_t, 2>> PlanIndex::overlapping_faces(const Mesh& mesh, int turn, int threads) const {
    if (threads <= 0) threads = omp_get_max_threads();
    // Each pair whose boxes meet is tested once, in the first cell both list (on each axis the
    // later of their first cells). Every pair is looked at, so the smallest overlapping one is
    // found whatever the thread count.
    struct Plan {
        std::uint32_t face;
        PlanExtent box;
        std::int64_t cx, cy;  // first cell
    };
    constexpr std::uint32_t kNone = 0xffffffffu;
    std::vector<std::array<std::uint32_t, 2>> found(static_cast<std::size_t>(threads), {kNone, kNone});
#pragma omp parallel num_threads(threads)
    {
        std::vector<Plan> here;
        exact::PredicateStats stats;
        std::array<std::uint32_t, 2>& best = found[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(dynamic, 64)
        for (std::int64_t x = 0; x < n_x_; ++x) {
            for (std::int64_t y = 0; y < n_y_; ++y) {
                const auto c = static_cast<std::size_t>(x * n_y_ + y);
                here.clear();
                for (std::size_t i = first_[c]; i < first_[c + 1]; ++i) {
                    const std::uint32_t f = faces_[i];
                    const PlanExtent box = plan_box(mesh, mesh.faces[f]);
                    here.push_back({f, box, cell(box.x0, lo_x_, n_x_), cell(box.y0, lo_y_, n_y_)});
                }
                for (std::size_t i = 0; i < here.size(); ++i) {
                    for (std::size_t j = i + 1; j < here.size(); ++j) {
                        const Plan &a = here[i], &b = here[j];
                        if (a.box.x0 > b.box.x1 || b.box.x0 > a.box.x1 || a.box.y0 > b.box.y1 || b.box.y0 > a.box.y1) continue;
                        if (std::max(a.cx, b.cx) != x || std::max(a.cy, b.cy) != y) continue;
                        const std::array<std::uint32_t, 2> pair{std::min(a.face, b.face), std::max(a.face, b.face)};
                        if (pair < best && overlap_in_plan(mesh, mesh.faces[a.face], mesh.faces[b.face], turn, stats)) best = pair;
                    }
                }
            }
        }
    }
    const auto best = *std::min_element(found.begin(), found.end());
    if (best[0] == kNone) return std::nullopt;
    return best;
}

}  // namespace toposimp::mesh
