#!/usr/bin/env python3
"""Mesh benchmark: toposimp mesh (1 thread and all threads) against meshoptimizer
(meshopt_simplify, with and without LockBorder) and CGAL (Surface_mesh_simplification,
Garland-Heckbert plane policies), same inputs and face targets, one run each (or the medians of
--runs alternating runs).

toposimp runs as a user runs it: no flags but the face target and the thread count, so height
fields are found and simplified as terrains, and the default quick distance measure runs (its
time is a column of its own). On the terrains it also runs in space (--no-terrain), the generic
path.

For every output: wall time and peak RSS (/usr/bin/time -v), the simplification call's own
time, toposimp's measurement time, the sampled Hausdorff distance to the input, and the defects
the tests' independent brute-force checker finds (tests/tools/mesh_defects: intersecting face
pairs beyond shared corners, non-manifold edges, map-plane folds for terrains simplified as
terrains). Prints a Markdown table.

Usage: scripts/bench/mesh.py [--data DIR] [--datasets a,b,...] [--keep 0.1] [--runs N]
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
import statistics
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


def read_off(path):
    """Vertices and triangles of a plain OFF file (the CGAL demo models)."""
    with open(path) as f:
        words = [w for line in f for w in line.split("#", 1)[0].split()]
    assert words[0] == "OFF", path
    nv, nf = int(words[1]), int(words[2])
    at = 4
    points = [tuple(float(w) for w in words[at + 3 * i:at + 3 * i + 3]) for i in range(nv)]
    at += 3 * nv
    faces = []
    for _ in range(nf):
        k = int(words[at])
        assert k == 3, path + ": a face with " + str(k) + " corners"
        faces.append((int(words[at + 1]), int(words[at + 2]), int(words[at + 3])))
        at += 4
    return points, faces


def loop_step(points, faces):
    """One step of Loop subdivision (Loop 1987): every triangle into four, new edge points at
    3/8 (ends) + 1/8 (opposite corners), old points moved by Loop's weights (β from his thesis); border edges and
    points (and edges with more than two faces) follow the border curve's rules."""
    opposite = {}  # (lower, higher) -> corners opposite the edge
    for a, b, c in faces:
        for u, w, o in ((a, b, c), (b, c, a), (c, a, b)):
            opposite.setdefault((min(u, w), max(u, w)), []).append(o)
    index, new_points = {}, list(points)
    for (u, w), opp in opposite.items():
        pu, pw = points[u], points[w]
        if len(opp) == 2:
            po, pq = points[opp[0]], points[opp[1]]
            q = tuple(0.375 * (pu[i] + pw[i]) + 0.125 * (po[i] + pq[i]) for i in range(3))
        else:
            q = tuple(0.5 * (pu[i] + pw[i]) for i in range(3))
        index[(u, w)] = len(new_points)
        new_points.append(q)
    neighbours = [set() for _ in points]
    border = [[] for _ in points]
    for (u, w), opp in opposite.items():
        neighbours[u].add(w)
        neighbours[w].add(u)
        if len(opp) != 2:
            border[u].append(w)
            border[w].append(u)
    for v, p in enumerate(points):
        if border[v]:
            if len(border[v]) == 2:
                x, y = points[border[v][0]], points[border[v][1]]
                new_points[v] = tuple(0.75 * p[i] + 0.125 * (x[i] + y[i]) for i in range(3))
            continue  # (a corner of several border curves stays)
        n = len(neighbours[v])
        if n < 3:
            continue
        beta = (0.625 - (0.375 + 0.25 * math.cos(2 * math.pi / n)) ** 2) / n
        s = [sum(points[w][i] for w in neighbours[v]) for i in range(3)]
        new_points[v] = tuple((1 - n * beta) * p[i] + beta * s[i] for i in range(3))
    new_faces = []
    for a, b, c in faces:
        ab, bc, ca = index[(min(a, b), max(a, b))], index[(min(b, c), max(b, c))], index[(min(c, a), max(c, a))]
        new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    return new_points, new_faces


def subdivided(source, path, steps):
    """A CGAL demo model after `steps` Loop subdivision steps (4^steps times the faces), binary
    PLY: a smooth scan-sized model from a small one."""
    if os.path.exists(path):
        return path
    points, faces = read_off(source)
    for _ in range(steps):
        points, faces = loop_step(points, faces)
    with open(path + ".part", "wb") as out:
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\nproperty double x\n"
                   f"property double y\nproperty double z\nelement face {len(faces)}\n"
                   f"property list uchar int vertex_indices\nend_header\n").encode())
        out.write(b"".join(struct.pack("<ddd", *p) for p in points))
        out.write(b"".join(struct.pack("<Biii", 3, *f) for f in faces))
    os.replace(path + ".part", path)
    return path


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
    """A real DEM (Debian python-matplotlib-data: Jacksboro fault,
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
    parser.add_argument("--datasets", default="elephant,armadillo,bunny,fandisk,jacksboro,terrain-0.9M,terrain-2M,terrain-4M,"
                                              "armadillo-832k,elephant-1.4M")
    parser.add_argument("--keep", type=float, default=0.1)
    parser.add_argument("--runs", type=int, default=1, help="runs per tool (alternating); times are their medians")
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
        # Scan-sized models: two Loop subdivision steps of the small ones.
        "armadillo-832k": lambda: subdivided(cgal_model(args.data, "armadillo"), os.path.join(args.data, "armadillo-832k.ply"), 2),
        "elephant-1.4M": lambda: subdivided(cgal_model(args.data, "refined_elephant"), os.path.join(args.data, "elephant-1.4M.ply"), 2),
    }
    for name, n in (("terrain-0.9M", 671), ("terrain-2M", 1000), ("terrain-4M", 1414)):
        sources[name] = (lambda n=n, name=name: (terrain(os.path.join(args.data, name + ".ply"), n),
                                                 os.path.join(args.data, name + ".ply"))[1])
    out_dir = os.path.join(args.data, "mesh-out")
    os.makedirs(out_dir, exist_ok=True)
    threads = os.cpu_count()
    rows, ratios = [], []
    for name in args.datasets.split(","):
        source = sources[name]()
        is_terrain = name.startswith("terrain") or name == "jacksboro"
        faces = faces_of(source)
        target = round(args.keep * faces)
        # (label, command, output, (simplification, measurement) times from its output, check as
        # a terrain). toposimp's label says the mode it chose (its JSON's terrain_mode).
        jobs = []

        def toposimp_times(text):
            summary = json.loads(text)
            return summary["seconds"]["simplify"], summary["seconds"]["hausdorff"], summary["terrain"]

        for j in sorted({1, threads}):
            out = os.path.join(out_dir, f"{name}-toposimp-{j}.ply")
            jobs.append((f"toposimp {j} thr", [TOPOSIMP, "mesh", source, "-o", out, "--overwrite", "--keep-faces", str(target),
                                                "-j", str(j), "--json"], out, toposimp_times))
        if is_terrain:
            out = os.path.join(out_dir, f"{name}-toposimp-space.ply")
            jobs.append((f"toposimp {threads} thr --no-terrain", [TOPOSIMP, "mesh", source, "-o", out, "--overwrite", "--keep-faces",
                                                                   str(target), "-j", str(threads), "--no-terrain", "--json"],
                         out, toposimp_times))
        for flag in ([], ["--lock-border"]):
            out = os.path.join(out_dir, f"{name}-meshopt{''.join(flag)}.ply")
            jobs.append(("meshoptimizer 0.18" + (" LockBorder" if flag else ""),
                         [os.path.join(PEERS, "meshopt_simplify"), source, out, str(target)] + flag, out,
                         lambda text: (json.loads(text)["simplify_seconds"], None, None)))
        out = os.path.join(out_dir, f"{name}-cgal.ply")
        jobs.append(("CGAL 5.5 GH", [os.path.join(PEERS, "cgal_simplify"), source, out, str(target)], out,
                     lambda text: (json.loads(text)["simplify_seconds"], None, None)))
        # Alternating runs (every tool once, then again): the machine's slow and fast minutes fall
        # on all of them alike. Medians of the times, the largest peak memory.
        times = {label: [] for label, _, _, _ in jobs}
        for _ in range(args.runs):
            for label, command, out, times_of in jobs:
                wall, rss, text = timed(command)
                times[label].append((wall, rss) + times_of(text))
        walls, simplifies = {}, {}
        for label, command, out, times_of in jobs:
            runs_here = times[label]
            wall = statistics.median(t[0] for t in runs_here)
            rss = max(t[1] for t in runs_here)
            simplify = statistics.median(t[2] for t in runs_here)
            measure = statistics.median(t[3] for t in runs_here) if runs_here[0][3] is not None else None
            as_terrain = runs_here[0][4]
            if as_terrain is not None:
                label += " (terrain)" if as_terrain else " (in space)"
            walls[label], simplifies[label] = wall, simplify
            # Map-plane folds only where the output was simplified as a terrain (the peers make no
            # such promise; they are counted on terrain inputs all the same).
            fold_check = is_terrain and as_terrain is not False
            check = [DEFECTS, out, "--against", source] + (["--terrain"] if fold_check else [])
            try:
                found = json.loads(subprocess.run(check, capture_output=True, text=True, timeout=900, check=True).stdout)
            except subprocess.TimeoutExpired:
                found = {}
            rows.append((name, faces, label, found.get("faces", "?"), wall, simplify, measure, rss, found))
            print(f"{name} {label}: {wall:.2f} s, simplify {simplify:.3f} s, measure {measure}, {rss:.0f} MiB, {found}", file=sys.stderr)
        ours = next(label for label in walls if label.startswith(f"toposimp {threads} thr") and "--no-terrain" not in label)
        line = (f"{name}: wall time, CGAL's / toposimp {threads} thr's {walls['CGAL 5.5 GH'] / walls[ours]:.2f}, "
                f"meshoptimizer's / toposimp {threads} thr's {walls['meshoptimizer 0.18'] / walls[ours]:.2f}")
        generic = next((label for label in walls if label.startswith(f"toposimp {threads} thr") and label.endswith("(in space)")), None)
        if generic:
            line += (f"; simplification in space, toposimp {threads} thr / meshoptimizer (1 thread): "
                     f"{simplifies[generic] / simplifies['meshoptimizer 0.18']:.2f}")
        ratios.append(line)
    runs = "One run each" if args.runs == 1 else f"Median of {args.runs} alternating runs each"
    print(f"Target: {args.keep:.0%} of the faces. Machine: {os.cpu_count()} cores. {runs}.\n")
    print("| input (faces) | tool | faces out | wall s | simplify s | measure s (% of simplify) | peak MiB | Hausdorff (% diag) | "
          "mean dist | intersecting pairs | non-manifold edges | map-plane folds |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, faces, label, out_faces, wall, simplify, measure, rss, d in rows:
        h = f"{100 * d['hausdorff_fraction']:.3f}" if "hausdorff_fraction" in d else "?"
        mean = f"{d['mean_distance']:.4g}" if "mean_distance" in d else "?"
        folds = d.get("map_plane_folds", "–")
        measured = "–" if measure is None else f"{measure:.3f} ({100 * measure / simplify:.1f} %)"
        print(f"| {name} ({faces}) | {label} | {out_faces} | {wall:.2f} | {simplify:.3f} | {measured} | {rss:.0f} | {h} | {mean} | "
              f"{d.get('intersecting_pairs', '?')} | {d.get('non_manifold_edges', '?')} | {folds} |")
    print()
    for line in ratios:
        print(f"- {line}")


if __name__ == "__main__":
    main()
