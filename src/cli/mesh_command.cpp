#include "cli/mesh_command.hpp"

#include "cli/common.hpp"
#include "cli/progress.hpp"
#include "cli/logging.hpp"
#include "core/mesh/distance.hpp"
#include "core/mesh/simplify.hpp"
#include "io/common/errors.hpp"
#include "io/common/json_text.hpp"
#include "io/mesh/mesh_files.hpp"
#include "io/common/output_file.hpp"

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
    CLI::App* mesh = app.add_subcommand("mesh", "Simplify a triangle mesh or terrain TIN without self-intersections");
    mesh->footer(
        "Stopping criteria (one; default --keep 10%): --keep, --keep-faces, --max-error.\n"
        "Edges collapse in order of quadric error (Garland-Heckbert, optimal placement); a collapse is made only if\n"
        "exact predicates show it keeps the surface manifold, turns no face over, and makes no face touch or cross\n"
        "another. Formats: OBJ, PLY (ASCII or binary), OFF, STL. Normals, colours, texture coordinates and other vertex\n"
        "properties are kept (a merged vertex blends its two ends' values); faces keep theirs.\n"
        "Exit status: 0 ok, 2 usage or input error.");
    mesh->add_option("input", options.input, "Input mesh (.obj, .ply, .off, .stl) or a DEM raster (GeoTIFF or any GDAL raster)")
        ->required();
    mesh->add_option("-o,--output", options.output,
                     "Output: a mesh (.obj, .ply, .off, .stl) or an OGR layer of triangles with Z (.gpkg, .shp, .fgb, ...)")
        ->required();
    mesh->add_option("-f,--format", options.format, "Output format: obj, ply, off, stl, or an OGR driver name (GPKG, ...)");
    mesh->add_option("--band", options.band, "DEM band to read (default 1)")->check(CLI::PositiveNumber);
    mesh->add_option("--nln", options.layer_name, "Layer name for OGR output (default: tin)");
    auto* keep = mesh->add_option("--keep", options.keep, "Keep this share of the faces: 10% or 0.1 (default 10%)");
    auto* keep_faces = mesh->add_option("--keep-faces", options.keep_faces, "Keep at most N faces")->check(CLI::NonNegativeNumber);
    auto* max_error = mesh->add_option("--max-error", options.max_error,
                                       "Collapse only while the error stays at most E: for a terrain, the vertical distance to the "
                                       "input everywhere (guaranteed; the border is kept), else the quadric error (a distance)")
                          ->check(CLI::NonNegativeNumber);
    keep->excludes(keep_faces)->excludes(max_error);
    keep_faces->excludes(max_error);
    mesh->add_flag("--lock-boundary", options.lock_boundary,
                   "Keep every border vertex (on an edge with one face) where it is, so neighbouring tiles still match");
    mesh->add_flag("--free-boundary", options.free_boundary,
                   "For a DEM: let border vertices move (the default keeps them, as --lock-boundary)");
    mesh->add_flag("--terrain", options.terrain,
                   "The mesh is a TIN over the x-y plane (z = height): never fold a face over in the map plane");
    mesh->add_flag("--triangulate", options.triangulate, "Split polygons with more than 3 corners into fans (else an error)");
    mesh->add_flag("--weld", options.weld,
                   "First merge vertices at exactly the same location (an unwelded mesh, as converted from STL); vertex "
                   "attributes that differ between merged vertices are dropped");
    mesh->add_flag("--ascii", options.ascii,
                   "Write PLY and STL as text (default: binary; PLY little endian with double coordinates, STL only if "
                   "every coordinate is a float32, else text with every digit)");
    mesh->add_flag("--no-hausdorff", options.no_hausdorff, "Skip measuring the Hausdorff distance (saves time on big meshes)");
    mesh->add_option("-j,--threads", options.threads,
                     "Threads to use (default: all cores, or OMP_NUM_THREADS); the output is the same for any number")
        ->check(CLI::NonNegativeNumber);
    mesh->add_flag("--json", options.json, "Print a JSON summary on stdout (on stderr when the output is stdout)");
    mesh->add_flag("--overwrite", options.overwrite, "Replace the output if it exists");
    mesh->add_flag("--progress", options.progress,
                  "Report progress as lines \"PROGRESS <percent> <phase>\" on stderr (for GUIs and wrappers)");
    mesh->add_flag("-q,--quiet", options.quiet, "Print errors only");
    mesh->add_flag("-v,--verbose", options.verbosity, "More detail (repeat for more)");
    return mesh;
}

namespace {

// The output format's name as given with -f, in lower case ("" if none).
std::string format_name(const MeshCommandOptions& options) {
    std::string f = options.format;
    for (char& c : f) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return f;
}

bool mesh_output(const MeshCommandOptions& options) {
    const std::string name = format_name(options);
    return name.empty() ? io::has_mesh_extension(options.output) : (name == "obj" || name == "ply" || name == "off" || name == "stl");
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

}  // namespace

bool mesh_needs_gdal(const MeshCommandOptions& options) {
    return !io::has_mesh_extension(options.input) || !mesh_output(options);
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

int run_mesh(const MeshCommandOptions& options, Context& context, const MeshGdal& gdal) {
    auto log = make_logger(context.err, options.verbosity, options.quiet);
    std::string problem;
    std::optional<mesh::SimplifyOptions> engine = mesh_target(options, problem);
    if (!engine) {
        log->error("{}", problem);
        return kUsageError;
    }
    if (mesh_needs_gdal(options) && (!gdal.read_dem || !gdal.write_tin_layer || !gdal.check_layer_output)) {
        log->error("{} -> {}: a DEM or an OGR layer needs GDAL, which this caller did not provide", options.input, options.output);
        return kUsageError;
    }
    engine->lock_boundary = options.lock_boundary;
    engine->terrain = options.terrain;
    engine->threads = options.threads;
    const auto start = Clock::now();
    try {
        // Inside the try: on an error its destructor clears the terminal line before the message.
        Progress progress(context.err, progress_style(options.progress, context.err_is_terminal, options.quiet));
        engine->progress = [&progress](double done) { progress.update(done); };
        // Output: a mesh file, or an OGR layer of triangles.
        const std::string name = format_name(options);
        const bool to_mesh_file = mesh_output(options);
        io::MeshFormat format = io::MeshFormat::obj;
        if (to_mesh_file) {
            format = name.empty() ? io::mesh_format_of(options.output)
                     : name == "ply" ? io::MeshFormat::ply
                     : name == "off" ? io::MeshFormat::off
                     : name == "stl" ? io::MeshFormat::stl
                                     : io::MeshFormat::obj;
        }
        // Refuse an existing output, or a layer in a format GDAL cannot tell or write, before any work.
        io::OutputFile output(options.output, options.overwrite, &context.out);
        if (!to_mesh_file) gdal.check_layer_output(options.output, options.format);

        // Input: a mesh file, or a DEM raster triangulated into a TIN.
        progress.phase("reading " + options.input);
        mesh::Mesh m;
        io::AttributeLayout layout;                   // what m's attribute columns are
        std::vector<std::string> dropped, unwritten;  // attributes not kept, and not written
        std::optional<io::Dem> dem;
        std::size_t welded_vertices = 0;
        if (io::has_mesh_extension(options.input)) {
            io::MeshReadOptions read_options;
            read_options.triangulate = options.triangulate;
            io::MeshReadReport report;
            m = io::read_mesh(options.input, read_options, report);
            log->debug("read {} ({}{}): {} vertices, {} faces", options.input, io::to_string(report.format),
                       report.encoding.empty() ? "" : " " + report.encoding, m.points.size(), m.faces.size());
            layout = report.layout;
            dropped = report.dropped;
            for (const std::string& what : dropped) {
                log->warn("{}: {}: dropped (not carried to the simplified mesh)", options.input, what);
            }
            if (!layout.vertex.empty() || !layout.face.empty()) {
                log->debug("attributes kept: {} per vertex, {} per face", layout.vertex.size(), layout.face.size());
            }
            if (report.polygons_triangulated > 0) log->info("{} polygons split into triangle fans", report.polygons_triangulated);
            if (report.ignored_elements > 0) {
                log->warn("{} elements that are not faces (lines, points, unknown PLY elements) ignored", report.ignored_elements);
            }
            if (report.welded > 0) {
                log->info("{}: {} triangle corners welded into the vertex at their location (STL shares no vertices)", options.input,
                          report.welded);
            }
            welded_vertices = report.welded;
            if (options.weld) {
                const mesh::Welded welded = mesh::weld_coincident(m);
                welded_vertices += welded.vertices;
                log->info("welded {} vertices onto others at the same location", welded.vertices);
                for (std::size_t c = 0; c < welded.differs.size(); ++c) {
                    if (!welded.differs[c]) continue;
                    dropped.push_back("vertex " + layout.vertex[c].name + ": differs between vertices welded together");
                    log->warn("{}: {}: dropped (not carried to the simplified mesh)", options.input, dropped.back());
                }
                mesh::remove_vertex_columns(m, welded.differs);
                std::erase_if(layout.vertex, [&, c = std::size_t{0}](const io::AttributeColumn&) mutable { return welded.differs[c++]; });
            }
        } else {
            dem = gdal.read_dem(options.input, options.band);
            m = std::move(dem->tin);
            engine->terrain = true;
            engine->height_field = true;  // a grid's triangles: none overlap
            engine->lock_boundary = !options.free_boundary;
            log->debug("read DEM {} ({} x {} cells, {} without data): TIN of {} vertices, {} triangles", options.input,
                       dem->width, dem->height, dem->nodata_cells, m.points.size(), m.faces.size());
        }
        const double seconds_read = seconds_since(start);
        if (m.faces.empty()) throw io::InputError(options.input + ": no faces to simplify");
        if (const std::size_t repeated = mesh::count_repeated_corner_faces(m); repeated > 0) {
            log->warn("{} faces repeat a corner (no area) and are dropped", repeated);
        }
        const mesh::Mesh original = options.no_hausdorff ? mesh::Mesh{} : mesh::Mesh{m.points, m.faces};

        progress.phase("simplifying");
        const auto simplify_start = Clock::now();
        const mesh::SimplifyStats stats = mesh::simplify(m, *engine);
        const double seconds_simplify = seconds_since(simplify_start);
        if (const auto& edge = stats.non_manifold) {
            std::string faces;
            for (std::uint32_t f : edge->faces) faces += (faces.empty() ? "" : ", ") + std::to_string(f);
            throw io::InputError(options.input + ": the edge between vertices " + std::to_string(edge->a) + " and " +
                                 std::to_string(edge->b) + " (counted from 0) has more than two faces (" + faces +
                                 ", ...)" + (options.weld ? " once vertices at the same location are welded" : "") +
                                 ": non-manifold meshes are not supported");
        }
        if (engine->terrain && !stats.terrain) {
            const std::string why = stats.plan_overlap ? "faces " + std::to_string((*stats.plan_overlap)[0]) + " and " +
                                                             std::to_string((*stats.plan_overlap)[1]) +
                                                             " (counted from 0) overlap in the x-y plane"
                                                       : "the faces are not all turned the same way in the x-y plane";
            log->warn("{}: {}, so this is not a terrain TIN: simplified as a surface in space{}", options.input, why,
                      engine->stop.target == mesh::Target::max_error ? " (--max-error bounds the quadric error)" : "");
        } else if (stats.vertical_bound && !engine->lock_boundary) {
            log->info("border vertices kept where they are: the vertical bound is measured over the input's extent");
        }

        progress.phase("writing " + options.output);
        const auto write_start = Clock::now();
        if (to_mesh_file) {
            unwritten = io::write_mesh(m, layout, output.staging_path(), format, options.ascii);
            for (const std::string& column : unwritten) {
                log->warn("{}: {} not written: {} has no place for it", options.output, column, io::to_string(format));
            }
        } else {
            if (!layout.vertex.empty() || !layout.face.empty()) {
                log->warn("{}: vertex and face attributes not written: a layer of triangles has no place for them", options.output);
            }
            gdal.write_tin_layer(m, output.staging_path(), options.format, dem ? dem->crs_wkt : std::string(), options.layer_name);
        }
        output.commit();
        const double seconds_write = seconds_since(write_start);

        std::optional<mesh::HausdorffDistance> distance;
        std::optional<mesh::VerticalError> vertical;  // terrains
        double seconds_hausdorff = 0;
        if (!options.no_hausdorff) {
            progress.phase("measuring the Hausdorff distance");
            const auto measure_start = Clock::now();
            // Four samples per input face, at least 50 000 and at most 400 000 per direction.
            const std::size_t samples = std::clamp<std::size_t>(4 * original.faces.size(), 50000, 400000);
            distance = mesh::hausdorff(original, m, samples);
            if (stats.terrain) vertical = mesh::vertical_error(original, m, samples);
            seconds_hausdorff = seconds_since(measure_start);
        }
        const double total = seconds_since(start);
        progress.done();
        if (!stats.target_reached) {
            // An unwelded mesh is many separate pieces, whose border edges cannot collapse.
            const std::size_t coincident = options.weld ? 0 : mesh::count_coincident(m);
            log->warn("target not reached: {} faces left of the {} asked for; no more collapses pass the checks{}", stats.faces_out,
                      stats.target_faces,
                      coincident == 0 ? std::string()
                                      : fmt::format(" ({} of the vertices left share their location with another: "
                                                    "--weld merges such vertices first)",
                                                    coincident));
        }
        log->debug("refused collapses: {} link condition, {} border, {} flip, {} degenerate or duplicate face, {} intersection, "
                   "{} vertical error",
                   stats.refused_link, stats.refused_boundary, stats.refused_flip, stats.refused_degenerate,
                   stats.refused_intersection, stats.refused_vertical);
        log->debug("predicates: {} decided by the float filter, {} exactly in expansions, {} by GMP; peak memory {:.0f} MiB",
                   stats.predicates.filter_decided, stats.predicates.expansion_decided, stats.predicates.gmp_fallbacks,
                   peak_memory_mib());
        std::string summary = fmt::format("{} -> {} faces, {} -> {} vertices ({} collapses, {} refused), {}, {:.3f} s",
                                          stats.faces_in, stats.faces_out, stats.vertices_in, stats.vertices_out,
                                          stats.collapses, stats.refused(), describe(engine->stop, stats), total);
        if (distance) {
            summary += fmt::format("; Hausdorff {:.6g} ({:.4g}% of the diagonal)", distance->max(),
                                   distance->diagonal > 0 ? 100 * distance->max() / distance->diagonal : 0.0);
        }
        if (vertical) summary += fmt::format("; vertical error {:.6g}", vertical->max());
        if (context.err_is_terminal || options.verbosity > 0) log->info("{}", summary);
        if (options.json) {
            // The summary never mixes with a mesh written to stdout.
            std::ostream& out = output.to_stdout() ? context.err : context.out;
            out << "{\"command\":\"mesh\",\"input\":" << io::json_string(options.input)
                << ",\"output\":" << io::json_string(options.output) << ",\"vertices_in\":" << stats.vertices_in
                << ",\"vertices_out\":" << stats.vertices_out << ",\"faces_in\":" << stats.faces_in
                << ",\"faces_out\":" << stats.faces_out << ",\"welded_vertices\":" << welded_vertices
                << ",\"collapses\":" << stats.collapses
                << ",\"flat_collapses_unsearched\":" << stats.flat_unsearched
                << ",\"target\":{\"criterion\":" << io::json_string(describe(engine->stop, stats))
                << ",\"target_faces\":" << stats.target_faces << ",\"reached\":" << (stats.target_reached ? "true" : "false")
                << "},\"refused\":{\"total\":" << stats.refused() << ",\"link\":" << stats.refused_link
                << ",\"boundary\":" << stats.refused_boundary << ",\"flip\":" << stats.refused_flip
                << ",\"degenerate\":" << stats.refused_degenerate << ",\"intersection\":" << stats.refused_intersection
                << ",\"vertical\":" << stats.refused_vertical << "},\"max_quadric_error\":" << stats.max_error
                << ",\"terrain\":" << (stats.terrain ? "true" : "false")
                << ",\"lock_boundary\":" << (engine->lock_boundary || stats.vertical_bound ? "true" : "false");
            if (stats.vertical_bound) out << ",\"guaranteed_vertical_error\":" << engine->stop.value;
            // Attribute columns kept, dropped on reading (with the reason), left out on writing.
            auto names = [](const auto& list, auto name_of) {
                std::string text = "[";
                for (const auto& item : list) {
                    if (text.size() > 1) text += ',';
                    io::append_json_string(text, name_of(item));
                }
                return text + "]";
            };
            const auto column_name = [](const io::AttributeColumn& c) -> const std::string& { return c.name; };
            const auto itself = [](const std::string& text) -> const std::string& { return text; };
            out << ",\"attributes\":{\"vertex\":" << names(layout.vertex, column_name) << ",\"face\":" << names(layout.face, column_name)
                << ",\"dropped\":" << names(dropped, itself) << ",\"not_written\":" << names(unwritten, itself) << "}";
            if (dem) {
                out << ",\"dem\":{\"width\":" << dem->width << ",\"height\":" << dem->height
                    << ",\"cells_without_data\":" << dem->nodata_cells << ",\"crs\":" << (dem->crs_wkt.empty() ? "false" : "true") << "}";
            }
            if (distance) {
                const double diagonal = distance->diagonal > 0 ? distance->diagonal : 1.0;
                out << ",\"hausdorff\":{\"max\":" << distance->max() << ",\"max_fraction_of_diagonal\":" << distance->max() / diagonal
                    << ",\"input_to_output\":{\"max\":" << distance->forward.max << ",\"mean\":" << distance->forward.mean
                    << ",\"samples\":" << distance->forward.samples << "},\"output_to_input\":{\"max\":" << distance->backward.max
                    << ",\"mean\":" << distance->backward.mean << ",\"samples\":" << distance->backward.samples
                    << "},\"diagonal\":" << distance->diagonal << "}";
            }
            if (vertical) {
                out << ",\"vertical_error\":{\"max\":" << vertical->max() << ",\"input_to_output\":{\"max\":"
                    << vertical->forward.max << ",\"mean\":" << vertical->forward.mean << ",\"samples\":" << vertical->forward.samples
                    << "},\"output_to_input\":{\"max\":" << vertical->backward.max << ",\"mean\":" << vertical->backward.mean
                    << ",\"samples\":" << vertical->backward.samples << "},\"samples_outside\":" << vertical->outside << "}";
            }
            out << ",\"parallel\":{\"threads\":" << stats.threads << ",\"levels\":" << stats.levels << ",\"rounds\":" << stats.rounds
                << "},\"predicates\":{\"filter_decided\":" << stats.predicates.filter_decided
                << ",\"expansion_decided\":" << stats.predicates.expansion_decided
                << ",\"gmp_fallbacks\":" << stats.predicates.gmp_fallbacks << "},\"seconds\":{\"read\":" << seconds_read
                << ",\"simplify\":" << seconds_simplify << ",\"write\":" << seconds_write << ",\"hausdorff\":" << seconds_hausdorff
                << ",\"total\":" << total << "},\"peak_memory_mib\":" << peak_memory_mib() << "}\n";
        }
        return kOk;
    } catch (const io::InputError& error) {
        log->error("{}", error.what());
    } catch (const io::OutputError& error) {
        log->error("{}", error.what());
    } catch (const std::bad_alloc&) {
        log->error("out of memory");
    }
    return kUsageError;
}

}  // namespace toposimp::cli
