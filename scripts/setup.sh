#!/usr/bin/env bash
# Installs everything toposimp needs on Debian 12, from Debian packages only. Idempotent.
#   scripts/setup.sh          build and test dependencies
#   scripts/setup.sh --qgis   also QGIS (qgis, python3-qgis), to run the QGIS provider's test in
#                             qgis_process for real (without it that test reports itself skipped)
set -euo pipefail
packages=(build-essential cmake ninja-build pkg-config file python3
          libgdal-dev gdal-bin libsqlite3-dev libgeos-dev libgmp-dev libcli11-dev libspdlog-dev libgtest-dev libgmock-dev groff-base
          clang libclang-rt-14-dev libomp-dev
          pybind11-dev python3-dev python3-numpy python3-geopandas python3-pytest python3-distributed libjemalloc2)
for arg in "$@"; do
  case "$arg" in
    --qgis) packages+=(qgis python3-qgis) ;;
    *) echo "setup: unknown option $arg (--qgis is the only one)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
echo "setup: dependencies present"
