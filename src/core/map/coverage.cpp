#include "core/map/coverage.hpp"

#include "core/exact/predicates.hpp"
#include "core/map/location_key.hpp"

#include <algorithm>
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
    const std::uint32_t rings = ring_count();
    const std::span<const Point> points(points_);

    // 1. Each ring as a cyclic sequence of positions into points_, without the closing vertex
    //    and without consecutive duplicates. Degenerate rings are set aside.
    std::vector<std::uint32_t> clean, clean_start(rings + 1, 0);
    std::vector<std::uint8_t> degenerate(rings, 0);
    std::vector<std::uint32_t> sequence;
    for (std::uint32_t r = 0; r < rings; ++r) {
        clean_start[r] = static_cast<std::uint32_t>(clean.size());
        sequence.clear();
        const std::uint32_t begin = ring_start_[r];
        std::uint32_t end = begin + ring_size_[r];
        if (end - begin >= 2 && same_location(points_[begin], points_[end - 1])) --end;
        for (std::uint32_t p = begin; p < end; ++p) {
            if (sequence.empty() || !same_location(points_[p], points_[sequence.back()])) sequence.push_back(p);
        }
        while (sequence.size() > 1 && same_location(points_[sequence.back()], points_[sequence.front()])) sequence.pop_back();
        if (sequence.size() < 3 || collinear(points, sequence)) {
            degenerate[r] = 1;
            continue;
        }
        clean.insert(clean.end(), sequence.begin(), sequence.end());
    }
    clean_start[rings] = static_cast<std::uint32_t>(clean.size());
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
    std::vector<std::uint8_t> node(clean.size(), 0);
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
                for (std::size_t k = g; k < h && differ; ++k) node[order[k].second] = 1;
                g = h;
            }
        }
    }
    std::vector<std::uint32_t>().swap(ring_of);  // (step 3 walks rings from clean_start)

    // 3. Cut each ring at its nodes; one chain per distinct arc.
    std::unordered_map<ArcKey, std::uint32_t, ArcKeyHash> arcs;
    std::vector<std::uint32_t> arc;
    auto add_chain_from = [&](const std::vector<std::uint32_t>& positions) {
        std::vector<Point> chain_points;
        chain_points.reserve(positions.size());
        for (const std::uint32_t p : positions) {
            chain_points.push_back(points_[p]);
            source_.push_back(p);
        }
        ++arcs_;
        return map.add_chain(chain_points);
    };
    // Is chain `c` the arc `positions`, read forward or backward?
    auto same_arc = [&](std::uint32_t c, bool reversed) {
        const Chain chain = map.chains[c];
        if (chain.last - chain.first + 1 != arc.size()) return false;
        for (std::size_t k = 0; k < arc.size(); ++k) {
            const std::uint32_t v = reversed ? chain.last - static_cast<std::uint32_t>(k) : chain.first + static_cast<std::uint32_t>(k);
            if (!same_location(map.vertices[v], points_[arc[k]])) return false;
        }
        return true;
    };
    auto emit_arc = [&]() {
        const ArcKey forward{LocationKey(points_[arc[0]]), LocationKey(points_[arc[1]])};
        const ArcKey backward{LocationKey(points_[arc.back()]), LocationKey(points_[arc[arc.size() - 2]])};
        const ArcKey canonical = std::min(forward, backward);
        if (const auto found = arcs.find(canonical); found != arcs.end()) {
            for (const bool reversed : {false, true}) {
                if (same_arc(found->second, reversed)) {
                    uses_.push_back({found->second, reversed});
                    ++shared_arcs_;
                    return;
                }
            }
        }
        const std::uint32_t chain = add_chain_from(arc);
        arcs.emplace(canonical, chain);
        uses_.push_back({chain, false});
    };

    start_offset_.assign(rings, 0);
    for (std::uint32_t r = 0; r < rings; ++r) {
        uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
        if (degenerate[r]) {
            std::vector<std::uint32_t> raw(ring_size_[r]);
            for (std::uint32_t k = 0; k < raw.size(); ++k) raw[k] = ring_start_[r] + k;
            const std::uint32_t chain = add_chain_from(raw);
            map.freeze(chain);
            uses_.push_back({chain, false});
            ++degenerate_rings_;
            continue;
        }
        const std::uint32_t first = clean_start[r], size = clean_start[r + 1] - first;
        std::uint32_t start = 0;
        while (start < size && !node[first + start]) ++start;
        if (start == size) {
            // No node: one closed arc, starting where the ring starts.
            arc.assign(clean.begin() + first, clean.begin() + first + size);
            arc.push_back(clean[first]);
            uses_.push_back({add_chain_from(arc), false});
            continue;
        }
        start_offset_[r] = (size - start) % size;
        arc.assign(1, clean[first + start]);
        for (std::uint32_t step = 1; step <= size; ++step) {
            const std::uint32_t i = first + (start + step) % size;
            arc.push_back(clean[i]);
            if (node[i]) {
                emit_arc();
                arc.assign(1, clean[i]);
            }
        }
    }
    uses_start_.push_back(static_cast<std::uint32_t>(uses_.size()));
    degenerate_.swap(degenerate);
    std::vector<Point>().swap(points_);  // (the arcs hold them now: as much as the map's vertices again, or more)
}

std::vector<std::uint32_t> Coverage::ring_vertices(std::uint32_t ring, const std::vector<std::uint8_t>& kept, bool arc_order) const {
    std::vector<std::uint32_t> all;
    for (std::uint32_t u = uses_start_[ring]; u < uses_start_[ring + 1]; ++u) {
        const Chain chain = map_->chains[uses_[u].chain];
        const std::uint32_t length = chain.last - chain.first + 1;
        // Each arc after the first starts at the node where the previous one ended.
        for (std::uint32_t k = u == uses_start_[ring] ? 0 : 1; k < length; ++k) {
            all.push_back(uses_[u].reversed ? chain.last - k : chain.first + k);
        }
    }
    if (degenerate_[ring]) return all;  // frozen: exactly as given
    all.pop_back();  // the closing vertex; closed again below
    if (!arc_order) std::rotate(all.begin(), all.begin() + (kept[all[start_offset_[ring]]] ? start_offset_[ring] : 0), all.end());
    std::vector<std::uint32_t> ring_out;
    for (const std::uint32_t v : all) {
        if (kept[v]) ring_out.push_back(v);
    }
    ring_out.push_back(ring_out.front());
    return ring_out;
}

}  // namespace toposimp::map
