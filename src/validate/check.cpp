#include "validate/check.hpp"

#include "core/exact/point_in_ring.hpp"
#include "core/exact/predicates.hpp"
#include "core/exact/segments.hpp"
#include "core/map/crossings.hpp"
#include "core/map/location_key.hpp"
#include "core/map/point_grid.hpp"
#include "io/common/errors.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "validate/geos.hpp"
#include "validate/layers.hpp"

#include <cpl_vsi.h>
#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <span>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

namespace toposimp::validate {
namespace {

constexpr KindInfo kKinds[] = {
    {ViolationKind::feature_lost, "feature_lost", "a feature of the original is missing, or its geometry became empty"},
    {ViolationKind::parts_changed, "parts_changed", "a feature has a different number of lines, polygons or rings"},
    {ViolationKind::not_subset, "not_subset", "a line or ring is not an order-preserving subset of the original's vertices"},
    {ViolationKind::ring_collapsed, "ring_collapsed", "a ring has fewer than 3 distinct corners or no area"},
    {ViolationKind::ring_flipped, "ring_flipped", "a ring turns the other way than in the original"},
    {ViolationKind::invalid_polygon, "invalid_polygon", "a polygon valid in the original is invalid (GEOS IsValidOp)"},
    {ViolationKind::new_crossing, "new_crossing", "two lines (or rings) cross more often than in the original"},
    {ViolationKind::lost_crossing, "lost_crossing", "two lines cross less often than in the original"},
    {ViolationKind::new_touching, "new_touching", "two lines touch or overlap where they did not (a T-contact or partial overlap)"},
    {ViolationKind::lost_touching, "lost_touching", "two lines no longer touch as in the original"},
    {ViolationKind::new_coincidence, "new_coincidence", "two lines now share a segment; they shared none"},
    {ViolationKind::border_no_longer_shared, "border_no_longer_shared",
     "two features shared a border segment and share none now (gap or overlap)"},
    {ViolationKind::point_changed_polygon, "point_changed_polygon",
     "a control point is in a different polygon (or on a boundary) than before"},
    {ViolationKind::point_changed_side, "point_changed_side", "a control point was swept over by a simplified line: it changed side"},
};

}  // namespace

std::span<const KindInfo> kinds() { return kKinds; }

const char* name(ViolationKind kind) { return kKinds[static_cast<std::size_t>(kind)].name; }

std::map<std::string, std::uint64_t> CheckReport::counts() const {
    std::map<std::string, std::uint64_t> result;
    for (const KindInfo& kind : kinds()) result[kind.name] = 0;
    for (const Violation& v : violations) ++result[name(v.kind)];
    return result;
}

namespace {

using io::InputError;

// Rings of at least this many vertices are indexed (exact::RingLocator) to locate control points
// in them; a removed stretch's detour once this many points were located in it.
constexpr std::size_t kIndexedRing = 64;
constexpr std::size_t kIndexedAfter = 16;

// Does a simplified vertex stand for an original one: the same location, or, for output rounded
// onto a grid, a grid point of the 5×5 around the original's nearest one (where toposimp map
// --precision may put it)? Decided on the grid's integer indices: exact.
class VertexMatch {
public:
    explicit VertexMatch(const std::optional<map::OutputGrid>& grid) : grid_(grid) {}

    bool operator()(Point original, Point simplified) const {
        if (same_location(original, simplified)) return true;
        if (!grid_) return false;
        return near(grid_->x, original.x, simplified.x) && near(grid_->y, original.y, simplified.y);
    }

private:
    static bool near(const map::AxisGrid& axis, double original, double simplified) {
        // Two grid indices from the original's nearest lie within 2.5 steps of it (and the
        // rounding of grid values): farther is no match, decided without the grid's arithmetic.
        const double reach = 3 * axis.step() + std::ldexp(std::max(std::abs(original), std::abs(simplified)), -48);
        if (!(std::abs(simplified - original) <= reach)) return false;
        const std::optional<std::int64_t> k = axis.nearest(simplified), o = axis.nearest(original);
        if (!k || !o || axis.at(*k) != simplified) return false;  // not on the grid
        return *k >= *o - 2 && *k <= *o + 2;
    }

    const std::optional<map::OutputGrid>& grid_;
};

// Is `simplified` an order-preserving subset of `original` with the same ends (lines), or of
// some rotation of the ring, forwards or backwards (rings)? Fills the original index of each
// simplified vertex.
bool match_line(const std::vector<Point>& original, const std::vector<Point>& simplified, std::vector<std::size_t>& at,
                const VertexMatch& same_location) {
    at.clear();
    if (original.empty()) return simplified.empty();  // (an empty part that stays empty: its own subset)
    if (simplified.size() < 2) {
        std::size_t i = 0;
        for (const Point p : simplified) {
            while (i < original.size() && !same_location(original[i], p)) ++i;
            if (i == original.size()) return false;
            at.push_back(i++);
        }
        return !at.empty() && at.front() == 0 && at.back() + 1 == original.size();
    }
    // The ends are the original's ends; the vertices between, in order, before its last one. (A
    // line ending in a repeated vertex Z, Z simplified to A, Z matched Z to the first copy and
    // was reported not a subset: issue 29.)
    const std::size_t last = original.size() - 1;
    if (!same_location(original.front(), simplified.front()) || !same_location(original[last], simplified.back())) return false;
    at.push_back(0);
    std::size_t i = 1;
    for (std::size_t k = 1; k + 1 < simplified.size(); ++k) {
        while (i < last && !same_location(original[i], simplified[k])) ++i;
        if (i == last) return false;
        at.push_back(i++);
    }
    at.push_back(last);
    return true;
}

// Which ways the simplified ring runs along the original (an order-preserving subset of some
// rotation): forwards, backwards, or both — both can match when a grid is given and the ring is
// no bigger than a few grid steps, every vertex then standing for several (issue 30: a ring
// rewound by the writer was reported flipped).
struct RingMatch {
    bool forwards = false, backwards = false;
    bool any() const { return forwards || backwards; }
};

RingMatch match_ring(const std::vector<Point>& original, std::vector<Point> simplified, const VertexMatch& same_location) {
    RingMatch match;
    if (original.size() < 2 || simplified.size() < 2) return match;
    const std::size_t n = original.size() - 1;  // without the closing vertex
    simplified.pop_back();
    for (const bool backwards : {false, true}) {
        if (backwards) std::reverse(simplified.begin(), simplified.end());
        for (std::size_t start = 0; start < n; ++start) {
            if (!same_location(original[start], simplified[0])) continue;
            std::size_t k = 0;
            for (std::size_t step = 0; step < n && k < simplified.size(); ++step) {
                if (same_location(original[(start + step) % n], simplified[k])) ++k;
            }
            if (k == simplified.size()) {
                (backwards ? match.backwards : match.forwards) = true;
                break;
            }
        }
    }
    return match;
}

int area_sign(const std::vector<Point>& ring) {
    mpq_class twice = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        twice += mpq_class(ring[i].x) * mpq_class(ring[i + 1].y) - mpq_class(ring[i + 1].x) * mpq_class(ring[i].y);
    }
    return sgn(twice);
}

std::size_t distinct_locations(const std::vector<Point>& ring) {
    std::vector<std::pair<double, double>> keys;
    for (const Point p : ring) keys.emplace_back(p.x == 0 ? 0.0 : p.x, p.y == 0 ? 0.0 : p.y);
    std::sort(keys.begin(), keys.end());
    return static_cast<std::size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

struct Matched {
    std::size_t layer;
    const Feature* original;
    const Feature* simplified;  // null if lost
};

// All linework of a side (original or simplified), each distinct segment once with the features
// it belongs to and how often: a border shared by two polygons is one segment of two features,
// a route a track drives 10 000 times one segment of one feature, 10 000 times. Contacts are
// then counted per pair of features by multiplying, not by listing every pair of segments
// (issue 29: 5·10^9 pairs for a 100 000-vertex track back and forth over one stretch).
// Memory (issue 32: a 200 M-vertex map's check): an added segment is 16 bytes, a pointer into its
// feature's points (which outlive the Linework) rather than its two ends' keys; a distinct
// segment then 52 bytes (its two points, chain, member and where its members begin).
class Linework {
public:
    struct Member {
        std::uint32_t feature;
        std::uint32_t times;  // (products of two: take them in 64 bits)
    };

    // Room for `segments` added segments in all (exactly: no slack doubling the array).
    void reserve(std::size_t segments) { added_.reserve(segments); }

    void add(const Feature& feature, std::uint32_t id) {
        for (const auto& part : feature.parts) {
            for (std::size_t k = 0; k + 1 < part.size(); ++k) added_.push_back({part.data() + k, id, static_cast<std::uint32_t>(added_.size())});
        }
    }

    // Groups what was added: afterwards map() holds each distinct segment as a chain of its
    // own (distinct segment d from vertex 2d), in order of first appearance.
    void finish() {
        std::sort(added_.begin(), added_.end(), [](const Added& x, const Added& y) {
            const auto ex = x.ends(), ey = y.ends();
            return std::tie(ex.first, ex.second, x.order) < std::tie(ey.first, ey.second, y.order);
        });
        struct Group {
            std::uint32_t first_added, begin, end;
        };
        std::vector<Group> groups;
        for (std::uint32_t k = 0; k < added_.size();) {
            std::uint32_t end = k + 1;
            const auto ends = added_[k].ends();
            while (end < added_.size() && added_[end].ends() == ends) ++end;
            groups.push_back({added_[k].order, k, end});
            k = end;
        }
        std::sort(groups.begin(), groups.end(), [](const Group& x, const Group& y) { return x.first_added < y.first_added; });
        // (Every array at its size at once: no slack.)
        std::size_t members = 0;
        for (const Group& group : groups) {
            for (std::uint32_t k = group.begin; k < group.end; ++k) members += k == group.begin || added_[k].feature != added_[k - 1].feature;
        }
        members_.reserve(members);
        map_.vertices.reserve(2 * groups.size());
        map_.chains.reserve(groups.size());
        start_.reserve(groups.size() + 1);
        start_.push_back(0);
        for (const Group& group : groups) {
            const auto [a, b] = added_[group.begin].ends();
            map_.vertices.push_back(a.point());
            map_.vertices.push_back(b.point());
            const auto v = static_cast<std::uint32_t>(map_.vertices.size() - 2);
            map_.chains.push_back({v, v + 1});
            // Features were added in increasing order, and the group keeps that order.
            for (std::uint32_t k = group.begin; k < group.end; ++k) {
                if (members_.size() > start_.back() && members_.back().feature == added_[k].feature) ++members_.back().times;
                else members_.push_back({added_[k].feature, 1});
            }
            start_.push_back(static_cast<std::uint32_t>(members_.size()));
        }
        added_ = {};
    }

    const map::MapData& map() const { return map_; }
    std::size_t segments() const { return map_.chains.size(); }
    std::span<const Member> members(std::size_t segment) const {
        return {members_.data() + start_[segment], members_.data() + start_[segment + 1]};
    }

private:
    struct Added {
        const Point* at;  // the segment is at[0]–at[1], in its feature
        std::uint32_t feature, order;
        // Its ends as location keys, the smaller first.
        std::pair<map::LocationKey, map::LocationKey> ends() const {
            const map::LocationKey a(at[0]), b(at[1]);
            return b < a ? std::pair{b, a} : std::pair{a, b};
        }
    };
    std::vector<Added> added_;
    map::MapData map_;
    std::vector<Member> members_;
    std::vector<std::uint32_t> start_;  // per distinct segment, where its members begin
};

using PairKey = std::pair<std::uint32_t, std::uint32_t>;
struct PairHash {
    std::size_t operator()(const PairKey& k) const { return std::hash<std::uint64_t>()((std::uint64_t{k.first} << 32) | k.second); }
};
struct PairContacts {
    std::array<std::uint64_t, 3> count{};            // by ContactKind
    std::array<map::SegmentContact, 3> first{};      // one example of each kind
};

// Distinct segments of a side that lie on one line, so that their overlaps along it are counted
// by a sweep rather than pair by pair (issue 29: a track driven 400 times along one straight road,
// its vertices elsewhere each time, has 10^7 overlapping pairs, every one a slow exact test of
// collinear points). Segments are bucketed by a rounded key of their line (its direction, its
// distance from the origin); in a bucket, a group is every segment whose two ends are exactly
// collinear with the group's first segment, when there are four or more. The key only decides
// what is tried together: two segments of one line that round into different buckets (or a
// small group) stay apart and are tested as a pair, as before; slower, never wrong.
struct LineGroups {
    std::vector<std::uint32_t> line_of;               // per vertex of side.map(): its segment's group, or kNoLine; empty if none
    std::vector<std::vector<std::uint32_t>> members;  // per group, its distinct segments
};

LineGroups find_line_groups(const Linework& side, exact::PredicateStats& stats) {
    // Lines shared by a few segments cost little pair by pair; grouping pays for many.
    constexpr std::size_t kMinGroup = 4;
    const auto& vertices = side.map().vertices;
    LineGroups groups;
    double scale = 0;
    for (const Point p : vertices) scale = std::max({scale, std::abs(p.x), std::abs(p.y)});
    struct Keyed {
        std::uint64_t key;  // a hash of the rounded line: buckets that collide are split below
        std::uint32_t segment;
    };
    std::vector<Keyed> keyed;
    keyed.reserve(side.segments());
    for (std::uint32_t d = 0; d < side.segments(); ++d) {
        Point a = vertices[2 * d], b = vertices[2 * d + 1];
        if (std::tie(b.x, b.y) < std::tie(a.x, a.y)) std::swap(a, b);
        const double dx = b.x - a.x, dy = b.y - a.y;
        if (dx == 0 && dy == 0) continue;  // a point lies on no one line
        // The direction scaled so that its larger component is ±1, and the line's offset from
        // the origin in the same scale, against the coordinates' size.
        const double m = std::max(std::abs(dx), std::abs(dy)), ux = dx / m, uy = dy / m;
        const double offset = (a.x * uy - a.y * ux) / scale;
        if (!std::isfinite(ux) || !std::isfinite(uy) || !std::isfinite(offset)) continue;  // (overflow: tested pairwise)
        constexpr double kSteps = 0x1p30;
        auto word = [&](double value) { return static_cast<std::uint64_t>(std::llround(value * kSteps)); };
        keyed.push_back({map::hash_words({word(ux), word(uy), word(offset)}), d});
    }
    std::sort(keyed.begin(), keyed.end(),
              [](const Keyed& x, const Keyed& y) { return std::tie(x.key, x.segment) < std::tie(y.key, y.segment); });
    std::vector<std::uint32_t> open, rest, group;
    for (std::size_t k = 0; k < keyed.size();) {
        std::size_t end = k + 1;
        while (end < keyed.size() && keyed[end].key == keyed[k].key) ++end;
        open.clear();
        if (end - k >= kMinGroup) {
            for (std::size_t i = k; i < end; ++i) open.push_back(keyed[i].segment);
        }
        k = end;
        // A bucket of many distinct lines (made to be, most likely) leaves the rest pairwise.
        for (int tries = 0; open.size() >= kMinGroup && tries < 16; ++tries) {
            const Point p = vertices[2 * open[0]], q = vertices[2 * open[0] + 1];
            group.assign(1, open[0]);
            rest.clear();
            for (std::size_t i = 1; i < open.size(); ++i) {
                const Point r = vertices[2 * open[i]], u = vertices[2 * open[i] + 1];
                const bool on_line = exact::orient2d(p, q, r, stats) == 0 && exact::orient2d(p, q, u, stats) == 0;
                (on_line ? group : rest).push_back(open[i]);
            }
            if (group.size() >= kMinGroup) {
                if (groups.line_of.empty()) groups.line_of.assign(vertices.size(), map::kNoLine);
                for (const std::uint32_t d : group) groups.line_of[2 * d] = static_cast<std::uint32_t>(groups.members.size());
                groups.members.push_back(group);
            }
            open.swap(rest);
        }
    }
    return groups;
}

std::unordered_map<PairKey, PairContacts, PairHash> count_contacts(const Linework& side, exact::PredicateStats& stats) {
    std::unordered_map<PairKey, PairContacts, PairHash> pairs;
    auto add = [&](std::uint32_t a, std::uint32_t b, std::uint64_t times, const map::SegmentContact& contact) {
        if (times == 0) return;
        PairContacts& entry = pairs[{std::min(a, b), std::max(a, b)}];
        const auto kind = static_cast<std::size_t>(contact.kind);
        if (entry.count[kind] == 0) entry.first[kind] = contact;
        entry.count[kind] += times;
    };
    // Copies of one segment: identical to each other, when a segment meets itself improperly
    // (anything but a point, which is only its own ends).
    for (std::uint32_t d = 0; d < side.segments(); ++d) {
        const std::uint32_t v = 2 * d;
        const Point p = side.map().vertices[v], q = side.map().vertices[v + 1];
        if (!exact::improper_contact(p, q, p, q, exact::Arithmetic::exact, stats)) continue;
        const map::SegmentContact itself{v, v, map::ContactKind::identical};
        const std::span<const Linework::Member> list = side.members(d);
        for (std::size_t i = 0; i < list.size(); ++i) {
            add(list[i].feature, list[i].feature, std::uint64_t{list[i].times} * (list[i].times - 1) / 2, itself);
            for (std::size_t j = i + 1; j < list.size(); ++j) add(list[i].feature, list[j].feature, std::uint64_t{list[i].times} * list[j].times, itself);
        }
    }
    // Distinct segments that meet: every copy of one meets every copy of the other.
    const LineGroups lines = find_line_groups(side, stats);
    for (const map::SegmentContact& contact : map::find_segment_contacts(side.map(), exact::Arithmetic::exact, stats, 0, lines.line_of)) {
        for (const Linework::Member& a : side.members(contact.s / 2)) {
            for (const Linework::Member& b : side.members(contact.t / 2)) add(a.feature, b.feature, std::uint64_t{a.times} * b.times, contact);
        }
    }
    // Distinct segments of one line meet (improperly) where they overlap by more than a point:
    // meeting in one point, that is an end of both. A sweep along the line (along x, or y if it
    // is upright: every point of the line has its own): a segment starting meets every segment
    // still open (ends go before starts at one place), counted per feature by its open copies.
    struct Open {
        std::uint64_t times = 0;
        std::vector<std::uint32_t> segments;  // as opened; the closed are dropped from the back when met
    };
    struct Event {
        double at;
        bool starts;
        std::uint32_t segment;
    };
    const auto& vertices = side.map().vertices;
    for (const std::vector<std::uint32_t>& group : lines.members) {
        const bool upright = vertices[2 * group[0]].x == vertices[2 * group[0] + 1].x;
        std::vector<Event> events;
        for (const std::uint32_t d : group) {
            const Point p = vertices[2 * d], q = vertices[2 * d + 1];
            const double a = upright ? p.y : p.x, b = upright ? q.y : q.x;
            events.push_back({std::min(a, b), true, d});
            events.push_back({std::max(a, b), false, d});
        }
        std::sort(events.begin(), events.end(), [](const Event& x, const Event& y) {
            return std::tie(x.at, x.starts, x.segment) < std::tie(y.at, y.starts, y.segment);
        });
        std::unordered_map<std::uint32_t, Open> open;
        std::vector<std::uint32_t> open_features;  // those with copies open, in the order they opened
        std::unordered_set<std::uint32_t> closed;
        for (const Event& event : events) {
            const std::span<const Linework::Member> list = side.members(event.segment);
            if (!event.starts) {
                closed.insert(event.segment);
                for (const Linework::Member& m : list) {
                    if ((open[m.feature].times -= m.times) == 0) std::erase(open_features, m.feature);
                }
                continue;
            }
            for (const std::uint32_t g : open_features) {
                Open& other = open[g];
                while (closed.contains(other.segments.back())) other.segments.pop_back();
                const std::uint32_t met = other.segments.back();
                const map::SegmentContact contact{2 * std::min(event.segment, met), 2 * std::max(event.segment, met), map::ContactKind::touching};
                for (const Linework::Member& m : list) add(m.feature, g, m.times * other.times, contact);  // (other.times: 64 bits)
            }
            for (const Linework::Member& m : list) {
                Open& mine = open[m.feature];
                if (mine.times == 0) open_features.push_back(m.feature);
                mine.times += m.times;
                mine.segments.push_back(event.segment);
            }
        }
    }
    return pairs;
}

// One comparison, phase by phase: match the features, then per feature (lost, parts, subset,
// rings, validity), then the contacts between every pair of features, then the control points,
// and last the report's order.
class Checker {
public:
    explicit Checker(const CheckOptions& options) : options_(options), matches_vertex_(options.grid) {}

    CheckReport run() {
        match_features();
        check_features();
        check_contacts();
        if (!options_.points.empty()) {
            const std::vector<Point> points = io::read_control_points(options_.points);
            report_.control_points = points.size();
            check_points_in_polygons(points);
            check_points_beside_lines(points);
        }
        sort_report();
        return std::move(report_);
    }

private:
    void violation(ViolationKind kind, const std::string& layer, const std::string& feature, Point where, std::string detail,
                   std::string decided_by = "exact", std::string other = {}) {
        report_.violations.push_back({kind, layer, feature, std::move(other), where.x, where.y, std::move(detail), std::move(decided_by)});
    }
    const std::string& layer_of(std::size_t m) const { return original_[matched_[m].layer].name; }

    // Layers by name (or the only one to the only one), features by key or order.
    void match_features() {
        original_ = read_layers(options_.original, options_.layers, options_.key);
        // The control points' own layer, when -p names one in the original (ORIG:points), is not
        // compared: it need not be in the simplified file (issue 29).
        if (options_.layers.empty() && !options_.points.empty() && original_.size() > 1) {
            const io::PointsSpec points = io::split_points_spec(options_.points);
            std::error_code error;
            if (!points.layer.empty() && std::filesystem::equivalent(points.path, options_.original, error)) {
                std::erase_if(original_, [&](const Layer& layer) { return layer.name == points.layer; });
            }
        }
        if (options_.simplified_layer.empty()) {
            simplified_ = read_layers(options_.simplified, {}, options_.key);
        } else {
            if (original_.size() != 1) {
                throw InputError("--simplified-layer compares one layer, and the original has several: name one with -l");
            }
            simplified_ = read_layers(options_.simplified, {options_.simplified_layer}, options_.key);
            simplified_.front().name = original_.front().name;  // matched whatever it is called
        }
        for (std::size_t l = 0; l < original_.size(); ++l) {
            const Layer* target = nullptr;
            for (const Layer& candidate : simplified_) {
                if (candidate.name == original_[l].name) target = &candidate;
            }
            if (target == nullptr && original_.size() == 1 && simplified_.size() == 1) target = &simplified_.front();
            if (target == nullptr) {
                throw InputError("'" + options_.simplified + "' has no layer '" + original_[l].name + "' (name the layers with -l)");
            }
            std::unordered_map<std::string, const Feature*> by_key;
            for (const Feature& feature : target->features) by_key.emplace(feature.key, &feature);
            // Matched by order from a TopoJSON: the simplified features are the original's with
            // a geometry (Layer::without_nulls), each the next of those.
            const bool by_order_without_nulls = options_.key.empty() && target->without_nulls;
            std::size_t next = 0;
            for (const Feature& feature : original_[l].features) {
                if (by_order_without_nulls && !feature.has_geometry) {
                    matched_.push_back({l, &feature, nullptr});
                    continue;
                }
                const auto found = by_key.find(by_order_without_nulls ? std::to_string(next++) : feature.key);
                matched_.push_back({l, &feature, found == by_key.end() ? nullptr : found->second});
            }
        }
        report_.features = matched_.size();
    }

    // Per feature: lost, parts, subset, rings, validity. Keeps where each simplified line's
    // vertices are in the original (line_matches_), for the control points.
    void check_features() {
        line_matches_.resize(matched_.size());
        for (std::size_t m = 0; m < matched_.size(); ++m) {
            const Feature& before = *matched_[m].original;
            const Feature* after = matched_[m].simplified;
            const std::string& layer = layer_of(m);
            const Point somewhere = before.parts.empty() || before.parts[0].empty() ? Point{0, 0} : before.parts[0][0];
            if (before.parts.empty()) continue;  // nothing to lose
            if (after == nullptr || after->parts.empty()) {
                violation(ViolationKind::feature_lost, layer, before.key, somewhere, after ? "geometry is empty" : "no such feature");
                continue;
            }
            if (after->parts.size() != before.parts.size() || after->rings_per_polygon != before.rings_per_polygon) {
                violation(ViolationKind::parts_changed, layer, before.key, somewhere,
                          std::to_string(before.parts.size()) + " parts became " + std::to_string(after->parts.size()));
                continue;
            }
            auto& matches = line_matches_[m];
            matches.resize(before.parts.size());
            for (std::size_t k = 0; k < before.parts.size(); ++k) {
                const auto& a = before.parts[k];
                const auto& b = after->parts[k];
                if (before.type == Feature::Type::polygons) {
                    const RingMatch match = match_ring(a, b, matches_vertex_);
                    if (!match.any()) {
                        violation(ViolationKind::not_subset, layer, before.key, b.empty() ? somewhere : b[0], "ring " + std::to_string(k));
                        continue;
                    }
                    if (b.size() < 4 || distinct_locations(b) < 3 || area_sign(b) == 0) {
                        violation(ViolationKind::ring_collapsed, layer, before.key, b[0],
                                  "ring " + std::to_string(k) + " has " + std::to_string(b.size()) + " vertices");
                    } else if (!(match.forwards && area_sign(b) == area_sign(a)) && !(match.backwards && area_sign(b) == -area_sign(a))) {
                        // (Flipped: no way it runs along the original turns as the original does.)
                        violation(ViolationKind::ring_flipped, layer, before.key, b[0], "ring " + std::to_string(k));
                    }
                } else if (!match_line(a, b, matches[k], matches_vertex_)) {
                    violation(ViolationKind::not_subset, layer, before.key, b.empty() ? somewhere : b[0], "line " + std::to_string(k));
                    matches[k].clear();
                }
            }
            if (before.type == Feature::Type::polygons && after->has_geometry) {
                Point where{};
                auto invalid = [&](const Feature& feature) {
                    return feature.geometry ? geos_.invalid_reason(*feature.geometry, where)
                                            : geos_.invalid_reason(feature.parts, feature.rings_per_polygon, where);
                };
                if (invalid(before)) {
                    ++report_.invalid_in_original;
                } else if (const auto reason = invalid(*after)) {
                    violation(ViolationKind::invalid_polygon, layer, before.key, where, *reason, "GEOS");
                }
            }
        }
    }

    // Contacts between every pair of features, before and after: crossings, touchings and
    // shared segments that appeared or vanished.
    void check_contacts() {
        Linework before_lines, after_lines;
        auto segments_of = [](const Feature& feature) {
            std::size_t count = 0;
            for (const auto& part : feature.parts) count += part.empty() ? 0 : part.size() - 1;
            return count;
        };
        std::size_t before_count = 0, after_count = 0;
        for (const Matched& m : matched_) {
            before_count += segments_of(*m.original);
            if (m.simplified) after_count += segments_of(*m.simplified);
        }
        before_lines.reserve(before_count);
        after_lines.reserve(after_count);
        for (std::uint32_t m = 0; m < matched_.size(); ++m) {
            before_lines.add(*matched_[m].original, m);
            if (matched_[m].simplified) after_lines.add(*matched_[m].simplified, m);
        }
        before_lines.finish();
        after_lines.finish();
        const auto before_pairs = count_contacts(before_lines, stats_);
        const auto after_pairs = count_contacts(after_lines, stats_);
        auto location = [&](const Linework& side, const map::SegmentContact& c) {
            const auto& v = side.map().vertices;
            return geos_.meeting_point(v[c.s], v[c.s + 1], v[c.t], v[c.t + 1]);
        };
        auto name_of = [&](std::uint32_t m) { return matched_[m].original->key; };
        auto compare = [&](const auto& pairs, const auto& others, bool after_side) {
            for (const auto& [pair, contacts] : pairs) {
                const auto other = others.find(pair);
                for (std::size_t kind = 0; kind < 3; ++kind) {
                    const std::uint64_t here = contacts.count[kind];
                    const std::uint64_t there = other == others.end() ? 0 : other->second.count[kind];
                    // Where: computed only for a pair that is reported.
                    const auto where = [&] { return location(after_side ? after_lines : before_lines, contacts.first[kind]); };
                    const std::string counts = std::to_string(after_side ? there : here) + " before, " +
                                               std::to_string(after_side ? here : there) + " after";
                    if (kind == static_cast<std::size_t>(map::ContactKind::identical)) {
                        // Shared segments: only appearing (coincidence) or vanishing (border split) matters.
                        if (here > 0 && there == 0) {
                            violation(after_side ? ViolationKind::new_coincidence : ViolationKind::border_no_longer_shared,
                                      layer_of(pair.first), name_of(pair.first), where(), counts + " shared segments", "exact",
                                      name_of(pair.second));
                        }
                    } else if (here > there) {
                        const bool crossing = kind == static_cast<std::size_t>(map::ContactKind::crossing);
                        const ViolationKind what = after_side ? (crossing ? ViolationKind::new_crossing : ViolationKind::new_touching)
                                                              : (crossing ? ViolationKind::lost_crossing : ViolationKind::lost_touching);
                        violation(what, layer_of(pair.first), name_of(pair.first), where(), counts, "exact", name_of(pair.second));
                    }
                }
            }
        };
        compare(after_pairs, before_pairs, true);
        compare(before_pairs, after_pairs, false);
    }

    // Control points and polygons: each point in the same polygon (inside, on its boundary or
    // outside) before and after.
    void check_points_in_polygons(const std::vector<Point>& points) {
        // Long rings are indexed the first time a point is located in them (the same answers).
        std::unordered_map<const std::vector<Point>*, exact::RingLocator> locators;
        auto locate_in = [&](const std::vector<Point>& ring, Point p) {
            if (ring.size() < kIndexedRing) return exact::locate_in_ring(ring, p, stats_);
            auto found = locators.find(&ring);
            if (found == locators.end()) found = locators.emplace(&ring, exact::RingLocator(ring)).first;
            return found->second.locate(p, stats_);
        };
        auto locate = [&](const Feature& feature, Point p) {
            // 2 inside, 1 on the boundary, 0 outside (polygon = exterior minus holes; any polygon).
            int best = 0;
            std::size_t ring = 0;
            for (const std::uint32_t rings : feature.rings_per_polygon) {
                int here = 0;
                for (std::uint32_t r = 0; r < rings; ++r, ++ring) {
                    const auto at = locate_in(feature.parts[ring], p);
                    if (r == 0) here = at == exact::RingLocation::inside ? 2 : at == exact::RingLocation::boundary ? 1 : 0;
                    else if (here == 2 && at == exact::RingLocation::boundary) here = 1;
                    else if (here == 2 && at == exact::RingLocation::inside) here = 0;
                }
                best = std::max(best, here);
            }
            return best;
        };
        // Bounding boxes of polygon features, for a quick reject before the exact test.
        std::vector<Box> boxes(matched_.size(), Box{INFINITY, INFINITY, -INFINITY, -INFINITY});
        for (std::size_t m = 0; m < matched_.size(); ++m) {
            for (const Feature* f : {matched_[m].original, matched_[m].simplified}) {
                if (f == nullptr || f->type != Feature::Type::polygons) continue;
                for (const auto& part : f->parts) {
                    for (const Point q : part) {
                        boxes[m] = {std::min(boxes[m].min_x, q.x), std::min(boxes[m].min_y, q.y), std::max(boxes[m].max_x, q.x),
                                    std::max(boxes[m].max_y, q.y)};
                    }
                }
            }
        }
        // Candidate polygons per point from a uniform grid over their boxes.
        std::vector<std::size_t> polygons;
        Box extent{INFINITY, INFINITY, -INFINITY, -INFINITY};
        for (std::size_t m = 0; m < matched_.size(); ++m) {
            if (matched_[m].original->type != Feature::Type::polygons || !(boxes[m].min_x <= boxes[m].max_x)) continue;
            polygons.push_back(m);
            extent = {std::min(extent.min_x, boxes[m].min_x), std::min(extent.min_y, boxes[m].min_y),
                      std::max(extent.max_x, boxes[m].max_x), std::max(extent.max_y, boxes[m].max_y)};
        }
        const std::size_t side = std::clamp<std::size_t>(static_cast<std::size_t>(std::sqrt(static_cast<double>(polygons.size()))), 1, 1024);
        auto cell = [&](double value, double lo, double hi) {
            const double t = hi > lo ? (value - lo) / (hi - lo) * static_cast<double>(side) : 0.0;
            return std::min(side - 1, static_cast<std::size_t>(std::max(0.0, t)));
        };
        std::vector<std::vector<std::size_t>> cells(side * side);
        for (const std::size_t m : polygons) {
            for (std::size_t y = cell(boxes[m].min_y, extent.min_y, extent.max_y); y <= cell(boxes[m].max_y, extent.min_y, extent.max_y); ++y) {
                for (std::size_t x = cell(boxes[m].min_x, extent.min_x, extent.max_x); x <= cell(boxes[m].max_x, extent.min_x, extent.max_x); ++x) {
                    cells[y * side + x].push_back(m);
                }
            }
        }
        for (const Point p : points) {
            if (polygons.empty()) break;
            if (!box_contains(extent, p)) continue;
            for (const std::size_t m : cells[cell(p.y, extent.min_y, extent.max_y) * side + cell(p.x, extent.min_x, extent.max_x)]) {
                if (!box_contains(boxes[m], p)) continue;
                const int before = locate(*matched_[m].original, p);
                const int after = matched_[m].simplified ? locate(*matched_[m].simplified, p) : 0;
                if (before != after) {
                    static const char* names[] = {"outside", "on the boundary", "inside"};
                    violation(ViolationKind::point_changed_polygon, layer_of(m), matched_[m].original->key, p,
                              std::string("was ") + names[before] + ", now " + names[after]);
                }
            }
        }
    }

    // Control points and lines: no point in the detour a removed stretch of a line sweeps.
    void check_points_beside_lines(const std::vector<Point>& points) {
        // Lines: a removed stretch a…b sweeps the detour a…b + segment b→a; no point may be in it.
        const map::PointGrid grid(points);
        for (std::size_t m = 0; m < matched_.size(); ++m) {
            const Feature& before = *matched_[m].original;
            if (before.type != Feature::Type::lines) continue;
            for (std::size_t k = 0; k < line_matches_[m].size(); ++k) {
                const auto& at = line_matches_[m][k];
                const std::vector<Point>& output = matched_[m].simplified->parts[k];
                for (std::size_t i = 0; i + 1 < at.size(); ++i) {
                    // The original stretch, closed by the output segment (ends moved, when
                    // rounded: the stretch and the segment then bound what the move swept).
                    const Point a = before.parts[k][at[i]], b = before.parts[k][at[i + 1]];
                    const Point a_out = output[i], b_out = output[i + 1];
                    const bool moved = !same_location(a, a_out) || !same_location(b, b_out);
                    if (at[i + 1] <= at[i] + 1 && !moved) continue;
                    std::vector<Point> detour(before.parts[k].begin() + static_cast<std::ptrdiff_t>(at[i]),
                                              before.parts[k].begin() + static_cast<std::ptrdiff_t>(at[i + 1]) + 1);
                    if (!same_location(b, b_out)) detour.push_back(b_out);
                    if (!same_location(a, a_out)) detour.push_back(a_out);
                    detour.push_back(a);
                    Box box{INFINITY, INFINITY, -INFINITY, -INFINITY};
                    for (const Point q : detour) box = {std::min(box.min_x, q.x), std::min(box.min_y, q.y), std::max(box.max_x, q.x), std::max(box.max_y, q.y)};
                    // A long detour that many points fall in is indexed (the same answers).
                    std::optional<exact::RingLocator> locator;
                    std::size_t located = 0;
                    auto locate = [&](Point q) {
                        if (!locator && detour.size() >= kIndexedRing && ++located > kIndexedAfter) locator.emplace(detour);
                        return locator ? locator->locate(q, stats_) : exact::locate_in_ring(detour, q, stats_);
                    };
                    grid.any_in_cells(box, [&](std::uint32_t, Point q) {
                        // A point at an end that stayed is on the line before and after.
                        if (!box_contains(box, q) || (same_location(q, a) && same_location(a, a_out)) ||
                            (same_location(q, b) && same_location(b, b_out))) {
                            return false;
                        }
                        if (locate(q) != exact::RingLocation::outside) {
                            violation(ViolationKind::point_changed_side, layer_of(m), before.key, q,
                                      std::string(moved ? "swept by the rounded segment standing for vertices "
                                                        : "swept by the segment replacing vertices ") +
                                          std::to_string(at[i]) + "…" + std::to_string(at[i + 1]) + " of line " + std::to_string(k));
                        }
                        return false;
                    });
                }
            }
        }
    }

    // Report order: by kind as listed, then layer, feature, other feature and place — a total
    // order, so the report does not depend on hash-map iteration.
    void sort_report() {
        std::sort(report_.violations.begin(), report_.violations.end(), [](const Violation& a, const Violation& b) {
            return std::tie(a.kind, a.layer, a.feature, a.other, a.x, a.y, a.detail) <
                   std::tie(b.kind, b.layer, b.feature, b.other, b.x, b.y, b.detail);
        });
    }

    const CheckOptions& options_;
    VertexMatch matches_vertex_;
    std::vector<Layer> original_, simplified_;
    std::vector<Matched> matched_;
    std::vector<std::vector<std::vector<std::size_t>>> line_matches_;  // per feature, per line: original index of each vertex
    CheckReport report_;
    Geos geos_;
    exact::PredicateStats stats_;
};

}  // namespace

namespace {

// The grid of a quantized TopoJSON, from its "transform" member: nullopt if `path` is no such
// file. A light scan, not a JSON parser: toposimp and the common tools write the member as
// {"scale":[kx,ky],"translate":[dx,dy]} (either order).
std::optional<map::OutputGrid> topojson_grid(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
    if (extension != ".topojson") return std::nullopt;
    std::ifstream in(path, std::ios::binary);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::size_t at = text.find("\"transform\"");
    if (at == std::string::npos) return std::nullopt;
    auto pair_after = [&](const char* key) -> std::optional<std::array<double, 2>> {
        const std::size_t found = text.find(key, at);
        if (found == std::string::npos || found > at + 400) return std::nullopt;
        std::size_t p = text.find('[', found);
        std::array<double, 2> values{};
        for (double& value : values) {
            if (p == std::string::npos) return std::nullopt;
            ++p;
            while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
            const auto result = std::from_chars(text.data() + p, text.data() + text.size(), value);
            if (result.ec != std::errc()) return std::nullopt;
            p = text.find_first_of(",]", static_cast<std::size_t>(result.ptr - text.data()));
        }
        return values;
    };
    const auto scale = pair_after("\"scale\""), translate = pair_after("\"translate\"");
    if (!scale || !translate || !((*scale)[0] > 0) || !((*scale)[1] > 0)) {
        throw InputError("'" + path + "': its \"transform\" is not {\"scale\":[kx,ky],\"translate\":[dx,dy]} with positive scales");
    }
    return map::OutputGrid(map::AxisGrid::quantized((*scale)[0], (*translate)[0]), map::AxisGrid::quantized((*scale)[1], (*translate)[1]));
}

}  // namespace

CheckReport check(const CheckOptions& options) {
    if (!options.grid) {
        if (std::optional<map::OutputGrid> grid = topojson_grid(options.simplified)) {
            CheckOptions quantized = options;
            quantized.grid = grid;
            return Checker(quantized).run();
        }
    }
    return Checker(options).run();
}

CheckReport check(const io::MemoryLayers& original, const io::MemoryLayers& simplified, const io::MemoryLayers* points,
                  CheckOptions options) {
    static std::atomic<unsigned> calls{0};
    const std::string folder = "/vsimem/toposimp_check_" + std::to_string(calls++);
    struct Remove {
        const std::string& folder;
        ~Remove() { VSIRmdirRecursive(folder.c_str()); }
    } remove{folder};
    options.original = folder + "/original.gpkg";
    options.simplified = folder + "/simplified.gpkg";
    io::write_geopackage(original, options.original);
    io::write_geopackage(simplified, options.simplified);
    if (points) {
        options.points = folder + "/points.gpkg";
        io::write_geopackage(*points, options.points);
    }
    return check(options);
}

}  // namespace toposimp::validate
