// Empirical variogram throughput: N = 2,000 / 20,000 / 50,000 locations in 3-D (task space, mm)
// and 6-D (joint space, degrees), 20 bins, 1 or 2 threads. Simulated data: uniform random
// locations, a smooth field plus noise as value. Counter `pairs_per_s` = N(N-1)/2 / wall time.
//
//   build/benchmarks/bm_variogram --benchmark_filter='BM_Variogram3d/20000/2'

#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "errfield/empirical_variogram.hpp"

namespace {

template <int D>
void run(benchmark::State& state, double extent) {
  using L = Eigen::Matrix<double, D, 1>;
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, extent);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<L> loc(n);
  std::vector<double> val(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < D; ++k) loc[i][k] = u(rng);
    val[i] = std::sin(loc[i][0] / extent * 3.0) + std::cos(loc[i][D - 1] / extent * 2.0) + noise(rng);
  }
  // 20 bins up to about the diameter of the point cloud / 1.1.
  const double max_lag = extent * std::sqrt(static_cast<double>(D)) / 1.1;
  const auto bins = errfield::LagBins::uniform(0.0, max_lag, max_lag / 20.0);
  errfield::EmpiricalVariogramOptions options;
  options.threads = threads;
  for (auto _ : state) {
    auto v = errfield::empirical_variogram<L, errfield::EuclideanMetric, double>(
        std::span<const L>(loc), std::span<const double>(val), errfield::EuclideanMetric{}, bins,
        options);
    benchmark::DoNotOptimize(v.bins.data());
  }
  const double pairs = 0.5 * static_cast<double>(n) * static_cast<double>(n - 1);
  state.counters["pairs_per_s"] =
      benchmark::Counter(pairs, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Variogram3d(benchmark::State& state) { run<3>(state, 2000.0); }
void BM_Variogram6d(benchmark::State& state) { run<6>(state, 180.0); }

void sizes(benchmark::internal::Benchmark* b) {
  for (long n : {2000L, 20000L, 50000L})
    for (long t : {1L, 2L}) b->Args({n, t});
  b->ArgNames({"N", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_Variogram3d)->Apply(sizes);
BENCHMARK(BM_Variogram6d)->Apply(sizes);
