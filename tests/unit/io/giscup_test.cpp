#include "io/map/giscup.hpp"

#include "io/common/errors.hpp"
#include "support/temp_path.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace toposimp::io {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
    const auto path = testing::temp_path("giscup-" + name);
    std::ofstream(path) << text;
    return path.string();
}

const std::string kHead = R"(<gml:LineString srsName="EPSG:54004" xmlns:gml="http://www.opengis.net/gml"><gml:coordinates decimal="." cs="," ts=" ">)";

TEST(Giscup, RoundTripsCoordinatesBitForBit) {
    const std::string text = "7:" + kHead + "68.35270000000001,-0.1 1e-300,5e-324 -7984749.593824852,2 </gml:coordinates></gml:LineString>\n";
    map::MapData map;
    const GiscupLines lines = read_giscup_lines(write_temp("roundtrip.txt", text), map);
    ASSERT_EQ(lines.ids, std::vector<std::string>{"7"});
    ASSERT_EQ(map.vertices.size(), 3u);
    EXPECT_EQ(map.vertices[0].x, 68.35270000000001);
    EXPECT_EQ(map.vertices[1].y, 5e-324);
    std::ostringstream out;
    write_giscup_lines(out, lines, map, {1, 1, 1});
    EXPECT_EQ(out.str(), text);
}

TEST(Giscup, KeepsOnlyKeptVertices) {
    const std::string text = "1:" + kHead + "0,0 1,1 2,0 </gml:coordinates></gml:LineString>\n";
    map::MapData map;
    const GiscupLines lines = read_giscup_lines(write_temp("kept.txt", text), map);
    std::ostringstream out;
    write_giscup_lines(out, lines, map, {1, 0, 1});
    EXPECT_EQ(out.str(), "1:" + kHead + "0,0 2,0 </gml:coordinates></gml:LineString>\n");
}

TEST(Giscup, RejectsMalformedLinesWithTheirLineNumber) {
    map::MapData map;
    const std::string bad_number = write_temp("bad.txt", "1:" + kHead + "0,0 1,x </gml:coordinates></gml:LineString>\n");
    try {
        read_giscup_lines(bad_number, map);
        FAIL() << "expected an InputError";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find(":1: feature 1: bad coordinate '1,x'"), std::string::npos) << error.what();
    }
    const std::string nan = write_temp("nan.txt", "\n2:" + kHead + "0,0 nan,1 </gml:coordinates></gml:LineString>\n");
    EXPECT_THROW(read_giscup_lines(nan, map), InputError);
    const std::string unterminated = write_temp("open.txt", "3:" + kHead + "0,0 1,1\n");
    EXPECT_THROW(read_giscup_lines(unterminated, map), InputError);
    const std::string single = write_temp("single.txt", "4:" + kHead + "0,0 </gml:coordinates></gml:LineString>\n");
    EXPECT_THROW(read_giscup_lines(single, map), InputError);
    EXPECT_THROW(read_giscup_lines("/nonexistent/lines.txt", map), InputError);
}

}  // namespace
}  // namespace toposimp::io
