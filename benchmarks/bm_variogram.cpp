// Empirical variogram throughput: N = 2,000 / 20,000 / 50,000 locations in 3-D (task space, mm)
// and 6-D (joint space, degrees), 20 bins, 1 or 2 threads. Simulated data: uniform random
// locations, a smooth field plus noise as value. Counter `pairs_per_s` = N(N-1)/2 / wall time.
//
//   build/benchmarks/bm_variogram --benchmark_filter='BM_Variogram3d/N:20000/threads:2'
//
// BM_Variogram3dAlpha / BM_Variogram6dAxis: the same with a direction filter (gstat alpha 45,
// tol.hor 22.5; coordinate axis 0 within 45 degrees).
//
// BM_VariogramKernel3d runs the pair kernel alone (one thread, all rows as one chunk, N = 20,000,
// 3-D, 20 bins) with each instruction set this CPU has, for a same-process A/B comparison:
//
//   build/benchmarks/bm_variogram --benchmark_filter=BM_VariogramKernel3d

#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "errfield/empirical_variogram.hpp"
#include "pair_binning_simd.hpp"

namespace {

template <int D>
void run(benchmark::State& state, double extent,
         const errfield::VariogramDirection& direction = errfield::VariogramDirection()) {
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
  options.direction = direction;
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
// Directional: one angle test per pair inside the same pair loops (compare with BM_Variogram3d).
void BM_Variogram3dAlpha(benchmark::State& state) {
  run<3>(state, 2000.0, errfield::VariogramDirection::gstat(45.0, 22.5));
}
void BM_Variogram6dAxis(benchmark::State& state) {
  run<6>(state, 180.0, errfield::VariogramDirection::axis(0, 6, 45.0));
}

void sizes(benchmark::internal::Benchmark* b) {
  for (long n : {2000L, 20000L, 50000L})
    for (long t : {1L, 2L}) b->Args({n, t});
  b->ArgNames({"N", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

// isa: 0 = baseline, 1 = AVX2, 2 = AVX-512 (skipped when this CPU lacks it).
void BM_VariogramKernel3d(benchmark::State& state) {
  namespace k = errfield::kernels;
  const auto isa = static_cast<k::KernelIsa>(state.range(0));
  if (!k::kernel_isa_supported(isa)) {
    state.SkipWithError("this CPU lacks the instruction set");
    return;
  }
  const std::size_t n = 20000;
  const double extent = 2000.0;
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, extent);
  std::vector<double> soa(3 * n), val(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t a = 0; a < 3; ++a) soa[a * n + i] = u(rng);
    val[i] = std::sin(soa[i] / extent * 3.0) + std::cos(soa[2 * n + i] / extent * 2.0);
  }
  const double max_lag = extent * std::sqrt(3.0) / 1.1;
  const auto bins = errfield::LagBins::uniform(0.0, max_lag, max_lag / 20.0);
  const k::BinLayout layout{bins.edges().data(), bins.size(), false, true,
                            1.0 / (bins.edges()[1] - bins.edges()[0])};
  std::vector<std::uint64_t> count(bins.size() + 1);
  std::vector<double> lag(bins.size() + 1), stat(bins.size() + 1);
  for (auto _ : state) {
    std::fill(count.begin(), count.end(), 0);
    std::fill(lag.begin(), lag.end(), 0.0);
    std::fill(stat.begin(), stat.end(), 0.0);
    k::bin_pair_rows_euclidean_isa<k::PairStatistic::SquaredDifference, false, 1, 3>(
        isa, soa.data(), n, 3, val.data(), 1, layout, 0, 0, 1, n,
        k::PairSums{count.data(), lag.data(), stat.data()});
    benchmark::DoNotOptimize(lag.data());
  }
  const double pairs = 0.5 * static_cast<double>(n) * static_cast<double>(n - 1);
  // Per CPU second of the (single) calling thread: robust on a busy machine.
  state.counters["pairs_per_cpu_s"] =
      benchmark::Counter(pairs, benchmark::Counter::kIsIterationInvariantRate);
}

// Cutoff against extent (issue 22 item 7): 3-D locations uniform in a 500 cube, 15 bins up to
// the cutoff = ratio x 500, N up to 10^6 (the largest N only at short cutoffs). `search`: 0 =
// automatic (sorted columns where they pay), 1 = all pairs, 2 = sorted columns forced. Counter
// `binned_pairs` = pairs within the cutoff.
//
//   build/benchmarks/bm_variogram --benchmark_filter='BM_VariogramCutoff3d/N:80000/ratio_pct:20'
void BM_VariogramCutoff3d(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const double cutoff = 500.0 * static_cast<double>(state.range(1)) / 100.0;
  const auto search = static_cast<errfield::PairSearch>(state.range(2));
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::MatrixXd x(static_cast<Eigen::Index>(n), 3), z(static_cast<Eigen::Index>(n), 1);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (int a = 0; a < 3; ++a) x(i, a) = u(rng);
    z(i, 0) = std::sin(x(i, 0) / 80.0) + std::cos(x(i, 2) / 120.0) + noise(rng);
  }
  const auto bins = errfield::LagBins::uniform(0.0, cutoff, cutoff / 15.0);
  errfield::EmpiricalVariogramOptions options;
  options.threads = 2;
  options.pair_search = search;
  double binned = 0.0;
  for (auto _ : state) {
    auto v = errfield::empirical_variogram(x, z, bins, options);
    binned = 0.0;
    for (const auto& b : v.bins) binned += static_cast<double>(b.pairs);
    benchmark::DoNotOptimize(v.bins.data());
  }
  state.counters["binned_pairs"] = binned;
}

// Directional variograms on the fast path (issue 36): N = 78,000 2-D locations uniform in a
// 260 x 300 window (simulated; a smooth field plus noise), 10 bins up to a cutoff of 20 (gstat's
// convention), 2 threads. `directions`: 0 = omnidirectional, 1 = alpha 0 with gstat's default
// tolerance for one direction (90: every pair), 2 = alpha 0 with tolerance 22.5, 4 = alpha
// 0, 45, 90, 135 with tolerance 22.5 (four variograms, as `errfield variogram --alpha 0,45,90,135`).
// The R gstat call on the same job: benchmarks/peers/gstat_variogram_directional_timing.R.
//
//   build/benchmarks/bm_variogram --benchmark_filter=BM_Variogram2dDirections
void BM_Variogram2dDirections(benchmark::State& state) {
  const std::size_t n = 78000;
  const long directions = state.range(0);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> ux(0.0, 260.0), uy(0.0, 300.0);
  std::normal_distribution<double> noise(0.0, 5.0);
  Eigen::MatrixXd x(static_cast<Eigen::Index>(n), 2), z(static_cast<Eigen::Index>(n), 1);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    x(i, 0) = ux(rng);
    x(i, 1) = uy(rng);
    z(i, 0) = 100.0 * std::sin(x(i, 0) / 25.0) + 80.0 * std::cos(x(i, 1) / 40.0) + noise(rng);
  }
  const auto bins = errfield::LagBins::uniform(0.0, 20.0, 2.0);
  std::vector<errfield::VariogramDirection> cones;
  if (directions == 0) cones.emplace_back();
  if (directions == 1) cones.push_back(errfield::VariogramDirection::gstat(0.0, 90.0));
  if (directions == 2) cones.push_back(errfield::VariogramDirection::gstat(0.0, 22.5));
  if (directions == 4)
    for (double alpha : {0.0, 45.0, 90.0, 135.0}) cones.push_back(errfield::VariogramDirection::gstat(alpha, 22.5));
  errfield::EmpiricalVariogramOptions options;
  options.threads = 2;
  options.convention = errfield::BinConvention::Gstat;
  double binned = 0.0;
  for (auto _ : state) {
    binned = 0.0;
    for (const auto& d : cones) {
      options.direction = d;
      auto v = errfield::empirical_variogram(x, z, bins, options);
      for (const auto& b : v.bins) binned += static_cast<double>(b.pairs);
      benchmark::DoNotOptimize(v.bins.data());
    }
  }
  state.counters["binned_pairs"] = binned;
}

void cutoff_cases(benchmark::internal::Benchmark* b) {
  for (long n : {20000L, 80000L})
    for (long ratio : {5L, 10L, 20L, 30L, 50L, 100L})
      for (long search : {0L, 1L}) b->Args({n, ratio, search});
  // Forced pair search at long cutoffs: where the automatic choice's threshold sits.
  for (long ratio : {30L, 50L, 70L, 100L}) b->Args({20000L, ratio, 2L});
  b->Args({80000L, 50L, 2L});
  // Larger N only where the cell list keeps it reasonable (all pairs: minutes).
  for (long ratio : {5L, 10L, 20L}) b->Args({200000L, ratio, 0L});
  for (long ratio : {5L, 10L}) b->Args({1000000L, ratio, 0L});
  b->ArgNames({"N", "ratio_pct", "search"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_VariogramCutoff3d)->Apply(cutoff_cases);
BENCHMARK(BM_Variogram2dDirections)->Arg(0)->Arg(1)->Arg(2)->Arg(4)->ArgName("directions")
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_VariogramKernel3d)->Arg(0)->Arg(1)->Arg(2)->ArgName("isa")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Variogram3d)->Apply(sizes);
BENCHMARK(BM_Variogram6d)->Apply(sizes);
BENCHMARK(BM_Variogram3dAlpha)->Apply(sizes);
BENCHMARK(BM_Variogram6dAxis)->Apply(sizes);
