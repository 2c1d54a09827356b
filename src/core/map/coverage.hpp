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

#include <cstdint>
#include <span>
#include <vector>

namespace toposimp::map {

class Coverage {
public:
    // Adds a ring (the closing vertex may be there or not); returns its id. Points are copied.
    std::uint32_t add_ring(std::span<const Point> ring);

    // Splits every ring into arcs and appends one chain per distinct arc to `map` (frozen chains
    // for degenerate rings). Call once, after the last add_ring.
    void build(MapData& map);

    // The ring rebuilt from its arcs' kept vertices, as map vertex ids, closed (last = first).
    // Starts at the ring's first input vertex if it was kept (`arc_order` false), or where its
    // first arc starts (true: as a TopoJSON reader rebuilds it from the arcs).
    std::vector<std::uint32_t> ring_vertices(std::uint32_t ring, const std::vector<std::uint8_t>& kept, bool arc_order = false) const;

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

    std::vector<Point> points_;               // every ring point as given, until build()
    std::vector<std::uint32_t> ring_start_;   // into points_
    std::vector<std::uint32_t> ring_size_;
    std::vector<std::uint32_t> uses_start_;   // per ring, into uses_ (one past the end: next ring's)
    std::vector<ArcUse> uses_;
    std::vector<std::uint32_t> start_offset_; // per ring: where its first input point is in ring order
    std::vector<std::uint8_t> degenerate_;    // per ring: frozen, returned as given
    std::vector<std::uint32_t> source_;
    const MapData* map_ = nullptr;
    std::uint32_t first_vertex_ = 0;
    std::uint64_t arcs_ = 0, shared_arcs_ = 0, degenerate_rings_ = 0;
};

}  // namespace toposimp::map
