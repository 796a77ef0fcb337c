// Inverse-distance weighting throughput.
//
// BM_GridIdw/<nodes per axis>/<threads>: 10^6 random targets in a cubic grid (5 = the paper's
// 5 x 5 x 5 grid, 50 = 125,000 nodes), scalar values, p = 1; items/s = targets per second.
// BM_ScatteredIdw/<samples>/<neighbors>/<threads>: 10^5 random targets, samples at random in the
// same 500 mm cube, k nearest via the k-d tree, p = 2; items/s = targets per second.
// Run: build/benchmarks/bm_idw --benchmark_filter=GridIdw (or ScatteredIdw)
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "errfield/grid_idw.hpp"
#include "errfield/scattered_idw.hpp"

namespace {

using errfield::GridIdw;
using errfield::GridIdwOptions;
using errfield::RegularGrid3;

Eigen::MatrixXd random_targets(const RegularGrid3& g, Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd t(n, 3);
  for (int a = 0; a < 3; ++a) {
    std::uniform_real_distribution<double> u(g.lower()[a], g.upper()[a]);
    for (Eigen::Index i = 0; i < n; ++i) t(i, a) = u(rng);
  }
  return t;
}

template <class V>
void BM_GridIdw(benchmark::State& state) {
  const int nodes = static_cast<int>(state.range(0));
  const RegularGrid3 grid({0, 0, 0}, Eigen::Vector3d::Constant(500.0 / (nodes - 1)), {nodes, nodes, nodes});
  std::mt19937_64 rng(1);
  std::normal_distribution<double> nd(0.0, 0.3);
  std::vector<V> values(grid.node_count());
  for (auto& v : values) {
    if constexpr (std::is_same_v<V, double>) v = nd(rng);
    else v = V(nd(rng), nd(rng), nd(rng));
  }
  GridIdwOptions options;
  options.threads = static_cast<int>(state.range(1));
  const GridIdw<V> idw(grid, values, options);
  const Eigen::MatrixXd targets = random_targets(grid, 1'000'000, 2);
  std::vector<V> out(static_cast<std::size_t>(targets.rows()));
  std::vector<errfield::GridIdwStatus> status(out.size());
  for (auto _ : state) {
    idw.predict_with_status(targets, out, status);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * targets.rows());
  state.counters["threads"] = static_cast<double>(options.threads);
}

BENCHMARK(BM_GridIdw<double>)->ArgNames({"nodes", "threads"})->ArgsProduct({{5, 50}, {1, 2}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridIdw<Eigen::Vector3d>)->ArgNames({"nodes", "threads"})->ArgsProduct({{5}, {1, 2}})->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_ScatteredIdw(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::vector<Eigen::Vector3d> locations(n);
  std::vector<double> values(n);
  for (std::size_t i = 0; i < n; ++i) {
    locations[i] = Eigen::Vector3d(u(rng), u(rng), u(rng));
    values[i] = std::sin(locations[i].x() / 100.0);
  }
  std::vector<Eigen::Vector3d> targets(100'000);
  for (auto& t : targets) t = Eigen::Vector3d(u(rng), u(rng), u(rng));
  errfield::ScatteredIdwOptions options;
  options.neighbors = static_cast<std::size_t>(state.range(1));
  options.threads = static_cast<int>(state.range(2));
  const errfield::ScatteredIdw<Eigen::Vector3d, double> idw(locations, values, options);
  for (auto _ : state) {
    auto out = idw.predict(targets);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(targets.size()));
}

BENCHMARK(BM_ScatteredIdw)->ArgNames({"samples", "k", "threads"})->ArgsProduct({{20000}, {8, 32}, {1, 2}})->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
