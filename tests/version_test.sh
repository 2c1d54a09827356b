#!/usr/bin/env bash
# The version is CMakeLists.txt's project version alone: the executable prints it (compiled in
# from CMake), and the man pages and the QGIS plugin's metadata, which are installed as written,
# must carry the same. Usage: version_test.sh VERSION SOURCE_DIR TOPOSIMP_BINARY
set -euo pipefail
version=$1 source=$2 binary=$3
status=0
printed=$("$binary" --version)
case "$printed" in
  "toposimp $version "*) ;;
  *) echo "toposimp --version printed '$printed', not toposimp $version"; status=1 ;;
esac
for page in "$source"/man/*.1; do
  grep -q "^\.TH .* \"toposimp $version\"" "$page" || { echo "$page: its .TH line does not say toposimp $version"; status=1; }
done
grep -qx "version=$version" "$source/scripts/qgis/toposimp_processing/metadata.txt" ||
  { echo "scripts/qgis/toposimp_processing/metadata.txt: not version=$version"; status=1; }
exit $status
