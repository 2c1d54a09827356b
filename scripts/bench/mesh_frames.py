#!/usr/bin/env python3
"""Where a mesh sits and how large it is must not matter: the refined elephant (CGAL's demo
data) as given, moved to UTM-like coordinates (+5e5, +4e6, +100), and scaled by 1e100, 1e150,
1e-100 and 1e-150, each simplified to 10 % of its faces on 2 threads. Prints per input the
simplification time, the Hausdorff distance as a share of the bounding-box diagonal, the
largest quadric error divided by the scale, and how many predicate calls went to GMP: a
Markdown table. Every row should match the first but for time.

Usage: scripts/bench/mesh_frames.py [--data DIR] [--toposimp BIN] [--timeout S]
Needs: build/release (scripts/build.sh release) and libcgal-demo (scripts/bench/fetch-data.sh).
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
from mesh import TOPOSIMP, cgal_model  # noqa: E402


def transformed(source, path, scale, offset):
    """The OFF file `source` with every point p written as p * scale + offset (shortest repr)."""
    if os.path.exists(path):
        return path
    with open(source) as f:
        lines = [line for line in f.read().split("\n") if line.strip() and not line.startswith("#")]
    vertices = int(lines[1].split()[0])
    out = lines[:2]
    for line in lines[2:2 + vertices]:
        x, y, z = (float(t) for t in line.split()[:3])
        out.append("%r %r %r" % (x * scale + offset[0], y * scale + offset[1], z * scale + offset[2]))
    out += lines[2 + vertices:]
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default="/work/bench-data")
    parser.add_argument("--toposimp", default=TOPOSIMP)
    parser.add_argument("--timeout", type=float, default=600)
    args = parser.parse_args()
    source = cgal_model(args.data, "refined_elephant")
    folder = os.path.join(args.data, "frames")
    os.makedirs(folder, exist_ok=True)
    cases = [("as given", 1.0, (0, 0, 0)), ("moved by (5e5, 4e6, 100)", 1.0, (5e5, 4e6, 100.0)),
             ("scaled by 1e100", 1e100, (0, 0, 0)), ("scaled by 1e150", 1e150, (0, 0, 0)),
             ("scaled by 1e-100", 1e-100, (0, 0, 0)), ("scaled by 1e-150", 1e-150, (0, 0, 0))]
    print("Elephant (88 928 faces) to 10 %, 2 threads, one run each.\n")
    print("| input | simplify s | Hausdorff (% diag) | largest quadric error / scale | GMP fallbacks |")
    print("|---|---|---|---|---|")
    for name, scale, offset in cases:
        path = source if scale == 1.0 and offset == (0, 0, 0) else transformed(
            source, os.path.join(folder, "elephant-%g-%g.off" % (scale, offset[1])), scale, offset)
        command = [args.toposimp, "mesh", path, "-o", os.path.join(folder, "out.off"), "--overwrite", "--keep", "10%",
                   "-j", "2", "--json", "-q"]
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=args.timeout, check=True)
        except subprocess.TimeoutExpired:
            print("| %s | over %g s | | | |" % (name, args.timeout))
            continue
        d = json.loads(result.stdout)
        print("| %s | %.3f | %.5f | %.6g | %d |" % (name, d["seconds"]["simplify"], 100 * d["hausdorff"]["max_fraction_of_diagonal"],
                                                d["max_quadric_error"] / scale, d["predicates"]["gmp_fallbacks"]))


if __name__ == "__main__":
    main()
