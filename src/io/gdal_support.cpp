#include "io/gdal_support.hpp"

#include "io/errors.hpp"

#include <cpl_error.h>

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

DatasetPtr open_vector(const std::string& path) {
    register_drivers();
    QuietGdal quiet;
    auto* dataset = static_cast<GDALDataset*>(
        GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
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

}  // namespace toposimp::io
