// `toposimp map` on layers in memory (map_job with MapMemory, what the Python module runs): the
// same geometries as the command line writes to a file, errors thrown with its messages, and a
// cancel flag that stops the engine. (tests/python covers the package; this covers the C++ path
// under every preset, ASan included.)
#include "cli/cli_fixtures.hpp"
#include "cli/guard.hpp"
#include "cli/logging.hpp"
#include "cli/map_command.hpp"
#include "core/cancel.hpp"
#include "io/common/errors.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "validate/check.hpp"

#include <atomic>

namespace toposimp::testing {
namespace {

// A layer of a dataset as WKB, feature by feature (an empty string for no geometry).
io::MemoryLayer layer_as_wkb(const std::string& path, const std::string& name) {
    GDALAllRegister();
    GDALDatasetUniquePtr dataset(GDALDataset::Open(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY));
    EXPECT_TRUE(dataset) << path;
    OGRLayer* layer = dataset->GetLayerByName(name.c_str());
    EXPECT_NE(layer, nullptr) << name;
    io::MemoryLayer out;
    out.name = name;
    for (const auto& feature : *layer) {
        const OGRGeometry* geometry = feature->GetGeometryRef();
        std::string& wkb = out.wkb.emplace_back();
        if (geometry == nullptr) continue;
        wkb.resize(static_cast<std::size_t>(geometry->WkbSize()));
        geometry->exportToWkb(wkbNDR, reinterpret_cast<unsigned char*>(wkb.data()), wkbVariantOldOgc);
    }
    return out;
}

struct MemoryRun {
    cli::MapMemory memory;
    std::ostringstream out, err;
};

void run_in_memory(cli::MapOptions options, const io::MemoryLayers& input, const io::MemoryLayers* points, MemoryRun& run,
                   const std::atomic<bool>* cancel = nullptr) {
    options.input = input.source;
    options.output = "<memory>";
    run.memory.input = &input;
    run.memory.points = points;
    cli::Context context{run.out, run.err, false};
    context.cancel = cancel;
    auto log = cli::make_logger(run.err, 0, false);
    cli::map_job(options, context, *log, &run.memory);
}

TEST(MapMemory, GivesTheGeometriesTheCommandLineWrites) {
    const std::string source = testdata("nh_borders.gpkg");
    io::MemoryLayers input, points;
    input.source = "test";
    input.layers.push_back(layer_as_wkb(source, "borders"));
    points.source = "points";
    points.layers.push_back(layer_as_wkb(source, "places"));
    for (const char* keep : {"10%", "3%"}) {
        cli::MapOptions options;
        options.keep = keep;
        MemoryRun run;
        run_in_memory(options, input, &points, run);
        ASSERT_EQ(run.memory.output.size(), 1u);
        ASSERT_EQ(run.memory.summaries.size(), 1u);
        EXPECT_NE(run.memory.summaries[0].find("\"vertices_in\":992"), std::string::npos) << run.memory.summaries[0];

        const auto dir = fresh_dir("map-memory");
        const std::string written = (dir / "out.gpkg").string();
        const CliResult cli = run_cli({"map", source, "-l", "borders", "--points", source + ":places", "--keep", keep, "-o", written});
        ASSERT_EQ(cli.code, 0) << cli.err;
        const io::MemoryLayer expected = layer_as_wkb(written, "borders");
        ASSERT_EQ(run.memory.output[0].layers.size(), 1u);
        EXPECT_EQ(run.memory.output[0].layers[0].wkb, expected.wkb) << keep;
    }
}

TEST(MapMemory, BadInputAndOptionsThrowTheCommandLinesMessages) {
    io::MemoryLayers input;
    input.source = "frame";
    io::MemoryLayer& layer = input.layers.emplace_back();
    layer.name = "roads";
    layer.wkb = {std::string("\x01\x02\x00\x00", 4)};  // a LineString's header, cut short
    cli::MapOptions options;
    MemoryRun bad;
    try {
        run_in_memory(options, input, nullptr, bad);
        FAIL() << "no error";
    } catch (const io::InputError& error) {
        EXPECT_NE(std::string(error.what()).find("'frame', layer 'roads', feature 0: not a WKB geometry"), std::string::npos)
            << error.what();
    }
    input.layers[0] = layer_as_wkb(testdata("nh_borders.gpkg"), "borders");
    options.keep = "120%";
    MemoryRun usage;
    try {
        run_in_memory(options, input, nullptr, usage);
        FAIL() << "no error";
    } catch (const cli::UsageError& error) {
        EXPECT_NE(error.message.find("more than all vertices"), std::string::npos) << error.message;
    }
}

TEST(MapMemory, ACancelFlagStopsTheEngine) {
    io::MemoryLayers input;
    input.source = "test";
    input.layers.push_back(layer_as_wkb(testdata("nh_borders.gpkg"), "borders"));
    std::atomic<bool> cancel{true};
    cli::MapOptions options;
    MemoryRun run;
    EXPECT_THROW(run_in_memory(options, input, nullptr, run, &cancel), Cancelled);
    EXPECT_TRUE(run.memory.output.empty());
}

// check on layers in memory (through GeoPackages in /vsimem/): clean for toposimp's output, and a
// line replaced by its chord puts a point on its other side.
TEST(MapMemory, CheckRunsOnLayersInMemory) {
    io::MemoryLayers original, points;
    original.source = "original";
    original.layers.push_back(layer_as_wkb(testdata("nh_borders.gpkg"), "borders"));
    points.source = "points";
    points.layers.push_back(layer_as_wkb(testdata("nh_borders.gpkg"), "places"));
    cli::MapOptions options;
    options.keep = "10%";
    MemoryRun run;
    run_in_memory(options, original, &points, run);
    io::MemoryLayers simplified = run.memory.output[0];
    simplified.source = "simplified";
    EXPECT_TRUE(validate::check(original, simplified, &points, {}).clean());

    io::MemoryLayers line, chord, point;
    auto wkb = [](const OGRGeometry& geometry) {
        std::string bytes(static_cast<std::size_t>(geometry.WkbSize()), '\0');
        geometry.exportToWkb(wkbNDR, reinterpret_cast<unsigned char*>(bytes.data()), wkbVariantOldOgc);
        return bytes;
    };
    OGRLineString bent, straight;
    bent.addPoint(0, 0), bent.addPoint(1, 1), bent.addPoint(2, 0);
    straight.addPoint(0, 0), straight.addPoint(2, 0);
    const OGRPoint inside(1, 0.5);
    line.layers.push_back({"l", "", {wkb(bent)}});
    chord.layers.push_back({"l", "", {wkb(straight)}});
    point.layers.push_back({"p", "", {wkb(inside)}});
    const validate::CheckReport report = validate::check(line, chord, &point, {});
    ASSERT_EQ(report.violations.size(), 1u);
    EXPECT_EQ(report.violations[0].kind, validate::ViolationKind::point_changed_side);
}

}  // namespace
}  // namespace toposimp::testing
