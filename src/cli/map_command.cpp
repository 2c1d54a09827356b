#include "cli/map_command.hpp"

#include "cli/check_command.hpp"
#include "cli/common.hpp"
#include "cli/validators.hpp"
#include "cli/guard.hpp"
#include "cli/json.hpp"
#include "cli/logging.hpp"
#include "cli/progress.hpp"
#include "core/map/levels.hpp"
#include "core/map/location_key.hpp"
#include "core/map/rounding.hpp"
#include "core/map/simplify.hpp"
#include "io/common/errors.hpp"
#include "io/common/output_file.hpp"
#include "io/map/giscup.hpp"
#include "io/ogr/gdal_env.hpp"
#include "io/ogr/ogr_dataset.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace toposimp::cli {

CLI::App* add_map_command(CLI::App& app, MapOptions& options) {
    CLI::App* map = app.add_subcommand("map", "Simplify line layers, keeping their topology and control points' sides");
    map->footer(
        "Stopping criteria (one; default --keep 10%): --keep, --keep-points, --remove-points, --max-area, --max; or\n"
        "--levels for several nested ones in one run.\n"
        "A vertex is removed only if the closed triangle it forms with its neighbours holds no other vertex and\n"
        "no control point (exact predicates), so no new crossing or touching appears and no control point changes\n"
        "side; crossings in the input are kept as they are. Output vertices are a subset of the input's,\n"
        "coordinates untouched (unless rounded, below), each line keeping its first and last vertex.\n"
        "--precision/--decimals put every written x and y on a grid (multiples of the step, as the doubles a reader\n"
        "parses from their short decimal text), moving each location only where that is safe by the same exact rules:\n"
        "a vertex whose grid point is its neighbour's is removed; one that no grid point nearby can serve is written\n"
        "where it was (counted in --json and -v). Z and M values are written as they are.\n"
        "Exit status: 0 ok, 1 --validate found a violation (no output written), 2 usage or input error.");
    map->add_option("input", options.input, "Input line layer (any OGR source; with --giscup, a GIS Cup lines file)")->required();
    map->add_option("-o,--output", options.output, "Output file (format from the extension or -f); /vsistdout/ for stdout")
        ->required();
    map->add_option("-p,--points", options.points, "Control points: FILE or FILE:LAYER (Point/MultiPoint)");
    map->add_option("-l,--layer", options.layers, "Input layer (repeatable; default: every layer, simplified together)")
        ->allow_extra_args(false);
    map->add_option("-f,--format", options.format, "Output OGR driver, e.g. GPKG, 'ESRI Shapefile', FlatGeobuf, GeoJSON");
    map->add_option("--nln", options.layer_name, "Output layer name (GDAL's -nln; default: the input layer's)");
    map->add_option("--lco", options.layer_options, "Layer creation option KEY=VALUE (GDAL's -lco; repeatable)")
        ->allow_extra_args(false);
    map->add_option("--dsco", options.dataset_options, "Dataset creation option KEY=VALUE (GDAL's -dsco; repeatable)")
        ->allow_extra_args(false);
    map->add_option("--config", options.config, "GDAL configuration option KEY VALUE (repeatable)")
        ->allow_extra_args(false);
    auto* keep = map->add_option("--keep", options.keep, "Keep this share of the vertices: 10% or 0.1 (default 10%)");
    auto* keep_points = map->add_option("--keep-points", options.keep_points, "Keep N vertices in total")
                            ->check(number_at_least(0));
    auto* remove_points = map->add_option("--remove-points", options.remove_points, "Remove N vertices (GIS Cup 2014)")
                              ->check(number_at_least(0));
    auto* max_area = map->add_option("--max-area", options.max_area,
                                     "Remove vertices whose effective area is at most A (map units squared; with --spherical "
                                     "m², or A with a unit: 5km2, 20ha, 3000m2)");
    auto* max = map->add_flag("--max", options.max, "Remove every vertex that can be removed");
    auto* levels = map->add_option("--levels", options.levels,
                                   "Nested levels in one run, finest first, e.g. 20%,5%,1% (shares, or vertex counts): each a "
                                   "subset of the one before; -o holds {level}, replaced by each level's name (20pct, 5000)");
    const std::vector<CLI::Option*> criteria{keep, keep_points, remove_points, max_area, max, levels};
    for (CLI::Option* a : criteria) {
        for (CLI::Option* b : criteria) {
            if (a != b) a->excludes(b);
        }
    }
    auto* precision = map->add_option("--precision", options.precision,
                                      "Write x and y on the grid of multiples of STEP (map units, e.g. 0.0001), topology kept");
    auto* decimals = map->add_option("--decimals", options.decimals, "Write x and y with D decimals at most: --precision 1e-D")
                         ->check(CLI::Range(0, 300));
    auto* quantize = map->add_option("--quantize", options.quantize,
                                     "TopoJSON: quantize positions to an N×N grid over the output's extent (transform, integer "
                                     "delta arcs), topology kept; refused if some location cannot be put on it")
                         ->check(CLI::Range(2, 1 << 30));
    for (CLI::Option* a : {precision, decimals, quantize}) {
        for (CLI::Option* b : {precision, decimals, quantize}) {
            if (a != b) a->excludes(b);
        }
    }
    map->add_option("--weighting", options.weighting,
                    "Weighted Visvalingam: rank by effective area × (1 − K·cos θ), so sharp angles go first (mapshaper's "
                    "default, K = 0.7); 0, the default, is plain Visvalingam–Whyatt")
        ->check(CLI::Range(0.0, 1.0));
    map->add_flag("--spherical", options.spherical,
                  "Rank by areas on the sphere (m²), for longitude/latitude input: a triangle near a pole ranks by its true size");
    map->add_option("--arithmetic", options.arithmetic,
                    "exact (default: float filter, GMP fallback), rational (all GMP, as EPLSimp), "
                    "float (naive doubles as TopoVW: UNSAFE, for experiments only)")
        ->check(CLI::IsMember({"exact", "rational", "float"}));
    map->add_option("-j,--threads", options.threads,
                    "Threads to use (default: all cores, or OMP_NUM_THREADS); the output is the same for any number")
        ->check(number_at_least(0));
    map->add_flag("--giscup", options.giscup, "Input, --points and output are GIS Cup 2014 text files");
    map->add_flag("--json", options.json, "Print a JSON summary on stdout (on stderr when the output is stdout)");
    map->add_flag("--overwrite", options.overwrite, "Replace the output if it exists");
    map->add_flag("--validate", options.validate,
                  "Run `toposimp check` on the output before moving it into place; exit 1 and no output if it finds anything");
    map->add_flag("--progress", options.progress,
                  "Report progress as lines \"PROGRESS <percent> <phase>\" on stderr (for GUIs and wrappers)");
    map->add_flag("-q,--quiet", options.quiet, "Print errors only");
    map->add_flag("-v,--verbose", options.verbosity, "More detail (repeat for more)");
    return map;
}

namespace {

// --max-area: a number (map units², or m² with --spherical), or with --spherical a number with a
// unit: m2, ha, km2.
std::optional<double> area_of(const std::string& text, bool spherical, std::string& problem) {
    static const std::pair<const char*, double> kUnits[] = {{"km2", 1e6}, {"ha", 1e4}, {"m2", 1.0}};
    std::string number = text;
    double unit = 1.0;
    for (const auto& [suffix, factor] : kUnits) {
        const std::string ending(suffix);
        if (number.size() > ending.size() && number.compare(number.size() - ending.size(), ending.size(), ending) == 0) {
            if (!spherical) {
                problem = "--max-area " + text + ": a unit needs --spherical (longitude, latitude input, areas in m²); "
                          "without it areas are in map units squared";
                return std::nullopt;
            }
            number.resize(number.size() - ending.size());
            unit = factor;
            break;
        }
    }
    double value = 0;
    std::istringstream parse(number);
    if (!(parse >> value) || !parse.eof() || !std::isfinite(value) || value < 0) {
        problem = "--max-area takes a non-negative area such as 0.01, or with --spherical 5km2, not '" + text + "'";
        return std::nullopt;
    }
    return value * unit;
}

std::optional<map::StopCriterion> stop_criterion(const MapOptions& options, std::string& problem) {
    map::StopCriterion stop;
    if (options.max) {
        stop.target = map::Target::max;
    } else if (options.keep_points >= 0) {
        stop = {map::Target::keep_points, std::floor(options.keep_points)};
    } else if (options.remove_points >= 0) {
        stop = {map::Target::remove_points, std::floor(options.remove_points)};
    } else if (!options.max_area.empty()) {
        const std::optional<double> area = area_of(options.max_area, options.spherical, problem);
        if (!area) return std::nullopt;
        stop = {map::Target::max_area, *area};
    } else if (!options.keep.empty()) {
        const std::optional<double> share = parse_share(options.keep, "vertices", problem);
        if (!share) return std::nullopt;
        stop = {map::Target::keep_fraction, *share};
    }
    return stop;
}

std::string describe(const map::StopCriterion& stop) {
    std::ostringstream text;
    switch (stop.target) {
        case map::Target::keep_fraction: text << "keep " << stop.value * 100 << "%"; break;
        case map::Target::keep_points: text << "keep " << stop.value << " vertices"; break;
        case map::Target::remove_points: text << "remove " << stop.value << " vertices"; break;
        case map::Target::max_area: text << "effective area <= " << stop.value; break;
        case map::Target::max: text << "max"; break;
    }
    return text.str();
}

// The grid of --precision or --decimals; nullopt for full precision. Sets `problem` when the
// step is not a positive decimal.
std::optional<map::GridStep> grid_of(const MapOptions& options, std::string& problem) {
    if (options.decimals >= 0) return map::GridStep::decimals(options.decimals);
    if (options.precision.empty()) return std::nullopt;
    const std::optional<map::GridStep> grid = map::GridStep::parse(options.precision);
    if (!grid) problem = "--precision: '" + options.precision + "' is not a positive decimal step (e.g. 0.0001, 1e-4 or 25)";
    return grid;
}

exact::Arithmetic arithmetic_of(const std::string& name) {
    if (name == "rational") return exact::Arithmetic::rational;
    if (name == "float") return exact::Arithmetic::floating;
    return exact::Arithmetic::exact;
}

// What a map job read: the engine's map, and what is needed to write it back (the OGR layers
// with their attributes, or the GIS Cup lines' ids).
struct MapInput {
    map::MapData map;
    std::optional<io::OgrDataset> dataset;
    io::GiscupLines giscup_lines;
    std::size_t written_points = 0;  // control points [0, n) are the dataset's own point features

    std::uint64_t features() const { return dataset ? dataset->summary().features() : map.chains.size(); }
};

MapInput read_giscup(const MapOptions& options) {
    MapInput input;
    input.giscup_lines = io::read_giscup_lines(options.input, input.map);
    if (!options.points.empty()) input.map.control_points = io::read_giscup_points(options.points);
    return input;
}

void log_input(spdlog::logger& log, const std::string& input, const io::DatasetSummary& summary) {
    for (const io::LayerSummary& layer : summary.layers) {
        log.debug("read {} ({}), layer '{}': {} features ({} lines, {} polygons){}{}", input, summary.driver, layer.layer,
                  layer.features, layer.line_features, layer.polygon_features, layer.has_z ? ", Z kept" : "",
                  layer.has_m ? ", M kept" : "");
    }
    if (const auto empty = summary.sum(&io::LayerSummary::empty_geometries); empty > 0) {
        log.warn("{} features with an empty or NULL geometry are written unchanged", empty);
    }
    if (summary.degenerate_rings > 0) {
        log.warn("{} polygon rings with fewer than 3 corners or no area are written unchanged", summary.degenerate_rings);
    }
    if (const auto points = summary.sum(&io::LayerSummary::untouched_points); points > 0) {
        log.debug("{} point features are written unchanged and kept on their side of every line", points);
    }
    if (summary.arcs > 0) log.debug("polygon rings: {} arcs, {} of them shared", summary.arcs, summary.shared_arcs);
}

// The bytes of `path` on disk: a file's size, or the sum of a folder's regular files' (not its
// subfolders'); 0 for anything else (a GDAL connection string, a /vsi path).
std::uintmax_t size_on_disk(const std::string& path) {
    std::error_code error;
    if (std::filesystem::is_regular_file(path, error)) {
        const std::uintmax_t size = std::filesystem::file_size(path, error);
        return error ? 0 : size;
    }
    std::uintmax_t total = 0;
    if (!std::filesystem::is_directory(path, error)) return 0;
    for (std::filesystem::directory_iterator it(path, error), end; !error && it != end; it.increment(error)) {
        if (it->is_regular_file(error)) {
            const std::uintmax_t size = it->file_size(error);
            if (!error) total += size;
        }
        error.clear();
    }
    return total;
}

// The layers through OGR, and the control points file on a second thread meanwhile.
MapInput read_layers(const MapOptions& options, spdlog::logger& log, const MapMemory* memory, bool vertices_in_file) {
    MapInput input;
    if (memory) {
        input.dataset.emplace(io::OgrDataset::read(*memory->input, input.map));
        input.written_points = input.map.control_points.size();
        if (memory->points) {
            const std::vector<Point> read = io::read_control_points(*memory->points);
            input.map.control_points.insert(input.map.control_points.end(), read.begin(), read.end());
        }
        if (const std::vector<Point>* given = memory->point_coordinates) {
            input.map.control_points.insert(input.map.control_points.end(), given->begin(), given->end());
        }
        log_input(log, options.input, input.dataset->summary());
        return input;
    }
    std::future<std::vector<Point>> points;
    if (!options.points.empty()) {
        const unsigned threads = options.threads > 0 ? static_cast<unsigned>(options.threads) : std::thread::hardware_concurrency();
        points = std::async(std::launch::async, [&options, threads] { return io::read_control_points(options.points, threads); });
    }
    try {
        // A Shapefile input's .prj may go to a Shapefile output (one .shp file, not a directory
        // of them) as it is, without parsing the CRS.
        const std::string extension = std::filesystem::path(options.output).extension().string();
        const bool prj_as_file = (extension == ".shp" || extension == ".SHP") && io::is_shapefile_output(options.output, options.format);
        input.dataset.emplace(io::OgrDataset::read(options.input, options.layers, input.map, prj_as_file, vertices_in_file));
        input.written_points = input.map.control_points.size();
    } catch (...) {
        if (points.valid()) points.wait();
        throw;
    }
    if (points.valid()) {
        std::vector<Point> read = points.get();
        std::vector<Point>& control_points = input.map.control_points;
        if (control_points.empty()) {
            control_points = std::move(read);
        } else {
            control_points.insert(control_points.end(), read.begin(), read.end());
        }
    }
    log_input(log, options.input, input.dataset->summary());
    return input;
}

void write_giscup(const MapOptions& options, const MapInput& input, const map::SimplifyResult& result, std::ostream& stdout_stream) {
    io::OutputFile output(options.output, options.overwrite, &stdout_stream);
    {
        std::ofstream out(output.staging_path(), std::ios::binary);
        io::write_giscup_lines(out, input.giscup_lines, input.map, result.kept);
        out.close();
        if (!out) throw io::OutputError("cannot write '" + options.output + "': " + std::strerror(errno));
    }
    output.commit();
}

// The layers through OGR; with --validate, `toposimp check` on the written file first, which
// leaves no output if it finds anything.
void write_layers(const MapOptions& options, const MapInput& input, const map::SimplifyResult& result,
                  const std::optional<map::OutputGrid>& grid, Context& context, Progress& progress, spdlog::logger& log,
                  const std::vector<std::uint8_t>* ranks = nullptr) {
    io::WriteOptions write;
    write.path = options.output;
    write.format = options.format;
    write.layer_name = options.layer_name;
    write.layer_options = options.layer_options;
    write.dataset_options = options.dataset_options;
    write.overwrite = options.overwrite;
    write.stdout_stream = &context.out;
    write.vertex_ranks = ranks;
    if (options.quantize > 0) {
        write.transform = io::TopoTransform{grid->x.scale, grid->y.scale, grid->x.translate, grid->y.translate};
    }
    if (options.validate) {
        write.before_commit = [&](const std::string& written) {
            progress.phase("validating");
            validate::CheckOptions check;
            check.original = options.input;
            check.simplified = written;
            check.points = options.points;
            check.layers = options.layers;
            check.grid = grid;
            const validate::CheckReport report = validate::check(check);
            if (!report.clean()) {
                progress.done();
                print_table(context.err, report);
                throw TopologyFailure{fmt::format("--validate found {} violation(s); no output written", report.violations.size())};
            }
            log.debug("validation: clean ({} features, {} control points)", report.features, report.control_points);
        };
    }
    for (const std::string& warning : input.dataset->write(write, input.map, result.kept)) log.warn("{}", warning);
}

struct Timings {
    double read = 0, simplify = 0, round = 0, write = 0, total = 0;
};

// The grid of a quantized TopoJSON: `quantize` steps across the extent of what is written (the
// kept vertices and the point features), as topojson and mapshaper choose it.
map::OutputGrid quantized_grid(const MapInput& input, const std::vector<std::uint8_t>& kept, int quantize) {
    Box extent{INFINITY, INFINITY, -INFINITY, -INFINITY};
    auto add = [&](Point p) {
        extent = {std::min(extent.min_x, p.x), std::min(extent.min_y, p.y), std::max(extent.max_x, p.x), std::max(extent.max_y, p.y)};
    };
    for (std::size_t v = 0; v < kept.size(); ++v) {
        if (kept[v]) add(input.map.vertices[v]);
    }
    for (std::size_t k = 0; k < input.written_points; ++k) add(input.map.control_points[k]);
    if (!(extent.min_x <= extent.max_x)) extent = {0, 0, 0, 0};
    auto axis = [&](double low, double high) {
        const double scale = high > low ? (high - low) / (quantize - 1) : 1.0;
        return map::AxisGrid::quantized(scale, low);
    };
    return {axis(extent.min_x, extent.max_x), axis(extent.min_y, extent.max_y)};
}

// The grid of what is published, given what the (first) level keeps; none without rounding.
std::optional<map::OutputGrid> output_grid(const MapOptions& options, const std::optional<map::GridStep>& decimal_grid,
                                           const MapInput& input, const std::vector<std::uint8_t>& kept) {
    if (decimal_grid) return map::OutputGrid(*decimal_grid);
    if (options.quantize > 0) return quantized_grid(input, kept, options.quantize);
    return std::nullopt;
}

// Runs `round` (the rounding of rounding.hpp), with a grid too fine for the coordinates as bad input.
template <class Round>
auto rounding_input(Round&& round) {
    try {
        return round();
    } catch (const std::invalid_argument& error) {
        throw io::InputError(std::string(error.what()) + " (--precision)");
    }
}

// Puts what `rounded` keeps where it is written (its coordinates in input.map replaced, the point
// features too), and says what the rounding cost.
map::RoundingStats apply_rounding(MapInput& input, const map::RoundingResult& rounded, const map::OutputGrid& grid, spdlog::logger& log) {
    for (std::size_t v = 0; v < rounded.kept.size(); ++v) {
        if (rounded.kept[v]) input.map.vertices[v] = rounded.at[v];
    }
    if (input.dataset && !rounded.points.empty()) input.dataset->move_points(rounded.points);
    const map::RoundingStats& stats = rounded.stats;
    log.debug("grid {}: {} locations, {} already on it, {} moved to the nearest grid point, {} to another, {} vertices removed "
              "(their grid point was a neighbour's), {} left off the grid, {} on rings written as given, {} passes",
              grid.text(), stats.locations, stats.already_on_grid, stats.moved_nearest, stats.moved_other, stats.removed,
              stats.off_grid, stats.frozen, stats.passes);
    if (stats.points_off_grid > 0) {
        log.warn("{} point features are written off the grid {}: on a line, or no way to the grid point without touching one",
                 stats.points_off_grid, grid.text());
    }
    if (stats.off_grid > 0) {
        std::string where;
        for (std::size_t k = 0; k < rounded.off_grid.size() && k < 3; ++k) {
            const Point p = input.map.vertices[rounded.off_grid[k]];
            where += fmt::format("{}({}, {})", k ? ", " : "", p.x, p.y);
        }
        log.warn("{} locations are written off the grid {}: no grid point near them keeps the topology (e.g. at {}{})",
                 stats.off_grid, grid.text(), where, stats.off_grid > 3 ? ", …" : "");
    }
    return stats;
}

// Puts the kept vertices of `input` on the grid (their coordinates in input.map replaced) and
// drops those rounding removed from `result`.
map::RoundingStats round_output(MapInput& input, map::SimplifyResult& result, const map::OutputGrid& grid,
                                exact::Arithmetic arithmetic, spdlog::logger& log) {
    map::RoundingOptions rounding{grid, arithmetic};
    rounding.written_points = input.written_points;
    map::RoundingResult rounded = rounding_input([&] { return map::round_to_grid(input.map, result.kept, rounding); });
    result.kept = rounded.kept;
    result.stats.vertices_out -= rounded.stats.removed;
    return apply_rounding(input, rounded, grid, log);
}

// The messages after a run: target missed, refusals, predicates, memory, the one-line summary.
void report(const map::SimplifyStats& stats, const map::StopCriterion& stop, const Timings& time, const MapOptions& options,
            bool err_is_terminal, spdlog::logger& log) {
    if (!stats.target_reached) {
        log.warn("target not reached: removed {} of the {} vertices asked for; no more can go without changing topology",
                 stats.removed, stats.removal_goal);
    }
    if (stats.swept_as_max) {
        log.debug("the target asks for at least as many removals as the rules can ever allow (chain ends, pinned vertices and "
                  "each ring's last 3 locations stay): run as --max, in one sweep");
    }
    log.debug("predicates: {} decided by the float filter, {} exactly in expansions, {} by GMP", stats.predicates.filter_decided,
              stats.predicates.expansion_decided, stats.predicates.gmp_fallbacks);
    const double memory = peak_memory_mib();
    log.debug("peak memory {:.0f} MiB: {:.0f} bytes per vertex and control point", memory,
              memory * 1048576.0 / static_cast<double>(std::max<std::uint64_t>(1, stats.vertices_in + stats.control_points)));
    log.debug("refused removals: {} point in triangle, {} ring, {} coincident segment", stats.blocked_by_point,
              stats.blocked_by_ring, stats.blocked_by_coincidence);
    if (stats.pinned_by_crossing > 0) {
        log.debug("{} vertices kept at the ends of segments that cross or touch other lines in the input", stats.pinned_by_crossing);
    }
    for (std::size_t k = 0; k < stats.round_times.size(); ++k) {
        const map::RoundTimes& round = stats.round_times[k];
        log.trace("round {}: {} removed; selection {:.3f} s, scheduling {:.3f} s, sweep {:.3f} s", k + 1, round.removed,
                  round.seconds_select, round.seconds_schedule, round.seconds_sweep);
    }
    const std::string summary = fmt::format("{} -> {} vertices ({} removed, {} refused), {}, {:.3f} s", stats.vertices_in,
                                            stats.vertices_out, stats.removed, stats.blocked(), describe(stop), time.total);
    if (err_is_terminal || options.verbosity > 0) log.info("{}", summary);
}

std::string json_summary(const MapOptions& options, const map::StopCriterion& stop, const map::SimplifyStats& stats,
                         const Timings& time, std::uint64_t features, const std::optional<map::OutputGrid>& grid,
                         const map::RoundingStats& rounding) {
    JsonWriter json;
    json.field("command", "map").field("input", options.input).field("output", options.output);
    json.field("features", features).field("vertices_in", stats.vertices_in).field("vertices_out", stats.vertices_out);
    json.field("removed", stats.removed).field("control_points", stats.control_points);
    json.object("target").field("criterion", describe(stop)).field("removal_goal", stats.removal_goal);
    json.field("reached", stats.target_reached).field("swept_as_max", stats.swept_as_max).end();
    json.object("blocked")
        .field("total", stats.blocked())
        .field("point_in_triangle", stats.blocked_by_point)
        .field("ring", stats.blocked_by_ring)
        .field("coincident_segment", stats.blocked_by_coincidence)
        .end();
    json.field("pinned_by_crossing", stats.pinned_by_crossing).field("arithmetic", options.arithmetic);
    json.object("ranking").field("weighting", options.weighting).field("spherical", options.spherical).end();
    json.object("parallel").field("threads", stats.threads).field("levels", stats.levels).field("rounds", stats.rounds).end();
    json.object("engine_seconds")
        .field("index", stats.seconds_index)
        .field("crossings", stats.seconds_crossings)
        .field("sweep", stats.seconds_sweep)
        .end();
    add_predicates(json, stats.predicates);
    if (grid) {
        json.object("rounding")
            .field("grid", grid->text())
            .field("locations", rounding.locations)
            .field("already_on_grid", rounding.already_on_grid)
            .field("moved_nearest", rounding.moved_nearest)
            .field("moved_other", rounding.moved_other)
            .field("removed", rounding.removed)
            .field("removed_off_grid", rounding.removed_off_grid)
            .field("off_grid", rounding.off_grid)
            .field("frozen", rounding.frozen)
            .field("points_on_grid", rounding.points_moved)
            .field("points_off_grid", rounding.points_off_grid)
            .field("passes", rounding.passes)
            .field("predicates", rounding.predicates.filter_decided + rounding.predicates.expansion_decided +
                                     rounding.predicates.gmp_fallbacks)
            .end();
    }
    json.object("seconds")
        .field("read", time.read)
        .field("simplify", time.simplify);
    if (grid) json.field("round", time.round);
    json.field("write", time.write)
        .field("total", time.total)
        .end();
    json.field("peak_memory_mib", peak_memory_mib());
    return json.line();
}

// --levels into one TopoJSON (no {level} in -o): each arc position gets a third coordinate, the
// number of levels that keep it.
bool ranked_levels(const MapOptions& options) {
    std::string extension = std::filesystem::path(options.output).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
    std::string format = options.format;
    std::transform(format.begin(), format.end(), format.begin(), [](unsigned char c) { return std::tolower(c); });
    return !options.levels.empty() && options.output.find("{level}") == std::string::npos &&
           (format == "topojson" || (format.empty() && extension == ".topojson"));
}

// --levels: the targets, finest first, and each one's name in the output pattern ("20%" →
// "20pct", "5000" → "5000"); sets `problem` for anything else.
struct Level {
    map::StopCriterion stop;
    std::string name;
};
std::vector<Level> levels_of(const MapOptions& options, bool in_memory, std::string& problem) {
    std::vector<Level> levels;
    std::stringstream list(options.levels);
    std::string token;
    while (std::getline(list, token, ',')) {
        Level level;
        const bool count = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos && token != "0";
        if (count && token.size() > 1 && std::stod(token) >= 2) {
            level.stop = {map::Target::keep_points, std::stod(token)};
            level.name = token;
        } else {
            const std::optional<double> share = parse_share(token, "vertices", problem);
            if (!share) {
                problem = "--levels: '" + token + "' is neither a share (20% or 0.2) nor a vertex count";
                return {};
            }
            level.stop = {map::Target::keep_fraction, *share};
            std::ostringstream name;
            name << *share * 100 << "pct";
            level.name = name.str();
        }
        if (!levels.empty() && levels.back().stop.target == level.stop.target && !(level.stop.value < levels.back().stop.value)) {
            problem = "--levels go from the finest to the coarsest: '" + token + "' keeps no fewer vertices than the level before it";
            return {};
        }
        levels.push_back(level);
    }
    if (levels.empty()) problem = "--levels takes a list such as 20%,5%,1%";
    if (!in_memory && options.output.find("{level}") == std::string::npos && !ranked_levels(options)) {
        problem = "--levels writes one output per level: put {level} in -o (e.g. -o states_{level}.gpkg), or write one "
                  "TopoJSON whose positions carry their level as a third coordinate (-o states.topojson)";
    }
    if (ranked_levels(options) && options.quantize > 0) {
        problem = "one TopoJSON of all --levels cannot be quantized: its arcs would be delta-encoded, and a viewer dropping the "
                  "positions of a level would shift the rest; round with --precision or --decimals, or write one file per "
                  "level ({level} in -o)";
    }
    return levels;
}

std::string output_of(const std::string& pattern, const std::string& level) {
    std::string path = pattern;
    for (std::size_t at = path.find("{level}"); at != std::string::npos; at = path.find("{level}", at + level.size())) {
        path.replace(at, 7, level);
    }
    return path;
}

// Every output the run will write can be written: fails now, not after reading and simplifying.
void check_outputs(const MapOptions& options, const std::vector<Level>& levels) {
    for (const Level& level : levels) {
        const std::string output = output_of(options.output, level.name);
        io::OutputFile::check_destination(output, options.overwrite);
        if (!options.giscup) io::check_vector_output(output, options.format);
        if (options.quantize > 0 && (options.giscup || !io::is_topojson_output(output, options.format))) {
            throw io::OutputError("--quantize writes a quantized TopoJSON: name the output .topojson or use -f TopoJSON");
        }
    }
}

void check_spherical(const MapOptions& options, const MapInput& input) {
    if (!options.spherical) return;
    const std::vector<io::LayerSummary>& layers = input.dataset->summary().layers;
    for (std::size_t k = 0; k < layers.size(); ++k) {
        if (!input.dataset->geographic(k)) {
            throw io::InputError("--spherical ranks by areas on the sphere and needs longitude, latitude: '" + options.input +
                                 "', layer '" + layers[k].layer + "' is not in a geographic CRS");
        }
    }
}

// One result per level (one level: the run's own target). Levels on a grid are rounded as they
// are simplified (levels.hpp); a single run is rounded when it is published.
map::Levels simplify_all(MapInput& input, const map::SimplifyOptions& simplify_options, const MapOptions& options,
                         const std::vector<Level>& levels, const std::optional<map::GridStep>& decimal_grid, const Context& context) {
    const bool rounds = decimal_grid || options.quantize > 0;
    if (const io::VerticesInFile* in_file = input.dataset ? input.dataset->vertices_in_file() : nullptr) {
        if (!context.map_engine_in_file || !options.levels.empty() || rounds) throw std::logic_error("a map's vertices left in its file");
        map::Levels one;
        one.results.push_back(context.map_engine_in_file(input.map, simplify_options, *in_file));
        return one;
    }
    if (context.map_engine && options.levels.empty()) {
        map::Levels one;
        one.results.push_back(context.map_engine(input.map, simplify_options));
        return one;
    }
    if (options.levels.empty()) {
        // Rounding needs the control points again; without it the engine may free them early.
        map::Levels one;
        one.results.push_back(rounds ? map::simplify(input.map, simplify_options) : map::simplify_releasing_points(input.map, simplify_options));
        return one;
    }
    std::vector<map::StopCriterion> targets;
    for (const Level& level : levels) targets.push_back(level.stop);
    if (!rounds) return map::simplify_levels(input.map, simplify_options, targets, nullptr, context.map_engine);
    map::LevelRounding rounding;
    rounding.grid = [&](const std::vector<std::uint8_t>& kept) { return *output_grid(options, decimal_grid, input, kept); };
    rounding.options.arithmetic = simplify_options.arithmetic;
    rounding.options.written_points = input.written_points;
    return rounding_input([&] { return map::simplify_levels(input.map, simplify_options, targets, &rounding, context.map_engine); });
}

// A level after the first, on the grid the first was rounded to: where its kept locations and
// written points are (on the grid or, as the first level left them, off it).
map::RoundingStats locations_on_grid(const MapInput& input, const std::vector<std::uint8_t>& kept, const map::OutputGrid& grid) {
    map::RoundingStats stats;
    auto on_grid = [&](Point p) { return grid.x.holds(p.x) && grid.y.holds(p.y); };
    std::vector<map::LocationKey> locations;
    for (std::size_t v = 0; v < kept.size(); ++v) {
        if (kept[v]) locations.emplace_back(input.map.vertices[v]);
    }
    std::sort(locations.begin(), locations.end());
    locations.erase(std::unique(locations.begin(), locations.end()), locations.end());
    stats.locations = locations.size();
    for (const map::LocationKey& location : locations) ++(on_grid(location.point()) ? stats.already_on_grid : stats.off_grid);
    for (std::size_t k = 0; k < input.written_points; ++k) ++(on_grid(input.map.control_points[k]) ? stats.points_moved : stats.points_off_grid);
    return stats;
}

// A quantized TopoJSON has no way to write a position off its grid.
void refuse_off_grid(const MapOptions& options, const map::RoundingStats& rounding) {
    const std::uint64_t off = rounding.off_grid + rounding.frozen + rounding.points_off_grid;
    if (options.quantize > 0 && off > 0) {
        throw io::InputError(fmt::format("--quantize {}: {} locations or points cannot be put on the quantization grid "
                                         "without changing the topology (see the warnings above); quantize finer (e.g. "
                                         "--quantize {}) or write TopoJSON unquantized",
                                         options.quantize, off, static_cast<long long>(options.quantize) * 10));
    }
}

// One TopoJSON of all levels: per vertex, the number of levels that keep it (a viewer shows level
// k by the positions ranked k or more).
std::vector<std::uint8_t> level_ranks(const std::vector<map::SimplifyResult>& results, std::size_t vertices) {
    std::vector<std::uint8_t> ranks(vertices, 0);
    for (const map::SimplifyResult& level : results) {
        for (std::size_t v = 0; v < vertices; ++v) ranks[v] = static_cast<std::uint8_t>(ranks[v] + level.kept[v]);
    }
    return ranks;
}

// The JSON summary: the run's, or one object listing the levels' in order, finest first.
void print_summaries(const MapOptions& options, const std::vector<std::string>& summaries, Context& context) {
    const bool output_is_stdout = options.output == "/vsistdout/" || options.output == "-";
    std::ostream& out = output_is_stdout ? context.err : context.out;
    if (options.levels.empty()) {
        out << summaries.front();
        return;
    }
    out << "{\"command\":\"map\",\"levels\":[";
    for (std::size_t k = 0; k < summaries.size(); ++k) {
        std::string line = summaries[k];
        while (!line.empty() && line.back() == '\n') line.pop_back();
        out << (k ? "," : "") << line;
    }
    out << "]}\n";
}

// What each output needs besides its result: the grid, the levels' rounding, the ranks.
struct Publishing {
    std::optional<map::GridStep> decimal_grid;
    std::optional<map::RoundingResult> levels_rounding;  // levels: the first one's, done (and applied) as they were simplified
    std::vector<std::uint8_t> ranks;                      // one ranked TopoJSON of all levels
    bool ranked = false;
};

// One output: round (a single run, if asked), write; returns its rounding.
map::RoundingStats publish(const MapOptions& options, const Publishing& publishing, std::size_t k, MapInput& input,
                           map::SimplifyResult& result, std::optional<map::OutputGrid>& grid, exact::Arithmetic arithmetic,
                           Timings& time, Context& context, Progress& progress, spdlog::logger& log, MapMemory* memory) {
    map::RoundingStats rounding;
    if (publishing.levels_rounding) {
        grid = publishing.levels_rounding->grid;
        rounding = k == 0 ? publishing.levels_rounding->stats : locations_on_grid(input, result.kept, *grid);
    } else if ((grid = output_grid(options, publishing.decimal_grid, input, result.kept))) {
        progress.phase("rounding to " + grid->text());
        const auto round_start = Clock::now();
        rounding = round_output(input, result, *grid, arithmetic, log);
        time.round += seconds_since(round_start);
        refuse_off_grid(options, rounding);
    }
    progress.phase("writing " + options.output);
    const auto write_start = Clock::now();
    if (memory) {
        memory->output.push_back(input.dataset->to_memory(input.map, result.kept));
    } else if (publishing.ranked && k > 0) {
        // (Written with the first level.)
    } else if (options.giscup) {
        write_giscup(options, input, result, context.out);
    } else {
        write_layers(options, input, result, grid, context, progress, log, publishing.ranked ? &publishing.ranks : nullptr);
    }
    time.write += seconds_since(write_start);
    return rounding;
}

}  // namespace

// parse (done) → read → simplify (once, or to each level) → per output: round → write → report.
int run_map(const MapOptions& options, Context& context) {
    auto log = make_logger(context.err, options.verbosity, options.quiet);
    return guarded(*log, [&] { return map_job(options, context, *log); });
}

int map_job(const MapOptions& options, Context& context, spdlog::logger& log, MapMemory* memory) {
    std::string problem;
    const std::optional<map::StopCriterion> stop = stop_criterion(options, problem);
    Publishing publishing;
    publishing.decimal_grid = grid_of(options, problem);
    publishing.ranked = !memory && ranked_levels(options);
    std::vector<Level> levels;
    if (!options.levels.empty()) levels = levels_of(options, memory != nullptr, problem);
    if (!stop || !problem.empty()) throw UsageError{problem};
    if (levels.empty()) levels.push_back({*stop, ""});

    io::set_config_options(options.config);

    map::SimplifyOptions simplify_options;
    simplify_options.stop = *stop;
    simplify_options.arithmetic = arithmetic_of(options.arithmetic);
    simplify_options.threads = options.threads;
    simplify_options.ranking = {options.weighting, options.spherical};
    simplify_options.cancel = context.cancel;
    if (options.spherical && options.giscup) throw UsageError{"--spherical takes longitude, latitude layers; GIS Cup text has no CRS"};
    if (options.validate && options.giscup) throw UsageError{"--validate reads the output with GDAL; GIS Cup text is not a GDAL format"};
    if (options.validate && options.input.rfind("/vsistdin", 0) == 0) {
        throw UsageError{"--validate reads the input a second time, which standard input cannot give; save it to a file first"};
    }
    if (memory && (options.giscup || options.validate || options.quantize > 0)) {
        throw UsageError{"layers in memory take neither GIS Cup text, --validate nor --quantize (a TopoJSON option)"};
    }
    if (simplify_options.arithmetic == exact::Arithmetic::floating) {
        log.warn("--arithmetic float uses naive double predicates: the output may break topology");
    }

    const auto start = Clock::now();
    Timings time;
    Progress progress(context.err, progress_style(options.progress, context.err_is_terminal, options.quiet), context.progress);
    simplify_options.progress = [&progress](double done) { progress.update(done); };
    if (!memory) check_outputs(options, levels);

    progress.phase("reading " + options.input);
    // (An engine that reads the vertices itself gets them left in the file where it can.)
    // (Unless the engine's caller declines, told the input's size: the input is then read here.)
    const bool could_leave = context.map_engine_in_file && !memory && !options.giscup && options.levels.empty() && !publishing.decimal_grid &&
                             options.quantize == 0;
    const bool declined = could_leave && context.leave_in_file_if && !context.leave_in_file_if(size_on_disk(options.input));
    const bool vertices_in_file = could_leave && !declined;
    log.debug("heap: {}", heap_pages());
    MapInput input = options.giscup ? read_giscup(options) : read_layers(options, log, memory, vertices_in_file);
    time.read = seconds_since(start);
    check_spherical(options, input);
    const io::VerticesInFile* in_file = input.dataset ? input.dataset->vertices_in_file() : nullptr;
    log.debug("{} chains, {} vertices{}, {} control points", input.map.chains.size(), in_file ? in_file->vertices : input.map.vertices.size(),
              in_file ? " (left in the file)" : "", input.map.control_points.size());
    if (context.map_engine_in_file && !in_file && !options.giscup && !declined) {
        const std::string why = input.dataset ? input.dataset->summary().read_whole_because : std::string();
        log.debug("the input is read here, whole{}{}", why.empty() ? "" : ": ", why);
        log.debug("(only Shapefiles (a file, or a folder of them) of PolyLines or of polygons, GeoPackage "
                  "and FlatGeobuf (indexed) layers of (Multi)LineStrings or (Multi)Polygons (Z or M too), and points, "
                  "at one target without --decimals, --precision, --levels or --quantize, are read by parts)");
    }

    // The engine builds chains, indexes and ranks inside simplify().
    progress.phase("simplifying");
    const auto simplify_start = Clock::now();
    map::Levels simplified = simplify_all(input, simplify_options, options, levels, publishing.decimal_grid, context);
    std::vector<map::SimplifyResult>& results = simplified.results;
    time.simplify = seconds_since(simplify_start);
    if (simplified.rounding) {
        time.round = simplified.rounding->seconds;
        time.simplify -= time.round;
        apply_rounding(input, *simplified.rounding, simplified.rounding->grid, log);
        refuse_off_grid(options, simplified.rounding->stats);
        publishing.levels_rounding = std::move(simplified.rounding);
    }
    if (publishing.ranked) publishing.ranks = level_ranks(results, input.map.vertices.size());
    std::vector<std::string> summaries;
    for (std::size_t k = 0; k < levels.size(); ++k) {
        MapOptions level_options = options;
        level_options.output = memory ? options.output : output_of(options.output, levels[k].name);
        std::optional<map::OutputGrid> grid;
        const map::RoundingStats rounding = publish(level_options, publishing, k, input, results[k], grid, simplify_options.arithmetic,
                                                    time, context, progress, log, memory);
        time.total = seconds_since(start);
        if (k + 1 == levels.size()) progress.done();
        report(results[k].stats, levels[k].stop, time, level_options, context.err_is_terminal, log);
        if (options.json || memory) {
            summaries.push_back(json_summary(level_options, levels[k].stop, results[k].stats, time, input.features(), grid, rounding));
        }
    }
    if (memory) {
        memory->summaries = std::move(summaries);
    } else if (options.json) {
        print_summaries(options, summaries, context);
    }
    return kOk;
}

}  // namespace toposimp::cli
