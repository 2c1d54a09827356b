// The rounds after the first from the first round's tiles kept on the workers (--kept-tiles;
// map::KeptTiles): a batch's tasks (python/toposimp/dask.py, _kept_*), and the lead's store, whose
// questions the Python side turns into tasks over the batches (_KeptStore).
#include "python/parts.hpp"
#include "python/wire.hpp"

#include <pybind11/stl.h>

#include <map>
#include <memory>
#include <vector>

namespace toposimp::python {

namespace {

// The tiles of a first-round batch, queued and run, kept (marked for the first round's budget).
map::KeptBatch kept_batch(const py::list& tiles, bool marks, std::pair<double, std::uint32_t> bound) {
    std::map<std::uint32_t, map::FirstTile> kept;
    for (const map::FirstTile* tile : tiles_in(tiles)) {
        if (tile->input.vertex_id.empty()) continue;
        map::FirstTile& at = kept[tile->number] = *tile;
        at.improper = {};
        at.passing = {};
        at.passing_id = {};
        if (marks) at.mark(bound.first, bound.second);
    }
    return map::KeptBatch(std::move(kept));
}

// A batch told a round's news, and after the tiles' levels the outcomes of the groups that ran
// (`own`: lists of outcome dicts, those of its tiles among them) → (the batch after it: a new one,
// so that the task is pure; its waits on a cut end, its cut ends moved and pieces joined).
py::tuple kept_advance(const map::KeptBatch& batch, const py::dict& news, const py::object& ran, const py::dict& plan, bool marks,
                       const py::dict& options, const py::list& own) {
    map::TileNews told = news_of(news);
    for (const py::handle list : own) {
        for (const py::handle one : list.cast<py::list>()) {
            const auto outcome = one.cast<py::dict>();
            const std::vector<std::uint32_t> ids = flat<std::uint32_t>(outcome, "ids");
            const std::vector<std::uint8_t> states = flat<std::uint8_t>(outcome, "states");
            if (ids.size() != states.size()) malformed("an outcome's states are not one per id");
            for (std::size_t k = 0; k < ids.size(); ++k) told.outcome_states.emplace_back(ids[k], states[k]);
            for (const auto& wait : pairs_of(outcome, "waits")) told.tile_waits.push_back(wait);
        }
    }
    std::sort(told.outcome_states.begin(), told.outcome_states.end());
    std::sort(told.tile_waits.begin(), told.tile_waits.end());
    py::dict holder;
    holder["ran"] = ran;
    const std::vector<std::uint32_t> running = flat<std::uint32_t>(holder, "ran");
    const map::GridPlan grid = plan_of(plan);
    const map::SimplifyOptions simplify = options_of(options);
    map::KeptBatch after;
    map::FirstTile::Advanced done;
    {
        py::gil_scoped_release release;
        after = batch.clone();
        done = after.advance(told, running, grid, marks, simplify.ranking);
    }
    py::dict dict;
    dict["across"] = pairs_array(done.across);
    dict["moved"] = done.cut_ends_moved;
    dict["joined"] = done.pieces_joined;
    return py::make_tuple(py::cast(std::move(after)), dict);
}

// A batch begun on a round: (a new batch, marked and settled, so that the task is pure; its tiles' facts).
py::tuple kept_begin_round(const map::KeptBatch& batch, const py::object& settled, bool marks, std::pair<double, std::uint32_t> bound) {
    py::dict holder;
    holder["settled"] = settled;
    const std::vector<std::uint32_t> chains = flat<std::uint32_t>(holder, "settled");
    map::KeptBatch begun = batch.clone();
    py::list facts;
    for (const map::FirstRoundLead::TileFacts& tile : begun.begin_round(chains, marks, bound.first, bound.second)) {
        facts.append(py::make_tuple(tile.number, tile.busy, array_of(tile.open_chains)));
    }
    return py::make_tuple(py::cast(std::move(begun)), facts);
}

py::list kept_inputs(const map::KeptBatch& batch, const py::list& numbers, bool marks, std::pair<double, std::uint32_t> bound, const py::list& points) {
    if (numbers.size() != points.size()) malformed("not one list of control points per tile");
    py::list tiles;
    for (std::size_t k = 0; k < numbers.size(); ++k) {
        py::dict holder;
        holder["points"] = points[k];
        tiles.append(tile_dict(batch.input(numbers[k].cast<std::uint32_t>(), marks, bound.first, bound.second, points_of(holder, "points"))));
    }
    return tiles;
}

py::list kept_crossings(const map::KeptBatch& batch) {
    py::list rings;
    for (const map::RingLocations& ring : batch.crossing_locations()) rings.append(py::make_tuple(ring.chain, points_array(ring.locations)));
    return rings;
}


// The lead's side of a distributed run's kept tiles: its questions to `store`, a Python object
// whose methods run them as tasks over the batches (python/toposimp/dask.py, _KeptStore).
class PythonStore final : public map::KeptStore {
public:
    PythonStore(py::object store, std::uint32_t vertices, std::uint32_t chains) : store_(std::move(store)), vertices_(vertices), chains_(chains) {}
    ~PythonStore() override {
        py::gil_scoped_acquire gil;
        store_ = py::object();
    }

    map::FirstTile::Advanced advance(const map::TileNews& news, std::span<const std::uint32_t> ran) override {
        py::gil_scoped_acquire gil;
        const py::dict done = store_.attr("advance")(news_dict(news), array_of(std::vector<std::uint32_t>(ran.begin(), ran.end())));
        map::FirstTile::Advanced out;
        out.across = pairs_of(done, "across");
        out.cut_ends_moved = item(done, "moved").cast<std::size_t>();
        out.pieces_joined = item(done, "joined").cast<std::size_t>();
        return out;
    }
    std::uint64_t queued() override {
        py::gil_scoped_acquire gil;
        return store_.attr("queued")().cast<std::uint64_t>();
    }
    parallel::KeyedSelection select(std::uint64_t wanted) override {
        py::gil_scoped_acquire gil;
        const auto [key, id] = store_.attr("select")(wanted).cast<std::pair<std::uint64_t, std::uint32_t>>();
        return {key, id};
    }
    std::vector<map::RingLocations> crossing_locations() override {
        py::gil_scoped_acquire gil;
        std::vector<map::RingLocations> rings;
        for (const py::handle one : store_.attr("crossings")().cast<py::list>()) {
            const auto ring = one.cast<py::tuple>();
            py::dict holder;
            holder["points"] = ring[1];
            rings.push_back({ring[0].cast<std::uint32_t>(), points_of(holder, "points")});
        }
        return rings;
    }
    std::vector<map::FirstRoundLead::TileFacts> begin_round(std::span<const std::uint32_t> settled, bool marks, double bound_key,
                                                            std::uint32_t bound_id) override {
        py::gil_scoped_acquire gil;
        std::vector<map::FirstRoundLead::TileFacts> facts;
        const py::list answers = store_.attr("begin_round")(array_of(std::vector<std::uint32_t>(settled.begin(), settled.end())), marks,
                                                            py::make_tuple(bound_key, bound_id));
        for (const py::handle one : answers) {
            const auto tile = one.cast<py::tuple>();
            py::dict holder;
            holder["open"] = tile[2];
            facts.push_back({tile[0].cast<std::uint32_t>(), tile[1].cast<bool>(), flat<std::uint32_t>(holder, "open")});
        }
        return facts;
    }
    std::vector<map::TileOutcome> run(const std::vector<std::vector<std::uint32_t>>& groups, std::vector<std::vector<Point>> points, bool marks,
                                      double bound_key, std::uint32_t bound_id) override {
        py::gil_scoped_acquire gil;
        py::list group_list, point_list;
        for (const std::vector<std::uint32_t>& group : groups) group_list.append(array_of(group));
        for (const std::vector<Point>& inside : points) point_list.append(points_array(inside));
        std::vector<map::TileOutcome> outcomes;
        for (const py::handle one : store_.attr("run")(group_list, point_list, marks, py::make_tuple(bound_key, bound_id)).cast<py::list>()) {
            outcomes.push_back(outcome_of(one.cast<py::dict>(), vertices_, chains_));
        }
        std::size_t tiles = 0;
        for (const std::vector<std::uint32_t>& group : groups) tiles += group.size();
        if (outcomes.size() != tiles) malformed("not one outcome per tile of the round's groups");
        return outcomes;
    }
    map::TileInput input(std::uint32_t number, bool marks, double bound_key, std::uint32_t bound_id, std::vector<Point> points) override {
        py::gil_scoped_acquire gil;
        return tile_of(store_.attr("input")(number, marks, py::make_tuple(bound_key, bound_id), points_array(points)).cast<py::dict>());
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> waits() override {
        py::gil_scoped_acquire gil;
        py::dict holder;
        holder["waits"] = store_.attr("waits")();
        return pairs_of(holder, "waits");
    }
    map::SubsetAnswer answer(const map::SubsetAsk& ask) override {
        py::gil_scoped_acquire gil;
        return answer_of(store_.attr("answer")(ask_dict(ask)).cast<py::dict>());
    }
    std::size_t tiles() override {
        py::gil_scoped_acquire gil;
        return store_.attr("tiles")().cast<std::size_t>();
    }

private:
    py::object store_;
    std::uint32_t vertices_, chains_;
};

}  // namespace

std::unique_ptr<map::KeptStore> python_store(py::object store, std::uint32_t vertices, std::uint32_t chains) {
    return std::make_unique<PythonStore>(std::move(store), vertices, chains);
}

void bind_kept(py::module_& module) {
    // The rounds after the first from kept tiles: a batch of them and its tasks.
    py::class_<map::KeptBatch>(module, "KeptBatch", "Kept tiles of a run in parts, a batch of them (core/map/tiles.hpp)")
        .def_property_readonly("tiles", &map::KeptBatch::tiles)
        .def_property_readonly("numbers", [](const map::KeptBatch& batch) {
            std::vector<std::uint32_t> numbers;
            for (const auto& [k, tile] : batch.all()) numbers.push_back(k);
            return array_of(numbers);
        })
        .def(py::pickle(
            [](const map::KeptBatch& batch) {
                py::list tiles;
                for (const auto& [k, tile] : batch.all()) tiles.append(first_tile_dict(tile));
                return tiles;
            },
            [](const py::list& tiles) {
                std::map<std::uint32_t, map::FirstTile> kept;
                for (const py::handle one : tiles) {
                    map::FirstTile tile = first_tile_of(one.cast<py::dict>());
                    const std::uint32_t number = tile.number;
                    kept.emplace(number, std::move(tile));
                }
                return map::KeptBatch(std::move(kept));
            }));
    module.def("kept_batch", &kept_batch, py::arg("tiles"), py::arg("marks"), py::arg("bound"));
    module.def("kept_advance", &kept_advance, py::arg("batch"), py::arg("news"), py::arg("ran"), py::arg("plan"), py::arg("marks"),
               py::arg("options"), py::arg("own"));
    module.def("kept_histogram", [](const map::KeptBatch& batch, int shift, std::uint64_t high) {
        if (shift < 0 || shift > 48 || shift % 16 != 0) malformed("a histogram's digit is not one");
        std::vector<std::uint64_t> counts(std::size_t{1} << 16, 0);
        batch.histogram(shift, high, counts);
        return sparse_histogram(counts);
    }, py::arg("batch"), py::arg("shift"), py::arg("high"));
    module.def("kept_ids_at", [](const map::KeptBatch& batch, std::uint64_t key) {
        std::vector<std::uint32_t> ids;
        batch.ids_at(key, ids);
        return array_of(ids);
    }, py::arg("batch"), py::arg("key"));
    module.def("kept_pairs_in", [](const map::KeptBatch& batch, int shift, std::uint64_t prefix) {
        if (shift < 0 || shift > 48 || shift % 16 != 0) malformed("a bucket's digit is not one");
        std::vector<std::uint64_t> keys;
        std::vector<std::uint32_t> ids;
        batch.pairs_in(shift, prefix, keys, ids);
        py::dict dict;
        dict["keys"] = array_of(keys);
        dict["ids"] = array_of(ids);
        return dict;
    }, py::arg("batch"), py::arg("shift"), py::arg("prefix"));
    module.def("kept_crossings", &kept_crossings, py::arg("batch"));
    module.def("kept_begin_round", &kept_begin_round, py::arg("batch"), py::arg("settled"), py::arg("marks"), py::arg("bound"));
    module.def("kept_inputs", &kept_inputs, py::arg("batch"), py::arg("numbers"), py::arg("marks"), py::arg("bound"), py::arg("points"));
    module.def("kept_waits", [](const map::KeptBatch& batch) { return pairs_array(batch.waits()); }, py::arg("batch"));
    module.def("kept_answer", [](const map::KeptBatch& batch, const py::dict& ask, const py::dict& plan) {
        const map::SubsetAsk question = ask_of(ask);
        const map::GridPlan grid = plan_of(plan);
        map::SubsetAnswer answer;
        {
            py::gil_scoped_release release;
            answer = batch.answer(question, grid);
        }
        return answer_dict(answer);
    }, py::arg("batch"), py::arg("ask"), py::arg("plan"));
}

}  // namespace toposimp::python
