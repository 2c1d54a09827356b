#!/usr/bin/env bash
# Builds the fuzz targets (clang, ASan + UBSan: the fuzz preset) and runs each for a bounded time
# through ctest (label fuzz), two at a time. Usage: scripts/fuzz.sh [SECONDS per target, default 60]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
seconds=${1:-60}
cmake --preset fuzz -DTOPOSIMP_FUZZ_SECONDS="$seconds" >/dev/null
cmake --build --preset fuzz -j "$(nproc)"
ctest --preset fuzz -j "$(nproc)"
