#!/usr/bin/python3
"""What toposimp mesh's distance measurement costs against its simplification, on the mesh
benchmark's datasets (as scripts/bench/mesh.py makes them): the default quick measure (one point
of each surface per 40 input faces, 1 024 to 8 192, spread by area) and --measure full, with the
largest distances each finds.

    scripts/bench/measure_cost.py [--data build/bench-data] [--datasets a,b,...] [--keep 10%]

Terrains (terrain-*, jacksboro) run with --terrain --lock-boundary; the rest as generic meshes.
Prints a Markdown table.
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mesh  # noqa: E402  (its dataset makers)

DATASETS = "elephant,armadillo,bunny,fandisk,jacksboro,terrain-0.9M,terrain-2M,armadillo-832k,elephant-1.4M"


def run(source, out, measure, terrain, keep):
    command = [mesh.TOPOSIMP, "mesh", source, "-o", out, "--overwrite", "--keep", keep, "--json", "--measure", measure]
    if terrain:
        command += ["--terrain", "--lock-boundary"]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", default=os.path.join(mesh.ROOT, "build", "bench-data"))
    parser.add_argument("--datasets", default=DATASETS)
    parser.add_argument("--keep", default="10%")
    args = parser.parse_args()
    sources = {
        "elephant": lambda: mesh.cgal_model(args.data, "refined_elephant"),
        "armadillo": lambda: mesh.cgal_model(args.data, "armadillo"),
        "bunny": lambda: mesh.cgal_model(args.data, "bunny00"),
        "fandisk": lambda: mesh.cgal_model(args.data, "fandisk_large"),
        "jacksboro": lambda: mesh.dem(args.data),
        "armadillo-832k": lambda: mesh.subdivided(mesh.cgal_model(args.data, "armadillo"),
                                                  os.path.join(args.data, "armadillo-832k.ply"), 2),
        "elephant-1.4M": lambda: mesh.subdivided(mesh.cgal_model(args.data, "refined_elephant"),
                                                 os.path.join(args.data, "elephant-1.4M.ply"), 2),
    }
    for name, n in (("terrain-0.9M", 671), ("terrain-2M", 1000), ("terrain-4M", 1414)):
        path = os.path.join(args.data, name + ".ply")
        sources[name] = (lambda n=n, path=path: (mesh.terrain(path, n), path)[1])
    out = os.path.join(args.data, "measure-cost.ply")
    print(f"| input | faces | mode | simplify s | quick measure s | quick / simplify | quick: Hausdorff ≥ | full measure s | "
          f"full: Hausdorff ≥ | vertical error (quick / full) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in args.datasets.split(","):
        source = sources[name]()
        terrain = name.startswith("terrain") or name == "jacksboro"
        quick = run(source, out, "quick", terrain, args.keep)
        full = run(source, out, "full", terrain, args.keep)
        vertical = ""
        if "vertical_error" in quick:
            vertical = f"{quick['vertical_error']['max']:.6g} / {full['vertical_error']['max']:.6g}"
        simplify = quick["seconds"]["simplify"]
        print(f"| {name} | {quick['faces_in']} | {'terrain' if quick['terrain'] else 'generic'} | {simplify:.3f} | "
              f"{quick['seconds']['hausdorff']:.3f} | {quick['seconds']['hausdorff'] / simplify:.1%} | "
              f"{quick['hausdorff']['max']:.6g} | {full['seconds']['hausdorff']:.3f} | {full['hausdorff']['max']:.6g} | {vertical} |")
    os.remove(out)


if __name__ == "__main__":
    main()
