#!/usr/bin/env bash
# The first README command: installs the dependencies, builds in Release, and simplifies the
# sample in testdata/ (New Hampshire county borders and 26 places, one GeoPackage) to 10% of its vertices.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh release
mkdir -p out
echo
echo "demo: toposimp map testdata/nh_borders.gpkg --keep 10% -o out/nh_borders_10pct.gpkg"
echo "      (layer 'borders' is simplified; layer 'places' is copied and its points stay on their side)"
build/release/toposimp map testdata/nh_borders.gpkg --keep 10% -o out/nh_borders_10pct.gpkg --overwrite --json -v
echo
echo "demo: wrote out/nh_borders_10pct.gpkg:"
ogrinfo -so -al out/nh_borders_10pct.gpkg | grep -E 'Layer name|Geometry:|Feature Count'
echo
echo "demo: toposimp mesh testdata/mesh/torus.off --keep 10% -o out/torus_10pct.ply"
build/release/toposimp mesh testdata/mesh/torus.off --keep 10% -o out/torus_10pct.ply --overwrite --json -v
