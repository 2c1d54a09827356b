#include "python/parts.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace toposimp::python {

namespace {

[[noreturn]] void malformed(const std::string& what) {
    throw py::value_error("toposimp: a tile task's data is malformed: " + what);
}

template <class T>
py::array_t<T> array_of(const std::vector<T>& values) {
    py::array_t<T> array(static_cast<py::ssize_t>(values.size()));
    if (!values.empty()) std::memcpy(array.mutable_data(), values.data(), values.size() * sizeof(T));
    return array;
}

py::array_t<double> points_array(const std::vector<Point>& points) {
    py::array_t<double> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{2}});
    double* out = array.mutable_data();
    for (std::size_t k = 0; k < points.size(); ++k) {
        out[2 * k] = points[k].x;
        out[2 * k + 1] = points[k].y;
    }
    return array;
}

py::array_t<std::uint32_t> pairs_array(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs) {
    py::array_t<std::uint32_t> array({static_cast<py::ssize_t>(pairs.size()), py::ssize_t{2}});
    std::uint32_t* out = array.mutable_data();
    for (std::size_t k = 0; k < pairs.size(); ++k) {
        out[2 * k] = pairs[k].first;
        out[2 * k + 1] = pairs[k].second;
    }
    return array;
}

py::object item(const py::dict& dict, const char* key) {
    if (!dict.contains(key)) malformed(std::string("no '") + key + "'");
    return dict[key];
}

// A 1-D array of `width`-tuples (width 1: a plain array) of T, checked, in C order.
template <class T>
py::array_t<T, py::array::c_style | py::array::forcecast> checked(const py::dict& dict, const char* key, std::size_t width) {
    auto array = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(item(dict, key));
    if (!array) malformed(std::string("'") + key + "' is not an array of numbers");
    const bool shaped = width == 1 ? array.ndim() == 1 : array.ndim() == 2 && array.shape(1) == static_cast<py::ssize_t>(width);
    if (!shaped && array.size() != 0) malformed(std::string("'") + key + "' has the wrong shape");
    return array;
}

// Such an array as a flat vector.
template <class T>
std::vector<T> flat(const py::dict& dict, const char* key, std::size_t width = 1) {
    const auto array = checked<T>(dict, key, width);
    return std::vector<T>(array.data(), array.data() + array.size());
}

// An array of (x, y) as points, or of pairs as pairs: one copy, straight from the array.
std::vector<Point> points_of(const py::dict& dict, const char* key) {
    const auto array = checked<double>(dict, key, 2);
    std::vector<Point> points(static_cast<std::size_t>(array.size()) / 2);
    const double* in = array.data();
    for (std::size_t k = 0; k < points.size(); ++k) points[k] = {in[2 * k], in[2 * k + 1]};
    return points;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_of(const py::dict& dict, const char* key) {
    const auto array = checked<std::uint32_t>(dict, key, 2);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs(static_cast<std::size_t>(array.size()) / 2);
    const std::uint32_t* in = array.data();
    for (std::size_t k = 0; k < pairs.size(); ++k) pairs[k] = {in[2 * k], in[2 * k + 1]};
    return pairs;
}

py::dict tile_dict(map::TileInput&& tile) {
    py::dict dict;
    dict["level"] = tile.level;
    dict["column"] = tile.column;
    dict["row"] = tile.row;
    dict["vertices"] = points_array(tile.map.vertices);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> chains;
    for (const map::Chain& chain : tile.map.chains) chains.emplace_back(chain.first, chain.last);
    dict["chains"] = pairs_array(chains);
    dict["control_points"] = points_array(tile.map.control_points);
    dict["vertex_id"] = array_of(tile.vertex_id);
    dict["state"] = array_of(tile.state);
    dict["marked"] = array_of(tile.marked);
    dict["chain_id"] = array_of(tile.chain_id);
    dict["whole_level"] = array_of(tile.whole_level);
    dict["settled"] = array_of(tile.settled);
    dict["distinct"] = array_of(tile.distinct);
    dict["orientation"] = array_of(tile.orientation);
    dict["waits"] = pairs_array(tile.waits);
    dict["marks"] = tile.marks;
    dict["bound"] = py::make_tuple(tile.bound_key, tile.bound_id);
    return dict;
}

// A tile dict back, checked to be one: every array the size its structure needs, the chains
// cutting the vertices into consecutive ranges.
map::TileInput tile_of(const py::dict& dict) {
    map::TileInput tile;
    tile.level = item(dict, "level").cast<unsigned>();
    tile.column = item(dict, "column").cast<std::uint32_t>();
    tile.row = item(dict, "row").cast<std::uint32_t>();
    tile.map.vertices = points_of(dict, "vertices");
    tile.map.control_points = points_of(dict, "control_points");
    const std::size_t n = tile.map.vertices.size();
    if (n >= std::numeric_limits<std::uint32_t>::max()) malformed("too many vertices");
    std::size_t next = 0;
    for (const auto& [first, last] : pairs_of(dict, "chains")) {
        if (first != next || last < first || last >= n) malformed("the chains do not cut the vertices into consecutive ranges");
        tile.map.chains.push_back({first, last});
        next = std::size_t{last} + 1;
    }
    if (next != n) malformed("the chains do not cover the vertices");
    tile.vertex_id = flat<std::uint32_t>(dict, "vertex_id");
    tile.state = flat<std::uint8_t>(dict, "state");
    tile.marked = flat<std::uint8_t>(dict, "marked");
    tile.chain_id = flat<std::uint32_t>(dict, "chain_id");
    tile.whole_level = flat<std::uint8_t>(dict, "whole_level");
    tile.settled = flat<std::uint8_t>(dict, "settled");
    tile.distinct = flat<std::uint32_t>(dict, "distinct");
    tile.orientation = flat<std::int8_t>(dict, "orientation");
    tile.waits = pairs_of(dict, "waits");
    tile.marks = item(dict, "marks").cast<bool>();
    std::tie(tile.bound_key, tile.bound_id) = item(dict, "bound").cast<std::pair<double, std::uint32_t>>();
    const std::size_t c = tile.map.chains.size();
    if (tile.vertex_id.size() != n || tile.state.size() != n) malformed("vertex_id or state is not one per vertex");
    if (tile.marked.size() != (tile.marks ? n : 0)) malformed("marked is not one per vertex with marks, none without");
    if (tile.chain_id.size() != c || tile.whole_level.size() != c || tile.settled.size() != c || tile.distinct.size() != c ||
        tile.orientation.size() != c) {
        malformed("chain_id, whole_level, settled, distinct or orientation is not one per chain");
    }
    if (std::any_of(tile.state.begin(), tile.state.end(), [](std::uint8_t s) { return s > static_cast<std::uint8_t>(map::VertexState::removed); })) {
        malformed("a vertex state is not one");
    }
    // (−1, 0, 1; 2: not known; 3 to 5 and 7 to 9: known, not yet counted: core/map/simplify.cpp)
    if (std::any_of(tile.orientation.begin(), tile.orientation.end(), [](std::int8_t o) { return o < -1 || o > 9 || o == 6; })) {
        malformed("an orientation is not one");
    }
    for (const auto& [waiter, blocker] : tile.waits) {
        if (waiter >= n || blocker >= n) malformed("a wait names a vertex the tile has not");
    }
    return tile;
}

py::dict plan_dict(const map::GridPlan& plan) {
    const map::PointGrid::Geometry& g = plan.grid;
    py::dict dict;
    dict["origin"] = py::make_tuple(g.origin_x, g.origin_y);
    dict["scale"] = py::make_tuple(g.scale_x, g.scale_y);
    dict["cells"] = py::make_tuple(g.columns, g.rows);
    dict["base_scale"] = py::make_tuple(g.base_scale_x, g.base_scale_y);
    dict["base_cells"] = py::make_tuple(g.base_columns, g.base_rows);
    dict["row_split"] = g.row_split;
    dict["shift"] = plan.shift;
    dict["levels"] = plan.levels;
    return dict;
}

map::GridPlan plan_of(const py::dict& dict) {
    map::GridPlan plan;
    map::PointGrid::Geometry& g = plan.grid;
    std::tie(g.origin_x, g.origin_y) = item(dict, "origin").cast<std::pair<double, double>>();
    std::tie(g.scale_x, g.scale_y) = item(dict, "scale").cast<std::pair<double, double>>();
    std::tie(g.columns, g.rows) = item(dict, "cells").cast<std::pair<std::uint32_t, std::uint32_t>>();
    std::tie(g.base_scale_x, g.base_scale_y) = item(dict, "base_scale").cast<std::pair<double, double>>();
    std::tie(g.base_columns, g.base_rows) = item(dict, "base_cells").cast<std::pair<std::uint32_t, std::uint32_t>>();
    g.row_split = item(dict, "row_split").cast<unsigned>();
    plan.shift = item(dict, "shift").cast<unsigned>();
    plan.levels = item(dict, "levels").cast<unsigned>();
    if (g.columns == 0 || g.rows == 0 || g.base_columns == 0 || g.base_rows == 0 || g.row_split > 8 || plan.shift > 31 ||
        plan.levels == 0 || plan.levels > 32) {
        malformed("the plan's grid is not one");
    }
    return plan;
}

py::dict options_dict(const map::SimplifyOptions& options) {
    py::dict dict;
    dict["target"] = static_cast<int>(options.stop.target);
    dict["value"] = options.stop.value;
    dict["weighting"] = options.ranking.weighting;
    dict["spherical"] = options.ranking.spherical;
    dict["arithmetic"] = static_cast<int>(options.arithmetic);
    dict["threads"] = options.threads;
    return dict;
}

map::SimplifyOptions options_of(const py::dict& dict) {
    map::SimplifyOptions options;
    const int target = item(dict, "target").cast<int>();
    if (target < static_cast<int>(map::Target::keep_fraction) || target > static_cast<int>(map::Target::max)) {
        malformed("the target is not one");
    }
    options.stop = {static_cast<map::Target>(target), item(dict, "value").cast<double>()};
    options.ranking = {item(dict, "weighting").cast<double>(), item(dict, "spherical").cast<bool>()};
    const int arithmetic = item(dict, "arithmetic").cast<int>();
    if (arithmetic < static_cast<int>(exact::Arithmetic::exact) || arithmetic > static_cast<int>(exact::Arithmetic::floating)) {
        malformed("the arithmetic is not one");
    }
    options.arithmetic = static_cast<exact::Arithmetic>(arithmetic);
    options.threads = item(dict, "threads").cast<int>();
    return options;
}

py::dict outcome_dict(const map::TileOutcome& outcome) {
    py::dict dict;
    dict["ids"] = array_of(outcome.ids);
    dict["states"] = array_of(outcome.states);
    dict["waits"] = pairs_array(outcome.waits);
    dict["oriented"] = array_of(outcome.oriented);
    dict["orientations"] = array_of(outcome.orientations);
    py::list later;
    for (const std::vector<std::uint32_t>& list : outcome.later) later.append(array_of(list));
    dict["later"] = later;
    dict["locations_lost"] = pairs_array(outcome.locations_lost);
    const map::SimplifyStats& s = outcome.stats;
    dict["stats"] = py::make_tuple(s.removed, s.blocked_by_point, s.blocked_by_ring, s.blocked_by_coincidence,
                                   s.predicates.filter_decided, s.predicates.expansion_decided, s.predicates.gmp_fallbacks);
    return dict;
}

// An outcome dict back, its ids checked against the map's vertices and chains.
map::TileOutcome outcome_of(const py::dict& dict, const map::MapData& map) {
    map::TileOutcome outcome;
    const auto n = static_cast<std::uint32_t>(map.vertices.size());
    const auto c = static_cast<std::uint32_t>(map.chains.size());
    auto ids = [&](std::vector<std::uint32_t> list) {
        if (std::any_of(list.begin(), list.end(), [&](std::uint32_t v) { return v >= n; })) malformed("an outcome names a vertex the map has not");
        return list;
    };
    outcome.ids = ids(flat<std::uint32_t>(dict, "ids"));
    outcome.states = flat<std::uint8_t>(dict, "states");
    if (outcome.states.size() != outcome.ids.size()) malformed("an outcome's states are not one per vertex");
    if (std::any_of(outcome.states.begin(), outcome.states.end(),
                    [](std::uint8_t s) { return s > static_cast<std::uint8_t>(map::VertexState::removed); })) {
        malformed("an outcome's vertex state is not one");
    }
    outcome.oriented = flat<std::uint32_t>(dict, "oriented");
    outcome.orientations = flat<std::int8_t>(dict, "orientations");
    if (outcome.orientations.size() != outcome.oriented.size()) malformed("an outcome's orientations are not one per ring");
    for (std::size_t k = 0; k < outcome.oriented.size(); ++k) {
        if (outcome.oriented[k] >= c || outcome.orientations[k] < -1 || outcome.orientations[k] > 1) {
            malformed("an outcome's ring orientation is not one");
        }
    }
    outcome.waits = pairs_of(dict, "waits");
    for (const auto& [waiter, blocker] : outcome.waits) {
        if (waiter >= n || blocker >= n) malformed("an outcome's wait names a vertex the map has not");
    }
    for (const py::handle list : item(dict, "later").cast<py::list>()) {
        py::dict holder;
        holder["list"] = list;
        outcome.later.push_back(ids(flat<std::uint32_t>(holder, "list")));
    }
    outcome.locations_lost = pairs_of(dict, "locations_lost");
    for (const auto& [chain, lost] : outcome.locations_lost) {
        if (chain >= c) malformed("an outcome names a chain the map has not");
    }
    map::SimplifyStats& s = outcome.stats;
    std::tie(s.removed, s.blocked_by_point, s.blocked_by_ring, s.blocked_by_coincidence, s.predicates.filter_decided,
             s.predicates.expansion_decided, s.predicates.gmp_fallbacks) =
        item(dict, "stats").cast<std::tuple<std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t,
                                            std::uint64_t>>();
    return outcome;
}

// The coarsest level below the top whose biggest tile holds at most `budget` vertices and
// control points (0 if none does: every level-0 block a tile). Counted in a dense array at the
// finest level whose blocks number at most 2^22, and summed up from there: tiles are never finer
// than that level (a map of more than 2^22 level-0 blocks has tiles of a few blocks at least).
unsigned tile_level_for(const map::MapData& map, const map::GridPlan& plan, std::uint64_t budget) {
    const auto blocks_at = [&](unsigned level) {
        return std::pair{((plan.grid.base_columns - 1) >> (plan.shift + level)) + 1, ((plan.grid.base_rows - 1) >> (plan.shift + level)) + 1};
    };
    unsigned dense = 0;
    while (dense + 1 < plan.levels) {
        const auto [columns, rows] = blocks_at(dense);
        if (std::uint64_t{columns} * rows <= (std::uint64_t{1} << 22)) break;
        ++dense;
    }
    std::vector<std::uint64_t> count;
    auto [columns, rows] = blocks_at(dense);
    count.assign(std::size_t{columns} * rows, 0);
    for (const auto* points : {&map.vertices, &map.control_points}) {
        for (const Point p : *points) ++count[std::size_t{plan.block_row(p, dense)} * columns + plan.block_column(p, dense)];
    }
    unsigned best = 0;
    for (unsigned level = dense; level + 1 < plan.levels; ++level) {
        if (level > dense) {  // (the counts one level up)
            const auto [up_columns, up_rows] = blocks_at(level);
            std::vector<std::uint64_t> up(std::size_t{up_columns} * up_rows, 0);
            for (std::uint32_t row = 0; row < rows; ++row) {
                for (std::uint32_t column = 0; column < columns; ++column) {
                    up[std::size_t{row >> 1} * up_columns + (column >> 1)] += count[std::size_t{row} * columns + column];
                }
            }
            count = std::move(up);
            columns = up_columns;
            rows = up_rows;
        }
        if (level >= 1 && *std::max_element(count.begin(), count.end()) <= budget) best = level;
    }
    return best != 0 ? best : dense;
}

}  // namespace

RoundGroups::RoundGroups(const map::MapInParts& parts, std::size_t count) : parts_(&parts), count_(count) {}

std::size_t RoundGroups::index(std::ptrdiff_t k) const {
    if (k < 0) k += static_cast<std::ptrdiff_t>(count_);
    if (k < 0 || static_cast<std::size_t>(k) >= count_) throw py::index_error("no such tile group in the round");
    if (parts_ == nullptr) throw std::runtime_error("the round is over: its tile groups are gone");
    return static_cast<std::size_t>(k);
}

std::uint64_t RoundGroups::points(std::ptrdiff_t k) const { return parts_->group_points(index(k)); }

py::list RoundGroups::get(std::ptrdiff_t k) const {
    const std::size_t at = index(k);
    std::vector<map::TileInput> group;
    {
        py::gil_scoped_release release;
        group = parts_->group(at);
    }
    py::list tiles;
    for (map::TileInput& tile : group) tiles.append(tile_dict(std::move(tile)));
    return tiles;
}

void bind_parts(py::module_& module) {
    py::class_<RoundGroups>(module, "RoundGroups",
                            "A round's tile groups: groups[k] builds group k's tiles (a list of dicts) when asked for")
        .def("__len__", &RoundGroups::size)
        .def("__getitem__", &RoundGroups::get, py::arg("k"))
        .def("points", &RoundGroups::points, py::arg("k"),
             "group k's vertices (with its tiles' cut ends) and control points, known before it is built");
}

map::SimplifyResult run_in_parts(const map::MapData& map, const map::SimplifyOptions& options, const py::object& run_groups,
                                 int tile_level, const py::object& tile_points, std::uint64_t here_below) {
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point from) { return std::chrono::duration<double>(Clock::now() - from).count(); };
    const auto start = Clock::now();
    unsigned level = tile_level >= 0 ? static_cast<unsigned>(tile_level) : 0;
    if (tile_level < 0) {
        std::uint64_t budget = 0;
        {
            py::gil_scoped_acquire gil;
            budget = (PyCallable_Check(tile_points.ptr()) ? tile_points() : tile_points).cast<std::uint64_t>();
        }
        level = tile_level_for(map, map::plan_grid(map), budget);
    }
    map::MapInParts parts(map, options, level, here_below);
    const double set_up = seconds(start);
    const auto rounds_start = Clock::now();
    bool whole = true;  // the whole map's engine is still here
    for (unsigned round = 1; parts.next_round(); ++round) {
        const std::size_t count = parts.split_round();
        std::vector<map::TileOutcome> outcomes;
        if (count > 0) {
            py::gil_scoped_acquire gil;
            py::object groups = py::cast(RoundGroups(parts, count));
            py::dict plan = plan_dict(parts.plan());
            plan["tile_level"] = parts.tile_level();  // (for progress; the tiles carry their level)
            py::object done;
            try {
                done = run_groups(groups, plan, options_dict(options), round);
            } catch (...) {
                groups.cast<RoundGroups&>().close();
                throw;
            }
            groups.cast<RoundGroups&>().close();
            const auto results = done.cast<py::list>();
            if (results.size() != count) malformed("not one outcome list per group");
            for (std::size_t k = 0; k < count; ++k) {
                const auto group = results[k].cast<py::list>();
                if (group.size() != parts.group_size(k)) malformed("not one outcome per tile");
                for (const py::handle one : group) outcomes.push_back(outcome_of(one.cast<py::dict>(), map));
            }
        }
        if (!parts.finish_tiles(outcomes)) continue;
        // From the first round's tiles on, the engine here holds the live vertices only.
        if (whole && count > 0) {
            parts.keep_live_only();
            whole = false;
        }
        parts.run_top_here();
    }
    map::SimplifyResult result = parts.result();
    // The phases: set-up and the crossing search; the rounds (tiles and the levels above).
    result.stats.seconds_crossings = set_up;
    result.stats.seconds_sweep = seconds(rounds_start);
    return result;
}

py::list run_tile_group(const py::list& group, const py::dict& plan, const py::dict& options) {
    std::vector<map::TileInput> tiles;
    for (const py::handle tile : group) tiles.push_back(tile_of(tile.cast<py::dict>()));
    const map::GridPlan grid = plan_of(plan);
    const map::SimplifyOptions simplify = options_of(options);
    for (const map::TileInput& tile : tiles) {
        if (tile.level != tiles.front().level || tile.level > grid.levels) malformed("the tiles are not of one level of the plan");
    }
    std::vector<map::TileOutcome> outcomes;
    {
        py::gil_scoped_release release;
        outcomes = map::run_tile_group(std::move(tiles), grid, simplify);
#ifdef __GLIBC__
        // The engine's arrays are freed; give their pages back, so that the worker's memory (what
        // Dask's memory limit watches) falls back to what it holds.
        malloc_trim(0);
#endif
    }
    py::list out;
    for (const map::TileOutcome& outcome : outcomes) out.append(outcome_dict(outcome));
    return out;
}

}  // namespace toposimp::python
