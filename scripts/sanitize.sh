#!/usr/bin/env bash
# The test suite built with AddressSanitizer + UndefinedBehaviorSanitizer (-DERRFIELD_SANITIZE=ON,
# RelWithDebInfo at -O1) in ./build-asan (or $ERRFIELD_ASAN_BUILD_DIR), then run with ctest. Any
# sanitizer report fails the test that triggered it (halt_on_error / abort_on_error).
#
# Subset: every test runs, except the statistical studies (label `study`, as in scripts/test.sh)
# and those whose name matches $ERRFIELD_ASAN_EXCLUDE (a ctest -E regex). Default: the peer
# cross-checks (GstatPeer, GstatIdwPeer, GstatKrige, KdlPeer: their time goes into R and KDL, which
# are not instrumented, and their errfield code paths are covered by the other tests; they are not
# even built here, -DERRFIELD_BUILD_PEER_TESTS=OFF), install_consumer (packaging only, no errfield
# code runs) and CalibrationIndependent.FitKinematicMatchesPlainLeastSquaresOnAnotherGeometry
# (179 s here, 0.5 s in Release: its own least-squares reference runs at -O0). The code it
# exercises runs under ASan in the calibration tests; in Release it runs.

# Debug info: -g1 (line tables, function names; no local variables) instead of -g: reports keep
# file:line, and the build, nearly all of this stage's CPU time, is cheaper (CI budget).
#
# Test sources at -O0 (-DERRFIELD_TEST_COMPILE_OPTIONS=-O0; the library and the CLI stay at -O1):
# nearly all of this stage is compiling, and ASan+UBSan codegen at -O1 of a gtest-heavy test file
# costs about twice -O0 (CPU s, gcc 12: kriging_test.cpp 47.6 vs 25.0,
# kriging_cli_test.cpp 13.8 vs 7.5; -Og 32.2). Nothing is left uninstrumented: the test code keeps both sanitizers, and at -O0 no UB in
# it is optimised away. Cost: the test bodies themselves run slower; most tests spend their time in
# the library or the CLI they call (docs/reliability.md, "CI time budget", has the measured ctest time).
#
# OpenMP: the library uses GCC's libgomp here; libgomp is not ASan-instrumented but that only
# matters for TSan (see scripts/tsan.sh), ASan+UBSan are quiet with it. Tests run with
# OMP_NUM_THREADS=2 so the parallel paths are exercised.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${ERRFIELD_ASAN_BUILD_DIR:-build-asan}
EXCLUDE=${ERRFIELD_ASAN_EXCLUDE:-'^Gstat|^KdlPeer|^install_consumer$|^CalibrationIndependent\.FitKinematicMatchesPlainLeastSquaresOnAnotherGeometry$'}

# clang, with -DERRFIELD_BUILD_FUZZERS=ON: the library and the CLI objects carry ASan+UBSan and
# libFuzzer's coverage instrumentation, so scripts/fuzz.sh --build-dir build-asan links its targets
# against this same build instead of compiling the library a third time (.ci/run does that).
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DERRFIELD_SANITIZE=ON -DERRFIELD_BUILD_FUZZERS=ON \
  -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF -DERRFIELD_BUILD_PEER_TESTS=OFF \
  -DERRFIELD_TEST_COMPILE_OPTIONS=-O0 "$@" >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" -LE study -E "$EXCLUDE"
