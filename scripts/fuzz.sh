#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz/fuzz_*.cpp) with clang, ASan and UBSan in ./build-fuzz
# (or $ERRFIELD_FUZZ_BUILD_DIR) and runs each one for N seconds (default 60) on its seed corpus
# tests/fuzz/corpus/<target>/. New interesting inputs go to build-fuzz/corpus/<target>/ (the repo's
# seeds are never modified); a crash stops that target, leaves its input in build-fuzz/artifacts/
# and makes the script exit non-zero after all targets ran.
#
#   scripts/fuzz.sh [--seconds N] [--jobs J] [target ...]     e.g. scripts/fuzz.sh --seconds 3600 csv
#
# CI (.ci/run) runs every target for 45 s. For a long campaign see docs/reliability.md.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET=60
JOBS=1
TARGETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) SECONDS_PER_TARGET=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) TARGETS+=("$1"); shift ;;
  esac
done
BUILD_DIR=${ERRFIELD_FUZZ_BUILD_DIR:-build-fuzz}
# Absolute paths: the CLI target changes into a scratch directory before libFuzzer writes anything.
case "$BUILD_DIR" in /*) ;; *) BUILD_DIR="$PWD/$BUILD_DIR" ;; esac

cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DERRFIELD_BUILD_FUZZERS=ON \
  -DERRFIELD_BUILD_TESTS=OFF -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF >/dev/null
if [ ${#TARGETS[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.cpp; do
    n=$(basename "$f" .cpp)
    case "$n" in *_test) continue ;; esac  # fuzz_replay_test.cpp is a unit test, not a target
    TARGETS+=("${n#fuzz_}")
  done
fi
cmake --build "$BUILD_DIR" -j "$(nproc)" --target "${TARGETS[@]/#/fuzz_}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
failed=()
for t in "${TARGETS[@]}"; do
  corpus="$BUILD_DIR/corpus/$t"
  artifacts="$BUILD_DIR/artifacts/$t"
  mkdir -p "$corpus" "$artifacts"
  seeds="$PWD/tests/fuzz/corpus/$t"
  extra=()
  # The CLI target prints usage and error messages for nearly every input: silence the target's
  # stdout/stderr (libFuzzer's own report still shows).
  [ "$t" = cli ] && extra+=(-close_fd_mask=3)
  [ -f "tests/fuzz/$t.dict" ] && extra+=("-dict=$PWD/tests/fuzz/$t.dict")
  [ "$JOBS" -gt 1 ] && extra+=(-jobs="$JOBS" -workers="$JOBS")
  echo "fuzz: $t for ${SECONDS_PER_TARGET}s"
  if ! "$BUILD_DIR/tests/fuzz/fuzz_$t" "$corpus" "$seeds" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=20 -rss_limit_mb=2048 -max_len=4096 \
      -artifact_prefix="$artifacts/" -print_final_stats=1 "${extra[@]}" \
      >"$BUILD_DIR/fuzz_$t.log" 2>&1; then
    failed+=("$t")
    echo "fuzz: $t FAILED; last lines of $BUILD_DIR/fuzz_$t.log:"
    tail -n 40 "$BUILD_DIR/fuzz_$t.log"
  elif ! grep -q '^stat::number_of_executed_units' "$BUILD_DIR/fuzz_$t.log"; then
    # -print_final_stats=1 always ends a finished run with these lines: without them the process
    # did not finish its run (the cli target once did, silently: tests/fuzz/fuzz_cli.cpp).
    failed+=("$t")
    echo "fuzz: $t ended without libFuzzer's final stats; last lines of $BUILD_DIR/fuzz_$t.log:"
    tail -n 40 "$BUILD_DIR/fuzz_$t.log"
  else
    grep -E '^stat::number_of_executed_units|^stat::new_units_added' "$BUILD_DIR/fuzz_$t.log" | tr '\n' ' '
    echo
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: crashes in: ${failed[*]} (inputs in $BUILD_DIR/artifacts/)"
  exit 1
fi
echo "fuzz: all ${#TARGETS[@]} targets ran ${SECONDS_PER_TARGET}s without a crash"
