// Kriging back ends (docs/benchmarks.md, section "Kriging"). Simulated data: N samples uniform in a
// 1000 mm cube, smooth field + noise; targets uniform in the same cube. Each case is one run of
// set-up (factorization) + prediction; the counters say what was computed.
//
//   dense  : ordinary kriging, N = 500 / 2,000 / 5,000 samples, 100,000 targets with variance
//   leave-one-out: closed form after the factorization, N = 2,000 / 4,000 ({N, threads})
//   local  : ordinary kriging, N = 100,000, k = 32, 100,000 targets with variance
//   sparse : ordinary kriging, N = 100,000, sph range 45 mm (~30 samples per support ball);
//            means at 100,000 targets; with variances at 1,000 targets
//   simulation: conditional simulation (conditional_simulation.hpp), local back end (k = 20),
//            sequential unconditional draws (60 neighbours, 100 draws per random path): issue 22's
//            case is 10,000 targets x 100 draws from 2,000 samples (target: under 30 s);
//            {N, targets, draws, threads}
//   simulation on a grid (issue 36, R gstat's krige(nsim = 100, nmax = 24) on the same job:
//            benchmarks/peers/gstat_simulation_timing.R): 300 samples in a 100 x 100 square,
//            100 x 100 grid nodes, k = 24, 100 draws; {draws per path, threads}
// Arguments: {N, targets, threads, variance 0/1}. Peak RSS of the process is reported as max_rss_MiB.

#include <sys/resource.h>

#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <omp.h>

#include "errfield/conditional_simulation.hpp"
#include "errfield/kriging.hpp"

namespace {

using P3 = Eigen::Vector3d;

struct Data {
  std::vector<P3> points;
  std::vector<double> values;
};

Data simulate(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::normal_distribution<double> e(0.0, 0.01);
  Data d;
  d.points.reserve(n);
  d.values.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const P3 p(u(rng), u(rng), u(rng));
    d.points.push_back(p);
    d.values.push_back(std::sin(p.x() / 150.0) * std::cos(p.y() / 200.0) + 0.0005 * p.z() + e(rng));
  }
  return d;
}

std::vector<P3> simulate_targets(std::size_t m, unsigned seed) { return simulate(m, seed).points; }

double max_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

void run(benchmark::State& state, errfield::KrigingOptions opt, const char* model_text) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto m = static_cast<std::size_t>(state.range(1));
  opt.threads = static_cast<int>(state.range(2));
  opt.compute_variance = state.range(3) != 0;
  const Data d = simulate(n, 1);
  const auto targets = simulate_targets(m, 2);
  const auto model = errfield::VariogramModel::parse(model_text);
  for (auto _ : state) {
    errfield::Kriging<P3, double> k(d.points, d.values, model, opt);
    if (!k.report().usable()) state.SkipWithError(k.report().message.c_str());
    auto p = k.predict(targets);
    benchmark::DoNotOptimize(p.mean.data());
  }
  state.counters["samples"] = static_cast<double>(n);
  state.counters["targets"] = static_cast<double>(m);
  state.counters["targets_per_s"] = benchmark::Counter(static_cast<double>(m), benchmark::Counter::kIsRate);
  state.counters["max_rss_MiB"] = max_rss_mib();
}

void BM_KrigingDense(benchmark::State& state) {
  errfield::KrigingOptions opt;  // ordinary, dense, with variance
  run(state, opt, "sph(sill=1,range=300)+nug(0.01)");
}
BENCHMARK(BM_KrigingDense)
    ->ArgNames({"N", "targets", "threads", "variance"})
    ->Args({500, 100000, 2, 1})
    ->Args({2000, 100000, 2, 1})
    ->Args({2000, 100000, 1, 1})
    ->Args({5000, 100000, 2, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// Closed-form leave-one-out of dense ordinary kriging (what `errfield fit` prints for the kriging
// methods): the factorization is made once outside the timed loop; the loop times leave_one_out().
void BM_KrigingLeaveOneOut(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  errfield::KrigingOptions opt;
  opt.threads = static_cast<int>(state.range(1));
  const Data d = simulate(n, 1);
  const auto model = errfield::VariogramModel::parse("sph(sill=1,range=300)+nug(0.01)");
  const errfield::Kriging<P3, double> k(d.points, d.values, model, opt);
  if (!k.report().usable()) state.SkipWithError(k.report().message.c_str());
  for (auto _ : state) {
    auto cv = k.leave_one_out();
    benchmark::DoNotOptimize(cv.residual.data());
  }
  state.counters["samples"] = static_cast<double>(n);
  state.counters["max_rss_MiB"] = max_rss_mib();
}
BENCHMARK(BM_KrigingLeaveOneOut)
    ->ArgNames({"N", "threads"})
    ->Args({2000, 1})
    ->Args({4000, 1})
    ->Args({4000, 2})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

void BM_KrigingLocal(benchmark::State& state) {
  errfield::KrigingOptions opt;
  opt.backend = errfield::KrigingBackend::Local;
  opt.neighbors = 32;
  run(state, opt, "sph(sill=1,range=300)+nug(0.01)");
}
BENCHMARK(BM_KrigingLocal)
    ->ArgNames({"N", "targets", "threads", "variance"})
    ->Args({100000, 100000, 2, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

void BM_KrigingSparse(benchmark::State& state) {
  errfield::KrigingOptions opt;
  opt.backend = errfield::KrigingBackend::Sparse;
  run(state, opt, "sph(sill=1,range=45)+nug(0.01)");
}
BENCHMARK(BM_KrigingSparse)
    ->ArgNames({"N", "targets", "threads", "variance"})
    ->Args({100000, 100000, 2, 0})
    ->Args({100000, 1000, 2, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

void BM_ConditionalSimulationLocal(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto m = static_cast<std::size_t>(state.range(1));
  errfield::KrigingOptions opt;
  opt.backend = errfield::KrigingBackend::Local;
  opt.neighbors = 20;
  opt.threads = static_cast<int>(state.range(3));
  errfield::SimulationOptions so;
  so.draws = static_cast<std::size_t>(state.range(2));
  so.method = errfield::UnconditionalMethod::Sequential;
  const Data d = simulate(n, 1);
  const auto targets = simulate_targets(m, 2);
  const auto model = errfield::VariogramModel::parse("sph(sill=1,range=300)+nug(0.01)");
  for (auto _ : state) {
    const auto r = errfield::simulate_conditional<P3, double>(d.points, d.values, targets, model, opt, so);
    if (!r.usable()) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r.draws.data());
  }
  state.counters["samples"] = static_cast<double>(n);
  state.counters["targets"] = static_cast<double>(m);
  state.counters["draws"] = static_cast<double>(so.draws);
  state.counters["max_rss_MiB"] = max_rss_mib();
}
// Issue 36's job against gstat's krige(nsim = 100, nmax = 24) (benchmarks/peers/gstat_simulation_timing.R
// writes the same data): 100 draws at the 10,000 nodes of a 100 x 100 grid from 300 samples, local
// back end with 24 neighbours, sequential unconditional field (60 neighbours). The library part of
// `errfield interpolate ... --simulations 100` (the CSV of a million cells is the rest); the
// 1-thread case is its CPU time. Figures: docs/kriging.md ("Against gstat").
void BM_ConditionalSimulationGrid2d(benchmark::State& state) {
  using P2 = Eigen::Vector2d;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> e(0.0, 0.2);
  std::vector<P2> samples;
  std::vector<double> values;
  for (int i = 0; i < 300; ++i) {
    const P2 p(u(rng), u(rng));
    samples.push_back(p);
    values.push_back(std::sin(p.x() / 15.0) + std::cos(p.y() / 20.0) + e(rng));
  }
  std::vector<P2> nodes;
  for (int j = 0; j < 100; ++j)
    for (int i = 0; i < 100; ++i) nodes.emplace_back(i + 0.5, j + 0.5);
  errfield::KrigingOptions opt;
  opt.backend = errfield::KrigingBackend::Local;
  opt.neighbors = 24;
  opt.threads = static_cast<int>(state.range(1));
  errfield::SimulationOptions so;
  so.draws = 100;
  so.method = errfield::UnconditionalMethod::Sequential;
  so.draws_per_path = static_cast<std::size_t>(state.range(0));
  const auto model = errfield::VariogramModel::parse("sph(sill=1,range=30)+nug(0.05)");
  const int before = omp_get_max_threads();
  omp_set_num_threads(opt.threads);  // the path's parallel loops too, as OMP_NUM_THREADS sets them for the CLI
  for (auto _ : state) {
    const auto r = errfield::simulate_conditional<P2, double>(samples, values, nodes, model, opt, so);
    if (!r.usable()) state.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r.draws.data());
  }
  omp_set_num_threads(before);
  state.counters["max_rss_MiB"] = max_rss_mib();
}
BENCHMARK(BM_ConditionalSimulationGrid2d)
    ->ArgNames({"per_path", "threads"})
    ->Args({100, 2})
    ->Args({100, 1})
    ->Args({10, 2})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

BENCHMARK(BM_ConditionalSimulationLocal)
    ->ArgNames({"N", "targets", "draws", "threads"})
    ->Args({2000, 10000, 100, 2})
    ->Args({2000, 10000, 100, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
