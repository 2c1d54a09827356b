// Regression tests for issue 29 (hostile and messy input), one per case it found, named after
// what it found. Each failed before its fix (noted per test).
#include "cli/cli_fixtures.hpp"
#include "io/common/errors.hpp"
#include "io/mesh/mesh_files.hpp"
#include "io/ogr/map_formats.hpp"
#include "support/exact_checker.hpp"

#include <gtest/gtest.h>
#include <ogrsf_frmts.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <set>

namespace toposimp::testing {
namespace {

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
}

template <class T>
std::string bytes_of(T value) {
    std::string text(sizeof value, '\0');
    std::memcpy(text.data(), &value, sizeof value);
    return text;
}

// The run failed with exit 2, said `message`, and left nothing in `dir` but `allowed`.
void expect_refused(const CliResult& result, const std::filesystem::path& dir, const std::string& message,
                    std::vector<std::string> allowed) {
    EXPECT_EQ(result.code, 2) << result.err;
    EXPECT_NE(result.err.find(message), std::string::npos) << "message was: " << result.err;
    std::vector<std::string> files = files_in(dir);
    std::sort(files.begin(), files.end());
    std::sort(allowed.begin(), allowed.end());
    EXPECT_EQ(files, allowed) << "output or temporary files left behind";
}

// Case 1. A layer whose features come in another order than their FIDs (a GeoJSON's "id"s out of
// order; here an OGR VRT ordered by name), written to GeoPackage, which keeps the FIDs and hands
// the rows back in FID order: the read-back compared them by position and refused the output
// ("the GPKG driver changed coordinates", recommending GeoPackage).
TEST(Issue29, FeaturesOutOfFidOrderAreComparedByFid) {
    const auto dir = fresh_dir("issue29");
    const std::string source = (dir / "lines.gpkg").string();
    write_layer(source, "GPKG", wkbLineString,
                {{"LINESTRING (0 0,1 0.3,2 0,3 0.3,4 0)", "c"},
                 {"LINESTRING (0 5,1 5.3,2 5,3 5.3,4 5,5 5.3,6 5,7 5.3,8 5)", "b"},
                 {"LINESTRING (0 9,1 9.3,2 9,3 9.3,4 9,5 9.2,6 9)", "a"}});
    const auto vrt = dir / "ordered.vrt";
    std::ofstream(vrt) << "<OGRVRTDataSource><OGRVRTLayer name=\"lines\"><SrcDataSource>" << source
                       << "</SrcDataSource><SrcSQL dialect=\"sqlite\">SELECT fid AS source_fid, * FROM lines ORDER BY name"
                          "</SrcSQL><FID>source_fid</FID></OGRVRTLayer></OGRVRTDataSource>";
    const std::string out = (dir / "out.gpkg").string();
    const CliResult map = run_cli({"map", vrt.string(), "-o", out, "--keep", "50%"});
    ASSERT_EQ(map.code, 0) << map.err;
    const CliResult check = run_cli({"check", vrt.string(), out, "--key", "name"});
    EXPECT_EQ(check.code, 0) << check.out << check.err;
    // And a refusal never recommends the format it refuses.
    EXPECT_EQ(io::recommended_formats_but("GPKG").find("GeoPackage"), std::string::npos);
    EXPECT_NE(io::recommended_formats_but("CSV").find("GeoPackage (.gpkg)"), std::string::npos);
}

// Case 2. A line ending in a repeated vertex (…, Z, Z) simplified to (A, Z): `check` matched the
// last Z to the first copy and reported not_subset.
TEST(Issue29, CheckAcceptsALineEndingInARepeatedVertex) {
    const auto dir = fresh_dir("issue29");
    const std::string original = (dir / "original.gpkg").string(), simplified = (dir / "simplified.gpkg").string();
    write_layer(original, "GPKG", wkbLineString, {{"LINESTRING (0 0,1 1,2 0,3 0,3 0)", "a"}});
    write_layer(simplified, "GPKG", wkbLineString, {{"LINESTRING (0 0,3 0)", "a"}});
    const CliResult check = run_cli({"check", original, simplified, "--json"});
    EXPECT_EQ(check.code, 0) << check.out << check.err;
    EXPECT_NE(check.out.find("\"clean\":true"), std::string::npos) << check.out;
    // A vertex truly missing from the original is still found.
    write_layer(simplified, "GPKG", wkbLineString, {{"LINESTRING (0 0,2 1,3 0)", "a"}});
    EXPECT_NE(run_cli({"check", original, simplified, "--json"}).out.find("\"not_subset\":1"), std::string::npos);
}

// Case 3. `check ORIG SIMP -p ORIG:points` expected the control points' layer in SIMP too.
TEST(Issue29, CheckDoesNotCompareTheControlPointLayerItIsGiven) {
    const auto dir = fresh_dir("issue29");
    const std::string original = testdata("nh_borders.gpkg"), out = (dir / "borders.gpkg").string();
    ASSERT_EQ(run_cli({"map", original, "-l", "borders", "-p", original + ":places", "-o", out, "--keep", "10%"}).code, 0);
    const CliResult check = run_cli({"check", original, out, "-p", original + ":places", "--json"});
    EXPECT_EQ(check.code, 0) << check.out << check.err;
    EXPECT_NE(check.out.find("\"features\":27,\"control_points\":26"), std::string::npos) << check.out;
}

// Case 9. A GPS track driving one route 10 000 times, back and forth (40 000 vertices), and a
// road across it: the input-crossing search listed every pair of the track's segments (7 GB in
// 60 s, no end, for 100 000), and so did `check` counting contacts (2·10^8 pairs of identical
// segments here).
// Now map pins the whole track (it overlaps itself everywhere) and check counts the copies.
TEST(Issue29, TrackRepeatingARouteIsSimplifiedAndChecked) {
    const auto dir = fresh_dir("issue29");
    std::vector<std::string> route;
    for (int k = 0; k < 5; ++k) route.push_back(std::to_string(100 * k) + " " + std::to_string(3000 * k + (k % 2 ? 70 : 0)));
    std::string track = "LINESTRING (" + route.front();
    for (int pass = 0; pass < 10000; ++pass) {
        for (std::size_t k = 1; k < route.size(); ++k) track += "," + route[pass % 2 == 0 ? k : route.size() - 1 - k];
    }
    const std::string input = (dir / "tracks.gpkg").string(), out = (dir / "out.gpkg").string();
    track += ")";
    write_layer(input, "GPKG", wkbLineString, {{track, "track"}, {"LINESTRING (-10 7000,100 7100,200 7000,300 7100,400 7000,510 7100)", "road"}});
    const CliResult map = run_cli({"map", input, "-o", out, "--keep", "50%", "--json"});
    ASSERT_EQ(map.code, 0) << map.err;
    const CliResult check = run_cli({"check", input, out, "--json"});
    EXPECT_EQ(check.code, 0) << check.out << check.err;
    EXPECT_NE(check.out.find("\"clean\":true"), std::string::npos) << check.out;
    // The track is kept whole; the road is free to lose corners away from the crossing.
    const ReadLayer written = read_layer(out);
    ASSERT_EQ(written.features.size(), 2u);
    EXPECT_EQ(written.features[0].coordinates[0].size(), 2u * (4u * 10000u + 1u));  // x, y
}

// Case 9, the other way round: a track along one straight road with its vertices elsewhere each
// pass. Its segments overlap along the road pair by pair (10^7 pairs for 100 000 vertices, 19 s
// and 1 GB in check, each pair a slow exact test of collinear points); check now counts overlaps
// along a line with a sweep. Random lines on three exact lines (level, upright, slope 1/2), some
// lines across them, and random subsets (repeated locations left in): check reports exactly what
// counting every pair of segments with the independent checker's predicates says.
TEST(Issue29, CheckCountsOverlapsAlongALineAsEveryPairDoes) {
    using Line = std::vector<Point>;
    auto at = [](Point p, Point q) { return p.x == q.x && p.y == q.y; };
    // Per pair of features (i <= j): proper crossings, other contacts, identical segments.
    using Counts = std::map<std::pair<std::size_t, std::size_t>, std::array<std::uint64_t, 3>>;
    auto count_pairs = [&at](const std::vector<Line>& lines) {
        Counts counts;
        for (std::size_t i = 0; i < lines.size(); ++i) {
            for (std::size_t j = i; j < lines.size(); ++j) {
                for (std::size_t a = 0; a + 1 < lines[i].size(); ++a) {
                    for (std::size_t b = i == j ? a + 1 : 0; b + 1 < lines[j].size(); ++b) {
                        const Point p = lines[i][a], q = lines[i][a + 1], r = lines[j][b], u = lines[j][b + 1];
                        if (!improper_contact(p, q, r, u)) continue;
                        const bool same = (at(p, r) && at(q, u)) || (at(p, u) && at(q, r));
                        const bool proper = exact_orient(p, q, r) * exact_orient(p, q, u) < 0 && exact_orient(r, u, p) * exact_orient(r, u, q) < 0;
                        ++counts[{i, j}][same ? 2 : proper ? 0 : 1];
                    }
                }
            }
        }
        return counts;
    };
    const auto dir = fresh_dir("issue29");
    std::mt19937 random(29);
    for (int trial = 0; trial < 25; ++trial) {
        std::vector<Line> before, after;
        for (int f = 0; f < 6; ++f) {
            Line line;
            const int on = f < 5 ? f % 3 : 3;  // 3: across, anywhere
            const int count = 3 + static_cast<int>(random() % 12);
            while (static_cast<int>(line.size()) < count) {
                const double t = static_cast<double>(random() % 21) / 2;
                const Point p = on == 0 ? Point{t, 0} : on == 1 ? Point{3, t} : on == 2 ? Point{2 * t, t}
                                                      : Point{static_cast<double>(random() % 11), static_cast<double>(random() % 11) - 1};
                if (line.empty() || !at(line.back(), p)) line.push_back(p);
            }
            Line kept{line.front()};
            for (std::size_t k = 1; k + 1 < line.size(); ++k) {
                if (random() % 2) kept.push_back(line[k]);
            }
            kept.push_back(line.back());
            before.push_back(line);
            after.push_back(kept);
        }
        const Counts was = count_pairs(before), is = count_pairs(after);
        std::multiset<std::string> expected;
        const char* names[2][3] = {{"lost_crossing", "lost_touching", "border_no_longer_shared"}, {"new_crossing", "new_touching", "new_coincidence"}};
        for (const auto* side : {&is, &was}) {
            const bool after_side = side == &is;
            for (const auto& [pair, here] : *side) {
                const auto other = (after_side ? was : is).find(pair);
                for (int kind = 0; kind < 3; ++kind) {
                    const std::uint64_t there = other == (after_side ? was : is).end() ? 0 : other->second[kind];
                    const bool reported = kind == 2 ? here[kind] > 0 && there == 0 : here[kind] > there;
                    if (!reported) continue;
                    const std::uint64_t b = after_side ? there : here[kind], a = after_side ? here[kind] : there;
                    expected.insert(std::string(names[after_side][kind]) + " f" + std::to_string(pair.first) + " f" + std::to_string(pair.second) +
                                    " " + std::to_string(b) + " before, " + std::to_string(a) + " after" + (kind == 2 ? " shared segments" : ""));
                }
            }
        }
        std::vector<FeatureSpec> original, simplified;
        for (std::size_t f = 0; f < before.size(); ++f) {
            original.push_back({line_wkt(before[f]), "f" + std::to_string(f)});
            simplified.push_back({line_wkt(after[f]), "f" + std::to_string(f)});
        }
        const std::string a = (dir / "a.gpkg").string(), b = (dir / "b.gpkg").string();
        std::filesystem::remove(a);
        std::filesystem::remove(b);
        write_layer(a, "GPKG", wkbLineString, original);
        write_layer(b, "GPKG", wkbLineString, simplified);
        const CliResult check = run_cli({"check", a, b, "--key", "name", "--json"});
        ASSERT_NE(check.code, 2) << check.err;
        std::multiset<std::string> found;
        const std::regex violation(R"re("kind":"([a-z_]+)","layer":"[^"]*","feature":"([^"]*)","other":"([^"]*)","x":[^,]*,"y":[^,]*,"detail":"([^"]*)")re");
        for (auto it = std::sregex_iterator(check.out.begin(), check.out.end(), violation); it != std::sregex_iterator(); ++it) {
            found.insert((*it)[1].str() + " " + (*it)[2].str() + " " + (*it)[3].str() + " " + (*it)[4].str());
        }
        EXPECT_EQ(found, expected) << "trial " << trial << "\n" << check.out;
        EXPECT_EQ(check.code, expected.empty() ? 0 : 1);
    }
}

const std::string kBinaryFace = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

std::string triangle_face() { return std::string(1, '\3') + bytes_of<std::int32_t>(0) + bytes_of<std::int32_t>(1) + bytes_of<std::int32_t>(2); }

// Case 4. A binary PLY whose vertex element is `uchar x, uchar x, uchar y`: the check counted
// names, not axes, and the reader went 8 bytes past a 3-byte record (ASan).
TEST(Issue29, PlyVertexWithAnAxisTwiceIsRefused) {
    const auto dir = fresh_dir("issue29");
    write_bytes(dir / "in.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty uchar x\nproperty uchar x\n"
                                "property uchar y\n" + kBinaryFace + std::string("\0\0\0\1\1\0\0\0\1", 9) + triangle_face());
    expect_refused(run_cli({"mesh", (dir / "in.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "in.ply: the vertex element has property x twice", {"in.ply"});
}

// Case 5. Two vertex (or face) elements: std::invalid_argument escaped the command (abort, exit
// 134) and left the staging folder behind.
TEST(Issue29, PlyWithTwoVertexOrFaceElementsIsRefused) {
    const auto dir = fresh_dir("issue29");
    const std::string vertex = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
    write_bytes(dir / "vertices.ply", "ply\nformat ascii 1.0\n" + vertex + vertex + face + "end_header\n0 0 0\n1 0 0\n0 1 0\n"
                                      "0 0 1\n1 0 1\n0 1 1\n3 0 1 2\n");
    expect_refused(run_cli({"mesh", (dir / "vertices.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "vertices.ply:7: a second 'vertex' element", {"vertices.ply"});
    write_bytes(dir / "faces.ply", "ply\nformat ascii 1.0\n" + vertex + face + face + "end_header\n0 0 0\n1 0 0\n0 1 0\n"
                                   "3 0 1 2\n3 0 2 1\n");
    expect_refused(run_cli({"mesh", (dir / "faces.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "faces.ply:9: a second 'face' element", {"faces.ply", "vertices.ply"});
}

// Case 6. Control points in a GeoPackage whose FIDs lie far apart: FIDs 1 and 2^62 threw
// std::length_error from a reservation (abort), 1 and 2^40 reserved 8 TiB, INT64_MIN and
// INT64_MAX overflowed a signed difference. Read on two threads, where the FID range is split.
TEST(Issue29, ControlPointFidsFarApart) {
    constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min(), kMax = std::numeric_limits<std::int64_t>::max();
    const std::pair<std::int64_t, std::int64_t> cases[] = {{1, std::int64_t{1} << 62}, {1, std::int64_t{1} << 40}, {kMin, kMax}};
    for (const auto& [first, second] : cases) {
        const auto dir = fresh_dir("issue29");
        const std::string points = (dir / "points.gpkg").string();
        {
            GDALAllRegister();
            GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GPKG");
            std::unique_ptr<GDALDataset> dataset(driver->Create(points.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
            ASSERT_TRUE(dataset);
            const char* options[] = {"SPATIAL_INDEX=NO", nullptr};
            OGRLayer* layer = dataset->CreateLayer("points", nullptr, wkbPoint, const_cast<char**>(options));
            ASSERT_NE(layer, nullptr);
            for (const std::int64_t fid : {first, second}) {
                OGRFeature feature(layer->GetLayerDefn());
                feature.SetFID(fid);
                feature.SetGeometryDirectly(new OGRPoint(-7.9e6, 5.3e6));
                ASSERT_EQ(layer->CreateFeature(&feature), OGRERR_NONE) << fid;
            }
        }
        const CliResult r = run_cli({"map", testdata("nh_borders.gpkg"), "-l", "borders", "-p", points, "-o",
                                     (dir / "out.gpkg").string(), "-j", "2", "--json"});
        EXPECT_EQ(r.code, 0) << first << " " << second << ": " << r.err;
        EXPECT_NE(r.out.find("\"control_points\":2,"), std::string::npos) << r.out;
    }
}

// Case 7. A 79-byte binary PLY with `element foo 9223372036854775807` and no properties: the
// reader looped over the elements without end.
TEST(Issue29, PlyElementWithoutPropertiesAndAHugeCountEnds) {
    const auto dir = fresh_dir("issue29");
    write_bytes(dir / "in.ply", "ply\nformat binary_little_endian 1.0\nelement foo 9223372036854775807\nend_header\n");
    expect_refused(run_cli({"mesh", (dir / "in.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "in.ply: no faces to simplify", {"in.ply"});
    // A count the rest of the file cannot hold is refused before anything is read.
    write_bytes(dir / "in.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                                "property float y\nproperty float z\n" + kBinaryFace + std::string(12, '\0'));
    expect_refused(run_cli({"mesh", (dir / "in.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "in.ply: truncated binary PLY: the file ends inside vertex 1 (the header promises 4000000000)", {"in.ply"});
}

// Case 8. A Shapefile of control points whose first record claims 0x3ffffff0 words: 2.1 GB were
// allocated and zeroed before the length was held against the file. Now the record is refused at
// once (GDAL, reading the file in its place, says why): the run stays far below that.
TEST(Issue29, ShapefileRecordLongerThanTheFileAllocatesNothing) {
    const auto dir = fresh_dir("issue29");
    const std::string points = (dir / "points.shp").string();
    write_layer(points, "ESRI Shapefile", wkbPoint, {{"POINT (1 2)", "a"}, {"POINT (3 4)", "b"}}, "points");
    for (const char* extension : {".shp", ".shx"}) {
        std::fstream file(dir / (std::string("points") + extension), std::ios::in | std::ios::out | std::ios::binary);
        file.seekp(104);  // the first record's content length (.shp header) or index entry (.shx), big-endian words
        file.write("\x3f\xff\xff\xf0", 4);
    }
    const std::string command = "'" + std::string(TOPOSIMP_BINARY) + "' map '" + testdata("nh_borders.gpkg") + "' -l borders -p '" +
                                points + "' -o '" + (dir / "out.gpkg").string() + "' 2>'" + (dir / "err.txt").string() + "'";
    const int status = std::system(command.c_str());
    rusage children{};
    ::getrusage(RUSAGE_CHILDREN, &children);
    std::ifstream in(dir / "err.txt");
    const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(WEXITSTATUS(status), 2) << err;
    EXPECT_NE(err.find("points.shp"), std::string::npos) << err;
    EXPECT_LT(children.ru_maxrss, 512 * 1024) << "KiB at the peak";  // (it was 2.15 GB)
}

// Case 10. --overwrite replaced whatever -o named: a character device (as root, /dev/null), an
// empty folder. Only files are replaced now; a FIFO stands in for a device (no root needed).
TEST(Issue29, OverwriteReplacesFilesOnly) {
    const auto dir = fresh_dir("issue29");
    ASSERT_EQ(::mkfifo((dir / "fifo.ply").c_str(), 0600), 0);
    std::filesystem::create_directory(dir / "folder.ply");
    for (const char* target : {"fifo.ply", "folder.ply"}) {
        const CliResult r = run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / target).string(), "--overwrite"});
        expect_refused(r, dir, "toposimp writes and replaces files only", {"fifo.ply", "folder.ply"});
    }
    EXPECT_TRUE(std::filesystem::is_fifo(dir / "fifo.ply"));
    EXPECT_TRUE(std::filesystem::is_directory(dir / "folder.ply"));
    const CliResult null = run_cli({"mesh", testdata("mesh/torus.off"), "-o", "/dev/null", "--overwrite"});
    EXPECT_EQ(null.code, 2);
    EXPECT_TRUE(std::filesystem::is_character_file("/dev/null"));
}

// Case 11. A valid OBJ beginning "# OFFSET" and a binary STL whose header starts "OFFSHORE" were
// refused as "not an OFF file": content sniffing ran before the extension.
TEST(Issue29, ContentThatOnlyLooksLikeOffIsReadByItsExtension) {
    const auto dir = fresh_dir("issue29");
    write_bytes(dir / "offset.obj", "# OFFSET 0 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    std::string stl = "OFFSHORE platform" + std::string(63, ' ') + bytes_of<std::uint32_t>(4);
    const float corners[4][3][3] = {{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}},
                                    {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    for (const auto& triangle : corners) {
        for (int k = 0; k < 3; ++k) stl += bytes_of(0.0f);
        for (const auto& corner : triangle) {
            for (const float value : corner) stl += bytes_of(value);
        }
        stl += bytes_of<std::uint16_t>(0);
    }
    write_bytes(dir / "offshore.stl", stl);
    for (const char* name : {"offset.obj", "offshore.stl"}) {
        const CliResult r = run_cli({"mesh", (dir / name).string(), "-o", (dir / "out.ply").string(), "--overwrite", "--json"});
        EXPECT_EQ(r.code, 0) << name << ": " << r.err;
        EXPECT_NE(r.out.find("\"faces_in\":4,"), std::string::npos) << name << ": " << r.out;
    }
}

// Case 12. /dev/zero behind a mesh file's name, or as --giscup input: read until memory ran out.
TEST(Issue29, DevicesAreNotReadAsFiles) {
    const auto dir = fresh_dir("issue29");
    std::filesystem::create_symlink("/dev/zero", dir / "zero.ply");
    std::filesystem::create_symlink("/dev/zero", dir / "zero.txt");
    expect_refused(run_cli({"mesh", (dir / "zero.ply").string(), "-o", (dir / "out.ply").string()}), dir,
                   "zero.ply: is a device, not a file", {"zero.ply", "zero.txt"});
    expect_refused(run_cli({"map", "--giscup", (dir / "zero.txt").string(), "-o", (dir / "out.txt").string()}), dir,
                   "zero.txt: is a device, not a file", {"zero.ply", "zero.txt"});
}

// Case 14. --remove-points nan was taken as "not given" (the default --keep 10% ran); a negative
// count was refused with a 309-digit bound.
TEST(Issue29, NumericOptionsRefuseNanInfinityAndNegatives) {
    const auto dir = fresh_dir("issue29");
    const std::string out = (dir / "out.gpkg").string();
    for (const char* value : {"nan", "inf", "-1", "1x"}) {
        const CliResult r = run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--remove-points", value});
        EXPECT_EQ(r.code, 2) << value;
        EXPECT_NE(r.err.find(std::string("--remove-points: '") + value + "'"), std::string::npos) << r.err;
        EXPECT_LT(r.err.size(), 200u) << r.err;
    }
    const CliResult mesh = run_cli({"mesh", testdata("mesh/torus.off"), "-o", (dir / "out.ply").string(), "--keep-faces", "nan"});
    EXPECT_EQ(mesh.code, 2);
    EXPECT_TRUE(files_in(dir).empty());
    EXPECT_EQ(run_cli({"map", testdata("nh_borders.gpkg"), "-o", out, "--remove-points", "+5", "-q"}).code, 0);
}

// Found by the OFF fuzz target: a 20-byte OFF file claiming 60 million vertices reserved room
// for 2^26 of them (1.6 GB) before reading one; under a 1 GB address-space limit the run ended
// "out of memory" instead of saying the file is truncated.
TEST(Issue29, OffVertexCountIsHeldAgainstTheFile) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer reserves terabytes of shadow address space: an address-space limit stops it starting";
#endif
    const auto dir = fresh_dir("issue29");
    write_bytes(dir / "huge.off", "OFF\n60000000 1 0\n0 0 0\n");
    const std::string command = "ulimit -v 1000000; '" + std::string(TOPOSIMP_BINARY) + "' mesh '" + (dir / "huge.off").string() +
                                "' -o '" + (dir / "out.ply").string() + "' 2>'" + (dir / "err.txt").string() + "'";
    const int status = std::system(command.c_str());
    std::ifstream in(dir / "err.txt");
    const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(WEXITSTATUS(status), 2) << err;
    EXPECT_NE(err.find("huge.off: truncated: the header promises 60000000 vertices"), std::string::npos) << err;
}

// Case 14, last part. A full disk was reported as a "write error" on the staging path; now the
// destination and the system's reason ("No space left on device": /dev/full stands in for a
// full disk).
TEST(Issue29, AFullDiskIsReportedAsSuch) {
    mesh::Mesh tetrahedron;
    tetrahedron.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    tetrahedron.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    // (Big enough that the buffer is written before the file is closed, as well as at the close.)
    for (int i = 0; i < 60000; ++i) tetrahedron.points.push_back({0.1 * i, 0.2, 0.3});
    try {
        io::write_mesh(tetrahedron, {}, "/dev/full", io::MeshFormat::ply, true, "out.ply");
        ADD_FAILURE() << "no error writing to /dev/full";
    } catch (const io::OutputError& error) {
        EXPECT_NE(std::string(error.what()).find("out.ply: cannot write: No space left on device"), std::string::npos) << error.what();
    }
}

}  // namespace
}  // namespace toposimp::testing
