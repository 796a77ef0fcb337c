#!/usr/bin/env bash
# The whole test suite, from a bare Debian 12 machine: install dependencies, build, run ctest.
#   scripts/test.sh              every test except the statistical studies (label `study`)
#   scripts/test.sh --studies    the statistical studies alone (minutes; docs/reliability.md lists
#                                them and the figures they measured)
#   scripts/test.sh --all        both
set -euo pipefail
cd "$(dirname "$0")/.."
select=(-LE study)
case "${1:-}" in
  --studies) select=(-L study) ;;
  --all) select=() ;;
  "") ;;
  *) echo "usage: scripts/test.sh [--studies|--all]"; exit 2 ;;
esac
bash scripts/setup.sh
bash scripts/build.sh
ctest --test-dir "${ERRFIELD_BUILD_DIR:-build}" --output-on-failure -j "$(nproc)" "${select[@]}"
