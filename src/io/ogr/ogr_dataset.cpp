#include "io/ogr/ogr_dataset.hpp"

#include "core/map/coverage.hpp"
#include "io/common/errors.hpp"
#include "io/common/output_file.hpp"
#include "io/map/gpkg_points.hpp"
#include "io/map/shapefile.hpp"
#include "io/ogr/gdal_support.hpp"
#include "io/ogr/geojson_writer.hpp"
#include "io/ogr/topojson_writer.hpp"
#include "io/ogr/map_formats.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <unordered_map>

namespace toposimp::io {
namespace {

constexpr std::uint32_t kEmptyPart = std::numeric_limits<std::uint32_t>::max();

// The .shp's size in bytes (the largest value where it cannot be read).
std::uintmax_t shapefile_size(const std::string& path) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    return error ? std::numeric_limits<std::uintmax_t>::max() : size;
}

// Polygon Shapefiles up to this size are decoded here when read whole (OgrDataset::Data::read_layer).
constexpr std::uintmax_t kPolygonsDecodedUpTo = std::uintmax_t{64} << 20;

// A .shp file on disk (not behind /vsi…), which the readers of shapefile.hpp can decode.
bool is_local_shp(const std::string& path) {
    const std::string extension = std::filesystem::path(path).extension().string();
    return (extension == ".shp" || extension == ".SHP") && path.rfind("/vsi", 0) != 0;
}

// A layer that cannot be left in its file (OgrDataset::read's vertices_in_file): the dataset is
// read again, whole. `why` says which and why, for -v (DatasetSummary::read_whole_because).
struct NotInFile {
    std::string why;
};

// The file of layer `name` of the dataset at `path`, a `lower` (".shp", ".fgb") or `upper` file:
// `path` itself if it is one on disk (not behind /vsi…), the layer's file if `path` is a folder
// of them; "" otherwise.
std::string layer_file(const std::string& path, const std::string& name, const char* lower, const char* upper) {
    std::error_code error;
    if (path.rfind("/vsi", 0) == 0) return {};
    const std::string extension = std::filesystem::path(path).extension().string();
    if ((extension == lower || extension == upper) && std::filesystem::is_regular_file(path, error)) return path;
    if (!std::filesystem::is_directory(path, error)) return {};
    for (const char* ending : {lower, upper}) {
        const std::filesystem::path file = std::filesystem::path(path) / (name + ending);
        if (std::filesystem::is_regular_file(file, error)) return file.string();
    }
    return {};
}

// The .shp of layer `name` of the dataset at `path` (layer_file).
std::string layer_shp(const std::string& path, const std::string& name) { return layer_file(path, name, ".shp", ".SHP"); }

// A GeoPackage file on disk (not behind /vsi…): its layers may be left in it, read through OGR by
// FID ranges (FeatureRun).
bool is_local_gpkg(const std::string& path) {
    std::error_code error;
    return path.rfind("/vsi", 0) != 0 && std::filesystem::is_regular_file(path, error);
}

// A layer's file as VerticesInFile keeps it: where it is (absolute: other processes read it),
// its size and modification time.
LayerInFile layer_in_file(const std::string& shp, const std::string& layer, std::uintmax_t size) {
    LayerInFile planned;
    planned.path = std::filesystem::absolute(shp).string();
    planned.layer = layer;
    planned.size = size;
    planned.time = modified_ns(shp);
    return planned;
}

// The error for a feature (or a Shapefile's record) of a layer left in its file that is not, read
// again, what it was when the map was read.
InputError changed_while_running(const LayerInFile& layer, std::size_t index, const char* what = "feature") {
    return InputError("'" + layer.path + "' changed while toposimp ran: " + what + " " + std::to_string(index) +
                      " is not what it was when it was read; nothing written");
}

// Is a layer's file still what it was when it was read (its size and modification time)?
bool unchanged(const LayerInFile& layer) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(layer.path, error);
    return !error && size == layer.size && modified_ns(layer.path) == layer.time;
}

// The machine's memory in bytes (0 if unknown).
std::uint64_t machine_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
}

// Memory for a coverage plan's node passes (map::Coverage::plan, 56 bytes a ring point) over
// files of `file_bytes`: about as much as the files (a quarter of the ring points of a .shp, 16
// bytes each, a pass: on a 1.9 M-vertex coverage, 2 to 4 passes took no more time than one and
// the command's peak fell from 299 to 177 MiB), from 16 MiB to an eighth of the machine's.
std::size_t coverage_pass_bytes(std::uintmax_t file_bytes) {
    const std::uint64_t most = std::max<std::uint64_t>(machine_memory() / 8, std::uint64_t{16} << 20);
    return static_cast<std::size_t>(std::clamp<std::uint64_t>(file_bytes, std::uint64_t{16} << 20, most));
}

}  // namespace

std::uint64_t DatasetSummary::sum(std::uint64_t LayerSummary::*field) const {
    std::uint64_t total = 0;
    for (const LayerSummary& layer : layers) total += layer.*field;
    return total;
}

std::uint64_t DatasetSummary::features() const { return sum(&LayerSummary::features); }

// Where vertex v of the map is for build_geometry: data[v - first] (the map's own vertices, or
// one record of a map whose vertices are in a file).
struct VertexView {
    const Point* data;
    std::size_t first = 0;
    Point operator[](std::size_t v) const { return data[v - first]; }
    // A feature's rings read again (a polygon layer left in its file): ring id r is
    // (*rings)[r - first_ring]; the map's vertices are not there.
    const std::vector<std::vector<Point>>* rings = nullptr;
    std::uint32_t first_ring = 0;
    const LayerInFile* file = nullptr;  // (with rings, or a feature's lines read through OGR: where they are)
    // A feature's lines read again through OGR: their Z and M beside `data` (nullptr: none).
    const double* z = nullptr;
    const double* m = nullptr;
    // A feature's rings read again: their Z and M, per ring and point (nullptr: none).
    const std::vector<std::vector<double>>* ring_z = nullptr;
    const std::vector<std::vector<double>>* ring_m = nullptr;
};

class VertexCursor;

struct OgrDataset::Data {
    struct Layer {
        // What a feature's geometry became: chains (lines), coverage rings (polygons), or an
        // untouched copy (points, which also serve as obstacles).
        enum class Kind : std::uint8_t { null, lines, polygons, untouched };
        struct Shape {
            OGRwkbGeometryType type = wkbUnknown;  // the feature's own type, with Z/M flags
            Kind kind = Kind::null;
            std::uint32_t first = 0;  // lines: into items (chain per part); polygons: into items
            std::uint32_t count = 0;  //   (ring count, then ring ids, per polygon); untouched: into untouched
        };

        std::string name;
        std::string fid_column;
        OGRwkbGeometryType geometry_type = wkbUnknown;
        std::unique_ptr<OGRSpatialReference> srs;
        std::filesystem::path prj;  // instead of srs: the input's .prj, written out as it is
        OGRFeatureDefn* definition = nullptr;       // reference-counted
        std::vector<OGRFeatureUniquePtr> features;  // attributes only: geometries are in the map
        std::vector<Shape> shapes;
        std::vector<std::uint32_t> items;
        std::vector<std::unique_ptr<OGRGeometry>> untouched;
        std::vector<std::uint32_t> untouched_points;  // per untouched geometry: its first control point

        Layer() = default;
        Layer(const Layer&) = delete;
        Layer& operator=(const Layer&) = delete;
        ~Layer() {
            if (definition) definition->Release();
        }
    };

    DatasetSummary summary;
    std::vector<std::unique_ptr<Layer>> layers;
    map::Coverage coverage;              // rings of every layer: borders shared across layers too
    bool carries_zm = false;             // some layer has Z or M
    bool points_moved = false;           // move_points() put the point features elsewhere
    std::vector<double> z, m;            // per map vertex, when carries_zm
    std::vector<double> ring_z, ring_m;  // per coverage ring point, until the coverage is built
    std::optional<VerticesInFile> in_file;  // the map's vertices left in the files (then every layer's)
    std::uint32_t in_file_rings = 0;        // the polygon rings of the layers left in their files so far

    void start_carrying_zm(const map::MapData& map) {
        if (carries_zm) return;
        carries_zm = true;
        z.assign(map.vertices.size(), 0.0);
        m.assign(map.vertices.size(), 0.0);
        ring_z.assign(coverage.point_count(), 0.0);
        ring_m.assign(coverage.point_count(), 0.0);
    }

    void read_layer(const std::string& path, OGRLayer& source, map::MapData& map, bool prj_as_file, bool leave_in_file);
    void read_memory_layer(const std::string& source, const MemoryLayer& given, map::MapData& map);
    void add_geometry(Layer& layer, Layer::Shape& shape, LayerSummary& summary_of_layer, const OGRGeometry& geometry,
                      const std::string& label, map::MapData& map);
    void finish(const std::string& path, map::MapData& map);
    void plan_coverage_in_files(map::MapData& map);
    // The vertices of `layer`'s features, feature after feature (VertexCursor).
    VertexCursor vertex_cursor(const map::MapData& map, const Layer& layer) const;

    // `arc_order`: rings start where their first arc does (as a TopoJSON reader rebuilds them).
    std::unique_ptr<OGRGeometry> build_geometry(const Layer& layer, std::size_t index, const map::MapData& map,
                                                const std::vector<std::uint8_t>& kept, bool arc_order = false) const {
        return build_geometry(layer, index, map, VertexView{map.vertices.data()}, kept, arc_order);
    }
    std::unique_ptr<OGRGeometry> build_geometry(const Layer& layer, std::size_t index, const map::MapData& map, VertexView vertices,
                                                const std::vector<std::uint8_t>& kept, bool arc_order = false) const;

    // The geometry as TopoJSON arc references: arc i is map chain i.
    TopoGeometry topo_geometry(const Layer& layer, std::size_t index) const;
};

namespace {

std::vector<Point> read_points(const OGRSimpleCurve& curve, const std::string& label) {
    const int count = curve.getNumPoints();
    std::vector<Point> points(count);
    for (int i = 0; i < count; ++i) {
        points[i] = {curve.getX(i), curve.getY(i)};
        if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
            throw InputError(label + ": vertex " + std::to_string(i) + " has a non-finite coordinate (" +
                             std::to_string(points[i].x) + ", " + std::to_string(points[i].y) + ")");
        }
    }
    return points;
}

void append_zm(const OGRSimpleCurve& curve, std::vector<double>& z, std::vector<double>& m) {
    for (int i = 0; i < curve.getNumPoints(); ++i) {
        z.push_back(curve.Is3D() ? curve.getZ(i) : 0.0);
        m.push_back(curve.IsMeasured() ? curve.getM(i) : 0.0);
    }
}

std::uint32_t add_line(OgrDataset::Data& data, OgrDataset::Data::Layer& layer, const OGRSimpleCurve& curve, map::MapData& map,
                       const std::string& label) {
    if (curve.getNumPoints() == 0) return kEmptyPart;
    if (map.vertices.size() + curve.getNumPoints() > std::numeric_limits<std::uint32_t>::max() / 2) {
        throw InputError(label + ": more than 2 billion vertices in one map");
    }
    const std::uint32_t chain = map.add_chain(read_points(curve, label));
    (void)layer;
    if (data.carries_zm) append_zm(curve, data.z, data.m);
    return chain;
}

void add_polygon(OgrDataset::Data& data, OgrDataset::Data::Layer& layer, const OGRPolygon& polygon, const std::string& label) {
    std::vector<const OGRLinearRing*> rings;
    for (const OGRLinearRing* ring : polygon) {
        if (!ring->IsEmpty()) rings.push_back(ring);
    }
    layer.items.push_back(static_cast<std::uint32_t>(rings.size()));
    for (const OGRLinearRing* ring : rings) {
        layer.items.push_back(data.coverage.add_ring(read_points(*ring, label)));
        if (data.carries_zm) append_zm(*ring, data.ring_z, data.ring_m);
    }
}

void set_point(OGRSimpleCurve& line, int i, Point p, bool with_z, bool with_m, double z, double m) {
    if (with_z && with_m) {
        line.setPoint(i, p.x, p.y, z, m);
    } else if (with_z) {
        line.setPoint(i, p.x, p.y, z);
    } else if (with_m) {
        line.setPointM(i, p.x, p.y, m);
    } else {
        line.setPoint(i, p.x, p.y);
    }
}

// A folder in GDAL's memory file system, removed with what it holds when it goes.
class MemoryFolder {
public:
    MemoryFolder() {
        static std::atomic<unsigned> count{0};
        path_ = "/vsimem/toposimp-" + std::to_string(getpid()) + "-" + std::to_string(count++);
        VSIMkdir(path_.c_str(), 0755);
    }
    ~MemoryFolder() { VSIRmdirRecursive(path_.c_str()); }
    MemoryFolder(const MemoryFolder&) = delete;
    MemoryFolder& operator=(const MemoryFolder&) = delete;
    const std::string& path() const { return path_; }

    // Copies every file to `folder` on disk, in one write each; `shown_as` names the output in errors.
    void copy_to(const std::filesystem::path& folder, const std::string& shown_as) const {
        const CPLStringList names(VSIReadDir(path_.c_str()));
        for (int k = 0; k < names.size(); ++k) {
            const std::string name = names[k];
            vsi_l_offset length = 0;
            const GByte* bytes = VSIGetMemFileBuffer((path_ + "/" + name).c_str(), &length, FALSE);
            if (bytes == nullptr) continue;  // (a folder)
            std::ofstream out(folder / name, std::ios::binary);
            out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(length));
            out.close();
            // (The reason, "No space left on device" say, not just that it failed.)
            if (!out) throw OutputError("cannot write '" + shown_as + "': " + std::strerror(errno));
        }
    }

private:
    std::string path_;
};

// The parts of a (Multi)LineString (with Z or M or not), each a chain of the map if it is not
// empty (add_geometry); false for any other geometry.
bool line_parts(const OGRGeometry& geometry, std::vector<const OGRLineString*>& parts) {
    parts.clear();
    if (wkbFlatten(geometry.getGeometryType()) == wkbLineString) {
        parts.push_back(geometry.toLineString());
    } else if (wkbFlatten(geometry.getGeometryType()) == wkbMultiLineString) {
        for (const OGRLineString* part : *geometry.toMultiLineString()) parts.push_back(part);
    } else {
        return false;
    }
    return true;
}

// Part k of a .shp record as a Line (OGRLineString or OGRLinearRing), with Z if the record has it.
template <class Line>
std::unique_ptr<Line> record_part(const ShapeRecord& record, std::size_t k) {
    const std::size_t first = record.part_starts[k];
    const std::size_t end = k + 1 < record.part_starts.size() ? record.part_starts[k + 1] : record.xy.size();
    auto line = std::make_unique<Line>();
    line->setNumPoints(static_cast<int>(end - first), FALSE);
    for (std::size_t j = first; j < end; ++j) {
        const auto at = static_cast<int>(j - first);
        if (record.z.empty()) {
            line->setPoint(at, record.xy[j].x, record.xy[j].y);
        } else {
            line->setPoint(at, record.xy[j].x, record.xy[j].y, record.z[j]);
        }
    }
    return line;
}

// A .shp record's shape as OGR reads a PolyLine: one part a LineString, more a
// MultiLineString.
std::unique_ptr<OGRGeometry> shape_geometry(const ShapeRecord& record) {
    auto part = [&](std::size_t k) { return record_part<OGRLineString>(record, k); };
    if (record.part_starts.size() == 1) return part(0);
    auto lines = std::make_unique<OGRMultiLineString>();
    for (std::size_t k = 0; k < record.part_starts.size(); ++k) lines->addGeometryDirectly(part(k).release());
    return lines;
}

// A 2D Polygon record's shape as OGR's Shapefile driver (GDAL 3.6) reads it: no part, no geometry;
// one, a Polygon of that ring; more, a ring a Polygon, put together by
// OGRGeometryFactory::organizePolygons with METHOD=ONLY_CCW, the driver's call. Built here, OGR
// hands out no geometry, and so never parses the layer's .prj (PROJ opening proj.db: Natural
// Earth's read 0.111 -> 0.096 s) where the output carries it as a file.
std::unique_ptr<OGRGeometry> polygon_geometry(const ShapeRecord& record) {
    const std::size_t parts = record.part_starts.size();
    auto ring = [&](std::size_t k) { return record_part<OGRLinearRing>(record, k); };
    if (parts == 0) return nullptr;
    if (parts == 1) {
        auto polygon = std::make_unique<OGRPolygon>();
        polygon->addRingDirectly(ring(0).release());
        return polygon;
    }
    std::vector<OGRGeometry*> polygons(parts);
    for (std::size_t k = 0; k < parts; ++k) {
        auto polygon = std::make_unique<OGRPolygon>();
        polygon->addRingDirectly(ring(k).release());
        polygons[k] = polygon.release();
    }
    int valid = FALSE;
    const char* options[] = {"METHOD=ONLY_CCW", nullptr};
    return std::unique_ptr<OGRGeometry>(
        OGRGeometryFactory::organizePolygons(polygons.data(), static_cast<int>(parts), &valid, options));
}

}  // namespace

namespace {

// (Multi)Point, with Z or M or not.
bool is_point_type(OGRwkbGeometryType type) {
    return wkbFlatten(type) == wkbPoint || wkbFlatten(type) == wkbMultiPoint;
}

// A feature in its layer's counts: empty (or NULL), polygons, lines.
void count_feature(LayerSummary& summary_of_layer, const OgrDataset::Data::Layer::Shape& shape, bool empty) {
    if (empty) {
        ++summary_of_layer.empty_geometries;
    } else if (shape.kind == OgrDataset::Data::Layer::Kind::polygons) {
        ++summary_of_layer.polygon_features;
    } else if (shape.kind == OgrDataset::Data::Layer::Kind::lines) {
        ++summary_of_layer.line_features;
    }
}

}  // namespace

// A feature's geometry into the map: lines as chains, polygon rings into the coverage, points as
// control points (kept as they are for writing back); `shape` says which, for writing.
void OgrDataset::Data::add_geometry(Layer& layer, Layer::Shape& shape, LayerSummary& summary_of_layer, const OGRGeometry& geometry,
                                    const std::string& label, map::MapData& map) {
    shape.type = geometry.getGeometryType();
    if (geometry.Is3D() || geometry.IsMeasured()) {
        // A layer declared 2D may hold 3D features: keep their Z/M too (a point's are in its
        // geometry, kept as it is).
        summary_of_layer.has_z = summary_of_layer.has_z || geometry.Is3D();
        summary_of_layer.has_m = summary_of_layer.has_m || geometry.IsMeasured();
        if (!is_point_type(shape.type)) start_carrying_zm(map);
    }
    switch (wkbFlatten(shape.type)) {
        case wkbLineString:
            shape.kind = Layer::Kind::lines;
            layer.items.push_back(add_line(*this, layer, *geometry.toLineString(), map, label));
            break;
        case wkbMultiLineString:
            shape.kind = Layer::Kind::lines;
            for (const OGRLineString* part : *geometry.toMultiLineString()) {
                layer.items.push_back(add_line(*this, layer, *part, map, label));
            }
            break;
        case wkbPolygon:
            shape.kind = Layer::Kind::polygons;
            add_polygon(*this, layer, *geometry.toPolygon(), label);
            break;
        case wkbMultiPolygon:
            shape.kind = Layer::Kind::polygons;
            for (const OGRPolygon* polygon : *geometry.toMultiPolygon()) add_polygon(*this, layer, *polygon, label);
            break;
        case wkbPoint:
        case wkbMultiPoint: {
            // Points among lines: written back untouched, kept on their side as control points.
            shape.kind = Layer::Kind::untouched;
            shape.first = static_cast<std::uint32_t>(layer.untouched.size());
            shape.count = 1;
            layer.untouched_points.push_back(static_cast<std::uint32_t>(map.control_points.size()));
            auto add = [&](const OGRPoint& point) {
                if (point.IsEmpty()) return;
                const Point p{point.getX(), point.getY()};
                if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(label + ": point has a non-finite coordinate");
                map.control_points.push_back(p);
            };
            if (wkbFlatten(shape.type) == wkbPoint) {
                add(*geometry.toPoint());
            } else {
                for (const OGRPoint* point : *geometry.toMultiPoint()) add(*point);
            }
            layer.untouched.emplace_back(geometry.clone());
            ++summary_of_layer.untouched_points;
            break;
        }
        default:
            throw InputError(label + ": geometry is " + OGRGeometryTypeToName(shape.type) +
                             "; toposimp map simplifies (Multi)LineString and (Multi)Polygon features" +
                             (OGR_GT_IsNonLinear(shape.type) ? " (linearize curves first: ogr2ogr -nlt CONVERT_TO_LINEAR)" : ""));
    }
    if (shape.kind != Layer::Kind::untouched) shape.count = static_cast<std::uint32_t>(layer.items.size()) - shape.first;
}

void OgrDataset::Data::read_layer(const std::string& path, OGRLayer& source, map::MapData& map, bool prj_as_file, bool leave_in_file) {
    auto layer = std::make_unique<Layer>();
    LayerSummary summary_of_layer;
    summary_of_layer.layer = source.GetName();
    layer->name = source.GetName();
    layer->fid_column = source.GetFIDColumn();
    layer->geometry_type = source.GetGeomType();
    summary_of_layer.has_z = OGR_GT_HasZ(layer->geometry_type);
    summary_of_layer.has_m = OGR_GT_HasM(layer->geometry_type);
    if ((summary_of_layer.has_z || summary_of_layer.has_m) && !is_point_type(layer->geometry_type)) start_carrying_zm(map);
    auto not_in_file = [&](const std::string& why) { return NotInFile{"'" + path + "', layer '" + layer->name + "': " + why}; };
    // A plain PolyLine Shapefile: its shapes are decoded from the .shp here (shapefile.hpp; a
    // one-part record is a LineString, more a MultiLineString, as OGR reads them) after OGR has
    // read the attributes only: OGR's geometries cost GSHHG 0.1-0.14 s more. Going to a
    // Shapefile, its .prj file goes to the output as it is: OGR hands out each geometry with the
    // layer's CRS, and the first one makes the driver parse the .prj with PROJ (and search
    // proj.db for its EPSG code) — most of a small file's run, for a CRS that is only written
    // back. Going elsewhere, the CRS is parsed once, as the output needs it. A .shp this reader
    // does not take is read again through OGR, geometries and all. (Decoding on a thread of its
    // own beside OGR saved 0.03 s on GSHHG but raised the peak of a run with 10 M control points
    // by 30 MB: the thread's malloc arena stays.) With `leave_in_file`, the records are streamed
    // and their vertices left in the file (VerticesInFile).
    // With `leave_in_file` the layer's vertices stay in its .shp (`shp`: the input, or the layer's
    // file in a folder), or NotInFile is thrown; the .prj goes to the output as it is only where
    // it would without it.
    // A GeoPackage's or FlatGeobuf's layers (a .fgb, or a folder of them) are read through OGR by
    // FID; a FlatGeobuf's only with its index of features (without it, every read by FID reads
    // the file up to the feature).
    const bool gpkg = leave_in_file && summary.driver == "GPKG" && is_local_gpkg(path);
    const std::string fgb_file = leave_in_file && summary.driver == "FlatGeobuf" ? layer_file(path, layer->name, ".fgb", ".FGB") : "";
    const bool fgb = !fgb_file.empty() && source.TestCapability(OLCRandomRead);
    const bool by_ogr = gpkg || fgb;
    const std::string shp = !leave_in_file ? std::string() : gpkg ? path : fgb ? fgb_file : layer_shp(path, layer->name);
    const bool copy_prj = prj_as_file && is_local_shp(path);
    // (A 2D Polygon Shapefile read whole too, its records small enough to be held at once beside
    // the coverage: the .prj parse saved matters for small files only.)
    const bool decode_polygons = !leave_in_file && copy_prj && summary.driver == "ESRI Shapefile" && layer->geometry_type == wkbPolygon &&
                                 shapefile_size(path) <= kPolygonsDecodedUpTo;
    const bool decode = summary.driver == "ESRI Shapefile" && (layer->geometry_type == wkbLineString || decode_polygons) &&
                        (leave_in_file ? !shp.empty() : is_local_shp(path)) &&
                        source.SetIgnoredFields(std::array<const char*, 2>{"OGR_GEOMETRY", nullptr}.data()) == OGRERR_NONE;
    layer->definition = source.GetLayerDefn();
    layer->definition->Reference();

    QuietGdal quiet;
    auto read_error = [&] {
        return InputError("error reading '" + path + "', layer '" + layer->name + "'" + last_gdal_error());
    };
    // A Shapefile record's lines (as shape_geometry gives them) as chains of the map, its
    // vertices the map's from `first` on: no OGR geometry, no copy.
    auto add_record_lines = [&](const ShapeRecord& record, std::size_t first, Layer::Shape& shape, auto&& label) {
        const std::span<const std::uint32_t> parts = record.part_starts;
        if (parts.empty()) return;
        refuse_non_finite(record, label);
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t part_first = parts[k], part_end = k + 1 < parts.size() ? parts[k + 1] : record.xy.size();
            map.chains.push_back({static_cast<std::uint32_t>(first + part_first), static_cast<std::uint32_t>(first + part_end - 1)});
            layer->items.push_back(static_cast<std::uint32_t>(map.chains.size() - 1));
        }
        const bool has_z = !record.z.empty();
        shape.type = parts.size() == 1 ? (has_z ? wkbLineString25D : wkbLineString) : (has_z ? wkbMultiLineString25D : wkbMultiLineString);
        shape.kind = Layer::Kind::lines;
        shape.count = static_cast<std::uint32_t>(layer->items.size()) - shape.first;
    };
    // Each feature in turn, with its record's shape (its vertices the map's from `first` on) if
    // `record`, else with OGR's geometry. A feature GDAL could not read is an error at once (a
    // later read may clear GDAL's last error).
    auto add_feature = [&](OGRFeatureUniquePtr feature, const ShapeRecord* record, std::size_t first) {
        Layer::Shape shape;
        shape.first = static_cast<std::uint32_t>(layer->items.size());
        bool empty = true;
        if (record) {
            add_record_lines(*record, first, shape, [&] { return feature_label(path, source, feature->GetFID()); });
            empty = shape.kind != Layer::Kind::lines;
        } else if (const OGRGeometry* geometry = feature->GetGeometryRef()) {
            empty = geometry->IsEmpty();
            add_geometry(*layer, shape, summary_of_layer, *geometry, feature_label(path, source, feature->GetFID()), map);
        }
        count_feature(summary_of_layer, shape, empty);
        feature->SetGeometryDirectly(nullptr);
        layer->shapes.push_back(shape);
        layer->features.push_back(std::move(feature));
    };
    // The CRS of a layer whose geometries OGR did not hand out: the .prj file as it is, for a
    // Shapefile output, else parsed (once, by the layer).
    auto take_crs = [&] {
        if (!copy_prj) {
            if (const OGRSpatialReference* srs = source.GetSpatialRef()) layer->srs.reset(srs->Clone());
            return;
        }
        for (const char* extension : {".prj", ".PRJ"}) {
            std::error_code error;
            if (std::filesystem::exists(std::filesystem::path(path).replace_extension(extension), error)) {
                layer->prj = std::filesystem::path(path).replace_extension(extension);
                break;
            }
        }
    };
    // The records streamed, the vertices left in the file (VerticesInFile), from the next vertex
    // id on; false if the file is not what ShapeReader decodes, in the features' order (a record
    // deleted: then its lines are left in the file through OGR, by FID).
    auto plan_in_file = [&](std::vector<OGRFeatureUniquePtr>& features) {
        std::optional<ShapeReader> reader = ShapeReader::open(shp);
        bool in_order = reader && reader->records() == features.size() && map.vertices.empty();
        for (std::size_t i = 0; i < features.size() && in_order; ++i) in_order = features[i]->GetFID() == static_cast<GIntBig>(i);
        if (!in_order) return false;
        LayerInFile planned = layer_in_file(shp, layer->name, reader->shp_size());
        planned.record_vertex.reserve(features.size() + 1);
        planned.record_chain.reserve(features.size() + 1);
        Box& extent = in_file->extent;
        std::uint64_t& vertices = in_file->vertices;  // (the lines' so far)
        layer->shapes.reserve(features.size());
        layer->features.reserve(features.size());
        for (std::size_t i = 0; i < features.size(); ++i) {
            const ShapeRecord* record = reader->next();
            if (record == nullptr || !record->z.empty()) throw not_in_file("record " + std::to_string(i) + " is not one the Shapefile reader takes");
            planned.record_vertex.push_back(vertices);
            planned.record_chain.push_back(static_cast<std::uint32_t>(map.chains.size()));
            if (vertices + record->xy.size() > std::numeric_limits<std::uint32_t>::max() / 2) {
                throw InputError("'" + path + "', layer '" + layer->name + "': more than 2 billion vertices in one map");
            }
            add_feature(std::move(features[i]), record, static_cast<std::size_t>(vertices));
            vertices += record->xy.size();
            for (const Point p : record->xy) {
                extent = {std::min(extent.min_x, p.x), std::min(extent.min_y, p.y), std::max(extent.max_x, p.x), std::max(extent.max_y, p.y)};
            }
        }
        planned.record_vertex.push_back(vertices);
        planned.record_chain.push_back(static_cast<std::uint32_t>(map.chains.size()));
        in_file->layers.push_back(std::move(planned));
        take_crs();
        return true;
    };
    // A feature's FID where its run will find it (FeatureRun): a FlatGeobuf's must be its index, a
    // GeoPackage's above the one before; a Shapefile's is its record number, its index until a
    // record is deleted, from where they are kept as a GeoPackage's are (the records before it
    // noted then). NotInFile otherwise.
    auto note_fid = [&](LayerInFile& planned, GIntBig fid) {
        const auto index = static_cast<GIntBig>(layer->features.size());
        if (fgb || (!gpkg && planned.record_fid.empty() && fid == index)) {
            if (fid != index) {
                throw not_in_file("feature " + std::to_string(index) + " has FID " + std::to_string(fid) +
                                  " (its parts are found by index)");
            }
            return;
        }
        if (!gpkg && planned.record_fid.empty()) {
            for (GIntBig before = 0; before < index; ++before) planned.record_fid.push_back(before);
        }
        if (fid == std::numeric_limits<GIntBig>::max() || (!planned.record_fid.empty() && fid <= planned.record_fid.back())) {
            throw not_in_file("its features do not come in rising FID order (FID " + std::to_string(fid) + " after " +
                              std::to_string(planned.record_fid.empty() ? 0 : planned.record_fid.back()) + ")");
        }
        planned.record_fid.push_back(fid);
    };
    auto end_fids = [&](LayerInFile& planned) {
        if (gpkg || !planned.record_fid.empty()) planned.record_fid.push_back(planned.record_fid.empty() ? 0 : planned.record_fid.back() + 1);
    };
    // A layer left in its file (VerticesInFile), its planned layer begun (planned_layer): each
    // feature read with its attributes, its FID noted, `per_feature()` called, its geometry (if
    // any) given to `add(geometry, label)` to fill its shape's items (or throw NotInFile) and
    // dropped; then `per_feature()` once more, the FIDs' end noted and the planned layer kept.
    auto plan_features = [&](LayerInFile&& planned, Layer::Kind kind, auto&& per_feature, auto&& add) {
        for (;;) {
            OGRFeatureUniquePtr feature{source.GetNextFeature()};
            if (CPLGetLastErrorType() >= CE_Failure) throw read_error();
            if (!feature) break;
            note_fid(planned, feature->GetFID());
            per_feature(planned);
            Layer::Shape shape;
            shape.first = static_cast<std::uint32_t>(layer->items.size());
            bool empty = true;
            if (const OGRGeometry* geometry = feature->GetGeometryRef()) {
                empty = geometry->IsEmpty();
                shape.type = geometry->getGeometryType();
                shape.kind = kind;
                add(*geometry, feature_label(path, source, feature->GetFID()));
                shape.count = static_cast<std::uint32_t>(layer->items.size()) - shape.first;
            }
            count_feature(summary_of_layer, shape, empty);
            feature->SetGeometryDirectly(nullptr);
            layer->shapes.push_back(shape);
            layer->features.push_back(std::move(feature));
        }
        per_feature(planned);  // (one more)
        end_fids(planned);
        in_file->layers.push_back(std::move(planned));
    };
    auto planned_layer = [&] {
        std::error_code error;
        const std::uintmax_t size = std::filesystem::file_size(shp, error);
        if (error) throw not_in_file("its file's size cannot be read (" + error.message() + ")");
        if (!map.vertices.empty()) throw not_in_file("a layer before it is held in memory");
        return layer_in_file(shp, layer->name, size);
    };
    // A polygon layer left in its file (VerticesInFile with a coverage): its rings counted and
    // checked but not kept (the rings of every such layer are planned as one coverage from the
    // files at the end, in finish()). NotInFile if a feature is not a polygon.
    auto plan_polygons_in_file = [&] {
        LayerInFile planned = planned_layer();
        planned.polygons = true;
        planned.each_by_fid = fgb;
        Box& extent = in_file->extent;
        std::uint32_t& rings = in_file_rings;
        // The rings of a polygon, counted.
        auto count_rings = [&](const OGRPolygon& polygon, const std::string& label) {
            std::uint32_t count = 0;
            for (const OGRLinearRing* ring : polygon) count += ring->IsEmpty() ? 0 : 1;
            layer->items.push_back(count);
            for (const OGRLinearRing* ring : polygon) {
                if (ring->IsEmpty()) continue;
                for (int i = 0; i < ring->getNumPoints(); ++i) {
                    const Point p{ring->getX(i), ring->getY(i)};
                    if (!std::isfinite(p.x) || !std::isfinite(p.y)) read_points(*ring, label);  // (its refusal)
                    extent = {std::min(extent.min_x, p.x), std::min(extent.min_y, p.y), std::max(extent.max_x, p.x), std::max(extent.max_y, p.y)};
                }
                if (rings == std::numeric_limits<std::uint32_t>::max()) throw not_in_file("more than 4 billion rings");
                layer->items.push_back(rings++);
            }
        };
        plan_features(
            std::move(planned), Layer::Kind::polygons, [&](LayerInFile& into) { into.record_ring.push_back(rings); },
            [&](const OGRGeometry& geometry, const std::string& label) {
                if (geometry.Is3D() || geometry.IsMeasured()) {
                    // (Written from the feature read again; where the rings at a shared location
                    // differ, with the Z and M the plan notes: plan_coverage_in_files.)
                    summary_of_layer.has_z = summary_of_layer.has_z || geometry.Is3D();
                    summary_of_layer.has_m = summary_of_layer.has_m || geometry.IsMeasured();
                    start_carrying_zm(map);
                }
                if (wkbFlatten(geometry.getGeometryType()) == wkbPolygon) {
                    count_rings(*geometry.toPolygon(), label);
                } else if (wkbFlatten(geometry.getGeometryType()) == wkbMultiPolygon) {
                    for (const OGRPolygon* polygon : *geometry.toMultiPolygon()) count_rings(*polygon, label);
                } else {
                    throw NotInFile{label + " is a " + std::string(OGRGeometryTypeToName(geometry.getGeometryType())) +
                                    " in a polygon layer"};
                }
            });
    };
    // A lines layer left in its file and read through OGR (a GeoPackage's or FlatGeobuf's, or a
    // Shapefile's with Z or M): each feature's parts become the map's chains (as add_geometry makes
    // them) without their vertices; their Z and M are read again when the output is written.
    // NotInFile if a feature is not a (Multi)LineString.
    auto plan_lines_through_ogr = [&] {
        LayerInFile planned = planned_layer();
        planned.ogr_lines = true;
        planned.each_by_fid = fgb;
        Box& extent = in_file->extent;
        std::uint64_t& vertices = in_file->vertices;  // (the lines' so far)
        plan_features(
            std::move(planned), Layer::Kind::lines,
            [&](LayerInFile& into) {
                into.record_vertex.push_back(vertices);
                into.record_chain.push_back(static_cast<std::uint32_t>(map.chains.size()));
            },
            [&](const OGRGeometry& geometry, const std::string& label) {
                thread_local std::vector<const OGRLineString*> parts;
                if (!line_parts(geometry, parts)) {
                    throw NotInFile{label + " is a " + std::string(OGRGeometryTypeToName(geometry.getGeometryType())) +
                                    " in a line layer"};
                }
                if (geometry.Is3D() || geometry.IsMeasured()) {
                    // (Written from the feature read again, as when it is read whole.)
                    summary_of_layer.has_z = summary_of_layer.has_z || geometry.Is3D();
                    summary_of_layer.has_m = summary_of_layer.has_m || geometry.IsMeasured();
                    start_carrying_zm(map);
                }
                for (const OGRLineString* part : parts) {
                    if (part->IsEmpty()) {
                        layer->items.push_back(kEmptyPart);
                        continue;
                    }
                    const auto count = static_cast<std::uint64_t>(part->getNumPoints());
                    if (vertices + count > std::numeric_limits<std::uint32_t>::max() / 2) {
                        throw InputError(label + ": more than 2 billion vertices in one map");
                    }
                    for (int i = 0; i < part->getNumPoints(); ++i) {
                        const Point p{part->getX(i), part->getY(i)};
                        if (!std::isfinite(p.x) || !std::isfinite(p.y)) read_points(*part, label);  // (its refusal)
                        extent = {std::min(extent.min_x, p.x), std::min(extent.min_y, p.y), std::max(extent.max_x, p.x), std::max(extent.max_y, p.y)};
                    }
                    map.chains.push_back({static_cast<std::uint32_t>(vertices), static_cast<std::uint32_t>(vertices + count - 1)});
                    layer->items.push_back(static_cast<std::uint32_t>(map.chains.size() - 1));
                    vertices += count;
                }
            });
    };
    // A point layer beside the layers left in their files is read as without them: its points
    // are control points (the command holds those anyway), written back as they were, with their
    // Z and M if they have them.
    const bool point_layer = leave_in_file && is_point_type(layer->geometry_type);
    const std::size_t chains_before = map.chains.size();
    if (leave_in_file) {
        // (Polygons, and a Shapefile's PolyLineZ or PolyLineM, with Z or M too: through OGR, as
        // when they are read whole.)
        const OGRwkbGeometryType flat_type = wkbFlatten(layer->geometry_type);
        const bool polygon_layer = (flat_type == wkbPolygon || flat_type == wkbMultiPolygon) && (summary.driver == "ESRI Shapefile" || by_ogr);
        const bool ogr_lines = (flat_type == wkbLineString || flat_type == wkbMultiLineString) &&
                               (by_ogr || (summary.driver == "ESRI Shapefile" && layer->geometry_type != wkbLineString));
        if (!point_layer && shp.empty()) {
            throw not_in_file(summary.driver == "FlatGeobuf" ? "a FlatGeobuf without its index of features"
                                                             : "its format (" + summary.driver + ") is not read by parts");
        }
        if (!point_layer && !decode && !polygon_layer && !ogr_lines) {
            throw not_in_file("its geometry type (" + std::string(OGRGeometryTypeToName(layer->geometry_type)) + ") is not read by parts");
        }
        if (!in_file) in_file.emplace();
    }
    source.ResetReading();
    bool decoded = false;
    if (decode) {
        std::vector<OGRFeatureUniquePtr> features;
        for (;;) {
            OGRFeatureUniquePtr feature{source.GetNextFeature()};
            if (CPLGetLastErrorType() >= CE_Failure) throw read_error();
            if (!feature) break;
            features.push_back(std::move(feature));
        }
        if (leave_in_file) {
            decoded = plan_in_file(features);
        } else if (decode_polygons) {
            if (std::optional<ShapeTable> records = read_shapefile_shapes(path); records && records->z.empty()) {
                bool in_order = records->size() == features.size();
                for (std::size_t i = 0; i < features.size() && in_order; ++i) in_order = features[i]->GetFID() == static_cast<GIntBig>(i);
                if (in_order) {
                    take_crs();
                    layer->shapes.reserve(features.size());
                    layer->features.reserve(features.size());
                    for (std::size_t r = 0; r < features.size(); ++r) {
                        features[r]->SetGeometryDirectly(polygon_geometry((*records)[r]).release());
                        add_feature(std::move(features[r]), nullptr, 0);
                    }
                    decoded = true;
                }
            }
        } else if (std::optional<ShapeTable> records = read_shapefile_shapes(path)) {
            // (The records' vertices go to the map in record order: the features must come in it.)
            bool in_order = records->size() == features.size();
            for (std::size_t i = 0; i < features.size() && in_order; ++i) in_order = features[i]->GetFID() == static_cast<GIntBig>(i);
            if (in_order) {
                // The records' vertices become the map's (moved, when this is its first layer).
                const std::size_t first_vertex = map.vertices.size();
                if (first_vertex + records->xy.size() > std::numeric_limits<std::uint32_t>::max() / 2) {
                    throw InputError("'" + path + "', layer '" + layer->name + "': more than 2 billion vertices in one map");
                }
                if (!records->z.empty()) {
                    summary_of_layer.has_z = true;
                    start_carrying_zm(map);
                }
                if (carries_zm) {
                    if (records->z.empty()) {
                        z.resize(z.size() + records->xy.size(), 0.0);
                    } else {
                        z.insert(z.end(), records->z.begin(), records->z.end());
                    }
                    m.resize(m.size() + records->xy.size(), 0.0);
                }
                if (first_vertex == 0) {
                    map.vertices = std::move(records->xy);
                } else {
                    map.vertices.insert(map.vertices.end(), records->xy.begin(), records->xy.end());
                    std::vector<Point>().swap(records->xy);
                }
                map.chains.reserve(map.chains.size() + records->part_starts.size());
                take_crs();
                layer->shapes.reserve(features.size());
                layer->features.reserve(features.size());
                for (std::size_t r = 0; r < features.size(); ++r) {
                    // (A view of the record on the map's vertices, where its own went.)
                    const std::size_t first = first_vertex + records->record_first[r], end = first_vertex + records->record_first[r + 1];
                    const ShapeRecord record{{map.vertices.data() + first, end - first},
                                             records->z.empty() ? std::span<const double>()
                                                                : std::span<const double>(records->z.data() + (first - first_vertex), end - first),
                                             {records->part_starts.data() + records->record_parts[r],
                                              records->record_parts[r + 1] - records->record_parts[r]}};
                    add_feature(std::move(features[r]), &record, first);
                }
                decoded = true;
            }
        }
        if (!decoded) {
            if (source.SetIgnoredFields(nullptr) != OGRERR_NONE) throw read_error();
            source.ResetReading();
        }
    }
    if (!decoded) {
        if (const OGRSpatialReference* srs = source.GetSpatialRef()) layer->srs.reset(srs->Clone());
        if (leave_in_file && !point_layer) {
            if (wkbFlatten(layer->geometry_type) == wkbPolygon || wkbFlatten(layer->geometry_type) == wkbMultiPolygon) {
                plan_polygons_in_file();
            } else {
                plan_lines_through_ogr();
            }
            decoded = true;
        }
    }
    if (!decoded) {
        for (;;) {
            OGRFeatureUniquePtr feature{source.GetNextFeature()};
            if (CPLGetLastErrorType() >= CE_Failure) throw read_error();
            if (!feature) break;
            add_feature(std::move(feature), nullptr, 0);
        }
    }
    if (point_layer) {
        // (Points only: no vertex, no chain, nothing carried in Z or M.)
        if (!map.vertices.empty() || map.chains.size() != chains_before) throw not_in_file("a point layer with other geometries");
        LayerInFile points;
        points.layer = layer->name;
        points.points = true;
        in_file->layers.push_back(std::move(points));
    }
    if (CPLGetLastErrorType() >= CE_Failure) throw read_error();
    summary_of_layer.features = layer->features.size();
    summary.layers.push_back(summary_of_layer);
    layers.push_back(std::move(layer));
}

// A layer in memory, straight from its WKB into the map (no OGR dataset, no feature objects: the
// attributes stay with the caller).
void OgrDataset::Data::read_memory_layer(const std::string& source, const MemoryLayer& given, map::MapData& map) {
    auto layer = std::make_unique<Layer>();
    LayerSummary summary_of_layer;
    summary_of_layer.layer = layer->name = given.name;
    if (!given.crs_wkt.empty()) {
        QuietGdal quiet;
        layer->srs = std::make_unique<OGRSpatialReference>();
        layer->srs->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
        if (layer->srs->importFromWkt(given.crs_wkt.c_str()) != OGRERR_NONE) {
            throw InputError("'" + source + "', layer '" + given.name + "': its CRS is not one GDAL reads" + last_gdal_error());
        }
    }
    layer->shapes.reserve(given.wkb.size());
    for (std::size_t k = 0; k < given.wkb.size(); ++k) {
        Layer::Shape shape;
        shape.first = static_cast<std::uint32_t>(layer->items.size());
        bool empty = true;
        if (const std::string& wkb = given.wkb[k]; !wkb.empty()) {
            const std::string label = "'" + source + "', layer '" + given.name + "', feature " + std::to_string(k);
            OGRGeometry* read = nullptr;
            std::size_t used = 0;
            QuietGdal quiet;
            if (OGRGeometryFactory::createFromWkb(wkb.data(), nullptr, &read, wkb.size(), wkbVariantOldOgc, used) != OGRERR_NONE ||
                read == nullptr) {
                throw InputError(label + ": not a WKB geometry GDAL reads" + last_gdal_error());
            }
            const std::unique_ptr<OGRGeometry> geometry(read);
            empty = geometry->IsEmpty();
            add_geometry(*layer, shape, summary_of_layer, *geometry, label, map);
        }
        count_feature(summary_of_layer, shape, empty);
        layer->shapes.push_back(shape);
    }
    summary_of_layer.features = layer->shapes.size();
    summary.layers.push_back(summary_of_layer);
    layers.push_back(std::move(layer));
}

OgrDataset::OgrDataset(std::unique_ptr<Data> data) : data_(std::move(data)) {}
OgrDataset::OgrDataset(OgrDataset&&) noexcept = default;
OgrDataset::~OgrDataset() = default;

const DatasetSummary& OgrDataset::summary() const { return data_->summary; }

bool OgrDataset::geographic(std::size_t k) const {
    const Data::Layer& layer = *data_->layers.at(k);
    if (layer.srs) return layer.srs->IsGeographic();
    if (layer.prj.empty()) return false;
    // (Parsed as the Shapefile driver parses it: the file's lines as ESRI's WKT.)
    QuietGdal quiet;
    CPLStringList lines(CSLLoad(layer.prj.c_str()));
    OGRSpatialReference srs;
    return lines.size() > 0 && srs.importFromESRI(lines.List()) == OGRERR_NONE && srs.IsGeographic();
}

const VerticesInFile* OgrDataset::vertices_in_file() const { return data_->in_file ? &*data_->in_file : nullptr; }

namespace {

// A dataset in GDAL's memory driver holding `layers`' geometries, feature k with FID k.
DatasetPtr memory_dataset(const MemoryLayers& layers) {
    register_drivers();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("Memory");
    if (driver == nullptr) throw InputError("GDAL has no Memory driver");
    QuietGdal quiet;
    DatasetPtr dataset{driver->Create("", 0, 0, 0, GDT_Unknown, nullptr)};
    if (!dataset) throw InputError("cannot make a dataset in memory" + last_gdal_error());
    for (const MemoryLayer& given : layers.layers) {
        std::unique_ptr<OGRSpatialReference> srs;
        if (!given.crs_wkt.empty()) {
            srs = std::make_unique<OGRSpatialReference>();
            srs->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
            if (srs->importFromWkt(given.crs_wkt.c_str()) != OGRERR_NONE) {
                throw InputError("'" + layers.source + "', layer '" + given.name + "': its CRS is not one GDAL reads" + last_gdal_error());
            }
        }
        OGRLayer* layer = dataset->CreateLayer(given.name.c_str(), srs.get(), wkbUnknown, nullptr);
        if (layer == nullptr) throw InputError("cannot make layer '" + given.name + "' in memory" + last_gdal_error());
        for (std::size_t k = 0; k < given.wkb.size(); ++k) {
            OGRFeatureUniquePtr feature{OGRFeature::CreateFeature(layer->GetLayerDefn())};
            feature->SetFID(static_cast<GIntBig>(k));
            const std::string& wkb = given.wkb[k];
            if (!wkb.empty()) {
                OGRGeometry* geometry = nullptr;
                std::size_t used = 0;
                if (OGRGeometryFactory::createFromWkb(wkb.data(), nullptr, &geometry, wkb.size(), wkbVariantOldOgc, used) !=
                        OGRERR_NONE || geometry == nullptr) {
                    throw InputError("'" + layers.source + "', layer '" + given.name + "', feature " + std::to_string(k) +
                                     ": not a WKB geometry GDAL reads" + last_gdal_error());
                }
                feature->SetGeometryDirectly(geometry);
            }
            if (layer->CreateFeature(feature.get()) != OGRERR_NONE) {
                throw InputError("cannot keep feature " + std::to_string(k) + " of layer '" + given.name + "' in memory" + last_gdal_error());
            }
        }
    }
    return dataset;
}

}  // namespace

// What every read ends with: a refusal if nothing is simplifiable, the coverage of the rings.
void OgrDataset::Data::finish(const std::string& path, map::MapData& map) {
    if (summary.sum(&LayerSummary::line_features) + summary.sum(&LayerSummary::polygon_features) == 0) {
        std::string what;
        for (const auto& layer : layers) {
            what += (what.empty() ? "" : "; ") + std::string("layer '") + layer->name + "': " +
                    OGRGeometryTypeToName(layer->geometry_type) + ", " + std::to_string(layer->shapes.size()) + " features";
        }
        throw InputError("'" + path + "' has no line or polygon geometry (" + what + ")");
    }
    // Polygon rings become arcs: one chain per border, shared by the polygons on both sides.
    const std::size_t before = map.vertices.size();
    if (in_file) {
        plan_coverage_in_files(map);
    } else {
        coverage.build(map);
    }
    if (carries_zm) {
        z.resize(map.vertices.size(), 0.0);
        m.resize(map.vertices.size(), 0.0);
        for (std::size_t v = before; v < map.vertices.size(); ++v) {
            const std::uint32_t origin = coverage.source_of(static_cast<std::uint32_t>(v));
            z[v] = ring_z[origin];
            m[v] = ring_m[origin];
        }
        std::vector<double>().swap(ring_z);
        std::vector<double>().swap(ring_m);
    }
    // Grown by doubling while reading: up to half of it spare, held through simplification.
    map.vertices.shrink_to_fit();
    map.chains.shrink_to_fit();
    summary.arcs = coverage.arc_count();
    summary.shared_arcs = coverage.shared_arc_count();
    summary.degenerate_rings = coverage.degenerate_ring_count();
}

// The layers left in their files (read_layer): their polygon rings planned as one coverage, each
// layer read again in passes (Coverage::plan), and every feature's first chain and vertex.
void OgrDataset::Data::plan_coverage_in_files(map::MapData& map) {
    std::vector<LayerInFile*> polygons;
    std::uintmax_t bytes = 0;
    for (LayerInFile& layer : in_file->layers) {
        if (!layer.polygons) continue;
        polygons.push_back(&layer);
        bytes += layer.size;
    }
    if (!polygons.empty()) {
        auto changed = [&](const LayerInFile& layer) {
            return InputError("'" + layer.path + "', layer '" + layer.layer + "' changed while toposimp read it");
        };
        const LayerInFile* reading = polygons.front();
        try {
            if (!carries_zm) {
                coverage.plan(
                    [&](const std::function<void(std::span<const Point>)>& visit) {
                        for (const LayerInFile* layer : polygons) {
                            reading = layer;
                            for_each_polygon_ring(layer->run(0, layer->record_ring.size() - 1), visit);
                        }
                    },
                    map, coverage_pass_bytes(bytes));
            } else {
                // Some layer has Z or M: a ring is written from its own points (read again), with
                // their Z and M, but where the rings at a location differ in them: there each arc
                // vertex gets those of the ring that made the arc, as when the map is read whole
                // (the plan notes them: Coverage::arc_tag).
                coverage.plan(
                    [&](const std::function<void(std::span<const Point>, std::span<const map::PointTag>)>& visit) {
                        for (const LayerInFile* layer : polygons) {
                            reading = layer;
                            for_each_polygon_ring(layer->run(0, layer->record_ring.size() - 1), visit);
                        }
                    },
                    map, coverage_pass_bytes(bytes));
            }
        } catch (const std::invalid_argument&) {
            throw changed(*reading);
        } catch (const std::length_error&) {
            throw InputError("'" + reading->path + "', layer '" + reading->layer + "': more than 2 billion vertices in one map");
        }
        for (const LayerInFile* layer : polygons) {
            if (!unchanged(*layer)) throw changed(*layer);
        }
        in_file->coverage = &coverage;
    }
    const auto chains = static_cast<std::uint32_t>(map.chains.size());
    in_file->vertices = map.chains.empty() ? 0 : std::uint64_t{map.chains.back().last} + 1;
    for (LayerInFile* layer : polygons) {
        layer->record_chain.reserve(layer->record_ring.size());
        layer->record_vertex.reserve(layer->record_ring.size());
        for (const std::uint32_t ring : layer->record_ring) {
            const std::uint32_t chain = coverage.chains_before(ring);
            layer->record_chain.push_back(chain);
            layer->record_vertex.push_back(chain < chains ? map.chains[chain].first : in_file->vertices);
        }
    }
}

std::vector<const LayerInFile*> VerticesInFile::in_chain_order() const {
    std::vector<const LayerInFile*> ordered;
    for (const bool polygons : {false, true}) {
        for (const LayerInFile& layer : layers) {
            if (layer.polygons == polygons && !layer.points) ordered.push_back(&layer);
        }
    }
    return ordered;
}

OgrDataset OgrDataset::read(const std::string& path, const std::vector<std::string>& layer_names_wanted, map::MapData& map,
                            bool prj_as_file, bool vertices_in_file) {
    if (vertices_in_file) {
        // (Every layer left in its file, or none: a layer that cannot be has the dataset read
        // whole.)
        const map::MapData given = map;
        std::string why;
        try {
            return read_dataset(path, layer_names_wanted, map, prj_as_file, true);
        } catch (const NotInFile& not_in_file) {
            map = given;
            why = not_in_file.why;
        }
        OgrDataset whole = read_dataset(path, layer_names_wanted, map, prj_as_file, false);
        whole.data_->summary.read_whole_because = why;
        return whole;
    }
    return read_dataset(path, layer_names_wanted, map, prj_as_file, false);
}

OgrDataset OgrDataset::read_dataset(const std::string& path, const std::vector<std::string>& layer_names_wanted, map::MapData& map,
                                    bool prj_as_file, bool vertices_in_file) {
    DatasetPtr dataset = open_vector(path);
    auto data = std::make_unique<Data>();
    data->summary.driver = dataset->GetDriver() ? dataset->GetDriver()->GetDescription() : "";
    if (dataset->GetLayerCount() == 0) throw InputError("'" + path + "' has no vector layer");
    if (layer_names_wanted.empty()) {
        for (int i = 0; i < dataset->GetLayerCount(); ++i) {
            data->read_layer(path, *dataset->GetLayer(i), map, prj_as_file, vertices_in_file);
        }
    } else {
        for (const std::string& name : layer_names_wanted) {
            data->read_layer(path, pick_layer(*dataset, path, name), map, prj_as_file, vertices_in_file);
        }
    }
    data->finish(path, map);
    return OgrDataset(std::move(data));
}

OgrDataset OgrDataset::read(const MemoryLayers& layers, map::MapData& map) {
    auto data = std::make_unique<Data>();
    data->summary.driver = "Memory";
    if (layers.layers.empty()) throw InputError("'" + layers.source + "' has no layer");
    for (const MemoryLayer& layer : layers.layers) data->read_memory_layer(layers.source, layer, map);
    data->finish(layers.source, map);
    return OgrDataset(std::move(data));
}

MemoryLayers OgrDataset::to_memory(const map::MapData& map, const std::vector<std::uint8_t>& kept) const {
    MemoryLayers out;
    for (const auto& layer : data_->layers) {
        MemoryLayer& written = out.layers.emplace_back();
        written.name = layer->name;
        written.wkb.resize(layer->shapes.size());
        std::vector<unsigned char> buffer;
        for (std::size_t k = 0; k < layer->shapes.size(); ++k) {
            const Data::Layer::Kind kind = layer->shapes[k].kind;
            if (kind == Data::Layer::Kind::null || (kind == Data::Layer::Kind::untouched && !data_->points_moved)) continue;
            std::unique_ptr<OGRGeometry> geometry = data_->build_geometry(*layer, k, map, kept);
            if (!geometry || geometry->IsEmpty()) continue;
            // GEOS (and so shapely) reads no M: written 2D or 3D.
            if (geometry->IsMeasured()) geometry->setMeasured(FALSE);
            buffer.resize(geometry->WkbSize());
            geometry->exportToWkb(wkbNDR, buffer.data(), wkbVariantOldOgc);
            written.wkb[k].assign(reinterpret_cast<const char*>(buffer.data()), buffer.size());
        }
    }
    return out;
}

std::unique_ptr<OGRGeometry> OgrDataset::Data::build_geometry(const Layer& layer, std::size_t index, const map::MapData& map,
                                                              VertexView at, const std::vector<std::uint8_t>& kept,
                                                              bool arc_order) const {
    using Kind = Layer::Kind;
    const Layer::Shape& shape = layer.shapes[index];
    const std::vector<std::uint32_t>& items = layer.items;
    const bool with_z = OGR_GT_HasZ(shape.type), with_m = OGR_GT_HasM(shape.type);
    auto zm_flags = [&](OGRGeometry& geometry) {
        if (with_z) geometry.set3D(TRUE);
        if (with_m) geometry.setMeasured(TRUE);
    };
    // (Z and M from the feature read again where its vertices were left in the file.)
    const bool rings_again = at.rings != nullptr;
    const bool has_z = rings_again ? at.ring_z != nullptr : at.z != nullptr, has_m = rings_again ? at.ring_m != nullptr : at.m != nullptr;
    if (at.file != nullptr && ((with_z && !has_z) || (with_m && !has_m))) throw changed_while_running(*at.file, index);
    const double* const z_of = at.z != nullptr ? at.z - at.first : z.data();
    const double* const m_of = at.m != nullptr ? at.m - at.first : m.data();
    auto fill = [&](OGRSimpleCurve& curve, const std::vector<std::uint32_t>& vertices) {
        curve.setNumPoints(static_cast<int>(vertices.size()), FALSE);
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const std::uint32_t v = vertices[i];
            set_point(curve, static_cast<int>(i), at[v], with_z, with_m, with_z ? z_of[v] : 0.0, with_m ? m_of[v] : 0.0);
        }
    };
    switch (shape.kind) {
        case Kind::null: return nullptr;
        case Kind::untouched: return std::unique_ptr<OGRGeometry>(layer.untouched[shape.first]->clone());
        case Kind::lines: {
            auto make_line = [&](std::uint32_t chain_index) {
                auto line = std::make_unique<OGRLineString>();
                zm_flags(*line);
                if (chain_index == kEmptyPart) return line;
                std::vector<std::uint32_t> vertices;
                for (std::uint32_t v = map.chains[chain_index].first; v <= map.chains[chain_index].last; ++v) {
                    if (kept[v]) vertices.push_back(v);
                }
                fill(*line, vertices);
                return line;
            };
            if (wkbFlatten(shape.type) == wkbLineString) return make_line(shape.count ? items[shape.first] : kEmptyPart);
            auto multi = std::make_unique<OGRMultiLineString>();
            zm_flags(*multi);
            for (std::uint32_t k = 0; k < shape.count; ++k) multi->addGeometryDirectly(make_line(items[shape.first + k]).release());
            return multi;
        }
        case Kind::polygons: {
            std::uint32_t k = shape.first;
            auto make_polygon = [&]() {
                auto polygon = std::make_unique<OGRPolygon>();
                zm_flags(*polygon);
                const std::uint32_t rings = items[k++];
                for (std::uint32_t r = 0; r < rings; ++r) {
                    auto ring = std::make_unique<OGRLinearRing>();
                    zm_flags(*ring);
                    const std::uint32_t id = items[k++];
                    if (at.rings == nullptr) {
                        fill(*ring, coverage.ring_vertices(id, kept, arc_order));
                    } else {
                        // (Its own points: VertexCursor checked the feature has its rings. Its own
                        // Z and M too, but where the rings at a location carry different ones: there
                        // each vertex has those of the ring that made its arc, which the coverage's
                        // plan noted.)
                        try {
                            const std::size_t own = id - at.first_ring;
                            const std::vector<map::Coverage::RingPoint> points = coverage.ring_points_from(id, (*at.rings).at(own), kept, arc_order);
                            ring->setNumPoints(static_cast<int>(points.size()), FALSE);
                            for (std::size_t i = 0; i < points.size(); ++i) {
                                double point_z = with_z ? (*at.ring_z).at(own).at(points[i].position) : 0.0;
                                double point_m = with_m ? (*at.ring_m).at(own).at(points[i].position) : 0.0;
                                if (const map::PointTag* arc = coverage.arc_tag(points[i].vertex)) {
                                    point_z = std::bit_cast<double>(arc->z);
                                    point_m = std::bit_cast<double>(arc->m);
                                }
                                set_point(*ring, static_cast<int>(i), points[i].point, with_z, with_m, point_z, point_m);
                            }
                        } catch (const std::invalid_argument&) {
                            throw changed_while_running(*at.file, index);
                        }
                    }
                    polygon->addRingDirectly(ring.release());
                }
                return polygon;
            };
            if (wkbFlatten(shape.type) == wkbPolygon) {
                if (shape.count == 0) {
                    auto empty = std::make_unique<OGRPolygon>();
                    zm_flags(*empty);
                    return empty;
                }
                return make_polygon();
            }
            auto multi = std::make_unique<OGRMultiPolygon>();
            zm_flags(*multi);
            while (k < shape.first + shape.count) multi->addGeometryDirectly(make_polygon().release());
            return multi;
        }
    }
    return nullptr;
}

namespace {

// The point sequences of a geometry: line parts, polygon rings (all of them, in order), points.
void collect_parts(const OGRGeometry* geometry, std::vector<const OGRSimpleCurve*>& parts,
                   std::vector<const OGRPoint*>& points) {
    if (geometry == nullptr || geometry->IsEmpty()) return;
    switch (wkbFlatten(geometry->getGeometryType())) {
        case wkbLineString: parts.push_back(geometry->toLineString()); break;
        case wkbPolygon:
            for (const OGRLinearRing* ring : *geometry->toPolygon()) {
                if (!ring->IsEmpty()) parts.push_back(ring);
            }
            break;
        case wkbPoint: points.push_back(geometry->toPoint()); break;
        case wkbMultiLineString:
        case wkbMultiPolygon:
        case wkbMultiPoint:
        case wkbGeometryCollection:
            for (const OGRGeometry* member : *geometry->toGeometryCollection()) collect_parts(member, parts, points);
            break;
        default: break;
    }
}

// Does a Shapefile record hold exactly the kept vertices of a plain (2D) line feature, part by
// part and in order? The common case of the check after writing, decided without an OGR geometry
// on either side (on GSHHG at 50 %, 0.22 s of a 0.75 s write went to building them). False for
// anything else, which same_coordinates then decides (and explains).
bool record_holds_lines(const OgrDataset::Data::Layer& layer, std::size_t index, const map::MapData& map, VertexView vertices,
                        const std::vector<std::uint8_t>& kept, const ShapeRecord& record) {
    const OgrDataset::Data::Layer::Shape& shape = layer.shapes[index];
    if (shape.kind != OgrDataset::Data::Layer::Kind::lines || OGR_GT_HasZ(shape.type) || OGR_GT_HasM(shape.type) ||
        !record.z.empty() || record.part_starts.size() != shape.count) {
        return false;
    }
    for (std::uint32_t k = 0; k < shape.count; ++k) {
        const std::uint32_t chain = layer.items[shape.first + k];
        if (chain == kEmptyPart) return false;
        std::size_t at = record.part_starts[k];
        const std::size_t end = k + 1 < shape.count ? record.part_starts[k + 1] : record.xy.size();
        for (std::uint32_t v = map.chains[chain].first; v <= map.chains[chain].last; ++v) {
            if (!kept[v]) continue;
            if (at == end || !(record.xy[at].x == vertices[v].x) || !(record.xy[at].y == vertices[v].y)) return false;
            ++at;
        }
        if (at != end) return false;
    }
    return true;
}

}  // namespace

namespace {

// A feature's polygon rings as OgrDataset::read gives them to its coverage: each polygon's
// non-empty rings, its exterior first (none for other geometries).
// (`visit(points, ring)`: each ring's points and the ring they were read from.)
template <class Visit>
void visit_rings(const OGRFeature& feature, const std::string& path, OGRLayer& layer, Visit&& visit) {
    const OGRGeometry* geometry = feature.GetGeometryRef();
    if (geometry == nullptr) return;
    const std::string label = feature_label(path, layer, feature.GetFID());
    auto rings_of = [&](const OGRPolygon& polygon) {
        for (const OGRLinearRing* ring : polygon) {
            if (!ring->IsEmpty()) visit(read_points(*ring, label), *ring);
        }
    };
    if (wkbFlatten(geometry->getGeometryType()) == wkbPolygon) {
        rings_of(*geometry->toPolygon());
    } else if (wkbFlatten(geometry->getGeometryType()) == wkbMultiPolygon) {
        for (const OGRPolygon* polygon : *geometry->toMultiPolygon()) rings_of(*polygon);
    }
}

}  // namespace

namespace {

// A run of features read in order, each checked to be where the run says (InputError naming the
// feature otherwise).
class FeatureReader {
public:
    explicit FeatureReader(const FeatureRun& run) : run_(run), dataset_(open_vector(run.path)), layer_(&pick_layer(*dataset_, run.path, run.layer)) {
        QuietGdal quiet;
        layer_->ResetReading();
        if (run.by_fid && shapefile_) {
            // (A Shapefile's FIDs are its record numbers, deleted ones skipped: its
            // SetNextByIndex goes to a record number, reading on from there.)
            if (run.fid_first > 0 && layer_->SetNextByIndex(run.fid_first) != OGRERR_NONE) fail(run.first, ": no such record" + last_gdal_error());
        } else if (run.by_fid) {
            // (The FID column is the table's integer primary key: a range of it is a range of
            // its rows, read in their order.)
            std::string column = layer_->GetFIDColumn();
            if (column.empty()) fail(run.first, ": it has no FID column");
            for (std::size_t at = 0; (at = column.find('"', at)) != std::string::npos; at += 2) column.insert(at, 1, '"');
            const std::string filter = "\"" + column + "\" >= " + std::to_string(run.fid_first) + " AND \"" + column + "\" < " +
                                       std::to_string(run.fid_end);
            if (layer_->SetAttributeFilter(filter.c_str()) != OGRERR_NONE) fail(run.first, ": its FIDs cannot be read by range" + last_gdal_error());
        } else if (each_) {
            if (!layer_->TestCapability(OLCRandomRead)) fail(run.first, ": the file has no index of its features");
        } else if (run.first > 0 && layer_->SetNextByIndex(static_cast<GIntBig>(run.first)) != OGRERR_NONE) {
            fail(run.first, ": no such feature" + last_gdal_error());
        }
    }

    // The run's next feature, or nullptr after its last.
    OGRFeatureUniquePtr next() {
        QuietGdal quiet;
        if (next_ == run_.end) {
            // (A range of FIDs holding more features than it did: the file changed.)
            if (run_.by_fid) {
                const OGRFeatureUniquePtr after(layer_->GetNextFeature());
                if (after && after->GetFID() < run_.fid_end) fail(next_, ": the layer holds more features than it did");
            }
            return nullptr;
        }
        OGRFeatureUniquePtr feature{each_ ? layer_->GetFeature(static_cast<GIntBig>(next_)) : layer_->GetNextFeature()};
        if (CPLGetLastErrorType() >= CE_Failure || !feature) fail(next_, feature ? last_gdal_error() : ": the layer ends before it");
        const GIntBig fid = feature->GetFID();
        if (run_.by_fid && (fid < run_.fid_first || fid >= run_.fid_end)) {
            fail(next_, ": the layer ends before it (the next feature has FID " + std::to_string(fid) + ", past the run's FIDs " +
                            std::to_string(run_.fid_first) + " to " + std::to_string(run_.fid_end - 1) + ")");
        }
        if (run_.by_fid ? fid <= last_fid_ : fid != static_cast<GIntBig>(next_)) {
            fail(next_, " has FID " + std::to_string(fid) + (run_.by_fid ? "" : " (a deleted record?): it cannot be read by index"));
        }
        last_fid_ = fid;
        ++next_;
        return feature;
    }

    OGRLayer& layer() { return *layer_; }

private:
    [[noreturn]] void fail(std::uint64_t feature, const std::string& why) const {
        throw InputError("'" + run_.path + "', layer '" + run_.layer + "', feature " + std::to_string(feature) + why);
    }

    FeatureRun run_;
    // Each feature read by its FID (a run of a FlatGeobuf's not from its first feature: read in
    // turn from the first, they come faster).
    bool each_ = run_.each_by_fid && run_.first > 0;
    DatasetPtr dataset_;
    OGRLayer* layer_;
    bool shapefile_ = dataset_->GetDriver() != nullptr && std::string(dataset_->GetDriver()->GetDescription()) == "ESRI Shapefile";
    std::uint64_t next_ = run_.first;
    GIntBig last_fid_ = std::numeric_limits<GIntBig>::min();
};

// A feature's lines as chains of `lines` (read_lines), or false if it is not a 2D
// (Multi)LineString.
// (With `z` and `m`: their Z and M too, 0 where they have none.)
bool add_lines(const OGRFeature& feature, const std::string& label, map::MapData& lines, std::vector<double>* z = nullptr,
               std::vector<double>* m = nullptr) {
    const OGRGeometry* geometry = feature.GetGeometryRef();
    if (geometry == nullptr) return true;
    thread_local std::vector<const OGRLineString*> parts;
    if (!line_parts(*geometry, parts)) return false;
    for (const OGRLineString* part : parts) {
        if (part->IsEmpty()) continue;
        if (lines.vertices.size() + static_cast<std::size_t>(part->getNumPoints()) >= std::numeric_limits<std::uint32_t>::max() / 2) {
            throw InputError(label + ": more than 2 billion vertices in one part of the map");
        }
        lines.add_chain(read_points(*part, label));
        if (z != nullptr) append_zm(*part, *z, *m);
    }
    return true;
}

}  // namespace

FeatureRun LayerInFile::run(std::uint64_t first, std::uint64_t end) const {
    FeatureRun run{path, layer, first, end, !record_fid.empty()};
    run.each_by_fid = each_by_fid;
    if (run.by_fid) {
        run.fid_first = record_fid.at(first);
        run.fid_end = record_fid.at(end);
    }
    return run;
}

void for_each_polygon_ring(const FeatureRun& run, const std::function<void(std::span<const Point>)>& visit) {
    FeatureReader reader(run);
    while (const OGRFeatureUniquePtr feature = reader.next()) {
        visit_rings(*feature, run.path, reader.layer(), [&](const std::vector<Point>& points, const OGRLinearRing&) { visit(points); });
    }
}

void for_each_polygon_ring(const FeatureRun& run, const std::function<void(std::span<const Point>, std::span<const map::PointTag>)>& visit) {
    FeatureReader reader(run);
    std::vector<map::PointTag> tags;
    std::vector<double> z, m;
    while (const OGRFeatureUniquePtr feature = reader.next()) {
        visit_rings(*feature, run.path, reader.layer(), [&](const std::vector<Point>& points, const OGRLinearRing& ring) {
            z.clear();
            m.clear();
            append_zm(ring, z, m);  // (the Z and M the whole read gives the ring's points)
            tags.clear();
            for (std::size_t i = 0; i < z.size(); ++i) tags.push_back({std::bit_cast<std::uint64_t>(z[i]), std::bit_cast<std::uint64_t>(m[i])});
            visit(points, tags);
        });
    }
}

void for_each_polygon_ring(const std::string& path, const std::string& layer, std::uint64_t first, std::uint64_t end,
                           const std::function<void(std::span<const Point>)>& visit) {
    for_each_polygon_ring(FeatureRun{path, layer, first, end}, visit);
}

map::MapData read_lines(const FeatureRun& run) {
    FeatureReader reader(run);
    map::MapData lines;
    while (const OGRFeatureUniquePtr feature = reader.next()) {
        const std::string label = feature_label(run.path, reader.layer(), feature->GetFID());
        if (!add_lines(*feature, label, lines)) throw InputError(label + ": not a LineString or MultiLineString, as it was when the map was read");
    }
    return lines;
}

// The vertices of a layer's features, feature after feature: the map's, or, for a layer left in
// its file (VerticesInFile), its records' (lines of a .shp), its features' lines (a GeoPackage)
// or its features' rings (polygons), read again one at a time.
class VertexCursor {
public:
    VertexCursor(const map::MapData& map, const LayerInFile* in_file) : map_(map), in_file_(in_file) {}

    // Feature i's (features asked in order read the file once).
    VertexView at(std::size_t i) {
        if (in_file_ == nullptr) return {map_.vertices.data()};
        if (in_file_->polygons) return rings_at(i);
        if (in_file_->ogr_lines) return lines_at(i);
        if (i + 1 >= in_file_->record_vertex.size()) throw std::logic_error("a feature beyond the records read");
        if (!reader_ || i != next_) {
            reader_ = ShapeReader::open(in_file_->path, i);
            if (!reader_ || reader_->shp_size() != in_file_->size || modified_ns(in_file_->path) != in_file_->time) changed(i);
        }
        const ShapeRecord* record = reader_->next();
        next_ = i + 1;
        if (record == nullptr || !record->z.empty() || record->xy.size() != in_file_->record_vertex[i + 1] - in_file_->record_vertex[i]) {
            changed(i);
        }
        return {record->xy.data(), static_cast<std::size_t>(in_file_->record_vertex[i])};
    }

private:
    [[noreturn]] void changed(std::size_t record) const {
        throw changed_while_running(*in_file_, record, in_file_->polygons || in_file_->ogr_lines ? "feature" : "record");
    }

    // Feature i read again through OGR (features from i on, if it is not the next one).
    OGRFeatureUniquePtr feature_at(std::size_t i, std::size_t features) {
        if (i + 1 >= features) throw std::logic_error("a feature beyond the features read");
        if (!features_ || i != next_) {
            if (!unchanged(*in_file_)) changed(i);
            features_.emplace(in_file_->run(i, features - 1));
        }
        next_ = i + 1;
        try {
            OGRFeatureUniquePtr feature = features_->next();
            if (!feature) changed(i);
            return feature;
        } catch (const InputError&) {
            changed(i);
        }
    }

    // A polygon layer's feature i: its rings.
    VertexView rings_at(std::size_t i) {
        const OGRFeatureUniquePtr feature = feature_at(i, in_file_->record_ring.size());
        rings_.clear();
        ring_z_.clear();
        ring_m_.clear();
        const OGRGeometry* geometry = feature->GetGeometryRef();
        const bool with_z = geometry != nullptr && geometry->Is3D(), with_m = geometry != nullptr && geometry->IsMeasured();
        visit_rings(*feature, in_file_->path, features_->layer(), [&](std::vector<Point>&& points, const OGRLinearRing& ring) {
            rings_.push_back(std::move(points));
            if (!with_z && !with_m) return;
            std::vector<double> z, m;
            append_zm(ring, z, m);
            ring_z_.push_back(std::move(z));
            ring_m_.push_back(std::move(m));
        });
        if (rings_.size() != in_file_->record_ring[i + 1] - in_file_->record_ring[i]) changed(i);
        VertexView view{nullptr};
        view.rings = &rings_;
        if (with_z) view.ring_z = &ring_z_;
        if (with_m) view.ring_m = &ring_m_;
        view.first_ring = in_file_->record_ring[i];
        view.file = in_file_;
        return view;
    }

    // A lines layer's feature i read through OGR: its parts' vertices one after another, with
    // their Z and M if it has them.
    VertexView lines_at(std::size_t i) {
        const OGRFeatureUniquePtr feature = feature_at(i, in_file_->record_vertex.size());
        lines_.vertices.clear();
        lines_.chains.clear();
        z_.clear();
        m_.clear();
        const OGRGeometry* geometry = feature->GetGeometryRef();
        const bool zm = geometry != nullptr && (geometry->Is3D() || geometry->IsMeasured());
        if (!add_lines(*feature, in_file_->path, lines_, zm ? &z_ : nullptr, zm ? &m_ : nullptr) ||
            lines_.vertices.size() != in_file_->record_vertex[i + 1] - in_file_->record_vertex[i]) {
            changed(i);
        }
        VertexView view{lines_.vertices.data(), static_cast<std::size_t>(in_file_->record_vertex[i])};
        view.file = in_file_;
        if (zm && geometry->Is3D()) view.z = z_.data();
        if (zm && geometry->IsMeasured()) view.m = m_.data();
        return view;
    }

    const map::MapData& map_;
    const LayerInFile* in_file_;
    std::optional<ShapeReader> reader_;
    std::optional<FeatureReader> features_;  // (polygons, a GeoPackage's lines)
    std::vector<std::vector<Point>> rings_;
    std::vector<std::vector<double>> ring_z_, ring_m_;  // (rings_'s)
    map::MapData lines_;
    std::vector<double> z_, m_;  // (lines_'s)
    std::size_t next_ = 0;
};

// The arcs of a map left in its files, in order, as a TopoJSON writes them (write_topojson asks
// for arc 0, 1, …): chain a's kept vertices, from the feature that holds it (a lines layer's) or
// from the feature whose rings make it (a polygon coverage's arcs, made again from those rings
// alone by map::arcs_of, each vertex with the bits of the ring that made the arc, as build()
// takes them), read again feature after feature: each file once, a feature at a time held.
class ArcCursor {
public:
    ArcCursor(const map::MapData& map, const VerticesInFile& in_file, const map::Coverage& coverage, const std::vector<std::uint8_t>& kept)
        : map_(map), layers_(in_file.in_chain_order()), coverage_(coverage), kept_(kept) {
        if (!layers_.empty()) cursor_.emplace(map_, layers_.front());
    }

    void arc(std::size_t a, std::vector<Point>& positions) {
        if (a < asked_) throw std::logic_error("arcs asked for out of order");
        asked_ = a;
        const auto chain = static_cast<std::uint32_t>(a);
        while (layer_ < layers_.size() && chain >= chains_end(*layers_[layer_])) next_layer();
        if (layer_ == layers_.size()) throw std::logic_error("an arc beyond the layers' chains");
        const LayerInFile& layer = *layers_[layer_];
        positions.clear();
        const map::Chain range = map_.chains.at(a);
        if (!layer.polygons) {
            while (layer.record_chain[feature_ + 1] <= chain) ++feature_;
            if (loaded_ != feature_) view_ = read_up_to_feature();
            for (std::uint32_t v = range.first; v <= range.last; ++v) {
                if (kept_[v]) positions.push_back(view_[v]);
            }
            return;
        }
        while (coverage_.chains_before(layer.record_ring[feature_ + 1]) <= chain) ++feature_;
        if (loaded_ != feature_) make_arcs(layer, read_up_to_feature());
        const map::Chain made = made_.chains.at(chain - made_first_);
        if (made.last - made.first != range.last - range.first) changed(layer);
        for (std::uint32_t k = 0; k <= range.last - range.first; ++k) {
            if (kept_[range.first + k]) positions.push_back(made_.vertices[made.first + k]);
        }
    }

private:
    std::uint32_t chains_end(const LayerInFile& layer) const {
        return layer.polygons ? coverage_.chains_before(layer.record_ring.back()) : layer.record_chain.back();
    }

    void next_layer() {
        ++layer_;
        feature_ = next_ = 0;
        loaded_ = kNoFeature;
        if (layer_ < layers_.size()) cursor_.emplace(map_, layers_[layer_]);
    }

    // Feature feature_, the features before it read too (and passed over: they hold none of the
    // arcs asked for), so that the file is read in order once.
    VertexView read_up_to_feature() {
        VertexView view{nullptr};
        while (next_ <= feature_) view = cursor_->at(next_++);
        loaded_ = feature_;
        return view;
    }

    // The arcs the rings of feature_ make.
    void make_arcs(const LayerInFile& layer, const VertexView& rings) {
        const map::CoverageSlice slice = coverage_.slice(layer.record_ring[feature_], layer.record_ring[feature_ + 1]);
        try {
            made_ = map::arcs_of(slice, [&](const std::function<void(std::span<const Point>)>& visit) {
                for (const std::vector<Point>& ring : *rings.rings) visit(ring);
            });
        } catch (const std::invalid_argument&) {
            changed(layer);
        }
        made_first_ = slice.first_chain;
    }

    [[noreturn]] void changed(const LayerInFile& layer) const { throw changed_while_running(layer, feature_); }

    static constexpr std::size_t kNoFeature = std::numeric_limits<std::size_t>::max();
    const map::MapData& map_;
    std::vector<const LayerInFile*> layers_;
    const map::Coverage& coverage_;
    const std::vector<std::uint8_t>& kept_;
    std::optional<VertexCursor> cursor_;
    std::size_t layer_ = 0, feature_ = 0, next_ = 0, loaded_ = kNoFeature, asked_ = 0;
    VertexView view_{nullptr};  // (a lines layer's feature loaded_)
    map::MapData made_;         // (the arcs feature loaded_'s rings make, the first of them made_first_)
    std::uint32_t made_first_ = 0;
};

VertexCursor OgrDataset::Data::vertex_cursor(const map::MapData& map, const Layer& layer) const {
    if (!in_file) return VertexCursor(map, nullptr);
    for (std::size_t k = 0; k < layers.size(); ++k) {
        if (layers[k].get() != &layer) continue;
        const LayerInFile& file = in_file->layers.at(k);
        return VertexCursor(map, file.points ? nullptr : &file);  // (points: written back as they were)
    }
    throw std::logic_error("a layer that is not the dataset's");
}

namespace {

// Do two geometries hold the same coordinates, bit for bit? A LineString equals a one-part
// MultiLineString, and a ring may come back reversed (Shapefile writes rings in its own
// orientation); nothing else may differ.
bool same_coordinates(const OGRGeometry* expected, const OGRGeometry* actual, std::string& difference) {
    std::vector<const OGRSimpleCurve*> want, got;
    std::vector<const OGRPoint*> want_points, got_points;
    collect_parts(expected, want, want_points);
    collect_parts(actual, got, got_points);
    if (want.size() != got.size() || want_points.size() != got_points.size()) {
        difference = std::to_string(want.size()) + " parts became " + std::to_string(got.size());
        return false;
    }
    for (std::size_t k = 0; k < want_points.size(); ++k) {
        if (!(want_points[k]->getX() == got_points[k]->getX()) || !(want_points[k]->getY() == got_points[k]->getY())) {
            difference = "point " + std::to_string(k) + " moved";
            return false;
        }
    }
    for (std::size_t k = 0; k < want.size(); ++k) {
        const int n = want[k]->getNumPoints();
        if (n != got[k]->getNumPoints()) {
            difference = "part " + std::to_string(k) + " has " + std::to_string(got[k]->getNumPoints()) +
                         " vertices, not " + std::to_string(n);
            return false;
        }
        auto matches = [&](bool reversed, int& bad) {
            for (int i = 0; i < n; ++i) {
                const int j = reversed ? n - 1 - i : i;
                const bool z_differs = want[k]->Is3D() && got[k]->Is3D() && !(want[k]->getZ(i) == got[k]->getZ(j));
                if (!(want[k]->getX(i) == got[k]->getX(j)) || !(want[k]->getY(i) == got[k]->getY(j)) || z_differs) {
                    bad = i;
                    return false;
                }
            }
            return true;
        };
        int bad = 0, ignored = 0;
        const bool ring = wkbFlatten(want[k]->getGeometryType()) == wkbLineString && want[k]->get_IsClosed();
        if (!matches(false, bad) && !(ring && matches(true, ignored))) {
            char text[200];
            std::snprintf(text, sizeof text, "part %zu, vertex %d: (%.17g, %.17g) was written as (%.17g, %.17g)", k, bad,
                          want[k]->getX(bad), want[k]->getY(bad), got[k]->getX(bad), got[k]->getY(bad));
            difference = text;
            return false;
        }
    }
    return true;
}

// Layer creation options toposimp adds unless the user set them (map_formats.cpp says which).
CPLStringList layer_options_for(const MapFormatRules* rules, const std::vector<std::string>& given,
                                const OgrDataset::Data::Layer& layer) {
    CPLStringList options;
    for (const auto& option : given) options.AddString(option.c_str());
    if (rules == nullptr) return options;
    if (rules->layer_option) {
        const std::string option = rules->layer_option;
        const std::size_t equals = option.find('=');
        const std::string key = option.substr(0, equals);
        if (options.FetchNameValue(key.c_str()) == nullptr) options.SetNameValue(key.c_str(), option.substr(equals + 1).c_str());
    }
    // Databases with an FID column: keep the source's FID column name, and never collide with an
    // attribute field of that name (GML inputs have a string 'fid').
    if (rules->keeps_fid_column && options.FetchNameValue("FID") == nullptr) {
        std::string fid = layer.fid_column.empty() ? "fid" : layer.fid_column;
        while (layer.definition->GetFieldIndex(fid.c_str()) >= 0) fid += "_";
        options.SetNameValue("FID", fid.c_str());
    }
    return options;
}

// Feature `index` of a layer lines_written_here takes, as a record of `shapes`: the kept vertices
// of each of its chains a part (build_geometry's lines, without the empty parts, which OGR's
// writer leaves out); NULL and empty geometries a null shape. `part_starts` and `xy` are the
// caller's room for the record.
void add_record_lines(PolyLineWriter& shapes, const OgrDataset::Data::Layer& layer, std::size_t index, const map::MapData& map,
                      VertexView at, const std::vector<std::uint8_t>& kept, const std::string& layer_name, const std::string& path,
                      std::vector<std::uint32_t>& part_starts, std::vector<Point>& xy) {
    part_starts.clear();
    xy.clear();
    const OgrDataset::Data::Layer::Shape& shape = layer.shapes[index];
    if (shape.kind == OgrDataset::Data::Layer::Kind::lines) {
        for (std::uint32_t k = 0; k < shape.count; ++k) {
            const std::uint32_t chain = layer.items[shape.first + k];
            if (chain == kEmptyPart) continue;
            const auto start = static_cast<std::uint32_t>(xy.size());
            for (std::uint32_t v = map.chains[chain].first; v <= map.chains[chain].last; ++v) {
                if (kept[v]) xy.push_back(at[v]);
            }
            if (xy.size() > start) part_starts.push_back(start);
        }
    }
    if (!shapes.add(part_starts, xy)) {
        throw OutputError("cannot write feature " + std::to_string(layer.features[index]->GetFID()) + " of layer '" + layer_name +
                          "' to '" + path + "': a Shapefile's .shp holds at most 4 GB; write a GeoPackage or FlatGeobuf");
    }
}

// About what a Shapefile output of `layers` takes, for the choice of writing it in memory first
// (WriteOptions::in_memory_at_most): its records (each kept vertex twice, as a coverage's shared
// borders are in two rings; a record's header, box and part), unless PolyLineWriter writes them
// to disk (`shapes_on_disk`), and its attributes (a field of no stated width at 254 bytes).
std::uint64_t shapefile_bytes(const std::vector<std::unique_ptr<OgrDataset::Data::Layer>>& layers, const std::vector<std::uint8_t>& kept,
                              bool shapes_on_disk) {
    std::uint64_t bytes = 0;
    if (!shapes_on_disk) {
        const auto kept_vertices = static_cast<std::uint64_t>(std::count_if(kept.begin(), kept.end(), [](std::uint8_t k) { return k != 0; }));
        bool z_or_m = false;
        for (const auto& layer : layers) z_or_m = z_or_m || OGR_GT_HasZ(layer->geometry_type) || OGR_GT_HasM(layer->geometry_type);
        bytes += 2 * kept_vertices * (z_or_m ? 32 : 16);
    }
    for (const auto& layer : layers) {
        std::uint64_t record = 1 + (shapes_on_disk ? 0 : 64);
        for (int i = 0; i < layer->definition->GetFieldCount(); ++i) {
            const int width = layer->definition->GetFieldDefn(i)->GetWidth();
            record += width > 0 ? static_cast<std::uint64_t>(width) : 254;
        }
        bytes += record * layer->features.size();
    }
    return bytes;
}

// Whether `layer` goes to the Shapefile `options.path` through PolyLineWriter: a 2D LineString or
// MultiLineString layer whose every feature is lines, NULL or empty, written as one .shp (a
// lower-case extension: GDAL's name for the .shx is then ".shx") without creation options.
bool lines_written_here(const OgrDataset::Data::Layer& layer, const WriteOptions& options) {
    using Kind = OgrDataset::Data::Layer::Kind;
    if (options.shapes_through_ogr || !options.layer_options.empty() || !options.dataset_options.empty()) return false;
    if (std::filesystem::path(options.path).extension() != ".shp" || options.path.rfind("/vsi", 0) == 0) return false;
    if (layer.geometry_type != wkbLineString && layer.geometry_type != wkbMultiLineString) return false;
    return std::all_of(layer.shapes.begin(), layer.shapes.end(), [&](const OgrDataset::Data::Layer::Shape& shape) {
        return shape.kind == Kind::null || shape.kind == Kind::lines || (shape.kind == Kind::untouched && layer.untouched[shape.first]->IsEmpty());
    });
}

}  // namespace

TopoGeometry OgrDataset::Data::topo_geometry(const Layer& layer, std::size_t index) const {
    using Kind = Layer::Kind;
    using Type = TopoGeometry::Type;
    const Layer::Shape& shape = layer.shapes[index];
    const std::vector<std::uint32_t>& items = layer.items;
    TopoGeometry topo;
    topo.has_z = OGR_GT_HasZ(shape.type);
    topo.has_m = OGR_GT_HasM(shape.type);
    switch (shape.kind) {
        case Kind::null: return topo;
        case Kind::untouched: {
            const OGRGeometry& geometry = *layer.untouched[shape.first];
            auto add = [&](const OGRPoint& point) {
                if (!point.IsEmpty()) topo.points.push_back({point.getX(), point.getY()});
            };
            if (wkbFlatten(geometry.getGeometryType()) == wkbPoint) {
                topo.type = Type::point;
                add(*geometry.toPoint());
            } else {
                topo.type = Type::multi_point;
                for (const OGRPoint* point : *geometry.toMultiPoint()) add(*point);
            }
            return topo;
        }
        case Kind::lines:
            topo.type = wkbFlatten(shape.type) == wkbLineString ? Type::line_string : Type::multi_line_string;
            for (std::uint32_t k = 0; k < shape.count; ++k) {
                const std::uint32_t chain = items[shape.first + k];
                topo.lines.push_back(chain == kEmptyPart ? std::vector<std::int64_t>{} : std::vector<std::int64_t>{chain});
            }
            return topo;
        case Kind::polygons: {
            topo.type = wkbFlatten(shape.type) == wkbPolygon ? Type::polygon : Type::multi_polygon;
            std::uint32_t k = shape.first;
            while (k < shape.first + shape.count) {
                auto& polygon = topo.polygons.emplace_back();
                const std::uint32_t rings = items[k++];
                for (std::uint32_t r = 0; r < rings; ++r) {
                    auto& ring = polygon.emplace_back();
                    for (const map::Coverage::ArcUse use : coverage.ring_arcs(items[k++])) {
                        ring.push_back(use.reversed ? ~static_cast<std::int64_t>(use.chain) : static_cast<std::int64_t>(use.chain));
                    }
                }
            }
            return topo;
        }
    }
    return topo;
}

void OgrDataset::move_points(std::span<const Point> points) {
    data_->points_moved = true;
    for (auto& layer : data_->layers) {
        for (std::size_t g = 0; g < layer->untouched.size(); ++g) {
            std::uint32_t next = layer->untouched_points[g];
            auto place = [&](OGRPoint& point) {
                if (point.IsEmpty() || next >= points.size()) return;
                point.setX(points[next].x);
                point.setY(points[next].y);
                ++next;
            };
            OGRGeometry& geometry = *layer->untouched[g];
            if (wkbFlatten(geometry.getGeometryType()) == wkbPoint) {
                place(*geometry.toPoint());
            } else {
                for (OGRPoint* point : *geometry.toMultiPoint()) place(*point);
            }
        }
    }
}

std::vector<std::string> OgrDataset::write(const WriteOptions& options, const map::MapData& map,
                                           const std::vector<std::uint8_t>& kept) const {
    const Data& data = *data_;
    std::vector<std::string> warnings;
    GDALDriver* driver = vector_driver_for(options.path, options.format);
    const std::string driver_name = driver->GetDescription();
    const MapFormatRules* rules = map_format_rules(driver_name);
    const std::size_t layer_count = data.layers.size();
    if (layer_count > 1 && !(rules && rules->several_layers)) {
        std::string names;
        for (const auto& layer : data.layers) names += (names.empty() ? "" : ", ") + layer->name;
        throw OutputError("a " + driver_name + " file holds one layer and the input has " + std::to_string(layer_count) +
                          " (" + names + "): pick one with -l, or write a GeoPackage");
    }
    if (!options.layer_name.empty() && layer_count > 1) throw OutputError("-nln names one layer, and there are " + std::to_string(layer_count));
    OutputFile output(options.path, options.overwrite, options.stdout_stream);
    if (output.to_stdout() && rules && rules->several_files) {
        throw OutputError("a " + driver_name + " is several files and cannot go to stdout; use -f GeoJSON, FlatGeobuf or GPKG");
    }
    auto output_name = [&](const Data::Layer& layer) { return options.layer_name.empty() ? layer.name : options.layer_name; };

    auto source_of = [&](const Data::Layer& layer) {
        LayerSource source;
        source.name = output_name(layer);
        source.srs = layer.srs.get();
        source.definition = layer.definition;
        source.feature_count = layer.features.size();
        source.feature = [&layer](std::size_t i) { return layer.features[i].get(); };
        // (Features in order: a layer left in its file is read again once, feature after feature.)
        auto vertices = std::make_shared<VertexCursor>(data.vertex_cursor(map, layer));
        source.geometry = [&data, &layer, &map, &kept, vertices](std::size_t i) {
            return data.build_geometry(layer, i, map, vertices->at(i), kept);
        };
        return source;
    };
    const bool topology = driver_name == "TopoJSON";
    if (options.transform && !topology) throw OutputError("a quantized output (--quantize) is TopoJSON: name it .topojson or use -f TopoJSON");
    if (rules && rules->own_writer) {
        // GDAL 3.6's GeoJSON writer rounds coordinates, and GDAL cannot write TopoJSON: toposimp
        // writes both itself (where the map was left in its files, a GeoJSON's features and a
        // TopoJSON's arcs from those files read again).
        if (data.in_file && topology && (options.transform || options.vertex_ranks)) {
            throw std::logic_error("a map left in its files written as a quantized or ranked TopoJSON");
        }
        if (!options.layer_options.empty() || !options.dataset_options.empty()) {
            warnings.push_back("-lco/-dsco are ignored for " + driver_name + ": toposimp writes it itself to keep coordinates exact");
        }
        std::vector<std::string> more;
        if (topology) {
            std::vector<TopologyLayer> layers;
            for (const auto& layer_pointer : data.layers) {
                const Data::Layer& layer = *layer_pointer;
                TopologyLayer topo;
                topo.name = output_name(layer);
                topo.definition = layer.definition;
                topo.feature_count = layer.features.size();
                topo.feature = [&layer](std::size_t i) { return layer.features[i].get(); };
                topo.geometry = [&data, &layer](std::size_t i) { return data.topo_geometry(layer, i); };
                layers.push_back(std::move(topo));
            }
            std::optional<ArcCursor> in_files;
            if (data.in_file) in_files.emplace(map, *data.in_file, data.coverage, kept);
            auto arc = [&map, &kept, &options, &in_files](std::size_t a, std::vector<Point>& positions, std::vector<int>& ranks) {
                if (in_files) return in_files->arc(a, positions);
                positions.clear();
                for (std::uint32_t v = map.chains[a].first; v <= map.chains[a].last; ++v) {
                    if (!kept[v]) continue;
                    positions.push_back(map.vertices[v]);
                    if (options.vertex_ranks) ranks.push_back((*options.vertex_ranks)[v]);
                }
            };
            more = write_topojson(output.staging_path(), layers, map.chains.size(), arc, options.path,
                                  options.transform ? &*options.transform : nullptr);
        } else {
            more = write_geojson(output.staging_path(), source_of(*data.layers.front()), options.path);
        }
        warnings.insert(warnings.end(), more.begin(), more.end());
    } else {
        QuietGdal quiet;
        CPLStringList dataset_options;
        for (const auto& option : options.dataset_options) dataset_options.AddString(option.c_str());
        // CSV writes WKT: ask for 17 significant digits (the read-back below checks the result).
        CPLConfigOptionSetter precision("OGR_WKT_PRECISION", "17", true);
        // A Shapefile is written record by record, each with seeks and small writes (730 000
        // system calls for GSHHG's 180 000 lines, most of the write): it is written in memory,
        // then copied to the staging folder a file at a time — unless it would take more than
        // a sixteenth of the machine's memory (or what the options say): then straight to the
        // staging folder, so that no process holds a big map's output. The bytes are GDAL's
        // either way.
        std::optional<MemoryFolder> memory;
        if (driver_name == "ESRI Shapefile") {
            const bool shapes_on_disk = layer_count == 1 && lines_written_here(*data.layers.front(), options);
            if (shapefile_bytes(data.layers, kept, shapes_on_disk) <= options.in_memory_at_most.value_or(machine_memory() / 16)) memory.emplace();
        }
        const std::string create_at =
            memory ? memory->path() + "/" + std::filesystem::path(output.staging_path()).filename().string() : output.staging_path();
        DatasetPtr dataset(driver->Create(create_at.c_str(), 0, 0, 0, GDT_Unknown, dataset_options.List()));
        if (!dataset) throw OutputError("cannot create '" + options.path + "' (" + driver_name + ")" + last_gdal_error());
        for (const auto& layer_pointer : data.layers) {
            const Data::Layer& layer = *layer_pointer;
            const std::string name = output_name(layer);
            CPLStringList layer_options = layer_options_for(rules, options.layer_options, layer);
            // A Shapefile of lines: OGR writes the attributes and the CRS (a layer without
            // geometry: the .dbf and .prj only, the same bytes), PolyLineWriter the shapes.
            std::optional<PolyLineWriter> shapes;
            std::vector<std::uint32_t> part_starts;
            std::vector<Point> xy;
            if (driver_name == "ESRI Shapefile" && layer_count == 1 && lines_written_here(layer, options)) {
                shapes.emplace(output.staging_path(), options.path);
            }
            OGRLayer* target = dataset->CreateLayer(name.c_str(), layer.srs.get(), shapes ? wkbNone : layer.geometry_type, layer_options.List());
            if (target == nullptr) throw OutputError("cannot create layer '" + name + "' in '" + options.path + "'" + last_gdal_error());
            for (int i = 0; i < layer.definition->GetFieldCount(); ++i) {
                if (target->CreateField(layer.definition->GetFieldDefn(i), TRUE) != OGRERR_NONE) {
                    throw OutputError("cannot create field '" + std::string(layer.definition->GetFieldDefn(i)->GetNameRef()) +
                                      "' in '" + options.path + "'" + last_gdal_error());
                }
            }
            if (target->GetLayerDefn()->GetFieldCount() != layer.definition->GetFieldCount()) {
                throw OutputError("'" + options.path + "' (" + driver_name + ") could not keep all " +
                                  std::to_string(layer.definition->GetFieldCount()) + " fields of layer '" + name + "'");
            }
            std::vector<int> field_map(layer.definition->GetFieldCount());
            for (std::size_t i = 0; i < field_map.size(); ++i) field_map[i] = static_cast<int>(i);
            const bool keep_fids = !layer.fid_column.empty();
            const bool transaction = dataset->StartTransaction() == OGRERR_NONE;
            VertexCursor vertices = data.vertex_cursor(map, layer);
            for (std::size_t i = 0; i < layer.features.size(); ++i) {
                OGRFeature feature(target->GetLayerDefn());
                feature.SetFrom(layer.features[i].get(), field_map.data(), TRUE);
                if (keep_fids) feature.SetFID(layer.features[i]->GetFID());
                if (shapes) {
                    add_record_lines(*shapes, layer, i, map, vertices.at(i), kept, name, options.path, part_starts, xy);
                } else {
                    feature.SetGeometryDirectly(data.build_geometry(layer, i, map, vertices.at(i), kept).release());
                }
                if (target->CreateFeature(&feature) != OGRERR_NONE) {
                    throw OutputError("cannot write feature " + std::to_string(layer.features[i]->GetFID()) + " of layer '" +
                                      name + "' to '" + options.path + "'" + last_gdal_error());
                }
            }
            if (transaction && dataset->CommitTransaction() != OGRERR_NONE) {
                throw OutputError("cannot commit '" + options.path + "'" + last_gdal_error());
            }
            if (shapes) shapes->finish();
        }
        dataset.reset();
        if (CPLGetLastErrorType() >= CE_Failure) throw OutputError("error writing '" + options.path + "'" + last_gdal_error());
        if (memory) memory->copy_to(std::filesystem::path(output.staging_path()).parent_path(), options.path);
        // A Shapefile input's .prj read as a file (read_layer) goes next to the output as it is.
        for (const auto& layer : data.layers) {
            if (layer->prj.empty()) continue;
            if (driver_name != "ESRI Shapefile") throw std::logic_error("a .prj kept as a file for a " + driver_name + " output");
            std::error_code error;
            std::filesystem::copy_file(layer->prj, std::filesystem::path(output.staging_path()).replace_extension(".prj"),
                                       std::filesystem::copy_options::overwrite_existing, error);
            if (error) throw OutputError("cannot copy '" + layer->prj.string() + "' next to '" + options.path + "': " + error.message());
        }
    }

    // Read the file back: coordinates must have survived bit for bit, features all there. A
    // Shapefile's records are decoded here (shapefile.hpp): through OGR, each geometry handed out
    // would make the driver parse the .prj again. (Not a TopoJSON whose positions carry a rank:
    // GDAL 3.6's reader drops arcs with a third coordinate. Nor one of a map left in its files:
    // GDAL's reader holds the whole file as a JSON tree, about 21 times its size (856 MiB for
    // GSHHG's 41 MB at 10 %), the whole output map this process never holds otherwise; nor one
    // whose tree would take more than `read_back_at_most`, which could end the run for want of
    // memory. Their x and y are printed by the same code as the TopoJSON that is read back, and
    // the by-parts one is that TopoJSON's bytes: tests/python/test_parts.py.)
    bool read_back = !(topology && (options.vertex_ranks || data.in_file));
    if (read_back && topology) {
        std::error_code error;
        const std::uintmax_t size = std::filesystem::file_size(output.staging_path(), error);
        constexpr std::uint64_t kTreePerByte = 21;
        if (!error && size > options.read_back_at_most.value_or(machine_memory() / 4) / kTreePerByte) {
            read_back = false;
            warnings.push_back("'" + options.path + "' (" + std::to_string(size >> 20) + " MiB) was not read back through GDAL to check it: " +
                               "GDAL's TopoJSON reader would hold about " + std::to_string(kTreePerByte) +
                               " times its size; its coordinates are printed exactly (shortest round-trip decimals)");
        }
    }
    if (read_back) {
        auto check_geometry = [&](const Data::Layer& layer, std::size_t i, const OGRGeometry* actual, VertexView at) {
            std::string difference;
            const auto expected = data.build_geometry(layer, i, map, at, kept, topology);
            if (!same_coordinates(expected.get(), actual, difference)) {
                throw OutputError("the " + driver_name + " driver changed coordinates while writing '" + options.path +
                                  "' (layer '" + output_name(layer) + "', feature " + std::to_string(layer.features[i]->GetFID()) +
                                  ", " + difference +
                                  "); toposimp never rounds coordinates: write " + recommended_formats_but(driver_name) + " instead");
            }
        };
        auto check_count = [&](const Data::Layer& layer, std::size_t count) {
            if (count != layer.features.size()) {
                throw OutputError("'" + options.path + "' holds " + std::to_string(count) + " features in layer '" +
                                  output_name(layer) + "' after writing, not " + std::to_string(layer.features.size()));
            }
        };
        // (Record by record, none kept: the check adds no memory at the run's end, where the peak
        // can be.)
        bool decoded = false;
        if (driver_name == "ESRI Shapefile" && layer_count == 1) {
            const Data::Layer& layer = *data.layers.front();
            VertexCursor vertices = data.vertex_cursor(map, layer);
            std::size_t count = 0;
            decoded = for_each_shape(output.staging_path(), [&](std::uint64_t fid, const ShapeRecord& shape) {
                ++count;
                if (fid >= layer.features.size()) return true;
                const VertexView at = vertices.at(fid);
                if (!record_holds_lines(layer, fid, map, at, kept, shape)) {
                    check_geometry(layer, fid, shape.part_starts.empty() ? nullptr : shape_geometry(shape).get(), at);
                }
                return true;
            });
            if (decoded) check_count(layer, count);
        }
        if (!decoded) {
            DatasetPtr written = open_vector(output.staging_path(), driver_name.c_str());
            QuietGdal quiet;
            for (const auto& layer_pointer : data.layers) {
                const Data::Layer& layer = *layer_pointer;
                const std::string name = output_name(layer);
                OGRLayer* check = written->GetLayerByName(name.c_str());
                if (check == nullptr && written->GetLayerCount() == 1) check = written->GetLayer(0);
                if (check == nullptr) throw OutputError("'" + options.path + "': written layer '" + name + "' cannot be read back");
                // Where the driver stored the input's FIDs, it may hand the features back in FID
                // order, not in the order written: each is compared with the input feature of its
                // FID (issue 29: a GeoJSON's "id"s out of order, written to GeoPackage).
                VertexCursor vertices = data.vertex_cursor(map, layer);
                std::unordered_map<GIntBig, std::size_t> by_fid;
                if (rules && rules->keeps_fid_column && !layer.fid_column.empty()) {
                    for (std::size_t k = 0; k < layer.features.size(); ++k) by_fid.emplace(layer.features[k]->GetFID(), k);
                }
                // GDAL's TopoJSON reader drops the features whose geometry is null (written as the
                // specification's {"type":null}): each feature a TopoJSON gives back is the
                // input's next one that is not.
                const auto null = [&](std::size_t k) { return topology && layer.shapes[k].kind == Data::Layer::Kind::null; };
                std::size_t nulls = 0;
                for (std::size_t k = 0; k < layer.shapes.size(); ++k) nulls += null(k) ? 1 : 0;
                std::size_t i = 0, next = 0;  // (next: the input's feature after the last one compared)
                for (OGRFeatureUniquePtr feature{check->GetNextFeature()}; feature; feature.reset(check->GetNextFeature()), ++i) {
                    std::size_t at = i;
                    if (topology) {
                        while (next < layer.features.size() && null(next)) vertices.at(next++);  // (read in order)
                        at = next++;
                    }
                    if (!by_fid.empty()) {
                        const auto found = by_fid.find(feature->GetFID());
                        if (found == by_fid.end()) {
                            throw OutputError("the " + driver_name + " driver wrote a feature with FID " + std::to_string(feature->GetFID()) +
                                              ", which the input's layer '" + layer.name + "' does not have, to '" + options.path + "'");
                        }
                        at = found->second;
                    }
                    if (at < layer.features.size()) check_geometry(layer, at, feature->GetGeometryRef(), vertices.at(at));
                }
                check_count(layer, i + nulls);
            }
        }
    }
    if (options.before_commit) options.before_commit(output.staging_path());
    // An existing output is deleted by its driver (a Shapefile's side files with it), but one of
    // toposimp's own writers', a single file that commit() removes itself: GDAL deletes a dataset
    // by opening it to list its files, and opening an old TopoJSON parses it whole, about 21
    // times its size (overwriting GSHHG's at 10 % by parts: the command's peak 1 017 MiB, 524
    // MiB for a new file).
    const bool own_file = rules && rules->own_writer;
    output.commit([driver, own_file](const std::string& existing) {
        if (own_file) return;
        QuietGdal quiet;
        driver->Delete(existing.c_str());
    });
    return warnings;
}

namespace {

// Appends the points of the features `layer` hands out (after any filter set on it).
void read_points_of(OGRLayer& layer, const std::string& path, std::vector<Point>& points) {
    QuietGdal quiet;
    // Only the geometry matters: skip decoding the attributes (a third of the time on a GeoPackage).
    std::vector<std::string> names;
    OGRFeatureDefn* definition = layer.GetLayerDefn();
    for (int i = 0; i < definition->GetFieldCount(); ++i) names.emplace_back(definition->GetFieldDefn(i)->GetNameRef());
    names.emplace_back("OGR_STYLE");
    std::vector<const char*> ignored;
    for (const std::string& name : names) ignored.push_back(name.c_str());
    ignored.push_back(nullptr);
    layer.SetIgnoredFields(ignored.data());

    OGRFeature* current = nullptr;
    auto label = [&] { return feature_label(path, layer, current->GetFID()); };
    auto add = [&](const OGRPoint& point) {
        if (point.IsEmpty()) return;
        const Point p{point.getX(), point.getY()};
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(label() + ": control point has a non-finite coordinate");
        points.push_back(p);
    };
    // A feature GDAL could not read is an error at once: a later read may clear GDAL's last
    // error (a Shapefile with a .prj did, and a broken record's point was silently left out).
    CPLErrorReset();
    for (;;) {
        OGRFeatureUniquePtr feature{layer.GetNextFeature()};
        if (CPLGetLastErrorType() >= CE_Failure) throw InputError("error reading '" + path + "'" + last_gdal_error());
        if (!feature) break;
        current = feature.get();
        const OGRGeometry* geometry = feature->GetGeometryRef();
        if (geometry == nullptr) continue;
        switch (wkbFlatten(geometry->getGeometryType())) {
            case wkbPoint: add(*geometry->toPoint()); break;
            case wkbMultiPoint:
                for (const OGRPoint* point : *geometry->toMultiPoint()) add(*point);
                break;
            default:
                throw InputError(label() + ": control points must be Point or MultiPoint, not " +
                                 OGRGeometryTypeToName(geometry->getGeometryType()));
        }
    }
    if (CPLGetLastErrorType() >= CE_Failure) throw InputError("error reading '" + path + "'" + last_gdal_error());
}

}  // namespace

PointsSpec split_points_spec(const std::string& spec) {
    PointsSpec split{spec, {}};
    std::error_code error;
    const std::size_t colon = spec.rfind(':');
    if (!std::filesystem::exists(spec, error) && colon != std::string::npos && colon > 0 && spec.rfind("/vsi", 0) != 0) {
        split.path = spec.substr(0, colon);
        split.layer = spec.substr(colon + 1);
    }
    return split;
}

std::vector<Point> read_control_points(const std::string& spec, unsigned threads) {
    const auto [path, layer_name] = split_points_spec(spec);
    DatasetPtr dataset = open_vector(path);
    OGRLayer& layer = pick_layer(*dataset, path, layer_name);
    // A GeoPackage is read with SQLite directly (gpkg_points.hpp): ten times less CPU than
    // OGR's feature by feature, on several connections at once.
    const std::string driver = dataset->GetDriver() != nullptr ? dataset->GetDriver()->GetDescription() : "";
    if (driver == "GPKG" && path.rfind("/vsi", 0) != 0) {
        const GpkgTable table{path, layer.GetName(), layer.GetGeometryColumn(), layer.GetFIDColumn()};
        if (std::optional<std::vector<Point>> points = read_gpkg_points(table, threads)) return std::move(*points);
    }
    // A Shapefile's records are decoded here too (shapefile.hpp): OGR would parse its .prj first.
    if (driver == "ESRI Shapefile" && is_local_shp(path)) {
        if (std::optional<std::vector<Point>> points = read_shapefile_points(path)) return std::move(*points);
    }
    std::vector<Point> points;
    const GIntBig count = layer.GetFeatureCount(FALSE);
    if (count > 0) points.reserve(static_cast<std::size_t>(count));
    read_points_of(layer, path, points);
    return points;
}

std::vector<Point> read_control_points(const MemoryLayers& layers) {
    DatasetPtr dataset = memory_dataset(layers);
    std::vector<Point> points;
    for (int i = 0; i < dataset->GetLayerCount(); ++i) read_points_of(*dataset->GetLayer(i), layers.source, points);
    return points;
}

void write_geopackage(const MemoryLayers& layers, const std::string& path) {
    DatasetPtr memory = memory_dataset(layers);
    register_drivers();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GPKG");
    if (driver == nullptr) throw OutputError("GDAL has no GPKG driver");
    QuietGdal quiet;
    DatasetPtr dataset{driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr)};
    if (!dataset) throw OutputError("cannot write '" + path + "'" + last_gdal_error());
    const char* options[] = {"SPATIAL_INDEX=NO", nullptr};
    for (int i = 0; i < memory->GetLayerCount(); ++i) {
        OGRLayer& source = *memory->GetLayer(i);
        if (dataset->CopyLayer(&source, source.GetName(), const_cast<char**>(options)) == nullptr) {
            throw OutputError("cannot write layer '" + std::string(source.GetName()) + "' to '" + path + "'" + last_gdal_error());
        }
    }
}

}  // namespace toposimp::io
