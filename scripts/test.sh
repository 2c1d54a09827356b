#!/usr/bin/env bash
# The second README command: installs the dependencies, builds (dev preset: debug, -Werror) and
# runs every test through ctest (labels: unit, cli, property, golden, corpus, python, qgis, install).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/corpus.sh  # real files written by others, from Debian packages (the corpus test)
scripts/build.sh "${PRESET:-dev}"
ctest --preset "${PRESET:-dev}" -j "$(nproc)" "$@"
