#include "cli/mesh_command.hpp"

#include "cli/common.hpp"
#include "cli/validators.hpp"
#include "cli/guard.hpp"
#include "cli/json.hpp"
#include "cli/logging.hpp"
#include "cli/progress.hpp"
#include "core/mesh/distance.hpp"
#include "core/mesh/simplify.hpp"
#include "io/common/errors.hpp"
#include "io/common/output_file.hpp"
#include "io/mesh/mesh_files.hpp"

#include <CLI/CLI.hpp>  // (all of CLI11, for parse_mesh_command's own App: the launcher has no other)

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <ostream>
#include <sstream>

namespace toposimp::cli {

CLI::App* add_mesh_command(CLI::App& app, MeshCommandOptions& options) {
    // The formats as io/mesh's table lists them.
    std::string titles, text_and_binary;
    for (const io::MeshFormatInfo& format : io::mesh_formats()) {
        titles += (titles.empty() ? "" : ", ") + std::string(format.title) + (format.has_text_and_binary ? " (text or binary)" : "");
        if (format.has_text_and_binary) text_and_binary += (text_and_binary.empty() ? "" : " and ") + std::string(format.title);
    }
    const std::string extensions = io::mesh_extensions_text();
    CLI::App* mesh = app.add_subcommand("mesh", "Simplify a triangle mesh or terrain TIN without self-intersections");
    mesh->footer(
        "Stopping criteria (one; default --keep 10%): --keep, --keep-faces, --max-error.\n"
        "Edges collapse in order of quadric error (Garland-Heckbert, optimal placement); a collapse is made only if\n"
        "exact predicates show it keeps the surface manifold, turns no face over, and makes no face touch or cross\n"
        "another. Formats: " + titles + " ('toposimp formats' says what each carries).\n"
        "Normals, colours, texture coordinates and other vertex properties are kept (a merged vertex blends its two\n"
        "ends' values); faces keep theirs.\n"
        "Exit status: 0 ok, 2 usage or input error.");
    mesh->add_option("input", options.input, "Input mesh (" + extensions + ") or a DEM raster (GeoTIFF or any GDAL raster)")
        ->required();
    mesh->add_option("-o,--output", options.output,
                     "Output: a mesh (" + extensions + ") or an OGR layer of triangles with Z (.gpkg, .shp, .fgb, ...)")
        ->required();
    mesh->add_option("-f,--format", options.format,
                     "Output format: " + io::mesh_format_names_text() + ", or an OGR driver name (GPKG, ...)");
    mesh->add_option("--band", options.band, "DEM band to read (default 1)")->check(number_at_least(1));
    mesh->add_option("--nln", options.layer_name, "Layer name for OGR output (default: tin)");
    auto* keep = mesh->add_option("--keep", options.keep, "Keep this share of the faces: 10% or 0.1 (default 10%)");
    auto* keep_faces = mesh->add_option("--keep-faces", options.keep_faces, "Keep at most N faces")->check(number_at_least(0));
    auto* max_error = mesh->add_option("--max-error", options.max_error,
                                       "Collapse only while the error stays at most E: for a terrain, the vertical distance to the "
                                       "input everywhere (guaranteed; the border is kept), else the quadric error (a distance)")
                          ->check(number_at_least(0));
    keep->excludes(keep_faces)->excludes(max_error);
    keep_faces->excludes(max_error);
    mesh->add_flag("--lock-boundary", options.lock_boundary,
                   "Keep every border vertex (on an edge with one face) where it is, so neighbouring tiles still match");
    mesh->add_flag("--free-boundary", options.free_boundary,
                   "For a DEM: let border vertices move (the default keeps them, as --lock-boundary)");
    auto* terrain = mesh->add_flag("--terrain", options.terrain,
                                   "The mesh is a TIN over the x-y plane (z = height): never fold a face over in the map plane "
                                   "(the default for any mesh found to be one; a warning if it is not)");
    mesh->add_flag("--no-terrain", options.no_terrain,
                   "Simplify in space even a mesh that is a height field (the default simplifies those as terrains: "
                   "--max-error then bounds the vertical error and keeps the border)")
        ->excludes(terrain);
    mesh->add_flag("--triangulate", options.triangulate, "Split polygons with more than 3 corners into fans (else an error)");
    mesh->add_flag("--weld", options.weld,
                   "First merge vertices at exactly the same location (an unwelded mesh, as converted from STL); vertex "
                   "attributes that differ between merged vertices are dropped");
    mesh->add_flag("--ascii", options.ascii,
                   "Write " + text_and_binary + " as text (default: binary; PLY little endian with double coordinates, STL only if "
                   "every coordinate is a float32, else text with every digit)");
    auto* measure = mesh->add_option("--measure", options.measure,
                                     "How far the output lies from the input: quick (default: one point per 40 input faces, at "
                                     "least 1 024 and at most 8 192, of each surface, spread by area, measured exactly; a lower "
                                     "bound of the Hausdorff distance, for a tenth of the simplification's time or less from ~30 000 "
                                     "faces up), full "
                                     "(every vertex and ~4 points per face, up to 400 000: slow on big meshes) or none")
                         ->check(CLI::IsMember({"quick", "full", "none"}));
    mesh->add_flag("--no-hausdorff", options.no_hausdorff, "The same as --measure none")->excludes(measure);
    mesh->add_option("--contact-check", options.contact_check,
                     "How a mesh simplified in space is kept from touching or crossing itself: after (default: the "
                     "collapses made without searching for nearby faces, then the result checked once, exactly, and "
                     "simplified again with every collapse checked if it meets itself anywhere) or each (every collapse "
                     "checked: slower; the same result whenever no collapse is refused for a contact). A terrain whose "
                     "border may move is checked in the map plane; one whose border is kept needs neither")
        ->check(CLI::IsMember({"after", "each"}));
    mesh->add_option("-j,--threads", options.threads,
                     "Threads to use (default: all cores, or OMP_NUM_THREADS); the output is the same for any number")
        ->check(number_at_least(0));
    mesh->add_flag("--json", options.json, "Print a JSON summary on stdout (on stderr when the output is stdout)");
    mesh->add_flag("--overwrite", options.overwrite, "Replace the output if it exists");
    mesh->add_flag("--progress", options.progress,
                  "Report progress as lines \"PROGRESS <percent> <phase>\" on stderr (for GUIs and wrappers)");
    mesh->add_flag("-q,--quiet", options.quiet, "Print errors only");
    mesh->add_flag("-v,--verbose", options.verbosity, "More detail (repeat for more)");
    return mesh;
}

namespace {

// The mesh format of the output (-f, else the extension), or null: an OGR layer.
const io::MeshFormatInfo* output_format(const MeshCommandOptions& options) {
    return options.format.empty() ? io::mesh_format_by_extension(options.output) : io::mesh_format_named(options.format);
}

std::optional<mesh::SimplifyOptions> mesh_target(const MeshCommandOptions& options, std::string& problem) {
    mesh::SimplifyOptions target;
    if (options.keep_faces >= 0) {
        target.stop = {mesh::Target::keep_faces, std::floor(options.keep_faces)};
    } else if (options.max_error >= 0) {
        target.stop = {mesh::Target::max_error, options.max_error};
    } else if (!options.keep.empty()) {
        const std::optional<double> share = parse_share(options.keep, "faces", problem);
        if (!share) return std::nullopt;
        target.stop.value = *share;
    }
    return target;
}

std::string describe(const mesh::StopCriterion& target, const mesh::SimplifyStats& stats) {
    std::ostringstream text;
    switch (target.target) {
        case mesh::Target::keep_fraction: text << "keep " << target.value * 100 << "% of the faces"; break;
        case mesh::Target::keep_faces: text << "keep " << target.value << " faces"; break;
        case mesh::Target::max_error:
            text << (stats.vertical_bound ? "vertical error <= " : "quadric error <= ") << target.value;
            break;
    }
    return text.str();
}

// What a mesh job read: a mesh file with its attribute columns, or a DEM's TIN.
struct MeshInput {
    mesh::Mesh mesh;
    io::AttributeLayout layout;         // what the mesh's attribute columns are
    std::vector<std::string> dropped;   // attributes in the file not kept, each with the reason
    std::optional<io::Dem> dem;
    std::size_t welded_vertices = 0;
};

void weld(const MeshCommandOptions& options, MeshInput& input, spdlog::logger& log);

// A mesh file, its vertices welded if asked.
MeshInput read_mesh_file(const MeshCommandOptions& options, spdlog::logger& log) {
    MeshInput input;
    io::MeshReadOptions read_options;
    read_options.triangulate = options.triangulate;
    io::MeshReadReport report;
    mesh::Mesh& m = input.mesh;
    m = io::read_mesh(options.input, read_options, report);
    log.debug("read {} ({}{}): {} vertices, {} faces", options.input, io::to_string(report.format),
              report.encoding.empty() ? "" : " " + report.encoding, m.points.size(), m.faces.size());
    input.layout = report.layout;
    input.dropped = report.dropped;
    for (const std::string& what : input.dropped) log.warn("{}: {}: dropped (not carried to the simplified mesh)", options.input, what);
    if (!input.layout.vertex.empty() || !input.layout.face.empty()) {
        log.debug("attributes kept: {} per vertex, {} per face", input.layout.vertex.size(), input.layout.face.size());
    }
    if (report.polygons_triangulated > 0) log.info("{} polygons split into triangle fans", report.polygons_triangulated);
    if (report.ignored_elements > 0) {
        log.warn("{} elements that are not faces (lines, points, unknown PLY elements) ignored", report.ignored_elements);
    }
    if (report.welded > 0) {
        log.info("{}: {} triangle corners welded into the vertex at their location (STL shares no vertices)", options.input,
                 report.welded);
    }
    input.welded_vertices = report.welded;
    weld(options, input, log);
    return input;
}

// --weld: vertices at one location merged, attribute columns that differ between them dropped.
void weld(const MeshCommandOptions& options, MeshInput& input, spdlog::logger& log) {
    mesh::Mesh& m = input.mesh;
    if (options.weld) {
        const mesh::Welded welded = mesh::weld_coincident(m);
        input.welded_vertices += welded.vertices;
        log.info("welded {} vertices onto others at the same location", welded.vertices);
        for (std::size_t c = 0; c < welded.differs.size(); ++c) {
            if (!welded.differs[c]) continue;
            input.dropped.push_back("vertex " + input.layout.vertex[c].name + ": differs between vertices welded together");
            log.warn("{}: {}: dropped (not carried to the simplified mesh)", options.input, input.dropped.back());
        }
        mesh::remove_vertex_columns(m, welded.differs);
        std::erase_if(input.layout.vertex, [&, c = std::size_t{0}](const io::AttributeColumn&) mutable { return welded.differs[c++]; });
    }
}

// A DEM raster triangulated into a TIN: a terrain, its border locked unless freed.
MeshInput read_dem(const MeshCommandOptions& options, const MeshGdal& gdal, mesh::SimplifyOptions& engine, spdlog::logger& log) {
    MeshInput input;
    input.dem = gdal.read_dem(options.input, options.band);
    const io::Dem& dem = *input.dem;
    input.mesh = std::move(input.dem->tin);
    engine.terrain = true;
    engine.height_field = true;  // a grid's triangles: none overlap
    engine.lock_boundary = !options.free_boundary;
    log.debug("read DEM {} ({} x {} cells, {} without data): TIN of {} vertices, {} triangles", options.input, dem.width,
              dem.height, dem.nodata_cells, input.mesh.points.size(), input.mesh.faces.size());
    return input;
}

// Why the mesh was simplified as a terrain or in space: (mode for --json, words for people).
std::pair<std::string, std::string> terrain_mode(const mesh::SimplifyStats& stats, const mesh::SimplifyOptions& engine,
                                                 const MeshCommandOptions& options, bool dem) {  // dem: a DEM's TIN, not checked
    if (!engine.terrain) return {"off", "in space: --no-terrain"};
    if (stats.terrain) {
        if (dem) return {"dem", "as a terrain: a DEM's TIN"};
        if (options.terrain) return {"asked", "as a terrain: --terrain, and every face turns the same way in the x-y plane, none overlapping"};
        return {"detected", "as a terrain: found to be a height field (every face turns the same way in the x-y plane, none "
                            "overlapping; --no-terrain for the checks in space)"};
    }
    const std::string why = stats.plan_overlap ? "faces " + std::to_string((*stats.plan_overlap)[0]) + " and " +
                                                     std::to_string((*stats.plan_overlap)[1]) +
                                                     " (counted from 0) overlap in the x-y plane"
                                               : "the faces are not all turned the same way in the x-y plane";
    return {"not_a_height_field", "in space: " + why};
}

// What the engine's stats say the user must hear: a non-manifold input is an error; a terrain
// that is not one is simplified in space, with a warning.
void check_result(const mesh::SimplifyStats& stats, const mesh::SimplifyOptions& engine, const MeshCommandOptions& options,
                  spdlog::logger& log) {
    if (const auto& edge = stats.non_manifold) {
        std::string faces;
        for (std::uint32_t f : edge->faces) faces += (faces.empty() ? "" : ", ") + std::to_string(f);
        throw io::InputError(options.input + ": the edge between vertices " + std::to_string(edge->a) + " and " +
                             std::to_string(edge->b) + " (counted from 0) has more than two faces (" + faces + ", ...)" +
                             (options.weld ? " once vertices at the same location are welded" : "") +
                             ": non-manifold meshes are not supported");
    }
    const auto [mode, words] = terrain_mode(stats, engine, options, engine.height_field);
    if (mode == "not_a_height_field" && options.terrain) {
        log.warn("{}: {}, so this is not a terrain TIN: simplified as a surface in space{}", options.input, words.substr(10),
                 engine.stop.target == mesh::Target::max_error ? " (--max-error bounds the quadric error)" : "");
    } else {
        log.debug("{}: simplified {}", options.input, words);
    }
    if (stats.vertical_bound && !engine.lock_boundary) {
        log.info("border vertices kept where they are: the vertical bound is measured over the input's extent");
    }
}

// Writes the simplified mesh to `path` (the output's staging file): a mesh file, or an OGR layer
// of triangles. The attribute columns not written.
std::vector<std::string> write_output(const MeshInput& input, const io::MeshFormatInfo* format, const std::string& path,
                                      const MeshCommandOptions& options, const MeshGdal& gdal, spdlog::logger& log) {
    const io::AttributeLayout& layout = input.layout;
    if (format) {
        std::vector<std::string> unwritten = io::write_mesh(input.mesh, layout, path, format->format, options.ascii, options.output);
        for (const std::string& column : unwritten) {
            log.warn("{}: {} not written: {} has no place for it", options.output, column, format->title);
        }
        return unwritten;
    }
    if (!layout.vertex.empty() || !layout.face.empty()) {
        log.warn("{}: vertex and face attributes not written: a layer of triangles has no place for them", options.output);
    }
    gdal.write_tin_layer(input.mesh, path, options.format, input.dem ? input.dem->crs_wkt : std::string(), options.layer_name);
    return {};
}

// How far the output lies from the input: the sampled Hausdorff distance, and for terrains the
// vertical error; quick (a bounded number of points spread over each surface) or full.
struct Measures {
    std::string mode;  // quick, full
    std::size_t points = 0;  // quick: spread over each surface
    std::optional<mesh::HausdorffDistance> distance;
    std::optional<mesh::VerticalError> vertical;
};

bool measuring(const MeshCommandOptions& options) { return !options.no_hausdorff && options.measure != "none"; }

Measures measure(const MeshCommandOptions& options, const mesh::Mesh& original, const mesh::Mesh& simplified,
                 const mesh::SimplifyStats& stats) {
    Measures measures;
    measures.mode = options.measure;
    if (options.measure == "full") {
        // Every vertex and four points per input face, at least 50 000 and at most 400 000 per direction.
        const std::size_t samples = std::clamp<std::size_t>(4 * original.faces.size(), 50000, 400000);
        measures.distance = mesh::hausdorff(original, simplified, samples, options.threads);
        if (stats.terrain) measures.vertical = mesh::vertical_error(original, simplified, samples, options.threads);
    } else if (stats.terrain) {
        measures.points = mesh::quick_points(original.faces.size());
        const mesh::TerrainMeasure both = mesh::spread_terrain_measure(original, simplified, measures.points, options.threads);
        measures.distance = both.distance;
        measures.vertical = both.vertical;
    } else {
        measures.points = mesh::quick_points(original.faces.size());
        measures.distance = mesh::spread_hausdorff(original, simplified, measures.points, options.threads);
    }
    return measures;
}

struct Timings {
    double read = 0, simplify = 0, write = 0, hausdorff = 0, total = 0;
};

// The messages after a run: target missed, refusals, predicates, the one-line summary.
void report(const mesh::SimplifyStats& stats, const mesh::SimplifyOptions& engine, const Measures& measures, const Timings& time,
            const MeshCommandOptions& options, const MeshInput& input, bool err_is_terminal, spdlog::logger& log) {
    if (!stats.target_reached) {
        // An unwelded mesh is many separate pieces, whose border edges cannot collapse.
        const std::size_t coincident = options.weld ? 0 : mesh::count_coincident(input.mesh);
        log.warn("target not reached: {} faces left of the {} asked for; no more collapses pass the checks{}", stats.faces_out,
                 stats.target_faces,
                 coincident == 0 ? std::string()
                                 : fmt::format(" ({} of the vertices left share their location with another: "
                                               "--weld merges such vertices first)",
                                               coincident));
    }
    log.debug("refused collapses: {} link condition, {} border, {} flip, {} degenerate or duplicate face, {} intersection, "
              "{} vertical error",
              stats.refused_link, stats.refused_boundary, stats.refused_flip, stats.refused_degenerate,
              stats.refused_intersection, stats.refused_vertical);
    if (stats.simplified_again) {
        const Point3 at = *stats.contact_near;
        log.debug("contacts: the collapses made without a search left faces meeting near ({}, {}, {}) (a collapse made a "
                  "contact, or a face met one the input's faces met): simplified again with every collapse checked "
                  "({:.3f} s spent before)",
                  at.x, at.y, at.z, stats.seconds_first_run);
    } else if (stats.contacts_checked_after) {
        log.debug("contacts: none in the result, checked once after the collapses ({:.3f} s)", stats.seconds_check);
    }
    log.debug("predicates: {} decided by the float filter, {} exactly in expansions, {} by GMP; peak memory {:.0f} MiB",
              stats.predicates.filter_decided, stats.predicates.expansion_decided, stats.predicates.gmp_fallbacks,
              peak_memory_mib());
    std::string summary = fmt::format("{} -> {} faces, {} -> {} vertices ({} collapses, {} refused), {}, {:.3f} s",
                                      stats.faces_in, stats.faces_out, stats.vertices_in, stats.vertices_out, stats.collapses,
                                      stats.refused(), describe(engine.stop, stats), time.total);
    if (const auto& distance = measures.distance) {
        summary += fmt::format("; Hausdorff {}{:.6g} ({:.4g}% of the diagonal{})", measures.mode == "quick" ? ">= " : "", distance->max(),
                               distance->diagonal > 0 ? 100 * distance->max() / distance->diagonal : 0.0,
                               measures.mode == "quick" ? fmt::format("; quick, {} points of each surface: --measure full for more",
                                                                      measures.points)
                                                        : std::string());
    }
    if (measures.vertical) summary += fmt::format("; vertical error {:.6g}", measures.vertical->max());
    if (err_is_terminal || options.verbosity > 0) log.info("{}", summary);
}

// A one-sided distance as JSON: its largest and mean sample distance, and how many samples.
template <class Side>
void sides(JsonWriter& json, const Side& forward, const Side& backward) {
    json.object("input_to_output").field("max", forward.max).field("mean", forward.mean).field("samples", forward.samples).end();
    json.object("output_to_input").field("max", backward.max).field("mean", backward.mean).field("samples", backward.samples).end();
}

std::string json_summary(const mesh::SimplifyStats& stats, const mesh::SimplifyOptions& engine, const Measures& measures,
                         const Timings& time, const MeshCommandOptions& options, const MeshInput& input,
                         const std::vector<std::string>& unwritten) {
    JsonWriter json;
    json.field("command", "mesh").field("input", options.input).field("output", options.output);
    json.field("vertices_in", stats.vertices_in).field("vertices_out", stats.vertices_out);
    json.field("faces_in", stats.faces_in).field("faces_out", stats.faces_out);
    json.field("welded_vertices", input.welded_vertices).field("collapses", stats.collapses);
    json.field("flat_collapses_unsearched", stats.flat_unsearched);
    json.object("target")
        .field("criterion", describe(engine.stop, stats))
        .field("target_faces", stats.target_faces)
        .field("reached", stats.target_reached)
        .end();
    json.object("refused")
        .field("total", stats.refused())
        .field("link", stats.refused_link)
        .field("boundary", stats.refused_boundary)
        .field("flip", stats.refused_flip)
        .field("degenerate", stats.refused_degenerate)
        .field("intersection", stats.refused_intersection)
        .field("vertical", stats.refused_vertical)
        .end();
    json.field("max_quadric_error", stats.max_error).field("terrain", stats.terrain);
    const auto [mode, words] = terrain_mode(stats, engine, options, engine.height_field);
    json.field("terrain_mode", mode).field("terrain_why", words);
    json.field("lock_boundary", engine.lock_boundary || stats.vertical_bound);
    if (stats.vertical_bound) json.field("guaranteed_vertical_error", engine.stop.value);
    // Attribute columns kept, dropped on reading (with the reason), left out on writing.
    json.object("attributes").array("vertex");
    for (const io::AttributeColumn& column : input.layout.vertex) json.item(column.name);
    json.end().array("face");
    for (const io::AttributeColumn& column : input.layout.face) json.item(column.name);
    json.end().array("dropped");
    for (const std::string& what : input.dropped) json.item(what);
    json.end().array("not_written");
    for (const std::string& what : unwritten) json.item(what);
    json.end().end();
    if (const auto& dem = input.dem) {
        json.object("dem")
            .field("width", dem->width)
            .field("height", dem->height)
            .field("cells_without_data", dem->nodata_cells)
            .field("crs", !dem->crs_wkt.empty())
            .end();
    }
    if (const auto& distance = measures.distance) {
        const double diagonal = distance->diagonal > 0 ? distance->diagonal : 1.0;
        json.object("hausdorff").field("mode", measures.mode).field("max", distance->max()).field("max_fraction_of_diagonal", distance->max() / diagonal);
        // Quick: at 99.9 % confidence, at most this share of each surface is farther from the other than max.
        if (measures.mode == "quick") json.field("share_beyond_max", mesh::share_beyond(measures.points));
        sides(json, distance->forward, distance->backward);
        json.field("diagonal", distance->diagonal).end();
    }
    if (const auto& vertical = measures.vertical) {
        json.object("vertical_error").field("max", vertical->max());
        sides(json, vertical->forward, vertical->backward);
        json.field("samples_outside", vertical->outside).end();
    }
    json.object("parallel").field("threads", stats.threads).field("levels", stats.levels).field("rounds", stats.rounds).end();
    // How contacts were kept out: "after" (the result checked; again: a second run, every collapse
    // checked, because the first result met itself), "each", or "terrain" (a terrain whose border
    // stays: no search needed).
    json.object("contact_check")
        .field("mode", stats.contacts_checked_after                                          ? "after"
                       : stats.terrain && (engine.lock_boundary || stats.vertical_bound) ? "terrain"
                                                                                          : "each")
        .field("simplified_again", stats.simplified_again)
        .field("seconds_check", stats.seconds_check)
        .field("seconds_first_run", stats.seconds_first_run);
    if (const std::optional<Point3>& at = stats.contact_near) json.array("contact_near").item(at->x).item(at->y).item(at->z).end();
    json.end();
    add_predicates(json, stats.predicates);
    json.object("seconds")
        .field("read", time.read)
        .field("simplify", time.simplify)
        .field("write", time.write)
        .field("hausdorff", time.hausdorff)
        .field("total", time.total)
        .end();
    json.field("peak_memory_mib", peak_memory_mib());
    return json.line();
}

}  // namespace

bool mesh_needs_gdal(const MeshCommandOptions& options) {
    return !io::has_mesh_extension(options.input) || output_format(options) == nullptr;
}

bool parse_mesh_command(const std::vector<std::string>& args, MeshCommandOptions& options) {
    if (args.empty() || args.front() != "mesh") return false;
    CLI::App app;
    add_mesh_command(app, options);
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
        app.parse(reversed);
    } catch (const CLI::Error&) {
        return false;
    }
    return true;
}

void print_mesh_formats(std::ostream& out, bool json) {
    if (json) {
        JsonWriter writer;
        writer.array("mesh_formats");
        for (const io::MeshFormatInfo& format : io::mesh_formats()) {
            writer.object()
                .field("name", format.name)
                .field("title", format.title)
                .field("extension", format.extension)
                .field("carries", format.carries)
                .field("text_and_binary", format.has_text_and_binary)
                .end();
        }
        out << writer.line();
        return;
    }
    out << "Mesh formats (toposimp mesh; -f NAME or the extension):\n";
    for (const io::MeshFormatInfo& format : io::mesh_formats()) {
        out << "  " << format.name << "  " << format.extension << "  " << format.title
            << (format.has_text_and_binary ? " (text or binary)" : "") << ": " << format.carries << "\n";
    }
    out << "Maps and DEMs are read and written through GDAL: 'ogrinfo --formats', 'gdalinfo --formats'.\n";
}

// parse (done) → read → simplify → write → measure → report.
int run_mesh(const MeshCommandOptions& options, Context& context, const MeshGdal& gdal) {
    auto log = make_logger(context.err, options.verbosity, options.quiet);
    return guarded(*log, [&] { return mesh_job(options, context, gdal, *log); });
}

int mesh_job(const MeshCommandOptions& options, Context& context, const MeshGdal& gdal, spdlog::logger& log, MeshMemory* memory) {
    std::string problem;
    std::optional<mesh::SimplifyOptions> engine = mesh_target(options, problem);
    if (!engine) throw UsageError{problem};
    if (!memory && mesh_needs_gdal(options) && (!gdal.read_dem || !gdal.write_tin_layer || !gdal.check_layer_output)) {
        throw UsageError{options.input + " -> " + options.output + ": a DEM or an OGR layer needs GDAL, which this caller did not provide"};
    }
    engine->lock_boundary = options.lock_boundary;
    // A height field is found by the engine's own exact test, which --terrain asks for anyway.
    engine->terrain = !options.no_terrain;
    engine->threads = options.threads;
    engine->contacts = options.contact_check == "each" ? mesh::ContactCheck::every_collapse : mesh::ContactCheck::at_the_end;
    engine->cancel = context.cancel;
    const auto start = Clock::now();
    Timings time;
    Progress progress(context.err, progress_style(options.progress, context.err_is_terminal, options.quiet), context.progress);
    engine->progress = [&progress](double done) { progress.update(done); };
    engine->phase = [&progress](const char* phase) { progress.phase(phase); };
    log.debug("heap: {}", heap_pages());
    // Refuse an existing output, or a layer in a format GDAL cannot tell or write, before any work.
    const io::MeshFormatInfo* format = memory ? nullptr : output_format(options);
    std::optional<io::OutputFile> output;
    if (!memory) output.emplace(options.output, options.overwrite, &context.out);
    if (!memory && !format) gdal.check_layer_output(options.output, options.format);

    progress.phase("reading " + options.input);
    MeshInput input;
    if (memory) {
        input.mesh = std::move(memory->mesh);
        input.layout = std::move(memory->layout);
        weld(options, input, log);
    } else {
        input = io::has_mesh_extension(options.input) ? read_mesh_file(options, log) : read_dem(options, gdal, *engine, log);
    }
    mesh::Mesh& m = input.mesh;
    time.read = seconds_since(start);
    if (m.faces.empty()) throw io::InputError(options.input + ": no faces to simplify");
    if (const std::size_t repeated = mesh::count_repeated_corner_faces(m); repeated > 0) {
        log.warn("{} faces repeat a corner (no area) and are dropped", repeated);
    }
    const mesh::Mesh original = measuring(options) ? mesh::Mesh{m.points, m.faces} : mesh::Mesh{};

    progress.phase("simplifying");
    const auto simplify_start = Clock::now();
    const mesh::SimplifyStats stats = mesh::simplify(m, *engine);
    time.simplify = seconds_since(simplify_start);
    check_result(stats, *engine, options, log);

    std::vector<std::string> unwritten;
    if (!memory) {
        progress.phase("writing " + options.output);
        const auto write_start = Clock::now();
        unwritten = write_output(input, format, output->staging_path(), options, gdal, log);
        output->commit();
        time.write = seconds_since(write_start);
    }

    Measures measures;
    if (measuring(options)) {
        progress.phase("measuring the Hausdorff distance");
        const auto measure_start = Clock::now();
        measures = measure(options, original, m, stats);
        time.hausdorff = seconds_since(measure_start);
    }
    time.total = seconds_since(start);
    progress.done();

    report(stats, *engine, measures, time, options, input, context.err_is_terminal, log);
    if (memory) {
        memory->summary = json_summary(stats, *engine, measures, time, options, input, unwritten);
        memory->mesh = std::move(input.mesh);
        memory->layout = std::move(input.layout);
    } else if (options.json) {
        // The summary never mixes with a mesh written to stdout.
        (output->to_stdout() ? context.err : context.out) << json_summary(stats, *engine, measures, time, options, input, unwritten);
    }
    return kOk;
}

}  // namespace toposimp::cli
