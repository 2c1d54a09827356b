#include "core/mesh/face_index.hpp"

#include <algorithm>

namespace toposimp::mesh::detail {
namespace {

// A face's entry in the list of one of its cells.
IndexEntry index_entry(std::uint32_t f, const UnitBox& unit, std::uint64_t key) {
    IndexEntry entry;
    entry.face = f;
    for (int axis = 0; axis < 3; ++axis) {
        const std::uint32_t c = Grid::unpack(key, axis);
        entry.lo[axis] = cell_lo(unit.lo[axis], Grid::unpack(unit.first, axis), c);
        entry.hi[axis] = cell_hi(unit.hi[axis], Grid::unpack(unit.last, axis), c);
    }
    return entry;
}

}  // namespace

UnitBox FaceIndex::unit_box(const Box3& box) const {
    UnitBox unit;
    for (int axis = 0; axis < 3; ++axis) {
        unit.lo[axis] = grid_.units(box.lo[axis], axis);
        unit.hi[axis] = grid_.units(box.hi[axis], axis);
    }
    unit.first = grid_.cell_key(box.lo);
    unit.last = grid_.cell_key(box.hi);
    return unit;
}

void FaceIndex::build(const Grid& grid, const std::vector<Face>& faces, const std::vector<Point3>& points,
                      const std::vector<std::uint8_t>& alive, int threads) {
    // Parts of the faces, one per thread (a function of the thread count, but the lists are not).
    const auto parts = static_cast<std::int64_t>(threads);
    cells_.clear(static_cast<std::size_t>(parts));
    const auto m = static_cast<std::int64_t>(faces.size());
    grid_ = grid;
    changed_.assign(faces.size(), 0);
    auto face_box = [&](std::int64_t f) {
        const Face& c = faces[static_cast<std::size_t>(f)];
        return triangle_box(points[c[0]], points[c[1]], points[c[2]]);
    };
    // Each cell lists its faces in face order: part k holds a run of faces.
    auto run_of = [&](std::int64_t k) { return m * k / parts; };
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::int64_t k = 0; k < parts; ++k) {
        for (std::int64_t f = run_of(k); f < run_of(k + 1); ++f) {
            if (!alive[f]) continue;
            const UnitBox unit = unit_box(face_box(f));
            for_cells(unit.first, unit.last, [&](std::uint64_t key) { cells_.count(static_cast<std::size_t>(k), key); });
        }
    }
    cells_.allocate();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::int64_t k = 0; k < parts; ++k) {
        for (std::int64_t f = run_of(k); f < run_of(k + 1); ++f) {
            if (!alive[f]) continue;
            const UnitBox unit = unit_box(face_box(f));  // (again: cheaper than keeping 64 bytes a face)
            for_cells(unit.first, unit.last, [&](std::uint64_t key) {
                cells_.place(static_cast<std::size_t>(k), key, index_entry(static_cast<std::uint32_t>(f), unit, key));
            });
        }
    }
}

// Faces that may touch `box` (inside the calling block), each once: from the round's index
// those whose box at the start of the round overlaps it — a face another block changes lay, and
// lies, inside that block, so its start box cannot overlap and it is never read — unless this
// block changed them, and the faces this block changed, from its overlay, if their box now
// overlaps it. Boxes are compared rounded outward, in each cell's 8-bit coordinates (a few more
// faces, never fewer: where a face begins is at most where the box ends in any cell's
// coordinates if it is in the real ones, as both round the same monotone way, outward). A face
// spanning several of the box's cells is taken in the first (lowest on every axis) of them.
void FaceIndex::query(const Box3& box, const Overlay& overlay, std::vector<std::uint32_t>& out) const {
    out.clear();
    const UnitBox unit = unit_box(box);
    for_cells(unit.first, unit.last, [&](std::uint64_t key) {
        // The box in this cell's coordinates. The first cell a face and the box share is, on each
        // axis, the later of their first ones; the cell visited is in both: it is that one where
        // it is the face's first or the box's on every axis (a lo of 0 says it is not) — where
        // the box's is not, the face's lo must be at least 1.
        std::uint8_t box_lo[3], box_hi[3], least[3];
        for (int axis = 0; axis < 3; ++axis) {
            const std::uint32_t c = Grid::unpack(key, axis);
            box_lo[axis] = cell_lo(unit.lo[axis], Grid::unpack(unit.first, axis), c);
            box_hi[axis] = cell_hi(unit.hi[axis], Grid::unpack(unit.last, axis), c);
            least[axis] = box_lo[axis] == 0;
        }
        // An entry's box (its six 8-bit coordinates) meets the box here, and this is the first
        // cell they share.
        auto meets = [&](std::uint8_t x0, std::uint8_t y0, std::uint8_t z0, std::uint8_t x1, std::uint8_t y1, std::uint8_t z1) {
            return static_cast<std::uint8_t>((x0 >= least[0]) & (x0 <= box_hi[0]) & (box_lo[0] <= x1) & (y0 >= least[1]) &
                                             (y0 <= box_hi[1]) & (box_lo[1] <= y1) & (z0 >= least[2]) & (z0 <= box_hi[2]) &
                                             (box_lo[2] <= z1));
        };
        // Without branches (a hit is written always, kept or overwritten), as the tests are
        // hard to predict; the index's hits then lose the faces this block changed. The index's
        // cell is compared column by column (a loop the compiler vectorizes), its hits then
        // gathered.
        const CellColumns cell = cells_.entries(key);
        thread_local std::vector<std::uint8_t> hit;
        hit.resize(cell.count);
        const std::uint8_t *lo_x = cell.bounds[0], *lo_y = cell.bounds[1], *lo_z = cell.bounds[2];
        const std::uint8_t *hi_x = cell.bounds[3], *hi_y = cell.bounds[4], *hi_z = cell.bounds[5];
        std::uint8_t* const hits = hit.data();
        for (std::size_t k = 0; k < cell.count; ++k) {
            hits[k] = meets(lo_x[k], lo_y[k], lo_z[k], hi_x[k], hi_y[k], hi_z[k]);
        }
        std::size_t start = out.size();
        out.resize(start + cell.count);
        std::uint32_t* at = out.data() + start;
        for (std::size_t k = 0; k < cell.count; ++k) {
            *at = cell.faces[k];
            at += hits[k];
        }
        at = std::remove_if(out.data() + start, at, [this](std::uint32_t f) { return changed_[f] != 0; });
        out.resize(static_cast<std::size_t>(at - out.data()));
        if (const std::vector<IndexEntry>* mine = overlay.find(key)) {
            start = out.size();
            out.resize(start + mine->size());
            at = out.data() + start;
            for (const IndexEntry& entry : *mine) {
                *at = entry.face;
                at += meets(entry.lo[0], entry.lo[1], entry.lo[2], entry.hi[0], entry.hi[1], entry.hi[2]);
            }
            out.resize(static_cast<std::size_t>(at - out.data()));
        }
    });
}

void FaceIndex::leave_overlay(std::uint32_t f, const Box3& box, Overlay& overlay) const {
    if (!changed_[f]) return;
    for_cells(grid_.cell_key(box.lo), grid_.cell_key(box.hi), [&](std::uint64_t key) {
        std::vector<IndexEntry>& list = *overlay.find(key);
        auto it = std::find_if(list.begin(), list.end(), [f](const IndexEntry& e) { return e.face == f; });
        *it = list.back();
        list.pop_back();
    });
}

void FaceIndex::enter_overlay(std::uint32_t f, const Box3& box, Overlay& overlay) {
    changed_[f] = 1;
    const UnitBox unit = unit_box(box);
    for_cells(unit.first, unit.last, [&](std::uint64_t key) { overlay[key].push_back(index_entry(f, unit, key)); });
}

}  // namespace toposimp::mesh::detail
