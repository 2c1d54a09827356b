#!/usr/bin/env bash
# The corpus of real files written by others that tests/cli/corpus_test.cpp runs `toposimp map`
# and `toposimp check` over: vector data shipped in Debian packages, extracted (not installed,
# no dependencies pulled) into build/corpus/<package>/. Idempotent. Sources and licences:
#   python3-geopandas (BSD-3-Clause): Natural Earth countries and cities (public domain), the New
#     York City borough boundaries nybb_16a (NYC Department of City Planning, BSD as shipped),
#     a GeoJSON with NULL geometries (geopandas' tests).
#   r-cran-sf (GPL-2 | MIT): North Carolina counties (nc.shp, nc.gpkg), Olinda census tracts
#     (olinda1.shp), Atlantic storm tracks with Z and M (storms_*: GPS-like tracks), buildings,
#     a TIGER line sample (tl.gpkg), pump points, an FMI GML sample, a point CSV.
#   qgis-common (GPL-2+), when installed: Natural Earth admin-0 and admin-1 (world_map.gpkg).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
corpus=${TOPOSIMP_CORPUS:-$here/build/corpus}
mkdir -p "$corpus"
cd "$corpus"
for package in python3-geopandas r-cran-sf; do
  [ -f "$package/.done" ] && continue
  rm -rf "$package" download && mkdir -p "$package" download
  (cd download && apt-get download -qq "$package" 2>/dev/null) ||
    { apt-get update -qq && (cd download && apt-get download -qq "$package"); }
  dpkg-deb -x download/*.deb download/root
  find download/root \( -path '*geopandas/datasets/*' -o -path '*geopandas/tests/data/*' -o -path '*site-library/sf/*' \) \
       -type f \( -name '*.shp' -o -name '*.shx' -o -name '*.dbf' -o -name '*.prj' -o -name '*.cpg' -o -name '*.gpkg' \
       -o -name '*.geojson' -o -name '*.gml' -o -name '*.zip' \) -exec cp {} "$package/" \;
  rm -rf download
  touch "$package/.done"
done
if [ -f /usr/share/qgis/resources/data/world_map.gpkg ] && [ ! -f qgis-common/world_map.gpkg ]; then
  mkdir -p qgis-common && cp /usr/share/qgis/resources/data/world_map.gpkg qgis-common/
fi
echo "corpus: $(find "$corpus" -type f ! -name .done | wc -l) files in $corpus"
