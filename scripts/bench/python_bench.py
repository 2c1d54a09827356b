#!/usr/bin/python3
"""toposimp from Python against geopandas' own simplify, on Natural Earth's states/provinces with
the GeoNames cities as control points (scripts/bench/fetch-data.sh makes them):

- for each target, toposimp.simplify's time (the whole call: WKB out of the GeoDataFrame, the
  engine, the GeoDataFrame back) and its violations counted by toposimp.check (0 expected);
- geopandas.GeoSeries.simplify(tol, preserve_topology=True) with the tolerance found by bisection
  to keep as many feature vertices as toposimp kept, its time and its violations;
- the same job with the toposimp executable (GeoPackage in, GeoPackage out, --json), and the
  overhead of the Python path: its time over the command line's engine time (the summary's
  seconds.simplify + seconds.round) and over the command line's whole run.

    scripts/bench/python_bench.py [--data build/bench-data] [--build build/release] [--targets 50%,20%,max]
                                  [--runs 3] [--markdown FILE]

The package is imported from <build>/python, the executable is <build>/toposimp. Prints a
Markdown table (and writes it to --markdown).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))


def feature_vertices(series):
    """Coordinates of every line and ring, as the features hold them (closing points included)."""
    total = 0
    for geometry in series.values:
        if geometry is None or geometry.is_empty:
            continue
        polygons = geometry.geoms if geometry.geom_type == "MultiPolygon" else [geometry]
        for polygon in polygons:
            total += len(polygon.exterior.coords) + sum(len(ring.coords) for ring in polygon.interiors)
    return total


def median_time(call, runs):
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    times.sort()
    return times[len(times) // 2], result


def violations_text(report):
    if report.empty:
        return "0"
    counts = report["kind"].value_counts()
    return f"{len(report)}: " + ", ".join(f"{n} {kind.replace('_', ' ')}" for kind, n in counts.items())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", default=os.path.join(ROOT, "build", "bench-data"))
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--targets", default="50%,20%,max")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--markdown")
    args = parser.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import warnings

    import geopandas
    import toposimp
    warnings.simplefilter("ignore", toposimp.ToposimpWarning)  # (the targets below the reachable minimum)

    states_path = os.path.join(args.data, "ne_states.gpkg")
    cities_path = os.path.join(args.data, "cities.gpkg")
    for path in (states_path, cities_path):
        if not os.path.exists(path):
            sys.exit(f"{path} missing: run scripts/bench/fetch-data.sh")
    states = geopandas.read_file(states_path)
    cities = geopandas.read_file(cities_path)
    binary = os.path.join(args.build, "toposimp")
    input_vertices = feature_vertices(states.geometry)
    rows = []
    for target in args.targets.split(","):
        option = {"max": True} if target == "max" else {"keep": float(target.rstrip("%")) / 100}
        ours_s, ours = median_time(lambda: toposimp.simplify(states, points=cities, **option), args.runs)
        summary = toposimp.summary(ours)
        kept = feature_vertices(ours.geometry)
        ours_report = toposimp.check(states, ours, points=cities)

        with tempfile.TemporaryDirectory() as folder:
            out = os.path.join(folder, "out.gpkg")
            cli_runs = []
            for _ in range(args.runs):
                criterion = ["--max"] if target == "max" else ["--keep", target]
                done = subprocess.run([binary, "map", states_path, "--points", cities_path, *criterion, "--json",
                                       "--overwrite", "-o", out], capture_output=True, text=True, check=True)
                cli_runs.append(json.loads(done.stdout))
            cli_runs.sort(key=lambda s: s["seconds"]["total"])
            cli = cli_runs[len(cli_runs) // 2]
            theirs_cli = geopandas.read_file(out)
        same = [g.wkb for g in ours.geometry.values] == [g.wkb for g in theirs_cli.geometry.values]
        engine = cli["seconds"]["simplify"] + cli["seconds"].get("round", 0.0)

        # geopandas (shapely/GEOS, feature by feature) at the same number of feature vertices.
        low, high = 0.0, 1.0
        while feature_vertices(states.geometry.simplify(high, preserve_topology=True)) > kept:
            high *= 2
        for _ in range(40):
            middle = (low + high) / 2
            if feature_vertices(states.geometry.simplify(middle, preserve_topology=True)) > kept:
                low = middle
            else:
                high = middle
        tolerance = high
        theirs_s, theirs = median_time(lambda: states.geometry.simplify(tolerance, preserve_topology=True), args.runs)
        theirs_report = toposimp.check(states.geometry, theirs, points=cities)
        rows.append(dict(target=target, kept=kept, ours_s=ours_s, summary=summary, job=summary["seconds"]["total"], ours=violations_text(ours_report),
                         cli_total=cli["seconds"]["total"], engine=engine, same=same, tolerance=tolerance,
                         theirs_kept=feature_vertices(theirs), theirs_s=theirs_s, theirs=violations_text(theirs_report)))

    lines = [f"States/provinces: {len(states)} features, {input_vertices} feature vertices; "
             f"{len(cities)} cities as control points. {args.runs} runs each, medians; 2 threads.", "",
             "| target | tool | feature vertices kept | seconds | `toposimp.check` violations |", "|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['target']} | `toposimp.simplify(states, {'max=True' if row['target'] == 'max' else 'keep=…'}, points=cities)` | {row['kept']} | "
                     f"{row['ours_s']:.3f} | {row['ours']} |")
        lines.append(f"| {row['target']} | `GeoSeries.simplify({row['tolerance']:.4g}, preserve_topology=True)` | "
                     f"{row['theirs_kept']} | {row['theirs_s']:.3f} | {row['theirs']} |")
    lines += ["", "| target | Python call s | of which the job in C++ s (layers in, coverage, engine, WKB out) | "
              "conversions in Python s | CLI engine s (simplify + round) | CLI whole run s (GeoPackages in and out) | "
              "Python / CLI engine | Python / CLI run | same geometries as the CLI |", "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['target']} | {row['ours_s']:.3f} | {row['job']:.3f} | {row['ours_s'] - row['job']:.3f} | "
                     f"{row['engine']:.3f} | {row['cli_total']:.3f} | {row['ours_s'] / row['engine']:.2f} | "
                     f"{row['ours_s'] / row['cli_total']:.2f} | {'yes' if row['same'] else 'NO'} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as out:
            out.write(text)


if __name__ == "__main__":
    main()
