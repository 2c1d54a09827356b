"""Triangle meshes as numpy arrays: simplify (``toposimp mesh``), read and write mesh files."""

from __future__ import annotations

import json
from types import MappingProxyType
from typing import Callable, Dict, List, Mapping, NamedTuple, Optional, Union

import numpy

from . import _toposimp

__all__ = ["Mesh", "simplify_mesh", "read_mesh", "write_mesh"]


class Mesh(NamedTuple):
    """A triangle mesh: ``vertices`` (n × 3 float64), ``faces`` (m × 3 int64 corner indices,
    counted from 0), and what each vertex or face carries besides, one array per column keyed by
    its name as a PLY property (nx ny nz: normals; red green blue alpha: colours; u v: texture
    coordinates; anything else as it is), its dtype the type it is written with. ``report``: what
    reading or simplifying said (for :func:`simplify_mesh`, the ``toposimp mesh --json`` summary).
    """
    vertices: numpy.ndarray
    faces: numpy.ndarray
    # (Defaults read-only: one shared empty mapping, which no Mesh can change for the others.)
    vertex_attributes: Mapping[str, numpy.ndarray] = MappingProxyType({})
    face_attributes: Mapping[str, numpy.ndarray] = MappingProxyType({})
    report: Mapping = MappingProxyType({})


_TYPES = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"}


def _columns(attributes: Optional[Dict[str, numpy.ndarray]]) -> list:
    columns = []
    for name, values in (attributes or {}).items():
        array = numpy.asarray(values)
        kind = array.dtype.name if array.dtype.name in _TYPES else "float64"
        columns.append((str(name), kind, array.astype(numpy.float64, copy=False)))
    return columns


def _attributes(columns: list) -> Dict[str, numpy.ndarray]:
    return {name: values.astype(kind) if kind != "float64" else values for name, kind, values in columns}


def _share(value) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _toposimp.UsageError(f"keep takes a share such as 0.1 or '10%', not {value!r}")
    return repr(float(value))


def simplify_mesh(vertices, faces, keep: Union[float, str, None] = None, *, keep_faces: Optional[int] = None,
                  max_error: Optional[float] = None, terrain: Optional[bool] = None, lock_boundary: bool = False,
                  weld: bool = False, vertex_attributes: Optional[Dict[str, numpy.ndarray]] = None,
                  face_attributes: Optional[Dict[str, numpy.ndarray]] = None, measure: Optional[str] = "quick",
                  threads: Optional[int] = None, progress: Optional[Callable[[str, float], object]] = None,
                  verbose: int = 0, contact_check: str = "after") -> Mesh:
    """Simplify a triangle mesh without self-intersections, flipped faces or non-manifold edges
    (``toposimp mesh``: quadric-error edge collapse, every collapse checked with exact predicates).

    ``vertices``: n × 3 numbers; ``faces``: m × 3 corner indices. One target (default
    ``keep=0.1``): ``keep`` the share of the faces (0.1 or "10%"), ``keep_faces`` a face count, or
    ``max_error`` the largest error (for a terrain, a TIN with z as height: the vertical
    distance to the input, guaranteed everywhere, the border kept; otherwise the quadric error).
    ``terrain``: None (the default) simplifies a mesh found to be a height field (exactly: every
    face turned the same way in the x-y plane, none overlapping there) as a terrain, any other in
    space; True asks for a terrain (a warning if it is not one), False never.
    ``lock_boundary`` keeps border vertices where they are; ``weld`` merges vertices at the same
    location first (triangle soups). ``vertex_attributes``/``face_attributes``: arrays of one
    value per vertex (face) by column name; a merged vertex gets the blend of its two ends'.
    ``measure``: how far the output lies from the input, in the report: "quick" (one point of
    each surface per 40 input faces, 1 024 to 8 192, spread by area and measured exactly: a lower
    bound of the Hausdorff distance, for under a tenth of the simplification's time from some
    30 000 faces up), "full" (every vertex and ~4 points per face: slow on big meshes) or
    None.
    ``contact_check``: "after" (the default: collapses made without searching for nearby faces, then
    the result checked once, exactly, and simplified again with every collapse checked if it
    meets itself anywhere) or "each" (every collapse checked: slower, the same result whenever no
    collapse is refused for a contact); ``report["contact_check"]`` says what ran.
    ``threads``: None for all cores (the result is the same for any number). ``progress``: a
    callable taking (phase, share done).

    Returns a :class:`Mesh`: the surviving vertices and faces in input order, their attributes,
    and the ``toposimp mesh --json`` summary as ``report``. Raises :class:`toposimp.InputError`
    for a mesh the engine cannot take (a corner out of range, a non-manifold edge).
    """
    given = [name for name, value in (("keep", keep), ("keep_faces", keep_faces), ("max_error", max_error))
             if value is not None]
    if len(given) > 1:
        raise _toposimp.UsageError("give one target, not " + " and ".join(given))
    if measure not in ("quick", "full", None):
        raise _toposimp.UsageError(f"measure is 'quick', 'full' or None, not {measure!r}")
    if contact_check not in ("after", "each"):
        raise _toposimp.UsageError(f"contact_check is 'after' or 'each', not {contact_check!r}")
    options = {"terrain": terrain is True, "no_terrain": terrain is False, "lock_boundary": bool(lock_boundary), "weld": bool(weld),
               "measure": measure or "none", "threads": 0 if threads is None else int(threads), "verbosity": int(verbose),
               "contact_check": contact_check}
    if keep is not None:
        options["keep"] = _share(keep)
    if keep_faces is not None:
        if keep_faces < 0:
            raise _toposimp.UsageError(f"keep_faces takes a count of at least 0, not {keep_faces!r}")
        options["keep_faces"] = float(keep_faces)
    if max_error is not None:
        if not max_error >= 0:
            raise _toposimp.UsageError(f"max_error takes a distance of at least 0, not {max_error!r}")
        options["max_error"] = float(max_error)
    if options["threads"] < 0:
        raise _toposimp.UsageError(f"threads takes a number of at least 1 (None: all cores), not {threads!r}")
    from . import _interruptible, _report
    out = _toposimp.simplify_mesh_arrays(numpy.asarray(vertices), numpy.asarray(faces), _columns(vertex_attributes),
                                         _columns(face_attributes), options, progress, _interruptible())
    points, corners, vertex_columns, face_columns, summary, messages = out
    _report(messages)
    report = json.loads(summary)
    for key in ("input", "output"):
        report.pop(key, None)
    return Mesh(points, corners, _attributes(vertex_columns), _attributes(face_columns), report)


def read_mesh(path: str, *, triangulate: bool = False) -> Mesh:
    """Read a mesh file (OBJ, PLY, OFF, STL, as ``toposimp mesh`` reads them): polygons are an
    error unless ``triangulate`` splits them into fans. ``report`` says what was read (format,
    encoding, attributes dropped with the reason, STL corners welded)."""
    points, corners, vertex_columns, face_columns, report = _toposimp.read_mesh_file(str(path), bool(triangulate))
    return Mesh(points, corners, _attributes(vertex_columns), _attributes(face_columns), dict(report))


def write_mesh(path: str, mesh: Union[Mesh, tuple], *, format: Optional[str] = None, ascii: bool = False,
               overwrite: bool = False) -> List[str]:
    """Write a mesh file, its format from ``format`` ("obj", "ply", "off", "stl") or the extension,
    with exact coordinates (shortest round-trip text, or doubles in binary PLY). The file appears
    complete or not at all; an existing one is replaced only with ``overwrite``. Returns the
    attribute columns the format has no place for (not written)."""
    vertices, faces = mesh[0], mesh[1]
    vertex_attributes = mesh[2] if len(mesh) > 2 else None
    face_attributes = mesh[3] if len(mesh) > 3 else None
    return _toposimp.write_mesh_file(str(path), numpy.asarray(vertices), numpy.asarray(faces), _columns(vertex_attributes),
                                     _columns(face_attributes), format or "", bool(ascii), bool(overwrite))
