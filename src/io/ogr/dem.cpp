#include "io/ogr/dem.hpp"

#include "io/common/errors.hpp"
#include "io/ogr/gdal_support.hpp"

#include <cmath>
#include <limits>
#include <vector>

namespace toposimp::io {

Dem read_dem(const std::string& path, int band_number) {
    register_drivers();
    QuietGdal quiet;
    DatasetPtr dataset(static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
    if (!dataset) {
        throw InputError(path + ": neither a mesh (.obj, .ply, .off, .stl) nor a raster GDAL can open" + last_gdal_error());
    }
    if (band_number < 1 || band_number > dataset->GetRasterCount()) {
        throw InputError(path + ": no band " + std::to_string(band_number) + " (the raster has " +
                         std::to_string(dataset->GetRasterCount()) + ")");
    }
    GDALRasterBand* band = dataset->GetRasterBand(band_number);
    Dem dem;
    dem.width = dataset->GetRasterXSize();
    dem.height = dataset->GetRasterYSize();
    if (dem.width < 2 || dem.height < 2) throw InputError(path + ": a DEM needs at least 2 x 2 cells");
    if (static_cast<double>(dem.width) * dem.height > 4e9) throw InputError(path + ": too many cells for one TIN");
    double gt[6] = {0, 1, 0, 0, 0, 1};
    const bool georeferenced = dataset->GetGeoTransform(gt) == CE_None;
    if (!georeferenced) gt[5] = -1;  // no geotransform: pixel coordinates, north up
    if (const OGRSpatialReference* srs = dataset->GetSpatialRef()) {
        char* wkt = nullptr;
        srs->exportToWkt(&wkt);
        if (wkt) dem.crs_wkt = wkt;
        CPLFree(wkt);
    }
    int has_nodata = 0;
    const double nodata = band->GetNoDataValue(&has_nodata);
    const auto w = static_cast<std::size_t>(dem.width), h = static_cast<std::size_t>(dem.height);
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> id(w * h, kNone);
    std::vector<double> row(w);
    for (std::size_t j = 0; j < h; ++j) {
        if (band->RasterIO(GF_Read, 0, static_cast<int>(j), dem.width, 1, row.data(), dem.width, 1, GDT_Float64, 0, 0) != CE_None) {
            throw InputError(path + ": cannot read row " + std::to_string(j) + last_gdal_error());
        }
        for (std::size_t i = 0; i < w; ++i) {
            const double z = row[i];
            if (!std::isfinite(z) || (has_nodata && z == nodata)) {
                ++dem.nodata_cells;
                continue;
            }
            const double px = static_cast<double>(i) + 0.5, py = static_cast<double>(j) + 0.5;
            id[j * w + i] = static_cast<std::uint32_t>(dem.tin.points.size());
            dem.tin.points.push_back({gt[0] + px * gt[1] + py * gt[2], gt[3] + px * gt[4] + py * gt[5], z});
        }
    }
    // Counter-clockwise in the map plane: pixel order (i, j) → (i+1, j) → (i+1, j+1) turns the way
    // the geotransform's determinant says.
    const bool flip = gt[1] * gt[5] - gt[2] * gt[4] < 0;
    auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        dem.tin.faces.push_back(flip ? mesh::Face{a, c, b} : mesh::Face{a, b, c});
    };
    for (std::size_t j = 0; j + 1 < h; ++j) {
        for (std::size_t i = 0; i + 1 < w; ++i) {
            const std::uint32_t a = id[j * w + i], b = id[j * w + i + 1], c = id[(j + 1) * w + i + 1], d = id[(j + 1) * w + i];
            const int valid = (a != kNone) + (b != kNone) + (c != kNone) + (d != kNone);
            if (valid == 4) {
                add(a, b, c);
                add(a, c, d);
            } else if (valid == 3) {
                if (a == kNone) add(b, c, d);
                if (b == kNone) add(a, c, d);
                if (c == kNone) add(a, b, d);
                if (d == kNone) add(a, b, c);
            }
        }
    }
    return dem;
}

void write_tin_layer(const mesh::Mesh& tin, const std::string& path, const std::string& driver_name, const std::string& crs_wkt,
                     const std::string& layer_name) {
    register_drivers();
    QuietGdal quiet;
    GDALDriver* driver = vector_driver_for(path, driver_name);
    DatasetPtr dataset(driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!dataset) throw OutputError(path + ": cannot create" + last_gdal_error());
    OGRSpatialReference srs;
    const bool has_crs = !crs_wkt.empty() && srs.importFromWkt(crs_wkt.c_str()) == OGRERR_NONE;
    if (has_crs) srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    OGRLayer* layer = dataset->CreateLayer(layer_name.c_str(), has_crs ? &srs : nullptr, wkbPolygon25D, nullptr);
    if (!layer) throw OutputError(path + ": cannot create layer '" + layer_name + "'" + last_gdal_error());
    // Drivers without transactions write directly; their refusal to start one is not an error.
    const bool transaction = layer->StartTransaction() == OGRERR_NONE;
    for (const mesh::Face& f : tin.faces) {
        OGRLinearRing ring;
        for (int k = 0; k <= 3; ++k) {
            const Point3& p = tin.points[f[k % 3]];
            ring.addPoint(p.x, p.y, p.z);
        }
        OGRPolygon polygon;
        polygon.addRing(&ring);
        OGRFeature feature(layer->GetLayerDefn());
        feature.SetGeometry(&polygon);
        if (layer->CreateFeature(&feature) != OGRERR_NONE) throw OutputError(path + ": cannot write a triangle" + last_gdal_error());
    }
    if (transaction && layer->CommitTransaction() != OGRERR_NONE) throw OutputError(path + ": cannot commit" + last_gdal_error());
    dataset.reset();
}

}  // namespace toposimp::io
