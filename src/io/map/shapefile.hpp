// Shapefile records read straight from the .shp, .shx and .dbf, not through OGR: control
// points, the shapes of PolyLine layers (and of small Polygon layers going to a Shapefile), and
// the shapes of a written output when they are read back; and the .shp and .shx of a PolyLine
// output written (PolyLineWriter).
//
// Reading features through OGR makes the Shapefile driver parse the layer's .prj with PROJ
// (and look for a matching EPSG entry in proj.db) the first time a geometry is handed out:
// on a small map that is a fifth of the whole run, for a CRS neither use needs. The records
// themselves are simple to decode (ESRI Shapefile Technical Description, 1998): these readers
// do that and give up on anything unexpected, and the caller then reads the layer through OGR,
// which reports or handles it as for any other format.
#pragma once

#include "core/geometry.hpp"
#include "core/map/map_data.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace toposimp::io {

// The points of every record of the .shp at `path`, in record order, as OGR hands them out:
// Point and MultiPoint shapes, plain, Z or M; null shapes and empty multipoints skipped, and
// records marked deleted in the .dbf skipped. InputError (naming the file and FID) for a
// non-finite coordinate; std::nullopt when a sibling file is missing or anything is not what
// this reader decodes: other shape types, records out of step with the .shx or the .dbf.
std::optional<std::vector<Point>> read_shapefile_points(const std::string& path);

// One record's shape, a view into a ShapeTable: its parts' vertices one after another (z only
// for Z shape types, else empty), and where each part starts among them; no parts for a null
// shape.
struct ShapeRecord {
    std::span<const Point> xy;
    std::span<const double> z;
    std::span<const std::uint32_t> part_starts;
};

// Every record of a file in a few flat arrays, not a few vectors per record (on GSHHG, 180 000
// records): all vertices record after record, and where each record's vertices and parts begin.
struct ShapeTable {
    std::vector<Point> xy;                  // every record's vertices, in record order
    std::vector<double> z;                  // parallel to xy for Z shape types, else empty
    std::vector<std::uint32_t> part_starts; // per part: its first vertex, counted from its record's first
    std::vector<std::size_t> record_first;  // per record and one more: its first vertex in xy
    std::vector<std::size_t> record_parts;  // per record and one more: its first part in part_starts

    std::size_t size() const { return record_first.size() - 1; }
    ShapeRecord operator[](std::size_t record) const;
};

// Every record of the PolyLine or Polygon (plain, Z or M) .shp at `path`, in record order;
// std::nullopt if a record is deleted in the .dbf, when a sibling file is missing or anything
// is not what this reader decodes (as for read_shapefile_points). Coordinates as stored,
// non-finite ones included.
std::optional<ShapeTable> read_shapefile_shapes(const std::string& path);

// The same records one at a time, none kept: calls visit(fid, record) for each in order (the
// record valid during the call) until visit returns false. False where read_shapefile_shapes
// gives std::nullopt (after the records before the one it stops at) or visit returned false.
bool for_each_shape(const std::string& path, const std::function<bool(std::uint64_t, const ShapeRecord&)>& visit);

// Records [first, end) of a PolyLine or Polygon .shp one at a time, none kept, the first found
// through the .shx (a part of a file read by a process of its own: toposimp.dask).
class ShapeReader {
public:
    // std::nullopt where read_shapefile_shapes gives it before any record, or if first is past
    // the file's records; `end` beyond them is the file's end.
    static std::optional<ShapeReader> open(const std::string& path, std::uint64_t first = 0,
                                           std::uint64_t end = std::numeric_limits<std::uint64_t>::max());
    ShapeReader(ShapeReader&&) noexcept;
    ShapeReader& operator=(ShapeReader&&) noexcept;
    ~ShapeReader();

    std::uint64_t records() const;    // the file's
    std::uintmax_t shp_size() const;  // the .shp's bytes
    // The next record (valid until the next call; its FID then fid()), or nullptr at the end of
    // the range, or where read_shapefile_shapes would give std::nullopt (failed() then).
    const ShapeRecord* next();
    std::uint64_t fid() const;
    bool failed() const;

private:
    struct State;
    explicit ShapeReader(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

// A PolyLine Shapefile's .shp and .shx written record by record, byte for byte as GDAL 3.6's
// Shapefile driver writes a 2D LineString or MultiLineString layer (shapelib's SHPWriteObject
// through OGR; tests/unit/io/shapefile_test.cpp compares the two), without an OGR geometry per
// feature: on GSHHG that was most of the write. Each record's parts in order; a record without
// parts is a null shape. Boxes as shapelib makes them: a record's from its first vertex on, the
// file's from the first record's first vertex (0 if that record is null), each widened with
// (low < v ? low : v) and (high > v ? high : v), so that a 0 can replace a −0. The .dbf and .prj
// are another writer's (OGR's, for a layer without geometry).
class PolyLineWriter {
public:
    // Creates `shp` and the .shx beside it (its extension replaced by ".shx"); OutputError naming
    // `shown_as` if it cannot.
    PolyLineWriter(const std::string& shp, std::string shown_as);
    PolyLineWriter(PolyLineWriter&&) noexcept;
    PolyLineWriter& operator=(PolyLineWriter&&) noexcept;
    ~PolyLineWriter();

    // Appends a record: the points of `xy`, its parts starting at `part_starts` (rising, the first
    // 0, none empty); no part, a null shape. False, and nothing written, if the .shp would pass
    // the format's 4 GiB (shapelib refuses such a record too). OutputError if writing failed.
    bool add(std::span<const std::uint32_t> part_starts, std::span<const Point> xy);

    // Writes both headers and closes the files; OutputError if anything failed.
    void finish();

private:
    struct State;
    std::unique_ptr<State> state_;
};

// InputError "<label()>: vertex i has a non-finite coordinate (x, y)" for a record's first
// non-finite vertex (i counted from its part's first), as the map's readers word it.
void refuse_non_finite(const ShapeRecord& record, const std::function<std::string()>& label);

// When the file at `path` was last modified (the file system's clock, in nanoseconds), or -1.
std::int64_t modified_ns(const std::string& path);

// Records [first, end) of the plain PolyLine .shp at `path` as a map of their own, as the map
// reader makes them (io::VerticesInFile): each record's parts its chains, in order. InputError
// naming the feature ("'<path>', layer '<layer>', feature <fid>") for a non-finite coordinate,
// and naming the file if it is not a PolyLine file ShapeReader decodes to its end.
map::MapData read_shapefile_lines(const std::string& path, const std::string& layer, std::uint64_t first, std::uint64_t end);

}  // namespace toposimp::io
