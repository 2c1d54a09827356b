#include "cli/check_command.hpp"

#include "cli/guard.hpp"
#include "cli/json.hpp"
#include "cli/logging.hpp"
#include "cli/progress.hpp"
#include "io/common/errors.hpp"
#include "io/common/json_text.hpp"
#include "io/common/output_file.hpp"

#include <fstream>
#include <iomanip>
#include <ostream>

namespace toposimp::cli {

CLI::App* add_check_command(CLI::App& app, CheckCommandOptions& options) {
    CLI::App* check = app.add_subcommand("check", "Compare an original with a simplified dataset and report what was broken");
    std::string kinds = "Violations reported:\n";
    for (const validate::KindInfo& kind : validate::kinds()) kinds += std::string("  ") + kind.name + ": " + kind.meaning + "\n";
    check->footer(kinds +
                  "GEOS checks polygon validity; contacts, sides and containment are decided with exact predicates.\n"
                  "Exit status: 0 clean, 1 violations found, 2 usage or input error.");
    check->add_option("original", options.check.original, "The dataset before simplification (any OGR source)")->required();
    check->add_option("simplified", options.check.simplified, "The simplified dataset (by any tool)")->required();
    check->add_option("-p,--points", options.check.points, "Control points: FILE or FILE:LAYER");
    check->add_option("--key", options.check.key, "Match features by this field (default: by order)");
    check->add_option("-l,--layer", options.check.layers, "Layer to compare (repeatable; default: every layer)")
        ->allow_extra_args(false);
    check->add_option("-L,--simplified-layer", options.check.simplified_layer,
                      "The simplified dataset's layer to compare with the one original layer (-l), whatever its name");
    auto* precision = check->add_option("--precision", options.precision,
                                        "The simplified output was rounded onto the grid of multiples of STEP (toposimp map "
                                        "--precision): a vertex on it stands for an original vertex up to two steps away");
    auto* decimals = check->add_option("--decimals", options.decimals, "The same as --precision 1e-D")->check(CLI::Range(0, 300));
    precision->excludes(decimals);
    decimals->excludes(precision);
    check->add_flag("--json", options.json, "Print the report as JSON instead of a table");
    check->add_option("--geojson-errors", options.geojson_errors,
                      "Also write each violation as a GeoJSON point with its kind and detail (for QGIS)");
    check->add_flag("--progress", options.progress,
                  "Report progress as lines \"PROGRESS <percent> <phase>\" on stderr (for GUIs and wrappers)");
    check->add_flag("-q,--quiet", options.quiet, "Print nothing; the exit status tells");
    check->add_flag("-v,--verbose", options.verbosity, "More detail");
    return check;
}

void print_table(std::ostream& out, const validate::CheckReport& report) {
    out << report.features << " features compared, " << report.control_points << " control points: ";
    if (report.clean()) {
        out << "clean\n";
    } else {
        out << report.violations.size() << " violation(s)\n";
        out << std::left << std::setw(24) << "kind" << std::setw(14) << "layer" << std::setw(10) << "feature" << std::setw(10)
            << "other" << std::setw(44) << "where (x y)" << "detail [decided by]\n";
        for (const validate::Violation& v : report.violations) {
            out << std::setw(24) << validate::name(v.kind) << std::setw(14) << v.layer << std::setw(10) << v.feature << std::setw(10) << v.other
                << std::setw(44) << (io::json_number(v.x) + " " + io::json_number(v.y)) << v.detail << " [" << v.decided_by << "]\n";
        }
        out << "counts:";
        for (const auto& [kind, count] : report.counts()) {
            if (count > 0) out << ' ' << kind << '=' << count;
        }
        out << '\n';
    }
    if (report.invalid_in_original > 0) {
        out << report.invalid_in_original << " polygons were already invalid in the original (not counted)\n";
    }
}

void print_json(std::ostream& out, const validate::CheckReport& report) {
    JsonWriter json;
    json.field("command", "check").field("clean", report.clean()).field("features", report.features);
    json.field("control_points", report.control_points).field("invalid_in_original", report.invalid_in_original);
    json.object("counts");
    for (const auto& [kind, count] : report.counts()) json.field(kind, count);
    json.end().array("violations");
    for (const validate::Violation& v : report.violations) {
        json.object()
            .field("kind", validate::name(v.kind))
            .field("layer", v.layer)
            .field("feature", v.feature)
            .field("other", v.other)
            .exact("x", v.x)
            .exact("y", v.y)
            .field("detail", v.detail)
            .field("decided_by", v.decided_by)
            .end();
    }
    out << json.line();
}

std::string violations_geojson(const validate::CheckReport& report) {
    std::string out = "{\"type\":\"FeatureCollection\",\"name\":\"violations\",\"features\":[\n";
    for (std::size_t i = 0; i < report.violations.size(); ++i) {
        const validate::Violation& v = report.violations[i];
        out += i ? ",\n" : "";
        out += "{\"type\":\"Feature\",\"properties\":{\"kind\":" + io::json_string(validate::name(v.kind)) + ",\"layer\":" + io::json_string(v.layer) +
               ",\"feature\":" + io::json_string(v.feature) + ",\"other\":" + io::json_string(v.other) + ",\"detail\":" + io::json_string(v.detail) +
               ",\"decided_by\":" + io::json_string(v.decided_by) + "},\"geometry\":{\"type\":\"Point\",\"coordinates\":[" +
               io::json_number(v.x) + "," + io::json_number(v.y) + "]}}";
    }
    return out + "\n]}\n";
}

// parse (done) → check → write the GeoJSON of the violations → report.
int run_check(const CheckCommandOptions& command, Context& context) {
    auto log = make_logger(context.err, command.verbosity, command.quiet);
    CheckCommandOptions options = command;
    if (options.decimals >= 0) options.check.grid = map::GridStep::decimals(options.decimals);
    if (!options.precision.empty()) {
        options.check.grid = map::GridStep::parse(options.precision);
        if (!options.check.grid) {
            log->error("--precision: '{}' is not a positive decimal step (e.g. 0.0001, 1e-4 or 25)", options.precision);
            return kUsageError;
        }
    }
    return guarded(*log, [&] {
        Progress progress(context.err, progress_style(options.progress, context.err_is_terminal, options.quiet));
        progress.phase("checking " + options.check.simplified + " against " + options.check.original);
        const validate::CheckReport report = validate::check(options.check);
        progress.done();
        if (!options.geojson_errors.empty()) {
            io::OutputFile output(options.geojson_errors, true, &context.out);
            {
                std::ofstream file(output.staging_path(), std::ios::binary);
                file << violations_geojson(report);
                if (!file) throw io::OutputError("error writing '" + options.geojson_errors + "'");
            }
            output.commit();
        }
        if (options.json) {
            print_json(context.out, report);
        } else if (!options.quiet) {
            print_table(context.out, report);
        }
        return report.clean() ? kOk : kTopologyFailure;
    });
}

}  // namespace toposimp::cli
