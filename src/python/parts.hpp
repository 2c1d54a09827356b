// The map engine in parts for Python (python/toposimp/dask.py): tiles and their outcomes as dicts
// of numpy arrays, which Dask moves between processes as they are.
#pragma once

#include "core/map/simplify.hpp"
#include "core/map/tiles.hpp"

#include <pybind11/pybind11.h>

#include <cstdint>

namespace toposimp::python {

namespace py = pybind11;

// The tile and outcome dicts' format: a worker whose engine has another cannot run this one's
// tiles (python/toposimp/dask.py checks before the first round). Raise it when they change.
inline constexpr int kPartsProtocol = 2;  // 2: orientations known but not yet counted (3 to 5, 7 to 9)

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

// RoundGroups for Python.
void bind_parts(py::module_& module);

// Runs the map in parts (map::MapInParts): each round's tile groups go to
// `run_groups(groups, plan, options, round) -> outcomes` (RoundGroups in, a list per group of
// outcome dicts back, in the same order). The tile level is `tile_level`, or,
// if negative, the coarsest whose biggest tile holds at most `tile_points` vertices and control
// points (a number, or a callable giving it: called once the map is read). A count target's round whose budget is under `here_below` vertices runs here, whole.
// Called with the GIL released; takes it to call run_groups.
map::SimplifyResult run_in_parts(const map::MapData& map, const map::SimplifyOptions& options, const py::object& run_groups,
                                 int tile_level, const py::object& tile_points, std::uint64_t here_below);

// A task: one group of tile dicts → their outcome dicts (the engine runs without the GIL).
py::list run_tile_group(const py::list& group, const py::dict& plan, const py::dict& options);

}  // namespace toposimp::python
