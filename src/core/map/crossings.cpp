#include "core/map/crossings.hpp"

#include "core/exact/segments.hpp"

#include <algorithm>
#include <cmath>

namespace toposimp::map {
namespace {

// A uniform grid of segment boxes, stored compactly (counting sort, no per-cell allocation).
class SegmentGrid {
public:
    SegmentGrid(const MapData& map, const std::vector<std::uint32_t>& segments) : map_(map) {
        Box bounds{INFINITY, INFINITY, -INFINITY, -INFINITY};
        for (const Point& p : map.vertices) {
            bounds = {std::min(bounds.min_x, p.x), std::min(bounds.min_y, p.y), std::max(bounds.max_x, p.x),
                      std::max(bounds.max_y, p.y)};
        }
        const double width = bounds.max_x - bounds.min_x, height = bounds.max_y - bounds.min_y;
        const double side = std::clamp(std::floor(std::sqrt(static_cast<double>(segments.size()) / 2.0)), 1.0, 4096.0);
        columns_ = static_cast<std::uint32_t>(side);
        rows_ = columns_;
        origin_x_ = bounds.min_x;
        origin_y_ = bounds.min_y;
        scale_x_ = width > 0 ? columns_ / width : 0.0;
        scale_y_ = height > 0 ? rows_ / height : 0.0;

        cell_start_.assign(std::size_t{columns_} * rows_ + 1, 0);
        for_each_registration(segments, [&](std::size_t cell, std::uint32_t) { ++cell_start_[cell + 1]; });
        for (std::size_t c = 0; c + 1 < cell_start_.size(); ++c) cell_start_[c + 1] += cell_start_[c];
        entries_.resize(cell_start_.back());
        std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
        for_each_registration(segments, [&](std::size_t cell, std::uint32_t v) { entries_[fill[cell]++] = v; });
    }

    Box box_of(std::uint32_t v) const { return segment_box(map_.vertices[v], map_.vertices[v + 1]); }

    std::size_t cell_of(double x, double y) const { return std::size_t{row(y)} * columns_ + column(x); }

    std::size_t cell_count() const { return cell_start_.size() - 1; }

    template <class Visit>
    void for_each_in_cell(std::size_t cell, Visit&& visit) const {
        for (std::size_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) visit(k, entries_[k]);
    }

    std::uint32_t entry(std::size_t k) const { return entries_[k]; }
    std::size_t cell_end(std::size_t cell) const { return cell_start_[cell + 1]; }

private:
    static Box segment_box(Point a, Point b) {
        return {std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.x, b.x), std::max(a.y, b.y)};
    }

    static std::uint32_t index(double value, double origin, double scale, std::uint32_t count) {
        double t = (value - origin) * scale;
        if (!(t >= 0.0)) t = 0.0;
        if (t >= static_cast<double>(count)) return count - 1;
        return static_cast<std::uint32_t>(t);
    }
    std::uint32_t column(double x) const { return index(x, origin_x_, scale_x_, columns_); }
    std::uint32_t row(double y) const { return index(y, origin_y_, scale_y_, rows_); }

    template <class Register>
    void for_each_registration(const std::vector<std::uint32_t>& segments, Register&& add) const {
        for (const std::uint32_t v : segments) {
            const Box box = box_of(v);
            for (std::uint32_t y = row(box.min_y); y <= row(box.max_y); ++y) {
                for (std::uint32_t x = column(box.min_x); x <= column(box.max_x); ++x) add(std::size_t{y} * columns_ + x, v);
            }
        }
    }

    const MapData& map_;
    double origin_x_ = 0, origin_y_ = 0, scale_x_ = 0, scale_y_ = 0;
    std::uint32_t columns_ = 1, rows_ = 1;
    std::vector<std::size_t> cell_start_;
    std::vector<std::uint32_t> entries_;
};

}  // namespace

std::vector<SegmentContact> find_segment_contacts(const MapData& map, exact::Arithmetic arithmetic,
                                                  exact::PredicateStats& stats) {
    std::vector<SegmentContact> contacts;
    std::vector<std::uint32_t> segments;  // each named by its first vertex
    for (const Chain& chain : map.chains) {
        for (std::uint32_t v = chain.first; v < chain.last; ++v) segments.push_back(v);
    }
    if (segments.size() < 2) return contacts;
    const SegmentGrid grid(map, segments);
    const auto cells = static_cast<std::ptrdiff_t>(grid.cell_count());
#pragma omp parallel if (segments.size() >= 1 << 14)
    {
        std::vector<SegmentContact> found;
        exact::PredicateStats counted;
        std::vector<std::pair<Box, std::uint32_t>> here;  // the cell's segments by left edge
#pragma omp for schedule(dynamic, 256) nowait
        for (std::ptrdiff_t cell = 0; cell < cells; ++cell) {
            here.clear();
            grid.for_each_in_cell(static_cast<std::size_t>(cell), [&](std::size_t, std::uint32_t s) {
                here.emplace_back(grid.box_of(s), s);
            });
            if (here.size() < 2) continue;
            std::sort(here.begin(), here.end(), [](const auto& a, const auto& b) {
                return a.first.min_x < b.first.min_x || (a.first.min_x == b.first.min_x && a.second < b.second);
            });
            for (std::size_t i = 0; i < here.size(); ++i) {
                const auto& [sb, s] = here[i];
                // Only boxes starting before this one ends can overlap it in x.
                for (std::size_t j = i + 1; j < here.size() && here[j].first.min_x <= sb.max_x; ++j) {
                    const auto& [tb, t] = here[j];
                    // Test each pair once: in the cell holding the low corner of the boxes' overlap.
                    const double x = std::max(sb.min_x, tb.min_x), y = std::max(sb.min_y, tb.min_y);
                    if (x > std::min(sb.max_x, tb.max_x) || y > std::min(sb.max_y, tb.max_y)) continue;
                    if (grid.cell_of(x, y) != static_cast<std::size_t>(cell)) continue;
                    const Point p = map.vertices[s], q = map.vertices[s + 1], r = map.vertices[t], u = map.vertices[t + 1];
                    if (!exact::improper_contact(p, q, r, u, arithmetic, counted)) continue;
                    ContactKind kind = ContactKind::touching;
                    if ((same_location(p, r) && same_location(q, u)) || (same_location(p, u) && same_location(q, r))) {
                        kind = ContactKind::identical;
                    } else if (exact::proper_crossing(p, q, r, u, arithmetic, counted)) {
                        kind = ContactKind::crossing;
                    }
                    found.push_back({std::min(s, t), std::max(s, t), kind});
                }
            }
        }
#pragma omp critical(toposimp_segment_contacts)
        {
            contacts.insert(contacts.end(), found.begin(), found.end());
            stats += counted;
        }
    }
    // Sorted, so the result does not depend on which thread found what.
    std::sort(contacts.begin(), contacts.end(), [](const SegmentContact& a, const SegmentContact& b) {
        return a.s < b.s || (a.s == b.s && a.t < b.t);
    });
    return contacts;
}

std::vector<std::uint8_t> find_improper_segments(const MapData& map, exact::Arithmetic arithmetic,
                                                 exact::PredicateStats& stats) {
    std::vector<std::uint8_t> improper(map.vertices.size(), 0);
    for (const SegmentContact& contact : find_segment_contacts(map, arithmetic, stats)) {
        improper[contact.s] = improper[contact.t] = 1;
    }
    return improper;
}

}  // namespace toposimp::map
