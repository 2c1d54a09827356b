#include "core/map/coverage.hpp"

#include "core/exact/predicates.hpp"
#include "core/map/location_key.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>

namespace toposimp::map {
namespace {

// The first two locations of an arc in one direction: with the nodes fixed, they determine the
// whole arc (every location between two nodes has a single way on).
struct ArcKey {
    LocationKey first, second;
    friend bool operator==(const ArcKey&, const ArcKey&) = default;
    friend auto operator<=>(const ArcKey&, const ArcKey&) = default;
};

struct ArcKeyHash {
    std::size_t operator()(const ArcKey& k) const { return hash_words({k.first.x, k.first.y, k.second.x, k.second.y}); }
};

// The arcs made so far, by the lesser of their two keys (the first two locations read forward,
// or backward), with the chain each became and its forward key. With the nodes fixed, an arc is
// its first two locations (from there every location has a single way on, to the next node), so
// an arc whose key is found is that chain, read backward unless its forward key is the chain's.
class ArcTable {
public:
    // key(k): the arc's k-th location; `size` locations.
    template <class Key>
    std::optional<Coverage::ArcUse> find(Key&& key, std::size_t size) const {
        const ArcKey forward{key(0), key(1)};
        const auto found = arcs_.find(std::min(forward, ArcKey{key(size - 1), key(size - 2)}));
        if (found == arcs_.end()) return std::nullopt;
        return Coverage::ArcUse{found->second.chain, !(found->second.forward == forward)};
    }
    template <class Key>
    void add(Key&& key, std::size_t size, std::uint32_t chain) {
        const ArcKey forward{key(0), key(1)};
        arcs_.emplace(std::min(forward, ArcKey{key(size - 1), key(size - 2)}), Made{chain, forward});
    }

private:
    struct Made {
        std::uint32_t chain;
        ArcKey forward;
    };
    std::unordered_map<ArcKey, Made, ArcKeyHash> arcs_;
};

// Are all points on one line (or fewer than three distinct)? Exact.
bool collinear(std::span<const Point> points, const std::vector<std::uint32_t>& positions) {
    const Point u = points[positions.front()];
    std::size_t other = 1;
    while (other < positions.size() && same_location(points[positions[other]], u)) ++other;
    if (other == positions.size()) return true;
    const Point w = points[positions[other]];
    exact::PredicateStats ignored;
    for (const std::uint32_t p : positions) {
        if (exact::orient2d(u, w, points[p], ignored) != 0) return false;
    }
    return true;
}

// A ring's clean sequence: positions into `ring` without the closing vertex and without
// consecutive duplicates (the first of each run stays). False if the ring is degenerate: fewer
// than three distinct locations, or all on one line (exactly).
bool clean_ring(std::span<const Point> ring, std::vector<std::uint32_t>& sequence) {
    sequence.clear();
    auto end = static_cast<std::uint32_t>(ring.size());
    if (end >= 2 && same_location(ring[0], ring[end - 1])) --end;
    for (std::uint32_t p = 0; p < end; ++p) {
        if (sequence.empty() || !same_location(ring[p], ring[sequence.back()])) sequence.push_back(p);
    }
    while (sequence.size() > 1 && same_location(ring[sequence.back()], ring[sequence.front()])) sequence.pop_back();
    return sequence.size() >= 3 && !collinear(ring, sequence);
}

// A clean ring cut at its nodes (node(i): is its i-th clean occurrence one?): arc(positions)
// for each arc in ring order, from the first node on, each ending at the next node (the last
// back at the first; emit(positions, false)). Without a node, the whole ring is one closed arc from
// its first position (emit(positions, true)).
// Returns the first node's index (the ring's size if none).
template <class Node, class Arc>
std::uint32_t cut_at_nodes(std::span<const std::uint32_t> clean, Node&& node, std::vector<std::uint32_t>& arc, Arc&& emit) {
    const auto size = static_cast<std::uint32_t>(clean.size());
    std::uint32_t start = 0;
    while (start < size && !node(start)) ++start;
    if (start == size) {
        arc.assign(clean.begin(), clean.end());
        arc.push_back(clean[0]);
        emit(std::span<const std::uint32_t>(arc), true);
        return size;
    }
    arc.assign(1, clean[start]);
    for (std::uint32_t step = 1; step <= size; ++step) {
        const std::uint32_t i = (start + step) % size;
        arc.push_back(clean[i]);
        if (node(i)) {
            emit(std::span<const std::uint32_t>(arc), false);
            arc.assign(1, clean[i]);
        }
    }
    return start;
}

// Bit i of a bitmap of 64-bit words.
bool bit_at(std::span<const std::uint64_t> bits, std::size_t i) { return ((bits[i / 64] >> (i % 64)) & 1) != 0; }
void set_bit(std::vector<std::uint64_t>& bits, std::size_t i) { bits[i / 64] |= std::uint64_t{1} << (i % 64); }

// An occurrence's neighbours in its clean ring, as an unordered pair of locations.
using Neighbours = std::pair<LocationKey, LocationKey>;
Neighbours neighbours_at(std::span<const Point> ring, std::span<const std::uint32_t> clean, std::size_t i) {
    const std::size_t size = clean.size();
    LocationKey before(ring[clean[(i + size - 1) % size]]), after(ring[clean[(i + 1) % size]]);
    if (after < before) std::swap(before, after);
    return {before, after};
}

// Which of p's coordinates are −0.0: 1 for x, 2 for y.
std::uint8_t zero_signs(Point p) {
    return static_cast<std::uint8_t>((p.x == 0 && std::signbit(p.x) ? 1 : 0) | (p.y == 0 && std::signbit(p.y) ? 2 : 0));
}

}  // namespace

std::uint32_t Coverage::add_ring(std::span<const Point> ring) {
    ring_start_.push_back(static_cast<std::uint32_t>(points_.size()));
    ring_size_.push_back(static_cast<std::uint32_t>(ring.size()));
    points_.insert(points_.end(), ring.begin(), ring.end());
    return static_cast<std::uint32_t>(ring_start_.size() - 1);
}

void Coverage::build(MapData& map) {
    map_ = &map;
    first_vertex_ = static_cast<std::uint32_t>(map.vertices.size());
    first_chain_ = static_cast<std::uint32_t>(map.chains.size());
    const std::uint32_t rings = ring_count();
    const std::span<const Point> points(points_);
    auto ring_points = [&](std::uint32_t r) { return points.subspan(ring_start_[r], ring_size_[r]); };

    // 1. Each ring as a cyclic sequence of positions into points_, without the closing vertex
    //    and without consecutive duplicates. Degenerate rings are set aside.
    std::vector<std::uint32_t> clean;
    clean_start_.assign(rings + 1, 0);
    std::vector<std::uint8_t> degenerate(rings, 0);
    std::vector<std::uint32_t> sequence;
    for (std::uint32_t r = 0; r < rings; ++r) {
        clean_start_[r] = static_cast<std::uint32_t>(clean.size());
        if (!clean_ring(ring_points(r), sequence)) {
            degenerate[r] = 1;
            continue;
        }
        for (const std::uint32_t p : sequence) clean.push_back(ring_start_[r] + p);
    }
    clean_start_[rings] = static_cast<std::uint32_t>(clean.size());
    const std::vector<std::uint32_t>& clean_start = clean_start_;
    std::vector<std::uint32_t> ring_of(clean.size());
    for (std::uint32_t r = 0; r < rings; ++r) {
        for (std::uint32_t i = clean_start[r]; i < clean_start[r + 1]; ++i) ring_of[i] = r;
    }
    auto cyclic = [&](std::uint32_t i, int step) {
        const std::uint32_t r = ring_of[i], first = clean_start[r], size = clean_start[r + 1] - first;
        return first + (i - first + size + step) % size;
    };

    // 2. Nodes: locations whose occurrences do not all have the same pair of neighbours. The
    // occurrences are grouped by location: first into buckets by a hash of it (a counting sort
    // of positions, 4 bytes each), then each bucket's keys sorted with their positions (the sort
    // reads memory in order — a third of the build on Natural Earth's states went to sorting
    // positions by their keys). A bucket at a time: the keys of all of them at once took 24
    // bytes a ring point, a GB on a 40 M-point coverage, on top of the map being read.
    auto key_of = [&](std::uint32_t i) { return LocationKey(points_[clean[i]]); };
    node_bits_.assign((clean.size() + 63) / 64, 0);
    auto neighbours = [&](std::uint32_t i) {
        LocationKey before = key_of(cyclic(i, -1)), after = key_of(cyclic(i, 1));
        if (after < before) std::swap(before, after);
        return std::pair{before, after};
    };
    {
        const unsigned bucket_bits = clean.size() < (1u << 16) ? 0 : 6;
        auto bucket_of = [&](std::uint32_t i) {
            const LocationKey key = key_of(i);
            return bucket_bits == 0 ? std::size_t{0} : hash_words({key.x, key.y}) >> (64 - bucket_bits);
        };
        std::vector<std::uint32_t> bucket_start((std::size_t{1} << bucket_bits) + 1, 0);
        for (std::uint32_t i = 0; i < clean.size(); ++i) ++bucket_start[bucket_of(i) + 1];
        for (std::size_t b = 1; b < bucket_start.size(); ++b) bucket_start[b] += bucket_start[b - 1];
        std::vector<std::uint32_t> by_bucket(clean.size());
        {
            std::vector<std::uint32_t> fill(bucket_start.begin(), bucket_start.end() - 1);
            for (std::uint32_t i = 0; i < clean.size(); ++i) by_bucket[fill[bucket_of(i)]++] = i;
        }
        std::vector<std::pair<LocationKey, std::uint32_t>> order;
        for (std::size_t b = 0; b + 1 < bucket_start.size(); ++b) {
            order.clear();
            for (std::uint32_t k = bucket_start[b]; k < bucket_start[b + 1]; ++k) order.emplace_back(key_of(by_bucket[k]), by_bucket[k]);
            std::sort(order.begin(), order.end(), [](const auto& a, const auto& c) {
                return a.first < c.first || (a.first == c.first && a.second < c.second);
            });
            for (std::size_t g = 0; g < order.size();) {
                std::size_t h = g + 1;
                while (h < order.size() && order[h].first == order[g].first) ++h;
                bool differ = false;
                for (std::size_t k = g + 1; k < h && !differ; ++k) differ = neighbours(order[k].second) != neighbours(order[g].second);
                for (std::size_t k = g; k < h && differ; ++k) set_bit(node_bits_, order[k].second);
                g = h;
            }
        }
    }
    std::vector<std::uint32_t>().swap(ring_of);  // (step 3 walks rings from clean_start)

    // 3. Cut each ring at its nodes; one chain per distinct arc.
    ArcTable arcs;
    auto add_chain_from = [&](std::span<const std::uint32_t> positions) {
        std::vector<Point> chain_points;
        chain_points.reserve(positions.size());
        for (const std::uint32_t p : positions) {
            chain_points.push_back(points_[p]);
            source_.push_back(p);
        }
        ++arcs_;
        return map.add_chain(chain_points);
    };
    // Is the arc `positions` the chain `use` names, read the way it says? (Always, when the arc
    // table found it: see ArcTable. Checked here, where the vertices are at hand.)
    auto same_arc = [&](std::span<const std::uint32_t> positions, ArcUse use) {
        const Chain chain = map.chains[use.chain];
        if (chain.last - chain.first + 1 != positions.size()) return false;
        for (std::size_t k = 0; k < positions.size(); ++k) {
            const std::uint32_t v = use.reversed ? chain.last - static_cast<std::uint32_t>(k) : chain.first + static_cast<std::uint32_t>(k);
            if (!same_location(map.vertices[v], points_[positions[k]])) return false;
        }
        return true;
    };
    std::vector<std::uint32_t> arc;
    start_offset_.assign(rings, 0);
    new_chains_before_.assign(rings + 1, 0);
    for (std::uint32_t r = 0; r < rings; ++r) {
        uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
        new_chains_before_[r] = static_cast<std::uint32_t>(map.chains.size()) - first_chain_;
        if (degenerate[r]) {
            std::vector<std::uint32_t> raw(ring_size_[r]);
            for (std::uint32_t k = 0; k < raw.size(); ++k) raw[k] = ring_start_[r] + k;
            const std::uint32_t chain = add_chain_from(raw);
            map.freeze(chain);
            uses_.push_back({chain, false});
            ++degenerate_rings_;
            continue;
        }
        const std::span<const std::uint32_t> ring(clean.data() + clean_start[r], clean_start[r + 1] - clean_start[r]);
        const auto size = static_cast<std::uint32_t>(ring.size());
        const std::uint32_t start = cut_at_nodes(
            ring, [&](std::uint32_t i) { return bit_at(node_bits_, clean_start[r] + i); }, arc,
            [&](std::span<const std::uint32_t> positions, bool whole_ring) {
                const auto key = [&](std::size_t k) { return LocationKey(points_[positions[k]]); };
                if (!whole_ring) {
                    if (const std::optional<ArcUse> found = arcs.find(key, positions.size())) {
                        if (!same_arc(positions, *found)) throw std::logic_error("two arcs with the same ends and first steps");
                        uses_.push_back(*found);
                        ++shared_arcs_;
                        return;
                    }
                }
                const std::uint32_t chain = add_chain_from(positions);
                if (!whole_ring) arcs.add(key, positions.size(), chain);
                uses_.push_back({chain, false});
            });
        start_offset_[r] = start == size ? 0 : (size - start) % size;
    }
    uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
    new_chains_before_[rings] = static_cast<std::uint32_t>(map.chains.size()) - first_chain_;
    degenerate_.swap(degenerate);
    std::vector<Point>().swap(points_);  // (the arcs hold them now: as much as the map's vertices again, or more)
}

void Coverage::plan(const RingSource& rings, MapData& map, std::size_t pass_bytes) {
    plan_rings<false>(
        [&](const std::function<void(std::span<const Point>, std::span<const PointTag>)>& visit) {
            rings([&](std::span<const Point> ring) { visit(ring, {}); });
        },
        map, pass_bytes);
}

void Coverage::plan(const TaggedRingSource& rings, MapData& map, std::size_t pass_bytes) {
    plan_rings<true>(rings, map, pass_bytes);
}

template <bool kTagged>
void Coverage::plan_rings(const TaggedRingSource& tagged, MapData& map, std::size_t pass_bytes) {
    if (!ring_start_.empty()) throw std::logic_error("Coverage::plan on a coverage given rings");
    // (The passes that do not look at the tags.)
    auto rings = [&](const std::function<void(std::span<const Point>)>& visit) {
        tagged([&](std::span<const Point> ring, std::span<const PointTag>) { visit(ring); });
    };
    map_ = &map;
    first_chain_ = static_cast<std::uint32_t>(map.chains.size());
    first_vertex_ = map.chains.empty() ? 0 : map.chains.back().last + 1;
    std::vector<std::uint32_t> sequence, arc, clean_of;
    auto changed = [] { return std::invalid_argument("the rings are not those of the first pass"); };

    // 1. The rings' sizes, which are degenerate, and each one's clean occurrences, counted by
    // their location's bucket (a hash) for the passes below.
    constexpr std::uint32_t kBuckets = 4096;
    auto bucket_of = [](const LocationKey& key) { return static_cast<std::uint32_t>(hash_words({key.x, key.y}) % kBuckets); };
    std::vector<std::uint64_t> in_bucket(kBuckets, 0);
    clean_start_.assign(1, 0);
    std::uint32_t point_count = 0;
    rings([&](std::span<const Point> ring) {
        if (point_count + ring.size() > std::numeric_limits<std::uint32_t>::max() / 2) throw std::length_error("more than 2 billion vertices in one map");
        ring_start_.push_back(point_count);
        ring_size_.push_back(static_cast<std::uint32_t>(ring.size()));
        point_count += static_cast<std::uint32_t>(ring.size());
        const bool clean = clean_ring(ring, sequence);
        degenerate_.push_back(clean ? 0 : 1);
        clean_start_.push_back(clean_start_.back() + (clean ? static_cast<std::uint32_t>(sequence.size()) : 0));
        if (clean) {
            for (const std::uint32_t p : sequence) ++in_bucket[bucket_of(LocationKey(ring[p]))];
        }
    });
    const std::uint32_t ring_total = ring_count();

    // 2. Nodes, as build() finds them, in passes over the rings: each pass groups the occurrences
    // of a run of buckets, as many as fit in pass_bytes (or one bucket), every occurrence of a
    // location in the same pass.
    struct Plain {
        LocationKey key;
        Neighbours around;
        std::uint32_t index;  // among the clean occurrences
    };
    struct Tagged : Plain {
        PointTag tag;
    };
    using Occurrence = std::conditional_t<kTagged, Tagged, Plain>;
    const std::uint64_t total = clean_start_.back();
    const std::uint64_t per_pass = std::max<std::uint64_t>(1, pass_bytes / sizeof(Occurrence));
    std::vector<std::uint32_t> pass_of(kBuckets);
    std::vector<std::uint64_t> pass_size(1, 0);
    for (std::uint32_t b = 0; b < kBuckets; ++b) {
        if (pass_size.back() > 0 && pass_size.back() + in_bucket[b] > per_pass) pass_size.push_back(0);
        pass_of[b] = static_cast<std::uint32_t>(pass_size.size() - 1);
        pass_size.back() += in_bucket[b];
    }
    const std::uint64_t passes = pass_size.size();
    node_bits_.assign((total + 63) / 64, 0);
    std::vector<Occurrence> found;
    std::vector<std::uint64_t> conflict_bits;  // (with tags: per clean occurrence, do the tags at its location differ)
    if constexpr (kTagged) conflict_bits.assign((total + 63) / 64, 0);
    found.reserve(static_cast<std::size_t>(*std::max_element(pass_size.begin(), pass_size.end())));
    for (std::uint64_t pass = 0; pass < passes; ++pass) {
        found.clear();
        std::uint32_t r = 0;
        tagged([&](std::span<const Point> ring, std::span<const PointTag> tags) {
            if (r >= ring_total || ring.size() != ring_size_[r] || (kTagged && tags.size() != ring.size())) throw changed();
            if (!degenerate_[r]) {
                if (!clean_ring(ring, sequence) || sequence.size() != clean_start_[r + 1] - clean_start_[r]) throw changed();
                for (std::size_t i = 0; i < sequence.size(); ++i) {
                    const LocationKey key(ring[sequence[i]]);
                    if (passes > 1 && pass_of[bucket_of(key)] != pass) continue;
                    if (found.size() == pass_size[pass]) throw changed();
                    const Plain plain{key, neighbours_at(ring, sequence, i), clean_start_[r] + static_cast<std::uint32_t>(i)};
                    if constexpr (kTagged) {
                        found.push_back({plain, tags[sequence[i]]});
                    } else {
                        found.push_back(plain);
                    }
                }
            }
            ++r;
        });
        if (r != ring_total || found.size() != pass_size[pass]) throw changed();
        std::sort(found.begin(), found.end(), [](const Occurrence& a, const Occurrence& b) {
            return a.key < b.key || (a.key == b.key && a.index < b.index);
        });
        for (std::size_t g = 0; g < found.size();) {
            std::size_t h = g + 1;
            bool differ = false;
            for (; h < found.size() && found[h].key == found[g].key; ++h) {
                differ = differ || found[h].around != found[g].around;
            }
            if constexpr (kTagged) {
                bool conflict = false;
                for (std::size_t k = g + 1; k < h && !conflict; ++k) conflict = found[k].tag != found[g].tag;
                if (conflict) {
                    ++tag_conflicts_;
                    for (std::size_t k = g; k < h; ++k) set_bit(conflict_bits, found[k].index);
                }
            }
            for (std::size_t k = g; k < h && differ; ++k) set_bit(node_bits_, found[k].index);
            g = h;
        }
    }
    std::vector<Occurrence>().swap(found);

    // 3. The arcs, as build() makes them, their vertices left where the rings are.
    ArcTable arcs;
    std::uint64_t next_vertex = first_vertex_;
    auto add_chain_of = [&](std::size_t count) {
        if (next_vertex + count > std::numeric_limits<std::uint32_t>::max() / 2) throw std::length_error("more than 2 billion vertices in one map");
        map.chains.push_back({static_cast<std::uint32_t>(next_vertex), static_cast<std::uint32_t>(next_vertex + count - 1)});
        next_vertex += count;
        ++arcs_;
        return static_cast<std::uint32_t>(map.chains.size() - 1);
    };
    start_offset_.assign(ring_total, 0);
    new_chains_before_.assign(ring_total + 1, 0);
    std::uint32_t r = 0;
    tagged([&](std::span<const Point> ring, std::span<const PointTag> tags) {
        if (r >= ring_total || ring.size() != ring_size_[r] || (kTagged && tags.size() != ring.size())) throw changed();
        uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
        new_chains_before_[r] = static_cast<std::uint32_t>(map.chains.size()) - first_chain_;
        if (degenerate_[r]) {
            const std::uint32_t chain = add_chain_of(ring.size());
            map.freeze(chain);  // (ring_points_from gives it as it is given: no zero to note)
            uses_.push_back({chain, false});
            ++degenerate_rings_;
            ++r;
            return;
        }
        if (!clean_ring(ring, sequence) || sequence.size() != clean_start_[r + 1] - clean_start_[r]) throw changed();
        const std::uint32_t base = clean_start_[r];
        const auto size = static_cast<std::uint32_t>(sequence.size());
        if (tag_conflicts_ > 0) {  // (the ring's positions to their clean occurrences, for the conflict bits)
            clean_of.resize(ring.size());
            for (std::uint32_t i = 0; i < size; ++i) clean_of[sequence[i]] = base + i;
        }
        const std::uint32_t start = cut_at_nodes(
            sequence, [&](std::uint32_t i) { return bit_at(node_bits_, base + i); }, arc,
            [&](std::span<const std::uint32_t> positions, bool whole_ring) {
                const auto key = [&](std::size_t k) { return LocationKey(ring[positions[k]]); };
                if (!whole_ring) {
                    if (const std::optional<ArcUse> use = arcs.find(key, positions.size())) {
                        uses_.push_back(*use);
                        ++shared_arcs_;
                        return;
                    }
                }
                const std::uint32_t chain = add_chain_of(positions.size());
                if (!whole_ring) arcs.add(key, positions.size(), chain);
                uses_.push_back({chain, false});
                note_negative_zeros(ring, positions, map.chains[chain].first);
                if (tag_conflicts_ > 0) {
                    // (Where the rings' tags differ, the arc's vertices carry this ring's.)
                    for (std::size_t k = 0; k < positions.size(); ++k) {
                        if (bit_at(conflict_bits, clean_of[positions[k]])) {
                            arc_tag_vertices_.push_back(map.chains[chain].first + static_cast<std::uint32_t>(k));  // (rising: chains come in order)
                            arc_tags_.push_back(tags[positions[k]]);
                        }
                    }
                }
            });
        start_offset_[r] = start == size ? 0 : (size - start) % size;
        ++r;
    });
    if (r != ring_total) throw changed();
    uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
    new_chains_before_[ring_total] = static_cast<std::uint32_t>(map.chains.size()) - first_chain_;
}

CoverageSlice Coverage::slice(std::uint32_t first_ring, std::uint32_t end_ring) const {
    if (first_ring > end_ring || end_ring > ring_count()) throw std::out_of_range("Coverage::slice: rings out of range");
    CoverageSlice slice;
    slice.first_ring = first_ring;
    slice.degenerate.assign(degenerate_.begin() + first_ring, degenerate_.begin() + end_ring);
    const std::uint32_t first_bit = clean_start_[first_ring];
    slice.clean_count = clean_start_[end_ring] - first_bit;
    slice.node.assign((slice.clean_count + 63) / 64, 0);
    for (std::uint32_t i = 0; i < slice.clean_count; ++i) {
        if (bit_at(node_bits_, first_bit + i)) set_bit(slice.node, i);
    }
    for (std::uint32_t r = first_ring; r <= end_ring; ++r) slice.uses_start.push_back(uses_start_[r] - uses_start_[first_ring]);
    slice.uses.assign(uses_.begin() + uses_start_[first_ring], uses_.begin() + uses_start_[end_ring]);
    slice.first_chain = first_chain_ + new_chains_before_[first_ring];
    slice.end_chain = first_chain_ + new_chains_before_[end_ring];
    for (std::uint32_t c = slice.first_chain; c < slice.end_chain; ++c) slice.chain_size.push_back(map_->chains[c].last - map_->chains[c].first + 1);
    return slice;
}

MapData arcs_of(const CoverageSlice& slice, const RingSource& rings) {
    MapData part;
    std::vector<std::uint32_t> sequence, arc, all;
    std::vector<Point> points;
    std::uint32_t next = slice.first_chain;
    std::size_t r = 0;
    std::uint32_t bit = 0;
    auto changed = [] { return std::invalid_argument("the rings are not those the coverage was planned from"); };
    rings([&](std::span<const Point> ring) {
        if (r >= slice.degenerate.size()) throw changed();
        std::uint32_t u = slice.uses_start[r];
        // The ring's next arc: made here if this is where it is first used (ids go in that order).
        auto take = [&](std::span<const std::uint32_t> positions, bool frozen) {
            if (u >= slice.uses_start[r + 1]) throw changed();
            if (slice.uses[u++].chain != next) return;  // (an arc an earlier ring made)
            if (next >= slice.end_chain || positions.size() != slice.chain_size[next - slice.first_chain]) throw changed();
            points.clear();
            for (const std::uint32_t p : positions) points.push_back(ring[p]);
            const std::uint32_t chain = part.add_chain(points);
            if (frozen) part.freeze(chain);
            ++next;
        };
        const bool clean = clean_ring(ring, sequence);
        if (clean == (slice.degenerate[r] != 0)) throw changed();
        if (!clean) {
            all.resize(ring.size());
            for (std::uint32_t k = 0; k < all.size(); ++k) all[k] = k;
            take(all, true);
        } else {
            const std::uint32_t base = bit;
            bit += static_cast<std::uint32_t>(sequence.size());
            if (bit > slice.clean_count) throw changed();
            cut_at_nodes(
                sequence, [&](std::uint32_t i) { return bit_at(slice.node, base + i); }, arc,
                [&](std::span<const std::uint32_t> positions, bool) { take(positions, false); });
        }
        if (u != slice.uses_start[r + 1]) throw changed();
        ++r;
    });
    if (r != slice.degenerate.size() || bit != slice.clean_count || next != slice.end_chain) throw changed();
    return part;
}

// Ring `ring`'s vertices from its arcs, in arc order, without the closing one: all[i] is at its
// clean occurrence (first + i) % size, `first` the one its first arc starts at (degenerate: every
// point given, closing one included).
std::vector<std::uint32_t> Coverage::arc_order_vertices(std::uint32_t ring) const {
    std::vector<std::uint32_t> all;
    for (std::uint32_t u = uses_start_[ring]; u < uses_start_[ring + 1]; ++u) {
        const Chain chain = map_->chains[uses_[u].chain];
        const std::uint32_t length = chain.last - chain.first + 1;
        // Each arc after the first starts at the node where the previous one ended.
        for (std::uint32_t k = u == uses_start_[ring] ? 0 : 1; k < length; ++k) {
            all.push_back(uses_[u].reversed ? chain.last - k : chain.first + k);
        }
    }
    if (!degenerate_[ring]) all.pop_back();  // the closing vertex
    return all;
}

std::vector<std::uint32_t> Coverage::ring_vertices(std::uint32_t ring, const std::vector<std::uint8_t>& kept, bool arc_order) const {
    std::vector<std::uint32_t> all = arc_order_vertices(ring);
    if (degenerate_[ring]) return all;  // frozen: exactly as given
    if (!arc_order) std::rotate(all.begin(), all.begin() + (kept[all[start_offset_[ring]]] ? start_offset_[ring] : 0), all.end());
    std::vector<std::uint32_t> ring_out;
    for (const std::uint32_t v : all) {
        if (kept[v]) ring_out.push_back(v);
    }
    ring_out.push_back(ring_out.front());
    return ring_out;
}

std::vector<Coverage::RingPoint> Coverage::ring_points_from(std::uint32_t ring, std::span<const Point> given,
                                                            const std::vector<std::uint8_t>& kept, bool arc_order) const {
    std::vector<std::uint32_t> all = arc_order_vertices(ring);
    std::vector<RingPoint> ring_out;
    if (degenerate_[ring]) {
        if (given.size() != all.size()) throw std::invalid_argument("a ring that is not the one the coverage was made of");
        for (std::uint32_t k = 0; k < given.size(); ++k) ring_out.push_back({given[k], k, all[k]});  // (its own chain: its own bits)
        return ring_out;
    }
    std::vector<std::uint32_t> sequence;
    if (!clean_ring(given, sequence) || sequence.size() != all.size()) {
        throw std::invalid_argument("a ring that is not the one the coverage was made of");
    }
    const auto size = static_cast<std::uint32_t>(all.size());
    // all[i] is at clean occurrence (i - start_offset) mod size: ring_vertices' rotation, the
    // points taken from the occurrences instead of the arcs.
    const std::uint32_t offset = start_offset_[ring];
    const std::uint32_t from = !arc_order && kept[all[offset]] ? offset : 0;
    for (std::uint32_t step = 0; step < size; ++step) {
        const std::uint32_t i = (from + step) % size;
        if (!kept[all[i]]) continue;
        const std::uint32_t at = sequence[(i + size - offset) % size];
        ring_out.push_back({owner_zeros(all[i], given[at]), at, all[i]});
    }
    ring_out.push_back(ring_out.front());
    return ring_out;
}

void Coverage::note_negative_zeros(std::span<const Point> ring, std::span<const std::uint32_t> positions, std::uint32_t first_vertex) {
    for (std::size_t k = 0; k < positions.size(); ++k) {
        const Point p = ring[positions[k]];
        if (const std::uint8_t signs = zero_signs(p); signs != 0) negative_zeros_.emplace(first_vertex + static_cast<std::uint32_t>(k), signs);
    }
}

Point Coverage::owner_zeros(std::uint32_t v, Point p) const {
    if (p.x != 0 && p.y != 0) return p;
    std::uint8_t signs = 0;
    if (v < map_->vertices.size()) {  // (built: the vertex is there)
        signs = zero_signs(map_->vertices[v]);
    } else if (const auto found = negative_zeros_.find(v); found != negative_zeros_.end()) {
        signs = found->second;
    }
    if (p.x == 0) p.x = (signs & 1) != 0 ? -0.0 : 0.0;
    if (p.y == 0) p.y = (signs & 2) != 0 ? -0.0 : 0.0;
    return p;
}

}  // namespace toposimp::map
