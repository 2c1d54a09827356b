// Benchmark driver for GEOS's CoverageSimplifier (GEOS ≥ 3.12, built by build-geos.sh): reads a
// polygon layer with GDAL, simplifies all its polygons together as one coverage
// (GEOSCoverageSimplifyVW, area tolerance = tolerance²), writes them with their attributes to a
// new file of the same kind, and prints the phases' seconds and the vertex counts as JSON.
// A baseline for scripts/bench/run.py; nothing of toposimp uses it.
//
//   coverage_simplify INPUT OUTPUT TOLERANCE
#include <gdal.h>
#include <geos_c.h>
#include <ogr_api.h>

#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

void fail(const char* what) {
    std::fprintf(stderr, "coverage_simplify: %s\n", what);
    std::exit(2);
}

void geos_message(const char* format, ...) {
    va_list args;
    va_start(args, format);
    std::vfprintf(stderr, format, args);
    va_end(args);
    std::fputc('\n', stderr);
}

double since(std::chrono::steady_clock::time_point& start) {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - start).count();
    start = now;
    return seconds;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) fail("usage: coverage_simplify INPUT OUTPUT TOLERANCE");
    const double tolerance = std::atof(argv[3]);
    GDALAllRegister();
    GEOSContextHandle_t geos = GEOS_init_r();
    GEOSContext_setErrorHandler_r(geos, geos_message);
    auto start = std::chrono::steady_clock::now();

    GDALDatasetH in = GDALOpenEx(argv[1], GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
    if (!in) fail("cannot open the input");
    OGRLayerH layer = GDALDatasetGetLayer(in, 0);
    std::vector<GEOSGeometry*> parts;
    std::vector<OGRFeatureH> features;
    std::vector<unsigned char> wkb;
    OGR_L_ResetReading(layer);
    for (OGRFeatureH feature; (feature = OGR_L_GetNextFeature(layer)) != nullptr;) {
        OGRGeometryH geometry = OGR_F_GetGeometryRef(feature);
        if (!geometry) {
            OGR_F_Destroy(feature);
            continue;
        }
        wkb.resize(static_cast<std::size_t>(OGR_G_WkbSize(geometry)));
        OGR_G_ExportToIsoWkb(geometry, wkbNDR, wkb.data());
        GEOSGeometry* g = GEOSGeomFromWKB_buf_r(geos, wkb.data(), wkb.size());
        if (!g) fail("a geometry GEOS cannot read");
        parts.push_back(g);
        features.push_back(feature);
    }
    GEOSGeometry* coverage = GEOSGeom_createCollection_r(geos, GEOS_GEOMETRYCOLLECTION, parts.data(), static_cast<unsigned>(parts.size()));
    const int vertices_in = GEOSGetNumCoordinates_r(geos, coverage);
    const double read = since(start);

    GEOSGeometry* simplified = GEOSCoverageSimplifyVW_r(geos, coverage, tolerance, 0);
    if (!simplified) fail("GEOSCoverageSimplifyVW failed");
    const double simplify = since(start);
    const int vertices_out = GEOSGetNumCoordinates_r(geos, simplified);

    GDALDriverH driver = GDALGetDatasetDriver(in);
    GDALDatasetH out = GDALCreate(driver, argv[2], 0, 0, 0, GDT_Unknown, nullptr);
    if (!out) fail("cannot create the output");
    OGRLayerH written = GDALDatasetCreateLayer(out, OGR_L_GetName(layer), OGR_L_GetSpatialRef(layer), OGR_L_GetGeomType(layer), nullptr);
    OGRFeatureDefnH definition = OGR_L_GetLayerDefn(layer);
    for (int k = 0; k < OGR_FD_GetFieldCount(definition); ++k) OGR_L_CreateField(written, OGR_FD_GetFieldDefn(definition, k), 1);
    if (OGR_L_StartTransaction(written) != OGRERR_NONE) fail("cannot start a transaction");
    for (std::size_t k = 0; k < features.size(); ++k) {
        const GEOSGeometry* g = GEOSGetGeometryN_r(geos, simplified, static_cast<int>(k));
        std::size_t size = 0;
        GEOSWKBWriter* writer = GEOSWKBWriter_create_r(geos);
        unsigned char* bytes = GEOSWKBWriter_write_r(geos, writer, g, &size);
        GEOSWKBWriter_destroy_r(geos, writer);
        OGRGeometryH geometry = nullptr;
        OGR_G_CreateFromWkb(bytes, nullptr, &geometry, static_cast<int>(size));
        GEOSFree_r(geos, bytes);
        if (OGR_G_GetGeometryType(geometry) == wkbPolygon && OGR_L_GetGeomType(layer) == wkbMultiPolygon) {
            geometry = OGR_G_ForceToMultiPolygon(geometry);
        }
        OGRFeatureH feature = OGR_F_Create(OGR_L_GetLayerDefn(written));
        for (int f = 0; f < OGR_FD_GetFieldCount(definition); ++f) {
            if (OGR_F_IsFieldSetAndNotNull(features[k], f)) OGR_F_SetFieldString(feature, f, OGR_F_GetFieldAsString(features[k], f));
        }
        OGR_F_SetGeometryDirectly(feature, geometry);
        if (OGR_L_CreateFeature(written, feature) != OGRERR_NONE) fail("cannot write a feature");
        OGR_F_Destroy(feature);
        OGR_F_Destroy(features[k]);
    }
    if (OGR_L_CommitTransaction(written) != OGRERR_NONE) fail("cannot commit the features");
    GDALClose(out);
    GDALClose(in);
    const double write = since(start);
    GEOSGeom_destroy_r(geos, coverage);
    GEOSGeom_destroy_r(geos, simplified);
    GEOS_finish_r(geos);
    std::printf("{\"vertices_in\":%d,\"vertices_out\":%d,\"seconds\":{\"read\":%.6f,\"simplify\":%.6f,\"write\":%.6f}}\n",
                vertices_in, vertices_out, read, simplify, write);
    return 0;
}
