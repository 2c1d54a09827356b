#include "python/parts.hpp"
#include "python/wire.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "core/map/coverage.hpp"
#include "core/parallel/side_by_side.hpp"
#include "io/common/errors.hpp"
#include "io/map/shapefile.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace toposimp::python {

namespace {

// After a task's engine ran: its arrays are freed; give their pages back, so that the worker's
// memory (what Dask's memory limit watches) falls back to what it holds.
void give_pages_back() {
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}

// The coarsest level below the top whose biggest tile holds at most `budget` vertices and
// control points (0 if none does: every level-0 block a tile). Counted in a dense array at the
// finest level whose blocks number at most 2^22, and summed up from there: tiles are never finer
// than that level (a map of more than 2^22 level-0 blocks has tiles of a few blocks at least).
// `for_each(add)` calls add(p) for every vertex and control point of the map.
template <class ForEach>
unsigned tile_level_for(const map::GridPlan& plan, std::uint64_t budget, ForEach for_each) {
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
    for_each([&](Point p) { ++count[std::size_t{plan.block_row(p, dense)} * columns + plan.block_column(p, dense)]; });
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

// ---- The first round on the workers (map::cut_part, map::FirstTile; map::FirstRoundLead here)

// Chains [c0, c1) of `map` as a part: its own map, and where it starts in the whole map's.
py::dict part_dict(const map::MapData& map, std::uint32_t c0, std::uint32_t c1) {
    const std::uint32_t v0 = map.chains[c0].first, v1 = map.chains[c1 - 1].last + 1;
    py::array_t<double> vertices({static_cast<py::ssize_t>(v1 - v0), py::ssize_t{2}});
    std::memcpy(vertices.mutable_data(), map.vertices.data() + v0, std::size_t{v1 - v0} * sizeof(Point));
    std::vector<std::pair<std::uint32_t, std::uint32_t>> chains;
    std::vector<std::uint8_t> frozen;
    for (std::uint32_t c = c0; c < c1; ++c) {
        chains.emplace_back(map.chains[c].first - v0, map.chains[c].last - v0);
        frozen.push_back(map.is_frozen(c) ? 1 : 0);
    }
    py::dict dict;
    dict["vertices"] = vertices;
    dict["chains"] = pairs_array(chains);
    dict["frozen"] = array_of(frozen);
    dict["first_vertex"] = v0;
    dict["first_chain"] = c0;
    return dict;
}

// The chains records [r0, r1) of a layer left in its file make (its vertices from the first's
// on), for the part's reader to check.
void add_chains(py::dict& dict, const map::MapData& map, const io::LayerInFile& layer, std::uint64_t r0, std::uint64_t r1) {
    const std::uint32_t c0 = layer.record_chain[r0], c1 = layer.record_chain[r1];
    std::vector<std::pair<std::uint32_t, std::uint32_t>> chains;
    for (std::uint32_t c = c0; c < c1; ++c) {
        chains.emplace_back(map.chains[c].first - layer.record_vertex[r0], map.chains[c].last - layer.record_vertex[r0]);
    }
    dict["chains"] = pairs_array(chains);
    dict["first_vertex"] = layer.record_vertex[r0];
    dict["vertices"] = layer.record_vertex[r1] - layer.record_vertex[r0];
    dict["first_chain"] = c0;
}

// Where features [r0, r1) of a layer left in its file are (io::FeatureRun: a GeoPackage's FIDs
// too, or that a FlatGeobuf's are read one by one), its file under `path_key`.
void add_run(py::dict& dict, const io::LayerInFile& layer, const char* path_key, std::uint64_t r0, std::uint64_t r1) {
    const io::FeatureRun run = layer.run(r0, r1);
    dict[path_key] = layer.path;
    dict["layer"] = layer.layer;
    dict["size"] = std::uint64_t{layer.size};
    dict["time"] = layer.time;
    dict["features"] = py::make_tuple(r0, r1);
    if (run.by_fid) dict["fids"] = py::make_tuple(run.fid_first, run.fid_end);
    if (run.each_by_fid) dict["each_by_fid"] = true;
}

// Features [r0, r1) of a polygon layer a map's vertices are in as a part: where they are, the
// coverage's slice for their rings (map::arcs_of), and the chains they make.
py::dict polygon_part_dict(const map::MapData& map, const io::LayerInFile& layer, const map::Coverage& coverage, std::uint64_t r0,
                           std::uint64_t r1) {
    py::dict dict;
    add_run(dict, layer, "polygons_file", r0, r1);
    const map::CoverageSlice slice = coverage.slice(layer.record_ring[r0], layer.record_ring[r1]);
    dict["first_ring"] = slice.first_ring;
    dict["degenerate"] = array_of(slice.degenerate);
    dict["clean_count"] = slice.clean_count;
    dict["node"] = array_of(slice.node);
    dict["uses_start"] = array_of(slice.uses_start);
    std::vector<std::uint32_t> uses;
    for (const map::Coverage::ArcUse use : slice.uses) uses.push_back(use.chain);
    dict["uses"] = array_of(uses);  // (their chains: what arcs_of reads)
    dict["chain_size"] = array_of(slice.chain_size);
    if (slice.first_chain != layer.record_chain[r0] || slice.end_chain != layer.record_chain[r1]) {
        throw std::logic_error("a polygon layer's features are not their rings' chains");
    }
    add_chains(dict, map, layer, r0, r1);
    return dict;
}

// Records [r0, r1) of a layer a map's vertices are in as a part: where they are, and what the map
// made of them (checked by the part's reader, first_cut).
py::dict file_part_dict(const map::MapData& map, const io::VerticesInFile& in_file, const io::LayerInFile& layer, std::uint64_t r0,
                        std::uint64_t r1) {
    if (layer.polygons) return polygon_part_dict(map, layer, *in_file.coverage, r0, r1);
    py::dict dict;
    if (layer.ogr_lines) {
        add_run(dict, layer, "lines_file", r0, r1);
        add_chains(dict, map, layer, r0, r1);
        return dict;
    }
    dict["shp"] = layer.path;
    dict["layer"] = layer.layer;
    dict["shp_size"] = std::uint64_t{layer.size};
    dict["shp_time"] = layer.time;
    dict["records"] = py::make_tuple(r0, r1);
    add_chains(dict, map, layer, r0, r1);
    return dict;
}

// InputError unless the file at `path` has the size and modification time the part says (under
// `size_key` and `time_key`): a worker reads the input the command read.
void check_part_file(const py::dict& dict, const std::string& path, const char* size_key, const char* time_key) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    if (error || size != item(dict, size_key).cast<std::uint64_t>() || io::modified_ns(path) != item(dict, time_key).cast<std::int64_t>()) {
        throw io::InputError("'" + path + "' cannot be read here as it was when the map was read" +
                             (error ? " (" + error.message() + ")" : std::string(" (another size or modification time)")) +
                             ": every worker reads the input at the same absolute path, unchanged (or use --send-input: the "
                             "parts are then sent from the command)");
    }
}

// The run of features a part made by add_run reads, its file checked first (check_part_file).
io::FeatureRun run_of(const py::dict& dict, const char* path_key) {
    io::FeatureRun run;
    run.path = item(dict, path_key).cast<std::string>();
    run.layer = item(dict, "layer").cast<std::string>();
    std::tie(run.first, run.end) = item(dict, "features").cast<std::pair<std::uint64_t, std::uint64_t>>();
    if (dict.contains("fids")) {
        run.by_fid = true;
        std::tie(run.fid_first, run.fid_end) = item(dict, "fids").cast<std::pair<std::int64_t, std::int64_t>>();
    }
    run.each_by_fid = dict.contains("each_by_fid") && item(dict, "each_by_fid").cast<bool>();
    if (run.end < run.first || run.fid_end < run.fid_first) malformed("a part's features run backwards");
    check_part_file(dict, run.path, "size", "time");
    return run;
}

// Does `part`, read from its file, hold the chains the part says (file_part_dict's "chains" and
// "vertices")?
bool holds_part_chains(const map::MapData& part, const py::dict& dict) {
    const std::vector<map::Chain> chains = consecutive_chains(dict, "chains", item(dict, "vertices").cast<std::uint64_t>());
    return part.vertices.size() == item(dict, "vertices").cast<std::uint64_t>() && part.chains.size() == chains.size() &&
           std::equal(chains.begin(), chains.end(), part.chains.begin(),
                      [](const map::Chain& a, const map::Chain& b) { return a.first == b.first && a.last == b.last; });
}

// A part read from its file (file_part_dict): the same chains, or InputError.
map::MapData file_part_of(const py::dict& dict) {
    const auto shp = item(dict, "shp").cast<std::string>();
    const auto [r0, r1] = item(dict, "records").cast<std::pair<std::uint64_t, std::uint64_t>>();
    check_part_file(dict, shp, "shp_size", "shp_time");
    map::MapData part;
    {
        py::gil_scoped_release release;
        part = io::read_shapefile_lines(shp, item(dict, "layer").cast<std::string>(), r0, r1);
    }
    if (!holds_part_chains(part, dict)) {
        throw io::InputError("'" + shp + "': records " + std::to_string(r0) + " to " + std::to_string(r1) +
                             " are not the lines they were when the map was read");
    }
    return part;
}

// A part read from a lines layer read through OGR (file_part_dict): the same chains, or
// InputError.
map::MapData lines_part_of(const py::dict& dict) {
    const io::FeatureRun run = run_of(dict, "lines_file");
    map::MapData part;
    {
        py::gil_scoped_release release;
        part = io::read_lines(run);
    }
    if (!holds_part_chains(part, dict)) {
        throw io::InputError("'" + run.path + "', layer '" + run.layer + "': features " + std::to_string(run.first) + " to " +
                             std::to_string(run.end) + " are not the lines they were when the map was read");
    }
    return part;
}

// A part read from its polygon layer (polygon_part_dict): the same chains, or InputError.
map::MapData polygon_part_of(const py::dict& dict) {
    const io::FeatureRun run = run_of(dict, "polygons_file");
    const std::string& path = run.path;
    const std::string& layer = run.layer;
    const std::uint64_t r0 = run.first, r1 = run.end;
    map::CoverageSlice slice;
    slice.first_ring = item(dict, "first_ring").cast<std::uint32_t>();
    slice.degenerate = flat<std::uint8_t>(dict, "degenerate");
    slice.clean_count = item(dict, "clean_count").cast<std::uint32_t>();
    slice.node = flat<std::uint64_t>(dict, "node");
    slice.uses_start = flat<std::uint32_t>(dict, "uses_start");
    for (const std::uint32_t chain : flat<std::uint32_t>(dict, "uses")) slice.uses.push_back({chain, false});
    slice.chain_size = flat<std::uint32_t>(dict, "chain_size");
    slice.first_chain = item(dict, "first_chain").cast<std::uint32_t>();
    slice.end_chain = slice.first_chain + static_cast<std::uint32_t>(slice.chain_size.size());
    if (slice.uses_start.size() != slice.degenerate.size() + 1 || slice.node.size() != (std::uint64_t{slice.clean_count} + 63) / 64 ||
        slice.uses_start.front() != 0 || slice.uses_start.back() != slice.uses.size() ||
        !std::is_sorted(slice.uses_start.begin(), slice.uses_start.end()) || slice.end_chain < slice.first_chain) {
        malformed("a polygon part's slice does not hold together");
    }
    map::MapData part;
    {
        py::gil_scoped_release release;
        try {
            part = map::arcs_of(slice, [&](const std::function<void(std::span<const Point>)>& visit) {
                io::for_each_polygon_ring(run, visit);
            });
        } catch (const std::invalid_argument&) {
            part.chains.clear();
            part.vertices.clear();
        }
    }
    if (!holds_part_chains(part, dict)) {
        throw io::InputError("'" + path + "', layer '" + layer + "': features " + std::to_string(r0) + " to " + std::to_string(r1) +
                             " are not the polygons they were when the map was read");
    }
    return part;
}

map::MapData part_of(const py::dict& dict) {
    if (dict.contains("shp")) return file_part_of(dict);
    if (dict.contains("polygons_file")) return polygon_part_of(dict);
    if (dict.contains("lines_file")) return lines_part_of(dict);
    map::MapData part;
    part.vertices = points_of(dict, "vertices");
    if (part.vertices.size() >= std::numeric_limits<std::uint32_t>::max()) malformed("too many vertices");
    part.chains = consecutive_chains(dict, "chains", part.vertices.size());
    part.frozen = flat<std::uint8_t>(dict, "frozen");
    if (part.frozen.size() != part.chains.size()) malformed("frozen is not one per chain");
    return part;
}

py::dict facts_dict(const map::CutPart& cut, std::uint32_t first_chain) {
    const map::ChainFacts& facts = cut.facts;
    py::dict dict;
    dict["first_chain"] = first_chain;
    dict["chains"] = pairs_array(chain_pairs(facts.chains));
    dict["whole_level"] = array_of(facts.whole_level);
    dict["distinct"] = array_of(facts.distinct);
    dict["orientation"] = array_of(facts.orientation);
    // Its tiles: their numbers, vertices (with cut ends) and open rings (for the tasks' batches).
    std::vector<std::uint32_t> tiles;
    std::vector<std::uint64_t> vertices;
    py::list open;
    for (const map::FirstTile& tile : cut.tiles) {
        tiles.push_back(tile.number);
        vertices.push_back(tile.input.vertex_id.size());
        open.append(array_of(tile.open_chains()));
    }
    dict["tiles"] = array_of(tiles);
    dict["tile_vertices"] = array_of(vertices);
    dict["tile_open"] = open;
    return dict;
}

// A part's facts back, checked against a map of `n` vertices.
map::ChainFacts facts_of(const py::dict& dict, std::size_t n) {
    map::ChainFacts facts;
    for (const auto& [first, last] : pairs_of(dict, "chains")) {
        if (last < first || last >= n) malformed("a chain's ends are not the map's vertices");
        facts.chains.push_back({first, last});
    }
    facts.whole_level = flat<std::uint8_t>(dict, "whole_level");
    facts.distinct = flat<std::uint32_t>(dict, "distinct");
    facts.orientation = flat<std::int8_t>(dict, "orientation");
    const std::size_t c = facts.chains.size();
    if (facts.whole_level.size() != c || facts.distinct.size() != c || facts.orientation.size() != c) {
        malformed("whole_level, distinct or orientation is not one per chain");
    }
    if (!std::all_of(facts.orientation.begin(), facts.orientation.end(), orientation_code)) malformed("an orientation is not one");
    return facts;
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

FirstSteps::FirstSteps(const map::MapData& map, const io::VerticesInFile* in_file, const map::SimplifyOptions& options,
                       const map::GridPlan& plan, unsigned tile_level, std::uint64_t part_vertices)
    : map_(map),
      in_file_(in_file),
      vertices_(static_cast<std::uint32_t>(in_file ? in_file->vertices : map.vertices.size())),
      lead_(std::make_unique<map::FirstRoundLead>(plan, tile_level, options, vertices_)) {
    lead_->add_control_points(map.control_points);
    const auto chains = static_cast<std::uint32_t>(map.chains.size());
    part_chain_.push_back(0);
    if (in_file) {
        // Parts of whole records of a layer, each with a chain (the records after a layer's last
        // chain go to its part before; records without one before any are in none), in the
        // order of their chains.
        std::uint32_t next = 0;
        for (const io::LayerInFile* layer : in_file->in_chain_order()) {
            const std::vector<std::uint64_t>& first = layer->record_vertex;
            const std::vector<std::uint32_t>& chain = layer->record_chain;
            if (chain.empty() || chain.front() != next || (layer->polygons && in_file->coverage == nullptr)) {
                throw std::logic_error("a map's vertices in a file, not its chains");
            }
            const std::uint64_t records = first.size() - 1;
            bool here = false;  // a part of this layer made
            for (std::uint64_t r = 0; r < records;) {
                const std::uint64_t r0 = r;
                while (r < records && (first[r] == first[r0] || first[r] - first[r0] < part_vertices)) ++r;
                if (chain[r] == chain[r0]) {
                    if (here) file_parts_.back().end = r;
                } else {
                    file_parts_.push_back({layer, r0, r});
                    part_chain_.push_back(chain[r]);
                    here = true;
                }
            }
            next = chain.back();
        }
        if (next != chains || (!map.frozen.empty() && in_file->coverage == nullptr)) throw std::logic_error("a map's vertices in a file, not its chains");
        return;
    }
    for (std::uint32_t c = 0; c < chains;) {
        const std::uint32_t first = map.chains[c].first;
        while (c < chains && (c == part_chain_.back() || map.chains[c].last - first < part_vertices)) ++c;
        part_chain_.push_back(c);
    }
}

const map::FirstRoundLead& FirstSteps::lead() const {
    if (!open_ || lead_ == nullptr) throw std::runtime_error("the first round is over: its steps are gone");
    return *lead_;
}

map::FirstRoundLead& FirstSteps::lead() {
    if (!open_ || lead_ == nullptr) throw std::runtime_error("the first round is over: its steps are gone");
    return *lead_;
}

py::dict FirstSteps::part(std::ptrdiff_t k) const {
    lead();
    if (k < 0) k += static_cast<std::ptrdiff_t>(size());
    if (k < 0 || static_cast<std::size_t>(k) >= size()) throw py::index_error("no such part of the map");
    const auto at = static_cast<std::size_t>(k);
    if (in_file_) return file_part_dict(map_, *in_file_, *file_parts_[at].layer, file_parts_[at].first, file_parts_[at].end);
    return part_dict(map_, part_chain_[at], part_chain_[at + 1]);
}

std::uint64_t FirstSteps::part_vertices(std::ptrdiff_t k) const {
    lead();
    if (k < 0 || static_cast<std::size_t>(k) >= size()) throw py::index_error("no such part of the map");
    const auto at = static_cast<std::size_t>(k);
    if (in_file_) {
        const FilePart& part = file_parts_[at];
        return part.layer->record_vertex[part.end] - part.layer->record_vertex[part.first];
    }
    return map_.chains[part_chain_[at + 1] - 1].last + 1 - map_.chains[part_chain_[at]].first;
}

void FirstSteps::add_facts(const py::dict& dict) {
    map::FirstRoundLead& first = lead();
    const map::ChainFacts facts = facts_of(dict, vertices_);
    if (item(dict, "first_chain").cast<std::uint32_t>() != next_chain_) malformed("a part's facts are not the next part's");
    // (The chains must be this map's: the part was cut from it.)
    for (std::size_t i = 0; i < facts.chains.size(); ++i) {
        const std::size_t c = next_chain_ + i;
        if (c >= map_.chains.size() || facts.chains[i].first != map_.chains[c].first || facts.chains[i].last != map_.chains[c].last) {
            malformed("a part's facts are not of the map's chains");
        }
    }
    first.add_facts(facts, next_chain_);
    next_chain_ += static_cast<std::uint32_t>(facts.chains.size());
}

void FirstSteps::found(const py::dict& answer) {
    const std::vector<std::uint32_t> border = flat<std::uint32_t>(answer, "border");
    if (std::any_of(border.begin(), border.end(), [&](std::uint32_t v) { return v >= vertices_; })) {
        malformed("a tile's search names a segment the map has not");
    }
    lead().found(border, predicates_of(item(answer, "predicates")));
}

py::array_t<std::uint32_t> FirstSteps::border() {
    map::FirstRoundLead& first = lead();
    if (next_chain_ != map_.chains.size()) malformed("not every part's facts came");
    return array_of(first.border());
}

void FirstSteps::queued(std::uint64_t pinned, std::uint64_t keys) { lead().queued(pinned, keys); }

std::uint64_t FirstSteps::wanted() { return lead().wanted(); }

void FirstSteps::bound(std::uint64_t key, std::uint32_t id) {
    if (id >= vertices_) malformed("the bound names a vertex the map has not");
    lead().bound({key, id});
}

py::list FirstSteps::groups(const py::list& tiles) {
    std::vector<map::FirstRoundLead::TileFacts> facts;
    const std::uint32_t chains = lead().chains();
    for (const py::handle tile : tiles) {
        const auto [number, busy, open] = tile.cast<std::tuple<std::uint32_t, bool, py::object>>();
        py::dict holder;
        holder["open"] = open;
        std::vector<std::uint32_t> list = flat<std::uint32_t>(holder, "open");
        if (std::any_of(list.begin(), list.end(), [&](std::uint32_t c) { return c >= chains; })) malformed("a tile names a chain the map has not");
        facts.push_back({number, busy, std::move(list)});
    }
    py::list out;
    for (const std::vector<std::uint32_t>& group : lead().groups(std::move(facts))) out.append(py::cast(group));
    return out;
}

py::array_t<double> FirstSteps::points(std::uint32_t tile) const { return points_array(lead().points(tile)); }

void FirstSteps::add(const py::list& live_list, const py::list& outcome_list) {
    const map::FirstRoundLead& first = lead();
    for (const py::handle one : live_list) live_.push_back(live_of(one.cast<py::dict>(), vertices_, first.marks()));
    for (const py::handle one : outcome_list) outcomes_.push_back(outcome_of(one.cast<py::dict>(), vertices_, chains_of(map_)));
}

void FirstSteps::finish() {
    map::FirstRoundLead& first = lead();
    {
        py::gil_scoped_release release;
        try {
            parts_ = first.finish(std::move(live_), outcomes_, here_below_);
        } catch (const std::invalid_argument& error) {
            py::gil_scoped_acquire gil;
            malformed(error.what());
        }
        std::vector<map::TileOutcome>().swap(outcomes_);
    }
    lead_.reset();
}

void FirstSteps::keep(py::object store) {
    lead();  // (open)
    kept_store_ = std::move(store);
}

std::unique_ptr<map::MapInParts> FirstSteps::take() {
    if (parts_ == nullptr) malformed("the first round did not finish");
    return std::move(parts_);
}

namespace {

// The first round's tasks (python/toposimp/dask.py).

// A part of the map → (its facts, its tiles' pieces).
py::tuple first_cut(const py::dict& part, const py::dict& plan, unsigned tile_level, const py::dict& options) {
    const map::MapData data = part_of(part);
    const auto first_vertex = item(part, "first_vertex").cast<std::uint32_t>();
    const auto first_chain = item(part, "first_chain").cast<std::uint32_t>();
    if (std::uint64_t{first_vertex} + data.vertices.size() >= std::numeric_limits<std::uint32_t>::max() ||
        std::uint64_t{first_chain} + data.chains.size() >= std::numeric_limits<std::uint32_t>::max()) {
        malformed("a part's vertices or chains are beyond the map's ids");
    }
    const map::GridPlan grid = plan_of(plan);
    const map::SimplifyOptions simplify = options_of(options);
    map::CutPart cut;
    {
        py::gil_scoped_release release;
        cut = map::cut_part(data, first_vertex, first_chain, grid, tile_level, simplify);
    }
    py::dict facts = facts_dict(cut, first_chain);
    py::list tiles;
    for (map::FirstTile& tile : cut.tiles) tiles.append(py::cast(std::move(tile)));
    return py::make_tuple(facts, tiles);
}

// A tile's pieces from every part (in order) → (the tile searched, {"border", "predicates"}).
py::tuple first_search(const py::list& pieces, const py::dict& options) {
    const map::SimplifyOptions simplify = options_of(options);
    const std::vector<const map::FirstTile*> parts = tiles_in(pieces);
    if (parts.empty()) malformed("a tile without pieces");
    map::FirstTile tile;
    std::vector<std::uint32_t> border;
    exact::PredicateStats predicates;
    {
        py::gil_scoped_release release;
        tile = *parts.front();
        for (std::size_t k = 1; k < parts.size(); ++k) {
            if (parts[k]->number != tile.number) malformed("a tile's pieces are not of one tile");
            tile.add(map::FirstTile(*parts[k]));
        }
        border = tile.search(simplify.arithmetic, predicates);
    }
    py::dict answer;
    answer["border"] = array_of(border);
    answer["predicates"] = predicates_tuple(predicates);
    return py::make_tuple(py::cast(std::move(tile)), answer);
}

// A histogram as its nonzero digits and their counts.
std::vector<std::uint64_t> tiles_histogram(const std::vector<const map::FirstTile*>& tiles, int shift, std::uint64_t high) {
    if (shift < 0 || shift > 48 || shift % 16 != 0) malformed("a histogram's digit is not one");
    std::vector<std::uint64_t> counts(std::size_t{1} << 16, 0);
    for (const map::FirstTile* tile : tiles) tile->histogram(shift, high, counts);
    return counts;
}

// A searched tile and the lead's border → (the tile queued, what the lead needs of it: pinned and
// queued counts, its vertices, its open chains, and a count target's smallest pair and first
// histogram).
py::tuple first_queue(const map::FirstTile& searched, const py::object& border, bool marks, const py::dict& options) {
    const map::SimplifyOptions simplify = options_of(options);
    py::dict holder;
    holder["border"] = border;
    const std::vector<std::uint32_t> sorted = flat<std::uint32_t>(holder, "border");
    if (!std::is_sorted(sorted.begin(), sorted.end())) malformed("the border is not sorted");
    if (searched.improper.size() != searched.input.vertex_id.size()) malformed("a tile queued before its search");
    map::FirstTile tile;
    std::uint64_t pinned = 0;
    std::vector<std::uint64_t> counts;
    {
        py::gil_scoped_release release;
        tile = searched;
        pinned = tile.queue(sorted, marks, simplify.ranking);
        if (marks) counts = tiles_histogram({&tile}, 48, 0);
    }
    py::dict answer;
    answer["number"] = tile.number;
    answer["pinned"] = pinned;
    answer["queued"] = tile.queued();
    answer["vertices"] = tile.input.vertex_id.size();
    answer["open"] = array_of(tile.open_chains());
    if (marks) {
        answer["histogram"] = sparse_histogram(counts);
        answer["smallest"] = tile.smallest();
    }
    return py::make_tuple(py::cast(std::move(tile)), answer);
}

// The sum of the tiles' histograms (select_kth_by_digits's), sparse.
py::dict first_histogram(const py::list& tiles, int shift, std::uint64_t high) {
    const std::vector<const map::FirstTile*> all = tiles_in(tiles);
    std::vector<std::uint64_t> counts;
    {
        py::gil_scoped_release release;
        counts = tiles_histogram(all, shift, high);
    }
    return sparse_histogram(counts);
}

py::array_t<std::uint32_t> first_ids_at(const py::list& tiles, std::uint64_t key) {
    std::vector<std::uint32_t> ids;
    for (const map::FirstTile* tile : tiles_in(tiles)) tile->ids_at(key, ids);
    return array_of(ids);
}

// The tiles' (key, id) pairs in a DigitSelector's bucket.
py::dict first_pairs_in(const py::list& tiles, int shift, std::uint64_t prefix) {
    if (shift < 0 || shift > 48 || shift % 16 != 0) malformed("a bucket's digit is not one");
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> ids;
    for (const map::FirstTile* tile : tiles_in(tiles)) tile->pairs_in(shift, prefix, keys, ids);
    py::dict dict;
    dict["keys"] = array_of(keys);
    dict["ids"] = array_of(ids);
    return dict;
}

// A group of queued tiles with their control points, checked (with the GIL).
struct FirstGroup {
    std::vector<const map::FirstTile*> tiles;
    std::vector<std::vector<Point>> inside;
};

FirstGroup first_group(const py::list& tiles, const py::list& points, bool marks, const map::GridPlan& grid) {
    FirstGroup group{tiles_in(tiles), {}};
    if (points.size() != group.tiles.size()) malformed("not one list of control points per tile");
    for (const py::handle one : points) {
        py::dict holder;
        holder["points"] = one;
        group.inside.push_back(points_of(holder, "points"));
    }
    for (const map::FirstTile* tile : group.tiles) {
        if (tile->input.state.size() != tile->input.vertex_id.size() || (marks && tile->keys.size() != tile->queued())) {
            malformed("a tile run before it is queued");
        }
        if (tile->input.level != group.tiles.front()->input.level || tile->input.level > grid.levels) malformed("the tiles are not of one level of the plan");
    }
    return group;
}

struct FirstGroupRun {
    std::vector<map::TileOutcome> outcomes;
    std::vector<map::LiveVertices> live;
};

// (Without the GIL.) A group's tiles run; with live_too, their live vertices after.
FirstGroupRun run_first_group(FirstGroup& group, bool marks, std::pair<double, std::uint32_t> bound, const map::GridPlan& grid,
                              const map::SimplifyOptions& options, bool live_too) {
    FirstGroupRun run;
    std::vector<map::TileInput> inputs;
    for (std::size_t k = 0; k < group.tiles.size(); ++k) {
        inputs.push_back(group.tiles[k]->run_input(marks, bound.first, bound.second, std::move(group.inside[k])));
    }
    run.outcomes = map::run_tile_group(std::move(inputs), grid, options);
    if (live_too) {
        const auto changed = map::changed_states(run.outcomes);
        for (const map::FirstTile* tile : group.tiles) run.live.push_back(map::live_vertices(*tile, changed, marks, bound.first, bound.second));
    }
    return run;
}

py::tuple first_run_tuple(const FirstGroupRun& run) {
    py::list outcome_list, live_list;
    for (const map::TileOutcome& outcome : run.outcomes) outcome_list.append(outcome_dict(outcome));
    for (const map::LiveVertices& one : run.live) live_list.append(live_dict(one));
    return py::make_tuple(outcome_list, live_list);
}

// A group of queued tiles run, with their control points → (their outcomes, their live vertices).
py::tuple first_run(const py::list& tiles, const py::list& points, bool marks, std::pair<double, std::uint32_t> bound, const py::dict& plan,
                    const py::dict& options, bool live_too) {
    const map::GridPlan grid = plan_of(plan);
    FirstGroup group = first_group(tiles, points, marks, grid);
    const map::SimplifyOptions simplify = options_of(options);
    FirstGroupRun run;
    {
        py::gil_scoped_release release;
        run = run_first_group(group, marks, bound, grid, simplify, live_too);
        give_pages_back();
    }
    return first_run_tuple(run);
}

// A batch's groups (`groups`: a list of tile lists; `points`: per group, its tiles' control
// points) → first_run's answer per group. Side by side, a thread each, when there are at least as
// many as threads (parallel::side_by_side; all their control points here at once, where
// first_run group after group holds one group's).
py::list first_runs(const py::list& groups, const py::list& points, bool marks, std::pair<double, std::uint32_t> bound, const py::dict& plan,
                    const py::dict& options, bool live_too) {
    const map::GridPlan grid = plan_of(plan);
    if (points.size() != groups.size()) malformed("not one list of control points per group");
    std::vector<FirstGroup> all;
    for (std::size_t k = 0; k < groups.size(); ++k) all.push_back(first_group(groups[k].cast<py::list>(), points[k].cast<py::list>(), marks, grid));
    const map::SimplifyOptions simplify = options_of(options);
    std::vector<FirstGroupRun> runs(all.size());
    {
        py::gil_scoped_release release;
        const auto size = [&](std::size_t k) {
            std::size_t sum = 0;
            for (std::size_t t = 0; t < all[k].tiles.size(); ++t) sum += all[k].tiles[t]->input.vertex_id.size() + all[k].inside[t].size();
            return sum;
        };
        parallel::side_by_side(all.size(), simplify.threads, size,
                               [&](std::size_t k, int threads) {
                                   map::SimplifyOptions mine = simplify;
                                   mine.threads = threads;
                                   runs[k] = run_first_group(all[k], marks, bound, grid, mine, live_too);
                               });
        give_pages_back();
    }
    py::list out;
    for (const FirstGroupRun& run : runs) out.append(first_run_tuple(run));
    return out;
}

// A queued tile whose group sat the round out → its live vertices.
py::dict first_live(const map::FirstTile& tile, bool marks, std::pair<double, std::uint32_t> bound) {
    if (tile.input.state.size() != tile.input.vertex_id.size()) malformed("a tile's live vertices asked for before it is queued");
    return live_dict(map::live_vertices(tile, {}, marks, bound.first, bound.second));
}

}  // namespace

void bind_parts(py::module_& module) {
    py::class_<RoundGroups>(module, "RoundGroups",
                            "A round's tile groups: groups[k] builds group k's tiles (a list of dicts) when asked for")
        .def("__len__", &RoundGroups::size)
        .def("__getitem__", &RoundGroups::get, py::arg("k"))
        .def("points", &RoundGroups::points, py::arg("k"),
             "group k's vertices (with its tiles' cut ends) and control points, known before it is built");
    py::class_<FirstSteps, std::shared_ptr<FirstSteps>>(module, "FirstSteps", "The first round's side here, while the run's first_round runs (python/parts.hpp)")
        .def("__len__", &FirstSteps::size)
        .def("part", &FirstSteps::part, py::arg("k"))
        .def("part_vertices", &FirstSteps::part_vertices, py::arg("k"))
        .def("add_facts", &FirstSteps::add_facts, py::arg("facts"))
        .def("found", &FirstSteps::found, py::arg("answer"))
        .def("border", &FirstSteps::border)
        .def("queued", &FirstSteps::queued, py::arg("pinned"), py::arg("keys"))
        .def("wanted", &FirstSteps::wanted)
        .def("bound", &FirstSteps::bound, py::arg("key"), py::arg("id"))
        .def_property_readonly("marks", &FirstSteps::marks)
        .def_property_readonly("bound_now", &FirstSteps::bound_now)
        .def("groups", &FirstSteps::groups, py::arg("tiles"))
        .def("points", &FirstSteps::points, py::arg("tile"))
        .def("points_in", &FirstSteps::points_in, py::arg("tile"))
        .def("add", &FirstSteps::add, py::arg("live"), py::arg("outcomes"))
        .def("finish", &FirstSteps::finish)
        .def("keep", &FirstSteps::keep, py::arg("store"));
    py::class_<parallel::DigitSelector>(module, "DigitSelector", "The k-th smallest (key, id) by a histogram of 16-bit digits a pass")
        .def(py::init<std::uint64_t>(), py::arg("k"))
        .def_property_readonly("counting", &parallel::DigitSelector::counting)
        .def_property_readonly("shift", &parallel::DigitSelector::shift)
        .def_property_readonly("high", &parallel::DigitSelector::high)
        .def_property_readonly("key", &parallel::DigitSelector::key)
        .def("counted",
             [](parallel::DigitSelector& selector, const py::object& total) {
                 if (!selector.counting()) malformed("a histogram after the last pass");
                 py::dict holder;
                 holder["total"] = total;
                 const std::vector<std::uint64_t> counts = flat<std::uint64_t>(holder, "total");
                 if (counts.size() != (std::size_t{1} << 16)) malformed("a histogram is not of 65536 counts");
                 selector.counted(counts);
             })
        .def("choose_among",
             [](const parallel::DigitSelector& selector, const py::object& keys, const py::object& ids) {
                 // The pairs of the bucket the last pass ended in, gathered: the rank-th of them.
                 if (selector.shift() == 48) malformed("pairs chosen among before a pass");
                 py::dict holder;
                 holder["keys"] = keys;
                 holder["ids"] = ids;
                 const std::vector<std::uint64_t> all_keys = flat<std::uint64_t>(holder, "keys");
                 const std::vector<std::uint32_t> all_ids = flat<std::uint32_t>(holder, "ids");
                 const int shift = selector.shift() + 16;
                 if (all_keys.size() != all_ids.size() || selector.rank() < 1 || all_keys.size() < selector.rank()) {
                     malformed("fewer pairs in the bucket than its rank");
                 }
                 std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
                 pairs.reserve(all_keys.size());
                 for (std::size_t k = 0; k < all_keys.size(); ++k) {
                     if (all_keys[k] >> shift != selector.high()) malformed("a pair is not in the bucket");
                     pairs.emplace_back(all_keys[k], all_ids[k]);
                 }
                 const auto at = pairs.begin() + static_cast<std::ptrdiff_t>(selector.rank() - 1);
                 std::nth_element(pairs.begin(), at, pairs.end());
                 return py::make_tuple(at->first, at->second);
             })
        .def("choose", [](const parallel::DigitSelector& selector, const py::object& ids) {
            if (selector.counting()) malformed("ids chosen among before the last pass");
            py::dict holder;
            holder["ids"] = ids;
            std::vector<std::uint32_t> all = flat<std::uint32_t>(holder, "ids");
            if (selector.rank() < 1 || all.size() < selector.rank()) malformed("fewer ids at the key than its rank");
            const parallel::KeyedSelection chosen = selector.choose(std::move(all));
            return py::make_tuple(chosen.key, chosen.id);
        });
    py::class_<map::FirstTile>(module, "FirstTile", "A tile of the first round as it is built (core/map/tiles.hpp)")
        .def_property_readonly("number", [](const map::FirstTile& tile) { return tile.number; })
        .def_property_readonly("vertices", [](const map::FirstTile& tile) { return tile.input.vertex_id.size(); })
        .def(py::pickle([](const map::FirstTile& tile) { return first_tile_dict(tile); },
                        [](const py::dict& dict) { return first_tile_of(dict); }));
    module.def("first_cut", &first_cut, py::arg("part"), py::arg("plan"), py::arg("tile_level"), py::arg("options"));
    module.def("first_search", &first_search, py::arg("pieces"), py::arg("options"));
    module.def("first_queue", &first_queue, py::arg("tile"), py::arg("border"), py::arg("marks"), py::arg("options"));
    module.def("first_histogram", &first_histogram, py::arg("tiles"), py::arg("shift"), py::arg("high"));
    module.def("first_ids_at", &first_ids_at, py::arg("tiles"), py::arg("key"));
    module.def("first_pairs_in", &first_pairs_in, py::arg("tiles"), py::arg("shift"), py::arg("prefix"));
    module.def("first_run", &first_run, py::arg("tiles"), py::arg("points"), py::arg("marks"), py::arg("bound"), py::arg("plan"),
               py::arg("options"), py::arg("live") = true);
    module.def("first_runs", &first_runs, py::arg("groups"), py::arg("points"), py::arg("marks"), py::arg("bound"), py::arg("plan"),
               py::arg("options"), py::arg("live") = true);
    module.def("first_live", &first_live, py::arg("tile"), py::arg("marks"), py::arg("bound"));
    bind_kept(module);
}

map::SimplifyResult run_in_parts(const map::MapData& map, const map::SimplifyOptions& options, const py::object& run_groups,
                                 int tile_level, const py::object& tile_points, std::uint64_t here_below, const io::VerticesInFile* in_file) {
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point from) { return std::chrono::duration<double>(Clock::now() - from).count(); };
    const auto start = Clock::now();
    unsigned level = tile_level >= 0 ? static_cast<unsigned>(tile_level) : 0;
    std::uint64_t budget = 1'000'000;  // (the first round's parts' size too; this if the tile level is given and tile_points is a callable)
    bool first_here = true;  // the first round's tiles built here (or on the workers: run_groups.first_round)
    std::uint32_t top_runs = 0;  // the levels from the tile level up over a subset of the live map (run_groups.top_runs)
    {
        py::gil_scoped_acquire gil;
        // (run_groups.first_round_by_parts_only: on the workers only where the input is read by
        // parts there; a map read here runs its first round here.)
        first_here = !py::hasattr(run_groups, "first_round") || (py::hasattr(run_groups, "first_round_by_parts_only") && in_file == nullptr);
        if (py::hasattr(run_groups, "top_runs")) top_runs = run_groups.attr("top_runs").cast<std::uint32_t>();
    }
    if (in_file && first_here) throw std::logic_error("a map's vertices left in its file, and its first round here");
    // Built here, the whole map's engine is set up and searched for crossings first: tile_points
    // may wait for the workers (toposimp.dask connects meanwhile), and the tile level is set after.
    std::unique_ptr<map::MapInParts> parts;
    if (first_here) parts = std::make_unique<map::MapInParts>(map, options, level, here_below);
    const auto run_top = [&] {
        if (top_runs == 0) {
            parts->run_top_here();
        } else {
            map::run_top_over_subsets(*parts, options, top_runs);
        }
    };
    {
        py::gil_scoped_acquire gil;
        if (tile_level < 0) {
            budget = (PyCallable_Check(tile_points.ptr()) ? tile_points() : tile_points).cast<std::uint64_t>();
        } else if (!PyCallable_Check(tile_points.ptr())) {
            budget = tile_points.cast<std::uint64_t>();
        }
    }
    const auto vertices = static_cast<std::uint32_t>(in_file ? in_file->vertices : map.vertices.size());
    // The plan: the single process's, from the vertices' and control points' extent.
    map::GridPlan grid;
    if (in_file) {
        Box box = in_file->extent;
        for (const Point p : map.control_points) {
            box = {std::min(box.min_x, p.x), std::min(box.min_y, p.y), std::max(box.max_x, p.x), std::max(box.max_y, p.y)};
        }
        grid = map::plan_grid(box.min_x, box.min_y, box.max_x, box.max_y, std::size_t{vertices} + map.control_points.size());
    } else {
        grid = parts ? parts->plan() : map::plan_grid(map);
    }
    if (tile_level < 0) {
        level = tile_level_for(grid, budget, [&](auto&& add) {
            if (in_file) {
                // (The files once more: a lines layer a record at a time, a polygon layer's arcs
                // made by runs of features.)
                std::uint64_t read = 0;
                for (const io::LayerInFile* layer : in_file->in_chain_order()) {
                    if (layer->polygons) {
                        const std::vector<std::uint64_t>& first = layer->record_vertex;
                        for (std::uint64_t r = 0; r + 1 < first.size();) {
                            const std::uint64_t r0 = r;
                            while (r + 1 < first.size() && (r == r0 || first[r] - first[r0] < budget)) ++r;
                            const map::CoverageSlice slice = in_file->coverage->slice(layer->record_ring[r0], layer->record_ring[r]);
                            map::MapData arcs;
                            try {
                                arcs = map::arcs_of(slice, [&](const std::function<void(std::span<const Point>)>& visit) {
                                    io::for_each_polygon_ring(layer->run(r0, r), visit);
                                });
                            } catch (const std::invalid_argument&) {
                                throw io::InputError("'" + layer->path + "' changed while toposimp ran; nothing written");
                            }
                            for (const Point p : arcs.vertices) add(p);
                            read += arcs.vertices.size();
                        }
                        continue;
                    }
                    if (layer->ogr_lines) {
                        const std::vector<std::uint64_t>& first = layer->record_vertex;
                        std::uint64_t in_layer = 0;
                        for (std::uint64_t r = 0; r + 1 < first.size();) {
                            const std::uint64_t r0 = r;
                            while (r + 1 < first.size() && (r == r0 || first[r] - first[r0] < budget)) ++r;
                            const map::MapData lines = io::read_lines(layer->run(r0, r));
                            for (const Point p : lines.vertices) add(p);
                            in_layer += lines.vertices.size();
                        }
                        if (in_layer != first.back() - first.front()) {
                            throw io::InputError("'" + layer->path + "' changed while toposimp ran; nothing written");
                        }
                        read += in_layer;
                        continue;
                    }
                    std::optional<io::ShapeReader> reader = io::ShapeReader::open(layer->path);
                    std::uint64_t in_layer = 0;
                    while (const io::ShapeRecord* record = reader ? reader->next() : nullptr) {
                        for (const Point p : record->xy) add(p);
                        in_layer += record->xy.size();
                    }
                    if (!reader || reader->failed() || in_layer != layer->record_vertex.back() - layer->record_vertex.front()) {
                        throw io::InputError("'" + layer->path + "' changed while toposimp ran; nothing written");
                    }
                    read += in_layer;
                }
                if (read != in_file->vertices) throw std::logic_error("a map's vertices in its files, not all counted");
            } else {
                for (const Point p : map.vertices) add(p);
            }
            for (const Point p : map.control_points) add(p);
        });
    }
    unsigned round = 1;
    if (first_here) {
        parts->set_tile_level(level);
    } else {
        // The map is cut into parts on the workers, and the first round's tiles are built, searched
        // and run there; this process holds only what FirstRoundLead holds, then the live map.
        // (Held by Python too, which may keep it past the run: closed then, every call refused.)
        const auto steps = std::make_shared<FirstSteps>(map, in_file, options, grid, level, std::max<std::uint64_t>(budget, 1));
        steps->here_below_ = here_below;
        {
            py::gil_scoped_acquire gil;
            py::dict plan = plan_dict(grid);
            plan["tile_level"] = std::min(level, grid.levels);
            try {
                run_groups.attr("first_round")(py::cast(steps), plan, options_dict(options));
            } catch (...) {
                steps->close();
                throw;
            }
            steps->close();
        }
        if (steps->kept_store_) {
            // The rounds after the first from the tiles kept on the workers: nothing over the
            // whole map's vertices here but a byte each for the result.
            std::unique_ptr<map::KeptTiles> kept;
            std::vector<map::TileOutcome> outcomes;
            {
                py::gil_scoped_acquire gil;
                kept = std::make_unique<map::KeptTiles>(std::move(*steps->lead_), python_store(steps->kept_store_, vertices, chains_of(map)));
                steps->kept_store_ = py::object();
                steps->lead_.reset();
                outcomes = std::move(steps->outcomes_);
            }
            const double set_up = seconds(start);
            const auto rounds_start = Clock::now();
            for (;;) {
                if (kept->finish_tiles(outcomes)) map::run_kept_top(*kept, grid, options, std::max(top_runs, 4u));
                if (!kept->next_round()) break;
                outcomes = kept->run_groups();
            }
            map::SimplifyResult result = kept->result();
            {
                py::gil_scoped_acquire gil;
                kept.reset();
            }
            result.stats.seconds_crossings = set_up;
            result.stats.seconds_sweep = seconds(rounds_start);
            return result;
        }
        parts = steps->take();
        run_top();
        ++round;
    }
    const double set_up = seconds(start);
    const auto rounds_start = Clock::now();
    bool whole = first_here;  // the whole map's engine is still here
    for (; parts->next_round(); ++round) {
        const std::size_t count = parts->split_round();
        std::vector<map::TileOutcome> outcomes;
        if (count > 0) {
            py::gil_scoped_acquire gil;
            py::object groups = py::cast(RoundGroups(*parts, count));
            py::dict plan = plan_dict(parts->plan());
            plan["tile_level"] = parts->tile_level();  // (for progress; the tiles carry their level)
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
                if (group.size() != parts->group_size(k)) malformed("not one outcome per tile");
                for (const py::handle one : group) outcomes.push_back(outcome_of(one.cast<py::dict>(), vertices, chains_of(map)));
            }
        }
        if (!parts->finish_tiles(outcomes)) continue;
        // From the first round's tiles on, the engine here holds the live vertices only.
        if (whole && count > 0) {
            parts->keep_live_only();
            whole = false;
        }
        run_top();
    }
    map::SimplifyResult result = parts->result();
    // The phases: set-up and the crossing search; the rounds (tiles and the levels above).
    result.stats.seconds_crossings = set_up;
    result.stats.seconds_sweep = seconds(rounds_start);
    return result;
}

namespace {

// A group's tile dicts as engine inputs, checked to be of one level of the plan.
std::vector<map::TileInput> group_of(const py::list& group, const map::GridPlan& grid) {
    std::vector<map::TileInput> tiles;
    for (const py::handle tile : group) tiles.push_back(tile_of(tile.cast<py::dict>()));
    for (const map::TileInput& tile : tiles) {
        if (tile.level != tiles.front().level || tile.level > grid.levels) malformed("the tiles are not of one level of the plan");
    }
    return tiles;
}

py::list outcome_list(const std::vector<map::TileOutcome>& outcomes) {
    py::list out;
    for (const map::TileOutcome& outcome : outcomes) out.append(outcome_dict(outcome));
    return out;
}

}  // namespace

py::list run_tile_group(const py::list& group, const py::dict& plan, const py::dict& options) {
    const map::GridPlan grid = plan_of(plan);
    std::vector<map::TileInput> tiles = group_of(group, grid);
    const map::SimplifyOptions simplify = options_of(options);
    std::vector<map::TileOutcome> outcomes;
    {
        py::gil_scoped_release release;
        outcomes = map::run_tile_group(std::move(tiles), grid, simplify);
        give_pages_back();
    }
    return outcome_list(outcomes);
}

py::list run_tile_groups(const py::list& groups, const py::dict& plan, const py::dict& options) {
    const map::GridPlan grid = plan_of(plan);
    std::vector<std::vector<map::TileInput>> inputs;
    for (const py::handle group : groups) inputs.push_back(group_of(group.cast<py::list>(), grid));
    const map::SimplifyOptions simplify = options_of(options);
    std::vector<std::vector<map::TileOutcome>> outcomes;
    {
        py::gil_scoped_release release;
        outcomes = map::run_tile_groups(std::move(inputs), grid, simplify);
        give_pages_back();
    }
    py::list out;
    for (const std::vector<map::TileOutcome>& group : outcomes) out.append(outcome_list(group));
    return out;
}

}  // namespace toposimp::python
