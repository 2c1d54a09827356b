// UGSimp's simplifier (simplify.hpp says what it does), shared by the files that implement
// it, one step of the method each:
//   topology.cpp       corner lists, live faces, compaction, vertices sharing a location
//   quadrics.cpp       per-vertex quadrics (and border edges, non-manifold edges), placement
//   spatial_order.cpp  vertices and faces numbered along a Z-order curve while simplifying
//   face_index.cpp     faces by cell, for the contact search
//   collapse.cpp       one collapse: its checks in order, then the change
//   contacts.cpp       the no-new-contact check of a collapse (every_collapse; else the result
//                      is checked once: self_contact.cpp, result_contact in simplify.cpp)
//   simplify.cpp       the driver: grid, levels, rounds, blocks, the count target's threshold
#pragma once

#include "core/exact/predicates3d.hpp"
#include "core/mesh/face_index.hpp"
#include "core/mesh/grid.hpp"
#include "core/mesh/height_field.hpp"
#include "core/mesh/quadric.hpp"
#include "core/mesh/simplify.hpp"
#include "core/mesh/vertical_bound.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace toposimp::mesh::detail {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// Vertex flags.
constexpr std::uint8_t kBoundary = 1;  // on an edge with one face
constexpr std::uint8_t kLocked = 2;    // never moves, never removed
constexpr std::uint8_t kDead = 4;      // merged into another vertex
constexpr std::uint8_t kInside = 8;    // this level: it and all its neighbours lie in its block
constexpr std::uint8_t kNewlyInside = 16;  // inside at this level but not at the one before
// Marks set and cleared again on the corners of an inside vertex's faces by the link test and
// corners_but (vertices of the block, which one thread alone touches).
constexpr std::uint8_t kMarked = 32;   // gathered already, or (link test) a corner of a face of a
constexpr std::uint8_t kCounted = 64;  // a corner of a face of a and of one of b, counted

// Stamps count the changes of a vertex (a collapse it absorbed, its own death), in 31 bits (a
// candidate keeps their sum and one more bit): a candidate whose ends' stamps changed is stale.
constexpr std::uint32_t kStampMask = 0x7fffffff;

struct Candidate {
    double cost;
    std::uint32_t a, b;  // a < b
    // The sum of a's and b's stamps (modulo 2^31: stamps only grow, so another sum means that
    // one changed); top bit: the placement was held back by the block.
    std::uint32_t stamps_bound;
    // Under a vertical bound: the touch counts of a and b (summed) when it was last refused, or
    // kNone. Unchanged counts mean unchanged stars, so the same refusal: not tried again.
    std::uint32_t refused_touches;

    std::uint32_t stamps() const { return stamps_bound & kStampMask; }
    // The optimal point or the midpoint lay outside the block: a coarser level's block, which
    // holds this one, may place the merged vertex differently.
    bool bound() const { return (stamps_bound >> 31) != 0; }
};

static_assert(sizeof(Candidate) == 24, "candidates are sorted and moved by the million: keep them small");

// Candidates are ranked by their quadric cost plus kLengthWeight·|ab|⁴ (the cost's own units:
// area times squared distance), which only orders them (errors and --max-error use the quadric
// cost alone). On curved surfaces the term is a few millionths of the cost. Where the faces are
// coplanar the cost is rounding noise, and the noise used to order the collapses: on the fandisk
// model the new faces of a collapse numbered 13 on average (7 on curved models), and the contact
// search grows with their square. Short edges first keeps the fans small there: fandisk 0.80 →
// 0.27 s on one thread, the Hausdorff distance of every benchmark model the same (jacksboro
// +0.7 %), the mean distances within ±1 %.
constexpr double kLengthWeight = 1e-6;

// Heap order: the smallest (cost, a, b) on top. (A lambda, not a function: the heap algorithms
// inline it instead of calling through a pointer.)
inline constexpr auto later = [](const Candidate& x, const Candidate& y) {
    if (x.cost != y.cost) return x.cost > y.cost;
    if (x.a != y.a) return x.a > y.a;
    return x.b > y.b;
};

struct Placement {
    Point3 p;
    double cost;
    bool bound = false;  // see Candidate::bound
};

// An edge x → y of a collapse's link (opposite a or b in a face, in the face's turn).
struct LinkEdge {
    std::uint32_t x, y;
};

// What one block did.
struct BlockResult {
    SimplifyStats stats;
    std::uint64_t faces_removed = 0;
};

// What try_collapse() gathers about the collapse of an edge ab, check by check (one per thread,
// reused: its vectors keep their capacity).
struct Collapse {
    std::uint32_t a = 0, b = 0;  // b merges into a
    Placement placement;
    double error = 0;                 // the quadric error of the placement, in coordinate units
    std::vector<std::uint32_t> fa, fb;  // the live faces of a and of b, in list order
    std::uint32_t last_of_a = 0;      // a's last corner: b's list is appended after it
    std::vector<std::uint32_t> shared;    // the faces of ab: they die
    std::vector<std::uint32_t> opposite;  // their corners other than a and b, sorted
    std::vector<std::uint32_t> star;      // the faces with a or b but not both: they change
    std::size_t from_a = 0;               // star[0, from_a) are a's
    std::vector<exact::Triangle3> fresh;  // the star's faces with a and b at the placement
    std::vector<exact::Triangle3> fan;    // (vertical bound) the same, each from the placement
    std::vector<std::uint32_t> replaced;  // (vertical bound) the star and the shared faces
    Box3 reach{};                         // the box of the fresh faces
    bool twin_after = false;              // (3D) another vertex lies at the placement
    bool inherits = false;                // a new face meets a face an old one met (see no_new_contact)
};

class Simplifier {
public:
    // `input_copy`: where to copy the mesh before any collapse when the result is to be checked
    // after the run (quick_), for a second run.
    Simplifier(Mesh& mesh, const SimplifyOptions& options, Mesh* input_copy = nullptr)
        : mesh_(mesh), options_(options), input_copy_(input_copy) {}

    SimplifyStats run();

private:
    // ---- simplify.cpp: the driver ----
    // A block of a level: a run of the level's vertices, and its share of a round's work.
    struct Block {
        std::uint64_t key;
        std::size_t first, count;
        std::uint64_t budget;
    };
    // A level's blocks with their vertices and candidates; `before`: for each block, the
    // candidate lists of the finer level's blocks it is made of (handed down at its first round).
    struct Level {
        int level = 0;
        std::vector<Block> blocks;
        std::vector<std::uint32_t> vertices;
        std::vector<std::vector<Candidate>> candidates;
        std::vector<std::vector<std::vector<Candidate>*>> before;
    };
    bool prepare(SimplifyStats& stats);
    Level group_by_block(int level, Level& finer, std::vector<std::uint32_t>& live) const;
    void find_candidates(Level& level, int round);
    double share_work(Level& level, std::uint64_t left, bool top) const;
    std::uint64_t collapse_blocks(Level& level, double limit, SimplifyStats& stats);
    // A grid over the live faces' corners and `seed`, cells `factor` times the mean edge (at
    // most 2^20 per side). Edge lengths are summed in fixed chunks of faces, the chunks' sums in
    // order: the same grid for any thread count.
    Grid grid_over_faces(double factor, Point3 seed) const;
    void choose_grid();
    void check_terrain();
    void build_face_index();
    // After a run with quick_, its dead faces dropped: where two faces of the result meet (a
    // corner of one), one a collapse made, as no collapse checked with a search would have let
    // them, or a collapse made a degenerate face; none if nowhere.
    std::optional<Point3> result_contact(exact::PredicateStats& predicates) const;
    // The candidates of a block at the start of a level: the still valid ones of the blocks it
    // was made of at the level before (`before`, emptied), the others computed afresh.
    std::vector<Candidate> block_candidates(int level, const std::uint32_t* vertices, std::size_t count, std::uint64_t block,
                                            const std::vector<std::vector<Candidate>*>& before);
    // One round of a block, from its candidates (in any order; left in any order).
    BlockResult collapse_block(int level, std::uint64_t block, std::vector<Candidate>& candidates, std::uint64_t budget,
                               double cost_limit);
    // The candidates of a block for its next round of the level: those it has, without those a
    // collapse made stale.
    void reopen(std::vector<Candidate>& candidates) const;
    // In a terrain under a vertical bound, every collapse counts a touch of each vertex of the
    // faces it makes: a vertex's faces change only with its count (a refusal, which depends on
    // nothing else, need not be tried again until then).
    std::uint32_t touches(const Candidate& c) const { return touch_[c.a] + touch_[c.b]; }
    bool stale(const Candidate& c) const {
        return ((stamp_[c.a] + stamp_[c.b]) & kStampMask) != c.stamps();
    }
    Candidate candidate(std::uint32_t a, std::uint32_t b, const Placement& placement) const {
        const Point3 d = span(pos_[b], pos_[a]);
        const double length2 = dot(d, d);
        // (Never NaN, which the sorts could not order: a cost that is not a number goes last.)
        const double cost = placement.cost + kLengthWeight * length2 * length2;
        return {std::isnan(cost) ? std::numeric_limits<double>::infinity() : cost, a, b,
                ((stamp_[a] + stamp_[b]) & kStampMask) | (placement.bound ? ~kStampMask : 0u), kNone};
    }
    // The edges from v to its inside neighbours w for which wanted(w), placed, into `out`.
    template <class Wanted>
    void place_edges(std::uint32_t v, std::span<const std::uint32_t> around, Wanted wanted, int level, std::uint64_t block,
                     std::vector<Candidate>& out) const;
    bool in_block(Point3 p, int level, std::uint64_t block) const {
        return grid_.block_of(grid_.cell_key(p), level) == block;
    }

    // ---- topology.cpp ----
    void build_topology();
    // Each vertex's list of corners, in face order.
    void link_corners();
    // The dead faces dropped, the others kept in order with their attribute rows (their old
    // numbers to `kept`).
    void drop_dead_faces(std::vector<std::uint32_t>* kept);
    // Dead faces dropped, corner lists rebuilt.
    void compact_faces();
    // Marks the vertices that share their location with another (3D meshes: see flat_and_clean).
    void find_twins();
    // Live faces around v, unlinking dead corners from v's list as it goes.
    void faces_of(std::uint32_t v, std::vector<std::uint32_t>& out);
    // Those of v and those of w: the two lists walked side by side, so that the loads of one
    // (scattered: a corner at a time) overlap those of the other.
    void faces_of(std::uint32_t v, std::vector<std::uint32_t>& out_v, std::uint32_t w, std::vector<std::uint32_t>& out_w);
    // One step along a corner list at `link`: past a dead corner (unlinked) or a live one (its
    // face to `out`).
    void step(std::uint32_t*& link, std::vector<std::uint32_t>& out) {
        const std::uint32_t c = *link;
        if (!alive_[c / 3]) {
            *link = next_[c];
            return;
        }
        __builtin_prefetch(&face_[c / 3]);  // read next by every caller
        out.push_back(c / 3);
        link = &next_[c];
    }
    // The corners of `faces` other than v, each once, in no set order: v's neighbours when they
    // are its faces. Each is marked while they are gathered: all must be vertices of the
    // calling thread's block.
    void corners_but(const std::vector<std::uint32_t>& faces, std::uint32_t v, std::vector<std::uint32_t>& out) {
        out.clear();
        flags_[v] |= kMarked;
        for (std::uint32_t f : faces) {
            for (std::uint32_t w : face_[f]) {
                if ((flags_[w] & kMarked) == 0) {
                    flags_[w] |= kMarked;
                    out.push_back(w);
                }
            }
        }
        flags_[v] &= static_cast<std::uint8_t>(~kMarked);
        for (std::uint32_t w : out) flags_[w] &= static_cast<std::uint8_t>(~kMarked);
    }

    // ---- quadrics.cpp ----
    // Per vertex: the sum of its faces' planes, and kBoundary if it is on an edge with one face.
    // Also the first non-manifold edge, if any (non_manifold_), and, when the terrain check needs
    // them, the directed border edges (border_): all from one pass over each vertex's faces.
    void build_quadrics();
    // Border vertices: locked (lock_), or their border planes added.
    void add_border_planes();
    // Where b and a merge, inside the block, and at what cost; false if both are locked.
    bool place(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, Placement& out) const;
    double error_of(const Placement& placement, std::uint32_t a, std::uint32_t b) const;

    // ---- spatial_order.cpp ----
    // Vertices and faces renumbered in a space-filling order (spatial_order), and back to the
    // input's order for the output (input_order).
    void spatial_order();
    void input_order();
    // Vertex i becomes vertex vertex_from[i] and face j face face_from[j], with their rows; a
    // corner v is renamed corner_to[v].
    void renumber(const std::vector<std::uint32_t>& vertex_from, const std::vector<std::uint32_t>& face_from,
                  const std::vector<std::uint32_t>& corner_to);

    // ---- collapse.cpp: one collapse, its checks in the order try_collapse makes them ----
    // On success, `around` holds a's neighbours after the collapse.
    bool try_collapse(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, BlockResult& result,
                      std::vector<std::uint32_t>& around, Overlay& overlay);
    // The faces of a and b, and of the edge ab (c.shared: empty if ab is no longer an edge).
    void gather_faces(Collapse& c);
    // Link condition (Dey et al. 1999).
    bool link_condition_holds(Collapse& c);
    // Both ends on a border but ab not a border edge: the collapse would pinch the border.
    bool pinches_border(const Collapse& c) const;
    // The faces that change (c.star).
    void gather_star(Collapse& c) const;
    // No changed face turns over (3D: its normal reversed; terrain: its map-plane orientation),
    // loses its area or duplicates another; counts the refusal's reason in `stats`.
    bool faces_stay_upright(Collapse& c, SimplifyStats& stats) const;
    // b merges into a at the placement.
    void apply(const Collapse& c, BlockResult& result, std::vector<std::uint32_t>& around, Overlay& overlay);

    // ---- contacts.cpp: no new contact ----
    // No changed face touches or crosses another face except at the corners and edge they share
    // (3D meshes; terrains that move a border vertex: in the map plane). Counts the refusal, or
    // a collapse decided without a search, in `stats`; notes in c.twin_after whether another
    // vertex lies at the placement.
    bool no_new_contact(Collapse& c, Overlay& overlay, SimplifyStats& stats);
    // The search itself: the faces near the fresh ones, tested against them (flattened to z = 0
    // if `flatten`).
    bool search_contacts(Collapse& c, bool flatten, Overlay& overlay, exact::PredicateStats& predicates);
    // Whether the collapse of the interior edge ab, whose changed faces `star` become `fresh` with
    // a and b at p, provably makes no contact, without looking at other faces (see the definition).
    bool flat_and_clean(const Collapse& c, Overlay& overlay, exact::PredicateStats& predicates);
    bool met_by_replaced(const Collapse& c, const exact::Triangle3& other, const Box3& other_box,
                         exact::PredicateStats& predicates) const;
    // The link Γ of the collapse of ab: for each face of `star` (each has a or b, not both), its
    // edge x → y opposite that corner, sorted by x. True if Γ is one cycle.
    bool link_cycle(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& star, std::vector<LinkEdge>& link) const;
    // Whether the new faces (the faces `star` with a and b at p) meet one another only at p and
    // along their shared edges from p: Γ is one cycle and the fan over it simple (exact::simple_fan).
    bool fan_is_simple(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& star, Point3 p,
                       exact::PredicateStats& predicates) const;
    // Does face f meet a face near it beyond their shared corners/edge (faces_conflict), or is it
    // degenerate?
    bool meets_another(std::uint32_t f, const Overlay& overlay, exact::PredicateStats& predicates) const;

    // ---- shared helpers ----
    exact::Triangle3 triangle(const Face& f) const { return {pos_[f[0]], pos_[f[1]], pos_[f[2]]}; }
    Box3 face_box(std::uint32_t f) const {
        const Face& c = face_[f];
        return triangle_box(pos_[c[0]], pos_[c[1]], pos_[c[2]]);
    }
    // b merges into a at p: a's attribute row becomes the blend of both rows at the point of
    // segment ab nearest p (the placement often lies off the edge; an end when the other is
    // locked keeps that end's row).
    void blend_attributes(std::uint32_t a, std::uint32_t b, Point3 p) {
        Attributes& rows = mesh_.vertex_attributes;
        if (rows.width == 0) return;
        const Point3 edge = span(pos_[a], pos_[b]);
        const double length2 = dot(edge, edge);
        const double t = length2 > 0 ? std::clamp(dot(span(pos_[a], p), edge) / length2, 0.0, 1.0) : 0.5;
        double* to = rows.row(a);
        const double* from = rows.row(b);
        // Exact at both ends and for a value both rows share.
        for (std::size_t k = 0; k < rows.width; ++k) to[k] = t == 1 ? from[k] : to[k] + t * (from[k] - to[k]);
    }
    Point3 local(Point3 p) const { return frame_.local(p); }
    // q − p in frame units: the difference scaled, or if that overflowed (coordinates of opposite
    // signs beyond half the largest double) the difference of the frame coordinates, which lie
    // within the frame's extent.
    Point3 span(Point3 p, Point3 q) const {
        const Point3 d = minus(q, p);
        if (std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)) [[likely]] {
            return {d.x * frame_.scale, d.y * frame_.scale, d.z * frame_.scale};
        }
        return minus(local(q), local(p));
    }

    Mesh& mesh_;
    const SimplifyOptions& options_;
    Mesh* input_copy_ = nullptr;
    int threads_ = 1;  // every parallel loop's (num_threads clauses: no process-wide OpenMP state)
    bool by_count_ = true;       // a count target (not max_error)
    std::uint64_t target_ = 0;   // its faces
    bool use_index_ = false;
    bool terrain_ = false;
    // No contact search (ContactCheck::at_the_end, a 3D mesh or a terrain whose border may
    // move): the result is checked after the run (result_contact), and no face index, clean_ or
    // twin_ is kept.
    bool quick_ = false;
    bool lock_ = false;  // border vertices never move (asked for, or kept for the vertical bound)
    std::unique_ptr<VerticalBound> vertical_;  // terrains under a max_error target
    int terrain_turn_ = 0;  // the map-plane orientation all terrain faces share
    std::optional<std::array<std::uint32_t, 2>> plan_overlap_;  // see SimplifyStats
    std::optional<NonManifoldEdge> non_manifold_;                // see SimplifyStats
    std::vector<DirectedEdge> border_;                           // see build_quadrics
    BlockGrid grid_;

    std::vector<Point3>& pos_ = mesh_.points;
    std::vector<Face>& face_ = mesh_.faces;
    std::vector<std::uint8_t> alive_;
    std::vector<std::uint32_t> next_;  // per corner: the next corner of the same vertex
    std::vector<std::uint32_t> head_;  // per vertex: its first corner
    std::vector<std::uint8_t> flags_;
    std::vector<std::uint32_t> stamp_;
    std::vector<std::uint32_t> touch_;  // per vertex, under a vertical bound (see touches())
    std::vector<std::uint64_t> cell_;  // per vertex: its grid cell
    std::unique_ptr<Quadric[]> quadric_;  // per vertex, in frame coordinates (local())
    // The quadrics' frame: origin at the centre of the input's bounding box, unit a power of two
    // near its largest extent. About the coordinate origin a plane's offset d is as large as the
    // coordinates, and a cost sums terms of d² that cancel: in UTM metres (x ~ 5·10^5, y ~ 4·10^6)
    // the rounding of d² exceeded the costs of a decimetre-sized model, the collapse order was
    // noise and the result tens of times further from the input. And a cost goes with the fourth
    // power of the size: a model 10^100 units across overflowed, one 10^-150 across underflowed.
    // In the frame the terms are of the order of 1. Scaling by a power of two is exact: the order
    // and the placements are those the same model would get at that size.
    PowerOfTwoFrame frame_;
    FaceIndex index_;
    // Per face, whether it meets no other face beyond their shared corners/edge: kClean when made
    // by a collapse (checked against every face near it then, and every face made since against
    // it) or checked since (meets_another); kUnknown for an input face not checked yet;
    // kConflicting when the check found a contact. (With quick_: kClean for a face a collapse
    // made, unchecked, kUnknown for one of the input's.)
    std::vector<std::uint8_t> clean_;
    static constexpr std::uint8_t kUnknown = 0, kClean = 1, kConflicting = 2;
    // Per vertex (3D meshes): another live vertex may have its location.
    std::vector<std::uint8_t> twin_;
    // Each vertex's and each face's number before spatial_order().
    std::vector<std::uint32_t> input_vertex_, input_face_;
    std::uint64_t live_faces_ = 0;
};

}  // namespace toposimp::mesh::detail
