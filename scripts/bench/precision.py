#!/usr/bin/python3
"""Published precision on Natural Earth states with the GeoNames cities (issue 30): toposimp's own
rounding (`map --decimals D`) against rounding its full-precision output afterwards with GDAL's
GeoJSON writer (COORDINATE_PRECISION=D), each counted by `toposimp check --decimals D` (every
kind; given the grid, check takes a vertex on it up to a step from an original vertex for that
vertex); then quantized TopoJSON, toposimp's `--quantize N` against mapshaper's
`-o format=topojson quantization=N` of the same full-precision output (check reads the grid
from the transform). Prints Markdown tables. mapshaper comes from npm (scripts/bench/fetch-data.sh
installs it into --data).

    scripts/bench/precision.py [--build build/release] [--data build/bench-data] [--keep 10%]

The data are those of scripts/bench/same_outputs.py (ne_states.gpkg, cities.gpkg in --data)."""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import same_outputs  # noqa: E402  (the Natural Earth data maker)


def violations(toposimp, states, output, cities, decimals):
    run = subprocess.run([toposimp, "check", states, output, "-p", cities, "--decimals", str(decimals), "--json"],
                         capture_output=True, text=True)
    counts = json.loads(run.stdout)["counts"]
    return {kind: n for kind, n in counts.items() if n}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--data", default=os.path.join(ROOT, "build", "bench-data"))
    parser.add_argument("--keep", default="10%")
    args = parser.parse_args()
    toposimp = os.path.join(args.build, "toposimp")
    states, cities = same_outputs.ne_data(args.data)
    with tempfile.TemporaryDirectory() as out:
        full = os.path.join(out, "full.gpkg")
        subprocess.run([toposimp, "map", states, "-p", cities, "--keep", args.keep, "-o", full, "-q"], check=True)
        print(f"Natural Earth states + GeoNames cities, `--keep {args.keep}`; violations by `toposimp check "
              "--decimals D` (every kind)\n")
        print("| decimals | GDAL GeoJSON of the full-precision output | toposimp `--decimals` | toposimp: moved to nearest / "
              "other grid point / removed / left off the grid (of all locations) | rounding s |")
        print("|---|---|---|---|---|")
        for decimals in (5, 4, 3, 2, 1):
            gdal = os.path.join(out, f"gdal{decimals}.geojson")
            subprocess.run(["ogr2ogr", "-f", "GeoJSON", "-lco", f"COORDINATE_PRECISION={decimals}", gdal, full], check=True)
            rounded = os.path.join(out, f"toposimp{decimals}.gpkg")
            run = subprocess.run([toposimp, "map", states, "-p", cities, "--keep", args.keep, "--decimals", str(decimals), "-o",
                                  rounded, "--json", "-q"], capture_output=True, text=True, check=True)
            summary = json.loads(run.stdout)
            r = summary["rounding"]
            g, t = violations(toposimp, states, gdal, cities, decimals), violations(toposimp, states, rounded, cities, decimals)
            text = lambda found: (f"{sum(found.values())} (" + ", ".join(f"{n} {k}" for k, n in sorted(found.items())) + ")") if found else "0"
            print(f"| {decimals} | {text(g)} | {text(t)} | {r['moved_nearest']} / {r['moved_other']} / {r['removed']} / "
                  f"{r['off_grid']} (of {r['locations']}) | {summary['seconds']['round']:.3f} |", flush=True)
        mapshaper = os.path.join(args.data, "node_modules", ".bin", "mapshaper")
        full_geojson = os.path.join(out, "full.geojson")
        subprocess.run([toposimp, "map", states, "-p", cities, "--keep", args.keep, "-o", full_geojson, "-q"], check=True)
        print(f"\nQuantized TopoJSON of the same run; violations by `toposimp check` with the transform's grid\n")
        print("| quantization | mapshaper `quantization=N` | toposimp `--quantize N` | size: mapshaper / toposimp (bytes) |")
        print("|---|---|---|---|")
        for n in (10000, 100000, 1000000):
            theirs, ours = os.path.join(out, f"mapshaper{n}.topojson"), os.path.join(out, f"toposimp{n}.topojson")
            subprocess.run([mapshaper, "-i", full_geojson, "-o", "format=topojson", f"quantization={n}", theirs],
                           check=True, capture_output=True)
            run = subprocess.run([toposimp, "map", states, "-p", cities, "--keep", args.keep, "--quantize", str(n), "-o", ours, "-q"],
                                 capture_output=True, text=True)
            def counted(path):
                check = subprocess.run([toposimp, "check", states, path, "-p", cities, "--json"], capture_output=True, text=True)
                found = {k: v for k, v in json.loads(check.stdout)["counts"].items() if v}
                return (f"{sum(found.values())} (" + ", ".join(f"{v} {k}" for k, v in sorted(found.items())) + ")") if found else "0"
            toposimp_cell = counted(ours) if run.returncode == 0 else "refused: " + run.stderr.strip().splitlines()[-1][:120]
            size = f"{os.path.getsize(theirs)} / {os.path.getsize(ours) if run.returncode == 0 else '–'}"
            print(f"| {n} | {counted(theirs)} | {toposimp_cell} | {size} |", flush=True)
        print(f"\nGeoJSON at D decimals of the same run: mapshaper's `-o precision=` on the full-precision output "
              f"against toposimp `--decimals D`; violations by `toposimp check --decimals D`\n")
        print("| decimals | mapshaper `precision=` | toposimp `--decimals` | size: mapshaper / toposimp (bytes) |")
        print("|---|---|---|---|")
        for decimals in (4, 3, 2):
            theirs = os.path.join(out, f"mapshaper{decimals}.geojson")
            ours = os.path.join(out, f"toposimp{decimals}.geojson")
            subprocess.run([mapshaper, "-i", full_geojson, "-o", f"precision={10 ** -decimals:.{decimals}f}", theirs],
                           check=True, capture_output=True)
            subprocess.run([toposimp, "map", states, "-p", cities, "--keep", args.keep, "--decimals", str(decimals), "-o", ours, "-q"],
                           check=True)
            g, t = violations(toposimp, states, theirs, cities, decimals), violations(toposimp, states, ours, cities, decimals)
            text = lambda found: (f"{sum(found.values())} (" + ", ".join(f"{n} {k}" for k, n in sorted(found.items())) + ")") if found else "0"
            print(f"| {decimals} | {text(g)} | {text(t)} | {os.path.getsize(theirs)} / {os.path.getsize(ours)} |", flush=True)


if __name__ == "__main__":
    main()
