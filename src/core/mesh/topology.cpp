// The mesh's connectivity while it is simplified: each vertex's corners as a linked list (a
// collapse appends b's list to a's), faces alive or dead, and compaction between levels.
#include "core/mesh/simplifier.hpp"

#include <numeric>

namespace toposimp::mesh::detail {

void Simplifier::build_topology() {
    const std::size_t n = pos_.size(), m = face_.size();
    alive_.assign(m, 1);
    clean_.assign(m, kUnknown);
    flags_.assign(n, 0);
    stamp_.assign(n, 0);
    link_corners();
    live_faces_ = m;
}

void Simplifier::link_corners() {
    const std::size_t m = face_.size();
    next_.assign(3 * m, kNone);
    head_.assign(pos_.size(), kNone);
    for (std::size_t f = m; f-- > 0;) {
        for (int k = 2; k >= 0; --k) {
            const std::uint32_t v = face_[f][k];
            const auto corner = static_cast<std::uint32_t>(3 * f + k);
            next_[corner] = head_[v];
            head_[v] = corner;
        }
    }
}

void Simplifier::drop_dead_faces(std::vector<std::uint32_t>* kept) {
    Attributes& rows = mesh_.face_attributes;
    std::size_t count = 0;
    for (std::size_t f = 0; f < face_.size(); ++f) {
        if (!alive_[f]) continue;
        face_[count] = face_[f];
        clean_[count] = clean_[f];
        if (!input_face_.empty()) input_face_[count] = input_face_[f];
        std::copy_n(rows.row(f), rows.width, rows.row(count));
        if (kept) kept->push_back(static_cast<std::uint32_t>(f));
        ++count;
    }
    face_.resize(count);
    clean_.resize(count);
    if (!input_face_.empty()) input_face_.resize(count);
    rows.values.resize(count * rows.width);
    alive_.assign(count, 1);
}

void Simplifier::compact_faces() {
    std::vector<std::uint32_t> kept;
    drop_dead_faces(vertical_ ? &kept : nullptr);
    link_corners();
    if (vertical_) vertical_->renumber_faces(kept);
}

void Simplifier::faces_of(std::uint32_t v, std::vector<std::uint32_t>& out) {
    out.clear();
    std::uint32_t* link = &head_[v];
    while (*link != kNone) step(link, out);
}

void Simplifier::faces_of(std::uint32_t v, std::vector<std::uint32_t>& out_v, std::uint32_t w, std::vector<std::uint32_t>& out_w) {
    out_v.clear();
    out_w.clear();
    std::uint32_t *link_v = &head_[v], *link_w = &head_[w];
    while (*link_v != kNone && *link_w != kNone) {
        step(link_v, out_v);
        step(link_w, out_w);
    }
    while (*link_v != kNone) step(link_v, out_v);
    while (*link_w != kNone) step(link_w, out_w);
}

void Simplifier::find_twins() {
    std::vector<std::uint32_t> order(pos_.size());
    std::iota(order.begin(), order.end(), 0u);
    auto before = [this](std::uint32_t v, std::uint32_t w) {
        const Point3 &p = pos_[v], &q = pos_[w];
        return p.x != q.x ? p.x < q.x : p.y != q.y ? p.y < q.y : p.z < q.z;
    };
    std::sort(order.begin(), order.end(), before);
    twin_.assign(pos_.size(), 0);
    for (std::size_t i = 1; i < order.size(); ++i) {
        if (same_location(pos_[order[i]], pos_[order[i - 1]])) twin_[order[i]] = twin_[order[i - 1]] = 1;
    }
}

}  // namespace toposimp::mesh::detail
