#!/usr/bin/python3
"""A generated map for distributed runs (issue 32): a coverage of jagged square cells (shared
borders), rivers (random walks that cross the borders and themselves), roads (straight lines over
everything: crossings) and control points.

    scripts/bench/generate_map.py OUT_DIR [--cells N] [--edge-vertices K] [--rivers R]
                                  [--river-steps S] [--roads D] [--points P] [--seed X]

writes OUT_DIR/map.gpkg (layers cells, rivers, roads) and OUT_DIR/places.gpkg (layer places);
with --shapefiles, for maps of any size (streamed, no GDAL), OUT_DIR/cells.shp, rivers.shp,
roads.shp and places.shp instead. Cell (i, j) spans [i, i+1] × [j, j+1]; each shared border has K
vertices between the corners, displaced across it by at most 0.2·sin(π t) at t along it, so no two
borders meet but at corners.
"""
import argparse
import math
import pathlib
import struct

import numpy


def borders(rng, cells, k):
    """Horizontal borders H[i][j] (corner (i, j) to (i+1, j)) and vertical ones V[i][j] (to
    (i, j+1)), each an array of K+2 points."""
    t = numpy.arange(1, k + 1) / (k + 1)
    bulge = 0.2 * numpy.sin(math.pi * t)

    def edge(start, along):
        offset = bulge * rng.uniform(-1, 1, size=k)
        points = numpy.empty((k + 2, 2))
        points[0] = start
        points[-1] = (start[0] + along[0], start[1] + along[1])
        points[1:-1, 0] = start[0] + along[0] * t + along[1] * offset
        points[1:-1, 1] = start[1] + along[1] * t + along[0] * offset
        return points

    horizontal = [[edge((i, j), (1, 0)) for j in range(cells + 1)] for i in range(cells)]
    vertical = [[edge((i, j), (0, 1)) for j in range(cells)] for i in range(cells + 1)]
    return horizontal, vertical


def cell_rings(horizontal, vertical, cells):
    for j in range(cells):
        for i in range(cells):
            ring = numpy.concatenate([horizontal[i][j], vertical[i + 1][j][1:], horizontal[i][j + 1][::-1][1:],
                                      vertical[i][j][::-1][1:]])
            yield i, j, ring


def random_walk(rng, cells, steps):
    start = rng.uniform(0.5, cells - 0.5, size=2)
    angle = numpy.cumsum(rng.normal(0, 0.4, size=steps))
    step = numpy.stack([numpy.cos(angle), numpy.sin(angle)], axis=1) * 0.05
    walk = start + numpy.cumsum(step, axis=0)
    return numpy.clip(walk, 0.01, cells - 0.01)


def generate(out_dir, cells=20, edge_vertices=20, rivers=30, river_steps=300, roads=6, points=3000, seed=1):
    import geopandas
    from shapely.geometry import LineString, Point, Polygon

    rng = numpy.random.default_rng(seed)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    horizontal, vertical = borders(rng, cells, edge_vertices)
    ids, polygons = [], []
    for i, j, ring in cell_rings(horizontal, vertical, cells):
        ids.append(j * cells + i)
        polygons.append(Polygon(ring))
    geopandas.GeoDataFrame({"id": ids}, geometry=polygons, crs="EPSG:3857").to_file(out / "map.gpkg", layer="cells", driver="GPKG")
    walks = [LineString(random_walk(rng, cells, river_steps)) for _ in range(rivers)]
    geopandas.GeoDataFrame({"id": range(rivers)}, geometry=walks, crs="EPSG:3857").to_file(out / "map.gpkg", layer="rivers",
                                                                                           driver="GPKG")
    lines = []
    for _ in range(roads):
        a, b = rng.uniform(0, cells, size=2), rng.uniform(0, cells, size=2)
        lines.append(LineString([a, (a + b) / 2 + rng.normal(0, 0.5, size=2), b]))
    geopandas.GeoDataFrame({"id": range(roads)}, geometry=lines, crs="EPSG:3857").to_file(out / "map.gpkg", layer="roads", driver="GPKG")
    places = [Point(xy) for xy in rng.uniform(0, cells, size=(points, 2))]
    geopandas.GeoDataFrame({"id": range(points)}, geometry=places, crs="EPSG:3857").to_file(out / "places.gpkg", layer="places",
                                                                                            driver="GPKG")
    return out / "map.gpkg", out / "places.gpkg"


class ShapefileWriter:
    """Writes a Shapefile (.shp, .shx, .dbf with one numeric field "id") record by record: the
    headers are written last, when the extent and the count are known."""

    POINT, POLYLINE, POLYGON = 1, 3, 5

    def __init__(self, stem, kind):
        self.kind = kind
        self.shp = open(f"{stem}.shp", "wb")
        self.shx = open(f"{stem}.shx", "wb")
        self.dbf = open(f"{stem}.dbf", "wb")
        for f in (self.shp, self.shx):
            f.write(bytes(100))
        self.dbf.write(bytes(32 + 32 + 1))
        self.count = 0
        self.box = [math.inf, math.inf, -math.inf, -math.inf]
        self.offset = 50  # in 16-bit words

    def _record(self, content):
        self.count += 1
        words = len(content) // 2
        self.shp.write(struct.pack(">ii", self.count, words))
        self.shp.write(content)
        self.shx.write(struct.pack(">ii", self.offset, words))
        self.offset += 4 + words
        self.dbf.write(b" " + f"{self.count - 1:>12d}".encode())

    def add_null(self):
        """One record without a shape."""
        self._record(struct.pack("<i", 0))

    def add(self, parts):
        """One record: a point (x, y), or a list of arrays of points (lines, rings)."""
        if self.kind == self.POINT:
            x, y = parts
            self.box = [min(self.box[0], x), min(self.box[1], y), max(self.box[2], x), max(self.box[3], y)]
            self._record(struct.pack("<idd", self.POINT, x, y))
            return
        points = numpy.concatenate(parts)
        lo, hi = points.min(axis=0), points.max(axis=0)
        self.box = [min(self.box[0], lo[0]), min(self.box[1], lo[1]), max(self.box[2], hi[0]), max(self.box[3], hi[1])]
        starts = numpy.cumsum([0] + [len(part) for part in parts[:-1]]).astype("<i4")
        content = struct.pack("<i4dii", self.kind, lo[0], lo[1], hi[0], hi[1], len(parts), len(points))
        self._record(content + starts.tobytes() + numpy.ascontiguousarray(points, dtype="<f8").tobytes())

    def close(self):
        box = struct.pack("<4d", *self.box) if self.count else bytes(32)
        for f, length in ((self.shp, self.offset), (self.shx, 50 + 4 * self.count)):
            f.seek(0)
            f.write(struct.pack(">i5ii", 9994, 0, 0, 0, 0, 0, length) + struct.pack("<ii", 1000, self.kind) + box + bytes(32))
            f.close()
        self.dbf.write(b"\x1a")
        self.dbf.seek(0)
        self.dbf.write(struct.pack("<B3BIHH20x", 3, 126, 11, 27, self.count, 32 + 32 + 1, 1 + 12))
        self.dbf.write(b"id".ljust(11, b"\0") + b"N" + bytes(4) + bytes([12, 0]) + bytes(14) + b"\x0d")
        self.dbf.close()


def generate_shapefiles(out_dir, cells, edge_vertices, rivers, river_steps, roads, points, seed, with_cells=True):
    """The same map as generate(), as Shapefiles written as they are made (any size); without
    the cells' coverage if not `with_cells` (the other layers as with it)."""
    rng = numpy.random.default_rng(seed)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    horizontal, vertical = borders(rng, cells, edge_vertices)
    if with_cells:
        writer = ShapefileWriter(out / "cells", ShapefileWriter.POLYGON)
        for _, _, ring in cell_rings(horizontal, vertical, cells):
            writer.add([ring[::-1]])  # (outer rings clockwise)
        writer.close()
    del horizontal, vertical
    writer = ShapefileWriter(out / "rivers", ShapefileWriter.POLYLINE)
    for _ in range(rivers):
        writer.add([random_walk(rng, cells, river_steps)])
    writer.close()
    writer = ShapefileWriter(out / "roads", ShapefileWriter.POLYLINE)
    for _ in range(roads):
        a, b = rng.uniform(0, cells, size=2), rng.uniform(0, cells, size=2)
        writer.add([numpy.array([a, (a + b) / 2 + rng.normal(0, 0.5, size=2), b])])
    writer.close()
    writer = ShapefileWriter(out / "places", ShapefileWriter.POINT)
    for x, y in rng.uniform(0, cells, size=(points, 2)):
        writer.add((float(x), float(y)))
    writer.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out_dir")
    parser.add_argument("--cells", type=int, default=20)
    parser.add_argument("--edge-vertices", type=int, default=20)
    parser.add_argument("--rivers", type=int, default=30)
    parser.add_argument("--river-steps", type=int, default=300)
    parser.add_argument("--roads", type=int, default=6)
    parser.add_argument("--points", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--shapefiles", action="store_true", help="Shapefiles, streamed (for big maps)")
    a = parser.parse_args()
    make = generate_shapefiles if a.shapefiles else generate
    make(a.out_dir, a.cells, a.edge_vertices, a.rivers, a.river_steps, a.roads, a.points, a.seed)


if __name__ == "__main__":
    main()
