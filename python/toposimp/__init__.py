"""toposimp: exact, topology-preserving simplification of maps and meshes, in Python.

The engine of the ``toposimp`` command line, in-process:

- :func:`simplify` simplifies GeoDataFrames and GeoSeries as ``toposimp map`` does: polygons as
  one coverage (a border shared by two polygons is simplified once, so no gaps or overlaps
  appear), lines with their crossings kept, no vertex moved and no control point (``points``)
  put on another side of any line. Every decision is made with exact predicates.
- :func:`check` compares an original with a simplification made by any tool and lists what it
  broke, as ``toposimp check`` does.
- :func:`simplify_mesh`, :func:`read_mesh` and :func:`write_mesh` work on triangle meshes held in
  numpy arrays, as ``toposimp mesh`` does.

Geometries travel to the engine as WKB, so coordinates are bit-exact both ways, and the results
are those of the command line on the same data, for any number of threads. The engine runs
with the GIL released; Ctrl-C stops it (KeyboardInterrupt); ``progress=callable`` receives
``(phase, share_done)``. Errors are :class:`InputError` (bad input: the message names the layer
and feature, as the command line's do), :class:`UsageError` (options that do not fit together),
:class:`OutputError` and :class:`TopologyError`.

Example::

    import geopandas, toposimp
    states = geopandas.read_file("states.gpkg")
    simple = toposimp.simplify(states, keep=0.05)
    assert toposimp.check(states, simple).empty
"""

from __future__ import annotations

from . import _launch

_launch.restart_the_dask_command()  # (first: before the engine and numpy load)

import json
import logging
import threading
import warnings
from typing import Any, Callable, Optional, Sequence, Union

from ._toposimp import InputError, OutputError, TopologyError, UsageError  # noqa: F401
from . import _toposimp
from .mesh import Mesh, read_mesh, simplify_mesh, write_mesh  # noqa: F401

__all__ = ["simplify", "check", "summary", "simplify_mesh", "read_mesh", "write_mesh", "Mesh", "InputError",
           "UsageError", "OutputError", "TopologyError", "ToposimpWarning"]

log = logging.getLogger("toposimp")


class ToposimpWarning(UserWarning):
    """What the command line prints as a warning (a target not reached, locations left off a grid...)."""


Progress = Callable[[str, float], Any]


def _report(messages: str) -> None:
    """The command line's messages: warnings as Python warnings, the rest to the toposimp logger."""
    for line in messages.splitlines():
        if line.startswith("toposimp: warning: "):
            warnings.warn(line[len("toposimp: warning: "):], ToposimpWarning, stacklevel=3)
        elif line.startswith("toposimp: error: "):
            log.error("%s", line[len("toposimp: error: "):])
        elif line.startswith("toposimp: "):
            level, _, text = line[len("toposimp: "):].partition(": ")
            log.log(logging.INFO if level == "info" else logging.DEBUG, "%s", text)


def _interruptible() -> bool:
    return threading.current_thread() is threading.main_thread()


def _share(value, name: str) -> str:
    """keep=0.1 or keep="10%" as the command line's text (repr: the shortest text of the double)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UsageError(f"{name} takes a share such as 0.1 or '10%', not {value!r}")
    return repr(float(value))


def _number(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UsageError(f"{name} takes a number, not {value!r}")
    return float(value)


# --- GeoDataFrames and GeoSeries <-> layers of WKB ------------------------------------------------

def _geoms(data):
    """The GeoSeries of a GeoDataFrame or GeoSeries."""
    import geopandas
    if isinstance(data, geopandas.GeoDataFrame):
        return data.geometry
    if isinstance(data, geopandas.GeoSeries):
        return data
    raise TypeError(f"expected a GeoDataFrame or GeoSeries, not {type(data).__name__}")


_shared_geos = None


def _shares_geos() -> bool:
    """Does shapely run on the GEOS library the extension links (Debian's shapely does)? Then the
    extension reads shapely's geometries through it, instead of WKB made one geometry at a time."""
    global _shared_geos
    if _shared_geos is None:
        try:
            import ctypes
            from shapely.geos import lgeos
            address = ctypes.cast(lgeos._lgeos.GEOSversion, ctypes.c_void_p).value
            _shared_geos = bool(_toposimp.same_geos(address))
        except Exception:  # another shapely (2.x, or a wheel with its own GEOS): WKB
            _shared_geos = False
    return _shared_geos


def _wkb_writer():
    """One geometry to WKB: shapely 1.8's writer made once (its `wkb` makes one per call), else
    shapely's own function."""
    try:
        from shapely.geos import WKBWriter, lgeos
        return WKBWriter(lgeos).write
    except ImportError:
        import shapely.wkb
        return shapely.wkb.dumps


def _wkb_reader():
    try:
        from shapely.geos import WKBReader, lgeos
        return WKBReader(lgeos).read
    except ImportError:
        import shapely.wkb
        return shapely.wkb.loads


def _geometry_list(series) -> list:
    values = series.values
    data = getattr(values, "data", None)
    return data.tolist() if data is not None else list(values)


def _layer(name: str, data) -> tuple:
    """(name, CRS, geometries): shapely's own when the extension shares its GEOS, else WKB (None
    for None and empty geometries, which come back as they were)."""
    series = _geoms(data)
    crs = series.crs.to_wkt() if series.crs is not None else None
    geometries = _geometry_list(series)
    if not _shares_geos():
        write = _wkb_writer()
        geometries = [None if g is None or g.is_empty else write(g) for g in geometries]
    return (name, crs, geometries)


def _rebuild(data, wkb: Sequence[Optional[bytes]]):
    """`data` with its geometries replaced by the WKB (None: the geometry it had)."""
    import geopandas
    import numpy
    from geopandas.array import GeometryArray
    read = _wkb_reader()
    series = _geoms(data)
    old = _geometry_list(series)
    geometries = numpy.empty(len(wkb), dtype=object)
    for k, b in enumerate(wkb):  # (not a slice assignment: numpy would take multi-part geometries for sequences)
        geometries[k] = old[k] if b is None else read(b)
    new = geopandas.GeoSeries(GeometryArray(geometries), index=series.index, crs=series.crs, name=series.name)
    if isinstance(data, geopandas.GeoSeries):
        return new
    out = data.copy(deep=False)
    out[data.geometry.name] = new
    return out


def _layers(data) -> tuple:
    """(source name, [(name, data)], how to give the results back)."""
    if isinstance(data, dict):
        return "layers", [(str(name), value) for name, value in data.items()], "dict"
    if isinstance(data, (list, tuple)):
        return "layers", [(str(k), value) for k, value in enumerate(data)], "list"
    return type(data).__name__, [(_default_name(data), data)], "one"


def _default_name(data) -> str:
    """A lone layer's name in messages: a GeoSeries' own name, else "0"."""
    import geopandas
    if isinstance(data, geopandas.GeoSeries) and isinstance(data.name, str) and data.name:
        return data.name
    return "0"


def _points_layers(points) -> Optional[list]:
    if points is None:
        return None
    items = points if isinstance(points, (list, tuple)) else [points]
    return [_layer(str(k), item) for k, item in enumerate(items)]


def _give_back(kind: str, names: list, results: list):
    if kind == "one":
        return results[0]
    if kind == "dict":
        return dict(zip(names, results))
    return results


def _levels_text(levels) -> str:
    if isinstance(levels, str):
        return levels
    texts = []
    for level in levels:
        if isinstance(level, str):
            texts.append(level)
        elif isinstance(level, int) and not isinstance(level, bool) and level >= 2:
            texts.append(str(level))
        else:
            texts.append(_share(level, "levels"))
    return ",".join(texts)


def simplify(data, keep: Union[float, str, None] = None, *, keep_points: Optional[int] = None,
             remove_points: Optional[int] = None, max_area: Union[float, str, None] = None, max: bool = False,
             levels: Union[str, Sequence[Union[float, int, str]], None] = None, points=None,
             precision: Union[float, str, None] = None, decimals: Optional[int] = None, weighting: float = 0.0,
             spherical: bool = False, arithmetic: str = "exact", threads: Optional[int] = None,
             progress: Optional[Progress] = None, verbose: int = 0, client=None):
    """Simplify line and polygon layers without changing their topology (``toposimp map``).

    ``data`` is a GeoDataFrame or GeoSeries, or a list (or dict by name) of them: several layers
    simplified together, so that a border two layers share stays shared and no line of one crosses
    a line of another anew. The result has the same type (a list or dict for several layers),
    index, columns, dtypes, CRS and geometry types; only the geometries change: every output
    vertex is an input vertex (unless ``precision``/``decimals`` round them), each line keeps its
    ends, polygons are simplified as one coverage (shared borders once: no gaps, no overlaps),
    crossings in the input are kept as they are, and no control point changes side. Point, empty
    and None geometries come back unchanged; points among the features are control points too.

    One target (default ``keep=0.1``):

    - ``keep``: the share of the vertices to keep, 0.1 or "10%";
    - ``keep_points``: the number of vertices to keep; ``remove_points``: the number to remove;
    - ``max_area``: remove vertices whose effective area is at most this (map units², or with
      ``spherical`` m², or a text with a unit: "5km2", "20ha");
    - ``max=True``: remove every vertex that can be removed;
    - ``levels``: several nested targets at once, finest first (``["20%", "5%", "1%"]``, shares or
      vertex counts): returns a list with one result per level, each a subset of the one before.

    ``points``: control points (GeoSeries or GeoDataFrame of Point/MultiPoint, or a list of them)
    kept on their side of every line. ``precision`` (a grid step, e.g. 0.0001) or ``decimals``
    put every coordinate on a grid, keeping the topology (``--precision``/``--decimals``).
    ``weighting`` (0…1, mapshaper's 0.7) ranks sharp angles first; ``spherical`` ranks by areas on
    the sphere (longitude, latitude input). ``arithmetic``: "exact" (the default), "rational", or
    "float" (unsafe, for experiments). ``threads``: None for all cores, or OMP_NUM_THREADS as it
    was when toposimp was first imported (Dask's LocalCluster sets it to 1 in the process that
    starts it: import toposimp first, or pass a number); the result is the same for any number.
    ``progress``: a callable taking (phase, share done 0…1); raising from it stops
    the run. ``verbose``: 1 or 2 log the command line's -v/-vv details to the "toposimp" logger.
    ``client``: a ``distributed.Client`` (or a ``toposimp.dask.Tiles`` around one, to size the
    tasks): the engine's tiles run as tasks on its workers, as ``python3 -m toposimp.dask`` runs
    them, with the same result (see :mod:`toposimp.dask`).

    The summary of ``toposimp map --json`` (vertices in and out, refusals, seconds...) is in the
    result's ``.attrs["toposimp"]`` (see :func:`summary`). Raises :class:`InputError` for input
    the engine cannot take (naming layer and feature: the position of the row, counted from 0),
    :class:`UsageError` for options that do not fit.
    """
    criteria = {"keep": keep is not None, "keep_points": keep_points is not None,
                "remove_points": remove_points is not None, "max_area": max_area is not None, "max": bool(max),
                "levels": levels is not None}
    given = [name for name, present in criteria.items() if present]
    if len(given) > 1:
        raise UsageError("give one target, not " + " and ".join(given))
    if precision is not None and decimals is not None:
        raise UsageError("give precision or decimals, not both")
    options: dict = {"weighting": _number(weighting, "weighting"), "spherical": bool(spherical),
                     "arithmetic": arithmetic, "threads": 0 if threads is None else int(threads),
                     "verbosity": int(verbose)}
    if keep is not None:
        options["keep"] = _share(keep, "keep")
    if keep_points is not None:
        options["keep_points"] = _number(keep_points, "keep_points")
        if options["keep_points"] < 0:
            raise UsageError(f"keep_points takes a count of at least 0, not {keep_points!r}")
    if remove_points is not None:
        options["remove_points"] = _number(remove_points, "remove_points")
        if options["remove_points"] < 0:
            raise UsageError(f"remove_points takes a count of at least 0, not {remove_points!r}")
    if max_area is not None:
        options["max_area"] = max_area if isinstance(max_area, str) else repr(_number(max_area, "max_area"))
    if max:
        options["max"] = True
    if levels is not None:
        options["levels"] = _levels_text(levels)
    if precision is not None:
        options["precision"] = precision if isinstance(precision, str) else repr(_number(precision, "precision"))
    if decimals is not None:
        if isinstance(decimals, bool) or not isinstance(decimals, int) or not 0 <= decimals <= 300:
            raise UsageError(f"decimals takes a whole number from 0 to 300, not {decimals!r}")
        options["decimals"] = decimals
    if arithmetic not in ("exact", "rational", "float"):
        raise UsageError(f"arithmetic is 'exact', 'rational' or 'float', not {arithmetic!r}")
    if options["threads"] < 0:
        raise UsageError(f"threads takes a number of at least 1 (None: all cores), not {threads!r}")

    source, named, kind = _layers(data)
    if not named:
        raise UsageError("no layers to simplify")
    layers = [_layer(name, value) for name, value in named]
    parts = None
    if client is not None:
        from toposimp import dask as _dask
        parts = (client if isinstance(client, _dask.Tiles) else _dask.Tiles(client))._parts()
    levels_out, summaries, messages = _toposimp.simplify_layers(source, layers, _points_layers(points), options,
                                                                progress, _interruptible(), _shares_geos(), parts)
    _report(messages)
    results = []
    for level, text in zip(levels_out, summaries):
        info = json.loads(text)
        info.pop("output", None)
        simplified = [_rebuild(value, wkb) for (_, value), wkb in zip(named, level)]
        for item in simplified:
            item.attrs["toposimp"] = info
        results.append(_give_back(kind, [name for name, _ in named], simplified))
    return results if levels is not None else results[0]


def summary(result) -> dict:
    """The ``toposimp map --json`` summary of a result of :func:`simplify`."""
    return result.attrs["toposimp"]


def check(original, simplified, points=None, *, precision: Union[float, str, None] = None):
    """What a simplification broke (``toposimp check``): a DataFrame of violations, empty when clean.

    ``original`` and ``simplified``: GeoDataFrames or GeoSeries (or lists or dicts of them, as
    :func:`simplify` takes), the features matched by order. ``points``: control points that must
    keep their side. ``precision``: the simplified coordinates were rounded to this grid step.
    Any tool's output can be checked (GEOS's simplify, mapshaper, ...).

    Columns: kind (new_crossing, lost_touching, point_changed_side, not_subset, ...), layer,
    feature (row position, counted from 0), other (the other feature of a contact, if any), x, y
    (where), detail, decided_by ("exact": the exact predicates; "GEOS": polygon validity), and
    index and other_index (those rows' labels in the original's index). The counts are in
    ``.attrs["toposimp"]``.
    """
    import pandas
    _, before, _ = _layers(original)
    _, after, _ = _layers(simplified)
    if len(before) != len(after):
        raise UsageError(f"original has {len(before)} layers, simplified {len(after)}")
    layers_before = [_layer(name, value) for name, value in before]
    layers_after = [_layer(name, value) for name, value in after]
    step = None if precision is None else precision if isinstance(precision, str) else repr(_number(precision, "precision"))
    violations, features, control_points, invalid_before = _toposimp.check_layers(
        layers_before, layers_after, _points_layers(points), step, _interruptible(), _shares_geos())
    columns = ["kind", "layer", "feature", "other", "x", "y", "detail", "decided_by"]
    frame = pandas.DataFrame(violations, columns=columns)
    frame["x"] = frame["x"].astype("float64")
    frame["y"] = frame["y"].astype("float64")
    # The rows' index labels in the original (feature and other are positions, counted from 0).
    by_name = {name: _geoms(value).index for name, value in before}

    def label(layer, position):
        index = by_name.get(layer)
        return index[int(position)] if index is not None and str(position).isdigit() and int(position) < len(index) else None
    frame["index"] = [label(layer, f) for layer, f in zip(frame["layer"], frame["feature"])]
    frame["other_index"] = [label(layer, o) for layer, o in zip(frame["layer"], frame["other"])]
    frame.attrs["toposimp"] = {"features": features, "control_points": control_points,
                               "invalid_in_original": invalid_before,
                               "counts": frame["kind"].value_counts().to_dict()}
    return frame
