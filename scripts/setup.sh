#!/usr/bin/env bash
# Installs everything errfield needs to build, test, cross-check and benchmark, from Debian 12
# packages. Safe to run any number of times: it only calls apt-get when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libnlopt-dev libnlopt-cxx-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libnanoflann-dev
  # URDF import (errfield import-urdf); kdl_parser is its peer in tests/peers
  liburdfdom-dev libkdl-parser-dev
  # independent peers for cross-checks: R gstat, Orocos KDL, scipy
  r-cran-gstat liborocos-kdl-dev python3-numpy python3-scipy python3-sklearn
  # rasters: interpolate --grid ... --out F.tif / F.asc and raster covariates (GDAL); gdal-bin for the
  # tests, which read the rasters back with gdalinfo / gdal_translate
  libgdal-dev gdal-bin
  # Python module (docs/python.md): pybind11 bindings, their pytest suite and example plots
  python3-dev pybind11-dev python3-pybind11 python3-pytest python3-matplotlib
  # report rendering check, fuzzing and sanitizers
  chromium clang libclang-rt-14-dev libomp-14-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
