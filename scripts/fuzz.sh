#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz/fuzz_*.cpp) with clang, ASan and UBSan in ./build-fuzz
# (or $ERRFIELD_FUZZ_BUILD_DIR) and runs each one for N seconds (default 60) on its seed corpus
# tests/fuzz/corpus/<target>/. New interesting inputs go to build-fuzz/corpus/<target>/ (the repo's
# seeds are never modified); a crash stops that target, leaves its input in build-fuzz/artifacts/
# and makes the script exit non-zero after all targets ran.
#
#   scripts/fuzz.sh [--seconds N] [--jobs J] [target ...]     e.g. scripts/fuzz.sh --seconds 3600 csv
#
#   --build-dir DIR   use DIR, an existing build configured with -DERRFIELD_BUILD_FUZZERS=ON (as
#                     scripts/sanitize.sh's build-asan is): only the fuzz targets are built there, the
#                     library is not compiled again
#   --parallel P      run P targets at a time (default: the number of cores); each is one process
#
# CI (.ci/run) runs every target for 30 s, two at a time, in the sanitizer stage's build. For a long
# campaign see docs/reliability.md.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET=60
JOBS=1
PARALLEL=$(nproc)
REUSE_BUILD=""
TARGETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) SECONDS_PER_TARGET=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    --parallel) PARALLEL=$2; shift 2 ;;
    --build-dir) REUSE_BUILD=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) TARGETS+=("$1"); shift ;;
  esac
done
BUILD_DIR=${REUSE_BUILD:-${ERRFIELD_FUZZ_BUILD_DIR:-build-fuzz}}
# Absolute paths: the CLI target changes into a scratch directory before libFuzzer writes anything.
case "$BUILD_DIR" in /*) ;; *) BUILD_DIR="$PWD/$BUILD_DIR" ;; esac

if [ -n "$REUSE_BUILD" ]; then
  grep -q '^ERRFIELD_BUILD_FUZZERS:BOOL=ON' "$BUILD_DIR/CMakeCache.txt" 2>/dev/null ||
    { echo "fuzz: $BUILD_DIR is not a build configured with -DERRFIELD_BUILD_FUZZERS=ON"; exit 2; }
else
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DERRFIELD_BUILD_FUZZERS=ON \
    -DERRFIELD_BUILD_TESTS=OFF -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF >/dev/null
fi
if [ ${#TARGETS[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.cpp; do
    n=$(basename "$f" .cpp)
    case "$n" in *_test) continue ;; esac  # fuzz_replay_test.cpp is a unit test, not a target
    TARGETS+=("${n#fuzz_}")
  done
fi
cmake --build "$BUILD_DIR" -j "$(nproc)" --target "${TARGETS[@]/#/fuzz_}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}  # libomp's thread pool (tests/lsan.supp says why)
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
# One libFuzzer process per target, PARALLEL of them at a time; each writes its own log, and the
# verdicts are printed in target order once all have ended.
run_target() {
  local t=$1
  local corpus="$BUILD_DIR/corpus/$t" artifacts="$BUILD_DIR/artifacts/$t" seeds="$PWD/tests/fuzz/corpus/$t"
  mkdir -p "$corpus" "$artifacts"
  local extra=()
  # The CLI target prints usage and error messages for nearly every input: silence the target's
  # stdout/stderr (libFuzzer's own report still shows).
  [ "$t" = cli ] && extra+=(-close_fd_mask=3)
  [ -f "tests/fuzz/$t.dict" ] && extra+=("-dict=$PWD/tests/fuzz/$t.dict")
  [ "$JOBS" -gt 1 ] && extra+=(-jobs="$JOBS" -workers="$JOBS")
  local rc=0
  "$BUILD_DIR/tests/fuzz/fuzz_$t" "$corpus" "$seeds" -max_total_time="$SECONDS_PER_TARGET" \
    -timeout=20 -rss_limit_mb=2048 -max_len=4096 \
    -artifact_prefix="$artifacts/" -print_final_stats=1 "${extra[@]}" \
    >"$BUILD_DIR/fuzz_$t.log" 2>&1 || rc=$?
  echo "$rc" >"$BUILD_DIR/fuzz_$t.status"
}
for t in "${TARGETS[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$PARALLEL" ]; do wait -n || true; done
  echo "fuzz: $t for ${SECONDS_PER_TARGET}s"
  rm -f "$BUILD_DIR/fuzz_$t.status"
  run_target "$t" &
done
wait
failed=()
for t in "${TARGETS[@]}"; do
  status=$(cat "$BUILD_DIR/fuzz_$t.status" 2>/dev/null || echo missing)
  if [ "$status" != 0 ]; then
    failed+=("$t")
    echo "fuzz: $t FAILED (status $status); last lines of $BUILD_DIR/fuzz_$t.log:"
    tail -n 40 "$BUILD_DIR/fuzz_$t.log"
  elif ! grep -q '^stat::number_of_executed_units' "$BUILD_DIR/fuzz_$t.log"; then
    # -print_final_stats=1 always ends a finished run with these lines: without them the process
    # did not finish its run (the cli target once did, silently: tests/fuzz/fuzz_cli.cpp).
    failed+=("$t")
    echo "fuzz: $t ended without libFuzzer's final stats; last lines of $BUILD_DIR/fuzz_$t.log:"
    tail -n 40 "$BUILD_DIR/fuzz_$t.log"
  else
    echo -n "fuzz: $t: "
    grep -E '^stat::number_of_executed_units|^stat::new_units_added' "$BUILD_DIR/fuzz_$t.log" | tr '\n' ' '
    echo
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: crashes in: ${failed[*]} (inputs in $BUILD_DIR/artifacts/)"
  exit 1
fi
echo "fuzz: all ${#TARGETS[@]} targets ran ${SECONDS_PER_TARGET}s without a crash"
