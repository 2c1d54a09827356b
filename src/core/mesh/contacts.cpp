// The no-new-contact check of a collapse: no face it changes may touch or cross another face,
// except at the corners and the edge the two share — or where the input already crossed itself:
// a new face may meet a face g that one of the faces the collapse replaces met too (the contact
// is inherited, not new: the crossing of two interpenetrating parts moves along the faces that
// already crossed, and no part touches one it did not touch). A clean input never has such a
// face, so its result does not change. Decided with exact predicates: first, in flat regions, by
// a proof that needs no other face (flat_and_clean); otherwise by searching the face index for
// the faces near the new ones and testing each pair. Only with ContactCheck::every_collapse (or
// a second run): by default the result is checked once instead (self_contact.hpp).
#include "core/mesh/simplifier.hpp"

namespace toposimp::mesh::detail {
namespace {

// What the sides of another face's corners with respect to a new face's plane settle: apart
// (corners strictly on one side, but for those at a corner of the new face), coplanar (all in
// the plane, none shared: any contact is a conflict), or nothing (the general test decides).
enum class Verdict { apart, coplanar, unknown };

// The side of a nearby corner with respect to a new face's plane, remembered (a small
// direct-mapped cache by vertex, one generation per new face), so a corner shared by several
// nearby faces is decided once: in flat regions those are exact zeros, the dear case.
struct SideCache {
    struct Entry {
        std::uint32_t vertex = kNone;
        int side = 0;
        std::uint64_t generation = 0;  // 64 bits: never wraps
    };
    std::array<Entry, 512> entries{};
    std::uint64_t generation = 0;

    Entry& at(std::uint32_t v) { return entries[v % entries.size()]; }
};

// The faces near a collapse's new faces (not its own), as they are (flattened if asked), with
// their boxes.
struct Nearby {
    std::vector<std::uint32_t> faces;
    std::vector<exact::Triangle3> triangles;
    std::vector<Box3> boxes;
};

}  // namespace

bool Simplifier::no_new_contact(Collapse& c, Overlay& overlay, SimplifyStats& stats) {
    // In a terrain with a locked border the planar argument suffices; a collapse that moves a
    // border vertex of a terrain is checked in the map plane (faces flattened to z = 0).
    if (quick_) return true;  // (the result is checked after the run)
    exact::PredicateStats& predicates = stats.predicates;
    const bool moves_border = ((flags_[c.a] | flags_[c.b]) & kBoundary) != 0 && !lock_;
    const bool flatten = terrain_ && moves_border;
    const bool interior = ((flags_[c.a] | flags_[c.b]) & kBoundary) == 0 && c.shared.size() == 2;
    c.twin_after = false;
    c.inherits = false;
    if (!terrain_ && interior && options_.flat_shortcut && flat_and_clean(c, overlay, predicates)) {
        ++stats.flat_unsearched;
        return true;
    }
    if (terrain_ && !flatten) return true;
    if (search_contacts(c, flatten, overlay, predicates)) {
        ++stats.refused_intersection;
        return false;
    }
    return true;
}

bool Simplifier::search_contacts(Collapse& c, bool flatten, Overlay& overlay, exact::PredicateStats& predicates) {
    const std::uint32_t a = c.a, b = c.b;
    const Point3 p = c.placement.p;
    auto flat = [&](exact::Triangle3 t) {
        if (flatten) {
            for (Point3& q : t) q.z = 0;
        }
        return t;
    };
    Box3 box = c.reach;
    if (flatten) {
        box.lo.z = grid_.origin.z;
        box.hi.z = std::numeric_limits<double>::infinity();
    }
    thread_local std::vector<std::uint32_t> found;
    index_.query(box, overlay, found);
    std::sort(c.fa.begin(), c.fa.end());
    std::sort(c.fb.begin(), c.fb.end());
    thread_local Nearby near;
    thread_local SideCache sides;
    near.faces.clear();
    near.triangles.clear();
    near.boxes.clear();
    // The found faces and their corners lie anywhere in memory: load them all before reading.
    for (std::uint32_t g : found) __builtin_prefetch(&face_[g]);
    for (std::uint32_t g : found) {
        for (std::uint32_t w : face_[g]) __builtin_prefetch(&pos_[w]);
    }
    for (std::uint32_t g : found) {
        if (alive_[g] && !std::binary_search(c.fa.begin(), c.fa.end(), g) && !std::binary_search(c.fb.begin(), c.fb.end(), g)) {
            near.faces.push_back(g);
            near.triangles.push_back(flat(triangle(face_[g])));
            const exact::Triangle3& t = near.triangles.back();
            near.boxes.push_back(triangle_box(t[0], t[1], t[2]));
        }
    }
    // Each new face against the nearby faces and the new faces after it. A face whose corners
    // lie strictly on one side of the new face's plane, but for those at a corner of the new
    // face, meets it at most in those corners: apart (this decides most pairs, the corners
    // shared with the new face included). All corners in the plane and none shared: the
    // coplanar test, where any contact is a conflict. Otherwise the general test.
    // The new faces against one another: at once if they form a simple fan around p.
    const bool simple_fan = !flatten && fan_is_simple(a, b, c.star, p, predicates);
    for (std::size_t i = 0; i < c.fresh.size(); ++i) {
        const exact::Triangle3 mine = flat(c.fresh[i]);
        const Box3 mine_box = triangle_box(mine[0], mine[1], mine[2]);
        std::array<std::uint32_t, 3> mine_ids = face_[c.star[i]];
        for (std::uint32_t& v : mine_ids) v = v == b ? a : v;
        ++sides.generation;
        const exact::PlaneSide plane(mine[0], mine[1], mine[2]);
        // The sides of the other face's corners (`side`, for faces_conflict) and what they
        // settle.
        auto verdict = [&](const std::array<std::uint32_t, 3>& ids, const exact::Triangle3& other, std::array<int, 3>& side) {
            int sign = 0;
            bool on_corner = false, unshared_in_plane = false, both_sides = false;
            for (int k = 0; k < 3; ++k) {
                // At a corner of the new face: the same vertex, or one with twin_ set (a vertex
                // at x's location has it, and so has x), or one at p (not yet marked).
                const std::uint32_t v = ids[k];
                bool here = (v == mine_ids[0]) | (v == mine_ids[1]) | (v == mine_ids[2]);
                if (!here && (twin_[v] || same_location(other[k], p))) {
                    here = same_location(other[k], mine[0]) || same_location(other[k], mine[1]) || same_location(other[k], mine[2]);
                }
                if (here) {
                    on_corner = true;  // in the plane, no predicate needed
                    side[k] = 0;
                    continue;
                }
                SideCache::Entry& entry = sides.at(v);
                if (entry.vertex != v || entry.generation != sides.generation) {
                    entry = {v, plane(other[k], predicates), sides.generation};
                }
                side[k] = entry.side;
                if (entry.side == 0) {
                    unshared_in_plane = true;
                } else if (sign == 0) {
                    sign = entry.side;
                } else if (entry.side != sign) {
                    both_sides = true;
                }
            }
            if (sign != 0) return unshared_in_plane || both_sides ? Verdict::unknown : Verdict::apart;
            return on_corner ? Verdict::unknown : Verdict::coplanar;
        };
        auto conflict = [&](const std::array<std::uint32_t, 3>& ids, const exact::Triangle3& other) {
            std::array<int, 3> side{exact::kSideUnknown, exact::kSideUnknown, exact::kSideUnknown};
            if (!flatten) {
                const Verdict v = verdict(ids, other, side);
                if (v == Verdict::apart) return false;
                if (v == Verdict::coplanar) {
                    const int met = exact::coplanar_triangles_meet(mine, other, predicates);
                    if (met >= 0) return met == 1;  // (−1, a degenerate new face: the general test)
                }
            }
            return exact::faces_conflict(mine, other, side, predicates);
        };
        // The nearby faces whose box meets the new face's, listed without branches (about half
        // do: a branch would be mispredicted often).
        thread_local std::vector<std::uint32_t> meeting;
        meeting.resize(near.faces.size());
        std::size_t meets = 0;
        for (std::size_t n = 0; n < near.faces.size(); ++n) {
            const Box3& other = near.boxes[n];
            meeting[meets] = static_cast<std::uint32_t>(n);
            meets += (mine_box.lo.x <= other.hi.x) & (other.lo.x <= mine_box.hi.x) & (mine_box.lo.y <= other.hi.y) &
                     (other.lo.y <= mine_box.hi.y) & (mine_box.lo.z <= other.hi.z) & (other.lo.z <= mine_box.hi.z);
        }
        for (std::size_t k = 0; k < meets; ++k) {
            const std::size_t n = meeting[k];
            if (!conflict(face_[near.faces[n]], near.triangles[n])) continue;
            if (flatten || !met_by_replaced(c, near.triangles[n], near.boxes[n], predicates)) return true;
            c.inherits = true;
        }
        for (std::size_t j = i + 1; j < c.fresh.size() && !simple_fan; ++j) {
            const exact::Triangle3 other = flat(c.fresh[j]);
            if (!mine_box.overlaps(triangle_box(other[0], other[1], other[2]))) continue;
            std::array<std::uint32_t, 3> ids = face_[c.star[j]];
            for (std::uint32_t& v : ids) v = v == b ? a : v;
            if (conflict(ids, other)) return true;
        }
    }
    // A vertex at p is a corner of a face holding p: found (a corner of the star there would
    // have made a new face degenerate). It lies in this block, like p.
    if (!terrain_) {
        for (std::uint32_t g : near.faces) {
            for (std::uint32_t w : face_[g]) {
                if (same_location(pos_[w], p)) {
                    twin_[w] = 1;
                    c.twin_after = true;
                }
            }
        }
    }
    return false;
}

// A collapse in a flat region, shown free of contacts without looking at other faces. Write S
// for the faces of a and b (the two on ab die), Γ for the link: the edges of S opposite a or b.
// Conditions, all exact: (1) ab is an interior edge (two faces, neither end on a border); (2)
// every face of S is clean (made by an accepted collapse: it was checked against every face
// near it then, and every face made since against it, so it meets no face beyond their shared
// corner locations or the segment between two); (3) no other vertex has a's or b's location;
// (4) around a and around b every neighbour is once the next corner and once the previous one
// (the faces are consistently oriented) and Γ, oriented by its faces, is one cycle; (5) S and
// p lie in one plane H (orient3d against a face of S is 0); (6) in a coordinate plane onto which
// that face projects properly (an affine bijection from H: orientations kept or all flipped)
// every face of S and every new face has the same orientation σ (orient2d).
//
// Why that is enough. Take S and the new faces as 2-chains of H. By (4) the edges at a cancel
// in pairs, those at b too, and so do their images at p (the two dying faces held ab and its
// edges to the opposite corners): both chains have boundary Γ. With every orientation σ, the
// number of faces of each chain covering a point (off the edges) is σ times the winding number
// of Γ around it, so the same for both; the old faces, clean, do not overlap, so neither do
// the new ones and both cover the same set U. The new faces form a fan from p over the cycle Γ,
// all turning one way without overlap: a single turn, so Γ is a simple polygon star-shaped from
// p, bounding U, its corners at distinct locations, and two new faces meet only at p or along
// their shared edge from p. Another face g meeting a new face at x meets U, so an old face there,
// and since that one is clean, x is a location both have as a corner, or on the segment between
// two such. By (3) those are corners of Γ (g has no corner at a's or b's location, nor at p,
// which lies inside U where only an old face's corner at a or b could be), and on ∂U: x is then
// a corner of the new faces there, or on their edge of Γ, which g also has at both ends. So every
// new face meets every other face only as clean faces do, and the new faces are clean.
bool Simplifier::flat_and_clean(const Collapse& c, Overlay& overlay, exact::PredicateStats& predicates) {
    const std::uint32_t a = c.a, b = c.b;
    const std::vector<std::uint32_t>& fa = c.fa, &fb = c.fb, &star = c.star;
    const Point3 p = c.placement.p;
    if (twin_[a] || twin_[b]) return false;
    // One plane: p and every corner against the first face of a (first: on curved surfaces the
    // filter settles p's side at once).
    const exact::Triangle3 reference = triangle(face_[fa.front()]);
    auto in_plane = [&](Point3 q) { return exact::orient3d(reference[0], reference[1], reference[2], q, predicates) == 0; };
    if (!in_plane(p)) return false;
    for (const auto* faces : {&fa, &fb}) {
        for (std::uint32_t f : *faces) {
            if (clean_[f] == kConflicting) return false;
            for (std::uint32_t w : face_[f]) {
                if (!in_plane(pos_[w])) return false;
            }
        }
    }
    // Consistent orientation around each end.
    thread_local std::vector<std::uint32_t> next_corner, previous_corner;
    for (const std::uint32_t v : {a, b}) {
        next_corner.clear();
        previous_corner.clear();
        for (std::uint32_t f : v == a ? fa : fb) {
            const Face& corners = face_[f];
            const int k = corners[0] == v ? 0 : corners[1] == v ? 1 : 2;
            next_corner.push_back(corners[(k + 1) % 3]);
            previous_corner.push_back(corners[(k + 2) % 3]);
        }
        std::sort(next_corner.begin(), next_corner.end());
        std::sort(previous_corner.begin(), previous_corner.end());
        if (next_corner != previous_corner || std::adjacent_find(next_corner.begin(), next_corner.end()) != next_corner.end()) {
            return false;
        }
    }
    // Γ one cycle: the edges opposite a or b in the faces that stay (each has one of them).
    thread_local std::vector<LinkEdge> link;
    if (!link_cycle(a, b, star, link)) return false;
    // One orientation in a coordinate plane where the reference face is proper.
    int axis = 0, turn = 0;
    for (; axis < 3 && turn == 0; ++axis) turn = exact::orient_projected(reference[0], reference[1], reference[2], axis, predicates);
    if (turn == 0) return false;  // (a clean face is never degenerate)
    --axis;
    for (const auto* faces : {&fa, &fb}) {
        for (std::uint32_t f : *faces) {
            const exact::Triangle3 t = triangle(face_[f]);
            if (exact::orient_projected(t[0], t[1], t[2], axis, predicates) != turn) return false;
        }
    }
    for (const exact::Triangle3& t : c.fresh) {
        if (exact::orient_projected(t[0], t[1], t[2], axis, predicates) != turn) return false;
    }
    // Last, the faces not yet known clean (input faces) are checked against the faces near them,
    // once: clean from now on, or known to meet another.
    for (const auto* faces : {&fa, &fb}) {
        for (std::uint32_t f : *faces) {
            if (clean_[f] == kUnknown) clean_[f] = meets_another(f, overlay, predicates) ? kConflicting : kClean;
            if (clean_[f] != kClean) return false;
        }
    }
    return true;
}

bool Simplifier::link_cycle(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& star,
                            std::vector<LinkEdge>& link) const {
    link.clear();
    for (std::uint32_t f : star) {
        const Face& c = face_[f];
        const int k = c[0] == a || c[0] == b ? 0 : c[1] == a || c[1] == b ? 1 : 2;
        link.push_back({c[(k + 1) % 3], c[(k + 2) % 3]});
    }
    if (link.empty()) return false;
    std::sort(link.begin(), link.end(), [](const LinkEdge& e, const LinkEdge& f) { return e.x < f.x; });
    for (std::size_t i = 1; i < link.size(); ++i) {
        if (link[i].x == link[i - 1].x) return false;
    }
    std::uint32_t at = link.front().x;
    for (std::size_t steps = 0; steps < link.size(); ++steps) {
        const auto it = std::lower_bound(link.begin(), link.end(), at, [](const LinkEdge& e, std::uint32_t v) { return e.x < v; });
        if (it == link.end() || it->x != at) return false;
        at = it->y;
        if (at == link.front().x && steps + 1 != link.size()) return false;
    }
    return at == link.front().x;
}

bool Simplifier::fan_is_simple(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& star, Point3 p,
                               exact::PredicateStats& predicates) const {
    thread_local std::vector<LinkEdge> link;
    thread_local std::vector<Point3> ring;
    if (star.size() < 3 || !link_cycle(a, b, star, link)) return false;
    // Γ's corners in cycle order.
    ring.clear();
    const LinkEdge* edge = &link.front();
    for (std::size_t steps = 0; steps < link.size(); ++steps) {
        ring.push_back(pos_[edge->x]);
        edge = &*std::lower_bound(link.begin(), link.end(), edge->y, [](const LinkEdge& e, std::uint32_t v) { return e.x < v; });
    }
    return exact::simple_fan(p, ring, predicates);
}

// Did one of the faces the collapse replaces (a's and b's, as they are) meet `other` beyond
// their shared corners? (A degenerate one inherits nothing.)
bool Simplifier::met_by_replaced(const Collapse& c, const exact::Triangle3& other, const Box3& other_box,
                                 exact::PredicateStats& predicates) const {
    for (const std::vector<std::uint32_t>* faces : {&c.fa, &c.fb}) {
        for (const std::uint32_t r : *faces) {
            // (The faces of ab are both a's and b's: tested with a's.)
            if (faces == &c.fb && std::find(c.shared.begin(), c.shared.end(), r) != c.shared.end()) continue;
            const exact::Triangle3 old = triangle(face_[r]);
            if (!other_box.overlaps(triangle_box(old[0], old[1], old[2]))) continue;
            if (!exact::degenerate(old, predicates) && exact::faces_conflict(old, other, predicates)) return true;
        }
    }
    return false;
}

bool Simplifier::meets_another(std::uint32_t f, const Overlay& overlay, exact::PredicateStats& predicates) const {
    thread_local std::vector<std::uint32_t> found;
    const exact::Triangle3 t = triangle(face_[f]);
    if (exact::degenerate(t, predicates)) return true;
    const Box3 box = triangle_box(t[0], t[1], t[2]);
    index_.query(box, overlay, found);
    for (std::uint32_t g : found) {
        if (g == f || !alive_[g]) continue;
        const exact::Triangle3 u = triangle(face_[g]);
        if (box.overlaps(triangle_box(u[0], u[1], u[2])) && exact::faces_conflict(t, u, predicates)) return true;
    }
    return false;
}

}  // namespace toposimp::mesh::detail
