// Helpers for CLI tests: run toposimp in-process, build small OGR files, read them back.
#pragma once

#include "cli/cli.hpp"
#include "core/geometry.hpp"
#include "support/temp_path.hpp"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <sstream>
#include <string>
#include <vector>

namespace toposimp::testing {

struct CliResult {
    int code;
    std::string out;
    std::string err;
};

inline CliResult run_cli(const std::vector<std::string>& args) {
    std::ostringstream out, err;
    cli::Context context{out, err, false};
    const int code = cli::run(args, context);
    return {code, out.str(), err.str()};
}

// A fresh, empty folder for one test (named after the test too: ctest runs tests in parallel).
inline std::filesystem::path fresh_dir(const std::string& name) {
    std::string unique = name;
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info()) {
        unique += std::string("-") + info->test_suite_name() + "-" + info->name();
    }
    for (char& c : unique) {
        if (c == '/') c = '_';
    }
    const auto dir = testing::temp_path("test-" + unique);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// A TopoJSON text's arcs member (toposimp writes it after the objects, before the bounding box
// that ends the file).
inline std::string arcs_of(const std::string& text) {
    const std::size_t begin = text.rfind("\"arcs\":[["), end = text.find("\"bbox\"", begin);
    return text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

// A line as WKT, every coordinate round-tripping.
inline std::string line_wkt(const std::vector<Point>& points) {
    std::string wkt = "LINESTRING (";
    for (std::size_t i = 0; i < points.size(); ++i) {
        char text[64];
        std::snprintf(text, sizeof text, "%s%.17g %.17g", i ? ", " : "", points[i].x, points[i].y);
        wkt += text;
    }
    return wkt + ")";
}

inline std::string testdata(const std::string& name) { return std::string(TOPOSIMP_SOURCE_DIR) + "/testdata/" + name; }

struct FeatureSpec {
    std::string wkt;  // empty: NULL geometry
    std::string name;
};

// Writes a layer with fields `name` (string) and `rank` (integer = index).
inline void write_layer(const std::string& path, const char* driver_name, OGRwkbGeometryType type,
                        const std::vector<FeatureSpec>& features, const char* layer_name = "lines") {
    GDALAllRegister();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name);
    GDALDataset* dataset = driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
    OGRSpatialReference srs;
    srs.importFromEPSG(32633);
    OGRLayer* layer = dataset->CreateLayer(layer_name, &srs, type, nullptr);
    OGRFieldDefn name_field("name", OFTString), rank_field("rank", OFTInteger);
    (void)layer->CreateField(&name_field);
    (void)layer->CreateField(&rank_field);
    for (std::size_t i = 0; i < features.size(); ++i) {
        OGRFeature feature(layer->GetLayerDefn());
        feature.SetField("name", features[i].name.c_str());
        feature.SetField("rank", static_cast<int>(i));
        if (!features[i].wkt.empty()) {
            OGRGeometry* geometry = nullptr;
            OGRGeometryFactory::createFromWkt(features[i].wkt.c_str(), nullptr, &geometry);
            feature.SetGeometryDirectly(geometry);
        }
        if (layer->CreateFeature(&feature) != OGRERR_NONE) throw std::runtime_error("fixture: CreateFeature failed");
    }
    GDALClose(dataset);
}

struct ReadFeature {
    std::string name;
    int rank = -1;
    std::vector<std::vector<double>> coordinates;  // flattened x,y[,z][,m] per part
    OGRwkbGeometryType type = wkbNone;
    bool null_geometry = true;
};

struct ReadLayer {
    std::string name;
    std::string srs_wkt;
    std::vector<ReadFeature> features;
};

inline ReadLayer read_layer(const std::string& path, int index = 0) {
    GDALAllRegister();
    GDALDatasetUniquePtr dataset(GDALDataset::Open(path.c_str(), GDAL_OF_VECTOR));
    ReadLayer result;
    if (!dataset) return result;
    OGRLayer* layer = dataset->GetLayer(index);
    result.name = layer->GetName();
    if (const OGRSpatialReference* srs = layer->GetSpatialRef()) {
        char* wkt = nullptr;
        srs->exportToWkt(&wkt);
        result.srs_wkt = wkt;
        CPLFree(wkt);
    }
    for (auto& feature : *layer) {
        ReadFeature read;
        const int name_index = feature->GetFieldIndex("name"), rank_index = feature->GetFieldIndex("rank");
        if (name_index >= 0) read.name = feature->GetFieldAsString(name_index);
        if (rank_index >= 0) read.rank = feature->GetFieldAsInteger(rank_index);
        if (const OGRGeometry* geometry = feature->GetGeometryRef()) {
            read.null_geometry = false;
            read.type = geometry->getGeometryType();
            auto add = [&](const OGRLineString& line) {
                std::vector<double> values;
                for (int i = 0; i < line.getNumPoints(); ++i) {
                    values.push_back(line.getX(i));
                    values.push_back(line.getY(i));
                    if (line.Is3D()) values.push_back(line.getZ(i));
                    if (line.IsMeasured()) values.push_back(line.getM(i));
                }
                read.coordinates.push_back(values);
            };
            auto add_polygon = [&](const OGRPolygon& polygon) {
                for (const OGRLinearRing* ring : polygon) add(*ring);
            };
            switch (wkbFlatten(read.type)) {
                case wkbLineString: add(*geometry->toLineString()); break;
                case wkbMultiLineString:
                    for (const OGRLineString* part : *geometry->toMultiLineString()) add(*part);
                    break;
                case wkbPolygon: add_polygon(*geometry->toPolygon()); break;
                case wkbMultiPolygon:
                    for (const OGRPolygon* part : *geometry->toMultiPolygon()) add_polygon(*part);
                    break;
                case wkbPoint: {
                    const OGRPoint& point = *geometry->toPoint();
                    if (!point.IsEmpty()) read.coordinates.push_back({point.getX(), point.getY()});
                    break;
                }
                default: break;
            }
        }
        result.features.push_back(read);
    }
    return result;
}

// Files left in a folder (to prove a failed run left nothing behind).
inline std::vector<std::string> files_in(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename().string());
    return names;
}

}  // namespace toposimp::testing
