// One edge collapse: b merges into a at the placement the quadrics choose, made only if every
// check holds, in this order (cheapest and most often refusing first):
//   placement → link condition → border not pinched → star → faces stay upright →
//   vertical bound (terrains under --max-error) → no new contact (contacts.cpp) → apply.
#include "core/mesh/simplifier.hpp"

namespace toposimp::mesh::detail {

bool Simplifier::try_collapse(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, BlockResult& result,
                              std::vector<std::uint32_t>& around, Overlay& overlay) {
    SimplifyStats& stats = result.stats;
    thread_local Collapse c;
    c.a = a;
    c.b = b;
    if (!place(a, b, level, block, c.placement)) {
        ++stats.refused_boundary;
        return false;
    }
    c.error = error_of(c.placement, a, b);
    if (options_.stop.target == Target::max_error && !vertical_ && !(c.error <= options_.stop.value)) return false;  // (NaN: refused)
    gather_faces(c);
    if (c.shared.empty()) return false;  // no longer an edge
    if (!link_condition_holds(c)) {
        ++stats.refused_link;
        return false;
    }
    if (pinches_border(c)) {
        ++stats.refused_boundary;
        return false;
    }
    gather_star(c);
    if (c.star.empty()) {
        ++stats.refused_link;  // the component would vanish
        return false;
    }
    if (!faces_stay_upright(c, stats)) return false;
    if (vertical_ && !vertical_->holds(c.fan, c.replaced, stats.predicates)) {
        ++stats.refused_vertical;
        return false;
    }
    if (!no_new_contact(c, overlay, stats)) return false;
    apply(c, result, around, overlay);
    return true;
}

void Simplifier::gather_faces(Collapse& c) {
    const std::uint32_t a = c.a, b = c.b;
    faces_of(a, c.fa, b, c.fb);
    for (const auto* faces : {&c.fa, &c.fb}) {
        for (std::uint32_t f : *faces) {
            for (std::uint32_t w : face_[f]) __builtin_prefetch(&pos_[w]);  // read for the star below
        }
    }
    // a's list now holds the corners of fa, in order: b's are appended after the last.
    c.last_of_a = kNone;
    if (!c.fa.empty()) {
        const Face& last = face_[c.fa.back()];
        c.last_of_a = 3 * c.fa.back() + (last[0] == a ? 0 : last[1] == a ? 1 : 2);
    }
    c.shared.clear();
    for (std::uint32_t f : c.fa) {
        const Face& corners = face_[f];
        if (corners[0] == b || corners[1] == b || corners[2] == b) c.shared.push_back(f);
    }
}

// The common neighbours of a and b must be exactly the corners opposite the edge, each once; a
// border vertex pair joined through the interior would pinch. The opposite corners are common
// neighbours, so it is enough that they are distinct and that a and b have no other: the corners
// of a's faces are marked, those of b's faces found marked are counted once each (a, b and the
// common neighbours), and the marks cleared.
bool Simplifier::link_condition_holds(Collapse& c) {
    const std::uint32_t a = c.a, b = c.b;
    c.opposite.clear();
    for (std::uint32_t f : c.shared) {
        for (std::uint32_t w : face_[f]) {
            if (w != a && w != b) c.opposite.push_back(w);
        }
    }
    std::sort(c.opposite.begin(), c.opposite.end());
    if (std::adjacent_find(c.opposite.begin(), c.opposite.end()) != c.opposite.end()) return false;
    for (std::uint32_t f : c.fa) {
        for (std::uint32_t w : face_[f]) flags_[w] |= kMarked;
    }
    std::size_t common = 0;
    for (std::uint32_t f : c.fb) {
        for (std::uint32_t w : face_[f]) {
            if ((flags_[w] & (kMarked | kCounted)) == kMarked) {
                flags_[w] |= kCounted;
                ++common;
            }
        }
    }
    for (std::uint32_t f : c.fa) {
        for (std::uint32_t w : face_[f]) flags_[w] &= static_cast<std::uint8_t>(~(kMarked | kCounted));
    }
    return common == c.opposite.size() + 2;
}

bool Simplifier::pinches_border(const Collapse& c) const {
    const bool border_edge = c.shared.size() == 1;
    return (flags_[c.a] & kBoundary) && (flags_[c.b] & kBoundary) && !border_edge;
}

void Simplifier::gather_star(Collapse& c) const {
    c.star.clear();
    for (std::uint32_t f : c.fa) {
        if (std::find(c.shared.begin(), c.shared.end(), f) == c.shared.end()) c.star.push_back(f);
    }
    c.from_a = c.star.size();
    for (std::uint32_t f : c.fb) {
        if (std::find(c.shared.begin(), c.shared.end(), f) == c.shared.end()) c.star.push_back(f);
    }
}

bool Simplifier::faces_stay_upright(Collapse& c, SimplifyStats& stats) const {
    const std::uint32_t a = c.a, b = c.b;
    exact::PredicateStats& predicates = stats.predicates;
    c.fresh.clear();
    c.fan.clear();
    c.reach = point_box(c.placement.p);
    for (std::size_t i = 0; i < c.star.size(); ++i) {
        const Face& corners = face_[c.star[i]];
        exact::Triangle3 before = triangle(corners), after = before;
        for (int k = 0; k < 3; ++k) {
            if (corners[k] == a || corners[k] == b) after[k] = c.placement.p;
        }
        if (terrain_) {
            // Turned the terrain's way in the map plane: not degenerate either.
            if (exact::orient_projected(after[0], after[1], after[2], 2, predicates) != terrain_turn_) {
                ++(exact::degenerate(after, predicates) ? stats.refused_degenerate : stats.refused_flip);
                return false;
            }
        } else if (exact::degenerate(after, predicates)) {
            ++stats.refused_degenerate;
            return false;
        } else if (exact::normal_dot_sign(before[0], before[1], before[2], after[0], after[1], after[2], predicates) <= 0) {
            ++stats.refused_flip;
            return false;
        }
        if (i >= c.from_a && c.opposite.size() == 2) {
            // A face (b, x, y) becomes (a, x, y): refuse if a already has a face on x and y. Then x
            // and y are common neighbours of a and b: by the link test, the two opposite corners.
            std::uint32_t x = kNone, y = kNone;
            for (std::uint32_t w : corners) {
                if (w != b) (x == kNone ? x : y) = w;
            }
            const bool both_opposite = std::min(x, y) == c.opposite[0] && std::max(x, y) == c.opposite[1];
            for (std::size_t k = 0; both_opposite && k < c.fa.size(); ++k) {
                const Face& d = face_[c.fa[k]];
                const bool has_x = d[0] == x || d[1] == x || d[2] == x, has_y = d[0] == y || d[1] == y || d[2] == y;
                if (has_x && has_y) {
                    ++stats.refused_degenerate;
                    return false;
                }
            }
        }
        for (const Point3& corner : after) c.reach.add(corner);
        c.fresh.push_back(after);
        if (vertical_) {
            const int k = corners[0] == a || corners[0] == b ? 0 : corners[1] == a || corners[1] == b ? 1 : 2;
            c.fan.push_back({after[k], after[(k + 1) % 3], after[(k + 2) % 3]});
        }
    }
    if (vertical_) {
        c.replaced.assign(c.star.begin(), c.star.end());
        c.replaced.insert(c.replaced.end(), c.shared.begin(), c.shared.end());
    }
    return true;
}

void Simplifier::apply(const Collapse& c, BlockResult& result, std::vector<std::uint32_t>& around, Overlay& overlay) {
    const std::uint32_t a = c.a, b = c.b;
    const Point3 p = c.placement.p;
    // First the faces that change leave the overlay cells of their old boxes, if they are there.
    if (use_index_) {
        for (const auto* faces : {&c.shared, &c.star}) {
            for (std::uint32_t f : *faces) index_.leave_overlay(f, face_box(f), overlay);
        }
    }
    for (std::uint32_t f : c.shared) alive_[f] = 0;
    std::uint32_t* tail = &next_[c.last_of_a];
    for (std::uint32_t corner = head_[b]; corner != kNone; corner = next_[corner]) {
        if (alive_[corner / 3]) face_[corner / 3][corner % 3] = a;
    }
    *tail = head_[b];
    head_[b] = kNone;
    blend_attributes(a, b, p);
    pos_[a] = p;
    cell_[a] = grid_.cell_key(p);
    quadric_[a] += quadric_[b];
    flags_[a] = static_cast<std::uint8_t>(flags_[a] | (flags_[b] & (kBoundary | kLocked)));
    flags_[b] = static_cast<std::uint8_t>(flags_[b] | kDead);
    stamp_[a] = (stamp_[a] + 1) & kStampMask;
    stamp_[b] = (stamp_[b] + 1) & kStampMask;
    // Faces made by a collapse were checked against every face near them: clean, unless they
    // inherit a contact of the input's.
    for (std::uint32_t f : c.star) clean_[f] = c.inherits ? kConflicting : kClean;
    if (!terrain_ && !quick_) twin_[a] = c.twin_after;
    if (use_index_) {
        for (std::uint32_t f : c.shared) index_.mark_changed(f);
        for (std::uint32_t f : c.star) index_.enter_overlay(f, face_box(f), overlay);
    }
    corners_but(c.star, a, around);  // a's faces now: the star
    if (vertical_) {
        vertical_->collapsed(c.replaced, c.star);
        ++touch_[a];
        for (std::uint32_t w : around) ++touch_[w];
    }
    SimplifyStats& stats = result.stats;
    ++stats.collapses;
    stats.max_error = std::max(stats.max_error, c.error);
    result.faces_removed += c.shared.size();
}

}  // namespace toposimp::mesh::detail
