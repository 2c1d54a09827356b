// GeoPackage control points read with SQLite directly must be exactly the points OGR reads:
// blobs written by hand in every form the reader decodes, checked against OGR on the same file.
#include "io/map/gpkg_points.hpp"

#include "io/common/errors.hpp"
#include "io/ogr/gdal_support.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "support/temp_path.hpp"
#include "unit/io/ogr_points_reference.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

namespace toposimp::io {
namespace {

using Bytes = std::vector<unsigned char>;

void put_u32(Bytes& out, bool little, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(value >> (8 * (little ? i : 3 - i))));
}

void put_f64(Bytes& out, bool little, double value) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<unsigned char>(bits >> (8 * (little ? i : 7 - i))));
}

// WKB point with the given type code and ordinates.
Bytes wkb_point(bool little, std::uint32_t type, const std::vector<double>& ordinates) {
    Bytes out{static_cast<unsigned char>(little ? 1 : 0)};
    put_u32(out, little, type);
    for (const double value : ordinates) put_f64(out, little, value);
    return out;
}

Bytes wkb_multipoint(bool little, const std::vector<Bytes>& members) {
    Bytes out{static_cast<unsigned char>(little ? 1 : 0)};
    put_u32(out, little, 4);
    put_u32(out, little, static_cast<std::uint32_t>(members.size()));
    for (const Bytes& member : members) out.insert(out.end(), member.begin(), member.end());
    return out;
}

// GeoPackage binary: "GP", version 0, flags, srs_id 4326, an envelope of `envelope` kind
// (filled with junk: readers must not use it), then the WKB.
Bytes gp_blob(bool little_header, unsigned envelope, const Bytes& wkb, bool empty_flag = false) {
    static constexpr int kDoubles[] = {0, 4, 6, 6, 8};
    Bytes out{'G', 'P', 0, static_cast<unsigned char>((little_header ? 1 : 0) | envelope << 1 | (empty_flag ? 0x10 : 0))};
    put_u32(out, little_header, 4326);
    for (int i = 0; i < kDoubles[envelope]; ++i) put_f64(out, little_header, 1e300);
    out.insert(out.end(), wkb.begin(), wkb.end());
    return out;
}

class GpkgFile {
public:
    explicit GpkgFile(const std::string& name) {
        path_ = testing::temp_path("gpkg-" + name + ".gpkg").string();
        std::filesystem::remove(path_);
        register_drivers();
        GDALDataset* dataset = GetGDALDriverManager()->GetDriverByName("GPKG")->Create(path_.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
        const char* options[] = {"SPATIAL_INDEX=NO", nullptr};  // no R-tree triggers calling GDAL's SQL functions
        dataset->CreateLayer("points", nullptr, wkbUnknown, const_cast<char**>(options));
        GDALClose(dataset);
    }

    // Row `fid` with this geometry blob (empty: NULL).
    void insert(std::int64_t fid, const Bytes& blob) {
        sqlite3* db = nullptr;
        ASSERT_EQ(sqlite3_open(path_.c_str(), &db), SQLITE_OK);
        sqlite3_stmt* statement = nullptr;
        ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO points (fid, geom) VALUES (?1, ?2)", -1, &statement, nullptr), SQLITE_OK)
            << sqlite3_errmsg(db);
        sqlite3_bind_int64(statement, 1, fid);
        if (blob.empty()) {
            sqlite3_bind_null(statement, 2);
        } else {
            sqlite3_bind_blob(statement, 2, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
        }
        EXPECT_EQ(sqlite3_step(statement), SQLITE_DONE) << sqlite3_errmsg(db);
        sqlite3_finalize(statement);
        sqlite3_close(db);
    }

    std::vector<Point> read_with_ogr() const { return points_read_by_ogr(path_); }

    GpkgTable table() const { return {path_, "points", "geom", "fid"}; }
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

TEST(GpkgPoints, EveryEncodingReadsAsOgrReadsIt) {
    GpkgFile file("encodings");
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double tiny = 4.9406564584124654e-324, odd = 0.1 + 0.2;
    file.insert(1, gp_blob(true, 0, wkb_point(true, 1, {1.5, -2.25})));                     // what GDAL writes
    file.insert(2, gp_blob(false, 1, wkb_point(false, 1, {tiny, -odd})));                   // big-endian, xy envelope
    file.insert(3, gp_blob(true, 4, wkb_point(false, 3001, {7, 8, 9, 10})));                // ISO ZM, xyzm envelope
    file.insert(5, gp_blob(true, 2, wkb_point(true, 0x80000001u, {-180, 90, 5})));          // 2.5D flag
    file.insert(6, gp_blob(false, 3, wkb_point(true, 2001, {1e15, -1e-15, 3})));            // ISO M, xym envelope
    file.insert(7, {});                                                                      // NULL geometry
    file.insert(9, gp_blob(true, 0, wkb_multipoint(true, {wkb_point(false, 1, {3, 4}), wkb_point(true, 1, {nan, nan}),
                                                          wkb_point(true, 1001, {5, 6, 7})})));
    file.insert(10, gp_blob(true, 0, wkb_point(true, 1, {nan, nan})));                       // empty point
    file.insert(11, gp_blob(true, 0, wkb_point(true, 1, {nan, nan}), true));                // empty flag
    file.insert(12, gp_blob(true, 1, wkb_multipoint(false, {})));                            // empty multipoint

    const std::vector<Point> reference = file.read_with_ogr();
    ASSERT_EQ(reference.size(), 7u);  // rows 1, 2, 3, 5, 6 and two of row 9's three
    for (const unsigned threads : {1u, 2u}) {
        const std::optional<std::vector<Point>> read = read_gpkg_points(file.table(), threads);
        ASSERT_TRUE(read.has_value());
        expect_same_points(*read, reference);
    }
    expect_same_points(read_control_points(file.path()), reference);
}

// Rows split over connections by FID range, with gaps: the points of one connection, in order.
// FIDs close together and spread out (13 apart: parts of other sizes).
TEST(GpkgPoints, FidRangesOnSeveralConnectionsGiveTheSamePoints) {
    for (const std::int64_t spread : {std::int64_t{1}, std::int64_t{13}}) {
        GpkgFile file("ranges" + std::to_string(spread));
        {
            sqlite3* db = nullptr;
            ASSERT_EQ(sqlite3_open(file.path().c_str(), &db), SQLITE_OK);
            sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr);
            sqlite3_stmt* statement = nullptr;
            sqlite3_prepare_v2(db, "INSERT INTO points (fid, geom) VALUES (?1, ?2)", -1, &statement, nullptr);
            std::uint64_t state = 12345;
            for (std::int64_t k = 1; k < 300000; k += 1 + (k % 5 == 0 ? 3 : 0)) {  // gaps
                state = state * 6364136223846793005ull + 1442695040888963407ull;
                const double x = static_cast<double>(state >> 11) * 0x1p-53 * 360 - 180;
                const Bytes blob = gp_blob(true, 0, wkb_point(true, 1, {x, x / 3}));
                sqlite3_bind_int64(statement, 1, k * spread);
                sqlite3_bind_blob(statement, 2, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
                ASSERT_EQ(sqlite3_step(statement), SQLITE_DONE);
                sqlite3_reset(statement);
            }
            sqlite3_finalize(statement);
            sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
            sqlite3_close(db);
        }
        const std::vector<Point> reference = file.read_with_ogr();
        ASSERT_GT(reference.size(), 100000u);
        for (const unsigned threads : {1u, 2u, 3u, 7u}) {
            const std::optional<std::vector<Point>> read = read_gpkg_points(file.table(), threads);
            ASSERT_TRUE(read.has_value()) << threads;
            expect_same_points(*read, reference);
        }
    }
}

TEST(GpkgPoints, NonFiniteCoordinateNamesFileLayerAndFeature) {
    GpkgFile file("nonfinite");
    file.insert(1, gp_blob(true, 0, wkb_point(true, 1, {1, 2})));
    file.insert(7, gp_blob(true, 0, wkb_point(true, 1, {std::numeric_limits<double>::infinity(), 2})));
    for (const unsigned threads : {1u, 2u}) {
        try {
            (void)read_control_points(file.path(), threads);
            FAIL() << "no error";
        } catch (const InputError& error) {
            EXPECT_EQ(std::string(error.what()),
                      "'" + file.path() + "', layer 'points', feature 7: control point has a non-finite coordinate");
        }
    }
}

// Not a point, or not a GeoPackage blob: the fast reader declines and OGR's reading decides.
TEST(GpkgPoints, AnythingElseIsLeftToOgr) {
    GpkgFile lines("line");
    Bytes line{1};
    put_u32(line, true, 2);
    put_u32(line, true, 2);
    for (const double v : {0.0, 0.0, 1.0, 1.0}) put_f64(line, true, v);
    lines.insert(1, gp_blob(true, 0, wkb_point(true, 1, {1, 2})));
    lines.insert(2, gp_blob(true, 1, line));
    EXPECT_FALSE(read_gpkg_points(lines.table(), 1).has_value());
    try {
        (void)read_control_points(lines.path());
        FAIL() << "no error";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("feature 2: control points must be Point or MultiPoint, not"), std::string::npos)
            << error.what();
    }

    GpkgFile truncated("truncated");
    Bytes cut = gp_blob(true, 0, wkb_point(true, 1, {1, 2}));
    cut.resize(cut.size() - 3);
    truncated.insert(1, cut);
    EXPECT_FALSE(read_gpkg_points(truncated.table(), 1).has_value());

    GpkgFile missing("missing-table");
    EXPECT_FALSE(read_gpkg_points({missing.path(), "no_such_table", "geom", "fid"}, 1).has_value());
    EXPECT_FALSE(read_gpkg_points({missing.path() + ".absent", "points", "geom", "fid"}, 1).has_value());
}

}  // namespace
}  // namespace toposimp::io
