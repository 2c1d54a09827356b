// Shapefile control points decoded from the .shp directly must be exactly the points OGR reads:
// files written by OGR in every point shape type, checked against OGR's reading of the same file.
#include "io/shapefile_points.hpp"

#include "io/errors.hpp"
#include "io/gdal_support.hpp"
#include "io/ogr_dataset.hpp"
#include "unit/io/ogr_points_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace toposimp::io {
namespace {

// A shapefile of one geometry type, written through OGR; geometries given as WKT ("" for none).
class ShapeFile {
public:
    ShapeFile(const std::string& name, OGRwkbGeometryType type, const std::vector<std::string>& wkts,
              const std::vector<GIntBig>& deleted = {}) {
        directory_ = std::filesystem::temp_directory_path() / ("toposimp-shp-" + name);
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
        layer->CreateField(std::make_unique<OGRFieldDefn>("name", OFTString).get());
        for (const std::string& wkt : wkts) {
            OGRFeatureUniquePtr feature(OGRFeature::CreateFeature(layer->GetLayerDefn()));
            feature->SetField("name", "a point");
            if (!wkt.empty()) {
                OGRGeometry* geometry = nullptr;
                EXPECT_EQ(OGRGeometryFactory::createFromWkt(wkt.c_str(), nullptr, &geometry), OGRERR_NONE) << wkt;
                feature->SetGeometryDirectly(geometry);
            }
            EXPECT_EQ(layer->CreateFeature(feature.get()), OGRERR_NONE) << wkt;
        }
        for (const GIntBig fid : deleted) EXPECT_EQ(layer->DeleteFeature(fid), OGRERR_NONE);
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

}  // namespace
}  // namespace toposimp::io
