#!/usr/bin/env bash
# The whole test suite, from a bare Debian 12 machine: install dependencies, build, run ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --test-dir "${ERRFIELD_BUILD_DIR:-build}" --output-on-failure -j "$(nproc)"
