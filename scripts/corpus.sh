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
#     An OpenStreetMap extract from the Overpass API (osm/overpass.osm: roads, © OpenStreetMap
#     contributors, ODbL).
#   r-cran-rgdal (GPL-2+): a GPX track (test_trk2.gpx), Kiritimati's primary roads (a road
#     network as lines), Scottish districts in British National Grid, Trinidad Inca polygons.
#   r-cran-spdata (CC0): world, Auckland, Boston tracts, Columbus, Eire, SIDS, NY8 (polygons in
#     UTM), the London cycle hire points from OpenStreetMap.
#   r-cran-terra (GPL-3+): Luxembourg's cantons (lux.shp).
#   osmium-tool (GPL-3+): an OpenStreetMap extract of Karlsruhe (© OpenStreetMap contributors,
#     ODbL; decompressed to karlsruhe.osm) and Berlin boundaries as GeoJSON.
#   qgis-common (GPL-2+), when installed: Natural Earth admin-0 and admin-1 (world_map.gpkg).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
corpus=${TOPOSIMP_CORPUS:-$here/build/corpus}
mkdir -p "$corpus"
cd "$corpus"
for package in python3-geopandas r-cran-sf r-cran-rgdal r-cran-spdata r-cran-terra osmium-tool; do
  [ -f "$package/.done-2" ] && continue
  rm -rf "$package" download && mkdir -p "$package" download
  (cd download && apt-get download -qq "$package" 2>/dev/null) ||
    { apt-get update -qq && (cd download && apt-get download -qq "$package"); }
  dpkg-deb -x download/*.deb download/root
  find download/root \( -path '*geopandas/datasets/*' -o -path '*geopandas/tests/data/*' -o -path '*site-library/*' \
       -o -path '*doc/osmium-tool/examples/*' \) -type f \( -name '*.shp' -o -name '*.shx' -o -name '*.dbf' -o -name '*.prj' \
       -o -name '*.cpg' -o -name '*.gpkg' -o -name '*.geojson' -o -name '*.gml' -o -name '*.zip' -o -name '*.gpx' \
       -o -name '*.osm' -o -name '*.osm.bz2' \) -exec cp {} "$package/" \;
  find "$package" -name '*.osm.bz2' -exec bunzip2 -f {} \;
  rm -rf download
  touch "$package/.done-2"
done
if [ -f /usr/share/qgis/resources/data/world_map.gpkg ] && [ ! -f qgis-common/world_map.gpkg ]; then
  mkdir -p qgis-common && cp /usr/share/qgis/resources/data/world_map.gpkg qgis-common/
fi
echo "corpus: $(find "$corpus" -type f ! -name .done | wc -l) files in $corpus"
