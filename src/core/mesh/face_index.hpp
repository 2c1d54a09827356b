// The face index of UGSimp: which faces lie near a box, for the contact search of a collapse
// (contacts.cpp). Built once a round over a grid of its own; a block's changes during the round
// go to the block's overlay, so that threads never write to shared cells.
#pragma once

#include "core/mesh/grid.hpp"
#include "core/mesh/mesh.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace toposimp::mesh::detail {

// An open-addressing table (linear probing) from grid cell keys to values; it doubles when half
// full.
template <class Value>
class CellMap {
public:
    Value* find(std::uint64_t key) {
        const std::size_t at = slot_of(key);
        return at == kNowhere ? nullptr : &slots_[at].value;
    }
    const Value* find(std::uint64_t key) const {
        const std::size_t at = slot_of(key);
        return at == kNowhere ? nullptr : &slots_[at].value;
    }
    // The value of a cell, default-made if it had none.
    Value& operator[](std::uint64_t key) {
        if (2 * (size_ + 1) > slots_.size()) grow(slots_.empty() ? 64 : 2 * slots_.size());
        std::size_t at = home(key);
        for (; slots_[at].key != kEmpty; at = (at + 1) & (slots_.size() - 1)) {
            if (slots_[at].key == key) return slots_[at].value;
        }
        ++size_;
        slots_[at].key = key;
        return slots_[at].value;
    }
    // Room for `count` cells without growing.
    void reserve(std::size_t count) {
        std::size_t size = 64;
        while (size < 2 * (count + 1)) size *= 2;
        if (size > slots_.size()) grow(size);
    }
    void clear() {
        slots_.clear();
        size_ = 0;
    }
    // Each cell's value, in slot order (fixed by the keys and their order of insertion).
    template <class Visit>
    void for_each(Visit visit) {
        for (Slot& slot : slots_) {
            if (slot.key != kEmpty) visit(slot.value);
        }
    }
    // Each cell's key and value, in slot order.
    template <class Visit>
    void for_each_keyed(Visit visit) {
        for (Slot& slot : slots_) {
            if (slot.key != kEmpty) visit(slot.key, slot.value);
        }
    }

private:
    static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // no cell key: they use 63 bits
    struct Slot {
        std::uint64_t key = kEmpty;
        Value value{};
    };
    static constexpr std::size_t kNowhere = ~std::size_t{0};
    std::size_t home(std::uint64_t key) const { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
    std::size_t slot_of(std::uint64_t key) const {
        if (slots_.empty()) return kNowhere;
        for (std::size_t at = home(key);; at = (at + 1) & (slots_.size() - 1)) {
            if (slots_[at].key == key) return at;
            if (slots_[at].key == kEmpty) return kNowhere;
        }
    }
    void grow(std::size_t size) {
        std::vector<Slot> old(size);
        old.swap(slots_);
        shift_ = 64 - std::countr_zero(slots_.size());
        for (Slot& slot : old) {
            if (slot.key == kEmpty) continue;
            std::size_t at = home(slot.key);
            while (slots_[at].key != kEmpty) at = (at + 1) & (slots_.size() - 1);
            slots_[at] = std::move(slot);
        }
    }

    std::vector<Slot> slots_;
    std::size_t size_ = 0;
    int shift_ = 58;
};

// A face's box in an index cell's list, in that cell's own coordinates on 8 bits, rounded outward
// (a superset of its box: a filter, never a decision). On each axis, lo is 0 if the face begins in
// an earlier cell (this is not its first), else 1 + ⌊254 t⌋ for where it begins, t cells into this
// one; hi is 255 if it ends in a later cell, else 1 + ⌈254 t⌉ for where it ends (cell_lo and cell_hi
// below). A query scans a cell's list in order instead of reading the faces' data one cache line
// each: the round's index keeps the lists as columns (CellColumns, 10 bytes an entry), a block's
// overlay as these 12-byte entries. (Entries of float boxes took 32 bytes: the index of
// elephant-1.4M held 44 MiB more at the peak, for no faster a scan.)
struct IndexEntry {
    std::uint32_t face;
    std::uint8_t lo[3], hi[3];
};

// Where a box whose first cell on an axis is `first` begins, in the coordinates of cell `c` of
// the box's cells, from `units` (the box's low end in grid units, or less).
inline std::uint8_t cell_lo(double units, std::uint32_t first, std::uint32_t c) {
    if (first < c) return 0;
    const double t = (units - c) * 254;
    if (!(t >= 0)) return 1;  // (a clamped first cell, or NaN)
    return t >= 253 ? 254 : static_cast<std::uint8_t>(1 + static_cast<int>(t));
}
// Where a box whose last cell on an axis is `last` ends, in the coordinates of cell `c` of the
// box's cells, from `units` (the box's high end in grid units, or more).
inline std::uint8_t cell_hi(double units, std::uint32_t last, std::uint32_t c) {
    if (last > c) return 255;
    const double t = (units - c) * 254;
    if (!(t < 254)) return 255;  // (a clamped last cell, or NaN)
    if (t <= 0) return 1;
    const int whole = static_cast<int>(t);
    return static_cast<std::uint8_t>(1 + whole + (whole < t));
}

// A face's box in index grid units (Grid::units: monotone, so boxes that overlap still do, and so
// do their 8-bit coordinates in any cell; no rounding outward is needed), and the cells holding
// its corners (lowest and highest on every axis).
struct UnitBox {
    double lo[3], hi[3];
    std::uint64_t first, last;
};

// A cell's entries in the index, as columns: each of the six 8-bit box coordinates of IndexEntry
// (lo x, y, z, then hi x, y, z) for all of them, then their faces. A query compares a column's
// bytes sixteen at a time instead of one entry's nine fields one after another.
struct CellColumns {
    std::array<const std::uint8_t*, 6> bounds{};
    const std::uint32_t* faces = nullptr;
    std::size_t count = 0;
};

// Faces by grid cell for one round: the entries grouped by cell, and a table from a cell to its
// group. Built by a counting sort in parts (each a run of the entries, one thread's): each part
// count()s its (cell, entry) pairs in a table of its own, allocate() gives every cell its group
// and, in it, each part its share in part order, then each part place()s the same pairs in the
// same order. A cell lists its entries in their order, whatever the number of parts.
class CellIndex {
public:
    void clear(std::size_t parts) {
        bounds_.clear();
        faces_.clear();
        groups_.clear();
        parts_.resize(parts);
        for (CellMap<std::size_t>& part : parts_) part.clear();
    }
    void count(std::size_t part, std::uint64_t key) { ++parts_[part][key]; }
    void allocate() {
        for (CellMap<std::size_t>& part : parts_) {
            part.for_each_keyed([&](std::uint64_t key, std::size_t count) { groups_[key].count += count; });
        }
        std::size_t total = 0;
        groups_.for_each([&](Group& group) {
            group.first = total;
            total += group.count;
            group.count = 0;
        });
        // Each part's count becomes where its next entry in the cell goes.
        for (CellMap<std::size_t>& part : parts_) {
            part.for_each_keyed([&](std::uint64_t key, std::size_t& count) {
                Group& group = *groups_.find(key);
                const std::size_t at = group.first + group.count;
                group.count += count;
                count = at;
            });
        }
        bounds_.resize(6 * total);
        faces_.resize(total);
    }
    void place(std::size_t part, std::uint64_t key, const IndexEntry& entry) {
        const std::size_t at = (*parts_[part].find(key))++, total = faces_.size();
        for (std::size_t k = 0; k < 3; ++k) {
            bounds_[k * total + at] = entry.lo[k];
            bounds_[(k + 3) * total + at] = entry.hi[k];
        }
        faces_[at] = entry.face;
    }
    // The entries listed in a cell.
    CellColumns entries(std::uint64_t key) const {
        const Group* group = groups_.find(key);
        if (group == nullptr) return {};
        CellColumns cell;
        for (std::size_t k = 0; k < 6; ++k) cell.bounds[k] = bounds_.data() + k * faces_.size() + group->first;
        cell.faces = faces_.data() + group->first;
        cell.count = group->count;
        return cell;
    }

private:
    struct Group {
        std::size_t first = 0, count = 0;
    };
    std::vector<std::uint8_t> bounds_;  // six columns of faces_.size() bytes
    std::vector<std::uint32_t> faces_;
    CellMap<Group> groups_;
    std::vector<CellMap<std::size_t>> parts_;
};

// The faces a block changed in the current round and that live, by index cell: an entry in each
// cell their box spans now, as in the index.
using Overlay = CellMap<std::vector<IndexEntry>>;

// The live faces by index cell at the start of a round, each with its box at that time, and
// which faces a block changed (moved or removed) since. See query() for why blocks can share it
// without locks.
class FaceIndex {
public:
    // Indexes the faces for which alive[f], in cells of `grid`, using `threads` threads. Each
    // cell lists its faces in face order, whatever the thread count.
    void build(const Grid& grid, const std::vector<Face>& faces, const std::vector<Point3>& points,
               const std::vector<std::uint8_t>& alive, int threads);
    // Faces that may touch `box` (inside the calling block), each once, into `out`.
    void query(const Box3& box, const Overlay& overlay, std::vector<std::uint32_t>& out) const;
    // A face a block changes: it leaves the overlay cells of its box as it was (if the block
    // changed it before in this round, it is there), then, if it lives on, enters those of its
    // box now. A face that dies is only marked changed.
    void leave_overlay(std::uint32_t f, const Box3& box, Overlay& overlay) const;
    void enter_overlay(std::uint32_t f, const Box3& box, Overlay& overlay);
    void mark_changed(std::uint32_t f) { changed_[f] = 1; }

private:
    // A face's box in grid units, and the cells of its corners.
    UnitBox unit_box(const Box3& box) const;

    Grid grid_;  // the index's cells (not the blocks')
    CellIndex cells_;
    // Per face: changed (moved or removed) by its block in this round; the overlay has it if it
    // lives.
    std::vector<std::uint8_t> changed_;
};

}  // namespace toposimp::mesh::detail
