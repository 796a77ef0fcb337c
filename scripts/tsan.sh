#!/usr/bin/env bash
# ThreadSanitizer run of the OpenMP code paths (opt-in; not part of .ci/run, see docs/reliability.md).
#
# GCC's libgomp is not TSan-instrumented, so its barriers and reductions are invisible to TSan and
# every parallel region reports false races. This script therefore builds with clang and LLVM's
# libomp (package libomp-14-dev), and loads libomp's Archer tool (libarcher.so), which tells TSan
# about OpenMP's synchronisation. Build dir: ./build-tsan (or $ERRFIELD_TSAN_BUILD_DIR).
#
# Subset: the tests that run parallel regions with 2 threads — thread-count invariance and
# kernel-vs-reference tests of the variogram, IDW and kriging, and the determinism tests
# ($ERRFIELD_TSAN_TESTS, a ctest -R regex).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${ERRFIELD_TSAN_BUILD_DIR:-build-tsan}
TESTS=${ERRFIELD_TSAN_TESTS:-'Thread|Parallel|Determinism|Kernel|Omp'}
ARCHER=$(ls /usr/lib/llvm-*/lib/libarcher.so 2>/dev/null | sort -V | tail -n 1 || true)
[ -n "$ARCHER" ] || { echo "tsan: libarcher.so not found (apt-get install libomp-14-dev)"; exit 1; }

cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DERRFIELD_SANITIZE_THREAD=ON \
  -DERRFIELD_BUILD_BENCHMARKS=OFF -DERRFIELD_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"

export OMP_TOOL_LIBRARIES="$ARCHER"
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:ignore_noninstrumented_modules=1:second_deadlock_stack=1}
export OMP_NUM_THREADS=2
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" -R "$TESTS"
