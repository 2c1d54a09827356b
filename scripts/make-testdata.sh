#!/usr/bin/env bash
# Rebuilds testdata/nh_borders.gpkg from the GIS Cup 2014 training set td1 (New Hampshire county
# borders, MIT licence; testdata/giscup14). Coordinates are copied as text, and GDAL's WKT
# reader parses them correctly rounded, so the GeoPackage holds the contest's values exactly.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
src=${1:-$here/testdata/giscup14/td1}
out=$here/testdata/nh_borders.gpkg
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

to_csv() {  # $1 = GIS Cup file, $2 = LINESTRING|POINT, $3 = name prefix
  echo 'id,name,WKT'
  sed -E 's#^([^:]+):.*<gml:coordinates[^>]*>(.*)</gml:coordinates>.*$#\1|\2#' "$1" |
    awk -F'|' -v kind="$2" -v prefix="$3" '{
      n = split($2, pairs, " "); wkt = "";
      for (i = 1; i <= n; i++) { if (pairs[i] == "") continue; split(pairs[i], xy, ",");
        wkt = wkt (wkt == "" ? "" : ", ") xy[1] " " xy[2] }
      printf "%s,%s %s,\"%s (%s)\"\n", $1, prefix, $1, kind, wkt }'
}
to_csv "$src/lines_out.txt" LINESTRING border > "$tmp/borders.csv"
to_csv "$src/points_out.txt" POINT place > "$tmp/places.csv"
rm -f "$out"
common=(-oo GEOM_POSSIBLE_NAMES=WKT -oo KEEP_GEOM_COLUMNS=NO -oo AUTODETECT_TYPE=YES -a_srs ESRI:54004)
ogr2ogr -f GPKG "$out" "$tmp/borders.csv" -nln borders -nlt LINESTRING "${common[@]}"
ogr2ogr -f GPKG -update "$out" "$tmp/places.csv" -nln places -nlt POINT "${common[@]}"
ogrinfo -so -al "$out" | grep -E 'Layer name|Feature Count|Geometry:'
