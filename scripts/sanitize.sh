#!/usr/bin/env bash
# The test suite built with AddressSanitizer + UndefinedBehaviorSanitizer (-DERRFIELD_SANITIZE=ON,
# RelWithDebInfo at -O1) in ./build-asan (or $ERRFIELD_ASAN_BUILD_DIR), then run with ctest. Any
# sanitizer report fails the test that triggered it (halt_on_error / abort_on_error).
#
# Subset: every test runs, except the statistical studies (label `study`, as in scripts/test.sh)
# and those whose name matches $ERRFIELD_ASAN_EXCLUDE (a ctest -E regex). Default: the peer
# cross-checks (GstatPeer, GstatIdwPeer, GstatKrige, KdlPeer: their time goes into R and KDL, which
# are not instrumented, and their errfield code paths are covered by the other tests; they are not
# even built here, -DERRFIELD_BUILD_PEER_TESTS=OFF) and install_consumer (packaging only, no
# errfield code runs). Also three suites whose worth is a number, not a code path, each run in
# Release by scripts/test.sh: docs_commands (that the docs' ~100 commands run as written: 300+ s
# here, a timeout), CalibrationDistanceGeometry (distance calibration against a least squares
# written in the test: 88 s here, 0.5 s in Release; the calibration's code runs here through
# CalibrationIndependent, calibration_test and the CLI tests) and PredictiveCoverage (held-out
# coverage of six kriging fits: 65 s here; the same fits run here through the pipeline and
# determinism tests). Measured 2026-11-25; docs/reliability.md, "CI time budget". And the
# determinism check of `reproduce` (three whole reproductions compared byte for byte: 123 s here,
# the longest test of this stage): its worth is the bytes, checked in Release and under TSan; the
# reproduction's code runs here through ReproduceCli and AtomicCliOutput (measured 2026-11-26;
# ctest names a parameterized test "<name>  # GetParam() = ...", hence the "( |$)"). And
# KrigingCli.ModelAutoKeepsTheLikelihoodFamiliesBeyond3000Samples (a 3,100-sample Vecchia refit:
# 38 s here, 1.7 s in Release); the Vecchia likelihood's code runs here through VecchiaLikelihood.*.
# And ReproduceCli.OneRunWritesEveryTableAndARenderableReport (one whole reproduction and its
# report: 73 s here, the stage's longest test on 2026-11-26); the same CLI path, report included,
# runs here through AtomicCliOutput.ReproduceReplacesItsFilesAllOrNone.
# And every Commands/Determinism case (26 CLI runs compared byte for byte across thread counts:
# 110 CPU s here on 2026-11-26, interpolate_kriging_auto 24 s and the fit_*_kriging ones 17-19 s
# each): their worth is the bytes, which scripts/test.sh checks in Release and scripts/tsan.sh under
# TSan; the same commands run here through PipelineCli, KrigingCli, ValidateCli and the CLI tests.
# And JointFunctionsCli.* (held-out checks of fit's joint error functions on 400 simulated poses:
# 50 CPU s here on 2026-11-26, 6 s in Release): the functions' code runs here through
# JointErrorFunctions.* and every default kinematic+kriging fit of the CLI tests, the plan's linear
# term through PlanCandidates.* and VarianceReduction.*.

# Debug info: -g1 (line tables, function names; no local variables) instead of -g: reports keep
# file:line, and the build, nearly all of this stage's CPU time, is cheaper (CI budget).
#
# Test sources at the build's -O1 like everything else. (They were at -O0 while the stage used gcc
# and one executable per test file, to halve their compile time; but the header templates the tests
# instantiate - Eigen, kernels/, the variogram and kriging templates - then ran unoptimised:
# LikelihoodFit.ArdRangesRecoverTheTruthWithinThreeStandardErrors took 124 s against 0.2 s in
# Release. With clang and one unity build per test folder, -O1 costs ≈ 150 CPU s more to compile
# and saves far more in the tests; docs/reliability.md, "CI time budget".)
#
# OpenMP: clang links LLVM's libomp; it is not instrumented, which only matters for TSan (see
# scripts/tsan.sh). ASan+UBSan are quiet with it; LeakSanitizer needs one suppression for libomp's
# own thread pool (tests/lsan.supp). Tests run with
# OMP_NUM_THREADS=2 so the parallel paths are exercised.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${ERRFIELD_ASAN_BUILD_DIR:-build-asan}
EXCLUDE=${ERRFIELD_ASAN_EXCLUDE:-'^Gstat|^KdlPeer|^install_consumer$|^docs_commands$|^CalibrationDistanceGeometry\.|^PredictiveCoverage\.|^KrigingCli\.ModelAutoKeepsTheLikelihoodFamiliesBeyond3000Samples$|^ReproduceCli\.OneRunWritesEveryTableAndARenderableReport$|^Commands/Determinism\.|^JointFunctionsCli\.'}

# clang, with -DERRFIELD_BUILD_FUZZERS=ON: the library and the CLI objects carry ASan+UBSan and
# libFuzzer's coverage instrumentation, so scripts/fuzz.sh --build-dir build-asan links its targets
# against this same build instead of compiling the library a third time (.ci/run does that).
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DERRFIELD_SANITIZE=ON -DERRFIELD_BUILD_FUZZERS=ON \
  -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF -DERRFIELD_BUILD_PEER_TESTS=OFF \
  -DERRFIELD_TEST_COMPILE_OPTIONS= "$@" >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}  # libomp's thread pool (tests/lsan.supp says why)
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}  # as scripts/test.sh: no spinning while two tests share the cores
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" -LE study -E "$EXCLUDE"
