#include "cli/cli.hpp"

#include "cli/check_command.hpp"
#include "cli/map_command.hpp"
#include "cli/mesh_command.hpp"
#include "io/common/errors.hpp"
#include "io/mesh/mesh_files.hpp"
#include "io/ogr/dem.hpp"
#include "io/ogr/gdal_env.hpp"

#include <CLI/CLI.hpp>
#include <gmp.h>

#include <algorithm>
#include <ostream>

namespace toposimp::cli {
namespace {

constexpr const char* kVersion = TOPOSIMP_VERSION;  // CMakeLists.txt's project version

// GDAL's tools spell some options with one dash (-lco, -dsco, -nln); CLI11 wants two.
std::vector<std::string> gdal_style_to_cli11(const std::vector<std::string>& args) {
    std::vector<std::string> out;
    out.reserve(args.size());
    for (const std::string& arg : args) {
        if (arg == "-lco" || arg == "-dsco" || arg == "-nln") {
            out.push_back("-" + arg);
        } else {
            out.push_back(arg);
        }
    }
    return out;
}

}  // namespace

int run(const std::vector<std::string>& args, Context& context) {
    CLI::App app{"toposimp: exact, topology-preserving simplification of maps and meshes", "toposimp"};
    app.require_subcommand(0, 1);
    app.set_version_flag("--version",
                         std::string("toposimp ") + kVersion + " (GDAL " + io::gdal_version() + ", GMP " + gmp_version + ")");
    app.footer("Run 'toposimp COMMAND --help' for a command's options; 'man toposimp' for details.\n"
               "Exit status: 0 ok, 1 topology or validation failure, 2 usage or input error.");
    MapOptions map_options;
    CLI::App* map = add_map_command(app, map_options);
    MeshCommandOptions mesh_options;
    CLI::App* mesh = add_mesh_command(app, mesh_options);
    CheckCommandOptions check_options;
    CLI::App* check = add_check_command(app, check_options);
    bool formats_json = false;
    CLI::App* formats = app.add_subcommand("formats", "List the mesh formats and what each carries");
    formats->add_flag("--json", formats_json, "As JSON");
    auto chosen = [&]() -> CLI::App* {
        if (app.got_subcommand(map)) return map;
        if (app.got_subcommand(mesh)) return mesh;
        if (app.got_subcommand(check)) return check;
        if (app.got_subcommand(formats)) return formats;
        return nullptr;
    };

    std::vector<std::string> reversed = gdal_style_to_cli11(args);
    std::reverse(reversed.begin(), reversed.end());
    try {
        app.parse(reversed);
    } catch (const CLI::CallForHelp&) {
        context.out << (chosen() ? chosen()->help() : app.help());
        return kOk;
    } catch (const CLI::CallForVersion&) {
        context.out << app.version() << '\n';
        return kOk;
    } catch (const CLI::ParseError& error) {
        if (error.get_exit_code() == 0) {
            context.out << (chosen() ? chosen()->help() : app.help());
            return kOk;
        }
        context.err << "toposimp: error: " << error.what() << "\n";
        context.err << "Run 'toposimp " << (chosen() ? chosen()->get_name() + " " : "") << "--help' for usage.\n";
        return kUsageError;
    }
    if (app.got_subcommand(map)) return run_map(map_options, context);
    if (app.got_subcommand(mesh)) {
        auto check_layer_output = [](const std::string& path, const std::string& driver) {
            try {
                io::check_vector_output(path, driver);
            } catch (const io::OutputError& error) {
                throw io::OutputError(std::string(error.what()) + "; a mesh is written as " + io::mesh_extensions_text(", ", " or "));
            }
        };
        return run_mesh(mesh_options, context, {&io::read_dem, &io::write_tin_layer, check_layer_output});
    }
    if (app.got_subcommand(check)) return run_check(check_options, context);
    if (app.got_subcommand(formats)) {
        print_mesh_formats(context.out, formats_json);
        return kOk;
    }
    context.err << app.help();
    return kUsageError;
}

}  // namespace toposimp::cli
