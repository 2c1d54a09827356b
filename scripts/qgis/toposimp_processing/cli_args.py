"""Processing parameter values -> toposimp command-line arguments.

Plain Python, no QGIS import: the algorithms resolve their parameters (layers to file paths,
enums to indices) and hand the values to these functions, which the unit tests call directly.
The enum tables below are the ones the algorithms show, so an index means the same thing in
the dialog and here.
"""

import re

# (key, label) in the order the Processing dialog lists them.
MAP_TARGETS = [
    ("keep_percent", "Keep a share of the vertices (%)"),
    ("keep_points", "Keep N vertices"),
    ("remove_points", "Remove N vertices"),
    ("max_area", "Remove vertices with effective area up to A"),
    ("max", "Remove every vertex that can go"),
]
ARITHMETIC = [
    ("exact", "Exact (float filter, GMP fallback)"),
    ("rational", "Rational (every predicate in GMP, slow)"),
    ("float", "Float (naive doubles: UNSAFE, experiments only)"),
]
MESH_TARGETS = [
    ("keep_percent", "Keep a share of the faces (%)"),
    ("keep_faces", "Keep N faces"),
    ("max_error", "Error up to E (terrain: vertical distance, guaranteed; else quadric error)"),
]


class ArgumentError(ValueError):
    """A parameter combination the tool cannot run with; the message says which."""


def _key(table, index, what):
    if not isinstance(index, int) or not 0 <= index < len(table):
        raise ArgumentError("{}: no choice {!r} (0 to {})".format(what, index, len(table) - 1))
    return table[index][0]


def _number(value):
    """Shortest text that reads back as the same number (integers without a decimal point)."""
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ArgumentError("not a finite number: {!r}".format(value))
    if value.is_integer() and abs(value) < 2 ** 53:
        return str(int(value))
    return repr(value)


def _percent(value, what):
    if value is None:
        raise ArgumentError("{}: a percentage is needed".format(what))
    value = float(value)
    if not 0 <= value <= 100:
        raise ArgumentError("{}: {} is not between 0 and 100".format(what, _number(value)))
    return _number(value) + "%"


def _count(value, what):
    if value is None:
        raise ArgumentError("{}: a count is needed".format(what))
    if float(value) < 0 or not float(value).is_integer():
        raise ArgumentError("{}: {!r} is not a whole number >= 0".format(what, value))
    return str(int(value))


def _non_negative(value, what):
    if value is None:
        raise ArgumentError("{}: a value is needed".format(what))
    if float(value) < 0:
        raise ArgumentError("{}: {} is negative".format(what, _number(value)))
    return _number(value)


def source_spec(path, layer=None):
    """FILE or FILE:LAYER, as toposimp's --points takes it."""
    return path + ":" + layer if layer else path


_OGR_URI = re.compile(r"""^ogr:dbname=(?P<q>['"]?)(?P<path>.+?)(?P=q)\s+table=(?P<t>['"]?)(?P<table>.+?)(?P=t)(\s+\(.*\))?\s*$""")


def split_destination(destination):
    """A Processing vector destination -> (file path, layer name or None).

    Accepts a plain path, 'path|layername=NAME' and QGIS's
    'ogr:dbname='path' table="NAME" (geom)' form (a layer in a GeoPackage)."""
    if not destination:
        raise ArgumentError("no output given")
    match = _OGR_URI.match(destination)
    if match:
        return match.group("path"), match.group("table")
    if "|layername=" in destination:
        path, _, rest = destination.partition("|layername=")
        return path, rest.split("|")[0] or None
    return destination, None


def _common(threads, progress):
    args = []
    if threads:
        args += ["-j", _count(threads, "threads")]
    if progress:
        args.append("--progress")
    return args


def map_args(input_path, output_path, input_layer=None, output_layer=None, points_path=None,
             points_layer=None, target=0, percent=10.0, count=None, area=None, arithmetic=0,
             validate=False, threads=0, overwrite=True, progress=True, decimals=None, precision=None,
             weighting=None, spherical=False):
    """Arguments of `toposimp map` (without the executable). `decimals` or `precision` (a grid
    step in map units) round the output onto a grid without changing its topology; `weighting`
    (0 to 1) ranks by weighted effective area, `spherical` by areas on the sphere."""
    if not input_path:
        raise ArgumentError("no input layer")
    args = ["map", input_path, "-o", output_path]
    if input_layer:
        args += ["-l", input_layer]
    if output_layer:
        args += ["--nln", output_layer]
    if points_path:
        args += ["--points", source_spec(points_path, points_layer)]
    kind = _key(MAP_TARGETS, target, "target")
    if kind == "keep_percent":
        args += ["--keep", _percent(percent, "share of the vertices to keep")]
    elif kind == "keep_points":
        args += ["--keep-points", _count(count, "vertices to keep")]
    elif kind == "remove_points":
        args += ["--remove-points", _count(count, "vertices to remove")]
    elif kind == "max_area":
        args += ["--max-area", _non_negative(area, "effective area")]
    else:
        args.append("--max")
    mode = _key(ARITHMETIC, arithmetic, "arithmetic")
    if mode != "exact":
        args += ["--arithmetic", mode]
    if decimals is not None and precision is not None:
        raise ArgumentError("round to a number of decimals or to a grid step, not both")
    if decimals is not None:
        if float(decimals) < 0 or float(decimals) > 15 or not float(decimals).is_integer():
            raise ArgumentError("decimals: {!r} is not a whole number from 0 to 15".format(decimals))
        args += ["--decimals", str(int(decimals))]
    if precision is not None:
        if not float(precision) > 0:
            raise ArgumentError("grid step: {!r} is not positive".format(precision))
        args += ["--precision", _number(precision)]
    if weighting is not None:
        if not 0 <= float(weighting) <= 1:
            raise ArgumentError("weighting: {!r} is not between 0 and 1".format(weighting))
        args += ["--weighting", _number(weighting)]
    if spherical:
        args.append("--spherical")
    if validate:
        args.append("--validate")
    if overwrite:
        args.append("--overwrite")
    return args + _common(threads, progress) + ["--json"]


def check_args(original_path, simplified_path, layer=None, simplified_layer=None, points_path=None,
               points_layer=None, key_field=None, errors_path=None, progress=True):
    """Arguments of `toposimp check`: `layer` of the original against `simplified_layer` of the
    simplified dataset (by name, or the only one, when not given)."""
    if not original_path or not simplified_path:
        raise ArgumentError("check needs the original and the simplified layer")
    args = ["check", original_path, simplified_path]
    if layer:
        args += ["-l", layer]
    if simplified_layer:
        args += ["--simplified-layer", simplified_layer]
    if points_path:
        args += ["--points", source_spec(points_path, points_layer)]
    if key_field:
        args += ["--key", key_field]
    if errors_path:
        args += ["--geojson-errors", errors_path]
    return args + _common(0, progress) + ["--json"]


def mesh_args(input_path, output_path, target=0, percent=10.0, count=None, max_error=None,
              band=None, terrain=False, lock_boundary=False, free_boundary=False,
              triangulate=False, weld=False, output_format=None, output_layer=None, hausdorff=True,
              threads=0, overwrite=True, progress=True):
    """Arguments of `toposimp mesh`: a mesh file or a DEM raster in, a mesh file or an OGR
    layer of triangles out."""
    if not input_path:
        raise ArgumentError("no input mesh or DEM")
    if lock_boundary and free_boundary:
        raise ArgumentError("lock the border or free it, not both")
    args = ["mesh", input_path, "-o", output_path]
    kind = _key(MESH_TARGETS, target, "target")
    if kind == "keep_percent":
        args += ["--keep", _percent(percent, "share of the faces to keep")]
    elif kind == "keep_faces":
        args += ["--keep-faces", _count(count, "faces to keep")]
    else:
        args += ["--max-error", _non_negative(max_error, "error bound")]
    if band:
        args += ["--band", _count(band, "band")]
    if terrain:
        args.append("--terrain")
    if lock_boundary:
        args.append("--lock-boundary")
    if free_boundary:
        args.append("--free-boundary")
    if triangulate:
        args.append("--triangulate")
    if weld:
        args.append("--weld")
    if output_format:
        args += ["-f", output_format]
    if output_layer:
        args += ["--nln", output_layer]
    if not hausdorff:
        args.append("--no-hausdorff")
    if overwrite:
        args.append("--overwrite")
    return args + _common(threads, progress) + ["--json"]
