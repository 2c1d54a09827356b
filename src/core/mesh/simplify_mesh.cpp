#include "core/mesh/simplify_mesh.hpp"

#include "core/exact/predicates3d.hpp"
#include "core/mesh/height_field.hpp"
#include "core/mesh/vertical_bound.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <type_traits>
#include <span>
#include <stdexcept>
#include <string>

namespace toposimp::mesh {
namespace {

using Clock = std::chrono::steady_clock;
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

// A symmetric 4×4 quadric (Garland & Heckbert 1997) plus the area it was built from. Zero when
// value-initialised (`Quadric q{}`); default-initialised, undefined, so that the per-vertex array
// can be first written in parallel.
struct Quadric {
    double xx, xy, xz, xw, yy, yz, yw, zz, zw, ww, area;

    void add_plane(double a, double b, double c, double d, double weight) {
        xx += weight * a * a, xy += weight * a * b, xz += weight * a * c, xw += weight * a * d;
        yy += weight * b * b, yz += weight * b * c, yw += weight * b * d;
        zz += weight * c * c, zw += weight * c * d, ww += weight * d * d;
    }
    Quadric& operator+=(const Quadric& q) {
        xx += q.xx, xy += q.xy, xz += q.xz, xw += q.xw, yy += q.yy, yz += q.yz, yw += q.yw;
        zz += q.zz, zw += q.zw, ww += q.ww, area += q.area;
        return *this;
    }
    double operator()(Point3 p) const {
        const double x = p.x, y = p.y, z = p.z;
        return x * (xx * x + 2 * (xy * y + xz * z + xw)) + y * (yy * y + 2 * (yz * z + yw)) + z * (zz * z + 2 * zw) + ww;
    }
};

Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

Point3 minus(Point3 a, Point3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Point3 cross(Point3 a, Point3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(Point3 a, Point3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(Point3 a) { return std::sqrt(dot(a, a)); }

// The uniform grid: cells of one size, grouped 2^shift per side into level-0 blocks; a level-l
// block is 2^l level-0 blocks per side. Cell coordinates are a monotone function of each
// coordinate, so the points of a block form a box (convex).
struct Grid {
    Point3 origin{};
    double inverse_size = 1.0;
    std::uint32_t cells[3] = {1, 1, 1};
    int shift = 0;

    // The floor of the scaled offset, clamped to the grid (NaN: cell 0). Truncation is the floor
    // for c >= 1, and it stays inline (std::floor is a library call on baseline x86-64).
    std::uint32_t cell(double value, double origin_value, int axis) const {
        const double c = (value - origin_value) * inverse_size;
        if (!(c >= 1)) return 0;
        return c >= cells[axis] - 1.0 ? cells[axis] - 1 : static_cast<std::uint32_t>(c);
    }
    // A coordinate in cells from the origin (unclamped, not floored).
    double units(double value, int axis) const { return (value - origin[axis]) * inverse_size; }
    std::uint64_t cell_key(Point3 p) const {
        return pack(cell(p.x, origin.x, 0), cell(p.y, origin.y, 1), cell(p.z, origin.z, 2));
    }
    static std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) { return x << 42 | y << 21 | z; }
    static std::uint32_t unpack(std::uint64_t key, int axis) {
        return static_cast<std::uint32_t>(key >> (42 - 21 * axis)) & 0x1fffff;
    }
    // The key of the block holding a cell at `level`.
    std::uint64_t block_of(std::uint64_t cell_key, int level) const {
        const int s = shift + level;
        return pack(unpack(cell_key, 0) >> s, unpack(cell_key, 1) >> s, unpack(cell_key, 2) >> s);
    }
    int top_level() const {
        int level = 0;
        while (((cells[0] - 1) >> (shift + level)) > 0 || ((cells[1] - 1) >> (shift + level)) > 0 ||
               ((cells[2] - 1) >> (shift + level)) > 0) {
            ++level;
        }
        return level;
    }
};

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
constexpr auto later = [](const Candidate& x, const Candidate& y) {
    if (x.cost != y.cost) return x.cost > y.cost;
    if (x.a != y.a) return x.a > y.a;
    return x.b > y.b;
};

// Doubles in their order as unsigned integers (costs are never NaN; −0 is taken as +0, which it
// equals).
std::uint64_t ordered_bits(double value) {
    const auto bits = std::bit_cast<std::uint64_t>(value + 0.0);
    return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

// The k-th smallest cost (k from 1, at most their number) of all the blocks' candidates, and in
// `under` how many of each block's are at most that cost: a histogram of the top 16 bits of the
// costs' order, counted in parallel; then, in parallel, each list counts its costs in lower
// buckets and collects those in the bucket that holds the k-th, among which the k-th is selected.
double kth_smallest_cost(const std::vector<std::vector<Candidate>>& lists, std::size_t k, int threads,
                         std::vector<std::uint64_t>& under) {
    constexpr int kShift = 48;
    std::vector<std::size_t> count(std::size_t{1} << (64 - kShift), 0);
    const auto n = static_cast<std::int64_t>(lists.size());
#pragma omp parallel num_threads(threads)
    {
        std::vector<std::size_t> mine(count.size(), 0);
#pragma omp for schedule(dynamic, 1) nowait
        for (std::int64_t i = 0; i < n; ++i) {
            for (const Candidate& c : lists[static_cast<std::size_t>(i)]) ++mine[ordered_bits(c.cost) >> kShift];
        }
#pragma omp critical
        for (std::size_t b = 0; b < count.size(); ++b) count[b] += mine[b];
    }
    std::size_t bucket = 0, below = 0;
    while (below + count[bucket] < k) below += count[bucket++];
    std::vector<std::vector<double>> in_bucket(lists.size());
    under.assign(lists.size(), 0);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (std::int64_t i = 0; i < n; ++i) {
        const auto l = static_cast<std::size_t>(i);
        for (const Candidate& c : lists[l]) {
            const std::uint64_t b = ordered_bits(c.cost) >> kShift;
            if (b < bucket) ++under[l];
            if (b == bucket) in_bucket[l].push_back(c.cost);
        }
    }
    std::vector<double> costs;
    costs.reserve(count[bucket]);
    for (const auto& list : in_bucket) costs.insert(costs.end(), list.begin(), list.end());
    const auto at = costs.begin() + static_cast<std::ptrdiff_t>(k - below - 1);
    std::nth_element(costs.begin(), at, costs.end());
    const double kth = *at;
    for (std::size_t l = 0; l < lists.size(); ++l) {
        under[l] += static_cast<std::uint64_t>(std::count_if(in_bucket[l].begin(), in_bucket[l].end(), [kth](double c) { return c <= kth; }));
    }
    return kth;
}

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
    MeshStats stats;
    std::uint64_t faces_removed = 0;
};

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

// A face's box in an index cell's list, in float grid units rounded outward (a superset of its
// box: a filter, never a decision), with which of the cell's coordinates are the first the face
// spans (bit per axis). 32 bytes: a query scans a cell's list in order instead of reading the
// faces' data one cache line each, and the next lists' lines are on their way meanwhile.
struct IndexEntry {
    float lo[3], hi[3];
    std::uint32_t face;
    std::uint8_t first_here;
};

// A face's box in index grid units, rounded outward to floats, and the cells holding its corners
// (lowest and highest on every axis).
struct UnitBox {
    float lo[3], hi[3];
    std::uint64_t first, last;
};

// Faces by grid cell for one round: the entries grouped by cell, and a table from a cell to its
// group. Built by a counting sort in parts (each a run of the entries, one thread's): each part
// count()s its (cell, entry) pairs in a table of its own, allocate() gives every cell its group
// and, in it, each part its share in part order, then each part place()s the same pairs in the
// same order. A cell lists its entries in their order, whatever the number of parts.
class CellIndex {
public:
    void clear(std::size_t parts) {
        entries_.clear();
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
        entries_.resize(total);
    }
    void place(std::size_t part, std::uint64_t key, const IndexEntry& entry) { entries_[(*parts_[part].find(key))++] = entry; }
    // The entries listed in a cell.
    std::span<const IndexEntry> entries(std::uint64_t key) const {
        const Group* group = groups_.find(key);
        return group == nullptr ? std::span<const IndexEntry>{} : std::span(entries_.data() + group->first, group->count);
    }

private:
    struct Group {
        std::size_t first = 0, count = 0;
    };
    std::vector<IndexEntry> entries_;
    CellMap<Group> groups_;
    std::vector<CellMap<std::size_t>> parts_;
};

// The faces a block changed in the current round and that live, by index cell: an entry in each
// cell their box spans now, as in the index.
using Overlay = CellMap<std::vector<IndexEntry>>;

class Simplifier {
public:
    Simplifier(Mesh& mesh, const MeshOptions& options) : mesh_(mesh), options_(options) {}

    MeshStats run();

private:
    void build_topology();
    // Each vertex's list of corners, in face order.
    void link_corners();
    // The dead faces dropped, the others kept in order with their attribute rows (their old
    // numbers to `kept`).
    void drop_dead_faces(std::vector<std::uint32_t>* kept);
    // Dead faces dropped, corner lists rebuilt.
    void compact_faces();
    // Per vertex: the sum of its faces' planes, and kBoundary if it is on an edge with one face.
    // Also the first non-manifold edge, if any (non_manifold_), and, when the terrain check needs
    // them, the directed border edges (border_): all from one pass over each vertex's faces.
    void build_quadrics();
    // Border vertices: locked (lock_), or their border planes added.
    void add_border_planes();
    // A grid over the live faces' corners and `seed`, cells `factor` times the mean edge (at
    // most 2^20 per side). Edge lengths are summed in fixed chunks of faces, the chunks' sums in
    // order: the same grid for any thread count.
    Grid grid_over_faces(double factor, Point3 seed) const;
    void choose_grid();
    void check_terrain();
    // Vertices and faces renumbered in a space-filling order (spatial_order), and back to the
    // input's order for the output (input_order).
    void spatial_order();
    void input_order();
    // Vertex i becomes vertex vertex_from[i] and face j face face_from[j], with their rows; a
    // corner v is renamed corner_to[v].
    void renumber(const std::vector<std::uint32_t>& vertex_from, const std::vector<std::uint32_t>& face_from,
                  const std::vector<std::uint32_t>& corner_to);
    void build_face_index();
    // The candidates of a block at the start of a level: the still valid ones of the blocks it
    // was made of at the level before (`before`, emptied), the others computed afresh.
    std::vector<Candidate> block_candidates(int level, const std::uint32_t* vertices, std::size_t count, std::uint64_t block,
                                            const std::vector<std::vector<Candidate>*>& before);
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
    // One round of a block, from its candidates (in any order; left in any order).
    BlockResult collapse_block(int level, std::uint64_t block, std::vector<Candidate>& candidates, std::uint64_t budget,
                               double cost_limit);
    // The candidates of a block for its next round of the level: those it has, without those a
    // collapse made stale.
    void reopen(std::vector<Candidate>& candidates) const;

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
    // On success, `around` holds a's neighbours after the collapse.
    bool try_collapse(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, BlockResult& result,
                      std::vector<std::uint32_t>& around,
                      Overlay& overlay);
    bool place(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, Placement& out) const;
    // Whether the collapse of the interior edge ab, whose changed faces `star` become `fresh` with
    // a and b at p, provably makes no contact, without looking at other faces (see the definition).
    bool flat_and_clean(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& fa, const std::vector<std::uint32_t>& fb,
                        const std::vector<std::uint32_t>& star, Point3 p, const std::vector<exact::Triangle3>& fresh,
                        Overlay& overlay, exact::PredicateStats& predicates);
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
    // Marks the vertices that share their location with another (3D meshes: see flat_and_clean).
    void find_twins();
    bool in_block(Point3 p, int level, std::uint64_t block) const {
        return grid_.block_of(grid_.cell_key(p), level) == block;
    }
    exact::Triangle3 triangle(const Face& f) const { return {pos_[f[0]], pos_[f[1]], pos_[f[2]]}; }
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
    static bool shares_a_location(const exact::Triangle3& f, const exact::Triangle3& g) {
        for (const Point3& p : f) {
            for (const Point3& q : g) {
                if (same_location(p, q)) return true;
            }
        }
        return false;
    }
    Box3 face_box(std::uint32_t f) const {
        const Face& c = face_[f];
        return triangle_box(pos_[c[0]], pos_[c[1]], pos_[c[2]]);
    }
    template <class Visit>
    void for_cells(const Box3& box, Visit visit) const {
        for_cells(index_grid_.cell_key(box.lo), index_grid_.cell_key(box.hi), visit);
    }
    template <class Visit>
    void for_cells(std::uint64_t first, std::uint64_t last, Visit visit) const;
    UnitBox unit_box(const Box3& box) const;
    void query(const Box3& box, const Overlay& overlay,
               std::vector<std::uint32_t>& out) const;
    // The edges from v to its inside neighbours w for which wanted(w), placed, into `out`.
    template <class Wanted>
    void place_edges(std::uint32_t v, std::span<const std::uint32_t> around, Wanted wanted, int level, std::uint64_t block,
                     std::vector<Candidate>& out) const;
    double error_of(const Placement& placement, std::uint32_t a, std::uint32_t b) const;

    Mesh& mesh_;
    const MeshOptions& options_;
    bool use_index_ = false;
    bool terrain_ = false;
    bool lock_ = false;  // border vertices never move (asked for, or kept for the vertical bound)
    std::unique_ptr<VerticalBound> vertical_;  // terrains under a max_error target
    int terrain_turn_ = 0;  // the map-plane orientation all terrain faces share
    std::optional<std::array<std::uint32_t, 2>> plan_overlap_;  // see MeshStats
    std::optional<NonManifoldEdge> non_manifold_;                // see MeshStats
    std::vector<DirectedEdge> border_;                           // see build_quadrics
    Grid grid_;

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
    CellIndex index_;
    Grid index_grid_;                   // the index's cells (not the blocks')
    std::vector<UnitBox> unit_boxes_;  // per live face, while the index is built
    // Per face: changed (moved or removed) by its block in this round; the overlay has it if it
    // lives.
    std::vector<std::uint8_t> changed_;
    // Per face, whether it meets no other face beyond their shared corners/edge: kClean when made
    // by a collapse (checked against every face near it then, and every face made since against
    // it) or checked since (meets_another); kUnknown for an input face not checked yet;
    // kConflicting when the check found a contact.
    std::vector<std::uint8_t> clean_;
    static constexpr std::uint8_t kUnknown = 0, kClean = 1, kConflicting = 2;
    // Per vertex (3D meshes): another live vertex may have its location.
    std::vector<std::uint8_t> twin_;
    // Each vertex's and each face's number before spatial_order().
    std::vector<std::uint32_t> input_vertex_, input_face_;
    std::uint64_t live_faces_ = 0;
};

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

void Simplifier::build_quadrics() {
    // Each face's plane once (unit normal, offset, and the normal's length: twice the area).
    struct Plane {
        double a, b, c, d, length;
    };
    const auto m = static_cast<std::int64_t>(face_.size());
    const auto n = static_cast<std::int64_t>(pos_.size());
    double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, lo_z = lo_x;
    double hi_x = -lo_x, hi_y = -lo_x, hi_z = -lo_x;
#pragma omp parallel for schedule(static) reduction(min : lo_x, lo_y, lo_z) reduction(max : hi_x, hi_y, hi_z)
    for (std::int64_t i = 0; i < n; ++i) {
        const Point3 p = pos_[static_cast<std::size_t>(i)];
        lo_x = std::min(lo_x, p.x), lo_y = std::min(lo_y, p.y), lo_z = std::min(lo_z, p.z);
        hi_x = std::max(hi_x, p.x), hi_y = std::max(hi_y, p.y), hi_z = std::max(hi_z, p.z);
    }
    if (n > 0) frame_ = frame_around({{lo_x, lo_y, lo_z}, {hi_x, hi_y, hi_z}});
    // Left uninitialised (written once below, in parallel): zeroing and faulting in ~40 bytes per
    // face serially first took as long as the loop.
    const std::unique_ptr<Plane[]> planes(new Plane[face_.size()]);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < m; ++i) {
        const Face& f = face_[static_cast<std::size_t>(i)];
        const Point3 normal = cross(span(pos_[f[0]], pos_[f[1]]), span(pos_[f[0]], pos_[f[2]]));
        const double length = norm(normal);
        Plane& plane = planes[static_cast<std::size_t>(i)];
        plane.length = length;
        if (!(length > 0)) continue;
        const Point3 unit{normal.x / length, normal.y / length, normal.z / length};
        plane = {unit.x, unit.y, unit.z, -dot(unit, local(pos_[f[0]])), length};
    }
    // Each vertex sums the planes of its faces in list order: deterministic for any thread count.
    // Its neighbours are counted as it goes, by the faces it shares with each and the way those
    // turn (w after v, or before it): one face, a border edge; more than two, a non-manifold edge.
    quadric_ = std::make_unique_for_overwrite<Quadric[]>(pos_.size());  // each written once below
    const bool want_border = options_.terrain && !options_.height_field;
    const auto parts = static_cast<std::size_t>(omp_get_max_threads());
    std::vector<std::vector<DirectedEdge>> border_parts(parts);
    std::vector<DirectedEdge> first_bad(parts, {kNone, kNone});  // each thread's least non-manifold edge
#pragma omp parallel
    {
        // (neighbour, how many of v's faces have it, of those how many have it after v): a vertex
        // has a few, a scan, no sort.
        struct Seen {
            std::uint32_t vertex, count, after;
        };
        std::vector<Seen> seen;
        const auto me = static_cast<std::size_t>(omp_get_thread_num());
        auto meet = [&seen](std::uint32_t w, bool after) {
            for (Seen& s : seen) {
                if (s.vertex == w) {
                    ++s.count;
                    s.after += after;
                    return;
                }
            }
            seen.push_back({w, 1, after});
        };
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            const auto v = static_cast<std::uint32_t>(i);
            seen.clear();
            Quadric q{};
            for (std::uint32_t c = head_[v]; c != kNone; c = next_[c]) {
                const Face& f = face_[c / 3];
                const auto k = c % 3;
                meet(f[(k + 1) % 3], true);
                meet(f[(k + 2) % 3], false);
                const Plane& plane = planes[c / 3];
                if (!(plane.length > 0)) continue;
                const double area = 0.5 * plane.length;
                q.add_plane(plane.a, plane.b, plane.c, plane.d, area);
                q.area += area;
            }
            quadric_[v] = q;
            for (const Seen& s : seen) {
                if (s.count == 1) flags_[v] |= kBoundary;
                if (s.count > 2 && s.vertex > v && DirectedEdge{v, s.vertex} < first_bad[me]) first_bad[me] = {v, s.vertex};
                // A face has v → w and none w → v: once per such face.
                if (want_border && s.after == s.count) border_parts[me].insert(border_parts[me].end(), s.after, {v, s.vertex});
            }
        }
    }
    const DirectedEdge bad = *std::min_element(first_bad.begin(), first_bad.end());
    if (bad.first != kNone) {
        NonManifoldEdge edge{bad.first, bad.second, {}};
        for (std::uint32_t c = head_[bad.first]; c != kNone && edge.faces.size() < 4; c = next_[c]) {
            const Face& f = face_[c / 3];
            if (f[0] == bad.second || f[1] == bad.second || f[2] == bad.second) edge.faces.push_back(c / 3);
        }
        non_manifold_ = std::move(edge);
    }
    border_.clear();
    for (const auto& part : border_parts) border_.insert(border_.end(), part.begin(), part.end());
    std::sort(border_.begin(), border_.end());
}

void Simplifier::add_border_planes() {
    // Each border vertex finds its border edges (a neighbour met in only one of its faces) and
    // unless locked adds for each a plane through the edge perpendicular to its face, weighted
    // heavily (Garland & Heckbert §6), in neighbour order; computed from the edge's lower id so
    // both ends add the same quadric.
    const auto n = static_cast<std::int64_t>(pos_.size());
#pragma omp parallel
    {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> seen;     // (neighbour, face), with repeats
        std::vector<std::pair<std::uint32_t, std::uint32_t>> borders;  // (neighbour, face)
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            const auto v = static_cast<std::uint32_t>(i);
            if ((flags_[v] & kBoundary) == 0) continue;
            if (lock_) {
                flags_[v] |= kLocked;
                continue;
            }
            seen.clear();
            for (std::uint32_t c = head_[v]; c != kNone; c = next_[c]) {
                const Face& f = face_[c / 3];
                seen.emplace_back(f[(c % 3 + 1) % 3], c / 3);
                seen.emplace_back(f[(c % 3 + 2) % 3], c / 3);
            }
            borders.clear();
            for (const auto& [w, face] : seen) {
                const auto times = std::count_if(seen.begin(), seen.end(), [w](const auto& s) { return s.first == w; });
                if (times == 1) borders.emplace_back(w, face);
            }
            std::sort(borders.begin(), borders.end());
            Quadric& q = quadric_[v];
            for (const auto& [w, face] : borders) {
                const auto lo = std::min(v, w), hi = std::max(v, w);
                const Face& f = face_[face];
                const Point3 normal = cross(span(pos_[f[0]], pos_[f[1]]), span(pos_[f[0]], pos_[f[2]]));
                const Point3 edge = span(pos_[lo], pos_[hi]);
                const Point3 side = cross(edge, normal);
                const double length = norm(side);
                if (length > 0) {
                    const Point3 unit{side.x / length, side.y / length, side.z / length};
                    Quadric border{};
                    border.add_plane(unit.x, unit.y, unit.z, -dot(unit, local(pos_[lo])), 1000.0 * dot(edge, edge));
                    q += border;
                }
            }
        }
    }
}

Grid Simplifier::grid_over_faces(double factor, Point3 seed) const {
    constexpr std::int64_t kChunk = std::int64_t{1} << 14;
    const auto m = static_cast<std::int64_t>(face_.size());
    const std::int64_t chunks = (m + kChunk - 1) / kChunk;
    struct Part {
        double edges = 0;
        std::uint64_t count = 0;
        Box3 box;
    };
    std::vector<Part> parts(static_cast<std::size_t>(chunks), Part{0, 0, point_box(seed)});
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < chunks; ++k) {
        Part& part = parts[static_cast<std::size_t>(k)];
        for (std::int64_t f = k * kChunk; f < std::min(m, (k + 1) * kChunk); ++f) {
            if (!alive_[f]) continue;
            const Face& c = face_[f];
            for (int i = 0; i < 3; ++i) {
                part.edges += norm(minus(pos_[c[i]], pos_[c[(i + 1) % 3]]));
                part.box.add(pos_[c[i]]);
            }
            part.count += 3;
        }
    }
    double edges = 0;
    std::uint64_t count = 0;
    Box3 all = point_box(seed);
    for (const Part& part : parts) {
        edges += part.edges;
        count += part.count;
        all.add(part.box.lo);
        all.add(part.box.hi);
    }
    const double extent[3] = {all.hi.x - all.lo.x, all.hi.y - all.lo.y, all.hi.z - all.lo.z};
    const double largest = std::max({extent[0], extent[1], extent[2]});
    double size = count > 0 ? factor * edges / static_cast<double>(count) : 1.0;
    if (!(size > 0) || !std::isfinite(size)) size = largest > 0 ? largest : 1.0;
    // At most 2^20 cells per side (keys pack 21 bits per axis).
    if (largest / size > 1048575.0) size = largest / 1048575.0;
    Grid grid;
    grid.origin = all.lo;
    grid.inverse_size = 1.0 / size;
    for (int axis = 0; axis < 3; ++axis) {
        grid.cells[axis] = static_cast<std::uint32_t>(std::min(1048576.0, std::floor(extent[axis] / size) + 1));
    }
    return grid;
}

void Simplifier::choose_grid() {
    // Cells 1.5 times the mean edge.
    grid_ = grid_over_faces(1.5, pos_.empty() ? Point3{0, 0, 0} : pos_[0]);
    // Level-0 blocks: the fewest cells per block side (a power of two) that leaves at most one
    // block per 2 048 faces, between 8 and 512 (the dissertation's best resolution, for meshes of
    // millions of faces). Smaller blocks cost quality: on an 89 k-face model 512 blocks made the
    // Hausdorff distance 20× worse than one block. Blocks per 2 048 faces (23 on that model, 8 per
    // 4 096) kept the Hausdorff distance of every model and terrain of the benchmark, and left
    // less to the last level's single block: 0.95 → 0.74 s there on 2 threads. Never a function
    // of the thread count: the result must not depend on it.
    const double most_blocks = std::clamp(static_cast<double>(face_.size()) / 2048.0, 8.0, 512.0);
    grid_.shift = 0;
    for (;;) {
        double blocks = 1;
        for (int axis = 0; axis < 3; ++axis) blocks *= static_cast<double>(((grid_.cells[axis] - 1) >> grid_.shift) + 1);
        if (blocks <= most_blocks) break;
        ++grid_.shift;
    }
    cell_.resize(pos_.size());
    const auto n = static_cast<std::int64_t>(pos_.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < n; ++v) cell_[static_cast<std::size_t>(v)] = grid_.cell_key(pos_[static_cast<std::size_t>(v)]);
}

void Simplifier::check_terrain() {
    terrain_ = false;
    if (!options_.terrain) return;
    if (face_.empty()) return;
    // Every face turned the same way in the map plane, none degenerate there, and no two
    // overlapping there (height_field.hpp); otherwise not a planar triangulation: 3D tests.
    auto turn_of = [this](const Face& f) {
        exact::PredicateStats unused;
        return exact::orient_projected(pos_[f[0]], pos_[f[1]], pos_[f[2]], 2, unused);
    };
    const int turn = turn_of(face_[0]);
    if (turn == 0) return;
    const auto m = static_cast<std::int64_t>(face_.size());
    bool same = true;
#pragma omp parallel for schedule(static) reduction(&& : same)
    for (std::int64_t f = 1; f < m; ++f) same = same && turn_of(face_[static_cast<std::size_t>(f)]) == turn;
    terrain_turn_ = turn;
    if (!same) return;
    if (!options_.height_field) {
        plan_overlap_ = plan_overlap(mesh_, turn, border_);
        if (plan_overlap_) return;
    }
    terrain_ = true;
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

namespace {

// Item i (a row of `width` values) becomes the one at order[i]: the items copied aside into
// `scratch`, then gathered back in parallel. Measured on the 2 M terrain (before such inputs
// were left in their order), 2 threads: a new array for each, quadrics included, raised the
// peak memory from 327 to 419 MB; moving the items along the permutation's cycles, in place,
// reads memory at random one item at a time: +0.6 s. One scratch buffer for every array, the
// quadrics rebuilt rather than moved: 351 MB.
template <class T>
void permute(T* items, std::size_t rows, std::size_t width, const std::vector<std::uint32_t>& order, unsigned char* scratch) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (width == 0) return;
    T* aside = reinterpret_cast<T*>(scratch);
    std::copy_n(items, rows * width, aside);
    const auto count = static_cast<std::int64_t>(order.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < count; ++i) {
        std::copy_n(aside + std::size_t{order[static_cast<std::size_t>(i)]} * width, width, items + static_cast<std::size_t>(i) * width);
    }
}

// The bits of x (10 of them) spread to every third bit: one axis of a Morton code.
std::uint64_t every_third_bit(std::uint64_t x) {
    x &= 0x3ff;
    x = (x | x << 16) & 0x30000ffULL;
    x = (x | x << 8) & 0x300f00fULL;
    x = (x | x << 4) & 0x30c30c3ULL;
    x = (x | x << 2) & 0x9249249ULL;
    return x;
}

}  // namespace

void Simplifier::renumber(const std::vector<std::uint32_t>& vertex_from, const std::vector<std::uint32_t>& face_from,
                          const std::vector<std::uint32_t>& corner_to) {
    const std::size_t n = pos_.size(), m = face_.size();
    const Attributes &vertex_rows = mesh_.vertex_attributes, &face_rows = mesh_.face_attributes;
    const std::size_t bytes = std::max({n * sizeof(Point3), m * sizeof(Face), n * vertex_rows.width * sizeof(double),
                                        m * face_rows.width * sizeof(double)});
    const auto scratch = std::make_unique_for_overwrite<unsigned char[]>(bytes);
    permute(pos_.data(), n, 1, vertex_from, scratch.get());
    permute(mesh_.vertex_attributes.values.data(), n, vertex_rows.width, vertex_from, scratch.get());
    permute(face_.data(), m, 1, face_from, scratch.get());
    permute(mesh_.face_attributes.values.data(), m, face_rows.width, face_from, scratch.get());
    for (Face& c : face_) {
        for (std::uint32_t& v : c) v = corner_to[v];
    }
}

// The mean difference of a face's corner numbers up to which a mesh's numbering counts as local.
constexpr std::uint64_t kLocalSpread = 4096;

// A vertex's number is where its data lie in memory, and meshes come numbered in any order: in
// the CGAL demo models an edge joins vertices a tenth to a third of the model apart in number
// (their mean). A block's collapses then read and write all over every per-vertex array, which
// for a model of a million faces are far bigger than the caches. Numbered along a Z-order curve
// instead, the vertices of a cube of space mostly have neighbouring numbers, and the faces,
// numbered by their lowest corner, too. Measured on two Loop subdivisions of the CGAL armadillo
// (832 k faces), 2 threads: see BENCHMARKS.md.
void Simplifier::spatial_order() {
    const std::size_t n = pos_.size(), m = face_.size();
    if (n == 0) return;
    // Already local, as a grid read row by row (a face's corners a row apart, and a row's data
    // within the caches up to some thousands of vertices): left as it is. Renumbering costs
    // about 0.1 s on the 2 M terrain and gained nothing there.
    std::uint64_t spread = 0;
    const auto faces = static_cast<std::int64_t>(m);
#pragma omp parallel for schedule(static) reduction(+ : spread)
    for (std::int64_t f = 0; f < faces; ++f) {
        const Face& c = face_[static_cast<std::size_t>(f)];
        spread += std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]});
    }
    if (spread <= kLocalSpread * m) return;
    Box3 box = point_box(pos_[0]);
    for (const Point3& p : pos_) box.add(p);
    // 10 bits per axis (about a vertex per cell at a million vertices; more share a cell, in
    // input order), on one scale for all three: a flat terrain is ordered in its map plane. (An
    // extent that overflows, or NaN, gives every vertex the code 0: the input order.)
    const double extent = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    const double scale = extent > 0 && std::isfinite(extent) ? 0x1p10 / extent : 0.0;
    auto units = [scale](double value, double lo) -> std::uint64_t {
        const double u = (value - lo) * scale;
        if (!(u >= 1)) return 0;  // (NaN too)
        return u >= 0x1p10 - 1 ? 0x3ff : static_cast<std::uint64_t>(u);
    };
    // Code and number in one word, sorted by the code in three stable passes of 10 bits.
    std::vector<std::uint64_t> keyed(n), other(n);
    const auto count = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < count; ++i) {
        const Point3 p = pos_[static_cast<std::size_t>(i)];
        const std::uint64_t code = every_third_bit(units(p.x, box.lo.x)) | every_third_bit(units(p.y, box.lo.y)) << 1 |
                                   every_third_bit(units(p.z, box.lo.z)) << 2;
        keyed[static_cast<std::size_t>(i)] = code << 32 | static_cast<std::uint64_t>(i);
    }
    for (int shift = 32; shift < 62; shift += 10) {
        std::vector<std::size_t> first(1025, 0);
        for (const std::uint64_t k : keyed) ++first[((k >> shift) & 0x3ff) + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());
        for (const std::uint64_t k : keyed) other[first[(k >> shift) & 0x3ff]++] = k;
        keyed.swap(other);
    }
    input_vertex_.resize(n);
    std::vector<std::uint32_t> number(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<std::uint32_t>(keyed[i]);
        input_vertex_[i] = v;
        number[v] = static_cast<std::uint32_t>(i);
    }
    // Faces by their lowest new corner number, in input order among those of one corner (a
    // counting sort).
    std::vector<std::uint32_t> first(n + 1, 0);
    auto lowest = [&](const Face& c) { return std::min({number[c[0]], number[c[1]], number[c[2]]}); };
    for (const Face& c : face_) ++first[lowest(c) + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    input_face_.resize(m);
    for (std::size_t f = 0; f < m; ++f) input_face_[first[lowest(face_[f])]++] = static_cast<std::uint32_t>(f);

    renumber(input_vertex_, input_face_, number);
    // The topology and the quadrics afresh (quicker than moving them, and their old arrays go
    // before the new ones come).
    quadric_.reset();
    build_topology();
    build_quadrics();
}

// The live faces in the order of their numbers in the input, the vertices numbered as in the
// input (drop_unused then keeps that order).
void Simplifier::input_order() {
    if (input_vertex_.empty()) return;
    std::vector<std::uint32_t> order(face_.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [this](std::uint32_t f, std::uint32_t g) { return input_face_[f] < input_face_[g]; });
    std::vector<std::uint32_t> number(input_vertex_.size());  // the inverse: where each input vertex is now
    for (std::size_t i = 0; i < input_vertex_.size(); ++i) number[input_vertex_[i]] = static_cast<std::uint32_t>(i);
    renumber(number, order, input_vertex_);
    input_vertex_.clear();
    input_face_.clear();
}

template <class Visit>
void Simplifier::for_cells(std::uint64_t first, std::uint64_t last, Visit visit) const {
    for (std::uint32_t x = Grid::unpack(first, 0); x <= Grid::unpack(last, 0); ++x) {
        for (std::uint32_t y = Grid::unpack(first, 1); y <= Grid::unpack(last, 1); ++y) {
            for (std::uint32_t z = Grid::unpack(first, 2); z <= Grid::unpack(last, 2); ++z) visit(Grid::pack(x, y, z));
        }
    }
}

// The float next to a finite f, below or above it (std::nextafter, without the library call:
// a neighbouring float is the neighbouring bit pattern of the same sign).
float float_down(float f) {
    if (f == 0) return -std::numeric_limits<float>::denorm_min();
    const auto bits = std::bit_cast<std::uint32_t>(f);
    return std::bit_cast<float>(f > 0 ? bits - 1 : bits + 1);
}
float float_up(float f) { return -float_down(-f); }

// A coordinate in grid units, as a float at most (below) or at least (above) it. The double
// scaling is monotone, so is the rounding: boxes that overlap keep overlapping. The nearest float
// lies within half a spacing of the value, so the float below it is at most the value and the
// float above it at least the value: taken always, without asking on which side of the nearest
// float the value lay (a branch mispredicted half the time; a box one float spacing wider).
float float_below(double value) {
    if (!(value > -std::numeric_limits<float>::max())) return -std::numeric_limits<float>::infinity();
    if (value > std::numeric_limits<float>::max()) return std::numeric_limits<float>::max();
    return float_down(static_cast<float>(value));
}
float float_above(double value) {
    if (!(value < std::numeric_limits<float>::max())) return std::numeric_limits<float>::infinity();
    if (value < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::max();
    return float_up(static_cast<float>(value));
}

UnitBox Simplifier::unit_box(const Box3& box) const {
    UnitBox unit;
    for (int axis = 0; axis < 3; ++axis) {
        unit.lo[axis] = float_below(index_grid_.units(box.lo[axis], axis));
        unit.hi[axis] = float_above(index_grid_.units(box.hi[axis], axis));
    }
    unit.first = index_grid_.cell_key(box.lo);
    unit.last = index_grid_.cell_key(box.hi);
    return unit;
}

// A face's entry in the list of one of its cells.
IndexEntry index_entry(std::uint32_t f, const UnitBox& unit, std::uint64_t key) {
    IndexEntry entry;
    entry.first_here = 0;
    for (int axis = 0; axis < 3; ++axis) {
        entry.lo[axis] = unit.lo[axis];
        entry.hi[axis] = unit.hi[axis];
        entry.first_here = static_cast<std::uint8_t>(entry.first_here | (Grid::unpack(key, axis) == Grid::unpack(unit.first, axis)) << axis);
    }
    entry.face = f;
    return entry;
}

void Simplifier::build_face_index() {
    // Parts of the faces, one per thread (a function of the thread count, but the lists are not).
    const auto parts = static_cast<std::int64_t>(omp_get_max_threads());
    index_.clear(static_cast<std::size_t>(parts));
    if (!use_index_) return;
    const auto m = static_cast<std::int64_t>(face_.size());
    // The index has its own cells, about four times the current mean edge: stars grow as the
    // mesh gets coarser, and a query should span few cells (a cell visited costs two table
    // lookups, more than the dozen extra faces a bigger cell lists: 4 measured ~10 % faster
    // than 2 on the elephant, 1 ~50 % slower). Each face's box is kept as it is now;
    // see query() for why that makes reading other blocks' faces unnecessary.
    index_grid_ = grid_over_faces(4.0, grid_.origin);
    changed_.assign(face_.size(), 0);
    unit_boxes_.resize(face_.size());
    // Each cell lists its faces in face order: part k holds a run of faces.
    auto run_of = [&](std::int64_t k) { return m * k / parts; };
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < parts; ++k) {
        for (std::int64_t f = run_of(k); f < run_of(k + 1); ++f) {
            if (!alive_[f]) continue;
            const UnitBox& unit = unit_boxes_[f] = unit_box(face_box(static_cast<std::uint32_t>(f)));
            for_cells(unit.first, unit.last, [&](std::uint64_t key) { index_.count(static_cast<std::size_t>(k), key); });
        }
    }
    index_.allocate();
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < parts; ++k) {
        for (std::int64_t f = run_of(k); f < run_of(k + 1); ++f) {
            if (!alive_[f]) continue;
            const UnitBox& unit = unit_boxes_[f];
            for_cells(unit.first, unit.last, [&](std::uint64_t key) {
                index_.place(static_cast<std::size_t>(k), key, index_entry(static_cast<std::uint32_t>(f), unit, key));
            });
        }
    }
}

// Faces that may touch `box` (inside the calling block), each once: from the round's index
// those whose box at the start of the round overlaps it — a face another block changes lay, and
// lies, inside that block, so its start box cannot overlap and it is never read — unless this
// block changed them, and the faces this block changed, from its overlay, if their box now
// overlaps it. Boxes are compared rounded outward (a few more faces, never fewer). A face
// spanning several of the box's cells is taken in the first (lowest on every axis) of them.
void Simplifier::query(const Box3& box, const Overlay& overlay,
                       std::vector<std::uint32_t>& out) const {
    out.clear();
    const UnitBox unit = unit_box(box);
    const std::uint64_t box_lo = unit.first;
    const float* unit_lo = unit.lo;
    const float* unit_hi = unit.hi;
    for_cells(unit.first, unit.last, [&](std::uint64_t key) {
        // The first cell a face and the box share is, on each axis, the later of their first
        // ones; the cell visited is in both: it is that one where it is the face's first or the
        // box's on every axis.
        std::uint8_t box_first = 0;
        for (int axis = 0; axis < 3; ++axis) box_first |= static_cast<std::uint8_t>((Grid::unpack(key, axis) == Grid::unpack(box_lo, axis)) << axis);
        // Without branches (a hit is written always, kept or overwritten), as the tests are
        // hard to predict; the index's hits then lose the faces this block changed.
        auto scan = [&](std::span<const IndexEntry> entries, bool from_index) {
            const std::size_t start = out.size();
            out.resize(start + entries.size());
            std::uint32_t* at = out.data() + start;
            for (const IndexEntry& entry : entries) {
                *at = entry.face;
                at += (entry.lo[0] <= unit_hi[0]) & (unit_lo[0] <= entry.hi[0]) & (entry.lo[1] <= unit_hi[1]) &
                      (unit_lo[1] <= entry.hi[1]) & (entry.lo[2] <= unit_hi[2]) & (unit_lo[2] <= entry.hi[2]) &
                      ((entry.first_here | box_first) == 7);
            }
            if (from_index) at = std::remove_if(out.data() + start, at, [this](std::uint32_t f) { return changed_[f] != 0; });
            out.resize(static_cast<std::size_t>(at - out.data()));
        };
        scan(index_.entries(key), true);
        if (const std::vector<IndexEntry>* mine = overlay.find(key)) scan(*mine, false);
    });
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

bool Simplifier::place(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, Placement& out) const {
    const bool locked_a = (flags_[a] & kLocked) != 0, locked_b = (flags_[b] & kLocked) != 0;
    if (locked_a && locked_b) return false;
    const Quadric q = quadric_[a] + quadric_[b];
    if (locked_a || locked_b) {
        out.p = locked_a ? pos_[a] : pos_[b];
        out.cost = q(local(out.p));
        out.bound = false;
        return true;
    }
    // Optimal placement: solve the 3×3 system ∇(vᵀQv) = 0 (v about frame_) by Cramer's rule when it
    // is well conditioned and its solution stays near the edge and inside the block.
    const double m00 = q.xx, m01 = q.xy, m02 = q.xz, m11 = q.yy, m12 = q.yz, m22 = q.zz;
    const double r0 = -q.xw, r1 = -q.yw, r2 = -q.zw;
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11;
    const double det = m00 * c00 + m01 * c01 + m02 * c02;
    const double scale = std::max({std::fabs(m00), std::fabs(m11), std::fabs(m22)});
    const Point3 pa = pos_[a], pb = pos_[b];
    // (Halves first: no overflow; the same double as half the sum otherwise.)
    const Point3 mid{0.5 * pa.x + 0.5 * pb.x, 0.5 * pa.y + 0.5 * pb.y, 0.5 * pa.z + 0.5 * pb.z};
    bool bound = false;
    if (std::fabs(det) > 1e-10 * scale * scale * scale && std::isfinite(det)) {
        const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12, c22 = m00 * m11 - m01 * m01;
        const Point3 p{(c00 * r0 + c01 * r1 + c02 * r2) / det * frame_.unscale + frame_.centre.x,
                       (c01 * r0 + c11 * r1 + c12 * r2) / det * frame_.unscale + frame_.centre.y,
                       (c02 * r0 + c12 * r1 + c22 * r2) / det * frame_.unscale + frame_.centre.z};
        const double reach = norm(minus(pb, pa));  // (infinite if the difference overflows: no limit)
        const bool near = std::fabs(p.x - mid.x) <= reach && std::fabs(p.y - mid.y) <= reach && std::fabs(p.z - mid.z) <= reach;
        if (near && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) {
            if (in_block(p, level, block)) {
                out = {p, q(local(p)), false};
                return true;
            }
            bound = true;
        }
    }
    // Otherwise the best of the two ends and the midpoint.
    out = {pa, q(local(pa)), false};
    const double cost_b = q(local(pb));
    if (cost_b < out.cost) out = {pb, cost_b, false};
    const double cost_mid = q(local(mid));
    if (cost_mid < out.cost) {
        if (in_block(mid, level, block)) {
            out = {mid, cost_mid, false};
        } else {
            bound = true;
        }
    }
    out.bound = bound;
    return true;
}

double Simplifier::error_of(const Placement& placement, std::uint32_t a, std::uint32_t b) const {
    const double area = quadric_[a].area + quadric_[b].area;
    // (In frame units, so back to coordinate units.)
    return area > 0 ? std::sqrt(std::max(placement.cost, 0.0) / area) * frame_.unscale : 0.0;
}

template <class Wanted>
void Simplifier::place_edges(std::uint32_t v, std::span<const std::uint32_t> around, Wanted wanted, int level,
                             std::uint64_t block, std::vector<Candidate>& out) const {
    // The neighbours' quadrics are scattered: start loading them all before the first is needed.
    for (std::uint32_t w : around) {
        __builtin_prefetch(&quadric_[w]);
        __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[w]) + sizeof(Quadric) - 1);
    }
    for (std::uint32_t w : around) {
        if ((flags_[w] & kInside) == 0 || !wanted(w)) continue;
        const std::uint32_t a = std::min(v, w), b = std::max(v, w);
        Placement placement;
        if (!place(a, b, level, block, placement)) continue;
        out.push_back(candidate(a, b, placement));
    }
}

std::vector<Candidate> Simplifier::block_candidates(int level, const std::uint32_t* vertices, std::size_t count,
                                                     std::uint64_t block,
                                                     const std::vector<std::vector<Candidate>*>& before) {
    std::vector<std::uint32_t> scratch, around;
    // Which vertices have their whole star in the block (fixed for the level: a collapse only
    // merges two inside vertices, so no neighbour outside the block appears or disappears). A
    // vertex inside at the level before stays inside: its block holds the one it was in. The
    // neighbours of those newly inside are kept for their edges below: (vertex, first, count).
    std::vector<std::uint32_t> neighbours;
    std::vector<std::array<std::uint32_t, 3>> newly;
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint32_t v = vertices[i];
        if ((flags_[v] & (kDead | kInside)) != 0) continue;
        faces_of(v, scratch);
        bool inside = true;
        for (std::uint32_t f : scratch) {
            for (std::uint32_t w : face_[f]) inside = inside && grid_.block_of(cell_[w], level) == block;
        }
        if (!inside) continue;
        corners_but(scratch, v, around);
        flags_[v] |= kInside | kNewlyInside;
        newly.push_back({v, static_cast<std::uint32_t>(neighbours.size()), static_cast<std::uint32_t>(around.size())});
        neighbours.insert(neighbours.end(), around.begin(), around.end());
    }
    // Edges between vertices inside before: their candidates from the finer blocks, which keep
    // one valid candidate for each (see collapse_block). The placement is the same in the bigger
    // block unless the smaller one held it back.
    std::vector<Candidate> heap;
    for (std::vector<Candidate>* list : before) {
        for (const Candidate& c : *list) {
            if (stale(c)) continue;
            if (!c.bound()) {
                heap.push_back(c);
                continue;
            }
            Placement placement;
            if (place(c.a, c.b, level, block, placement)) heap.push_back(candidate(c.a, c.b, placement));
        }
        std::vector<Candidate>().swap(*list);
    }
    // Edges with a newly inside end: each once.
    for (const auto& [v, first, size] : newly) {
        place_edges(v, std::span(neighbours).subspan(first, size), [&](std::uint32_t w) { return (flags_[w] & kNewlyInside) == 0 || w > v; }, level, block, heap);
    }
    for (std::size_t i = 0; i < count; ++i) flags_[vertices[i]] &= static_cast<std::uint8_t>(~kNewlyInside);
    return heap;
}

BlockResult Simplifier::collapse_block(int level, std::uint64_t block, std::vector<Candidate>& candidates,
                                       std::uint64_t budget, double cost_limit) {
    BlockResult result;
    Overlay overlay;
    std::vector<Candidate> fresh;
    std::vector<std::uint32_t> around;
    // `candidates` keeps every live edge of the block's inside vertices (a collapse adds the
    // edges it changes and stamps make the old ones stale), so a later round of the level starts
    // from them instead of from scratch. Those under the round's cost limit are sorted and taken
    // in order, merged with a small heap of the new edges under the limit: the cheapest (cost, a,
    // b) first, as from one heap, but a candidate gone stale costs a step, not a heap pop. Those
    // refused and those dearer than the limit, which cannot be taken in this round, wait after
    // them; at the end the taken ones are dropped and the heap's rest joins the others.
    auto dear = [cost_limit](const Candidate& c) { return c.cost > cost_limit; };
    const auto cheap = static_cast<std::size_t>(
        std::partition(candidates.begin(), candidates.end(), [&](const Candidate& c) { return !dear(c); }) - candidates.begin());
    // Sorted a part at a time: a block with a small budget among many candidates (the last
    // level's one block) needs the first few only.
    const auto earlier = [](const Candidate& x, const Candidate& y) { return later(y, x); };
    const auto at = [&](std::size_t i) { return candidates.begin() + static_cast<std::ptrdiff_t>(i); };
    std::size_t sorted = 0;  // candidates[0, sorted) are the cheapest, in order
    std::vector<Candidate> heap;
    std::size_t next = 0;  // the first sorted one not taken
    while (result.faces_removed < budget) {
        if (next == sorted && sorted < cheap) {
            const std::uint64_t step = budget >= cheap ? cheap : 4 * budget + 256;  // (a budget may be unlimited)
            const std::size_t until = std::min<std::uint64_t>(cheap, std::max<std::uint64_t>(2 * sorted, sorted + step));
            if (until < cheap) std::nth_element(at(sorted), at(until), at(cheap), earlier);
            std::sort(at(sorted), at(until), earlier);
            sorted = until;
        }
        Candidate c;
        if (next < sorted && (heap.empty() || !later(candidates[next], heap.front()))) {
            c = candidates[next++];
        } else if (!heap.empty()) {
            std::pop_heap(heap.begin(), heap.end(), later);
            c = heap.back();
            heap.pop_back();
        } else {
            break;
        }
        // The sorted ones come in cost order, their vertices anywhere in the block: start loading
        // what the next one needs while this one is done.
        if (next + 4 < sorted) {
            __builtin_prefetch(&stamp_[candidates[next + 4].a]);
            __builtin_prefetch(&stamp_[candidates[next + 4].b]);
        }
        if (next < sorted) {
            for (const std::uint32_t v : {candidates[next].a, candidates[next].b}) {
                __builtin_prefetch(&head_[v]);
                __builtin_prefetch(&pos_[v]);
                __builtin_prefetch(&quadric_[v]);
                __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[v]) + sizeof(Quadric) - 1);
            }
        }
        if (stale(c)) continue;
        if (vertical_ && c.refused_touches == touches(c)) {
            candidates.push_back(c);
            continue;
        }
        if (!try_collapse(c.a, c.b, level, block, result, around, overlay)) {
            if (vertical_) c.refused_touches = touches(c);
            candidates.push_back(c);
            continue;
        }
        fresh.clear();
        place_edges(c.a, around, [](std::uint32_t) { return true; }, level, block, fresh);
        for (const Candidate& e : fresh) {
            if (dear(e)) {
                candidates.push_back(e);
            } else {
                heap.push_back(e);
                std::push_heap(heap.begin(), heap.end(), later);
            }
        }
    }
    candidates.erase(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(next));
    candidates.insert(candidates.end(), heap.begin(), heap.end());
    return result;
}

void Simplifier::reopen(std::vector<Candidate>& candidates) const {
    std::erase_if(candidates, [this](const Candidate& c) { return stale(c); });
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
bool Simplifier::flat_and_clean(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& fa,
                                const std::vector<std::uint32_t>& fb, const std::vector<std::uint32_t>& star, Point3 p,
                                const std::vector<exact::Triangle3>& fresh, Overlay& overlay, exact::PredicateStats& predicates) {
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
            const Face& c = face_[f];
            const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
            next_corner.push_back(c[(k + 1) % 3]);
            previous_corner.push_back(c[(k + 2) % 3]);
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
    for (const exact::Triangle3& t : fresh) {
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

bool Simplifier::meets_another(std::uint32_t f, const Overlay& overlay, exact::PredicateStats& predicates) const {
    thread_local std::vector<std::uint32_t> found;
    const exact::Triangle3 t = triangle(face_[f]);
    if (exact::degenerate(t, predicates)) return true;
    const Box3 box = triangle_box(t[0], t[1], t[2]);
    query(box, overlay, found);
    for (std::uint32_t g : found) {
        if (g == f || !alive_[g]) continue;
        const exact::Triangle3 u = triangle(face_[g]);
        if (box.overlaps(triangle_box(u[0], u[1], u[2])) && exact::faces_conflict(t, u, predicates)) return true;
    }
    return false;
}

bool Simplifier::try_collapse(std::uint32_t a, std::uint32_t b, int level, std::uint64_t block, BlockResult& result,
                              std::vector<std::uint32_t>& around,
                              Overlay& overlay) {
    MeshStats& stats = result.stats;
    Placement placement;
    if (!place(a, b, level, block, placement)) {
        ++stats.refused_boundary;
        return false;
    }
    const double error = error_of(placement, a, b);
    if (options_.target == MeshTarget::max_error && !vertical_ && !(error <= options_.value)) return false;  // (NaN: refused)
    thread_local std::vector<std::uint32_t> fa, fb, shared, opposite, star, found;
    faces_of(a, fa, b, fb);
    for (const auto* faces : {&fa, &fb}) {
        for (std::uint32_t f : *faces) {
            for (std::uint32_t w : face_[f]) __builtin_prefetch(&pos_[w]);  // read for the star below
        }
    }
    // a's list now holds the corners of fa, in order: b's are appended after the last.
    std::uint32_t last_of_a = kNone;
    if (!fa.empty()) {
        const Face& last = face_[fa.back()];
        last_of_a = 3 * fa.back() + (last[0] == a ? 0 : last[1] == a ? 1 : 2);
    }
    shared.clear();
    for (std::uint32_t f : fa) {
        const Face& c = face_[f];
        if (c[0] == b || c[1] == b || c[2] == b) shared.push_back(f);
    }
    if (shared.empty()) return false;  // no longer an edge
    // Link condition (Dey et al. 1999): the common neighbours of a and b are exactly the corners
    // opposite the edge, each once; a border vertex pair joined through the interior would pinch.
    // The opposite corners are common neighbours, so it is enough that they are distinct and that
    // a and b have no other: the corners of a's faces are marked, those of b's faces found marked
    // are counted once each (a, b and the common neighbours), and the marks cleared.
    opposite.clear();
    for (std::uint32_t f : shared) {
        for (std::uint32_t w : face_[f]) {
            if (w != a && w != b) opposite.push_back(w);
        }
    }
    std::sort(opposite.begin(), opposite.end());
    bool linked = std::adjacent_find(opposite.begin(), opposite.end()) == opposite.end();
    if (linked) {
        for (std::uint32_t f : fa) {
            for (std::uint32_t w : face_[f]) flags_[w] |= kMarked;
        }
        std::size_t common = 0;
        for (std::uint32_t f : fb) {
            for (std::uint32_t w : face_[f]) {
                if ((flags_[w] & (kMarked | kCounted)) == kMarked) {
                    flags_[w] |= kCounted;
                    ++common;
                }
            }
        }
        for (std::uint32_t f : fa) {
            for (std::uint32_t w : face_[f]) flags_[w] &= static_cast<std::uint8_t>(~(kMarked | kCounted));
        }
        linked = common == opposite.size() + 2;
    }
    if (!linked) {
        ++stats.refused_link;
        return false;
    }
    const bool border_edge = shared.size() == 1;
    if ((flags_[a] & kBoundary) && (flags_[b] & kBoundary) && !border_edge) {
        ++stats.refused_boundary;
        return false;
    }
    // star: every face that changes (has a or b but not both).
    star.clear();
    for (std::uint32_t f : fa) {
        if (std::find(shared.begin(), shared.end(), f) == shared.end()) star.push_back(f);
    }
    const std::size_t from_a = star.size();
    for (std::uint32_t f : fb) {
        if (std::find(shared.begin(), shared.end(), f) == shared.end()) star.push_back(f);
    }
    if (star.empty()) {
        ++stats.refused_link;  // the component would vanish
        return false;
    }
    exact::PredicateStats& predicates = stats.predicates;
    thread_local std::vector<exact::Triangle3> fresh, fan;
    fresh.clear();
    fan.clear();
    Box3 reach = point_box(placement.p);
    for (std::size_t i = 0; i < star.size(); ++i) {
        const Face& c = face_[star[i]];
        exact::Triangle3 before = triangle(c), after = before;
        for (int k = 0; k < 3; ++k) {
            if (c[k] == a || c[k] == b) after[k] = placement.p;
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
        if (i >= from_a && opposite.size() == 2) {
            // A face (b, x, y) becomes (a, x, y): refuse if a already has a face on x and y. Then x
            // and y are common neighbours of a and b: by the link test, the two opposite corners.
            std::uint32_t x = kNone, y = kNone;
            for (std::uint32_t w : c) {
                if (w != b) (x == kNone ? x : y) = w;
            }
            const bool both_opposite = std::min(x, y) == opposite[0] && std::max(x, y) == opposite[1];
            for (std::size_t k = 0; both_opposite && k < fa.size(); ++k) {
                const Face& d = face_[fa[k]];
                const bool has_x = d[0] == x || d[1] == x || d[2] == x, has_y = d[0] == y || d[1] == y || d[2] == y;
                if (has_x && has_y) {
                    ++stats.refused_degenerate;
                    return false;
                }
            }
        }
        for (const Point3& corner : after) reach.add(corner);
        fresh.push_back(after);
        if (vertical_) {
            const int k = c[0] == a || c[0] == b ? 0 : c[1] == a || c[1] == b ? 1 : 2;
            fan.push_back({after[k], after[(k + 1) % 3], after[(k + 2) % 3]});
        }
    }
    thread_local std::vector<std::uint32_t> replaced;  // (under a vertical bound) the faces the collapse replaces
    if (vertical_) {
        replaced.assign(star.begin(), star.end());
        replaced.insert(replaced.end(), shared.begin(), shared.end());
        if (!vertical_->holds(fan, replaced, predicates)) {
            ++stats.refused_vertical;
            return false;
        }
    }
    // Contacts. In a terrain with a locked border the planar argument suffices; a collapse that
    // moves a border vertex of a terrain is checked in the map plane (faces flattened to z = 0).
    const bool moves_border = ((flags_[a] | flags_[b]) & kBoundary) != 0 && !lock_;
    const bool flatten = terrain_ && moves_border;
    const bool interior = ((flags_[a] | flags_[b]) & kBoundary) == 0 && shared.size() == 2;
    bool twin_after = false;  // (3D) another vertex is at p
    if (!terrain_ && interior && options_.flat_shortcut && flat_and_clean(a, b, fa, fb, star, placement.p, fresh, overlay, predicates)) {
        ++stats.flat_unsearched;
    } else if (!terrain_ || flatten) {
        auto flat = [&](exact::Triangle3 t) {
            if (flatten) {
                for (Point3& p : t) p.z = 0;
            }
            return t;
        };
        Box3 box = reach;
        if (flatten) {
            box.lo.z = grid_.origin.z;
            box.hi.z = std::numeric_limits<double>::infinity();
        }
        query(box, overlay, found);
        std::sort(fa.begin(), fa.end());
        std::sort(fb.begin(), fb.end());
        // The faces near the star. The side of a nearby corner with respect to a new face's
        // plane is remembered (a small direct-mapped cache by vertex, one generation per new
        // face), so a corner shared by several nearby faces is decided once: in flat regions
        // those are exact zeros, the dear case.
        thread_local std::vector<std::uint32_t> near;
        struct SideEntry {
            std::uint32_t vertex = kNone;
            int side = 0;
            std::uint64_t generation = 0;  // 64 bits: never wraps
        };
        thread_local std::array<SideEntry, 512> sides{};
        thread_local std::uint64_t generation = 0;
        thread_local std::vector<exact::Triangle3> near_triangle;
        thread_local std::vector<Box3> near_box;
        near.clear();
        near_triangle.clear();
        near_box.clear();
        // The found faces and their corners lie anywhere in memory: load them all before reading.
        for (std::uint32_t g : found) __builtin_prefetch(&face_[g]);
        for (std::uint32_t g : found) {
            for (std::uint32_t w : face_[g]) __builtin_prefetch(&pos_[w]);
        }
        for (std::uint32_t g : found) {
            if (alive_[g] && !std::binary_search(fa.begin(), fa.end(), g) && !std::binary_search(fb.begin(), fb.end(), g)) {
                near.push_back(g);
                near_triangle.push_back(flat(triangle(face_[g])));
                const exact::Triangle3& t = near_triangle.back();
                near_box.push_back(triangle_box(t[0], t[1], t[2]));
            }
        }
        // Each new face against the nearby faces and the new faces after it. A face whose corners
        // lie strictly on one side of the new face's plane, but for those at a corner of the new
        // face, meets it at most in those corners: apart (this decides most pairs, the corners
        // shared with the new face included). All corners in the plane and none shared: the
        // coplanar test, where any contact is a conflict. Otherwise the general test.
        enum class Verdict { apart, coplanar, unknown };
        // The new faces against one another: at once if they form a simple fan around p.
        const bool simple_fan = !flatten && fan_is_simple(a, b, star, placement.p, predicates);
        for (std::size_t i = 0; i < fresh.size(); ++i) {
            const exact::Triangle3 mine = flat(fresh[i]);
            const Box3 mine_box = triangle_box(mine[0], mine[1], mine[2]);
            std::array<std::uint32_t, 3> mine_ids = face_[star[i]];
            for (std::uint32_t& v : mine_ids) v = v == b ? a : v;
            ++generation;
            // The sides of the other face's corners (`side`, for faces_conflict) and what they
            // settle.
            auto verdict = [&](const std::array<std::uint32_t, 3>& ids, const exact::Triangle3& other, std::array<int, 3>& side) {
                int sign = 0;
                bool on_corner = false, unshared_in_plane = false, both_sides = false;
                for (int k = 0; k < 3; ++k) {
                    // At a corner of the new face: the same vertex, or one with twin_ set (a
                    // vertex at x's location has it, and so has x), or one at p (not yet marked).
                    const std::uint32_t v = ids[k];
                    bool here = (v == mine_ids[0]) | (v == mine_ids[1]) | (v == mine_ids[2]);
                    if (!here && (twin_[v] || same_location(other[k], placement.p))) {
                        here = same_location(other[k], mine[0]) || same_location(other[k], mine[1]) || same_location(other[k], mine[2]);
                    }
                    if (here) {
                        on_corner = true;  // in the plane, no predicate needed
                        side[k] = 0;
                        continue;
                    }
                    SideEntry& entry = sides[v % sides.size()];
                    if (entry.vertex != v || entry.generation != generation) {
                        entry = {v, exact::orient3d(mine[0], mine[1], mine[2], other[k], predicates), generation};
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
            // The nearby faces whose box meets the new face's, listed without branches (about
            // half do: a branch would be mispredicted often).
            thread_local std::vector<std::uint32_t> meeting;
            meeting.resize(near.size());
            std::size_t meets = 0;
            for (std::size_t n = 0; n < near.size(); ++n) {
                const Box3& other = near_box[n];
                meeting[meets] = static_cast<std::uint32_t>(n);
                meets += (mine_box.lo.x <= other.hi.x) & (other.lo.x <= mine_box.hi.x) & (mine_box.lo.y <= other.hi.y) &
                         (other.lo.y <= mine_box.hi.y) & (mine_box.lo.z <= other.hi.z) & (other.lo.z <= mine_box.hi.z);
            }
            for (std::size_t k = 0; k < meets; ++k) {
                const std::size_t n = meeting[k];
                if (conflict(face_[near[n]], near_triangle[n])) {
                    ++stats.refused_intersection;
                    return false;
                }
            }
            for (std::size_t j = i + 1; j < fresh.size() && !simple_fan; ++j) {
                const exact::Triangle3 other = flat(fresh[j]);
                if (!mine_box.overlaps(triangle_box(other[0], other[1], other[2]))) continue;
                std::array<std::uint32_t, 3> ids = face_[star[j]];
                for (std::uint32_t& v : ids) v = v == b ? a : v;
                if (conflict(ids, other)) {
                    ++stats.refused_intersection;
                    return false;
                }
            }
        }
        // A vertex at p is a corner of a face holding p: found (a corner of the star there
        // would have made a new face degenerate). It lies in this block, like p.
        if (!terrain_) {
            for (std::uint32_t g : near) {
                for (std::uint32_t w : face_[g]) {
                    if (same_location(pos_[w], placement.p)) {
                        twin_[w] = 1;
                        twin_after = true;
                    }
                }
            }
        }
    }
    // Apply: b merges into a at the placement. First the faces that change leave the overlay
    // cells of their old boxes, if they are there.
    if (use_index_) {
        for (const auto* faces : {&shared, &star}) {
            for (std::uint32_t f : *faces) {
                if (!changed_[f]) continue;
                for_cells(face_box(f), [&](std::uint64_t key) {
                    std::vector<IndexEntry>& list = *overlay.find(key);
                    auto it = std::find_if(list.begin(), list.end(), [f](const IndexEntry& e) { return e.face == f; });
                    *it = list.back();
                    list.pop_back();
                });
            }
        }
    }
    for (std::uint32_t f : shared) alive_[f] = 0;
    std::uint32_t* tail = &next_[last_of_a];
    for (std::uint32_t c = head_[b]; c != kNone; c = next_[c]) {
        if (alive_[c / 3]) face_[c / 3][c % 3] = a;
    }
    *tail = head_[b];
    head_[b] = kNone;
    blend_attributes(a, b, placement.p);
    pos_[a] = placement.p;
    cell_[a] = grid_.cell_key(placement.p);
    quadric_[a] += quadric_[b];
    flags_[a] = static_cast<std::uint8_t>(flags_[a] | (flags_[b] & (kBoundary | kLocked)));
    flags_[b] = static_cast<std::uint8_t>(flags_[b] | kDead);
    stamp_[a] = (stamp_[a] + 1) & kStampMask;
    stamp_[b] = (stamp_[b] + 1) & kStampMask;
    for (std::uint32_t f : star) clean_[f] = kClean;
    if (!terrain_) twin_[a] = twin_after;
    if (use_index_) {
        for (std::uint32_t f : shared) changed_[f] = 1;
        for (std::uint32_t f : star) {
            changed_[f] = 1;
            const UnitBox unit = unit_box(face_box(f));
            for_cells(unit.first, unit.last, [&](std::uint64_t key) { overlay[key].push_back(index_entry(f, unit, key)); });
        }
    }
    corners_but(star, a, around);  // a's faces now: the star
    if (vertical_) {
        vertical_->collapsed(replaced, star);
        ++touch_[a];
        for (std::uint32_t w : around) ++touch_[w];
    }
    ++stats.collapses;
    stats.max_error = std::max(stats.max_error, error);
    result.faces_removed += shared.size();
    return true;
}

MeshStats Simplifier::run() {
    const auto start = Clock::now();
    MeshStats stats;
    // Each kept face's number in the input, if drop_unused drops some (for messages).
    std::vector<std::uint32_t> input_face;
    if (count_repeated_corner_faces(mesh_) > 0) {
        for (std::uint32_t f = 0; f < face_.size(); ++f) {
            const Face& c = face_[f];
            if (c[0] != c[1] && c[1] != c[2] && c[0] != c[2]) input_face.push_back(f);
        }
    }
    std::vector<std::uint32_t> input_vertex;  // likewise for vertices
    drop_unused(mesh_, &input_vertex);
    stats.vertices_in = pos_.size();
    stats.faces_in = face_.size();
    int threads = options_.threads > 0 ? options_.threads : omp_get_max_threads();
    if (face_.size() < options_.parallel_threshold) threads = 1;
    stats.threads = threads;
    std::uint64_t target = 0;
    if (options_.target == MeshTarget::keep_fraction) {
        target = static_cast<std::uint64_t>(std::llround(options_.value * static_cast<double>(face_.size())));
    } else if (options_.target == MeshTarget::keep_faces) {
        target = static_cast<std::uint64_t>(std::max(0.0, options_.value));
    }
    stats.target_faces = target;
    const int saved_threads = omp_get_max_threads();
    omp_set_num_threads(threads);
    build_topology();
    build_quadrics();
    if (non_manifold_) {
        NonManifoldEdge& edge = *non_manifold_;
        if (!input_vertex.empty()) edge.a = input_vertex[edge.a], edge.b = input_vertex[edge.b];
        if (!input_face.empty()) {
            for (std::uint32_t& f : edge.faces) f = input_face[f];
        }
        stats.non_manifold = std::move(non_manifold_);
        omp_set_num_threads(saved_threads);
        return stats;
    }
    check_terrain();
    spatial_order();
    if (terrain_ && options_.target == MeshTarget::max_error && std::isfinite(options_.value)) {
        vertical_ = std::make_unique<VerticalBound>(mesh_, options_.value);
    }
    lock_ = options_.lock_boundary || vertical_;
    stats.terrain = terrain_;
    if (plan_overlap_) {
        stats.plan_overlap = plan_overlap_;
        if (!input_face.empty()) {
            for (std::uint32_t& f : *stats.plan_overlap) f = input_face[f];
        }
    }
    stats.vertical_bound = vertical_ != nullptr;
    if (vertical_) touch_.assign(pos_.size(), 0);
    add_border_planes();
    choose_grid();
    if (!terrain_) find_twins();
    use_index_ = !terrain_ || !lock_;
    stats.seconds_setup = std::chrono::duration<double>(Clock::now() - start).count();
    const auto sweep = Clock::now();

    const bool by_count = options_.target != MeshTarget::max_error;
    struct Block {
        std::uint64_t key;
        std::size_t first, count;
        std::uint64_t budget;
    };
    // A level's blocks with their candidates, handed down to the next level's blocks.
    std::vector<Block> blocks, finer;
    std::vector<std::vector<Candidate>> candidates;
    std::vector<std::uint32_t> live(pos_.size());  // the live vertices, in id order
    std::iota(live.begin(), live.end(), 0u);
    const int top = grid_.top_level();
    for (int level = 0; level <= top; ++level) {
        if (by_count && live_faces_ <= target) break;
        ++stats.levels;
        // The live vertices grouped by block, blocks in key order, each block's in id order: a
        // counting sort over the level's blocks, numbered densely in key order (x, then y, then z).
        const std::uint64_t last = grid_.block_of(Grid::pack(grid_.cells[0] - 1, grid_.cells[1] - 1, grid_.cells[2] - 1), level);
        std::size_t span[3];
        for (int axis = 0; axis < 3; ++axis) span[axis] = std::size_t{Grid::unpack(last, axis)} + 1;
        auto dense = [&](std::uint64_t cell) {
            const std::uint64_t key = grid_.block_of(cell, level);
            return (Grid::unpack(key, 0) * span[1] + Grid::unpack(key, 1)) * span[2] + Grid::unpack(key, 2);
        };
        // After a level's collapses a vertex's corners lie far apart (a merge appends the other
        // end's): walking them would miss the cache at every step. (Measured: compacting at every
        // round, not only every level, saves nothing more.)
        if (level > 0) compact_faces();
        std::erase_if(live, [this](std::uint32_t v) { return (flags_[v] & kDead) != 0; });
        std::vector<std::size_t> first(span[0] * span[1] * span[2] + 1, 0);
        for (const std::uint32_t v : live) ++first[dense(cell_[v]) + 1];
        std::partial_sum(first.begin(), first.end(), first.begin());
        std::vector<std::uint32_t> vertices(first.back());
        finer.swap(blocks);
        blocks.clear();
        for (std::size_t id = 0; id + 1 < first.size(); ++id) {
            if (first[id + 1] == first[id]) continue;
            const std::size_t z = id % span[2], y = id / span[2] % span[1], x = id / span[2] / span[1];
            blocks.push_back({Grid::pack(x, y, z), first[id], first[id + 1] - first[id], 0});
        }
        for (const std::uint32_t v : live) vertices[first[dense(cell_[v])]++] = v;
        // Rounds. Every block builds its heap; with a count target (below the last level) a
        // global cost threshold is the cost of the k-th cheapest candidate of all blocks, k the
        // collapses still needed, and each block gets a share of the faces still to go in
        // proportion to its candidates under the threshold: no block is pushed into dear
        // collapses while cheap ones wait elsewhere. Rounds repeat while they make progress.
        const auto block_count = static_cast<std::int64_t>(blocks.size());
        // Each block of the level before lies in one block of this level.
        std::vector<std::vector<std::vector<Candidate>*>> before(blocks.size());
        for (std::size_t j = 0; j < finer.size(); ++j) {
            const std::uint64_t key = finer[j].key;
            const std::uint64_t parent = Grid::pack(Grid::unpack(key, 0) >> 1, Grid::unpack(key, 1) >> 1, Grid::unpack(key, 2) >> 1);
            const auto it = std::lower_bound(blocks.begin(), blocks.end(), parent,
                                             [](const Block& block, std::uint64_t k) { return block.key < k; });
            if (it == blocks.end() || it->key != parent) continue;  // (no live vertex left there)
            auto& lists = before[static_cast<std::size_t>(it - blocks.begin())];
            lists.push_back(&candidates[j]);
        }
        std::vector<std::vector<Candidate>> next_candidates(blocks.size());
        for (int round = 0; round < 3; ++round) {
            if (by_count && live_faces_ <= target) break;
            // The index and its start-of-round boxes are what query() relies on: faces a block
            // moved in an earlier round must be indexed where they are now.
            build_face_index();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
            for (std::int64_t i = 0; i < block_count; ++i) {
                const Block& block = blocks[static_cast<std::size_t>(i)];
                const auto k = static_cast<std::size_t>(i);
                if (round == 0) {
                    next_candidates[k] = block_candidates(level, vertices.data() + block.first, block.count, block.key, before[k]);
                } else {
                    reopen(candidates[k]);
                }
            }
            if (round == 0) {
                candidates.swap(next_candidates);
            }

            const std::uint64_t left = by_count ? live_faces_ - target : std::numeric_limits<std::uint64_t>::max();
            double limit = std::numeric_limits<double>::infinity();
            if (by_count && level < top) {
                std::size_t total = 0;
                for (const auto& list : candidates) total += list.size();
                const std::size_t needed = static_cast<std::size_t>((left + 1) / 2);  // a collapse removes ~2 faces
                std::vector<std::uint64_t> share(blocks.size(), 0);  // candidates at most the limit
                if (needed > 0 && needed < total) {
                    limit = kth_smallest_cost(candidates, needed, threads, share);
                } else {
                    for (std::size_t k = 0; k < blocks.size(); ++k) share[k] = candidates[k].size();
                }
                std::uint64_t under = 0;
                for (std::uint64_t n : share) under += n;
                for (std::size_t i = 0; i < blocks.size(); ++i) {
                    blocks[i].budget = under == 0 ? 0
                                                  : static_cast<std::uint64_t>(static_cast<long double>(left) * share[i] /
                                                                               static_cast<long double>(under));
                }
            } else {
                for (Block& block : blocks) block.budget = left;
            }

            std::vector<BlockResult> results(blocks.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
            for (std::int64_t i = 0; i < block_count; ++i) {
                const auto k = static_cast<std::size_t>(i);
                results[k] = collapse_block(level, blocks[k].key, candidates[k], blocks[k].budget, limit);
            }

            std::uint64_t removed = 0;
            for (const BlockResult& r : results) {
                const MeshStats& s = r.stats;
                stats.collapses += s.collapses;
                stats.refused_link += s.refused_link;
                stats.refused_boundary += s.refused_boundary;
                stats.refused_flip += s.refused_flip;
                stats.refused_degenerate += s.refused_degenerate;
                stats.refused_intersection += s.refused_intersection;
                stats.refused_vertical += s.refused_vertical;
                stats.flat_unsearched += s.flat_unsearched;
                stats.max_error = std::max(stats.max_error, s.max_error);
                stats.predicates += s.predicates;
                removed += r.faces_removed;
            }
            live_faces_ -= removed;
            ++stats.rounds;
            if (options_.progress) {
                const double work = by_count ? static_cast<double>(stats.faces_in - std::min(target, stats.faces_in)) : top + 1.0;
                const double done = by_count ? static_cast<double>(stats.faces_in - live_faces_) : level + 1.0;
                options_.progress(work > 0 ? std::min(1.0, done / work) : 1.0);
            }
            // Unlimited rounds do all they can at once; limited ones stop when they stall.
            if (!std::isfinite(limit) || removed * 8 < left) break;
        }
    }
    omp_set_num_threads(saved_threads);
    stats.target_reached = by_count ? live_faces_ <= target : true;

    // Compact: surviving faces and vertices in input order.
    drop_dead_faces(nullptr);
    input_order();
    drop_unused(mesh_);

    stats.vertices_out = pos_.size();
    stats.faces_out = face_.size();
    stats.seconds_collapse = std::chrono::duration<double>(Clock::now() - sweep).count();
    return stats;
}

}  // namespace

MeshStats simplify_mesh(Mesh& mesh, const MeshOptions& options) {
    // The readers promise these; a library caller may not: refuse rather than read out of range.
    const std::size_t n = mesh.points.size();
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        for (const std::uint32_t v : mesh.faces[f]) {
            if (v >= n) {
                throw std::invalid_argument("simplify_mesh: face " + std::to_string(f) + " has corner " + std::to_string(v) +
                                            ", beyond the " + std::to_string(n) + " vertices");
            }
        }
    }
    auto check = [](const Attributes& attributes, std::size_t rows, const char* what) {
        if (attributes.values.size() != rows * attributes.width) {
            throw std::invalid_argument(std::string("simplify_mesh: ") + what + " attributes hold " +
                                        std::to_string(attributes.values.size()) + " values, not " + std::to_string(rows) +
                                        " rows of " + std::to_string(attributes.width));
        }
    };
    check(mesh.vertex_attributes, n, "vertex");
    check(mesh.face_attributes, mesh.faces.size(), "face");
    return Simplifier(mesh, options).run();
}

}  // namespace toposimp::mesh
