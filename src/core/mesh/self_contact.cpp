#include "core/mesh/self_contact.hpp"

#include "core/exact/predicates3d.hpp"
#include "core/geometry.hpp"
#include "core/mesh/grid.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

namespace toposimp::mesh {
namespace {

// A uniform grid over a box, in halved coordinates (v/2 − lo/2 is finite for any two finite
// doubles, where v − lo may not be). Cell coordinates are a monotone function of a coordinate:
// the cells of two boxes that meet both hold the cell of the low corner of their overlap.
class HalfGrid {
public:
    HalfGrid(const Box3& box, double size) {
        const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
        for (int axis = 0; axis < 3; ++axis) {
            origin_[axis] = lo[axis] / 2;
            const double extent = hi[axis] / 2 - origin_[axis];
            const double cells = size > 0 && std::isfinite(size) ? std::floor(extent / size) + 1 : 1;
            cells_[axis] = cells >= kMostCells ? kMostCells : cells >= 1 ? static_cast<std::uint32_t>(cells) : 1;
        }
        inverse_ = size > 0 && std::isfinite(size) ? 1 / size : 0;
    }
    std::uint32_t cell(double value, int axis) const {
        const double c = (value / 2 - origin_[axis]) * inverse_;
        if (!(c >= 1)) return 0;
        return c >= cells_[axis] - 1.0 ? cells_[axis] - 1 : static_cast<std::uint32_t>(c);
    }
    // Keys as detail::Grid packs them.
    std::uint64_t key(Point3 p) const { return detail::Grid::pack(cell(p.x, 0), cell(p.y, 1), cell(p.z, 2)); }
    // The cells a box spans, as a count (at most 2^60).
    std::uint64_t span(const Box3& box) const {
        return std::uint64_t{cell(box.hi.x, 0) - cell(box.lo.x, 0) + 1} * (cell(box.hi.y, 1) - cell(box.lo.y, 1) + 1) *
               (cell(box.hi.z, 2) - cell(box.lo.z, 2) + 1);
    }

private:
    static constexpr std::uint32_t kMostCells = std::uint32_t{1} << 20;  // keys pack 21 bits an axis
    double origin_[3] = {0, 0, 0};
    double inverse_ = 0;
    std::uint32_t cells_[3] = {1, 1, 1};
};

struct Entry {
    std::uint64_t cell;
    std::uint32_t face;
    bool operator<(const Entry& other) const { return cell != other.cell ? cell < other.cell : face < other.face; }
};

struct Found {
    std::uint64_t pairs = 0;
    std::array<std::uint32_t, 2> first{~0u, ~0u};
    exact::PredicateStats stats;

    void add(std::uint32_t f, std::uint32_t g) {
        ++pairs;
        first = std::min(first, std::array<std::uint32_t, 2>{f, g});
    }
};

}  // namespace

SelfContact find_self_contact(const Mesh& mesh, int threads, exact::PredicateStats& stats, std::span<const std::uint8_t> changed) {
    if (threads <= 0) threads = omp_get_max_threads();
    const std::vector<Point3>& pos = mesh.points;
    const std::vector<Face>& faces = mesh.faces;
    const auto m = static_cast<std::int64_t>(faces.size());
    SelfContact out;
    if (m == 0) return out;
    auto is_changed = [&](std::size_t f) { return changed.empty() || changed[f] != 0; };
    auto triangle = [&](std::int64_t f) {
        const Face& c = faces[static_cast<std::size_t>(f)];
        return exact::Triangle3{pos[c[0]], pos[c[1]], pos[c[2]]};
    };

    // Each face's box; the degenerate ones; the mean of the boxes' largest sides, in halved
    // coordinates, each side divided by the count first (no sum can overflow).
    std::vector<Box3> boxes(faces.size());
    std::vector<std::uint8_t> degenerate(faces.size());
    std::vector<Found> found(static_cast<std::size_t>(threads));
    std::vector<double> sides(static_cast<std::size_t>(threads), 0.0);
    std::vector<Box3> extents(static_cast<std::size_t>(threads), point_box(pos[faces[0][0]]));
#pragma omp parallel num_threads(threads)
    {
        const auto me = static_cast<std::size_t>(omp_get_thread_num());
        Found& mine = found[me];
#pragma omp for schedule(static)
        for (std::int64_t f = 0; f < m; ++f) {
            const exact::Triangle3 t = triangle(f);
            const Box3 box = triangle_box(t[0], t[1], t[2]);
            boxes[static_cast<std::size_t>(f)] = box;
            extents[me].add(box.lo);
            extents[me].add(box.hi);
            const double side = std::max({box.hi.x / 2 - box.lo.x / 2, box.hi.y / 2 - box.lo.y / 2, box.hi.z / 2 - box.lo.z / 2});
            sides[me] += side / static_cast<double>(m);
            if (is_changed(static_cast<std::size_t>(f)) && exact::degenerate(t, mine.stats)) {
                degenerate[static_cast<std::size_t>(f)] = 1;
                mine.add(static_cast<std::uint32_t>(f), static_cast<std::uint32_t>(f));
            }
        }
    }
    Box3 all = extents[0];
    for (const Box3& box : extents) {
        all.add(box.lo);
        all.add(box.hi);
    }
    // Cells twice the mean side; twice as large again while the faces would fill more than eight
    // cells each on average (a few long faces across a fine grid).
    double size = 2 * std::accumulate(sides.begin(), sides.end(), 0.0);
    std::vector<std::uint64_t> first(faces.size() + 1, 0);  // each face's first entry
    const std::uint64_t most = 8 * static_cast<std::uint64_t>(m) + 1024;
    for (;;) {
        const HalfGrid grid(all, size);
        std::uint64_t total = 0;
#pragma omp parallel for schedule(static) reduction(+ : total) num_threads(threads)
        for (std::int64_t f = 0; f < m; ++f) {
            const auto k = static_cast<std::size_t>(f);
            // (At most `most` + 1 a face, so the sum cannot overflow; one face over it is enough.)
            first[k + 1] = degenerate[k] ? 0 : std::min(grid.span(boxes[k]), most + 1);
            total += first[k + 1];
        }
        if (total <= most || !(size > 0) || !std::isfinite(size)) break;
        size *= 2;
    }
    const HalfGrid grid(all, size);
    // Each face's cells, in order; with `changed`, an unchanged face only in the cells a changed
    // face meets (`marked`, sorted).
    auto for_cells = [&](const Box3& box, auto visit) { detail::for_cells(grid.key(box.lo), grid.key(box.hi), visit); };
    std::vector<std::uint64_t> marked;
    if (!changed.empty()) {
        for (std::size_t f = 0; f < faces.size(); ++f) {
            if (changed[f] && !degenerate[f]) for_cells(boxes[f], [&](std::uint64_t key) { marked.push_back(key); });
        }
        std::sort(marked.begin(), marked.end());
        marked.erase(std::unique(marked.begin(), marked.end()), marked.end());
    }
    auto listed = [&](std::size_t f, std::uint64_t key) {
        return changed.empty() || changed[f] || std::binary_search(marked.begin(), marked.end(), key);
    };
    if (!changed.empty()) {
#pragma omp parallel for schedule(static) num_threads(threads)
        for (std::int64_t f = 0; f < m; ++f) {
            const auto k = static_cast<std::size_t>(f);
            if (degenerate[k] || changed[k]) continue;
            std::uint64_t count = 0;
            for_cells(boxes[k], [&](std::uint64_t key) { count += listed(k, key); });
            first[k + 1] = count;
        }
    }
    std::partial_sum(first.begin(), first.end(), first.begin());
    std::vector<Entry> entries(first.back());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::int64_t f = 0; f < m; ++f) {
        const auto k = static_cast<std::size_t>(f);
        if (degenerate[k]) continue;
        std::uint64_t at = first[k];
        for_cells(boxes[k], [&](std::uint64_t key) {
            if (listed(k, key)) entries[at++] = {key, static_cast<std::uint32_t>(f)};
        });
    }
    std::sort(entries.begin(), entries.end());
    std::vector<std::size_t> runs;  // where each cell's entries begin, then the end
    for (std::size_t i = 0; i < entries.size(); ++i) {
        if (i == 0 || entries[i].cell != entries[i - 1].cell) runs.push_back(i);
    }
    runs.push_back(entries.size());

    // Each cell's pairs (f < g: the entries are sorted by face within a cell) whose boxes meet and
    // whose overlap begins in this cell.
    const auto cells = static_cast<std::int64_t>(runs.size()) - 1;
#pragma omp parallel num_threads(threads)
    {
        Found& mine = found[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(dynamic, 64)
        for (std::int64_t c = 0; c < cells; ++c) {
            const std::size_t begin = runs[static_cast<std::size_t>(c)], end = runs[static_cast<std::size_t>(c) + 1];
            const std::uint64_t here = entries[begin].cell;
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t f = entries[i].face;
                const Box3& a = boxes[f];
                for (std::size_t j = i + 1; j < end; ++j) {
                    const std::uint32_t g = entries[j].face;
                    const Box3& b = boxes[g];
                    if (!a.overlaps(b) || !(is_changed(f) || is_changed(g))) continue;
                    const Point3 low{std::max(a.lo.x, b.lo.x), std::max(a.lo.y, b.lo.y), std::max(a.lo.z, b.lo.z)};
                    if (grid.key(low) != here) continue;
                    if (exact::faces_conflict(triangle(f), triangle(g), mine.stats)) mine.add(f, g);
                }
            }
        }
    }
    Found total;
    for (const Found& part : found) {
        total.pairs += part.pairs;
        total.first = std::min(total.first, part.first);
        stats += part.stats;
    }
    out.pairs = total.pairs;
    if (total.pairs > 0) out.first = total.first;
    return out;
}

}  // namespace toposimp::mesh
