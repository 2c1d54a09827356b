#include "io/ogr/gdal_support.hpp"

#include "io/ogr/gdal_env.hpp"
#include "io/ogr/map_formats.hpp"

#include "io/common/errors.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>

#include <algorithm>
#include <filesystem>
#include <mutex>

namespace toposimp::io {

void register_drivers() {
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
}

QuietGdal::QuietGdal() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
}

QuietGdal::~QuietGdal() { CPLPopErrorHandler(); }

std::string last_gdal_error() {
    const char* message = CPLGetLastErrorMsg();
    return message && *message ? std::string(": ") + message : std::string();
}

DatasetPtr open_vector(const std::string& path, const char* driver) {
    register_drivers();
    QuietGdal quiet;
    const char* const only[] = {driver, nullptr};
    auto* dataset = static_cast<GDALDataset*>(
        GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, driver != nullptr ? only : nullptr, nullptr, nullptr));
    if (dataset == nullptr) {
        std::error_code error;
        if (path.rfind("/vsi", 0) != 0 && !std::filesystem::exists(path, error)) {
            throw InputError("cannot open '" + path + "': no such file");
        }
        throw InputError("cannot open '" + path + "' as a vector dataset" + last_gdal_error());
    }
    return DatasetPtr(dataset);
}

std::string layer_names(GDALDataset& dataset) {
    std::string names;
    for (int i = 0; i < dataset.GetLayerCount(); ++i) {
        names += (i ? ", " : "") + std::string(dataset.GetLayer(i)->GetName());
    }
    return names.empty() ? "none" : names;
}

OGRLayer& pick_layer(GDALDataset& dataset, const std::string& path, const std::string& name) {
    if (dataset.GetLayerCount() == 0) throw InputError("'" + path + "' has no vector layer");
    if (name.empty()) return *dataset.GetLayer(0);
    OGRLayer* layer = dataset.GetLayerByName(name.c_str());
    if (layer == nullptr) {
        throw InputError("'" + path + "' has no layer '" + name + "' (layers: " + layer_names(dataset) + ")");
    }
    return *layer;
}

std::string feature_label(const std::string& path, OGRLayer& layer, GIntBig fid) {
    return "'" + path + "', layer '" + std::string(layer.GetName()) + "', feature " + std::to_string(fid);
}

GDALDriver* vector_driver_for(const std::string& path, const std::string& format) {
    register_drivers();
    GDALDriverManager& drivers = *GetGDALDriverManager();
    std::string name = format;
    if (name.empty()) {
        std::string extension = std::filesystem::path(path).extension().string();
        if (!extension.empty()) extension.erase(0, 1);
        std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
        if (const char* known = map_driver_for_extension(extension)) name = known;
        for (int i = 0; name.empty() && i < drivers.GetDriverCount(); ++i) {
            GDALDriver* driver = drivers.GetDriver(i);
            const char* extensions = driver->GetMetadataItem(GDAL_DMD_EXTENSIONS);
            if (!extensions || !driver->GetMetadataItem(GDAL_DCAP_VECTOR) || !driver->GetMetadataItem(GDAL_DCAP_CREATE)) {
                continue;
            }
            const CPLStringList list(CSLTokenizeString(extensions));
            if (!extension.empty() && list.FindString(extension.c_str()) >= 0) name = driver->GetDescription();
        }
        if (name.empty()) {
            throw OutputError("cannot tell the output format of '" + path + "' from its extension; name it with -f (e.g. -f GPKG)");
        }
    }
    GDALDriver* driver = drivers.GetDriverByName(name.c_str());
    if (driver == nullptr || !driver->GetMetadataItem(GDAL_DCAP_VECTOR)) {
        throw OutputError("unknown vector output format '" + name + "' (see `ogrinfo --formats`)");
    }
    const MapFormatRules* rules = map_format_rules(driver->GetDescription());
    if (!driver->GetMetadataItem(GDAL_DCAP_CREATE) && !(rules && rules->own_writer)) {
        throw OutputError("GDAL cannot create '" + name + "' files");
    }
    return driver;
}


void set_config_options(const std::vector<std::pair<std::string, std::string>>& options) {
    for (const auto& [key, value] : options) CPLSetConfigOption(key.c_str(), value.c_str());
}

void check_vector_output(const std::string& path, const std::string& format) { vector_driver_for(path, format); }

bool is_topojson_output(const std::string& path, const std::string& format) {
    return vector_driver_for(path, format)->GetDescription() == std::string("TopoJSON");
}

bool is_shapefile_output(const std::string& path, const std::string& format) {
    return vector_driver_for(path, format)->GetDescription() == std::string("ESRI Shapefile");
}

std::string gdal_version() { return GDALVersionInfo("RELEASE_NAME"); }

}  // namespace toposimp::io
