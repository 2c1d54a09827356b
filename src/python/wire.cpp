#include "python/wire.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

namespace toposimp::python {

[[noreturn]] void malformed(const std::string& what) {
    throw py::value_error("toposimp: a tile task's data is malformed: " + what);
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

std::vector<std::pair<std::uint32_t, std::uint32_t>> chain_pairs(const std::vector<map::Chain>& chains) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    pairs.reserve(chains.size());
    for (const map::Chain& chain : chains) pairs.emplace_back(chain.first, chain.last);
    return pairs;
}

std::vector<map::Chain> consecutive_chains(const py::dict& dict, const char* key, std::size_t n) {
    std::vector<map::Chain> chains;
    std::size_t next = 0;
    for (const auto& [first, last] : pairs_of(dict, key)) {
        if (first != next || last < first || last >= n) malformed("the chains do not cut the vertices into consecutive ranges");
        chains.push_back({first, last});
        next = std::size_t{last} + 1;
    }
    if (next != n) malformed("the chains do not cover the vertices");
    return chains;
}

void put_vertex_ids(py::dict& dict, const std::vector<std::uint32_t>& ids) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> runs;
    for (std::size_t k = 0; k < ids.size() && 4 * runs.size() <= ids.size();) {
        std::size_t j = k + 1;
        while (j < ids.size() && ids[j - 1] != std::numeric_limits<std::uint32_t>::max() && ids[j] == ids[j - 1] + 1) ++j;
        runs.emplace_back(ids[k], static_cast<std::uint32_t>(j - k));
        k = j;
    }
    if (4 * runs.size() <= ids.size()) {
        dict["vertex_runs"] = pairs_array(runs);
    } else {
        dict["vertex_id"] = array_of(ids);
    }
}

std::vector<std::uint32_t> take_vertex_ids(const py::dict& dict, std::size_t n) {
    if (!dict.contains("vertex_runs")) return flat<std::uint32_t>(dict, "vertex_id");
    std::vector<std::uint32_t> ids;
    ids.reserve(n);
    for (const auto& [first, count] : pairs_of(dict, "vertex_runs")) {
        if (count == 0 || count > n - ids.size() || std::uint64_t{first} + count - 1 > std::numeric_limits<std::uint32_t>::max()) {
            malformed("the vertex id runs do not give one id per vertex");
        }
        for (std::uint32_t k = 0; k < count; ++k) ids.push_back(first + k);
    }
    if (ids.size() != n) malformed("the vertex id runs do not give one id per vertex");
    return ids;
}

bool orientation_code(std::int8_t o) { return o >= -1 && o <= 9 && o != 6; }

void put_tile_input(py::dict& dict, const map::TileInput& tile) {
    dict["level"] = tile.level;
    dict["column"] = tile.column;
    dict["row"] = tile.row;
    dict["vertices"] = points_array(tile.map.vertices);
    dict["chains"] = pairs_array(chain_pairs(tile.map.chains));
    put_vertex_ids(dict, tile.vertex_id);
    dict["state"] = array_of(tile.state);
    dict["chain_id"] = array_of(tile.chain_id);
    dict["whole_level"] = array_of(tile.whole_level);
    dict["settled"] = array_of(tile.settled);
    dict["distinct"] = array_of(tile.distinct);
    dict["orientation"] = array_of(tile.orientation);
}

void take_tile_input(const py::dict& dict, map::TileInput& tile, bool states_optional) {
    tile.level = item(dict, "level").cast<unsigned>();
    tile.column = item(dict, "column").cast<std::uint32_t>();
    tile.row = item(dict, "row").cast<std::uint32_t>();
    tile.map.vertices = points_of(dict, "vertices");
    const std::size_t n = tile.map.vertices.size();
    if (n >= std::numeric_limits<std::uint32_t>::max()) malformed("too many vertices");
    tile.map.chains = consecutive_chains(dict, "chains", n);
    tile.vertex_id = take_vertex_ids(dict, n);
    tile.state = flat<std::uint8_t>(dict, "state");
    tile.chain_id = flat<std::uint32_t>(dict, "chain_id");
    tile.whole_level = flat<std::uint8_t>(dict, "whole_level");
    tile.settled = flat<std::uint8_t>(dict, "settled");
    tile.distinct = flat<std::uint32_t>(dict, "distinct");
    tile.orientation = flat<std::int8_t>(dict, "orientation");
    const std::size_t c = tile.map.chains.size();
    if (tile.vertex_id.size() != n || (tile.state.size() != n && !(states_optional && tile.state.empty()))) {
        malformed("vertex_id or state is not one per vertex");
    }
    if (tile.chain_id.size() != c || tile.whole_level.size() != c || tile.settled.size() != c || tile.distinct.size() != c ||
        tile.orientation.size() != c) {
        malformed("chain_id, whole_level, settled, distinct or orientation is not one per chain");
    }
    if (std::any_of(tile.state.begin(), tile.state.end(), [](std::uint8_t s) { return s > static_cast<std::uint8_t>(map::VertexState::removed); })) {
        malformed("a vertex state is not one");
    }
    if (!std::all_of(tile.orientation.begin(), tile.orientation.end(), orientation_code)) malformed("an orientation is not one");
}

py::dict tile_dict(map::TileInput&& tile) {
    py::dict dict;
    put_tile_input(dict, tile);
    dict["control_points"] = points_array(tile.map.control_points);
    dict["marked"] = array_of(tile.marked);
    dict["waits"] = pairs_array(tile.waits);
    dict["marks"] = tile.marks;
    dict["bound"] = py::make_tuple(tile.bound_key, tile.bound_id);
    return dict;
}

map::TileInput tile_of(const py::dict& dict) {
    map::TileInput tile;
    take_tile_input(dict, tile, false);
    const std::size_t n = tile.map.vertices.size();
    tile.map.control_points = points_of(dict, "control_points");
    tile.marked = flat<std::uint8_t>(dict, "marked");
    tile.waits = pairs_of(dict, "waits");
    tile.marks = item(dict, "marks").cast<bool>();
    std::tie(tile.bound_key, tile.bound_id) = item(dict, "bound").cast<std::pair<double, std::uint32_t>>();
    if (tile.marked.size() != (tile.marks ? n : 0)) malformed("marked is not one per vertex with marks, none without");
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

std::uint32_t chains_of(const map::MapData& map) { return static_cast<std::uint32_t>(map.chains.size()); }

map::TileOutcome outcome_of(const py::dict& dict, std::uint32_t n, std::uint32_t c) {
    map::TileOutcome outcome;
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


py::dict first_tile_dict(const map::FirstTile& tile) {
    py::dict dict;
    put_tile_input(dict, tile.input);
    dict["number"] = tile.number;
    dict["cut_end"] = array_of(tile.cut_end);
    dict["frozen"] = array_of(tile.frozen);
    dict["passing"] = points_array(tile.passing);
    dict["passing_id"] = array_of(tile.passing_id);
    dict["improper"] = array_of(tile.improper);
    dict["keys"] = array_of(tile.keys);
    dict["waits"] = pairs_array(tile.waits);
    dict["marked"] = array_of(tile.marked);
    return dict;
}

map::FirstTile first_tile_of(const py::dict& dict) {
    map::FirstTile tile;
    const map::TileInput& in = tile.input;
    take_tile_input(dict, tile.input, true);
    tile.number = item(dict, "number").cast<std::uint32_t>();
    tile.cut_end = flat<std::uint8_t>(dict, "cut_end");
    tile.frozen = flat<std::uint8_t>(dict, "frozen");
    tile.passing = points_of(dict, "passing");
    tile.passing_id = flat<std::uint32_t>(dict, "passing_id");
    tile.improper = flat<std::uint8_t>(dict, "improper");
    tile.keys = flat<std::uint64_t>(dict, "keys");
    tile.waits = pairs_of(dict, "waits");
    tile.marked = flat<std::uint8_t>(dict, "marked");
    const std::size_t n = in.vertex_id.size();
    if (!tile.marked.empty() && tile.marked.size() != n) malformed("marked is not one per vertex");
    if (tile.cut_end.size() != n) malformed("cut_end is not one per vertex");
    if (!tile.improper.empty() && tile.improper.size() != n) malformed("improper is not one per vertex");
    if (tile.frozen.size() != in.map.chains.size()) malformed("frozen is not one per chain");
    if (tile.passing.size() != 2 * tile.passing_id.size()) malformed("passing is not two points per passing_id");
    const auto queued = static_cast<std::size_t>(
        std::count(in.state.begin(), in.state.end(), static_cast<std::uint8_t>(map::VertexState::queued)));
    if (!tile.keys.empty() && tile.keys.size() != queued) malformed("keys are not one per queued vertex");
    return tile;
}

py::dict live_dict(const map::LiveVertices& live) {
    py::dict dict;
    dict["ids"] = array_of(live.ids);
    dict["points"] = points_array(live.points);
    dict["states"] = array_of(live.states);
    dict["marked"] = array_of(live.marked);
    return dict;
}

map::LiveVertices live_of(const py::dict& dict, std::size_t n, bool marks) {
    map::LiveVertices live;
    live.ids = flat<std::uint32_t>(dict, "ids");
    live.points = points_of(dict, "points");
    live.states = flat<std::uint8_t>(dict, "states");
    live.marked = flat<std::uint8_t>(dict, "marked");
    const std::size_t k = live.ids.size();
    if (live.points.size() != k || live.states.size() != k || live.marked.size() != (marks ? k : 0)) {
        malformed("a tile's live vertices do not have one point, state (and mark) each");
    }
    for (std::size_t i = 0; i < k; ++i) {
        if (live.ids[i] >= n || (i > 0 && live.ids[i] <= live.ids[i - 1])) malformed("a tile's live vertices are not the map's, in order");
        if (live.states[i] >= static_cast<std::uint8_t>(map::VertexState::removed)) malformed("a live vertex's state is not one");
    }
    return live;
}

py::tuple predicates_tuple(const exact::PredicateStats& p) { return py::make_tuple(p.filter_decided, p.expansion_decided, p.gmp_fallbacks); }

exact::PredicateStats predicates_of(const py::handle& tuple) {
    exact::PredicateStats p;
    std::tie(p.filter_decided, p.expansion_decided, p.gmp_fallbacks) = tuple.cast<std::tuple<std::uint64_t, std::uint64_t, std::uint64_t>>();
    return p;
}

std::vector<const map::FirstTile*> tiles_in(const py::list& list) {
    std::vector<const map::FirstTile*> tiles;
    for (const py::handle tile : list) tiles.push_back(&tile.cast<const map::FirstTile&>());
    return tiles;
}


py::dict sparse_histogram(const std::vector<std::uint64_t>& counts) {
    std::vector<std::uint32_t> digits;
    std::vector<std::uint64_t> nonzero;
    for (std::size_t d = 0; d < counts.size(); ++d) {
        if (counts[d] == 0) continue;
        digits.push_back(static_cast<std::uint32_t>(d));
        nonzero.push_back(counts[d]);
    }
    py::dict dict;
    dict["digits"] = array_of(digits);
    dict["counts"] = array_of(nonzero);
    return dict;
}


// ---- the rounds after the first from kept tiles (map::KeptTiles): a batch's tasks, and the lead's
// questions as dicts of arrays.

py::dict news_dict(const map::TileNews& news) {
    py::dict dict;
    std::vector<std::uint32_t> ids, prev, next;
    std::vector<std::uint8_t> states;
    std::vector<Point> points;
    for (const auto& [id, state] : news.states) {
        ids.push_back(id);
        states.push_back(state);
    }
    dict["after_tiles"] = news.after_tiles;
    dict["state_ids"] = array_of(ids);
    dict["states"] = array_of(states);
    ids.clear();
    for (const map::Unlinked& u : news.unlinked) {
        ids.push_back(u.id);
        prev.push_back(u.prev);
        next.push_back(u.next);
        points.push_back(u.prev_point);
        points.push_back(u.next_point);
    }
    dict["unlinked"] = array_of(ids);
    dict["unlinked_prev"] = array_of(prev);
    dict["unlinked_next"] = array_of(next);
    dict["unlinked_points"] = points_array(points);
    dict["judged"] = array_of(news.judged);
    dict["top_waits"] = pairs_array(news.top_waits);
    dict["distinct"] = array_of(news.distinct);
    dict["orientation"] = array_of(news.orientation);
    return dict;
}

map::TileNews news_of(const py::dict& dict) {
    map::TileNews news;
    const std::vector<std::uint32_t> ids = flat<std::uint32_t>(dict, "state_ids");
    const std::vector<std::uint8_t> states = flat<std::uint8_t>(dict, "states");
    if (ids.size() != states.size()) malformed("news: not one state per id");
    for (std::size_t k = 0; k < ids.size(); ++k) {
        if (k > 0 && ids[k] <= ids[k - 1]) malformed("news: states not by id");
        news.states.emplace_back(ids[k], states[k]);
    }
    const std::vector<std::uint32_t> gone = flat<std::uint32_t>(dict, "unlinked"), prev = flat<std::uint32_t>(dict, "unlinked_prev"),
                                     next = flat<std::uint32_t>(dict, "unlinked_next");
    const std::vector<Point> points = points_of(dict, "unlinked_points");
    if (prev.size() != gone.size() || next.size() != gone.size() || points.size() != 2 * gone.size()) malformed("news: unlinked vertices");
    for (std::size_t k = 0; k < gone.size(); ++k) news.unlinked.push_back({gone[k], prev[k], next[k], points[2 * k], points[2 * k + 1]});
    news.after_tiles = item(dict, "after_tiles").cast<bool>();
    news.judged = flat<std::uint32_t>(dict, "judged");
    news.top_waits = pairs_of(dict, "top_waits");
    news.distinct = flat<std::uint32_t>(dict, "distinct");
    news.orientation = flat<std::int8_t>(dict, "orientation");
    return news;
}

py::dict ask_dict(const map::SubsetAsk& ask) {
    py::dict dict;
    dict["ids"] = array_of(ask.ids);
    dict["rings"] = array_of(ask.rings);
    dict["reach"] = ask.reach;
    std::vector<Point> corners;
    for (const Box& box : ask.boxes) {
        corners.push_back({box.min_x, box.min_y});
        corners.push_back({box.max_x, box.max_y});
    }
    dict["boxes"] = points_array(corners);
    dict["skip"] = array_of(ask.skip);
    dict["outside_rings"] = array_of(ask.outside_rings);
    dict["runs"] = array_of(ask.runs);
    dict["from_level"] = ask.from_level;
    return dict;
}

map::SubsetAsk ask_of(const py::dict& dict) {
    map::SubsetAsk ask;
    ask.ids = flat<std::uint32_t>(dict, "ids");
    ask.rings = flat<std::uint32_t>(dict, "rings");
    ask.reach = item(dict, "reach").cast<std::uint32_t>();
    const std::vector<Point> corners = points_of(dict, "boxes");
    if (corners.size() % 2 != 0) malformed("a box is not two corners");
    for (std::size_t k = 0; k < corners.size(); k += 2) ask.boxes.push_back({corners[k].x, corners[k].y, corners[k + 1].x, corners[k + 1].y});
    ask.skip = flat<std::uint32_t>(dict, "skip");
    ask.outside_rings = flat<std::uint32_t>(dict, "outside_rings");
    ask.runs = flat<std::uint32_t>(dict, "runs");
    ask.from_level = item(dict, "from_level").cast<unsigned>();
    return ask;
}

py::dict answer_dict(const map::SubsetAnswer& answer) {
    py::dict dict;
    dict["ids"] = array_of(answer.ids);
    dict["chain"] = array_of(answer.chain);
    dict["prev"] = array_of(answer.prev);
    dict["next"] = array_of(answer.next);
    dict["points"] = points_array(answer.points);
    dict["state"] = array_of(answer.state);
    dict["marked"] = array_of(answer.marked);
    dict["flags"] = array_of(answer.flags);
    dict["in_boxes"] = array_of(answer.in_boxes);
    py::list outside;
    for (const map::SubsetAnswer::Outside& piece : answer.outside) {
        py::list levels;
        for (const std::vector<Point>& level : piece.levels) levels.append(points_array(level));
        outside.append(py::make_tuple(piece.chain, piece.first, levels));
    }
    dict["outside"] = outside;
    return dict;
}

map::SubsetAnswer answer_of(const py::dict& dict) {
    map::SubsetAnswer answer;
    answer.ids = flat<std::uint32_t>(dict, "ids");
    answer.chain = flat<std::uint32_t>(dict, "chain");
    answer.prev = flat<std::uint32_t>(dict, "prev");
    answer.next = flat<std::uint32_t>(dict, "next");
    answer.points = points_of(dict, "points");
    answer.state = flat<std::uint8_t>(dict, "state");
    answer.marked = flat<std::uint8_t>(dict, "marked");
    answer.flags = flat<std::uint8_t>(dict, "flags");
    answer.in_boxes = flat<std::uint32_t>(dict, "in_boxes");
    const std::size_t n = answer.ids.size();
    if (answer.chain.size() != n || answer.prev.size() != n || answer.next.size() != n || answer.points.size() != n ||
        answer.state.size() != n || answer.marked.size() != n || answer.flags.size() != n) {
        malformed("a subset's answer is not one of each per vertex");
    }
    for (const py::handle one : item(dict, "outside").cast<py::list>()) {
        const auto piece = one.cast<py::tuple>();
        map::SubsetAnswer::Outside& at = answer.outside.emplace_back();
        at.chain = piece[0].cast<std::uint32_t>();
        at.first = piece[1].cast<std::uint32_t>();
        for (const py::handle level : piece[2].cast<py::list>()) {
            py::dict holder;
            holder["points"] = level;
            at.levels.push_back(points_of(holder, "points"));
        }
    }
    return answer;
}

}  // namespace toposimp::python
