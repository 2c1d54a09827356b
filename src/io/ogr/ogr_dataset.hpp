// OGR adapter for `toposimp map`: reads the layers of a dataset into one engine MapData — lines
// as chains, polygon rings as one coverage of shared arcs across all layers, points as control
// points — keeps every feature's attributes, and writes the simplified layers back through any
// OGR driver with the same fields, CRS, feature order, layer names and geometry types.
#pragma once

#include "core/map/map_data.hpp"
#include "io/ogr/topo_transform.hpp"

#include <cmath>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace toposimp::map {
class Coverage;
struct PointTag;
}

namespace toposimp::io {

// What one input layer looked like; for logging and the JSON summary.
struct LayerSummary {
    std::string layer;
    std::uint64_t features = 0;
    std::uint64_t empty_geometries = 0;  // NULL or empty: written back unchanged
    std::uint64_t untouched_points = 0;  // Point features: unchanged, used as control points
    std::uint64_t polygon_features = 0;
    std::uint64_t line_features = 0;
    bool has_z = false;
    bool has_m = false;
};

struct DatasetSummary {
    std::string driver;
    std::vector<LayerSummary> layers;
    std::uint64_t arcs = 0;              // polygon rings split at nodes
    std::uint64_t shared_arcs = 0;       // arcs used by two rings (or twice)
    std::uint64_t degenerate_rings = 0;  // fewer than 3 corners or flat: written back unchanged
    // Read with vertices_in_file but read whole: which layer could not be left in its file, and why.
    std::string read_whole_because;

    std::uint64_t features() const;
    std::uint64_t sum(std::uint64_t LayerSummary::*field) const;
};

struct WriteOptions {
    std::string path;                          // file name, or /vsistdout/
    std::string format;                        // OGR driver short name; empty: from the extension
    std::string layer_name;                    // -nln (one layer only); empty: the input layer's
    std::vector<std::string> layer_options;    // -lco KEY=VALUE
    std::vector<std::string> dataset_options;  // -dsco KEY=VALUE
    bool overwrite = false;
    std::ostream* stdout_stream = nullptr;     // where /vsistdout/ output goes
    std::optional<TopoTransform> transform;   // TopoJSON only: quantized with this transform
    const std::vector<std::uint8_t>* vertex_ranks = nullptr;  // TopoJSON only: per map vertex, a third coordinate
    // Called with the written (and verified) file before it is moved into place; throwing
    // from it leaves no output.
    std::function<void(const std::string& written)> before_commit;
    // A Shapefile of 2D lines gets its .shp and .shx through OGR too, as any other output, not
    // from PolyLineWriter (tests compare the two).
    bool shapes_through_ogr = false;
    // A Shapefile is written in memory, then copied out, when it would take at most this many
    // bytes (shapefile_bytes); else straight to its staging folder. Default: a sixteenth of the
    // machine's memory. The bytes are the same either way.
    std::optional<std::uint64_t> in_memory_at_most;
    // A TopoJSON is read back through GDAL, whose reader holds the whole file as a JSON tree
    // (about 21 times its size), only when that takes at most this many bytes; else it is
    // moved into place unread, with a warning. Default: a quarter of the machine's memory.
    std::optional<std::uint64_t> read_back_at_most;
};

// Layers handed over in memory (the Python module): each feature's geometry as WKB, in order.
// Messages name them as files are named: "'<source>', layer '<name>', feature <position>".
struct MemoryLayer {
    std::string name;
    std::string crs_wkt;           // empty: no CRS
    std::vector<std::string> wkb;  // per feature (ISO or extended WKB); empty: a NULL geometry
};
struct MemoryLayers {
    std::string source = "<memory>";
    std::vector<MemoryLayer> layers;
};

// Where the vertices of a map read with OgrDataset::read's `vertices_in_file` are: the features
// of layers of Shapefiles, GeoPackages or FlatGeobufs, read again by whoever needs them. Each
// layer holds either
// - lines: the records of a plain PolyLine Shapefile, decoded as read_shapefile_shapes decodes
//   them, or the (Multi)LineStrings of a GeoPackage's or FlatGeobuf's layer, or of a Shapefile's
//   with Z or M, read through OGR (read_lines; their Z and M only when the output is written): each
//   feature's non-empty parts its chains, in order, their vertices the map's from the layer's first
//   feature's on; or
// - polygons: the rings of a polygon layer (for_each_polygon_ring), planned as one coverage
//   with the other polygon layers' (map::Coverage::plan): the map's chains after the lines' are
//   its arcs, in the order the features first use them; a run of features makes its own with
//   map::arcs_of(coverage->slice(...)).
// The map holds the chains, and no vertex.
struct FeatureRun;
struct LayerInFile {
    std::string path;                          // its .shp, .gpkg or .fgb (an absolute path)
    std::string layer;                         // its name
    std::uintmax_t size = 0;                   // the file's size and modification time (ns) when it was read
    std::int64_t time = 0;
    bool polygons = false;
    bool points = false;                       // a 2D point layer, read whole (control points): no chain, nothing else here
    bool ogr_lines = false;                    // lines read through OGR (a GeoPackage's, FlatGeobuf's, or Shapefile's with Z or M or a deleted record)
    bool each_by_fid = false;                  // a FlatGeobuf's: each feature read by its FID, its index (FeatureRun)
    std::vector<std::uint64_t> record_vertex;  // per feature and one more: the first vertex of its chains
    std::vector<std::uint32_t> record_chain;   // per feature and one more: its first chain
    std::vector<std::uint32_t> record_ring;    // polygons: per feature and one more, its first ring
    // A GeoPackage's, or a Shapefile's with a deleted record: per feature and one more, its FID
    // (rising in the order OGR reads the layer; the last one past the last feature's; a
    // Shapefile's FIDs are its record numbers). Empty: each feature's FID is its index (a
    // Shapefile without deleted records, a FlatGeobuf).
    std::vector<std::int64_t> record_fid;

    // Its features [first, end).
    FeatureRun run(std::uint64_t first, std::uint64_t end) const;
};
struct VerticesInFile {
    std::vector<LayerInFile> layers;           // the dataset's, in its order
    std::uint64_t vertices = 0;                // the map's
    Box extent{INFINITY, INFINITY, -INFINITY, -INFINITY};  // theirs
    const map::Coverage* coverage = nullptr;   // the polygon layers' rings, planned (ids in layer order)

    // The layers with chains in the order of their chains: the lines' layers, then the polygons'.
    std::vector<const LayerInFile*> in_chain_order() const;
};

// Features [first, end) of a layer, in the order OGR reads it. `by_fid`: their FIDs rising in
// [fid_first, fid_end); a GeoPackage's found by the FID column's index (OGR's SetNextByIndex
// reads a GeoPackage's every feature before), a Shapefile's from record fid_first on (its
// SetNextByIndex goes to a record number). Else each feature's FID is its index: `each_by_fid`,
// a FlatGeobuf's with its index of features, each read by GetFeature (its SetNextByIndex and FID
// filters read every feature before too); otherwise a Shapefile's without deleted records,
// reached by SetNextByIndex.
struct FeatureRun {
    std::string path;
    std::string layer;
    std::uint64_t first = 0, end = 0;
    bool by_fid = false;
    std::int64_t fid_first = 0, fid_end = 0;
    bool each_by_fid = false;
};

// The rings of a run of features of a polygon layer (InputError if a feature is not where the
// run says), as OgrDataset::read gives them to its coverage: each polygon's non-empty rings, its
// exterior first; features without polygons give none. For a coverage planned from the file
// (map::Coverage::plan, map::arcs_of); the same refusals as read() (InputError). The second form:
// a Shapefile's features [first, end).
void for_each_polygon_ring(const FeatureRun& run, const std::function<void(std::span<const Point>)>& visit);
// The same, each ring point tagged with the bits of its Z and M (0.0 where it has none), as the
// map read whole would give its vertex (map::Coverage::plan with tags).
void for_each_polygon_ring(const FeatureRun& run, const std::function<void(std::span<const Point>, std::span<const map::PointTag>)>& visit);
void for_each_polygon_ring(const std::string& path, const std::string& layer, std::uint64_t first, std::uint64_t end,
                           const std::function<void(std::span<const Point>)>& visit);

// The lines of a run of features of a lines layer left in its file and read through OGR
// (ogr_lines): each feature's non-empty parts as chains (x and y), in order, as OgrDataset::read
// makes them. InputError if a feature is not where the run says, or not a (Multi)LineString.
map::MapData read_lines(const FeatureRun& run);

class OgrDataset {
public:
    // Reads the named layers of `path` (none named: every layer) into `map`. Throws InputError
    // naming the file, layer and feature for anything it cannot accept. `prj_as_file`: the output
    // will be a Shapefile, so a Shapefile's .prj may be carried over as it is instead of parsed
    // (see read_layer). `vertices_in_file`: if every layer read is a Shapefile's (a file, or a
    // folder of them) of plain PolyLines that the Shapefile reader decodes, or of polygons or of
    // (Multi)LineStrings with Z, M or deleted records, or a GeoPackage's or FlatGeobuf's (a file
    // on disk; a FlatGeobuf with its index of features) of (Multi)LineStrings or (Multi)Polygons
    // (its FIDs rising in read order, as a table's are), Z and M allowed, or of 2D points (read
    // whole), their vertices are left in the files
    // (vertices_in_file() says where; the map gets its chains only), for an engine that reads
    // them by parts; else read as without it. (The output must then be written by write(), which
    // reads them again: not as TopoJSON.)
    static OgrDataset read(const std::string& path, const std::vector<std::string>& layers, map::MapData& map,
                           bool prj_as_file = false, bool vertices_in_file = false);

    // The same from layers in memory (every one of them).
    static OgrDataset read(const MemoryLayers& layers, map::MapData& map);

    OgrDataset(OgrDataset&&) noexcept;
    ~OgrDataset();

    const DatasetSummary& summary() const;
    // Is layer k's CRS longitude, latitude (degrees)? Asked only by --spherical: a Shapefile's .prj
    // carried to the output as a file is parsed here, not when the layer is read (PROJ opening
    // its database: a small line Shapefile's run 0.135 -> 0.107 s without it).
    bool geographic(std::size_t layer) const;
    const VerticesInFile* vertices_in_file() const;  // nullptr: the map holds its vertices

    // Writes the layers with only the kept vertices. The written file is read back and its
    // coordinates compared bit for bit before it is moved into place (OutputError otherwise).
    // Returns warnings worth telling the user (e.g. values a format cannot hold). A Shapefile
    // of 2D lines gets its shapes from PolyLineWriter (shapefile.hpp), the same bytes as OGR's
    // driver writes (GSHHG at 10 %: the write 0.34–0.39 s → 0.16–0.18 s), its attributes from OGR.
    std::vector<std::string> write(const WriteOptions& options, const map::MapData& map,
                                   const std::vector<std::uint8_t>& kept) const;

    // The layers with only the kept vertices, as WKB (extended WKB for Z, as GEOS and shapely
    // read it; M is dropped), in memory: what write() would write, without the attributes —
    // except that geometries the caller has already are left empty: NULL and empty ones, and
    // point features unless move_points() moved them.
    MemoryLayers to_memory(const map::MapData& map, const std::vector<std::uint8_t>& kept) const;

    // Moves the point features (written unchanged otherwise) to `points`: the map's control
    // points as read from this dataset, in the same order (rounding put them on a grid).
    void move_points(std::span<const Point> points);

    struct Data;  // layers, their definitions and attributes, the shared coverage

private:
    explicit OgrDataset(std::unique_ptr<Data> data);
    static OgrDataset read_dataset(const std::string& path, const std::vector<std::string>& layers, map::MapData& map,
                                   bool prj_as_file, bool vertices_in_file);
    std::unique_ptr<Data> data_;
};

// Reads control points from "path" or "path:layer" (Point or MultiPoint features), a
// GeoPackage on up to `threads` connections at once.
std::vector<Point> read_control_points(const std::string& spec, unsigned threads = 1);

// Control points from the Point or MultiPoint geometries of a layer in memory.
std::vector<Point> read_control_points(const MemoryLayers& layers);

// Writes layers in memory to a GeoPackage at `path` (e.g. under /vsimem/), for code that reads
// datasets by name (toposimp check). OutputError if it cannot.
void write_geopackage(const MemoryLayers& layers, const std::string& path);

// "path:layer" split as read_control_points splits it (a path that exists as given is a path).
struct PointsSpec {
    std::string path;
    std::string layer;  // empty: the dataset's only layer
};
PointsSpec split_points_spec(const std::string& spec);

}  // namespace toposimp::io
