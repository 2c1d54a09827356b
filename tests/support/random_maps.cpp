#include "support/random_maps.hpp"

#include "support/exact_checker.hpp"

#include <cmath>

namespace toposimp::testing {
namespace {

class Builder {
public:
    Builder(std::mt19937_64& rng, const RandomMapOptions& options) : rng_(rng), options_(options) {}

    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
    int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
    bool chance(double p) { return uniform(0, 1) < p; }

    Point random_point() {
        return {options_.origin_x + uniform(-0.5, 0.5) * options_.extent,
                options_.origin_y + uniform(-0.5, 0.5) * options_.extent};
    }

    // Can segment ab join the map without an improper contact with any existing segment?
    bool fits(Point a, Point b, const std::vector<Point>& pending) const {
        for (const auto& [p, q] : segments_) {
            if (improper_contact(a, b, p, q)) return false;
        }
        for (std::size_t i = 1; i + 1 < pending.size(); ++i) {
            if (improper_contact(a, b, pending[i - 1], pending[i])) return false;
        }
        return true;
    }

    void commit(const std::vector<Point>& chain) {
        if (chain.size() < 2) return;
        for (std::size_t i = 1; i < chain.size(); ++i) segments_.push_back({chain[i - 1], chain[i]});
        map_.add_chain(chain);
    }

    Point existing_vertex() {
        return map_.vertices[std::uniform_int_distribution<std::size_t>(0, map_.vertices.size() - 1)(rng_)];
    }

    void add_walk() {
        std::vector<Point> chain;
        chain.push_back(!map_.vertices.empty() && chance(0.4) ? existing_vertex() : random_point());
        const int steps = integer(1, options_.max_steps);
        const double step = options_.extent / 10;
        for (int s = 0; s < steps; ++s) {
            const Point from = chain.back();
            Point to;
            const double kind = uniform(0, 1);
            if (kind < 0.1 && chain.size() >= 2 && options_.near_degenerate) {
                // Continue exactly along the last segment's direction: a collinear run.
                const Point before = chain[chain.size() - 2];
                to = {from.x + (from.x - before.x), from.y + (from.y - before.y)};
            } else if (kind < 0.15) {
                to = from;  // duplicate consecutive vertex
            } else if (kind < 0.2 && !map_.vertices.empty()) {
                to = existing_vertex();  // end on a node
            } else if (kind < 0.3 && !map_.vertices.empty() && options_.near_degenerate) {
                // Within an ulp or two of another vertex: nearly touching, never quite.
                to = existing_vertex();
                const int ulps = integer(1, 2) * (chance(0.5) ? 1 : -1);
                double& coordinate = chance(0.5) ? to.x : to.y;
                for (int k = 0; k < std::abs(ulps); ++k) coordinate = std::nextafter(coordinate, ulps > 0 ? INFINITY : -INFINITY);
            } else {
                const double angle = uniform(0, 2 * M_PI);
                const double length = step * uniform(0.05, 1);
                to = {from.x + length * std::cos(angle), from.y + length * std::sin(angle)};
            }
            if (!fits(from, to, chain) || (chain.size() >= 2 && improper_contact(chain[chain.size() - 2], from, from, to) &&
                                           !(to.x == from.x && to.y == from.y))) {
                continue;
            }
            chain.push_back(to);
        }
        if (chain.size() >= 2 && chance(0.3) && options_.near_degenerate) {
            // A second line with the same two endpoints, as straight as possible.
            const std::vector<Point> twin{chain.front(), chain.back()};
            commit(chain);
            if (!(twin[0].x == twin[1].x && twin[0].y == twin[1].y) && fits(twin[0], twin[1], {})) commit(twin);
            return;
        }
        commit(chain);
    }

    void add_ring() {
        const Point center = random_point();
        const int corners = integer(3, 12);
        const double radius = options_.extent / 20;
        std::vector<Point> ring;
        for (int i = 0; i < corners; ++i) {
            const double angle = 2 * M_PI * (i + uniform(0, 0.8)) / corners;
            const double r = radius * uniform(0.2, 1);
            ring.push_back({center.x + r * std::cos(angle), center.y + r * std::sin(angle)});
        }
        ring.push_back(ring.front());
        for (std::size_t i = 1; i < ring.size(); ++i) {
            std::vector<Point> before(ring.begin(), ring.begin() + i);
            if (!fits(ring[i - 1], ring[i], before)) return;
            // The closing segment may touch the first one only at the shared start.
            if (i + 1 == ring.size()) {
                for (std::size_t k = 2; k + 1 < ring.size(); ++k) {
                    if (improper_contact(ring[i - 1], ring[i], ring[k - 1], ring[k])) return;
                }
            }
        }
        commit(ring);
    }

    // A wiggly line across the whole map, added whatever it crosses (roads over rivers): some
    // crossings, some T-contacts where a vertex lands on a line, some vertices shared.
    void add_road() {
        std::vector<Point> road;
        const Point from = random_point(), to = random_point();
        const int steps = integer(3, 3 * options_.max_steps);
        for (int s = 0; s <= steps; ++s) {
            const double t = static_cast<double>(s) / steps;
            Point p{from.x + t * (to.x - from.x), from.y + t * (to.y - from.y)};
            p.x += uniform(-1, 1) * options_.extent / 200;
            p.y += uniform(-1, 1) * options_.extent / 200;
            if (!map_.vertices.empty() && chance(0.05)) p = existing_vertex();
            road.push_back(p);
        }
        roads_.push_back(road);
    }

    void add_control_point() {
        if (map_.vertices.size() < 2 || !options_.near_degenerate || chance(0.4)) {
            map_.control_points.push_back(random_point());
            return;
        }
        const std::size_t i = std::uniform_int_distribution<std::size_t>(0, map_.vertices.size() - 2)(rng_);
        const Point a = map_.vertices[i], b = map_.vertices[i + 1];
        Point p{a.x + (b.x - a.x) * 0.5, a.y + (b.y - a.y) * 0.5};  // on or within rounding of ab
        const int ulps = integer(-2, 2);
        for (int k = 0; k < std::abs(ulps); ++k) p.y = std::nextafter(p.y, ulps > 0 ? INFINITY : -INFINITY);
        if (chance(0.1)) p = a;  // exactly on a vertex
        map_.control_points.push_back(p);
    }

    map::MapData take() {
        for (const auto& road : roads_) map_.add_chain(road);
        return std::move(map_);
    }

private:
    std::mt19937_64& rng_;
    const RandomMapOptions& options_;
    map::MapData map_;
    std::vector<std::pair<Point, Point>> segments_;
    std::vector<std::vector<Point>> roads_;
};

}  // namespace

map::MapData random_planar_map(std::mt19937_64& rng, const RandomMapOptions& options) {
    Builder builder(rng, options);
    for (int r = 0; r < options.rings; ++r) builder.add_ring();
    for (int c = 0; c < options.chains; ++c) builder.add_walk();
    for (int r = 0; r < options.roads; ++r) builder.add_road();
    for (int p = 0; p < options.control_points; ++p) builder.add_control_point();
    return builder.take();
}

}  // namespace toposimp::testing
