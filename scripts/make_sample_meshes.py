#!/usr/bin/env python3
"""Writes the sample meshes in testdata/mesh/ (deterministic; no dependencies).

torus.off   a torus with bumps (closed, genus 1): 4 800 triangles
hills.obj   a 64 x 64 terrain grid, z = height in metres, 1 m cells: 8 192 triangles
bridge-deck.obj
            a noisy 24 x 24 grid with a 6 x 6 deck 0.01 above the highest ground under it:
            not a height field (the deck overlaps the ground in x-y), 1 224 triangles
"""
import math
import os
import random

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


def bridge_deck(path, n=24, m=6, seed=4):
    rng = random.Random(seed)
    points, faces = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            points.append((i, j, 0.5 * math.sin(i * 0.9) * math.cos(j * 0.7) + rng.uniform(-0.3, 0.3)))
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            faces += [(a, b, c), (a, c, d)]
    first, x0 = len(points), 9.25
    top = max(p[2] for p in points if x0 - 0.5 <= p[0] <= x0 + m + 0.5 and x0 - 0.5 <= p[1] <= x0 + m + 0.5)
    for j in range(m + 1):
        for i in range(m + 1):
            points.append((x0 + i, x0 + j, top + 0.01))
    for j in range(m):
        for i in range(m):
            a, b = first + j * (m + 1) + i, first + j * (m + 1) + i + 1
            c, d = first + (j + 1) * (m + 1) + i + 1, first + (j + 1) * (m + 1) + i
            faces += [(a, b, c), (a, c, d)]
    with open(path, "w") as out:
        out.write("# a terrain with a bridge deck over it (not a height field), written by scripts/make_sample_meshes.py\n")
        for p in points:
            out.write("v %r %r %r\n" % p)
        for f in faces:
            out.write("f %d %d %d\n" % (f[0] + 1, f[1] + 1, f[2] + 1))


if __name__ == "__main__":
    os.makedirs(HERE, exist_ok=True)
    torus(os.path.join(HERE, "torus.off"))
    hills(os.path.join(HERE, "hills.obj"))
    bridge_deck(os.path.join(HERE, "bridge-deck.obj"))
