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
# ctest runs nproc tests at once and each test's OpenMP team has nproc threads: libgomp's default
# spin-wait at every barrier then takes the cores from the threads with work (a 40 ms model-choice
# test took 7 s). Waiting threads sleep instead: the suite took 67 s instead of 118 s of wall time
# here (2026-11-26, docs/reliability.md). A test's results do not depend on it.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
ctest --test-dir "${ERRFIELD_BUILD_DIR:-build}" --output-on-failure -j "$(nproc)" "${select[@]}"
