#!/usr/bin/env bash
# ThreadSanitizer run of the OpenMP code paths (docs/reliability.md, "ThreadSanitizer").
#
# GCC's libgomp is not TSan-instrumented, so its barriers and reductions are invisible to TSan and
# every parallel region reports false races. This script therefore builds with clang and LLVM's
# libomp (package libomp-14-dev), and loads libomp's Archer tool (libarcher.so), which tells TSan
# about OpenMP's synchronisation (barriers, task and loop scheduling, critical sections).
# Build dir: ./build-tsan (or $ERRFIELD_TSAN_BUILD_DIR). Suppressions: tests/tsan.supp (each one
# says why it is a false positive).
#
# Subset (about 90 tests, listed in docs/reliability.md): every test of the in-process library
# tests of the parallel code — empirical variogram, grid IDW (class and kernel), scattered IDW,
# kriging (dense, local, sparse back ends; each has a 1-vs-2-thread test, the others run with
# OMP_NUM_THREADS=2 too) — plus the per-command determinism tests, which run the TSan-built CLI
# with OMP_NUM_THREADS=2 (variogram, interpolate with every back end, cv, simulate, calibrate,
# plan, fit, compensate, and reproduce --runs 2, whose two parallel loops, over the Table 6 runs
# and over the Fig. 5 grid nodes, both split).
# Only their executables are built. Override with $ERRFIELD_TSAN_TESTS (a ctest -R regex) and
# $ERRFIELD_TSAN_TARGETS (build targets).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${ERRFIELD_TSAN_BUILD_DIR:-build-tsan}
TESTS=${ERRFIELD_TSAN_TESTS:-'^((EmpiricalVariogram|PairBinningKernel|GridIdw|GridIdwKernel|ScatteredIdw|Kriging|SimpleOrdinaryUniversal/KrigingVariants|Commands/Determinism)\.|VecchiaLikelihood\.SameBits|ConditionalSimulation\.SameDraws|VarianceReduction\.SamePicks|Cokriging\.ResultsAreBitIdentical|CrossVariogram\.BitIdentical)'}
TARGETS=${ERRFIELD_TSAN_TARGETS:-errfield_cli estimators_tests kernels_tests reliability_tests}
ARCHER=$(ls /usr/lib/llvm-*/lib/libarcher.so 2>/dev/null | sort -V | tail -n 1 || true)
[ -n "$ARCHER" ] || { echo "tsan: libarcher.so not found (apt-get install libomp-14-dev)"; exit 1; }

cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_UNITY_BUILD="${ERRFIELD_UNITY_BUILD:-ON}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DERRFIELD_SANITIZE_THREAD=ON \
  -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF >/dev/null
# shellcheck disable=SC2086  # TARGETS is a space-separated list
cmake --build "$BUILD_DIR" -j "$(nproc)" --target $TARGETS

export OMP_TOOL_LIBRARIES="$ARCHER"
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp}
export OMP_NUM_THREADS=2
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}  # as scripts/test.sh: no spinning while two tests share the cores

# Self-check (tests/tsan/openmp_canary.cpp): correct OpenMP synchronisation must stay quiet (else
# TSan does not see libomp's ordering and every report would be suspect) and a real race must be
# reported (else the suppressions or the build make this job blind).
CXX_TSAN=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD_DIR/CMakeCache.txt")
"$CXX_TSAN" -std=c++20 -O1 -g -Wall -Wextra -fsanitize=thread -fopenmp=libomp tests/tsan/openmp_canary.cpp \
  -o "$BUILD_DIR/openmp_canary"
"$BUILD_DIR/openmp_canary" clean >"$BUILD_DIR/openmp_canary_clean.log" 2>&1 ||
  { cat "$BUILD_DIR/openmp_canary_clean.log"; echo "tsan: reports on race-free OpenMP code (is Archer loaded?)"; exit 1; }
if "$BUILD_DIR/openmp_canary" race >"$BUILD_DIR/openmp_canary_race.log" 2>&1 ||
   ! grep -q "WARNING: ThreadSanitizer: data race" "$BUILD_DIR/openmp_canary_race.log"; then
  cat "$BUILD_DIR/openmp_canary_race.log"; echo "tsan: a deliberate data race was NOT reported"; exit 1
fi
echo "tsan: self-check ok (race-free OpenMP code quiet, a deliberate race reported)"
# A test that selects nothing would make this job vacuous: insist on the subset being there.
n=$(ctest --test-dir "$BUILD_DIR" -N -R "$TESTS" | sed -n 's/^Total Tests: //p')
[ "${n:-0}" -gt 0 ] || { echo "tsan: the regex selects no test: $TESTS"; exit 1; }
echo "tsan: $n tests, OMP_NUM_THREADS=2, Archer=$ARCHER"
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" -R "$TESTS"
