// Shapefile records decoded from the .shp directly must be exactly what OGR reads: control
// points from files written by OGR in every point shape type, and line and polygon shapes (what
// a written output is checked with) in every such type, each against OGR's reading of the file.
#include "core/map/coverage.hpp"
#include "io/map/shapefile.hpp"

#include "io/common/errors.hpp"
#include "io/ogr/gdal_support.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "support/temp_path.hpp"
#include "unit/io/ogr_points_reference.hpp"

#include <cpl_conv.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <tuple>
#include <limits>

namespace toposimp::io {
namespace {

// A shapefile of one geometry type, written through OGR; geometries given as WKT ("" for none).
// A "name" field and a feature per WKT ("": a NULL geometry) in `layer`, then the FIDs in
// `deleted` deleted.
void add_features(OGRLayer& layer, const std::vector<std::string>& wkts, const std::vector<GIntBig>& deleted) {
    layer.CreateField(std::make_unique<OGRFieldDefn>("name", OFTString).get());
    for (const std::string& wkt : wkts) {
        OGRFeatureUniquePtr feature(OGRFeature::CreateFeature(layer.GetLayerDefn()));
        feature->SetField("name", "a point");
        if (!wkt.empty()) {
            OGRGeometry* geometry = nullptr;
            EXPECT_EQ(OGRGeometryFactory::createFromWkt(wkt.c_str(), nullptr, &geometry), OGRERR_NONE) << wkt;
            // (A layer of Multi geometries takes only those: a FlatGeobuf's.)
            if (OGR_GT_IsSubClassOf(layer.GetGeomType(), wkbGeometryCollection)) geometry = OGRGeometryFactory::forceTo(geometry, layer.GetGeomType());
            feature->SetGeometryDirectly(geometry);
        }
        EXPECT_EQ(layer.CreateFeature(feature.get()), OGRERR_NONE) << wkt;
    }
    for (const GIntBig fid : deleted) EXPECT_EQ(layer.DeleteFeature(fid), OGRERR_NONE);
}

class ShapeFile {
public:
    ShapeFile(const std::string& name, OGRwkbGeometryType type, const std::vector<std::string>& wkts,
              const std::vector<GIntBig>& deleted = {}) {
        // Named for the test too: tests run in parallel, and two of them write a "line" file.
        const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
        directory_ = testing::temp_path("shp-" + std::string(test->test_suite_name()) + "-" + test->name() + "-" + name);
        std::filesystem::remove_all(directory_);
        std::filesystem::create_directories(directory_);
        path_ = (directory_ / (name + ".shp")).string();
        register_drivers();
        GDALDataset* dataset =
            GetGDALDriverManager()->GetDriverByName("ESRI Shapefile")->Create(path_.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
        const char* options[] = {"AUTO_REPACK=NO", nullptr};  // deleted records stay in the files, flagged
        OGRSpatialReference wgs84;
        wgs84.importFromEPSG(4326);
        OGRLayer* layer = dataset->CreateLayer(name.c_str(), &wgs84, type, const_cast<char**>(options));
        add_features(*layer, wkts, deleted);
        GDALClose(dataset);
    }
    ~ShapeFile() { std::filesystem::remove_all(directory_); }

    std::vector<Point> read_with_ogr() const { return points_read_by_ogr(path_); }

    const std::string& path() const { return path_; }
    std::filesystem::path sibling(const char* extension) const {
        return std::filesystem::path(path_).replace_extension(extension);
    }

private:
    std::filesystem::path directory_;
    std::string path_;
};

TEST(ShapefilePoints, EveryPointTypeReadsAsOgrReadsIt) {
    const std::string tiny = "4.9406564584124654e-324", odd = "0.30000000000000004";
    struct Case {
        const char* name;
        OGRwkbGeometryType type;
        std::vector<std::string> wkts;
        std::size_t points;
    };
    const std::vector<Case> cases = {
        {"point", wkbPoint, {"POINT (1.5 -2.25)", "", "POINT (" + tiny + " -" + odd + ")", "POINT (1e15 -1e-15)"}, 3},
        {"pointz", wkbPoint25D, {"POINT Z (7 8 9)", "", "POINT Z (-180 90 5)"}, 2},
        {"pointm", wkbPointM, {"POINT M (1 2 3)", "POINT M (" + odd + " " + tiny + " 0)"}, 2},
        {"multipoint", wkbMultiPoint, {"MULTIPOINT ((3 4),(5 6))", "", "MULTIPOINT EMPTY", "MULTIPOINT ((-1 " + odd + "))"}, 3},
        {"multipointz", wkbMultiPoint25D, {"MULTIPOINT Z ((3 4 1),(5 6 2),(7 8 3))", "MULTIPOINT Z ((1 1 1))"}, 4},
        {"multipointm", wkbMultiPointM, {"MULTIPOINT M ((3 4 1),(5 6 2))"}, 2},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const ShapeFile file(c.name, c.type, c.wkts);
        const std::vector<Point> reference = file.read_with_ogr();
        ASSERT_EQ(reference.size(), c.points);
        const std::optional<std::vector<Point>> read = read_shapefile_points(file.path());
        ASSERT_TRUE(read.has_value());
        expect_same_points(*read, reference);
        expect_same_points(read_control_points(file.path()), reference);
    }
}

// Records deleted in the .dbf are skipped, as OGR skips them; many records cross the read buffer.
TEST(ShapefilePoints, DeletedRecordsAndManyRecords) {
    std::vector<std::string> wkts;
    std::uint64_t state = 12345;
    for (int i = 0; i < 120000; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        const double x = static_cast<double>(state >> 11) * 0x1p-53 * 360 - 180;
        char text[128];
        if (i % 7 == 3) {
            std::snprintf(text, sizeof text, "MULTIPOINT ((%.17g %.17g),(%.17g 1))", x, x / 3, -x);
        } else {
            std::snprintf(text, sizeof text, "MULTIPOINT ((%.17g %.17g))", x, x / 3);
        }
        wkts.emplace_back(i % 1000 == 999 ? "" : text);
    }
    const ShapeFile file("many", wkbMultiPoint, wkts, {0, 5, 77777, 119999});
    const std::vector<Point> reference = file.read_with_ogr();
    ASSERT_GT(reference.size(), 130000u);
    const std::optional<std::vector<Point>> read = read_shapefile_points(file.path());
    ASSERT_TRUE(read.has_value());
    expect_same_points(*read, reference);
}

TEST(ShapefilePoints, NonFiniteCoordinateNamesFileLayerAndFeature) {
    const ShapeFile file("nonfinite", wkbPoint, {"POINT (1 2)", "POINT (3 4)", "POINT (5 2)"});
    {
        // WKT has no infinity: the third record's x (header 100 bytes, records of 8 + 20) set in place.
        std::fstream shp(file.path(), std::ios::in | std::ios::out | std::ios::binary);
        shp.seekp(100 + 2 * 28 + 8 + 4);
        const double infinity = std::numeric_limits<double>::infinity();
        unsigned char bytes[8];
        std::uint64_t bits = 0;
        std::memcpy(&bits, &infinity, sizeof bits);
        for (int i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(bits >> (8 * i));
        shp.write(reinterpret_cast<const char*>(bytes), 8);
    }
    EXPECT_THROW((void)read_shapefile_points(file.path()), InputError);
    try {
        (void)read_control_points(file.path());
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_EQ(std::string(error.what()),
                  "'" + file.path() + "', layer 'nonfinite', feature 2: control point has a non-finite coordinate");
    }
}

// Not points, a sibling file missing, or records not where the .shx says: the fast reader
// declines and OGR's reading decides.
TEST(ShapefilePoints, AnythingElseIsLeftToOgr) {
    const ShapeFile lines("line", wkbLineString, {"LINESTRING (0 0,1 1)"});
    EXPECT_FALSE(read_shapefile_points(lines.path()).has_value());
    try {
        (void)read_control_points(lines.path());
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("feature 0: control points must be Point or MultiPoint, not"), std::string::npos)
            << error.what();
    }

    const ShapeFile no_dbf("nodbf", wkbPoint, {"POINT (1 2)"});
    std::filesystem::remove(no_dbf.sibling(".dbf"));
    EXPECT_FALSE(read_shapefile_points(no_dbf.path()).has_value());
    expect_same_points(read_control_points(no_dbf.path()), no_dbf.read_with_ogr());

    const ShapeFile truncated("truncated", wkbPoint, {"POINT (1 2)", "POINT (3 4)"});
    std::filesystem::resize_file(truncated.path(), std::filesystem::file_size(truncated.path()) - 5);
    EXPECT_FALSE(read_shapefile_points(truncated.path()).has_value());

    const ShapeFile moved("moved", wkbPoint, {"POINT (1 2)", "POINT (3 4)"});
    {
        std::fstream shx(moved.sibling(".shx"), std::ios::in | std::ios::out | std::ios::binary);
        shx.seekp(100 + 8 + 3);  // the second record's offset, low byte of a big-endian word count
        shx.put(static_cast<char>(0x41));  // was 0x40: (100 + 28) / 2
    }
    EXPECT_FALSE(read_shapefile_points(moved.path()).has_value());
}

// The parts of an OGR geometry as read_shapefile_shapes gives them: vertices one after another
// (z too for 3D ones), each part's start.
struct Reference {
    std::vector<Point> xy;
    std::vector<double> z;
    std::vector<std::uint32_t> part_starts;
};

Reference as_record(const OGRGeometry* geometry) {
    Reference record;
    auto add = [&](const OGRSimpleCurve& curve) {
        record.part_starts.push_back(static_cast<std::uint32_t>(record.xy.size()));
        for (int i = 0; i < curve.getNumPoints(); ++i) {
            record.xy.push_back({curve.getX(i), curve.getY(i)});
            if (curve.Is3D()) record.z.push_back(curve.getZ(i));
        }
    };
    auto walk = [&](auto&& self, const OGRGeometry* g) -> void {
        if (g == nullptr) return;
        switch (wkbFlatten(g->getGeometryType())) {
            case wkbLineString: add(*g->toLineString()); break;
            case wkbPolygon:
                for (const OGRLinearRing* ring : *g->toPolygon()) add(*ring);
                break;
            case wkbMultiLineString:
            case wkbMultiPolygon:
                for (const OGRGeometry* member : *g->toGeometryCollection()) self(self, member);
                break;
            default: ADD_FAILURE() << "unexpected " << g->getGeometryName();
        }
    };
    walk(walk, geometry);
    return record;
}

void expect_same_record(const ShapeRecord& read, const Reference& reference, std::size_t fid) {
    ASSERT_EQ(std::vector<std::uint32_t>(read.part_starts.begin(), read.part_starts.end()), reference.part_starts) << "feature " << fid;
    ASSERT_EQ(read.xy.size(), reference.xy.size()) << "feature " << fid;
    for (std::size_t i = 0; i < read.xy.size(); ++i) {
        EXPECT_EQ(std::memcmp(&read.xy[i], &reference.xy[i], sizeof(Point)), 0) << "feature " << fid << ", vertex " << i;
    }
    ASSERT_EQ(read.z.size(), reference.z.size()) << "feature " << fid;
    for (std::size_t i = 0; i < read.z.size(); ++i) {
        EXPECT_EQ(std::memcmp(&read.z[i], &reference.z[i], sizeof(double)), 0) << "feature " << fid << ", z " << i;
    }
}

// A layer to write through OGR (ShapeFile): its name, geometry type and features as WKT.
struct LayerCase {
    const char* name;
    OGRwkbGeometryType type;
    std::vector<std::string> wkts;
};
// The least subnormal double, and a sum that is not its decimal text.
constexpr const char* kTiny = "4.9406564584124654e-324";
constexpr const char* kOdd = "0.30000000000000004";

TEST(ShapefileShapes, EveryLineAndPolygonTypeReadsAsOgrReadsIt) {
    const std::string tiny = kTiny, odd = kOdd;
    const std::vector<LayerCase> cases = {
        {"line", wkbLineString, {"LINESTRING (0 0,1 " + odd + ",2 " + tiny + ")", "", "LINESTRING (1e300 -1e-300,5 6)"}},
        {"multiline", wkbMultiLineString, {"MULTILINESTRING ((0 0,1 1),(2 2,3 3,4 " + odd + "))", "LINESTRING (7 7,8 8)"}},
        {"linez", wkbLineString25D, {"LINESTRING Z (0 0 1,1 1 " + odd + ")", "MULTILINESTRING Z ((0 0 0,1 0 0),(5 5 5,6 6 6))"}},
        {"linem", wkbLineStringM, {"LINESTRING M (0 0 1,1 1 2,3 " + odd + " 4)"}},
        // Rings written clockwise outside and counter-clockwise inside, as the driver stores
        // them: OGR reads them back in the stored order either way.
        {"polygon", wkbPolygon,
         {"POLYGON ((0 0,0 10,10 10,10 0,0 0),(2 2,4 2,4 4,2 4,2 2))", "",
          "MULTIPOLYGON (((20 20,20 30,30 30,20 20)),((40 40,40 " + odd + ",50 40,40 40)))"}},
        {"polygonz", wkbPolygon25D, {"POLYGON Z ((0 0 1,0 10 2,10 10 3,0 0 1))"}},
    };
    for (const LayerCase& c : cases) {
        SCOPED_TRACE(c.name);
        const ShapeFile file(c.name, c.type, c.wkts);
        const std::optional<ShapeTable> read = read_shapefile_shapes(file.path());
        ASSERT_TRUE(read.has_value());
        ASSERT_EQ(read->size(), c.wkts.size());
        DatasetPtr dataset = open_vector(file.path());
        OGRLayer* layer = dataset->GetLayer(0);
        std::size_t fid = 0;
        for (OGRFeatureUniquePtr feature{layer->GetNextFeature()}; feature; feature.reset(layer->GetNextFeature()), ++fid) {
            ASSERT_LT(fid, read->size());
            expect_same_record((*read)[fid], as_record(feature->GetGeometryRef()), fid);
        }
        EXPECT_EQ(fid, read->size());
        EXPECT_EQ((*read)[0].part_starts.empty(), false);
    }
}

// Points, deleted records, a missing sibling, or a record cut short: the reader declines (and
// the written output is read back through OGR).
TEST(ShapefileShapes, AnythingElseIsLeftToOgr) {
    const ShapeFile points("points", wkbPoint, {"POINT (1 2)"});
    EXPECT_FALSE(read_shapefile_shapes(points.path()).has_value());

    const ShapeFile deleted("deleted", wkbLineString, {"LINESTRING (0 0,1 1)", "LINESTRING (2 2,3 3)"}, {1});
    EXPECT_FALSE(read_shapefile_shapes(deleted.path()).has_value());

    const ShapeFile no_shx("noshx", wkbLineString, {"LINESTRING (0 0,1 1)"});
    std::filesystem::remove(no_shx.sibling(".shx"));
    EXPECT_FALSE(read_shapefile_shapes(no_shx.path()).has_value());

    const ShapeFile truncated("cut", wkbLineString, {"LINESTRING (0 0,1 1,2 2)"});
    std::filesystem::resize_file(truncated.path(), std::filesystem::file_size(truncated.path()) - 8);
    EXPECT_FALSE(read_shapefile_shapes(truncated.path()).has_value());

    // A part index beyond the points (the record's first part start, at 8 + 44, set to 5).
    const ShapeFile bad_part("badpart", wkbLineString, {"LINESTRING (0 0,1 1,2 2)"});
    {
        std::fstream shp(bad_part.path(), std::ios::in | std::ios::out | std::ios::binary);
        shp.seekp(100 + 8 + 44);
        shp.put(5);
    }
    EXPECT_FALSE(read_shapefile_shapes(bad_part.path()).has_value());
}

// A map read for a Shapefile output decodes a line file's records itself (OGR reads the
// attributes only); a file the decoder declines (here a deleted record) is read again through
// OGR, geometries and all: the same chains either way.
TEST(ShapefileShapes, MapReadFallsBackToOgrWhereTheDecoderDeclines) {
    const std::vector<std::string> lines = {"LINESTRING (0 0,1 1)", "MULTILINESTRING ((2 2,3 3),(4 4,5 5,6 6))", "LINESTRING (7 7,8 8)"};
    for (const bool with_deleted : {false, true}) {
        const ShapeFile file(with_deleted ? "withdeleted" : "plain", wkbLineString, lines,
                             with_deleted ? std::vector<GIntBig>{1} : std::vector<GIntBig>{});
        EXPECT_EQ(read_shapefile_shapes(file.path()).has_value(), !with_deleted);
        map::MapData map;
        const OgrDataset dataset = OgrDataset::read(file.path(), {}, map, true);
        std::vector<std::vector<Point>> chains;
        for (const map::Chain& chain : map.chains) chains.emplace_back(map.vertices.begin() + chain.first, map.vertices.begin() + chain.last + 1);
        std::vector<std::vector<Point>> expected = {{{0, 0}, {1, 1}}, {{2, 2}, {3, 3}}, {{4, 4}, {5, 5}, {6, 6}}, {{7, 7}, {8, 8}}};
        if (with_deleted) expected.erase(expected.begin() + 1, expected.begin() + 3);
        ASSERT_EQ(chains.size(), expected.size()) << with_deleted;
        for (std::size_t c = 0; c < chains.size(); ++c) {
            ASSERT_EQ(chains[c].size(), expected[c].size());
            for (std::size_t i = 0; i < chains[c].size(); ++i) {
                EXPECT_EQ(chains[c][i].x, expected[c][i].x);
                EXPECT_EQ(chains[c][i].y, expected[c][i].y);
            }
        }
    }
}


// Any range of records, read by ShapeReader from its first record on (found through the .shx),
// is those records as the whole file's reading gives them; a range past the records is refused,
// and a record cut short stops the reading (failed()).
TEST(ShapefileShapes, ReaderGivesAnyRangeOfRecords) {
    const std::vector<std::string> lines = {"LINESTRING (0 0,1 1)", "", "MULTILINESTRING ((2 2,3 3),(4 4,5 5,6 6))",
                                            "LINESTRING (7 7,8 8,9 7)", "", "LINESTRING (1e300 -1e-300,5 6)"};
    const ShapeFile file("ranges", wkbLineString, lines);
    const std::optional<ShapeTable> whole = read_shapefile_shapes(file.path());
    ASSERT_TRUE(whole.has_value());
    const std::size_t n = lines.size();
    for (std::size_t first = 0; first <= n; ++first) {
        for (std::size_t end = first; end <= n + 1; ++end) {
            SCOPED_TRACE(std::to_string(first) + " to " + std::to_string(end));
            std::optional<ShapeReader> reader = ShapeReader::open(file.path(), first, end);
            ASSERT_TRUE(reader.has_value());
            EXPECT_EQ(reader->records(), n);
            EXPECT_EQ(reader->shp_size(), std::filesystem::file_size(file.path()));
            std::size_t fid = first;
            while (const ShapeRecord* record = reader->next()) {
                ASSERT_LT(fid, std::min(end, n));
                EXPECT_EQ(reader->fid(), fid);
                const ShapeRecord expected = (*whole)[fid];
                expect_same_record(*record, {std::vector<Point>(expected.xy.begin(), expected.xy.end()), {},
                                             std::vector<std::uint32_t>(expected.part_starts.begin(), expected.part_starts.end())},
                                   fid);
                ++fid;
            }
            EXPECT_EQ(fid, std::min(end, n));
            EXPECT_FALSE(reader->failed());
        }
    }
    EXPECT_FALSE(ShapeReader::open(file.path(), n + 1).has_value());

    const ShapeFile truncated("cutrange", wkbLineString, {"LINESTRING (0 0,1 1)", "LINESTRING (0 0,1 1,2 2)"});
    std::filesystem::resize_file(truncated.path(), std::filesystem::file_size(truncated.path()) - 8);
    std::optional<ShapeReader> reader = ShapeReader::open(truncated.path());
    ASSERT_TRUE(reader.has_value());
    EXPECT_NE(reader->next(), nullptr);
    EXPECT_EQ(reader->next(), nullptr);
    EXPECT_TRUE(reader->failed());
    reader = ShapeReader::open(truncated.path(), 1);
    ASSERT_TRUE(reader.has_value());
    EXPECT_EQ(reader->next(), nullptr);
    EXPECT_TRUE(reader->failed());
}

std::vector<std::vector<Point>> chains_of(const map::MapData& map) {
    std::vector<std::vector<Point>> chains;
    for (const map::Chain& chain : map.chains) chains.emplace_back(map.vertices.begin() + chain.first, map.vertices.begin() + chain.last + 1);
    return chains;
}

// Chains [first, end) of `whole`, with their points.
std::vector<std::vector<Point>> chains_of(const map::MapData& whole, std::uint32_t first, std::uint32_t end) {
    std::vector<std::vector<Point>> chains;
    for (std::uint32_t c = first; c < end; ++c) {
        chains.emplace_back(whole.vertices.begin() + whole.chains[c].first, whole.vertices.begin() + whole.chains[c].last + 1);
    }
    return chains;
}

void expect_same_points(const std::vector<std::vector<Point>>& a, const std::vector<std::vector<Point>>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t c = 0; c < a.size(); ++c) {
        ASSERT_EQ(a[c].size(), b[c].size()) << "chain " << c;
        for (std::size_t i = 0; i < a[c].size(); ++i) EXPECT_EQ(std::memcmp(&a[c][i], &b[c][i], sizeof(Point)), 0) << "chain " << c;
    }
}

// A map read with its vertices left in the file: no vertex, and the chains (and frozen ones) of
// the map read whole.
void expect_same_chains(const map::MapData& planned, const map::MapData& whole) {
    EXPECT_TRUE(planned.vertices.empty());
    ASSERT_EQ(planned.chains.size(), whole.chains.size());
    for (std::size_t c = 0; c < whole.chains.size(); ++c) {
        EXPECT_EQ(planned.chains[c].first, whole.chains[c].first);
        EXPECT_EQ(planned.chains[c].last, whole.chains[c].last);
        EXPECT_EQ(planned.is_frozen(static_cast<std::uint32_t>(c)), whole.is_frozen(static_cast<std::uint32_t>(c)));
    }
}

// Writes the map read whole and the map left in the file (the same `kept`) and expects the same
// bytes; then, the input touched, expects the map left in the file refused with `changed` (the
// start of its message after the path), nothing written.
void expect_written_alike(const std::string& input, const OgrDataset& read_whole, const map::MapData& whole,
                          const OgrDataset& read_planned, const map::MapData& planned, const std::vector<std::uint8_t>& kept,
                          const std::string& changed) {
    const std::filesystem::path out = std::filesystem::path(input).parent_path() / "out";
    std::filesystem::create_directories(out);
    auto write = [&](const OgrDataset& dataset, const map::MapData& map, const std::string& name) {
        WriteOptions options;
        options.path = (out / name).string();
        return dataset.write(options, map, kept);
    };
    const CPLConfigOptionSetter date("OGR_CURRENT_DATE", "2000-01-01T00:00:00Z", false);
    write(read_whole, whole, "whole.shp");
    write(read_planned, planned, "planned.shp");
    for (const char* extension : {".shp", ".shx", ".dbf", ".prj"}) {
        auto bytes = [&](const char* stem) {
            std::ifstream in(out / (std::string(stem) + extension), std::ios::binary);
            return std::string(std::istreambuf_iterator<char>(in), {});
        };
        EXPECT_FALSE(bytes("whole").empty()) << extension;
        EXPECT_EQ(bytes("whole"), bytes("planned")) << extension;
    }
    std::filesystem::last_write_time(input, std::filesystem::last_write_time(input) + std::chrono::seconds(2));
    try {
        write(read_planned, planned, "changed.shp");
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("'" + input + "' changed while toposimp ran: " + changed), std::string::npos)
            << error.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out / "changed.shp"));
}

// A map read with its vertices left in the file: the same chains as the map read whole, no
// vertex held; where they are (each record's first vertex and chain, their extent); any range of
// records read back as the same chains; written, the same bytes as the map read whole. With a
// deleted record, the lines are left in the file through OGR instead.
TEST(ShapefileShapes, MapVerticesLeftInTheFile) {
    const std::vector<std::string> lines = {"LINESTRING (0 0,1 1)", "", "MULTILINESTRING ((2 2,3 3),(4 4,5 5,6 6))",
                                            "LINESTRING (7 7,8 -8,9 7)", "", ""};
    const ShapeFile file("infile", wkbLineString, lines);
    map::MapData whole, planned;
    const OgrDataset read_whole = OgrDataset::read(file.path(), {}, whole, true);
    const OgrDataset read_planned = OgrDataset::read(file.path(), {}, planned, true, true);
    EXPECT_EQ(read_whole.vertices_in_file(), nullptr);
    const VerticesInFile* in_file = read_planned.vertices_in_file();
    ASSERT_NE(in_file, nullptr);
    ASSERT_EQ(in_file->layers.size(), 1u);
    const LayerInFile& file_layer = in_file->layers[0];
    EXPECT_TRUE(planned.vertices.empty());
    ASSERT_EQ(planned.chains.size(), whole.chains.size());
    for (std::size_t c = 0; c < whole.chains.size(); ++c) {
        EXPECT_EQ(planned.chains[c].first, whole.chains[c].first);
        EXPECT_EQ(planned.chains[c].last, whole.chains[c].last);
    }
    EXPECT_EQ(file_layer.path, file.path());
    EXPECT_EQ(file_layer.layer, "infile");
    EXPECT_EQ(in_file->vertices, whole.vertices.size());
    EXPECT_EQ(file_layer.record_vertex, (std::vector<std::uint64_t>{0, 2, 2, 7, 10, 10, 10}));
    EXPECT_EQ(file_layer.record_chain, (std::vector<std::uint32_t>{0, 1, 1, 3, 4, 4, 4}));
    EXPECT_EQ(in_file->extent.min_x, 0);
    EXPECT_EQ(in_file->extent.min_y, -8);
    EXPECT_EQ(in_file->extent.max_x, 9);
    EXPECT_EQ(in_file->extent.max_y, 7);
    EXPECT_EQ(read_planned.summary().features(), read_whole.summary().features());
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::line_features), 3u);
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::empty_geometries), 3u);

    for (std::uint64_t first = 0; first <= lines.size(); ++first) {
        for (std::uint64_t end = first; end <= lines.size(); ++end) {
            SCOPED_TRACE(std::to_string(first) + " to " + std::to_string(end));
            const map::MapData part = read_shapefile_lines(file.path(), "infile", first, end);
            expect_same_points(chains_of(part), chains_of(whole, file_layer.record_chain[first], file_layer.record_chain[end]));
            EXPECT_EQ(part.vertices.size(), file_layer.record_vertex[end] - file_layer.record_vertex[first]);
        }
    }
    EXPECT_THROW((void)read_shapefile_lines(file.path(), "infile", 7, 7), InputError);

    // Written (every other vertex kept), the same bytes; and refused, nothing written, once the
    // file has changed.
    std::vector<std::uint8_t> kept(whole.vertices.size(), 1);
    kept[1] = kept[4] = kept[8] = 0;
    expect_written_alike(file.path(), read_whole, whole, read_planned, planned, kept, "record 0");

    // A deleted record: not what the decoder reads in OGR's order, so the lines are left in the
    // file through OGR, their record numbers kept from the gap on; the same chains, and written
    // alike.
    const ShapeFile deleted("infiledeleted", wkbLineString, lines, {2});
    map::MapData with_deleted, whole_deleted;
    const OgrDataset read_deleted = OgrDataset::read(deleted.path(), {}, with_deleted, true, true);
    const OgrDataset read_deleted_whole = OgrDataset::read(deleted.path(), {}, whole_deleted, true);
    ASSERT_NE(read_deleted.vertices_in_file(), nullptr) << read_deleted.summary().read_whole_because;
    EXPECT_TRUE(with_deleted.vertices.empty());
    EXPECT_EQ(whole_deleted.vertices.size(), 5u);
    expect_same_chains(with_deleted, whole_deleted);
    const LayerInFile& deleted_layer = read_deleted.vertices_in_file()->layers.at(0);
    EXPECT_TRUE(deleted_layer.ogr_lines);
    EXPECT_EQ(deleted_layer.record_fid.at(2), 3);
    const map::MapData part = read_lines(deleted_layer.run(1, deleted_layer.record_fid.size() - 1));
    EXPECT_EQ(part.vertices.size(), whole_deleted.vertices.size() - (whole_deleted.chains[0].last + 1));
    std::vector<std::uint8_t> kept_deleted(whole_deleted.vertices.size(), 1);
    kept_deleted[1] = 0;
    expect_written_alike(deleted.path(), read_deleted_whole, whole_deleted, read_deleted, with_deleted, kept_deleted, "feature 0");
}

// A non-finite vertex: the map left in the file names it as the map read whole does, and so does
// a part of the file read alone.
TEST(ShapefileShapes, NonFiniteVertexLeftInTheFileNamesTheFeature) {
    const ShapeFile file("nonfiniteline", wkbLineString, {"LINESTRING (0 0,1 1)", "LINESTRING (2 2,3 3,4 4)"});
    {
        // The second record's second x: header 100, record 0 of 8 + 80 bytes, then 8 + 48 to
        // its points.
        std::fstream shp(file.path(), std::ios::in | std::ios::out | std::ios::binary);
        shp.seekp(100 + 88 + 8 + 48 + 16);
        const double infinity = std::numeric_limits<double>::infinity();
        shp.write(reinterpret_cast<const char*>(&infinity), 8);
    }
    auto message = [&](bool in_file) {
        map::MapData map;
        try {
            (void)OgrDataset::read(file.path(), {}, map, true, in_file);
        } catch (const InputError& error) {
            return std::string(error.what());
        }
        return std::string("no error");
    };
    const std::string expected = "'" + file.path() + "', layer 'nonfiniteline', feature 1: vertex 1 has a non-finite coordinate (inf, 3.000000)";
    EXPECT_EQ(message(false), expected);
    EXPECT_EQ(message(true), expected);
    try {
        (void)read_shapefile_lines(file.path(), "nonfiniteline", 1, 2);
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_EQ(std::string(error.what()), expected);
    }
}

// Each chain's ends kept and its other vertices but every `nth` (as the engine keeps a chain's ends).
std::vector<std::uint8_t> thinned(const map::MapData& whole, std::uint32_t nth) {
    std::vector<std::uint8_t> kept(whole.vertices.size(), 1);
    for (const map::Chain chain : whole.chains) {
        for (std::uint32_t v = chain.first + 1; v < chain.last; ++v) kept[v] = v % nth != 0;
    }
    return kept;
}

// `map` read by `dataset`, its `kept` vertices written to the GeoPackage `name` in `input`'s
// folder's "out": the file's bytes.
std::string written_geopackage(const std::string& input, const OgrDataset& dataset, const map::MapData& map,
                               const std::vector<std::uint8_t>& kept, const std::string& name) {
    const std::filesystem::path out = std::filesystem::path(input).parent_path() / "out";
    std::filesystem::create_directories(out);
    const CPLConfigOptionSetter date("OGR_CURRENT_DATE", "2000-01-01T00:00:00Z", false);
    WriteOptions options;
    options.path = (out / name).string();
    dataset.write(options, map, kept);
    std::ifstream in(out / name, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// A coverage of squares whose shared borders carry a middle point, some with a hole, then
// multipolygons, NULL geometries and a flat ring (a frozen chain).
std::vector<std::string> grid_polygons() {
    std::vector<std::string> polygons;
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
            const double x = i, y = j;
            std::ostringstream wkt;
            wkt << "POLYGON ((" << x << " " << y << "," << x + 0.5 << " " << y << "," << x + 1 << " " << y << "," << x + 1 << " "
                << y + 0.5 << "," << x + 1 << " " << y + 1 << "," << x + 0.5 << " " << y + 1 << "," << x << " " << y + 1 << ","
                << x << " " << y + 0.5 << "," << x << " " << y << ")";
            if ((i + j) % 3 == 0) {
                wkt << ",(" << x + 0.25 << " " << y + 0.25 << "," << x + 0.25 << " " << y + 0.75 << "," << x + 0.75 << " "
                    << y + 0.75 << "," << x + 0.25 << " " << y + 0.25 << ")";
            }
            wkt << ")";
            polygons.push_back(wkt.str());
        }
        polygons.emplace_back(i % 2 ? "" : "MULTIPOLYGON (((10 10,11 10,11 11,10 10)),((12 12,13 12,12 13,12 12)))");
    }
    polygons.emplace_back("POLYGON ((20 20,21 20,22 20,20 20))");  // flat: a frozen chain
    return polygons;
}

// A polygon layer's rings streamed from the file, as read() gives them to its coverage: a
// coverage planned from them has read()'s chains, and any run of features makes its own chains
// with read()'s vertices (issue 32: polygon coverages read by parts).
TEST(ShapefileShapes, PolygonRingsStreamedPlanTheCoverageRead) {
    const std::vector<std::string> polygons = grid_polygons();
    const ShapeFile file("coverage", wkbPolygon, polygons);
    map::MapData whole;
    OgrDataset::read(file.path(), {}, whole);
    auto rings_of = [&](std::uint64_t first, std::uint64_t end) {
        return [&, first, end](const std::function<void(std::span<const Point>)>& visit) {
            for_each_polygon_ring(file.path(), "coverage", first, end, visit);
        };
    };
    map::MapData planned;
    map::Coverage coverage;
    coverage.plan(rings_of(0, polygons.size()), planned, 56 * 16);
    ASSERT_EQ(planned.chains.size(), whole.chains.size());
    for (std::size_t c = 0; c < whole.chains.size(); ++c) {
        EXPECT_EQ(planned.chains[c].first, whole.chains[c].first);
        EXPECT_EQ(planned.chains[c].last, whole.chains[c].last);
        EXPECT_EQ(planned.is_frozen(static_cast<std::uint32_t>(c)), whole.is_frozen(static_cast<std::uint32_t>(c)));
    }
    EXPECT_GT(coverage.shared_arc_count(), 0u);
    EXPECT_EQ(coverage.degenerate_ring_count(), 1u);
    // The rings before each feature: a feature range is a ring range.
    std::vector<std::uint32_t> ring_before(polygons.size() + 1, 0);
    for (std::size_t f = 0; f < polygons.size(); ++f) {
        std::uint32_t count = 0;
        for_each_polygon_ring(file.path(), "coverage", f, f + 1, [&](std::span<const Point>) { ++count; });
        ring_before[f + 1] = ring_before[f] + count;
    }
    ASSERT_EQ(ring_before.back(), coverage.ring_count());
    for (std::size_t first = 0; first <= polygons.size(); first += 3) {
        for (std::size_t end = first; end <= polygons.size(); end += 5) {
            SCOPED_TRACE(std::to_string(first) + " to " + std::to_string(end));
            const map::CoverageSlice slice = coverage.slice(ring_before[first], ring_before[end]);
            const map::MapData part = map::arcs_of(slice, rings_of(first, end));
            expect_same_points(chains_of(part), chains_of(whole, slice.first_chain, slice.end_chain));
        }
    }
    EXPECT_THROW(for_each_polygon_ring(file.path(), "coverage", 0, polygons.size() + 1, [](std::span<const Point>) {}), InputError);
}

// A polygon layer read with its vertices left in the file: the chains of the map read whole, no
// vertex held, each feature's first ring, chain and vertex; written, the same bytes as the map
// read whole, and refused, nothing written, once the file has changed. A deleted record or a 3D
// ring makes it read whole.
TEST(ShapefileShapes, PolygonLayerLeftInTheFile) {
    const std::vector<std::string> polygons = grid_polygons();
    const ShapeFile file("polygonsinfile", wkbPolygon, polygons);
    map::MapData whole, planned;
    const OgrDataset read_whole = OgrDataset::read(file.path(), {}, whole, true);
    const OgrDataset read_planned = OgrDataset::read(file.path(), {}, planned, true, true);
    const VerticesInFile* in_file = read_planned.vertices_in_file();
    ASSERT_NE(in_file, nullptr);
    ASSERT_EQ(in_file->layers.size(), 1u);
    const LayerInFile& file_layer = in_file->layers[0];
    ASSERT_NE(in_file->coverage, nullptr);
    expect_same_chains(planned, whole);
    EXPECT_EQ(in_file->vertices, whole.vertices.size());
    EXPECT_EQ(file_layer.path, file.path());
    EXPECT_EQ(in_file->extent.min_x, 0);
    EXPECT_EQ(in_file->extent.max_x, 22);
    EXPECT_EQ(in_file->extent.max_y, 20);
    ASSERT_EQ(file_layer.record_ring.size(), polygons.size() + 1);
    EXPECT_EQ(file_layer.record_ring.back(), in_file->coverage->ring_count());
    for (std::size_t f = 0; f < polygons.size(); ++f) {
        std::uint32_t count = 0;
        for_each_polygon_ring(file.path(), "polygonsinfile", f, f + 1, [&](std::span<const Point>) { ++count; });
        EXPECT_EQ(file_layer.record_ring[f + 1] - file_layer.record_ring[f], count) << "feature " << f;
        const map::CoverageSlice slice = in_file->coverage->slice(file_layer.record_ring[f], file_layer.record_ring[f + 1]);
        EXPECT_EQ(file_layer.record_chain[f], slice.first_chain) << "feature " << f;
        EXPECT_EQ(file_layer.record_chain[f + 1], slice.end_chain) << "feature " << f;
        EXPECT_EQ(file_layer.record_vertex[f], slice.first_chain < whole.chains.size() ? whole.chains[slice.first_chain].first : whole.vertices.size());
    }
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::polygon_features), read_whole.summary().sum(&LayerSummary::polygon_features));
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::empty_geometries), 2u);
    EXPECT_EQ(read_planned.summary().arcs, read_whole.summary().arcs);
    EXPECT_EQ(read_planned.summary().shared_arcs, read_whole.summary().shared_arcs);

    // Every third vertex dropped but the arcs' ends (the engine keeps at least those of a ring).
    std::vector<std::uint8_t> kept(whole.vertices.size(), 1);
    for (const map::Chain chain : whole.chains) {
        for (std::uint32_t v = chain.first + 1; v < chain.last; ++v) kept[v] = v % 3 != 0;
    }
    expect_written_alike(file.path(), read_whole, whole, read_planned, planned, kept, "feature 0");

    // Deleted records: left in the file too, its features' FIDs (record numbers) kept from the
    // first gap on; every run read back by its FIDs gives the rings read whole; written alike.
    // (Read by index, a run past the first deleted record is refused.)
    const ShapeFile deleted("polygonsdeleted", wkbPolygon, polygons, {3, 7, 8});
    map::MapData with_deleted, whole_deleted;
    const OgrDataset read_deleted = OgrDataset::read(deleted.path(), {}, with_deleted, true, true);
    const OgrDataset read_deleted_whole = OgrDataset::read(deleted.path(), {}, whole_deleted, true);
    ASSERT_NE(read_deleted.vertices_in_file(), nullptr) << read_deleted.summary().read_whole_because;
    expect_same_chains(with_deleted, whole_deleted);
    const LayerInFile& deleted_layer = read_deleted.vertices_in_file()->layers.at(0);
    ASSERT_EQ(deleted_layer.record_fid.size(), polygons.size() - 3 + 1);
    EXPECT_EQ(deleted_layer.record_fid[3], 4);
    EXPECT_EQ(deleted_layer.record_fid[6], 9);
    const std::size_t features = deleted_layer.record_fid.size() - 1;
    for (std::size_t first = 0; first <= features; ++first) {
        for (std::size_t end = first; end <= features; ++end) {
            std::uint32_t count = 0;
            for_each_polygon_ring(deleted_layer.run(first, end), [&](std::span<const Point>) { ++count; });
            EXPECT_EQ(count, deleted_layer.record_ring[end] - deleted_layer.record_ring[first]) << first << " to " << end;
        }
    }
    FeatureRun longer = deleted_layer.run(0, 3);  // (a run claiming the record after a gap)
    ++longer.end;
    EXPECT_THROW(for_each_polygon_ring(longer, [](std::span<const Point>) {}), InputError);
    std::vector<std::uint8_t> kept_deleted(whole_deleted.vertices.size(), 1);
    for (const map::Chain chain : whole_deleted.chains) {
        for (std::uint32_t v = chain.first + 1; v < chain.last; ++v) kept_deleted[v] = v % 3 != 0;
    }
    expect_written_alike(deleted.path(), read_deleted_whole, whole_deleted, read_deleted, with_deleted, kept_deleted, "feature 0");
    EXPECT_THROW(for_each_polygon_ring(deleted.path(), "polygonsdeleted", 0, 5, [](std::span<const Point>) {}), InputError);
}

// Polygons that share a border where one has -0.0 and the other 0.0 (one location): left in the
// file, each ring written from its own points still gets the bits of the shared arc's vertices
// (those of the ring that made it), as the layer read whole writes them.
TEST(ShapefileShapes, PolygonLayerLeftInTheFileKeepsTheArcsZeros) {
    const std::vector<std::string> polygons = {
        "POLYGON ((-0 -0,-0 1,-0 2,1 2,1 -0,-0 -0))",      // makes the x = 0 border with -0.0
        "POLYGON ((0 0,-1 0,-1 2,0 2,0 1,0 0))",           // uses it with 0.0
        "POLYGON ((1 -0,1 2,2 2,2 0,1 -0))",                // makes x = 1 with y -0.0 at its foot
        "POLYGON ((3 0,3 1,4 1,4 0,3 0),(3.25 0.25,3.75 0.25,3.75 0.75,3.25 0.25))"};
    const ShapeFile file("polygonszeros", wkbPolygon, polygons);
    map::MapData whole, planned;
    const OgrDataset read_whole = OgrDataset::read(file.path(), {}, whole, true);
    const OgrDataset read_planned = OgrDataset::read(file.path(), {}, planned, true, true);
    ASSERT_NE(read_planned.vertices_in_file(), nullptr);
    ASSERT_EQ(planned.chains.size(), whole.chains.size());
    const std::vector<std::uint8_t> kept(whole.vertices.size(), 1);
    expect_written_alike(file.path(), read_whole, whole, read_planned, planned, kept, "feature 0");
}

// A GeoPackage of `layers` (name, geometry type, WKTs: "" a NULL geometry), features with FIDs from
// 1, then the FIDs in `deleted` (per layer) deleted; or a FlatGeobuf of one layer (FIDs from 0,
// with its index of features unless `options` say SPATIAL_INDEX=NO).
class GeoPackage {
public:
    struct Layer {
        std::string name;
        OGRwkbGeometryType type;
        std::vector<std::string> wkts;
        std::vector<GIntBig> deleted;
    };

    GeoPackage(const std::string& name, const std::vector<Layer>& layers, const char* driver = "GPKG", const char* extension = ".gpkg",
               std::vector<const char*> options = {}) {
        const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
        directory_ = testing::temp_path("gpkg-" + std::string(test->test_suite_name()) + "-" + test->name() + "-" + name);
        std::filesystem::remove_all(directory_);
        std::filesystem::create_directories(directory_);
        path_ = (directory_ / (name + extension)).string();
        register_drivers();
        // (Quiet: the driver warns once a layer about a MultiLineString in a LineString layer.)
        CPLPushErrorHandler(CPLQuietErrorHandler);
        GDALDataset* dataset = GetGDALDriverManager()->GetDriverByName(driver)->Create(path_.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
        OGRSpatialReference wgs84;
        wgs84.importFromEPSG(4326);
        for (const Layer& given : layers) {
            options.push_back(nullptr);
            OGRLayer* layer = dataset->CreateLayer(given.name.c_str(), &wgs84, given.type, const_cast<char**>(options.data()));
            options.pop_back();
            add_features(*layer, given.wkts, given.deleted);
        }
        GDALClose(dataset);
        CPLPopErrorHandler();
    }
    ~GeoPackage() { std::filesystem::remove_all(directory_); }

    const std::string& path() const { return path_; }

private:
    std::filesystem::path directory_;
    std::string path_;
};

// Lines and polygon layers of a GeoPackage, FIDs with gaps: left in the file, the same chains as
// the map read whole, no vertex held; each feature's FID kept; any run of features read back by
// its FIDs as the same chains (lines) or rings (polygons); written to a GeoPackage, the same bytes
// as the map read whole, and refused, nothing written, once the file has changed.
TEST(GeoPackageLayers, LeftInTheFile) {
    const std::vector<std::string> lines = {"LINESTRING (0 0,1 1)", "", "MULTILINESTRING ((2 2,3 3),EMPTY,(4 4,5 5,6 6))",
                                            "LINESTRING (7 7,8 -8,9 7)", "LINESTRING EMPTY", "LINESTRING (1 -1,2 -2)"};
    const GeoPackage file("layers", {{"lines", wkbLineString, lines, {2, 5}}, {"cells", wkbPolygon, grid_polygons(), {1, 7}}});
    map::MapData whole, planned;
    const OgrDataset read_whole = OgrDataset::read(file.path(), {}, whole);
    const OgrDataset read_planned = OgrDataset::read(file.path(), {}, planned, false, true);
    EXPECT_EQ(read_whole.vertices_in_file(), nullptr);
    const VerticesInFile* in_file = read_planned.vertices_in_file();
    ASSERT_NE(in_file, nullptr);
    ASSERT_EQ(in_file->layers.size(), 2u);
    ASSERT_NE(in_file->coverage, nullptr);
    expect_same_chains(planned, whole);
    EXPECT_EQ(in_file->vertices, whole.vertices.size());
    EXPECT_EQ(read_planned.summary().features(), read_whole.summary().features());
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::line_features), read_whole.summary().sum(&LayerSummary::line_features));
    EXPECT_EQ(read_planned.summary().sum(&LayerSummary::empty_geometries), read_whole.summary().sum(&LayerSummary::empty_geometries));
    EXPECT_EQ(read_planned.summary().arcs, read_whole.summary().arcs);

    const LayerInFile& line_layer = in_file->layers[0];
    EXPECT_TRUE(line_layer.ogr_lines);
    EXPECT_FALSE(line_layer.polygons);
    EXPECT_EQ(line_layer.path, std::filesystem::absolute(file.path()).string());
    EXPECT_EQ(line_layer.record_fid, (std::vector<std::int64_t>{1, 3, 4, 6, 7}));
    EXPECT_EQ(line_layer.record_vertex, (std::vector<std::uint64_t>{0, 2, 7, 10, 12}));
    EXPECT_EQ(line_layer.record_chain, (std::vector<std::uint32_t>{0, 1, 3, 4, 5}));
    const std::size_t features = line_layer.record_fid.size() - 1;
    for (std::uint64_t first = 0; first <= features; ++first) {
        for (std::uint64_t end = first; end <= features; ++end) {
            SCOPED_TRACE(std::to_string(first) + " to " + std::to_string(end));
            const map::MapData part = read_lines(line_layer.run(first, end));
            expect_same_points(chains_of(part), chains_of(whole, line_layer.record_chain[first], line_layer.record_chain[end]));
        }
    }
    // A run that is not the file's: one more feature than its FIDs hold, or one fewer.
    FeatureRun longer = line_layer.run(0, 2);
    ++longer.end;
    EXPECT_THROW((void)read_lines(longer), InputError);
    FeatureRun shorter = line_layer.run(0, 2);
    --shorter.end;
    EXPECT_THROW((void)read_lines(shorter), InputError);

    const LayerInFile& cells = in_file->layers[1];
    EXPECT_TRUE(cells.polygons);
    ASSERT_EQ(cells.record_fid.size(), grid_polygons().size() - 1);
    EXPECT_EQ(cells.record_fid[0], 2);
    EXPECT_EQ(cells.record_fid[5], 8);
    for (std::size_t f = 0; f + 1 < cells.record_ring.size(); ++f) {
        std::uint32_t count = 0;
        for_each_polygon_ring(cells.run(f, f + 1), [&](std::span<const Point>) { ++count; });
        EXPECT_EQ(cells.record_ring[f + 1] - cells.record_ring[f], count) << "feature " << f;
    }

    // Written (some vertices dropped, but the ends of chains), the same bytes; refused once the
    // file has changed.
    const std::vector<std::uint8_t> kept = thinned(whole, 3);
    const std::string written = written_geopackage(file.path(), read_whole, whole, kept, "whole.gpkg");
    EXPECT_FALSE(written.empty());
    EXPECT_EQ(written_geopackage(file.path(), read_planned, planned, kept, "planned.gpkg"), written);
    std::filesystem::last_write_time(file.path(), std::filesystem::last_write_time(file.path()) + std::chrono::seconds(2));
    try {
        written_geopackage(file.path(), read_planned, planned, kept, "changed.gpkg");
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("changed while toposimp ran: feature 0"), std::string::npos) << error.what();
    }
    EXPECT_FALSE(std::filesystem::exists(std::filesystem::path(file.path()).parent_path() / "out" / "changed.gpkg"));
}

// The map read whole and the map left in its file written alike (`kept`): a Shapefile's files the
// same bytes, then refused once the input changed (expect_written_alike; returns nullptr); a
// GeoPackage the same bytes (returns the first feature of `layer` written from the file).
OGRFeatureUniquePtr written_alike(const std::string& path, bool is_shp, const OgrDataset& read_whole, const map::MapData& whole,
                                  const OgrDataset& read_planned, const map::MapData& planned, const std::vector<std::uint8_t>& kept,
                                  const char* layer) {
    if (is_shp) {
        expect_written_alike(path, read_whole, whole, read_planned, planned, kept, "feature 0");
        return nullptr;
    }
    const std::string written = written_geopackage(path, read_whole, whole, kept, "whole.gpkg");
    EXPECT_EQ(written_geopackage(path, read_planned, planned, kept, "planned.gpkg"), written);
    const DatasetPtr check = open_vector((std::filesystem::path(path).parent_path() / "out" / "planned.gpkg").string());
    return OGRFeatureUniquePtr(pick_layer(*check, "planned", layer).GetNextFeature());
}

// The polygons given as WKT with a Z and an M for each point: z_of(feature, x, y), m_of(...).
std::vector<std::string> with_zm(const std::vector<std::string>& wkts, bool z, bool m,
                                 const std::function<double(std::size_t, double, double)>& z_of,
                                 const std::function<double(std::size_t, double, double)>& m_of) {
    std::vector<std::string> out;
    for (std::size_t f = 0; f < wkts.size(); ++f) {
        if (wkts[f].empty()) {
            out.emplace_back();
            continue;
        }
        OGRGeometry* geometry = nullptr;
        EXPECT_EQ(OGRGeometryFactory::createFromWkt(wkts[f].c_str(), nullptr, &geometry), OGRERR_NONE);
        std::vector<OGRPolygon*> polygons;
        if (wkbFlatten(geometry->getGeometryType()) == wkbPolygon) {
            polygons.push_back(geometry->toPolygon());
        } else {
            for (OGRPolygon* polygon : *geometry->toMultiPolygon()) polygons.push_back(polygon);
        }
        if (z) geometry->set3D(TRUE);
        if (m) geometry->setMeasured(TRUE);
        for (OGRPolygon* polygon : polygons) {
            for (OGRLinearRing* ring : *polygon) {
                for (int i = 0; i < ring->getNumPoints(); ++i) {
                    if (z) ring->setZ(i, z_of(f, ring->getX(i), ring->getY(i)));
                    if (m) ring->setM(i, m_of(f, ring->getX(i), ring->getY(i)));
                }
            }
        }
        OGRWktOptions iso;  // (with its M: not OGC's old WKT)
        iso.variant = wkbVariantIso;
        out.push_back(geometry->exportToWkt(iso));
        OGRGeometryFactory::destroyGeometry(geometry);
    }
    return out;
}

// Polygons with Z, M or both (GeoPackages, PolygonZ Shapefiles), each ring's Z and M a function
// of the location (the same on every ring sharing it) or of the feature (each cell at its own
// height or measure: rings at a shared location differ, and its vertex has those of the ring
// that made the border): left in their files, the same chains as read whole, written the same
// bytes (each ring's Z and M read again with it, the arc vertices' noted where rings differ),
// refused once the file has changed.
TEST(GeoPackageLayers, PolygonsWithZAndMLeftInTheFile) {
    using Value = std::function<double(std::size_t, double, double)>;
    const Value height = [](std::size_t, double x, double y) { return 10 * x + y + 0.125; };
    const Value measure = [](std::size_t, double x, double y) { return x - 2 * y; };
    const Value own = [](std::size_t f, double, double) { return static_cast<double>(f); };
    struct Case {
        std::string name;
        OGRwkbGeometryType type;
        Value z, m;
        bool shapefile = false;
    };
    const std::vector<Case> cases = {
        {"zm", wkbPolygonZM, height, measure},     {"z", wkbMultiPolygon25D, height, nullptr}, {"m", wkbPolygonM, nullptr, measure},
        {"own_z", wkbPolygon25D, own, nullptr},    {"own_m", wkbPolygonZM, height, own},       {"cellz", wkbPolygon25D, height, nullptr, true},
        {"own_cellz", wkbPolygon25D, own, nullptr, true},
    };
    for (const Case& given : cases) {
        SCOPED_TRACE(given.name);
        const std::vector<std::string> wkts = with_zm(grid_polygons(), given.z != nullptr, given.m != nullptr, given.z ? given.z : own,
                                                      given.m ? given.m : own);
        std::optional<GeoPackage> gpkg;
        std::optional<ShapeFile> shp;
        if (given.shapefile) {
            shp.emplace(given.name, given.type, wkts);
        } else {
            gpkg.emplace(given.name, std::vector<GeoPackage::Layer>{{"cells", given.type, wkts, given.name == "zm" ? std::vector<GIntBig>{3} : std::vector<GIntBig>{}}});
        }
        const std::string path = given.shapefile ? shp->path() : gpkg->path();
        map::MapData whole, planned;
        const OgrDataset read_whole = OgrDataset::read(path, {}, whole, given.shapefile);
        const OgrDataset read_planned = OgrDataset::read(path, {}, planned, given.shapefile, true);
        const VerticesInFile* in_file = read_planned.vertices_in_file();
        ASSERT_NE(in_file, nullptr) << read_planned.summary().read_whole_because;
        EXPECT_TRUE(planned.vertices.empty());
        expect_same_chains(planned, whole);
        EXPECT_TRUE(in_file->layers[0].polygons);
        EXPECT_EQ(read_planned.summary().layers[0].has_z, read_whole.summary().layers[0].has_z);
        EXPECT_EQ(read_planned.summary().layers[0].has_m, read_whole.summary().layers[0].has_m);
        EXPECT_GT(read_whole.summary().shared_arcs, 0u);
        EXPECT_EQ(read_planned.summary().read_whole_because, "");

        const std::vector<std::uint8_t> kept = thinned(whole, 3);
        const OGRFeatureUniquePtr first = written_alike(path, given.shapefile, read_whole, whole, read_planned, planned, kept, "cells");
        if (given.shapefile) continue;
        // (The Z and M are there.)
        ASSERT_TRUE(first && first->GetGeometryRef());
        const OGRGeometry* geometry = first->GetGeometryRef();
        const OGRLinearRing* ring = wkbFlatten(geometry->getGeometryType()) == wkbPolygon
                                        ? geometry->toPolygon()->getExteriorRing()
                                        : geometry->toMultiPolygon()->getGeometryRef(0)->getExteriorRing();
        ASSERT_GT(ring->getNumPoints(), 2);
        const double x = ring->getX(1), y = ring->getY(1);
        if (given.z) {
            EXPECT_EQ(ring->getZ(1), given.z(0, x, y));
        }
        if (given.m) {
            EXPECT_EQ(ring->getM(1), given.m(0, x, y));
        }
        std::filesystem::last_write_time(path, std::filesystem::last_write_time(path) + std::chrono::seconds(2));
        EXPECT_THROW(written_geopackage(path, read_planned, planned, kept, "changed.gpkg"), InputError);
    }
}

// Lines with Z or M (a GeoPackage's with Z and M, a PolyLineZ Shapefile) beside 2D polygons: left
// in their files, the map holds no Z or M either; written, the same bytes as read whole (the Z
// and M of the kept vertices read again from the features), and refused once the file changed.
TEST(GeoPackageLayers, LinesWithZAndMLeftInTheFile) {
    const std::vector<std::string> lines = {"LINESTRING ZM (0 0 1 2,0.5 0.5 3 4,1 1 5 6)", "",
                                            "MULTILINESTRING ZM ((2 2 0 0,3 3 -1 -2),EMPTY,(4 4 7 7,5 5 8 8,6 6 9 9))"};
    const GeoPackage gpkg("zm", {{"lines", wkbLineStringZM, lines, {}}, {"cells", wkbPolygon, grid_polygons(), {}}});
    const ShapeFile shp("linez", wkbLineString25D, {"LINESTRING Z (0 0 1,0.5 0.5 3,1 1 5)", "MULTILINESTRING Z ((2 2 0,3 3 -1),(4 4 7,5 5 8,6 6 9))"});
    for (const std::string& path : {gpkg.path(), shp.path()}) {
        SCOPED_TRACE(path);
        const bool is_shp = path == shp.path();
        map::MapData whole, planned;
        const OgrDataset read_whole = OgrDataset::read(path, {}, whole, is_shp);
        const OgrDataset read_planned = OgrDataset::read(path, {}, planned, is_shp, true);
        const VerticesInFile* in_file = read_planned.vertices_in_file();
        ASSERT_NE(in_file, nullptr);
        expect_same_chains(planned, whole);
        EXPECT_TRUE(in_file->layers[0].ogr_lines);
        EXPECT_EQ(read_planned.summary().layers[0].has_z, read_whole.summary().layers[0].has_z);
        EXPECT_EQ(read_planned.summary().layers[0].has_m, read_whole.summary().layers[0].has_m);
        const map::MapData part = read_lines(in_file->layers[0].run(1, in_file->layers[0].record_vertex.size() - 1));
        EXPECT_EQ(part.vertices.size(), 5u);

        const std::vector<std::uint8_t> kept = thinned(whole, 2);
        const OGRFeatureUniquePtr first = written_alike(path, is_shp, read_whole, whole, read_planned, planned, kept, "lines");
        if (is_shp) continue;
        // (The Z and M are there: the first feature's last kept vertex.)
        ASSERT_TRUE(first && first->GetGeometryRef());
        const OGRLineString* line = first->GetGeometryRef()->toLineString();
        ASSERT_EQ(line->getNumPoints(), 3);
        EXPECT_EQ(line->getZ(2), 5);
        EXPECT_EQ(line->getM(2), 6);
    }
}

// A FlatGeobuf of lines and one of polygons (one layer each, FIDs from 0): left in their files,
// each read by FID where a run does not begin at the first feature; the same chains, runs and
// written bytes as read whole. Without its index of features, a FlatGeobuf is read whole.
TEST(GeoPackageLayers, FlatGeobufLeftInTheFile) {
    const std::vector<std::string> lines = {"LINESTRING (0 0,1 1)", "", "MULTILINESTRING ((2 2,3 3),EMPTY,(4 4,5 5,6 6))",
                                            "LINESTRING (7 7,8 -8,9 7)", "LINESTRING (1 -1,2 -2)"};
    const GeoPackage line_file("lines", {{"lines", wkbMultiLineString, lines, {}}}, "FlatGeobuf", ".fgb");
    const GeoPackage cell_file("cells", {{"cells", wkbMultiPolygon, grid_polygons(), {}}}, "FlatGeobuf", ".fgb");
    for (const GeoPackage* file : {&line_file, &cell_file}) {
        SCOPED_TRACE(file->path());
        map::MapData whole, planned;
        const OgrDataset read_whole = OgrDataset::read(file->path(), {}, whole);
        const OgrDataset read_planned = OgrDataset::read(file->path(), {}, planned, false, true);
        const VerticesInFile* in_file = read_planned.vertices_in_file();
        ASSERT_NE(in_file, nullptr);
        ASSERT_EQ(in_file->layers.size(), 1u);
        expect_same_chains(planned, whole);
        const LayerInFile& layer = in_file->layers[0];
        EXPECT_TRUE(layer.each_by_fid);
        EXPECT_TRUE(layer.record_fid.empty());
        EXPECT_EQ(layer.polygons, file == &cell_file);
        const std::size_t features = layer.record_vertex.size() - 1;
        for (std::uint64_t first = 0; first <= features; ++first) {
            for (std::uint64_t end = first; end <= features; ++end) {
                SCOPED_TRACE(std::to_string(first) + " to " + std::to_string(end));
                if (layer.polygons) {
                    std::uint32_t count = 0;
                    for_each_polygon_ring(layer.run(first, end), [&](std::span<const Point>) { ++count; });
                    EXPECT_EQ(count, layer.record_ring[end] - layer.record_ring[first]);
                    continue;
                }
                const map::MapData part = read_lines(layer.run(first, end));
                expect_same_points(chains_of(part), chains_of(whole, layer.record_chain[first], layer.record_chain[end]));
            }
        }
        FeatureRun beyond = layer.run(1, features);
        ++beyond.end;
        EXPECT_THROW(for_each_polygon_ring(beyond, [](std::span<const Point>) {}), InputError);

        const std::vector<std::uint8_t> kept = thinned(whole, 3);
        const std::string written = written_geopackage(file->path(), read_whole, whole, kept, "whole.gpkg");
        EXPECT_FALSE(written.empty());
        EXPECT_EQ(written_geopackage(file->path(), read_planned, planned, kept, "planned.gpkg"), written);
    }

    const GeoPackage no_index("noindex", {{"lines", wkbMultiLineString, lines, {}}}, "FlatGeobuf", ".fgb", {"SPATIAL_INDEX=NO"});
    map::MapData read;
    const OgrDataset read_no_index = OgrDataset::read(no_index.path(), {}, read, false, true);
    EXPECT_EQ(read_no_index.vertices_in_file(), nullptr);
    EXPECT_FALSE(read.vertices.empty());
    EXPECT_EQ(read_no_index.summary().read_whole_because, "'" + no_index.path() + "', layer 'lines': a FlatGeobuf without its index of features");
}

std::string file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// A 2D polygon Shapefile going to a Shapefile is decoded here, its polygons put together as OGR's
// driver does (organizePolygons, ONLY_CCW) and its .prj carried unparsed: the same map and, thinned
// and written, the same .shp, .shx and .dbf as the layer read through OGR. Holes, multipolygons,
// an island in a lake, a hole touching its shell, NULL and flat polygons.
TEST(ShapefileShapes, PolygonsDecodedHereAreOgrsPolygons) {
    std::vector<std::string> polygons = grid_polygons();
    polygons.emplace_back("MULTIPOLYGON (((30 30,40 30,40 40,30 40,30 30),(32 32,32 38,38 38,38 32,32 32)),"
                          "((34 34,36 34,36 36,34 36,34 34)))");  // an island in a lake
    polygons.emplace_back("POLYGON ((50 50,60 50,60 60,50 60,50 50),(50 50,52 55,55 52,50 50),(56 56,58 56,58 58,56 56))");
    polygons.emplace_back("MULTIPOLYGON (((70 70,71 70,71 71,70 70)),((72 70,74 70,74 72,72 72,72 70),(72.5 70.5,72.5 71.5,73.5 71.5,72.5 70.5)))");
    const ShapeFile file("parcels", wkbPolygon, polygons);
    map::MapData here, through_ogr;
    const OgrDataset decoded = OgrDataset::read(file.path(), {}, here, /*prj_as_file=*/true);
    const OgrDataset read_by_ogr = OgrDataset::read(file.path(), {}, through_ogr, /*prj_as_file=*/false);
    ASSERT_EQ(here.vertices.size(), through_ogr.vertices.size());
    EXPECT_EQ(std::memcmp(here.vertices.data(), through_ogr.vertices.data(), here.vertices.size() * sizeof(Point)), 0);
    ASSERT_EQ(here.chains.size(), through_ogr.chains.size());
    for (std::size_t c = 0; c < here.chains.size(); ++c) {
        EXPECT_EQ(here.chains[c].first, through_ogr.chains[c].first);
        EXPECT_EQ(here.chains[c].last, through_ogr.chains[c].last);
    }
    EXPECT_EQ(decoded.summary().sum(&LayerSummary::polygon_features), read_by_ogr.summary().sum(&LayerSummary::polygon_features));
    EXPECT_EQ(decoded.summary().degenerate_rings, read_by_ogr.summary().degenerate_rings);
    EXPECT_TRUE(decoded.geographic(0));
    const std::filesystem::path out = std::filesystem::path(file.path()).parent_path() / "out";
    std::filesystem::create_directories(out);
    const CPLConfigOptionSetter date("OGR_CURRENT_DATE", "2000-01-01T00:00:00Z", false);
    const std::vector<std::uint8_t> kept = thinned(here, 2);
    // (A Shapefile's writer finds outer rings and holes itself: the polygons' make-up shows in WKB.)
    EXPECT_EQ(decoded.to_memory(here, kept).layers.at(0).wkb, read_by_ogr.to_memory(through_ogr, kept).layers.at(0).wkb);
    for (const auto& [dataset, map, name] : {std::tuple{&decoded, &here, "here.shp"}, std::tuple{&read_by_ogr, &through_ogr, "ogr.shp"}}) {
        WriteOptions options;
        options.path = (out / name).string();
        dataset->write(options, *map, kept);
    }
    for (const char* extension : {".shp", ".shx", ".dbf"}) {
        const std::string expected = file_bytes(out / (std::string("ogr") + extension));
        EXPECT_FALSE(expected.empty()) << extension;
        EXPECT_EQ(file_bytes(out / (std::string("here") + extension)), expected) << extension;
    }
}

// A line Shapefile going to another format: its shapes decoded here, not through OGR, and its
// CRS parsed for the output: the GeoPackage written holds the input's CRS and every line as OGR
// reads it from the input.
TEST(ShapefileShapes, LinesGoingElsewhereKeepTheirCrs) {
    const ShapeFile input("rivers", wkbLineString,
                          {"LINESTRING (0 0,1 1,2 0)", "", "MULTILINESTRING ((10 10,11 12),(20 20,21 22,22 20))"});
    map::MapData map;
    const OgrDataset dataset = OgrDataset::read(input.path(), {}, map, /*prj_as_file=*/false);
    const std::filesystem::path out = std::filesystem::path(input.path()).parent_path() / "rivers.gpkg";
    WriteOptions options;
    options.path = out.string();
    dataset.write(options, map, std::vector<std::uint8_t>(map.vertices.size(), 1));
    DatasetPtr written = open_vector(out.string());
    DatasetPtr original = open_vector(input.path());
    OGRLayer* layer = written->GetLayer(0);
    OGRLayer* source = original->GetLayer(0);
    ASSERT_NE(layer->GetSpatialRef(), nullptr);
    EXPECT_TRUE(layer->GetSpatialRef()->IsSame(source->GetSpatialRef()));
    EXPECT_TRUE(layer->GetSpatialRef()->IsGeographic());
    std::size_t count = 0;
    for (OGRFeatureUniquePtr feature{source->GetNextFeature()}; feature; feature.reset(source->GetNextFeature()), ++count) {
        OGRFeatureUniquePtr copy{layer->GetNextFeature()};
        ASSERT_TRUE(copy);
        const OGRGeometry* expected = feature->GetGeometryRef();
        const OGRGeometry* actual = copy->GetGeometryRef();
        ASSERT_EQ(expected == nullptr, actual == nullptr) << count;
        if (expected != nullptr) {
            EXPECT_TRUE(expected->Equals(actual)) << count;
        }
    }
    EXPECT_EQ(count, 3u);
}

// PolyLineWriter's .shp and .shx are byte for byte what OGR's Shapefile driver writes for the
// same lines: NULL and empty geometries (null shapes), several parts with an empty one (left
// out), a first record without a shape (the file's box then starts at 0), −0 beside 0 in the
// boxes either way round, huge, tiny and subnormal values, a one-point line, one record.
TEST(ShapefileWriter, PolyLinesAreWhatOgrWrites) {
    const std::string tiny = kTiny, odd = kOdd;
    const std::vector<LayerCase> cases = {
        {"null_first", wkbLineString, {"", "LINESTRING (5 6,7 8)", "LINESTRING EMPTY", "MULTILINESTRING ((1 2,3 4),EMPTY,(9 9,10 10))"}},
        {"zeros", wkbLineString, {"LINESTRING (-0 -0,0 0)", "LINESTRING (0 -0,-0 0,-0 -0)", "LINESTRING (5 6,7 8)"}},
        {"negative_zero_last", wkbLineString, {"LINESTRING (0 0,-0 -0)", "LINESTRING (-0 0,-1 -1,0 -0)"}},
        {"extremes", wkbMultiLineString,
         {"MULTILINESTRING ((1e300 -1e-300,-1e300 1e-300,2 " + tiny + "),(0.1 " + odd + ",-3 -3))", "LINESTRING (1 1,2 2)"}},
        {"one_point", wkbLineString, {"LINESTRING (3 3)", "LINESTRING (4 4,5 5)"}},
        {"all_null", wkbLineString, {"", "LINESTRING EMPTY"}},
        {"one", wkbLineString, {"LINESTRING (-5 -6,7 8,1 2)"}},
    };
    for (const LayerCase& c : cases) {
        SCOPED_TRACE(c.name);
        const ShapeFile ogr(c.name, c.type, c.wkts);
        const std::filesystem::path mine = ogr.sibling(".shp").parent_path() / "mine.shp";
        PolyLineWriter writer(mine.string(), mine.string());
        for (const std::string& wkt : c.wkts) {
            std::vector<std::uint32_t> part_starts;
            std::vector<Point> xy;
            if (!wkt.empty()) {
                OGRGeometry* geometry = nullptr;
                ASSERT_EQ(OGRGeometryFactory::createFromWkt(wkt.c_str(), nullptr, &geometry), OGRERR_NONE);
                std::unique_ptr<OGRGeometry> owned(geometry);
                std::vector<const OGRLineString*> parts;
                if (wkbFlatten(geometry->getGeometryType()) == wkbLineString) {
                    parts.push_back(geometry->toLineString());
                } else {
                    for (const OGRLineString* part : *geometry->toMultiLineString()) parts.push_back(part);
                }
                for (const OGRLineString* part : parts) {
                    if (part->IsEmpty()) continue;
                    part_starts.push_back(static_cast<std::uint32_t>(xy.size()));
                    for (int i = 0; i < part->getNumPoints(); ++i) xy.push_back({part->getX(i), part->getY(i)});
                }
            }
            EXPECT_TRUE(writer.add(part_starts, xy));
        }
        writer.finish();
        for (const char* extension : {".shp", ".shx"}) {
            const std::string expected = file_bytes(ogr.sibling(extension));
            EXPECT_GT(expected.size(), 100u) << extension;
            EXPECT_EQ(file_bytes(std::filesystem::path(mine).replace_extension(extension)), expected) << extension;
        }
    }
}

// PolyLineWriter cannot create its files: OutputError naming the output.
TEST(ShapefileWriter, UnwritableFolderIsAnOutputError) {
    try {
        PolyLineWriter writer("/nonexistent-folder/out.shp", "out.shp");
        FAIL() << "no error";
    } catch (const OutputError& error) {
        EXPECT_NE(std::string(error.what()).find("cannot write 'out.shp'"), std::string::npos) << error.what();
    }
}

// A line layer written to a Shapefile (its shapes by PolyLineWriter, its attributes and CRS by
// OGR as a layer without geometry) gives the files written wholly through OGR, byte for byte:
// every vertex kept or a thinned map, NULL, empty and multi-part features, the input's .prj
// carried as a file or its CRS written by OGR.
TEST(ShapefileWriter, LineLayerOutputIsOgrsOutput) {
    const ShapeFile input("roads", wkbLineString,
                          {"LINESTRING (0 0,1 1,2 0,3 1,4 0)", "", "MULTILINESTRING ((10 10,11 12,12 10,13 12),(20 20,21 22,22 20))",
                           "LINESTRING EMPTY", "LINESTRING (-0 -0,0.5 0.25,1 -0)"});
    const std::filesystem::path out = std::filesystem::path(input.path()).parent_path() / "out";
    std::filesystem::create_directories(out);
    const CPLConfigOptionSetter date("OGR_CURRENT_DATE", "2000-01-01T00:00:00Z", false);
    for (const bool prj_as_file : {true, false}) {
        map::MapData map;
        const OgrDataset dataset = OgrDataset::read(input.path(), {}, map, prj_as_file);
        for (const std::uint32_t nth : {1000u, 2u}) {
            SCOPED_TRACE(std::to_string(nth) + (prj_as_file ? " .prj as a file" : " CRS through OGR"));
            const std::vector<std::uint8_t> kept = thinned(map, nth);
            auto write = [&](const std::string& name, bool through_ogr) {
                WriteOptions options;
                options.path = (out / name).string();
                options.overwrite = true;
                options.shapes_through_ogr = through_ogr;
                EXPECT_TRUE(dataset.write(options, map, kept).empty());
            };
            write("here.shp", false);
            write("ogr.shp", true);
            for (const char* extension : {".shp", ".shx", ".dbf", ".prj"}) {
                const std::string expected = file_bytes(out / (std::string("ogr") + extension));
                EXPECT_FALSE(expected.empty()) << extension;
                EXPECT_EQ(file_bytes(out / (std::string("here") + extension)), expected) << extension;
            }
            EXPECT_EQ(std::filesystem::exists(out / "here.cpg"), std::filesystem::exists(out / "ogr.cpg"));
        }
    }
}

// A Shapefile output too big to be written in memory first goes straight to its staging folder:
// the same bytes as written in memory (a coverage of polygons with a hole and a multipolygon,
// and lines, each thinned, with their attributes and CRS).
TEST(ShapefileWriter, StraightToDiskIsTheSameBytes) {
    const ShapeFile polygons("cells", wkbPolygon,
                             {"POLYGON ((0 0,0 4,1 5,2 4,4 4,4 0,3 -1,2 0,0 0),(1 1,2 1,2 2,1 2,1 1))",
                              "MULTIPOLYGON (((4 0,4 4,6 4,6 0,5 -1,4 0)),((10 10,10 11,11 11,11 10,10 10)))", "",
                              "POLYGON ((6 0,6 4,7 5,8 4,8 0,6 0))"});
    const ShapeFile lines("roads", wkbLineString,
                          {"LINESTRING (0 0,1 1,2 0,3 1,4 0)", "MULTILINESTRING ((10 10,11 12,12 10,13 12),(20 20,21 22,22 20))"});
    const CPLConfigOptionSetter date("OGR_CURRENT_DATE", "2000-01-01T00:00:00Z", false);
    for (const ShapeFile* input : {&polygons, &lines}) {
        const std::filesystem::path out = std::filesystem::path(input->path()).parent_path() / "out";
        std::filesystem::create_directories(out);
        map::MapData map;
        const OgrDataset dataset = OgrDataset::read(input->path(), {}, map, true);
        const std::vector<std::uint8_t> kept = thinned(map, 2);
        EXPECT_LT(std::count(kept.begin(), kept.end(), 1), static_cast<std::ptrdiff_t>(kept.size())) << input->path();
        auto write = [&](const std::string& name, std::optional<std::uint64_t> in_memory_at_most) {
            WriteOptions options;
            options.path = (out / name).string();
            options.overwrite = true;
            options.in_memory_at_most = in_memory_at_most;
            EXPECT_TRUE(dataset.write(options, map, kept).empty());
        };
        write("memory.shp", std::nullopt);
        write("disk.shp", 0);
        for (const char* extension : {".shp", ".shx", ".dbf", ".prj"}) {
            const std::string expected = file_bytes(out / (std::string("memory") + extension));
            EXPECT_FALSE(expected.empty()) << extension;
            EXPECT_EQ(file_bytes(out / (std::string("disk") + extension)), expected) << input->path() << extension;
        }
    }
}

// A TopoJSON whose reading back through GDAL would take more than `read_back_at_most` (GDAL's
// reader holds about 21 times the file) is moved into place unread, with a warning that says
// why: the same bytes as one read back.
TEST(TopoJsonWriter, TooBigToReadBackIsWrittenWithAWarning) {
    const ShapeFile polygons("cells", wkbPolygon,
                             {"POLYGON ((0 0,0 4,1 5,2 4,4 4,4 0,3 -1,2 0,0 0),(1 1,2 1,2 2,1 2,1 1))", "",
                              "POLYGON ((4 0,4 4,6 4,6 0,5 -1,4 0))"});
    const std::filesystem::path out = std::filesystem::path(polygons.path()).parent_path() / "out";
    std::filesystem::create_directories(out);
    map::MapData map;
    const OgrDataset dataset = OgrDataset::read(polygons.path(), {}, map, true);
    const std::vector<std::uint8_t> kept = thinned(map, 2);
    auto write = [&](const std::string& name, std::optional<std::uint64_t> read_back_at_most) {
        WriteOptions options;
        options.path = (out / name).string();
        options.overwrite = true;
        options.read_back_at_most = read_back_at_most;
        return dataset.write(options, map, kept);
    };
    EXPECT_TRUE(write("read.topojson", std::nullopt).empty());
    const std::uint64_t size = std::filesystem::file_size(out / "read.topojson");
    EXPECT_TRUE(write("just.topojson", 21 * size).empty());
    const std::vector<std::string> warnings = write("unread.topojson", 21 * size - 1);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings.front().find("was not read back through GDAL"), std::string::npos) << warnings.front();
    EXPECT_NE(warnings.front().find("unread.topojson"), std::string::npos) << warnings.front();
    EXPECT_EQ(file_bytes(out / "unread.topojson"), file_bytes(out / "read.topojson"));
    EXPECT_EQ(file_bytes(out / "just.topojson"), file_bytes(out / "read.topojson"));
}

}  // namespace
}  // namespace toposimp::io
