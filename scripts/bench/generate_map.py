#!/usr/bin/python3
"""A generated map for distributed runs (issue 32): a coverage of jagged square cells (shared
borders), rivers (random walks that cross the borders and themselves), roads (straight lines over
everything: crossings) and control points.

    scripts/bench/generate_map.py OUT_DIR [--cells N] [--edge-vertices K] [--rivers R]
                                  [--river-steps S] [--roads D] [--points P] [--seed X]

writes OUT_DIR/map.gpkg (layers cells, rivers, roads) and OUT_DIR/places.gpkg (layer places).
Cell (i, j) spans [i, i+1] × [j, j+1]; each shared border has K vertices between the corners,
displaced across it by at most 0.2·sin(π t) at t along it, so no two borders meet but at corners.
"""
import argparse
import math
import pathlib

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
    a = parser.parse_args()
    generate(a.out_dir, a.cells, a.edge_vertices, a.rivers, a.river_steps, a.roads, a.points, a.seed)


if __name__ == "__main__":
    main()
