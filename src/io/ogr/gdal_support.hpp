// Small GDAL helpers shared by the adapters: driver registration, quiet error handling,
// opening vector datasets with clear errors, and labels naming file, layer and feature.
#pragma once

#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <memory>
#include <string>

namespace toposimp::io {

void register_drivers();

// Silences GDAL's own printing for a scope; its messages are read with last_gdal_error().
class QuietGdal {
public:
    QuietGdal();
    ~QuietGdal();
    QuietGdal(const QuietGdal&) = delete;
    QuietGdal& operator=(const QuietGdal&) = delete;
};

// ": message" of GDAL's last error, or "" if there is none.
std::string last_gdal_error();

struct DatasetCloser {
    void operator()(GDALDataset* dataset) const { GDALClose(dataset); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

// Opens a vector dataset read-only; InputError saying why if it cannot. With `driver`, only
// that driver is tried (no probing of the others).
DatasetPtr open_vector(const std::string& path, const char* driver = nullptr);

// The vector driver for an output: `format` by name, or else from the path's extension;
// OutputError if there is none that can create files.
GDALDriver* vector_driver_for(const std::string& path, const std::string& format);

// "name1, name2, …" (or "none").
std::string layer_names(GDALDataset& dataset);

// The named layer (empty: the first); InputError listing the layers if there is none.
OGRLayer& pick_layer(GDALDataset& dataset, const std::string& path, const std::string& name);

// "'path', layer 'name', feature 12"
std::string feature_label(const std::string& path, OGRLayer& layer, GIntBig fid);

}  // namespace toposimp::io
