// toposimp._toposimp: the engine for Python. The package (python/toposimp/__init__.py) turns
// GeoDataFrames and numpy arrays into what these functions take, and back: geometries travel as
// WKB or shapely's own GEOS geometries (exact doubles both ways), meshes as arrays. The work is the command line's own (the same
// options, the same messages, the same result), run with the GIL released, stopped by Ctrl-C
// (while the engine runs, SIGINT sets a flag the engine reads) and reporting progress through a
// callable.
#include "cli/cli.hpp"
#include "cli/guard.hpp"
#include "cli/logging.hpp"
#include "cli/map_command.hpp"
#include "cli/mesh_command.hpp"
#include "core/cancel.hpp"
#include "io/common/errors.hpp"
#include "io/common/output_file.hpp"
#include "io/mesh/mesh_files.hpp"
#include "io/ogr/ogr_dataset.hpp"
#include "python/parts.hpp"
#include "validate/check.hpp"

#include <geos_c.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace toposimp;

namespace {

// Raised in Python for what the command line reports with exit status 2 or 1.
PyObject* input_error = nullptr;     // toposimp.InputError: bad input (ValueError too)
PyObject* output_error = nullptr;    // toposimp.OutputError (OSError too)
PyObject* usage_error = nullptr;     // toposimp.UsageError: options that do not fit (ValueError too)
PyObject* topology_error = nullptr;  // toposimp.TopologyError

[[noreturn]] void raise(PyObject* kind, const std::string& message) {
    PyErr_SetString(kind, message.c_str());
    throw py::error_already_set();
}

// SIGINT while the engine runs: the run's stop flag, read by the engine, is set instead of
// running Python's handler (which could only run once the call returns). Installed by the main
// thread only, as Python's own is.
std::atomic<std::atomic<bool>*> interrupt_target{nullptr};
void on_interrupt(int) {
    if (std::atomic<bool>* flag = interrupt_target.load()) flag->store(true);
}

class InterruptScope {
public:
    InterruptScope(std::atomic<bool>& flag, bool install) {
        if (!install) return;
        interrupt_target.store(&flag);
        struct sigaction action {};
        action.sa_handler = on_interrupt;
        sigemptyset(&action.sa_mask);
        action.sa_flags = SA_RESTART;  // reads and writes under way carry on; the engine looks at the flag
        installed_ = sigaction(SIGINT, &action, &previous_) == 0;
    }
    ~InterruptScope() {
        if (!installed_) return;
        sigaction(SIGINT, &previous_, nullptr);
        interrupt_target.store(nullptr);
    }
    InterruptScope(const InterruptScope&) = delete;
    InterruptScope& operator=(const InterruptScope&) = delete;

private:
    struct sigaction previous_ {};
    bool installed_ = false;
};

// A run of the command line's work: messages collected, progress passed to `callback` (with the
// GIL), the GIL released meanwhile; errors become the package's exceptions with the same text.
// The engine stops (Cancelled) when SIGINT comes or the callback raises.
class Run {
public:
    std::ostringstream out, err;
    cli::Context context{out, err, false};

    Run(py::object progress, bool interruptible) : callback_(std::move(progress)), interruptible_(interruptible) {
        context.cancel = &stop_;
        if (!callback_.is_none()) {
            context.progress = [this](const std::string& phase, double done) {
                if (stop_.load()) return;
                py::gil_scoped_acquire gil;
                try {
                    callback_(phase, done);
                } catch (py::error_already_set& error) {
                    callback_error_.emplace(std::move(error));
                    stop_.store(true);
                }
            };
        }
    }

    // Runs `work` without the GIL; raises what it threw.
    template <class Work>
    void operator()(Work&& work) {
        std::string failure;
        PyObject* kind = nullptr;
        {
            py::gil_scoped_release release;
            InterruptScope interrupt(stop_, interruptible_);
            try {
                work();
            } catch (const Cancelled&) {
                kind = PyExc_KeyboardInterrupt;
            } catch (const io::InputError& error) {
                kind = input_error, failure = error.what();
            } catch (const io::OutputError& error) {
                kind = output_error, failure = error.what();
            } catch (const cli::UsageError& error) {
                kind = usage_error, failure = error.message;
            } catch (const cli::TopologyFailure& topology) {
                kind = topology_error, failure = topology.message;
            } catch (const std::bad_alloc&) {
                kind = PyExc_MemoryError, failure = "out of memory";
            } catch (const std::invalid_argument& error) {
                kind = input_error, failure = error.what();
            }
        }
        if (callback_error_) throw std::move(*callback_error_);
        if (kind == PyExc_KeyboardInterrupt || stop_.load()) {
            PyErr_SetNone(PyExc_KeyboardInterrupt);
            throw py::error_already_set();
        }
        if (kind) {
            PyErr_SetString(kind, failure.c_str());
            throw py::error_already_set();
        }
    }

private:
    py::object callback_;
    bool interruptible_;
    std::atomic<bool> stop_{false};
    std::optional<py::error_already_set> callback_error_;
};

// Geometries from Python come as WKB bytes, or, when shapely runs on the very GEOS library this
// module links (same_geos: the same GEOSversion function in this process, as Debian's shapely 1.8
// does), as shapely geometries, read here through GEOS with the GIL held: no bytes object per
// geometry (2.4 µs each through shapely, 171 000 cities 0.4 s).
GEOSContextHandle_t geos() {
    static const GEOSContextHandle_t context = GEOS_init_r();
    return context;
}

bool same_geos(std::uintptr_t geos_version_address) {
    return geos_version_address == reinterpret_cast<std::uintptr_t>(&GEOSversion);
}

const GEOSGeometry* geos_geometry(const py::handle object) {
    return reinterpret_cast<const GEOSGeometry*>(object.attr("_geom").cast<std::uintptr_t>());
}

class WkbWriter {
public:
    WkbWriter() : writer_(GEOSWKBWriter_create_r(geos())) {
        GEOSWKBWriter_setOutputDimension_r(geos(), writer_, 3);
        GEOSWKBWriter_setByteOrder_r(geos(), writer_, GEOS_WKB_NDR);
    }
    ~WkbWriter() { GEOSWKBWriter_destroy_r(geos(), writer_); }
    WkbWriter(const WkbWriter&) = delete;
    WkbWriter& operator=(const WkbWriter&) = delete;

    // Empty geometries go as NULL ones: the package gives back the geometry it had.
    void write(const GEOSGeometry* geometry, std::string& into) {
        if (GEOSisEmpty_r(geos(), geometry) != 0) return;
        std::size_t size = 0;
        unsigned char* bytes = GEOSWKBWriter_write_r(geos(), writer_, geometry, &size);
        if (bytes == nullptr) raise(input_error, "GEOS cannot write a geometry as WKB");
        into.assign(reinterpret_cast<const char*>(bytes), size);
        GEOSFree_r(geos(), bytes);
    }

private:
    GEOSWKBWriter* writer_;
};

// Layers from Python: [(name, crs_wkt, [WKB bytes, shapely geometry or None, ...]), ...].
io::MemoryLayers memory_layers(const std::string& source, const py::list& layers, bool shapely_geos) {
    io::MemoryLayers memory;
    memory.source = source;
    std::optional<WkbWriter> writer;
    if (shapely_geos) writer.emplace();
    for (const py::handle item : layers) {
        const auto layer = item.cast<py::tuple>();
        io::MemoryLayer& into = memory.layers.emplace_back();
        into.name = layer[0].cast<std::string>();
        into.crs_wkt = layer[1].is_none() ? std::string() : layer[1].cast<std::string>();
        const auto geometries = py::reinterpret_borrow<py::sequence>(layer[2]);
        into.wkb.resize(py::len(geometries));
        std::size_t k = 0;
        for (const py::handle geometry : geometries) {
            if (PyBytes_Check(geometry.ptr())) {
                char* data = nullptr;
                Py_ssize_t size = 0;
                if (PyBytes_AsStringAndSize(geometry.ptr(), &data, &size) != 0) throw py::error_already_set();
                into.wkb[k].assign(data, static_cast<std::size_t>(size));
            } else if (!geometry.is_none()) {
                if (!writer) raise(PyExc_TypeError, "geometries go as WKB bytes unless shapely shares this module's GEOS");
                writer->write(geos_geometry(geometry), into.wkb[k]);
            }
            ++k;
        }
    }
    return memory;
}

// Control points from shapely geometries through GEOS: their coordinates, without OGR.
std::vector<Point> point_coordinates(const py::list& layers) {
    std::vector<Point> points;
    for (const py::handle item : layers) {
        const auto layer = item.cast<py::tuple>();
        const auto name = layer[0].cast<std::string>();
        const auto geometries = py::reinterpret_borrow<py::sequence>(layer[2]);
        std::size_t k = 0;
        for (const py::handle object : geometries) {
            const std::size_t feature = k++;
            if (object.is_none()) continue;
            const GEOSGeometry* geometry = geos_geometry(object);
            auto label = [&] { return "'points', layer '" + name + "', feature " + std::to_string(feature); };
            auto add = [&](const GEOSGeometry* point) {
                if (GEOSisEmpty_r(geos(), point) != 0) return;
                Point p;
                if (GEOSGeomGetX_r(geos(), point, &p.x) == 0 || GEOSGeomGetY_r(geos(), point, &p.y) == 0) {
                    raise(input_error, label() + ": GEOS cannot read the point");
                }
                if (!std::isfinite(p.x) || !std::isfinite(p.y)) raise(input_error, label() + ": control point has a non-finite coordinate");
                points.push_back(p);
            };
            const int type = GEOSGeomTypeId_r(geos(), geometry);
            if (type == GEOS_POINT) {
                add(geometry);
            } else if (type == GEOS_MULTIPOINT) {
                const int parts = GEOSGetNumGeometries_r(geos(), geometry);
                for (int i = 0; i < parts; ++i) add(GEOSGetGeometryN_r(geos(), geometry, i));
            } else {
                char* type_name = GEOSGeomType_r(geos(), geometry);
                const std::string what = type_name ? type_name : "another type";
                GEOSFree_r(geos(), type_name);
                raise(input_error, label() + ": control points must be Point or MultiPoint, not " + what);
            }
        }
    }
    return points;
}

py::list python_layers(const io::MemoryLayers& layers) {
    py::list out;
    for (const io::MemoryLayer& layer : layers.layers) {
        py::list geometries;
        for (const std::string& wkb : layer.wkb) {
            if (wkb.empty()) {
                geometries.append(py::none());
            } else {
                geometries.append(py::bytes(wkb));
            }
        }
        out.append(geometries);
    }
    return out;
}

template <class T>
void set_if(const py::dict& options, const char* key, T& field) {
    if (options.contains(key) && !options[key].is_none()) field = options[key].cast<T>();
}

// toposimp map on layers in memory. Returns ([per level: [per layer: [wkb or None]]],
// [per level: JSON summary], messages).
// `parts`: None, or (run_groups, tile_level, tile_points, local_budget) to run the engine in parts
// (python/parts.hpp), as toposimp.dask does.
py::tuple simplify_layers(const std::string& source, const py::list& layers, const py::object& points, const py::dict& options,
                          const py::object& progress, bool interruptible, bool shapely_geos, const py::object& parts) {
    cli::MapOptions map;
    map.input = source;
    map.output = "<memory>";
    set_if(options, "keep", map.keep);
    set_if(options, "keep_points", map.keep_points);
    set_if(options, "remove_points", map.remove_points);
    set_if(options, "max_area", map.max_area);
    set_if(options, "max", map.max);
    set_if(options, "levels", map.levels);
    set_if(options, "precision", map.precision);
    set_if(options, "decimals", map.decimals);
    set_if(options, "weighting", map.weighting);
    set_if(options, "spherical", map.spherical);
    set_if(options, "arithmetic", map.arithmetic);
    set_if(options, "threads", map.threads);
    set_if(options, "verbosity", map.verbosity);

    const io::MemoryLayers input = memory_layers(source, layers, shapely_geos);
    std::optional<io::MemoryLayers> control_points;
    std::vector<Point> coordinates;
    if (!points.is_none() && shapely_geos) {
        coordinates = point_coordinates(points.cast<py::list>());
    } else if (!points.is_none()) {
        control_points = memory_layers("points", points.cast<py::list>(), false);
    }
    cli::MapMemory memory;
    memory.input = &input;
    memory.points = control_points ? &*control_points : nullptr;
    memory.point_coordinates = &coordinates;
    // (The run's callables live here, beyond the run: the engine below refers to them. Held in
    // the block that unpacks them, they were gone when it ran — a crash in Release builds.)
    py::object run_groups, tile_points;
    Run run(progress, interruptible);
    if (!parts.is_none()) {
        const auto how = parts.cast<py::tuple>();
        run_groups = how[0];
        const int tile_level = how[1].cast<int>();
        tile_points = how[2];
        const auto local_budget = how[3].cast<std::uint64_t>();
        run.context.map_engine = [&run_groups, &tile_points, tile_level, local_budget](const map::MapData& data,
                                                                                      const map::SimplifyOptions& simplify) {
            return python::run_in_parts(data, simplify, run_groups, tile_level, tile_points, local_budget);
        };
    }
    run([&] {
        auto log = cli::make_logger(run.context.err, map.verbosity, false);
        cli::map_job(map, run.context, *log, &memory);
    });
    py::list levels;
    for (const io::MemoryLayers& level : memory.output) levels.append(python_layers(level));
    return py::make_tuple(levels, memory.summaries, run.err.str());
}

// toposimp check on layers in memory: the violations as tuples (kind, layer, feature, other, x,
// y, detail, decided_by), and the counts of the report.
py::tuple check_layers(const py::list& original, const py::list& simplified, const py::object& points, const py::object& precision,
                       bool interruptible, bool shapely_geos) {
    const io::MemoryLayers before = memory_layers("original", original, shapely_geos);
    const io::MemoryLayers after = memory_layers("simplified", simplified, shapely_geos);
    std::optional<io::MemoryLayers> control_points;
    if (!points.is_none()) control_points = memory_layers("points", points.cast<py::list>(), shapely_geos);
    validate::CheckOptions check;
    if (!precision.is_none()) {
        const auto text = precision.cast<std::string>();
        const std::optional<map::GridStep> step = map::GridStep::parse(text);
        if (!step) {
            PyErr_SetString(usage_error, ("precision: '" + text + "' is not a positive decimal step (e.g. 0.0001, 1e-4 or 25)").c_str());
            throw py::error_already_set();
        }
        check.grid = map::OutputGrid(*step);
    }
    validate::CheckReport report;
    Run run(py::none(), interruptible);
    run([&] { report = validate::check(before, after, control_points ? &*control_points : nullptr, check); });
    py::list violations;
    for (const validate::Violation& v : report.violations) {
        violations.append(py::make_tuple(validate::name(v.kind), v.layer, v.feature, v.other, v.x, v.y, v.detail, v.decided_by));
    }
    return py::make_tuple(violations, report.features, report.control_points, report.invalid_in_original);
}

}  // namespace

// --- meshes: numpy arrays <-> mesh::Mesh --------------------------------------------------------

const std::array<std::pair<io::ValueType, const char*>, 8> kTypes{{{io::ValueType::i8, "int8"},
                                                                    {io::ValueType::u8, "uint8"},
                                                                    {io::ValueType::i16, "int16"},
                                                                    {io::ValueType::u16, "uint16"},
                                                                    {io::ValueType::i32, "int32"},
                                                                    {io::ValueType::u32, "uint32"},
                                                                    {io::ValueType::f32, "float32"},
                                                                    {io::ValueType::f64, "float64"}}};

const char* type_name(io::ValueType type) {
    for (const auto& [value, name] : kTypes) {
        if (value == type) return name;
    }
    return "float64";
}

io::ValueType type_named(const std::string& name) {
    for (const auto& [value, known] : kTypes) {
        if (name == known) return value;
    }
    raise(usage_error, "attribute type '" + name + "' is not one of int8, uint8, int16, uint16, int32, uint32, float32, float64");
}

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Corners = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

// Columns [(name, type, array of one value per element)] as interleaved rows.
mesh::Attributes attributes_of(const py::list& columns, std::size_t rows, const char* what, std::vector<io::AttributeColumn>& layout) {
    mesh::Attributes attributes;
    attributes.width = py::len(columns);
    attributes.values.resize(rows * attributes.width);
    std::size_t c = 0;
    for (const py::handle item : columns) {
        const auto column = item.cast<py::tuple>();
        const auto name = column[0].cast<std::string>();
        layout.push_back({name, type_named(column[1].cast<std::string>())});
        const auto values = column[2].cast<Doubles>();
        if (values.ndim() != 1 || static_cast<std::size_t>(values.shape(0)) != rows) {
            raise(usage_error, std::string(what) + " attribute '" + name + "' holds " + std::to_string(values.size()) +
                                   " values, not one per " + what + " (" + std::to_string(rows) + ")");
        }
        const double* data = values.data();
        for (std::size_t r = 0; r < rows; ++r) attributes.values[r * attributes.width + c] = data[r];
        ++c;
    }
    return attributes;
}

py::list columns_of(const mesh::Attributes& attributes, const std::vector<io::AttributeColumn>& layout, std::size_t rows) {
    py::list columns;
    for (std::size_t c = 0; c < layout.size(); ++c) {
        Doubles values(static_cast<py::ssize_t>(rows));
        double* data = values.mutable_data();
        for (std::size_t r = 0; r < rows; ++r) data[r] = attributes.values[r * attributes.width + c];
        columns.append(py::make_tuple(layout[c].name, type_name(layout[c].type), values));
    }
    return columns;
}

mesh::Mesh mesh_of(const py::object& points_in, const py::object& faces_in, const py::list& vertex_columns, const py::list& face_columns,
                   io::AttributeLayout& layout) {
    const auto points = points_in.cast<Doubles>();
    const auto faces = faces_in.cast<Corners>();
    if (points.ndim() != 2 || points.shape(1) != 3) raise(usage_error, "vertices must be an array of shape (n, 3)");
    if (faces.ndim() != 2 || faces.shape(1) != 3) raise(usage_error, "faces must be an array of shape (m, 3) (triangles)");
    mesh::Mesh mesh;
    const auto n = static_cast<std::size_t>(points.shape(0));
    const auto m = static_cast<std::size_t>(faces.shape(0));
    mesh.points.resize(n);
    const double* p = points.data();
    for (std::size_t v = 0; v < n; ++v) mesh.points[v] = {p[3 * v], p[3 * v + 1], p[3 * v + 2]};
    mesh.faces.resize(m);
    const std::int64_t* f = faces.data();
    for (std::size_t k = 0; k < 3 * m; ++k) {
        if (f[k] < 0 || static_cast<std::size_t>(f[k]) >= n) {
            raise(input_error, "face " + std::to_string(k / 3) + " has corner " + std::to_string(f[k]) + ", not a vertex (0 to " +
                                   std::to_string(n == 0 ? 0 : n - 1) + ")");
        }
        mesh.faces[k / 3][k % 3] = static_cast<std::uint32_t>(f[k]);
    }
    mesh.vertex_attributes = attributes_of(vertex_columns, n, "vertex", layout.vertex);
    mesh.face_attributes = attributes_of(face_columns, m, "face", layout.face);
    return mesh;
}

// (vertices, faces, vertex columns, face columns) of a mesh.
py::tuple arrays_of(const mesh::Mesh& mesh, const io::AttributeLayout& layout) {
    const std::size_t n = mesh.points.size(), m = mesh.faces.size();
    Doubles points({static_cast<py::ssize_t>(n), py::ssize_t{3}});
    double* p = points.mutable_data();
    for (std::size_t v = 0; v < n; ++v) {
        p[3 * v] = mesh.points[v].x;
        p[3 * v + 1] = mesh.points[v].y;
        p[3 * v + 2] = mesh.points[v].z;
    }
    Corners faces({static_cast<py::ssize_t>(m), py::ssize_t{3}});
    std::int64_t* f = faces.mutable_data();
    for (std::size_t k = 0; k < m; ++k) {
        for (int c = 0; c < 3; ++c) f[3 * k + c] = mesh.faces[k][static_cast<std::size_t>(c)];
    }
    return py::make_tuple(points, faces, columns_of(mesh.vertex_attributes, layout.vertex, n),
                          columns_of(mesh.face_attributes, layout.face, m));
}

// toposimp mesh on arrays: (vertices, faces, vertex columns, face columns, JSON summary, messages).
py::tuple simplify_mesh_arrays(const py::object& points, const py::object& faces, const py::list& vertex_columns,
                               const py::list& face_columns, const py::dict& options, const py::object& progress, bool interruptible) {
    cli::MeshCommandOptions command;
    command.input = "<vertices, faces>";
    command.output = "<memory>";
    set_if(options, "keep", command.keep);
    set_if(options, "keep_faces", command.keep_faces);
    set_if(options, "max_error", command.max_error);
    set_if(options, "lock_boundary", command.lock_boundary);
    set_if(options, "terrain", command.terrain);
    set_if(options, "no_terrain", command.no_terrain);
    set_if(options, "weld", command.weld);
    set_if(options, "threads", command.threads);
    set_if(options, "verbosity", command.verbosity);
    set_if(options, "measure", command.measure);
    set_if(options, "contact_check", command.contact_check);
    cli::MeshMemory memory;
    memory.mesh = mesh_of(points, faces, vertex_columns, face_columns, memory.layout);
    Run run(progress, interruptible);
    run([&] {
        auto log = cli::make_logger(run.context.err, command.verbosity, false);
        cli::mesh_job(command, run.context, cli::MeshGdal{}, *log, &memory);
    });
    const py::tuple arrays = arrays_of(memory.mesh, memory.layout);
    return py::make_tuple(arrays[0], arrays[1], arrays[2], arrays[3], memory.summary, run.err.str());
}

// A mesh file: (vertices, faces, vertex columns, face columns, report).
py::tuple read_mesh_file(const std::string& path, bool triangulate) {
    io::MeshReadOptions options;
    options.triangulate = triangulate;
    io::MeshReadReport report;
    mesh::Mesh mesh;
    Run run(py::none(), false);
    run([&] { mesh = io::read_mesh(path, options, report); });
    py::dict about;
    about["format"] = io::to_string(report.format);
    about["encoding"] = report.encoding;
    about["dropped"] = report.dropped;
    about["polygons_triangulated"] = report.polygons_triangulated;
    about["ignored_elements"] = report.ignored_elements;
    about["welded"] = report.welded;
    const py::tuple arrays = arrays_of(mesh, report.layout);
    return py::make_tuple(arrays[0], arrays[1], arrays[2], arrays[3], about);
}

// Writes a mesh file (moved into place when complete); returns the columns the format cannot hold.
std::vector<std::string> write_mesh_file(const std::string& path, const py::object& points, const py::object& faces,
                                         const py::list& vertex_columns, const py::list& face_columns, const std::string& format_name,
                                         bool ascii, bool overwrite) {
    io::AttributeLayout layout;
    const mesh::Mesh mesh = mesh_of(points, faces, vertex_columns, face_columns, layout);
    std::vector<std::string> unwritten;
    Run run(py::none(), false);
    run([&] {
        const io::MeshFormatInfo* format =
            format_name.empty() ? io::mesh_format_by_extension(path) : io::mesh_format_named(format_name);
        if (!format) {
            throw cli::UsageError{"'" + (format_name.empty() ? path : format_name) + "': not a mesh format (" +
                                  io::mesh_format_names_text() + ")"};
        }
        io::OutputFile output(path, overwrite, nullptr);
        unwritten = io::write_mesh(mesh, layout, output.staging_path(), format->format, ascii, path);
        output.commit();
    });
    return unwritten;
}

// `toposimp ARGS...` in this process, the map engine run in parts through `run_groups` (see
// python/parts.hpp). `input_on_workers` (run_groups has first_round): where the input allows it,
// its vertices are read by the first round's tasks, not here (cli::Context::map_engine_in_file);
// and, with `in_file_if` (not None), where in_file_if(the input's bytes on disk) is true
// (cli::Context::leave_in_file_if). Returns (exit status, standard output, standard error).
py::tuple run_command(const std::vector<std::string>& args, const py::object& run_groups, int tile_level, const py::object& tile_points,
                      std::uint64_t local_budget, const py::object& progress, bool err_is_terminal, bool interruptible,
                      bool input_on_workers, const py::object& in_file_if) {
    Run run(progress, interruptible);
    run.context.err_is_terminal = err_is_terminal;
    run.context.map_engine = [&](const map::MapData& map, const map::SimplifyOptions& options) {
        return python::run_in_parts(map, options, run_groups, tile_level, tile_points, local_budget);
    };
    if (input_on_workers) {
        run.context.map_engine_in_file = [&](const map::MapData& map, const map::SimplifyOptions& options, const io::VerticesInFile& in_file) {
            return python::run_in_parts(map, options, run_groups, tile_level, tile_points, local_budget, &in_file);
        };
        if (!in_file_if.is_none()) {
            run.context.leave_in_file_if = [&](std::uintmax_t bytes) {
                py::gil_scoped_acquire gil;
                return in_file_if(bytes).cast<bool>();
            };
        }
    }
    int status = 0;
    run([&] { status = cli::run(args, run.context); });
    return py::make_tuple(status, run.out.str(), run.err.str());
}

PYBIND11_MODULE(_toposimp, module) {
    module.doc() = "toposimp's engine (use the toposimp package, which wraps it)";
    auto make = [&](const char* name, PyObject* bases) {
        PyObject* type = PyErr_NewException((std::string("toposimp.") + name).c_str(), bases, nullptr);
        module.add_object(name, py::handle(type));
        return type;
    };
    py::tuple value_error = py::make_tuple(py::handle(PyExc_ValueError));
    input_error = make("InputError", value_error.ptr());
    usage_error = make("UsageError", value_error.ptr());
    output_error = make("OutputError", py::make_tuple(py::handle(PyExc_OSError)).ptr());
    topology_error = make("TopologyError", nullptr);
    // (The tasks' functions, outside a Run: an input a task reads itself, e.g. its part of a file.)
    py::register_exception_translator([](std::exception_ptr thrown) {
        try {
            if (thrown) std::rethrow_exception(thrown);
        } catch (const io::InputError& error) {
            PyErr_SetString(input_error, error.what());
        }
    });
    module.def("same_geos", &same_geos, py::arg("geos_version_address"));
    module.def("simplify_layers", &simplify_layers, py::arg("source"), py::arg("layers"), py::arg("points"), py::arg("options"),
               py::arg("progress"), py::arg("interruptible"), py::arg("shapely_geos"), py::arg("parts") = py::none());
    module.def("simplify_mesh_arrays", &simplify_mesh_arrays, py::arg("vertices"), py::arg("faces"), py::arg("vertex_columns"),
               py::arg("face_columns"), py::arg("options"), py::arg("progress"), py::arg("interruptible"));
    module.def("read_mesh_file", &read_mesh_file, py::arg("path"), py::arg("triangulate"));
    module.def("write_mesh_file", &write_mesh_file, py::arg("path"), py::arg("vertices"), py::arg("faces"),
               py::arg("vertex_columns"), py::arg("face_columns"), py::arg("format"), py::arg("ascii"), py::arg("overwrite"));
    module.def("run_command", &run_command, py::arg("args"), py::arg("run_groups"), py::arg("tile_level"), py::arg("tile_points"),
               py::arg("local_budget"), py::arg("progress"), py::arg("err_is_terminal"), py::arg("interruptible"),
               py::arg("input_on_workers") = false, py::arg("in_file_if") = py::none());
    python::bind_parts(module);
    module.attr("version") = TOPOSIMP_VERSION;
    module.attr("parts_protocol") = python::kPartsProtocol;
    module.def("run_tile_group", &python::run_tile_group, py::arg("group"), py::arg("plan"), py::arg("options"));
    module.def("run_tile_groups", &python::run_tile_groups, py::arg("groups"), py::arg("plan"), py::arg("options"));
    module.def("check_layers", &check_layers, py::arg("original"), py::arg("simplified"), py::arg("points"), py::arg("precision"),
               py::arg("interruptible"), py::arg("shapely_geos"));
}
