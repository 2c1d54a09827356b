#!/usr/bin/env python3
"""Terrain benchmark of the guaranteed vertical error: toposimp mesh --terrain --max-error E
(all threads) against meshoptimizer (meshopt_simplify with LockBorder) asked for the same face
count, on the same inputs, one run each.

For every output: faces, wall time, the simplification call's own time, the sampled vertical
error to the input (largest |dz| straight above or below, from the samples toposimp mesh uses)
and the defects the tests' brute-force checker finds (tests/tools/mesh_defects). toposimp's
vertical error is guaranteed at most E everywhere; the samples can only confirm it.

Usage: scripts/bench/vertical.py [--data DIR] [--runs "jacksboro:2,5,10;terrain-2M:0.5,1.2"]
Needs what scripts/bench/mesh.py needs (it builds the peers and generates the inputs).
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mesh  # noqa: E402  (the inputs, the peers and the timing of mesh.py)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--data", default="/work/bench-data")
    parser.add_argument("--runs", default="jacksboro:2,5,10;terrain-2M:0.5,1.2")
    args = parser.parse_args()
    os.makedirs(args.data, exist_ok=True)
    subprocess.run(["cmake", "-S", os.path.join(mesh.ROOT, "scripts", "bench", "mesh_peers"), "-B", mesh.PEERS, "-G", "Ninja"],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", mesh.PEERS], check=True, stdout=subprocess.DEVNULL)
    sources = {"jacksboro": lambda: mesh.dem(args.data)}
    for name, n in (("terrain-0.9M", 671), ("terrain-2M", 1000), ("terrain-4M", 1414)):
        path = os.path.join(args.data, name + ".ply")
        sources[name] = lambda n=n, path=path: (mesh.terrain(path, n), path)[1]
    out_dir = os.path.join(args.data, "vertical-out")
    os.makedirs(out_dir, exist_ok=True)
    threads = os.cpu_count()
    rows = []
    for run in args.runs.split(";"):
        name, errors = run.split(":")
        source = sources[name]()
        faces = mesh.faces_of(source)
        for error in errors.split(","):
            out = os.path.join(out_dir, f"{name}-toposimp-{error}.ply")
            wall, _, text = mesh.timed([mesh.TOPOSIMP, "mesh", source, "-o", out, "--overwrite", "--terrain", "--max-error", error,
                                        "-j", str(threads), "--no-hausdorff", "--json"])
            report = json.loads(text)
            runs = [(f"toposimp {threads} thr, --max-error {error}", out, wall, report["seconds"]["simplify"])]
            peer = os.path.join(out_dir, f"{name}-meshopt-{error}.ply")
            wall, _, text = mesh.timed([os.path.join(mesh.PEERS, "meshopt_simplify"), source, peer, str(report["faces_out"]),
                                        "--lock-border"])
            runs.append(("meshoptimizer 0.18 LockBorder, same faces", peer, wall, json.loads(text)["simplify_seconds"]))
            for label, path, seconds, simplify in runs:
                check = [mesh.DEFECTS, path, "--terrain", "--against", source]
                found = json.loads(subprocess.run(check, capture_output=True, text=True, timeout=1800, check=True).stdout)
                rows.append((name, faces, error, label, found, seconds, simplify))
                print(f"{name} E={error} {label}: {seconds:.2f} s, {found}", file=sys.stderr)
    print(f"Machine: {threads} cores. One run each.\n")
    print("| input (faces) | E | tool | faces out | wall s | simplify s | sampled vertical error | intersecting pairs | non-manifold edges | map-plane folds |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, faces, error, label, d, seconds, simplify in rows:
        print(f"| {name} ({faces}) | {error} | {label} | {d['faces']} | {seconds:.2f} | {simplify:.3f} | {d['vertical_error']:.4g} | "
              f"{d['intersecting_pairs']} | {d['non_manifold_edges']} | {d['map_plane_folds']} |")


if __name__ == "__main__":
    main()
