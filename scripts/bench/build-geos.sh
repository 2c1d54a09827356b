#!/usr/bin/env bash
# Builds GEOS (≥ 3.12, for its CoverageSimplifier; Debian 12 ships 3.11) from a source tree into
# build/peers/geos, then the benchmark's driver scripts/bench/coverage_simplify.cpp against it.
# A benchmark baseline only: nothing of toposimp links it.
# Usage: scripts/bench/build-geos.sh GEOS_SOURCE_DIR   (e.g. an unpacked 3.14.1 release)
set -euo pipefail
cd "$(dirname "$0")/../.."
source=$(realpath "$1")
prefix=$PWD/build/peers/geos
cmake -S "$source" -B build/peers/geos-build -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
  -DBUILD_DOCUMENTATION=OFF -DCMAKE_INSTALL_PREFIX="$prefix" >/dev/null
cmake --build build/peers/geos-build -j "$(nproc)"
cmake --install build/peers/geos-build >/dev/null
g++ -O2 -std=c++17 -o build/peers/coverage_simplify scripts/bench/coverage_simplify.cpp \
  -I"$prefix/include" -I/usr/include/gdal -L"$prefix/lib" -Wl,--disable-new-dtags,-rpath,"$prefix/lib" -lgeos_c -lgdal
echo "built $prefix and build/peers/coverage_simplify ($("$prefix/bin/geos-config" --version))"
