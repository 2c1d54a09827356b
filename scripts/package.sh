#!/usr/bin/env bash
# Builds what users install, into out/:
#   out/toposimp_<version>_<arch>.deb   the Debian package (Release build): binary, man pages, QGIS plugin
#   out/toposimp-qgis-plugin.zip        the QGIS plugin alone, for Plugins > Manage and Install > Install from ZIP
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh release
mkdir -p out
(cd build/release && cpack -G DEB -B "$PWD/../../out/cpack" >/dev/null)
mv out/cpack/toposimp_*.deb out/
rm -rf out/cpack
rm -f out/toposimp-qgis-plugin.zip
python3 - <<'PY'
import os, zipfile
# The zip holds the folder toposimp_processing/ (QGIS installs a plugin zip by its top folder).
with zipfile.ZipFile("out/toposimp-qgis-plugin.zip", "w", zipfile.ZIP_DEFLATED) as archive:
    for name in sorted(os.listdir("scripts/qgis/toposimp_processing")):
        if not name.endswith(".pyc") and name != "__pycache__":
            archive.write(os.path.join("scripts/qgis/toposimp_processing", name), "toposimp_processing/" + name)
PY
ls -l out/toposimp_*.deb out/toposimp-qgis-plugin.zip
