// Real files written by others (scripts/corpus.sh extracts them from Debian packages into
// build/corpus): `toposimp map` on every layer of every dataset ends with exit 0 and an output
// that `toposimp check` finds clean, or with exit 2 and a message naming the file; never a crash,
// a hang (ctest's timeout) or a leftover file. Where a layer is small enough for the independent
// brute-force checker (tests/support), the engine's result on it is checked there too.
#include "cli/cli_fixtures.hpp"
#include "core/map/simplify.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "support/exact_checker.hpp"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace toposimp::testing {
namespace {

// The independent checker looks at every pair of segments: layers up to this many vertices.
constexpr std::size_t kIndependentCheckUpTo = 20000;

struct LayerCase {
    std::string dataset;  // a path GDAL opens (/vsizip/ for archives)
    std::string layer;
};

std::vector<LayerCase> corpus_layers(const std::filesystem::path& root) {
    std::vector<std::string> datasets;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        const std::string path = entry.path().string(), extension = entry.path().extension().string();
        if (extension == ".zip") datasets.push_back("/vsizip/" + path);
        if (extension == ".shp" || extension == ".gpkg" || extension == ".geojson" || extension == ".gml" || extension == ".gpx" ||
            extension == ".osm") {
            datasets.push_back(path);
        }
    }
    std::sort(datasets.begin(), datasets.end());
    std::vector<LayerCase> layers;
    GDALAllRegister();
    for (const std::string& dataset : datasets) {
        std::unique_ptr<GDALDataset> opened(GDALDataset::Open(dataset.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY));
        if (!opened) continue;
        for (int i = 0; i < opened->GetLayerCount(); ++i) layers.push_back({dataset, opened->GetLayer(i)->GetName()});
    }
    return layers;
}

TEST(Corpus, EveryLayerIsSimplifiedCleanlyOrRefusedByName) {
    const std::filesystem::path root = std::string(TOPOSIMP_SOURCE_DIR) + "/build/corpus";
    ASSERT_TRUE(std::filesystem::exists(root)) << "no corpus: run scripts/corpus.sh (scripts/test.sh does)";
    const std::vector<LayerCase> layers = corpus_layers(root);
    ASSERT_GE(layers.size(), 10u) << "the corpus is incomplete: run scripts/corpus.sh again";
    std::size_t simplified = 0, refused = 0, independently = 0;
    for (const LayerCase& c : layers) {
        SCOPED_TRACE(c.dataset + ", layer " + c.layer);
        const auto dir = fresh_dir("corpus");
        const std::string out = (dir / "out.gpkg").string();
        const CliResult map = run_cli({"map", c.dataset, "-l", c.layer, "-o", out, "--keep", "10%", "-q"});
        ASSERT_TRUE(map.code == 0 || map.code == 2) << map.code << ": " << map.err;
        if (map.code == 2) {
            ++refused;
            const std::string name = c.dataset.substr(c.dataset.rfind('/') + 1);
            EXPECT_NE(map.err.find(name), std::string::npos) << "the message names no file: " << map.err;
            EXPECT_TRUE(files_in(dir).empty()) << "left behind after a refusal";
            continue;
        }
        ++simplified;
        EXPECT_EQ(files_in(dir), std::vector<std::string>{"out.gpkg"});
        const CliResult check = run_cli({"check", c.dataset, out, "-l", c.layer, "-L", c.layer, "--json"});
        EXPECT_EQ(check.code, 0) << check.out << check.err;
        // The same simplification in-process, checked by the independent checker.
        map::MapData input;
        io::OgrDataset::read(c.dataset, {c.layer}, input);
        if (input.vertices.size() > kIndependentCheckUpTo) continue;
        ++independently;
        map::SimplifyOptions options;
        options.stop = {map::Target::keep_fraction, 0.1};
        const map::SimplifyResult result = map::simplify(input, options);
        const CheckReport report = check_simplification(input, result.kept);
        EXPECT_TRUE(report.ok()) << report.summary();
    }
    RecordProperty("layers", static_cast<int>(layers.size()));
    RecordProperty("simplified", static_cast<int>(simplified));
    RecordProperty("refused", static_cast<int>(refused));
    RecordProperty("independently_checked", static_cast<int>(independently));
    std::printf("corpus: %zu layers: %zu simplified and checked clean (%zu also by the independent checker), %zu refused "
                "with a message naming the file\n",
                layers.size(), simplified, independently, refused);
}

}  // namespace
}  // namespace toposimp::testing
