#!/usr/bin/python3
"""Issue 34's targets, two builds side by side: GSHHG at --keep 10 % and 1 %, GSHHG at 50 % with its
10 M control points, Natural Earth states + cities at 10 %, each on 1 and 2 threads, runs
alternating between the builds; mapshaper (-simplify visvalingam, at the share toposimp kept) in
the same run for the ratio. Prints a Markdown table of wall-time medians, toposimp's phases and
peak memory, and whether the two builds wrote byte-identical files:

    scripts/bench/map_speed.py OLD_BUILD_DIR NEW_BUILD_DIR [--runs 3] [--data build/bench-data] [--jobs a,b]
                               [--old-env NAME=VALUE ...] [--new-env NAME=VALUE ...]

--old-env/--new-env add environment variables to one side's runs (e.g. one build on both sides,
--old-env GLIBC_TUNABLES=glibc.malloc.hugetlb=0 to time it without transparent huge pages).

Data: scripts/bench/fetch-data.sh (GSHHG, its points, Natural Earth, the cities; mapshaper from npm)."""
import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))

# name: (input, control points or None, target options)
JOBS = {
    "gshhg-10%": ("gshhg.shp", None, ["--keep", "10%"]),
    "gshhg-1%": ("gshhg.shp", None, ["--keep", "1%"]),
    "gshhg-50%-points": ("gshhg.shp", "gshhg_points.gpkg", ["--keep", "50%"]),
    "ne-10%-cities": ("ne_states.shp", "cities.shp", ["--keep", "10%"]),
}


def digest(folder):
    h = hashlib.sha256()
    for name in sorted(os.listdir(folder)):
        with open(os.path.join(folder, name), "rb") as f:
            h.update(name.encode() + f.read())
    return h.hexdigest()[:16]


def run_toposimp(build, data, job, threads, out_dir, env=None):
    source, points, target = JOBS[job]
    command = [os.path.join(build, "toposimp"), "map", os.path.join(data, source), "-o", os.path.join(out_dir, "out.shp"),
               "--overwrite", "--json", "-j", str(threads)] + target
    if points:
        command += ["-p", os.path.join(data, points)]
    start = time.perf_counter()
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    wall = time.perf_counter() - start
    if result.returncode != 0:
        sys.exit("%s failed:\n%s" % (" ".join(command), result.stderr[-2000:]))
    return wall, json.loads(result.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--data", default=os.path.join(ROOT, "build", "bench-data"))
    parser.add_argument("--jobs", default=",".join(JOBS))
    parser.add_argument("--old-env", action="append", default=[], metavar="NAME=VALUE")
    parser.add_argument("--new-env", action="append", default=[], metavar="NAME=VALUE")
    args = parser.parse_args()
    environments = {"old": dict(os.environ, **dict(v.split("=", 1) for v in args.old_env)),
                    "new": dict(os.environ, **dict(v.split("=", 1) for v in args.new_env))}
    mapshaper = os.path.join(args.data, "node_modules", ".bin", "mapshaper")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for job in args.jobs.split(","):
            for threads in (1, 2):
                walls = {"old": [], "new": []}
                report = {}
                outputs = {}
                for _ in range(args.runs):
                    for which, build in (("old", args.old), ("new", args.new)):
                        out_dir = os.path.join(tmp, which)
                        os.makedirs(out_dir, exist_ok=True)
                        wall, summary = run_toposimp(build, args.data, job, threads, out_dir, environments[which])
                        walls[which].append(wall)
                        report.setdefault(which, []).append(summary)
                        outputs[which] = digest(out_dir)
                new = report["new"]
                phases = {k: statistics.median(r["seconds"][k] for r in new) for k in ("read", "simplify", "write")}
                engine = {k: statistics.median(r["engine_seconds"][k] for r in new) for k in ("index", "crossings", "sweep")}
                rows.append(dict(job=job, threads=threads, old=statistics.median(walls["old"]), new=statistics.median(walls["new"]),
                                 same=outputs["old"] == outputs["new"], phases=phases, engine=engine,
                                 memory=max(r["peak_memory_mib"] for r in new), old_memory=max(r["peak_memory_mib"] for r in report["old"]),
                                 kept=new[0]["vertices_out"],
                                 vertices=new[0]["vertices_in"], rounds=new[0]["parallel"]["rounds"]))
            # mapshaper at the share toposimp kept, in the same run.
            source = JOBS[job][0]
            share = rows[-1]["kept"] / rows[-1]["vertices"]
            ms_walls = []
            for _ in range(args.runs):
                command = [mapshaper, "-i", os.path.join(args.data, source), "-simplify", "visvalingam", "keep-shapes",
                           "%.4f%%" % (100 * share), "-o", os.path.join(tmp, "mapshaper.shp"), "force"]
                start = time.perf_counter()
                subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
                ms_walls.append(time.perf_counter() - start)
            for row in rows[-2:]:
                row["mapshaper"] = statistics.median(ms_walls)
    print("| job | threads | old wall s | new wall s | new/old | identical | read | index | crossings | sweep | write | rounds |"
          " simplify 1 → 2 threads | peak MiB old → new | mapshaper s | mapshaper/new |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        p, e = r["phases"], r["engine"]
        speedup = ""
        if r["threads"] == 2:
            one = next(x for x in rows if x["job"] == r["job"] and x["threads"] == 1)
            speedup = "%.2f×" % (one["phases"]["simplify"] / p["simplify"])
        print("| %s | %d | %.2f | %.2f | %.2f | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %d | %s | %.0f → %.0f | %.2f | %.1f× |" % (
            r["job"], r["threads"], r["old"], r["new"], r["new"] / r["old"], "yes" if r["same"] else "NO", p["read"],
            e["index"], e["crossings"], e["sweep"], p["write"], r["rounds"], speedup, r["old_memory"], r["memory"], r["mapshaper"],
            r["mapshaper"] / r["new"]))


if __name__ == "__main__":
    main()
