// Likelihood fits and anisotropic prediction (docs/benchmarks.md, section "Likelihood fits").
// SIMULATED data: N points uniform in [0,100]^D, C components of a smooth field + noise.
//
//   BM_RemlArd       : REML fit with one range per coordinate (ARD), Matérn 5/2 + nugget, ordinary
//                      kriging's likelihood; {N, D, C, local L-BFGS runs}. The case is
//                      {700, 6, 3, 1} (one start, like sklearn's default) and {700, 6, 3, 2} (the
//                      library's default).
//   BM_RemlVecchia   : the same REML ARD fit by the Vecchia likelihood (30 max-min neighbours, one
//                      local run from 4 screened starts, as the robot fit's refit); {N, D, C}: the
//                      robot's {5000, 6, 3} and a large map's {50000, 3, 1}.
//   BM_ModelChoice   : choose_likelihood_model (`interpolate --model auto`) on a 2-D scalar field;
//                      {N, fast}: ModelChoiceOptions::fast() (the CLI's default, issue 49's target:
//                      <= 1 s at N = 1,000 on 2 cores) or the defaults (--auto-search thorough).
//   BM_PredictIso/Ard: dense kriging prediction of 20,000 targets from N = 2,000 samples in 6-D
//                      with an isotropic and with an ARD model (same set-up otherwise); {threads}.

#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "errfield/kriging.hpp"
#include "errfield/kriging_likelihood.hpp"

namespace {

Eigen::MatrixXd points(int n, int d, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  Eigen::MatrixXd x(n, d);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) x(i, k) = u(rng);
  return x;
}

// Smooth in the first coordinates, slower in the later ones, plus noise.
Eigen::MatrixXd values(const Eigen::MatrixXd& x, int c, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> e(0.0, 0.05);
  Eigen::MatrixXd z(x.rows(), c);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < c; ++k) {
      double s = 0.0;
      for (Eigen::Index j = 0; j < x.cols(); ++j) s += std::sin(x(i, j) / (8.0 * (j + 1)) + k);
      z(i, k) = s + e(rng);
    }
  return z;
}

void BM_ModelChoice(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd x = points(n, 2, 5);
  const Eigen::MatrixXd z = values(x, 1, 6);
  errfield::ModelChoiceOptions o = state.range(1) ? errfield::ModelChoiceOptions::fast() : errfield::ModelChoiceOptions{};
  o.fit.standard_errors = false;
  if (!state.range(1)) {
    o.ranking_starts = 4;
    o.ranking_local_runs = 1;
  }
  for (auto _ : state) benchmark::DoNotOptimize(errfield::choose_likelihood_model(x, z, o));
}

void BM_RemlArd(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), d = static_cast<int>(state.range(1)), c = static_cast<int>(state.range(2));
  const Eigen::MatrixXd x = points(n, d, 1);
  const Eigen::MatrixXd z = values(x, c, 2);
  errfield::ModelComponent mat;
  mat.kind = errfield::ModelKind::Matern;
  mat.nu = 2.5;
  errfield::LikelihoodFitOptions o;
  o.anisotropy = errfield::LikelihoodFitOptions::Anisotropy::Ard;
  o.local_runs = static_cast<int>(state.range(3));
  int evaluations = 0;
  for (auto _ : state) {
    const auto r = errfield::fit_likelihood(x, z, {mat}, o);
    evaluations = r.evaluations;
    benchmark::DoNotOptimize(r.negative_log_likelihood);
  }
  state.counters["evaluations"] = evaluations;
}
BENCHMARK(BM_RemlArd)->Args({700, 6, 3, 1})->Args({700, 6, 3, 2})->Args({300, 6, 3, 2})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RemlVecchia(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)), d = static_cast<int>(state.range(1)), c = static_cast<int>(state.range(2));
  const Eigen::MatrixXd x = points(n, d, 1);
  const Eigen::MatrixXd z = values(x, c, 2);
  errfield::ModelComponent mat;
  mat.kind = errfield::ModelKind::Matern;
  mat.nu = 2.5;
  errfield::LikelihoodFitOptions o;
  o.anisotropy = errfield::LikelihoodFitOptions::Anisotropy::Ard;
  o.method = errfield::LikelihoodMethod::Vecchia;
  o.starts = 4;
  o.local_runs = 1;
  int evaluations = 0;
  for (auto _ : state) {
    const auto r = errfield::fit_likelihood(x, z, {mat}, o);
    evaluations = r.evaluations;
    benchmark::DoNotOptimize(r.negative_log_likelihood);
  }
  state.counters["evaluations"] = evaluations;
}
BENCHMARK(BM_ModelChoice)->Args({1000, 1})->Args({595, 1})->Args({1000, 0})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_RemlVecchia)->Args({5000, 6, 3})->Args({50000, 3, 1})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// `scale` divides every coordinate (samples and targets) before kriging: an isotropic model on
// coordinates mapped by hand, whose lags are exactly those of the ARD model with the same scales,
// so BM_PredictIsoMapped against BM_PredictArd measures only what the anisotropy costs.
void predict(benchmark::State& state, const char* model_text, const std::vector<double>& scale = {}) {
  Eigen::MatrixXd x = points(2000, 6, 3), t = points(20000, 6, 4);
  const Eigen::MatrixXd z = values(x, 1, 5);
  for (std::size_t a = 0; a < scale.size(); ++a) {
    x.col(static_cast<Eigen::Index>(a)) /= scale[a];
    t.col(static_cast<Eigen::Index>(a)) /= scale[a];
  }
  std::vector<Eigen::VectorXd> s, q;
  std::vector<double> v;
  for (Eigen::Index i = 0; i < x.rows(); ++i) s.push_back(x.row(i).transpose()), v.push_back(z(i, 0));
  for (Eigen::Index i = 0; i < t.rows(); ++i) q.push_back(t.row(i).transpose());
  errfield::KrigingOptions o;
  o.threads = static_cast<int>(state.range(0));
  const errfield::Kriging<Eigen::VectorXd, double> k(s, v, errfield::VariogramModel::parse(model_text), o);
  for (auto _ : state) {
    const auto p = k.predict(q);
    benchmark::DoNotOptimize(p.mean.data());
  }
  state.counters["targets_per_s"] = benchmark::Counter(static_cast<double>(q.size()), benchmark::Counter::kIsIterationInvariantRate);
}
void BM_PredictIso(benchmark::State& state) { predict(state, "mat(sill=1,range=30,nu=2.5)+nug(0.01)"); }
void BM_PredictArd(benchmark::State& state) {
  predict(state, "mat(sill=1,range=30,nu=2.5)+nug(0.01)@ard(0.3,0.5,0.7,1,1,1)");
}
void BM_PredictIsoMapped(benchmark::State& state) {
  predict(state, "mat(sill=1,range=30,nu=2.5)+nug(0.01)", {0.3, 0.5, 0.7, 1, 1, 1});
}
BENCHMARK(BM_PredictIso)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PredictArd)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PredictIsoMapped)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
