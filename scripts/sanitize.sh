#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer (-DERRFIELD_SANITIZE=ON) in ./build-asan (or
# $ERRFIELD_ASAN_BUILD_DIR), then ctest. Any sanitizer report fails the test that triggered it
# (halt_on_error / abort_on_error).
#
#   scripts/sanitize.sh          CI's subset (below), inside the 30-minute budget of .ci/run
#   scripts/sanitize.sh --all    every test executable and every test but the studies and
#                                $ERRFIELD_ASAN_EXCLUDE (the full sanitized suite: ~27 min here)
#
# CI's subset (since session 17; docs/reliability.md, "CI time budget", 2026-11-28): the library and
# the CLI at -O0 with ASan+UBSan, the libFuzzer targets that scripts/fuzz.sh then runs on them, and
# the test executables that run no whole CLI fit: io_tests, kernels_tests (the raw-pointer pair and
# IDW kernels), optim_tests and fuzz_tests (every fuzz seed and past crash, the CLI's included). The
# session-16 suite under ASan (708 tests, all executables at -O1) cost 1596 s of the 3351 s .ci/run
# took. The whole suite under ASan is `--all`, to run before a release and after changing memory
# handling anywhere; the Release stage runs every test.
#
# -O0 for the library in the subset: under ASan it compiles in 516 CPU s against 1178 at -O1. The
# CLI's fits then run 10x slower, so bad_input_tests is not in the subset (its tests summed 492 s
# at -O0, one calibrate beyond its 1500 s timeout; they run under ASan with `--all`). (`--all` keeps
# -O1: at -O0 the header templates the estimator tests instantiate ran unoptimised and
# LikelihoodFit.Ard* took 124 s against 0.2 s in Release.)
#
# Left out of `--all` by default ($ERRFIELD_ASAN_EXCLUDE, a ctest -E regex): the peer cross-checks
# (their time goes into R and KDL, not instrumented; not even built here), install_consumer
# (packaging only) and suites whose worth is a number, not a code path, each run in Release by
# scripts/test.sh: docs_commands, CalibrationDistanceGeometry, PredictiveCoverage,
# KrigingCli.ModelAutoKeeps..., ReproduceCli.OneRunWrites..., Commands/Determinism (bytes across
# thread counts) and JointFunctionsCli (held-out checks): each took 38-123 s here; realdata_scoreboard
# (a 1,000-pose real-data fit, 12 s in Release, minutes at -O0; its figures are gcc Release's).
#
# Debug info: -g1 (line tables, function names): reports keep file:line, and the build is cheaper.
# OpenMP: clang links LLVM's libomp; it is not instrumented, which only matters for TSan (see
# scripts/tsan.sh). LeakSanitizer needs one suppression for libomp's own thread pool
# (tests/lsan.supp). Tests run with OMP_NUM_THREADS=2 so the parallel paths are exercised.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${ERRFIELD_ASAN_BUILD_DIR:-build-asan}
EXCLUDE=${ERRFIELD_ASAN_EXCLUDE:-'^Gstat|^KdlPeer|^install_consumer$|^docs_commands$|^CalibrationDistanceGeometry\.|^PredictiveCoverage\.|^KrigingCli\.ModelAutoKeepsTheLikelihoodFamiliesBeyond3000Samples$|^ReproduceCli\.OneRunWritesEveryTableAndARenderableReport$|^Commands/Determinism\.|^JointFunctionsCli\.|^realdata_scoreboard$'}

all=0
if [ "${1:-}" = --all ]; then all=1; shift; fi
opt=-O0
[ "$all" = 1 ] && opt=-O1
# clang, with -DERRFIELD_BUILD_FUZZERS=ON: the library and the CLI objects carry ASan+UBSan and
# libFuzzer's coverage instrumentation, so scripts/fuzz.sh --build-dir build-asan links its targets
# against this same build instead of compiling the library a third time (.ci/run does that).
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt -g1" -DERRFIELD_SANITIZE=ON -DERRFIELD_BUILD_FUZZERS=ON \
  -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF -DERRFIELD_BUILD_PEER_TESTS=OFF \
  -DERRFIELD_TEST_COMPILE_OPTIONS= "$@" >/dev/null
select=(-LE study -E "$EXCLUDE")
if [ "$all" = 1 ]; then
  cmake --build "$BUILD_DIR" -j "$(nproc)"
else
  fuzzers=$(ls tests/fuzz/fuzz_*.cpp | sed -n 's|^tests/fuzz/\(fuzz_[a-z_]*\)\.cpp$|\1|p' | grep -v '_test$')
  targets="errfield_cli io_tests kernels_tests optim_tests fuzz_tests $fuzzers"
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target $targets
  # The executables not built here have a <name>_NOT_BUILT placeholder test; the subset is the
  # tests of the executables built.
  select=(-LE study -E "$EXCLUDE|_NOT_BUILT")
fi

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}  # libomp's thread pool (tests/lsan.supp says why)
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}  # as scripts/test.sh: no spinning while two tests share the cores
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "${select[@]}"
