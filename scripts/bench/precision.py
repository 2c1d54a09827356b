#!/usr/bin/python3
"""Published precision on Natural Earth states with the GeoNames cities (issue 30): toposimp's own
rounding (`map --decimals D`) against rounding its full-precision output afterwards with GDAL's
GeoJSON writer (COORDINATE_PRECISION=D), each counted by `toposimp check --decimals D` (every
kind; given the grid, check takes a vertex on it up to a step from an original vertex for that
vertex). Prints a Markdown table.

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


if __name__ == "__main__":
    main()
