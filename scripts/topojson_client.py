#!/usr/bin/python3
"""Reads toposimp's TopoJSON back with the reference client, npm's topojson-client (topo2geo),
and compares every feature with toposimp's GeoPackage output of the same run (decoded here
from its WKB): the same coordinates bit for bit (rings compared whatever vertex they start at:
a TopoJSON ring starts where its first arc does) and the same attributes. Also one TopoJSON of
nested --levels (positions ranked by a third coordinate): topojson-simplify's simplify(topology, k)
must give back level k, the same as the level's own file. Installs topojson-client and
topojson-simplify into build/npm on first use.

    scripts/topojson_client.py [--build build/dev]"""
import argparse
import json
import os
import sqlite3
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def canonical(geometry):
    if geometry is None:
        return None
    kind, coordinates = geometry["type"], geometry.get("coordinates")
    def ring(points):
        points = [tuple(p) for p in points[:-1]]
        start = points.index(min(points))
        return points[start:] + points[:start]
    if kind == "Polygon":
        return ("MultiPolygon", [[ring(r) for r in coordinates]])
    if kind == "MultiPolygon":
        return ("MultiPolygon", [[ring(r) for r in polygon] for polygon in coordinates])
    return (kind, coordinates)


def wkb_geometry(blob):
    """GeoPackage binary header + ISO WKB (2D) as a GeoJSON-like geometry."""
    if blob is None:
        return None
    flags = blob[3]
    at = 8 + {0: 0, 1: 32, 2: 48, 3: 48, 4: 64}[(flags >> 1) & 7]
    def read(at):
        order = "<" if blob[at] == 1 else ">"
        kind = struct.unpack_from(order + "I", blob, at + 1)[0] % 1000
        at += 5
        def points(at):
            n = struct.unpack_from(order + "I", blob, at)[0]
            values = struct.unpack_from(order + "%dd" % (2 * n), blob, at + 4)
            return [[values[2 * i], values[2 * i + 1]] for i in range(n)], at + 4 + 16 * n
        if kind == 1:
            x, y = struct.unpack_from(order + "dd", blob, at)
            return {"type": "Point", "coordinates": [x, y]}, at + 16
        if kind == 2:
            line, at = points(at)
            return {"type": "LineString", "coordinates": line}, at
        if kind == 3:
            n = struct.unpack_from(order + "I", blob, at)[0]
            at += 4
            rings = []
            for _ in range(n):
                ring, at = points(at)
                rings.append(ring)
            return {"type": "Polygon", "coordinates": rings}, at
        n = struct.unpack_from(order + "I", blob, at)[0]
        at += 4
        parts = []
        for _ in range(n):
            part, at = read(at)
            parts.append(part["coordinates"])
        return {"type": {4: "MultiPoint", 5: "MultiLineString", 6: "MultiPolygon"}[kind], "coordinates": parts}, at
    return read(at)[0]


def gpkg_features(path, layer):
    db = sqlite3.connect(path)
    column = db.execute("SELECT column_name FROM gpkg_geometry_columns WHERE table_name = ?", (layer,)).fetchone()[0]
    names = [row[1] for row in db.execute(f'PRAGMA table_info("{layer}")')]
    features = []
    for row in db.execute(f'SELECT * FROM "{layer}" ORDER BY rowid'):
        values = dict(zip(names, row))
        geometry = wkb_geometry(values.pop(column))
        values.pop("fid", None)
        features.append((values, geometry))
    return features


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "dev"))
    args = parser.parse_args()
    npm = os.path.join(ROOT, "build", "npm")
    topo2geo = os.path.join(npm, "node_modules", ".bin", "topo2geo")
    if not os.path.exists(os.path.join(npm, "node_modules", "topojson-simplify")):
        subprocess.run(["npm", "install", "--silent", "--prefix", npm, "topojson-client@3", "topojson-simplify@3"], check=True)
    toposimp = os.path.join(args.build, "toposimp")
    failures = 0
    with tempfile.TemporaryDirectory() as out:
        for data, options in (("ne_states_slice.gpkg", ["--keep", "20%"]), ("ne_states_slice.gpkg", ["--max", "--decimals", "2"]),
                              ("nh_borders.gpkg", ["--keep", "10%"]), ("ne_states_slice.gpkg", ["--keep", "20%", "--quantize", "10000"]),
                              ("nh_borders.gpkg", ["--keep", "10%", "--quantize", "100000"])):
            source = os.path.join(ROOT, "testdata", data)
            topo, gpkg = os.path.join(out, "out.topojson"), os.path.join(out, "out.gpkg")
            subprocess.run([toposimp, "map", source, "-o", topo, "--overwrite", "-q"] + options, check=True)
            if "--quantize" in options:
                # No GeoPackage has a quantized grid: GDAL's own decoding, which toposimp's read-back
                # found bit for bit what it meant, copied into one.
                if os.path.exists(gpkg):
                    os.remove(gpkg)
                subprocess.run(["ogr2ogr", "-f", "GPKG", gpkg, topo], check=True)
            else:
                subprocess.run([toposimp, "map", source, "-o", gpkg, "--overwrite", "-q"] + options, check=True)
            for layer in json.load(open(topo))["objects"]:
                subprocess.run([topo2geo, "-i", topo, f"{layer}={out}/{layer}.client.geojson"], check=True)
                client = json.load(open(f"{out}/{layer}.client.geojson"))["features"]
                ours = gpkg_features(gpkg, layer)
                # (Values compared as text: GDAL reads a TopoJSON property named "id" as a string.)
                def text(properties):
                    return {k: str(v) for k, v in properties.items() if v is not None}
                same = len(ours) == len(client) and all(
                    text(properties) == text(b["properties"]) and canonical(geometry) == canonical(b["geometry"])
                    for (properties, geometry), b in zip(ours, client))
                print(f"{data} {' '.join(options)}, layer {layer}: {len(client)} features, "
                      f"{'the same' if same else 'DIFFERENT'} through topojson-client")
                failures += not same
        # Nested levels in one ranked TopoJSON against one file per level, at full precision and
        # rounded (the coarser levels keep the first level's rounded positions).
        source = os.path.join(ROOT, "testdata", "ne_states_slice.gpkg")
        levels = ["60%", "30%", "22%"]
        script = os.path.join(out, "level.js")
        with open(script, "w") as f:
            f.write("const fs = require('fs'), simplify = require('topojson-simplify'), client = require('topojson-client');\n"
                    "const [file, object, weight, out] = process.argv.slice(2);\n"
                    "const level = simplify.simplify(JSON.parse(fs.readFileSync(file, 'utf8')), Number(weight));\n"
                    "fs.writeFileSync(out, JSON.stringify(client.feature(level, level.objects[object])));\n")
        for rounding in ([], ["--decimals", "3"]):
            ranked = os.path.join(out, "ranked.topojson")
            subprocess.run([toposimp, "map", source, "--levels", ",".join(levels), "-o", ranked, "-q", "--overwrite"] + rounding, check=True)
            subprocess.run([toposimp, "map", source, "--levels", ",".join(levels), "-o", os.path.join(out, "level_{level}.gpkg"), "-q",
                            "--overwrite"] + rounding, check=True)
            for k, level in enumerate(levels, 1):
                shown = os.path.join(out, f"shown{k}.geojson")
                subprocess.run(["node", script, ranked, "states", str(k), shown], check=True,
                               env=dict(os.environ, NODE_PATH=os.path.join(npm, "node_modules")))
                client = json.load(open(shown))["features"]
                ours = gpkg_features(os.path.join(out, f"level_{level.replace('%', 'pct')}.gpkg"), "states")
                def flat(geometry):  # without the rank
                    kind, parts = canonical(geometry)
                    return (kind, [[[(p[0], p[1]) for p in ring] for ring in polygon] for polygon in parts])
                same = len(ours) == len(client) and all(flat(g) == flat(b["geometry"]) for (_, g), b in zip(ours, client))
                print(f"ranked TopoJSON of --levels {','.join(levels)} {' '.join(rounding)}: topojson-simplify weight {k} gives "
                      f"level {level}: {'the same' if same else 'DIFFERENT'}")
                failures += not same
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
