// The wire format of the map engine's tasks (python/toposimp/dask.py): tiles, outcomes, plans,
// options, a round's news and the lead's questions as dicts of numpy arrays, each read back
// checked (a malformed one raises ValueError). Internal to the module: parts.cpp, kept.cpp.
#pragma once

#include "core/map/simplify.hpp"
#include "core/map/tiles.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace toposimp::python {

namespace py = pybind11;

[[noreturn]] void malformed(const std::string& what);

py::array_t<double> points_array(const std::vector<Point>& points);

py::array_t<std::uint32_t> pairs_array(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs);

py::object item(const py::dict& dict, const char* key);

// An array of (x, y) as points, or of pairs as pairs: one copy, straight from the array.
std::vector<Point> points_of(const py::dict& dict, const char* key);

std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_of(const py::dict& dict, const char* key);

std::vector<std::pair<std::uint32_t, std::uint32_t>> chain_pairs(const std::vector<map::Chain>& chains);

// Chains as pairs, checked to cut `n` vertices into consecutive ranges.
std::vector<map::Chain> consecutive_chains(const py::dict& dict, const char* key, std::size_t n);

// A tile's whole-map vertex ids, as `vertex_runs`, (first id, count) pairs of consecutive ids,
// where that takes at most half the room of `vertex_id`, an id a vertex: a piece of a chain is a
// run of the whole map's vertices while they are all live (GSHHG's first round: 39 MB of ids in
// 74 tiles, 37 kB as runs), and the ids of later rounds' live vertices have gaps.
void put_vertex_ids(py::dict& dict, const std::vector<std::uint32_t>& ids);

// Those back: `n` ids, from either form.
std::vector<std::uint32_t> take_vertex_ids(const py::dict& dict, std::size_t n);

// (−1, 0, 1; 2: not known; 3 to 5 and 7 to 9: known, not yet counted: core/map/simplify.cpp)
bool orientation_code(std::int8_t o);

// What tile dicts of both kinds (TileInput, FirstTile) hold of a TileInput.
void put_tile_input(py::dict& dict, const map::TileInput& tile);

// Those back, checked: the chains cutting the vertices into consecutive ranges, every array the
// size its structure needs (the states may be missing where `states_optional`).
void take_tile_input(const py::dict& dict, map::TileInput& tile, bool states_optional);

py::dict tile_dict(map::TileInput&& tile);

// A tile dict back, checked to be one.
map::TileInput tile_of(const py::dict& dict);

py::dict plan_dict(const map::GridPlan& plan);

map::GridPlan plan_of(const py::dict& dict);

py::dict options_dict(const map::SimplifyOptions& options);

map::SimplifyOptions options_of(const py::dict& dict);

py::dict outcome_dict(const map::TileOutcome& outcome);

std::uint32_t chains_of(const map::MapData& map);

// An outcome dict back, its ids checked against a map of `n` vertices and `c` chains.
map::TileOutcome outcome_of(const py::dict& dict, std::uint32_t n, std::uint32_t c);

py::dict first_tile_dict(const map::FirstTile& tile);

// A first-round tile dict back, checked to be one (its stage's arrays present or empty).
map::FirstTile first_tile_of(const py::dict& dict);

py::dict live_dict(const map::LiveVertices& live);

map::LiveVertices live_of(const py::dict& dict, std::size_t n, bool marks);

py::tuple predicates_tuple(const exact::PredicateStats& p);

exact::PredicateStats predicates_of(const py::handle& tuple);

// A list of FirstTile objects.
std::vector<const map::FirstTile*> tiles_in(const py::list& list);

py::dict sparse_histogram(const std::vector<std::uint64_t>& counts);

// A round's news without the tiles' own outcomes (the batches take those from where their groups
// ran: kept_advance's `own`).
py::dict news_dict(const map::TileNews& news);

map::TileNews news_of(const py::dict& dict);

py::dict ask_dict(const map::SubsetAsk& ask);

map::SubsetAsk ask_of(const py::dict& dict);

py::dict answer_dict(const map::SubsetAnswer& answer);

map::SubsetAnswer answer_of(const py::dict& dict);

template <class T>
py::array_t<T> array_of(const std::vector<T>& values) {
    py::array_t<T> array(static_cast<py::ssize_t>(values.size()));
    if (!values.empty()) std::memcpy(array.mutable_data(), values.data(), values.size() * sizeof(T));
    return array;
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

}  // namespace toposimp::python
