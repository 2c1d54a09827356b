// The map engine in parts for Python (python/toposimp/dask.py): tiles and their outcomes as dicts
// of numpy arrays, which Dask moves between processes as they are.
#pragma once

#include "core/map/simplify.hpp"
#include "core/map/tiles.hpp"
#include "io/ogr/ogr_dataset.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>

namespace toposimp::python {

namespace py = pybind11;

// The tile and outcome dicts' format: a worker whose engine has another cannot run this one's
// tiles (python/toposimp/dask.py checks before the first round). Raise it when they change.
inline constexpr int kPartsProtocol = 7;  // 2: orientations known but not yet counted (3 to 5, 7 to 9); 3: the first round's tasks; 4: polygon layers read by parts; 5: vertex ids as runs; 6: a task's groups in one call (run_tile_groups); 7: the first round's too (first_runs)

// A round's tile groups as run_groups sees them: a sequence whose item k is group k's tiles (a
// list of dicts), built when asked for, so that the round's tiles never all exist at once (ask
// once per task: each time builds them again). Usable while run_groups runs.
class RoundGroups {
public:
    RoundGroups(const map::MapInParts& parts, std::size_t count);
    std::size_t size() const { return count_; }
    py::list get(std::ptrdiff_t k) const;
    std::uint64_t points(std::ptrdiff_t k) const;  // what group k holds, without building it
    void close() { parts_ = nullptr; }

private:
    std::size_t index(std::ptrdiff_t k) const;  // k (negative from the end) checked, while the round lasts

    const map::MapInParts* parts_;
    std::size_t count_;
};

// The first round of a run whose tiles are built on the workers (map::FirstRoundLead here, the
// stages' tasks elsewhere: python/toposimp/dask.py, first_round): the map's parts to cut, and
// the lead's side of every stage, each answer checked. Usable while the run's first_round runs.
class FirstSteps {
public:
    // `in_file`: where the map's vertices are (the map then holds none): parts of whole records,
    // each read by its task.
    FirstSteps(const map::MapData& map, const io::VerticesInFile* in_file, const map::SimplifyOptions& options, const map::GridPlan& plan,
               unsigned tile_level, std::uint64_t part_vertices);
    std::size_t size() const { return part_chain_.size() - 1; }  // the parts
    py::dict part(std::ptrdiff_t k) const;                         // part k's chains (a dict), built when asked for
    std::uint64_t part_vertices(std::ptrdiff_t k) const;
    void add_facts(const py::dict& facts);  // each part's, in order
    void found(const py::dict& answer);     // each tile's search: {"border", "predicates"}
    py::array_t<std::uint32_t> border();
    void queued(std::uint64_t pinned, std::uint64_t keys);
    std::uint64_t wanted();
    void bound(std::uint64_t key, std::uint32_t id);
    bool marks() const { return lead_->marks(); }
    py::tuple bound_now() const { return py::make_tuple(lead_->bound_key(), lead_->bound_id()); }
    py::list groups(const py::list& tiles);  // each tile holding vertices: (number, busy, open chains)
    py::array_t<double> points(std::uint32_t tile) const;
    std::uint64_t points_in(std::uint32_t tile) const { return lead().points_in(tile); }
    // Tiles' live vertices (dicts) and their groups' outcomes (dicts), as they come (each tile's
    // and each outcome once); then finish, once every tile's came.
    void add(const py::list& live, const py::list& outcomes);
    void finish();
    // Or, the first round's tiles kept where they are (every outcome added, no live vertices):
    // the rounds after go on from them (map::KeptTiles), `store` asked what they answer.
    void keep(py::object store);
    std::unique_ptr<map::MapInParts> take();  // (after close)
    void close() { open_ = false; }

private:
    const map::FirstRoundLead& lead() const;
    map::FirstRoundLead& lead();

    const map::MapData& map_;
    const io::VerticesInFile* in_file_;
    std::uint32_t vertices_;  // the map's
    std::unique_ptr<map::FirstRoundLead> lead_;
    std::vector<std::uint32_t> part_chain_;  // part k: chains [part_chain_[k], part_chain_[k + 1])
    struct FilePart {
        const io::LayerInFile* layer;
        std::uint64_t first, end;  // its records [first, end)
    };
    std::vector<FilePart> file_parts_;  // with in_file_: part k's
    std::uint32_t next_chain_ = 0;
    std::uint64_t here_below_ = 0;
    std::vector<map::LiveVertices> live_;
    std::vector<map::TileOutcome> outcomes_;
    std::unique_ptr<map::MapInParts> parts_;
    py::object kept_store_;
    bool open_ = true;
    friend map::SimplifyResult run_in_parts(const map::MapData&, const map::SimplifyOptions&, const py::object&, int, const py::object&,
                                            std::uint64_t, const io::VerticesInFile*);
};

// RoundGroups, FirstSteps, map::FirstTile and the first round's tasks for Python (and
// bind_kept's).
void bind_parts(py::module_& module);

// The rounds after the first from kept tiles (kept.cpp): map::KeptBatch and its tasks for Python;
// the lead's store over `store`, a Python object whose methods ask the batches (dask.py,
// _KeptStore), for a map of `vertices` vertices and `chains` chains.
void bind_kept(py::module_& module);
std::unique_ptr<map::KeptStore> python_store(py::object store, std::uint32_t vertices, std::uint32_t chains);

// Runs the map in parts (map::MapInParts): each round's tile groups go to
// `run_groups(groups, plan, options, round) -> outcomes` (RoundGroups in, a list per group of
// outcome dicts back, in the same order). If run_groups has a `first_round` attribute, the first
// round is `run_groups.first_round(steps, plan, options)` instead (FirstSteps: its tiles built
// and run on the workers, no engine over the whole map here, the map cut into parts of about
// `tile_points` vertices). The tile level is `tile_level`, or, if negative, the coarsest whose
// biggest tile holds at most `tile_points` vertices and control points (a number, or a callable
// giving it: called once the map is read, and only if the level is to be chosen; 1 000 000
// otherwise). A count target's round whose budget is under `here_below` vertices runs here, whole.
// `in_file`: the map holds no vertex, they are in that file (io::OgrDataset::read's
// vertices_in_file), read here a record at a time to choose the tile level, and by the first
// round's tasks (run_groups must have first_round).
// Called with the GIL released; takes it to call run_groups.
map::SimplifyResult run_in_parts(const map::MapData& map, const map::SimplifyOptions& options, const py::object& run_groups,
                                 int tile_level, const py::object& tile_points, std::uint64_t here_below,
                                 const io::VerticesInFile* in_file = nullptr);

// A task: one group of tile dicts → their outcome dicts (the engine runs without the GIL).
py::list run_tile_group(const py::list& group, const py::dict& plan, const py::dict& options);

// A task of several groups: a list of such groups → a list of their outcome lists (map::run_tile_groups:
// side by side when there are at least as many as threads).
py::list run_tile_groups(const py::list& groups, const py::dict& plan, const py::dict& options);

}  // namespace toposimp::python
