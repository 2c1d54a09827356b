#!/usr/bin/env bash
# `cmake --install` into a temporary prefix, then runs what was installed: the executable on the
# sample map, the man pages (rendered with groff warnings on), the QGIS plugin's modules, and the
# provider in qgis_process when QGIS is installed.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1
source_dir=$2
prefix=$(mktemp -d /tmp/toposimp-install-test.XXXXXX)
trap 'rm -rf "$prefix"' EXIT

cmake --install "$build" --prefix "$prefix" >/dev/null
fail() { echo "FAIL: $*"; exit 1; }

[ -x "$prefix/bin/toposimp" ] || fail "no bin/toposimp"
# bin/toposimp hands every job that needs GDAL (here --version, map, check) to this one.
[ -x "$prefix/libexec/toposimp/toposimp-gdal" ] || fail "no libexec/toposimp/toposimp-gdal"
"$prefix/bin/toposimp" --version | grep -q '^toposimp 0\.1\.0 (GDAL ' || fail "--version: $("$prefix/bin/toposimp" --version)"

# The installed executable does the main job and its output checks clean.
out="$prefix/work"
mkdir "$out"
summary=$("$prefix/bin/toposimp" map "$source_dir/testdata/nh_borders.gpkg" -l borders \
          --points "$source_dir/testdata/nh_borders.gpkg:places" --keep 10% --validate --json -o "$out/b.gpkg")
echo "$summary" | grep -q '"vertices_in":992' || fail "map summary: $summary"
"$prefix/bin/toposimp" check "$source_dir/testdata/nh_borders.gpkg" "$out/b.gpkg" -l borders \
    --points "$source_dir/testdata/nh_borders.gpkg:places" -q || fail "the installed map output does not check clean"
"$prefix/bin/toposimp" mesh "$source_dir/testdata/mesh/torus.off" -o "$out/t.ply" --keep 10% --no-hausdorff -q \
    || fail "installed mesh failed"

# Man pages: every one installed, and rendered by man-db (when present) or groff without warnings.
for page in toposimp toposimp-map toposimp-mesh toposimp-check; do
    file="$prefix/share/man/man1/$page.1"
    [ -f "$file" ] || fail "no $file"
    if command -v man >/dev/null; then
        warnings=$(MANWIDTH=80 man --warnings -M "$prefix/share/man" "$page" 2>&1 >/dev/null) || fail "man $page failed"
    else
        warnings=$(groff -ww -z -man "$file" 2>&1)
    fi
    [ -z "$warnings" ] || fail "man $page: $warnings"
done

# The QGIS plugin: its files, and its QGIS-free modules import from the installed folder, in
# Debian's Python (where apt puts QGIS's and GDAL's modules; another python3 may come first on PATH).
python=/usr/bin/python3
[ -x "$python" ] || python=python3
plugins="$prefix/share/qgis/python/plugins"
for file in __init__.py metadata.txt plugin.py provider.py settings.py algorithms.py cli_args.py runner.py icon.svg; do
    [ -f "$plugins/toposimp_processing/$file" ] || fail "plugin file $file not installed"
done
grep -q '^hasProcessingProvider=yes' "$plugins/toposimp_processing/metadata.txt" || fail "metadata without hasProcessingProvider"
"$python" -c "import sys; sys.path.insert(0, sys.argv[1]); from toposimp_processing import cli_args, runner; \
assert runner.find_executable(sys.argv[2]) == sys.argv[2]" "$plugins" "$prefix/bin/toposimp" \
    || fail "the installed plugin's modules do not import"

# The Python package, where Debian's Python imports it under this prefix; with a folder of QGIS
# plugins first on sys.path, as QGIS's console has it (QGIS's own modules too, when installed).
site=$(echo "$prefix"/lib/python3*/dist-packages)
[ -f "$site/toposimp/__init__.py" ] || fail "no $site/toposimp/__init__.py"
ls "$site"/toposimp/_toposimp*.so >/dev/null || fail "no extension in $site/toposimp"
PYTHONPATH="$site" "$python" - "$plugins" "$source_dir" <<'PY' || fail "the installed Python package does not work"
import sys
sys.path.insert(0, sys.argv[1])
try:
    import qgis.core  # noqa: F401
except ImportError:
    pass
import geopandas
import toposimp
assert toposimp.__file__.startswith(sys.path[1]) or "dist-packages" in toposimp.__file__, toposimp.__file__
states = geopandas.read_file(sys.argv[2] + "/testdata/ne_states_slice.gpkg")
simple = toposimp.simplify(states, keep=0.3)
assert toposimp.check(states, simple).empty
assert toposimp.summary(simple)["vertices_out"] < toposimp.summary(simple)["vertices_in"]
PY

# The installed provider with the installed executable, in a real QGIS when there is one.
status=0
TOPOSIMP_BINARY="$prefix/bin/toposimp" TOPOSIMP_QGIS_PLUGINS="$plugins" TOPOSIMP_PYTHONPATH="$site" \
    "$python" "$source_dir/scripts/qgis/tests/qgis_process_test.py" || status=$?
if [ "$status" -eq 77 ]; then
    echo "note: qgis_process not installed; the installed provider was not run in QGIS"
elif [ "$status" -ne 0 ]; then
    fail "the installed provider failed in qgis_process"
fi
echo "installed into $prefix and ran: executable, man pages, QGIS plugin, Python package"
