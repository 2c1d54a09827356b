// Polygon layers as a coverage: rings are split into arcs at the nodes where the set of rings
// sharing a boundary changes, so a border shared by two polygons is one arc (one chain for the
// simplifier), simplified once, and both polygons get exactly the same vertices back.
//
// A location is a node when several ring vertices sit on it and their neighbour pairs differ
// (TopoJSON's junction rule), decided with exact coordinate equality. A ring without a node is
// one closed arc. Consecutive duplicate vertices in a ring are dropped first (they carry no
// shape). A ring with fewer than three distinct locations or zero area (exactly) is not split
// or simplified: it becomes a frozen chain, an obstacle for the others, and comes back as it was.
#pragma once

#include "core/map/map_data.hpp"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <span>
#include <unordered_map>
#include <vector>

namespace toposimp::map {

// Rings held elsewhere (a file): calls visit(ring) for every ring in order, each as add_ring
// would be given it. Called once for each pass over them.
using RingSource = std::function<void(const std::function<void(std::span<const Point>)>& visit)>;

// What a ring point carries besides its location (its Z and M, as bits), for rings that are
// written again from their own points: the map's vertex at a location has the bits of the ring
// that made its arc, so a ring's own point may stand in for it only where every ring at that
// location carries the same.
struct PointTag {
    std::uint64_t z = 0, m = 0;
    friend bool operator==(const PointTag&, const PointTag&) = default;
};
// Rings with their points' tags (as many as points).
using TaggedRingSource =
    std::function<void(const std::function<void(std::span<const Point>, std::span<const PointTag>)>& visit)>;

struct CoverageSlice;

class Coverage {
public:
    // Adds a ring (the closing vertex may be there or not); returns its id. Points are copied.
    std::uint32_t add_ring(std::span<const Point> ring);

    // Splits every ring into arcs and appends one chain per distinct arc to `map` (frozen chains
    // for degenerate rings). Call once, after the last add_ring.
    void build(MapData& map);

    // The same chains as build() would append for the rings `rings` streams, planned without
    // holding the rings: each chain is appended as its vertex range only (the vertex ids as
    // build() gives them, from one past the map's last chain's last vertex; map.vertices is not
    // touched), frozen chains marked. The first pass counts the ring points by a hash of their
    // location; the nodes are then found in passes over the rings, each holding at most
    // `pass_bytes` of them (56 bytes a ring point; at least a 4096th of the hash's range, all the
    // occurrences of its locations); then one more pass cuts the arcs.
    // Throws std::invalid_argument if a pass streams other rings than the first did. Instead
    // of add_ring and build; ring_vertices and ring_arcs answer as after build(); source_of does not.
    void plan(const RingSource& rings, MapData& map, std::size_t pass_bytes);
    // The same, the rings' points tagged (72 bytes a ring point in the passes that find the
    // nodes, where the tags of each location's clean occurrences are compared). Where they differ,
    // the tag of each arc vertex there (that of the ring that made the arc, as build() takes a
    // vertex's point and source from it) is noted: arc_tag(). Closing points and consecutive
    // duplicates, which make no vertex, and degenerate rings, which make their own chains, are
    // not compared. Memory: a bit a clean occurrence (where tags differ) while the arcs are cut,
    // and 20 bytes an arc vertex where they do.
    void plan(const TaggedRingSource& rings, MapData& map, std::size_t pass_bytes);
    // plan() with tags: arc vertex v's tag where the rings at its location differ (nullptr
    // elsewhere: there every ring's own point carries the arc vertex's tag).
    const PointTag* arc_tag(std::uint32_t v) const {
        const auto found = std::lower_bound(arc_tag_vertices_.begin(), arc_tag_vertices_.end(), v);
        return found == arc_tag_vertices_.end() || *found != v ? nullptr : &arc_tags_[static_cast<std::size_t>(found - arc_tag_vertices_.begin())];
    }
    std::uint64_t tag_conflicts() const { return tag_conflicts_; }  // locations where tags differ

    // What the rings [first_ring, end_ring) need to make, on their own, the chains they are the
    // first to use (arcs_of).
    CoverageSlice slice(std::uint32_t first_ring, std::uint32_t end_ring) const;

    // The ring rebuilt from its arcs' kept vertices, as map vertex ids, closed (last = first).
    // Starts at the ring's first input vertex if it was kept (`arc_order` false), or where its
    // first arc starts (true: as a TopoJSON reader rebuilds it from the arcs).
    std::vector<std::uint32_t> ring_vertices(std::uint32_t ring, const std::vector<std::uint8_t>& kept, bool arc_order = false) const;

    // The same ring's points, taken from `given` (the ring as plan's source streamed it) instead
    // of the map's vertices: ring_vertices' vertices' points, bit for bit (equal locations differ
    // at most in the sign of a zero, and a zero gets the sign the arc's vertex has: plan() notes
    // the -0.0s of the rings that make the arcs). For rings read again when they are written, the
    // map's vertices being elsewhere. Throws std::invalid_argument if `given` is not that ring.
    // (After build() too: the signs are then the map's vertices'.) Each point comes with where it
    // is in `given` (the closing point: the first's) and the map vertex it stands for: its tag is
    // arc_tag(vertex) if there is one, else the ring's own at `position`.
    struct RingPoint {
        Point point;
        std::uint32_t position;
        std::uint32_t vertex;
    };
    std::vector<RingPoint> ring_points_from(std::uint32_t ring, std::span<const Point> given, const std::vector<std::uint8_t>& kept,
                                            bool arc_order = false) const;

    // The map's first chain made by the rings from `ring` on (`ring` = ring_count(): one past the
    // coverage's last chain).
    std::uint32_t chains_before(std::uint32_t ring) const { return first_chain_ + new_chains_before_[ring]; }

    // A ring's arcs in order: the chain (its index in the map) and whether it runs backwards.
    struct ArcUse {
        std::uint32_t chain;
        bool reversed;
    };
    std::span<const ArcUse> ring_arcs(std::uint32_t ring) const {
        return {uses_.data() + uses_start_[ring], uses_.data() + uses_start_[ring + 1]};
    }

    // For map vertex v created by build(): the index of the input ring point it came from (in
    // add_ring order, counting every point given, closing vertex included), for Z/M and the like.
    std::uint32_t source_of(std::uint32_t v) const { return source_[v - first_vertex_]; }

    std::uint32_t ring_count() const { return static_cast<std::uint32_t>(ring_start_.size()); }
    // Ring points given (every one, closing vertices included).
    std::uint32_t point_count() const { return ring_start_.empty() ? 0 : ring_start_.back() + ring_size_.back(); }
    std::uint64_t arc_count() const { return arcs_; }
    std::uint64_t shared_arc_count() const { return shared_arcs_; }
    std::uint64_t degenerate_ring_count() const { return degenerate_rings_; }

private:
    template <bool kTagged>
    void plan_rings(const TaggedRingSource& rings, MapData& map, std::size_t pass_bytes);
    std::vector<std::uint32_t> arc_order_vertices(std::uint32_t ring) const;
    // plan(): the -0.0 coordinates of a chain made from `positions` of `ring`; p with the signs of
    // vertex v's zeros.
    void note_negative_zeros(std::span<const Point> ring, std::span<const std::uint32_t> positions, std::uint32_t first_vertex);
    Point owner_zeros(std::uint32_t v, Point p) const;

    std::vector<Point> points_;               // every ring point as given, until build()
    std::vector<std::uint32_t> ring_start_;   // into points_
    std::vector<std::uint32_t> ring_size_;
    std::vector<std::uint32_t> uses_start_;   // per ring, into uses_ (one past the end: next ring's)
    std::vector<ArcUse> uses_;
    std::vector<std::uint32_t> start_offset_; // per ring: where its first input point is in ring order
    std::vector<std::uint8_t> degenerate_;    // per ring: frozen, returned as given
    std::vector<std::uint32_t> source_;
    std::vector<std::uint32_t> clean_start_;       // per ring and one more: its first clean occurrence (degenerate: none)
    std::vector<std::uint64_t> node_bits_;         // per clean occurrence: is it a node
    std::vector<std::uint32_t> new_chains_before_; // per ring and one more: the chains the rings before it made
    std::unordered_map<std::uint32_t, std::uint8_t> negative_zeros_;  // plan(): per vertex with a -0.0, which (1: x, 2: y)
    const MapData* map_ = nullptr;
    std::vector<std::uint32_t> arc_tag_vertices_;  // plan() with tags: the arc vertices where tags differ, rising
    std::vector<PointTag> arc_tags_;               // and their tags
    std::uint64_t tag_conflicts_ = 0;
    std::uint32_t first_vertex_ = 0, first_chain_ = 0;
    std::uint64_t arcs_ = 0, shared_arcs_ = 0, degenerate_rings_ = 0;
};

// A run of rings of a coverage (Coverage::slice), as much of its plan as they need to make their
// own chains: their nodes, their arcs' uses, and which chains they make.
struct CoverageSlice {
    std::uint32_t first_ring = 0;
    std::vector<std::uint8_t> degenerate;      // per ring of the run
    std::uint32_t clean_count = 0;             // the run's clean occurrences
    std::vector<std::uint64_t> node;           // per clean occurrence, from the run's first: is it a node
    std::vector<std::uint32_t> uses_start;     // per ring and one more, into uses
    std::vector<Coverage::ArcUse> uses;        // the rings' arcs in order (whole-map chains)
    std::uint32_t first_chain = 0, end_chain = 0;  // the chains the run makes: [first_chain, end_chain)
    std::vector<std::uint32_t> chain_size;     // and their vertex counts
};

// The chains [slice.first_chain, slice.end_chain) with their vertices (as build() makes them),
// from the slice's rings, streamed by `rings` once. Throws std::invalid_argument if they are not
// the rings the slice was planned from.
MapData arcs_of(const CoverageSlice& slice, const RingSource& rings);

}  // namespace toposimp::map
