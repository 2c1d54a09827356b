#!/usr/bin/env python3
"""Mesh benchmark: toposimp mesh (1 thread and all threads) against meshoptimizer
(meshopt_simplify, with and without LockBorder) and CGAL (Surface_mesh_simplification,
Garland-Heckbert plane policies), same inputs and face targets, one run each.

For every output: wall time and peak RSS (/usr/bin/time -v), the simplification call's own
time, the sampled Hausdorff distance to the input, and the defects the tests' independent
brute-force checker finds (tests/tools/mesh_defects: intersecting face pairs beyond shared
corners, non-manifold edges, map-plane folds for terrains). Prints a Markdown table.

Usage: scripts/bench/mesh.py [--data DIR] [--datasets a,b,...] [--keep 0.1]
Needs: build/release (scripts/build.sh release) and the packages scripts/bench/fetch-data.sh
installs (libmeshoptimizer-dev, libcgal-dev, libcgal-demo for the models, libeigen3-dev);
builds the peers in build/peers. Terrains are generated into --data.
"""
import argparse
import json
import math
import os
import random
import re
import struct
import subprocess
import sys
import tarfile
import zipfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOPOSIMP = os.path.join(ROOT, "build", "release", "toposimp")
DEFECTS = os.path.join(ROOT, "build", "release", "tests", "mesh_defects")
PEERS = os.path.join(ROOT, "build", "peers")


def terrain(path, n, seed=1):
    """An n x n grid terrain (2 n^2 triangles), 10 m cells, hills plus noise, binary PLY."""
    if os.path.exists(path):
        return
    rng = random.Random(seed)
    with open(path, "wb") as out:
        v, f = (n + 1) ** 2, 2 * n * n
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {v}\nproperty double x\nproperty double y\n"
                   f"property double z\nelement face {f}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        buf = bytearray()
        for j in range(n + 1):
            for i in range(n + 1):
                z = 40 * math.sin(i * 0.013) * math.cos(j * 0.011) + 8 * math.sin(i * 0.07 + j * 0.05) + rng.uniform(-0.5, 0.5)
                buf += struct.pack("<ddd", i * 10.0, j * 10.0, z)
        out.write(buf)
        buf = bytearray()
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i
                buf += struct.pack("<Biii", 3, a, a + 1, a + n + 2) + struct.pack("<Biii", 3, a, a + n + 2, a + n + 1)
        out.write(buf)


def npy(data):
    """A little-endian array from a NumPy .npy file (format 1): (values, shape)."""
    size = struct.unpack("<H", data[8:10])[0]
    header = data[10:10 + size].decode("latin-1")
    descr = re.search(r"'descr': '<(\w\d)'", header).group(1)
    shape = tuple(int(x) for x in re.search(r"'shape': \(([^)]*)\)", header).group(1).split(",") if x.strip())
    code = {"i2": "h", "f8": "d", "f4": "f", "i4": "i"}[descr]
    count = 1
    for n in shape:
        count *= n
    return struct.unpack(f"<{count}{code}", data[10 + size:10 + size + count * struct.calcsize(code)]), shape


def dem(data):
    """The real DEM of ../shared/data/README.md (Debian python-matplotlib-data: Jacksboro fault,
    403 x 344 cells of 3 arc-seconds, heights in metres), written as an ESRI ASCII grid in local
    metres (cells about 75 x 93 m), then triangulated by toposimp's own DEM reader into a binary
    PLY (--keep 100%: no collapse) that every tool reads."""
    path = os.path.join(data, "jacksboro.ply")
    if os.path.exists(path):
        return path
    source = "/usr/share/matplotlib/mpl-data/sample_data/jacksboro_fault_dem.npz"
    with zipfile.ZipFile(source) as archive:
        heights, (rows, cols) = npy(archive.read("elevation.npy"))
        lat = npy(archive.read("ymin.npy"))[0][0]
        dx, dy = npy(archive.read("dx.npy"))[0][0], npy(archive.read("dy.npy"))[0][0]
    metres_x, metres_y = dx * 111320.0 * math.cos(math.radians(lat)), dy * 110574.0
    grid = os.path.join(data, "jacksboro.asc")
    with open(grid, "w") as out:
        out.write(f"ncols {cols}\nnrows {rows}\nxllcorner 0\nyllcorner 0\ndx {metres_x!r}\ndy {metres_y!r}\n")
        for r in range(rows):
            out.write(" ".join(str(h) for h in heights[r * cols:(r + 1) * cols]) + "\n")
    subprocess.run([TOPOSIMP, "mesh", grid, "-o", path, "--keep", "100%", "--no-hausdorff", "-q"], check=True)
    return path


def cgal_model(data, name):
    folder = os.path.join(data, "cgal")
    path = os.path.join(folder, "data", "meshes", name + ".off")
    if not os.path.exists(path):
        with tarfile.open("/usr/share/doc/libcgal-dev/data.tar.gz") as archive:
            archive.extractall(folder)
    return path


def timed(command):
    result = subprocess.run(["/usr/bin/time", "-v"] + command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(" ".join(command) + " failed:\n" + result.stderr[-2000:])
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", result.stderr).group(1)
    parts = [float(p) for p in wall.split(":")]
    seconds = parts[-1] + 60 * parts[-2] + (3600 * parts[-3] if len(parts) > 2 else 0)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", result.stderr).group(1))
    return seconds, rss / 1024.0, result.stdout


def faces_of(path):
    with open(path, "rb") as f:
        head = f.read(4096).decode("latin-1")
    m = re.search(r"element face (\d+)", head)
    if m:
        return int(m.group(1))
    m = re.search(r"OFF\s+(?:#.*\n\s*)*\d+\s+(\d+)", head)
    return int(m.group(1))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--data", default="/work/bench-data")
    parser.add_argument("--datasets", default="elephant,armadillo,bunny,fandisk,jacksboro,terrain-0.9M,terrain-2M,terrain-4M")
    parser.add_argument("--keep", type=float, default=0.1)
    args = parser.parse_args()
    os.makedirs(args.data, exist_ok=True)
    subprocess.run(["cmake", "-S", os.path.join(ROOT, "scripts", "bench", "mesh_peers"), "-B", PEERS, "-G", "Ninja"],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", PEERS], check=True, stdout=subprocess.DEVNULL)
    sources = {
        "elephant": lambda: cgal_model(args.data, "refined_elephant"),
        "armadillo": lambda: cgal_model(args.data, "armadillo"),
        "bunny": lambda: cgal_model(args.data, "bunny00"),
        "fandisk": lambda: cgal_model(args.data, "fandisk_large"),
        "jacksboro": lambda: dem(args.data),
    }
    for name, n in (("terrain-0.9M", 671), ("terrain-2M", 1000), ("terrain-4M", 1414)):
        sources[name] = (lambda n=n, name=name: (terrain(os.path.join(args.data, name + ".ply"), n),
                                                 os.path.join(args.data, name + ".ply"))[1])
    out_dir = os.path.join(args.data, "mesh-out")
    os.makedirs(out_dir, exist_ok=True)
    threads = os.cpu_count()
    rows = []
    for name in args.datasets.split(","):
        source = sources[name]()
        is_terrain = name.startswith("terrain") or name == "jacksboro"
        faces = faces_of(source)
        target = round(args.keep * faces)
        runs = []
        lock = ["--terrain", "--lock-boundary"] if is_terrain else []
        for j in (1, threads):
            out = os.path.join(out_dir, f"{name}-toposimp-{j}.ply")
            wall, rss, text = timed([TOPOSIMP, "mesh", source, "-o", out, "--overwrite", "--keep-faces", str(target), "-j", str(j),
                                     "--no-hausdorff", "--json"] + lock)
            runs.append((f"toposimp {j} thr" + (" (terrain, locked border)" if is_terrain else ""), out, wall, rss,
                         json.loads(text)["seconds"]["simplify"]))
        for flag in ([], ["--lock-border"]):
            out = os.path.join(out_dir, f"{name}-meshopt{''.join(flag)}.ply")
            wall, rss, text = timed([os.path.join(PEERS, "meshopt_simplify"), source, out, str(target)] + flag)
            runs.append(("meshoptimizer 0.18" + (" LockBorder" if flag else ""), out, wall, rss, json.loads(text)["simplify_seconds"]))
        out = os.path.join(out_dir, f"{name}-cgal.ply")
        wall, rss, text = timed([os.path.join(PEERS, "cgal_simplify"), source, out, str(target)])
        runs.append(("CGAL 5.5 GH", out, wall, rss, json.loads(text)["simplify_seconds"]))
        for label, out, wall, rss, simplify in runs:
            check = [DEFECTS, out, "--against", source] + (["--terrain"] if is_terrain else [])
            try:
                found = json.loads(subprocess.run(check, capture_output=True, text=True, timeout=900, check=True).stdout)
            except subprocess.TimeoutExpired:
                found = {}
            rows.append((name, faces, label, found.get("faces", "?"), wall, simplify, rss, found))
            print(f"{name} {label}: {wall:.2f} s, simplify {simplify:.3f} s, {rss:.0f} MiB, {found}", file=sys.stderr)
    print(f"Target: {args.keep:.0%} of the faces. Machine: {os.cpu_count()} cores. One run each.\n")
    print("| input (faces) | tool | faces out | wall s | simplify s | peak MiB | Hausdorff (% diag) | mean dist | intersecting pairs | non-manifold edges | map-plane folds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, faces, label, out_faces, wall, simplify, rss, d in rows:
        h = f"{100 * d['hausdorff_fraction']:.3f}" if "hausdorff_fraction" in d else "?"
        mean = f"{d['mean_distance']:.4g}" if "mean_distance" in d else "?"
        folds = d.get("map_plane_folds", "–")
        print(f"| {name} ({faces}) | {label} | {out_faces} | {wall:.2f} | {simplify:.3f} | {rss:.0f} | {h} | {mean} | "
              f"{d.get('intersecting_pairs', '?')} | {d.get('non_manifold_edges', '?')} | {folds} |")


if __name__ == "__main__":
    main()
