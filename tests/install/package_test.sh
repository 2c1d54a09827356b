#!/usr/bin/env bash
# `cpack -G DEB` builds a Debian package that declares its library dependencies, holds the
# executable, the man pages and the QGIS plugin, and that apt can install on this system
# (checked with apt-get's simulation: dependencies resolved, nothing changed).
# Usage: package_test.sh BUILD_DIR
set -euo pipefail
build=$1
tmp=$(mktemp -d /tmp/toposimp-package-test.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

(cd "$build" && cpack -G DEB -B "$tmp" >"$tmp/cpack.log" 2>&1) || { cat "$tmp/cpack.log"; fail "cpack failed"; }
deb=$(ls "$tmp"/toposimp_*_*.deb)
depends=$(dpkg-deb -f "$deb" Depends)
for library in libgdal libgeos-c libgmp libgomp libspdlog libstdc++; do
    grep -q "$library" <<<"$depends" || fail "Depends lacks $library: $depends"
done
contents=$(dpkg-deb -c "$deb" | awk '{print $6}')
for path in ./usr/bin/toposimp ./usr/libexec/toposimp/toposimp-gdal ./usr/share/man/man1/toposimp.1 ./usr/share/man/man1/toposimp-map.1 \
            ./usr/share/man/man1/toposimp-mesh.1 ./usr/share/man/man1/toposimp-check.1 ./usr/share/man/man1/toposimp-dask.1 \
            ./usr/share/qgis/python/plugins/toposimp_processing/metadata.txt ./usr/share/qgis/python/plugins/toposimp_processing/algorithms.py \
            ./usr/lib/python3/dist-packages/toposimp/__init__.py ./usr/lib/python3/dist-packages/toposimp/mesh.py \
            ./usr/lib/python3/dist-packages/toposimp/dask.py; do
    grep -qx "$path" <<<"$contents" || fail "$path not in the package"
done
dpkg-deb -I "$deb" prerm >/dev/null || fail "no prerm script"
# The package's own executable runs against this system's libraries.
dpkg-deb -x "$deb" "$tmp/root"
"$tmp/root/usr/bin/toposimp" --version | grep -q '^toposimp ' || fail "the packaged executable does not run"
grep -q '^./usr/lib/python3/dist-packages/toposimp/_toposimp.*\.so$' <<<"$contents" || fail "the Python extension is not in the package"
dpkg-deb -f "$deb" Recommends | grep -q python3-geopandas || fail "Recommends lacks python3-geopandas"
dpkg-deb -f "$deb" Suggests | grep -q python3-distributed || fail "Suggests lacks python3-distributed (python3 -m toposimp.dask)"
PYTHONPATH="$tmp/root/usr/lib/python3/dist-packages" /usr/bin/python3 -c "import toposimp, numpy; \
m = toposimp.read_mesh('$(dirname "$0")/../../testdata/mesh/torus.off'); \
assert len(toposimp.simplify_mesh(m.vertices, m.faces, keep=0.1, measure=None).faces) == 480" \
    || fail "the packaged Python package does not run"
simulation=$(apt-get install -s "$deb" 2>&1) || { echo "$simulation"; fail "apt-get cannot install the package"; }
grep -q '^Inst toposimp' <<<"$simulation" || { echo "$simulation"; fail "apt-get would not install toposimp"; }
echo "package $(basename "$deb"): Depends: $depends"
