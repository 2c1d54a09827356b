#!/usr/bin/python3
"""Draws the README's picture of nested levels: Natural Earth's states and provinces around the
Aegean, simplified by one `toposimp map --levels 50%,25%,13% --decimals 2` run (the whole world),
each level drawn from the real output. Needs matplotlib (Debian python3-matplotlib) and the
Natural Earth data of scripts/bench/same_outputs.py.

    scripts/draw_levels.py [--build build/release] [--data build/bench-data] [-o docs/levels.png]"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "bench"))
import same_outputs  # noqa: E402  (the Natural Earth data maker)
import topojson_client  # noqa: E402  (a GeoPackage reader)

WINDOW = (19.0, 34.5, 29.5, 42.0)  # lon, lat: the Aegean


def rings(geometry):
    if geometry is None:
        return []
    if geometry["type"] == "Polygon":
        return geometry["coordinates"]
    if geometry["type"] == "MultiPolygon":
        return [ring for polygon in geometry["coordinates"] for ring in polygon]
    return []


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--data", default=os.path.join(ROOT, "build", "bench-data"))
    parser.add_argument("-o", "--output", default=os.path.join(ROOT, "docs", "levels.png"))
    args = parser.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    states, _ = same_outputs.ne_data(args.data)
    levels = ["50%", "25%", "13%"]
    names = ["50pct", "25pct", "13pct"]
    with tempfile.TemporaryDirectory() as out:
        pattern = os.path.join(out, "states_{level}.gpkg")
        subprocess.run([os.path.join(args.build, "toposimp"), "map", states, "--levels", ",".join(levels),
                        "--decimals", "2", "-o", pattern, "-q"], check=True)
        layer = [row for row in subprocess.run(["ogrinfo", "-q", states], capture_output=True, text=True).stdout.split("\n")
                 if row.strip()][0].split(":")[1].split("(")[0].strip()
        drawn = [(f"input: {sum(len(r) for f in topojson_client.gpkg_features(states, layer) for r in rings(f[1]))} vertices",
                  topojson_client.gpkg_features(states, layer))]
        for level, name in zip(levels, names):
            features = topojson_client.gpkg_features(pattern.replace("{level}", name), layer)
            count = sum(len(r) for f in features for r in rings(f[1]))
            drawn.append((f"level {level} at 2 decimals: {count} vertices", features))
        x0, y0, x1, y1 = WINDOW
        figure, axes = plt.subplots(2, 2, figsize=(11, 9.5))
        for axis, (title, features) in zip(axes.flat, drawn):
            for _, geometry in features:
                for ring in rings(geometry):
                    xs, ys = zip(*ring)
                    if max(xs) < x0 or min(xs) > x1 or max(ys) < y0 or min(ys) > y1:
                        continue
                    axis.plot(xs, ys, color="#1f4e79", linewidth=0.6)
            axis.set_xlim(x0, x1)
            axis.set_ylim(y0, y1)
            axis.set_aspect(1 / 0.78)  # about 1/cos(38.5°)
            axis.set_title(title, fontsize=10)
            axis.tick_params(labelsize=7)
        figure.suptitle("Natural Earth states and provinces around the Aegean: one run, "
                        "toposimp map --levels 50%,25%,13% --decimals 2 (vertex counts: the whole world)", fontsize=10)
        figure.tight_layout()
        os.makedirs(os.path.dirname(args.output), exist_ok=True)
        figure.savefig(args.output, dpi=90)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
