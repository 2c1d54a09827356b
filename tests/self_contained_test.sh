#!/usr/bin/env bash
# The project stands on its own: no test, script or CI step reads the folder beside the checkout
# that holds the team's shared material (a fresh clone does not have it; copy what a test needs
# into testdata/, with its licence). Usage: self_contained_test.sh SOURCE_DIR
set -euo pipefail
cd "$1"
beside='\.\./'"shared"  # (spelt in two pieces, so that this file does not match itself)
if found=$(grep -rnE "$beside" tests scripts .ci CMakeLists.txt CMakePresets.json); then
  echo "these lines read the shared folder beside the checkout:"
  echo "$found"
  exit 1
fi
