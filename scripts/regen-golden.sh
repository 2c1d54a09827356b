#!/usr/bin/env bash
# Regenerates testdata/golden/ (the only way golden files change). Review the diff before committing.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh release >/dev/null
mkdir -p testdata/golden
data=testdata/giscup14
for spec in td1:883 td2:517; do
  set=${spec%%:*} n=${spec##*:}
  out=testdata/golden/giscup-${set}_--remove-points_${n}.txt
  build/release/toposimp map --giscup "$data/$set/lines_out.txt" --points "$data/$set/points_out.txt" \
    --remove-points "$n" -o "$out" --overwrite -q
  echo "wrote $out"
done
