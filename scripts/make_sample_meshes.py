#!/usr/bin/env python3
"""Writes the sample meshes in testdata/mesh/ (deterministic; no dependencies).

torus.off   a torus with bumps (closed, genus 1): 4 800 triangles
hills.obj   a 64 x 64 terrain grid, z = height in metres, 1 m cells: 8 192 triangles
"""
import math
import os

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "testdata", "mesh")


def torus(path, n=60, m=40, big=3.0, small=1.0):
    points, faces = [], []
    for i in range(n):
        u = 2 * math.pi * i / n
        for j in range(m):
            v = 2 * math.pi * j / m
            r = small * (1 + 0.08 * math.sin(5 * u) * math.cos(3 * v))
            points.append(((big + r * math.cos(v)) * math.cos(u), (big + r * math.cos(v)) * math.sin(u), r * math.sin(v)))
    for i in range(n):
        for j in range(m):
            a, b = i * m + j, ((i + 1) % n) * m + j
            c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
            faces += [(a, b, c), (a, c, d)]
    with open(path, "w") as out:
        out.write("OFF\n# a bumpy torus, written by scripts/make_sample_meshes.py\n")
        out.write(f"{len(points)} {len(faces)} 0\n")
        for p in points:
            out.write(" ".join(repr(round(c, 6)) for c in p) + "\n")
        for f in faces:
            out.write("3 %d %d %d\n" % f)


def hills(path, n=64):
    with open(path, "w") as out:
        out.write("# a synthetic terrain, written by scripts/make_sample_meshes.py\n")
        for j in range(n + 1):
            for i in range(n + 1):
                z = 20 * math.sin(i * 0.11) * math.cos(j * 0.07) + 6 * math.sin(i * 0.5 + j * 0.3) + 0.5 * math.sin(i * j)
                out.write(f"v {i} {j} {round(z, 3)!r}\n")
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                b, c, d = a + 1, a + n + 2, a + n + 1
                out.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")


if __name__ == "__main__":
    os.makedirs(HERE, exist_ok=True)
    torus(os.path.join(HERE, "torus.off"))
    hills(os.path.join(HERE, "hills.obj"))
