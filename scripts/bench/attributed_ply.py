#!/usr/bin/env python3
"""Writes a mesh (OFF) as binary PLY twice: with per-vertex normals, colours and texture
coordinates (all derived from the geometry), and without. For measuring what carrying
attributes through `toposimp mesh` costs (BENCHMARKS.md, "Vertex attributes").

usage: attributed_ply.py IN.off OUT_WITH.ply OUT_WITHOUT.ply
"""
import math
import struct
import sys


def read_off(path):
    words = []
    with open(path) as f:
        for line in f:
            words.extend(line.split("#", 1)[0].split())
    if not words or not words[0].endswith("OFF"):
        sys.exit(f"{path}: not an OFF file")
    nv, nf = int(words[1]), int(words[2])
    at = 4
    points = []
    for _ in range(nv):
        points.append(tuple(float(w) for w in words[at:at + 3]))
        at += 3
    faces = []
    for _ in range(nf):
        n = int(words[at])
        if n != 3:
            sys.exit(f"{path}: a face with {n} corners")
        faces.append(tuple(int(w) for w in words[at + 1:at + 4]))
        at += 1 + n
    return points, faces


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    points, faces = read_off(sys.argv[1])
    normals = [[0.0, 0.0, 0.0] for _ in points]
    for a, b, c in faces:  # area-weighted face normals
        u = [points[b][k] - points[a][k] for k in range(3)]
        v = [points[c][k] - points[a][k] for k in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        for w in (a, b, c):
            for k in range(3):
                normals[w][k] += n[k]
    lo = [min(p[k] for p in points) for k in range(3)]
    span = [max(p[k] for p in points) - lo[k] or 1.0 for k in range(3)]
    face_records = b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    header = "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
    with open(sys.argv[2], "wb") as out:
        out.write((header % len(points) + "property float nx\nproperty float ny\nproperty float nz\n"
                   "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float u\nproperty float v\n"
                   "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces)).encode())
        for p, n in zip(points, normals):
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            t = [(p[k] - lo[k]) / span[k] for k in range(3)]
            out.write(struct.pack("<6f3B2f", *p, *(x / length for x in n), *(int(255 * x) for x in t), t[0], t[1]))
        out.write(face_records)
    with open(sys.argv[3], "wb") as out:
        out.write((header % len(points) + "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces)).encode())
        for p in points:
            out.write(struct.pack("<3f", *p))
        out.write(face_records)


if __name__ == "__main__":
    main()
