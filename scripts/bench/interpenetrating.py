#!/usr/bin/python3
"""Meshes whose parts already cross each other (issue 33): two icospheres of 20 480 faces each,
the second shifted into the first, simplified to --keep (default 10% and 1%) with the Python
package of a build (default build/release/python), against one sphere alone. Prints faces
reached, refusals, the full sampled Hausdorff distance (fraction of the diagonal) and time.

    scripts/bench/interpenetrating.py [--build build/release] [--keep 0.1,0.01]
"""
import argparse
import os
import sys
import time
import warnings

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def icosphere(level, center):
    t = (1 + 5 ** 0.5) / 2
    points = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
              (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
             (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7),
             (9, 8, 1)]
    points = [numpy.array(p, float) / numpy.linalg.norm(p) for p in points]
    for _ in range(level):
        middle = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = points[a] + points[b]
                points.append(m / numpy.linalg.norm(m))
                middle[key] = len(points) - 1
            return middle[key]
        finer = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = finer
    return numpy.array(points) + center, numpy.array(faces)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--keep", default="0.1,0.01")
    args = parser.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import toposimp
    warnings.simplefilter("ignore", toposimp.ToposimpWarning)
    first, first_faces = icosphere(5, numpy.array([0.0, 0.0, 0.0]))
    second, second_faces = icosphere(5, numpy.array([0.9, 0.3, 0.1]))
    both = (numpy.vstack([first, second]), numpy.vstack([first_faces, second_faces + len(first)]))
    print("| input | keep | faces asked | faces reached | refused (intersection) | Hausdorff (full) / diagonal | seconds |")
    print("|---|---|---|---|---|---|---|")
    for keep in (float(k) for k in args.keep.split(",")):
        for name, (points, faces) in (("one sphere", (first, first_faces)), ("two interpenetrating spheres", both)):
            start = time.perf_counter()
            out = toposimp.simplify_mesh(points, faces, keep=keep, measure="full")
            seconds = time.perf_counter() - start
            report = out.report
            print(f"| {name} | {keep:g} | {report['target']['target_faces']} | {len(out.faces)} | "
                  f"{report['refused']['total']} ({report['refused']['intersection']}) | "
                  f"{report['hausdorff']['max_fraction_of_diagonal']:.2%} | {seconds:.2f} |")


if __name__ == "__main__":
    main()
