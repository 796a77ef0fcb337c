// Choosing where to measure next (errfield/sampling_design.hpp; `errfield plan --candidates`,
// docs/benchmarks.md, section "Sampling design"). SIMULATED joint-space poses: candidates and
// measured poses uniform in a 6-D box of joint angles (degrees).
//
//   BM_SelectMaximin           : greedy maximin batch of 40 from {candidates}, {measured} already taken.
//   BM_SelectByVarianceReduction: integrated variance reduction, batch of 40 (plus a look-ahead of
//                                 200, as `plan --target-rms` uses) under an ARD Matérn 5/2 + nugget
//                                 model, conditioned on {measured} poses, over {candidates};
//                                 issue 21's case is {10000, 500} (target: under 10 s for the plan).
//   BM_SelectByVarianceReductionLinearTerm: the same with a linear term beside the field, as `plan`
//                                 fills it from a model's joint error functions (48 coefficients:
//                                 6 joints x degree 8, 3 components per reading; docs/benchmarks.md).
//   BM_LocalErrorScale          : the leave-one-out local scale `plan --local-scale on` computes at
//                                 every candidate from {measured} poses and their values.

#include <cmath>
#include <random>

#include <benchmark/benchmark.h>

#include "errfield/sampling_design.hpp"
#include "errfield/variogram_model.hpp"

namespace {

Eigen::MatrixXd joint_poses(Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double half_range[6] = {150.0, 80.0, 100.0, 170.0, 110.0, 170.0};
  Eigen::MatrixXd q(n, 6);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < 6; ++j) q(i, j) = std::uniform_real_distribution<double>(-half_range[j], half_range[j])(rng);
  return q;
}

// A model like the ones `fit` estimates in joint space: Matérn 5/2 with one range per joint, a nugget.
errfield::VariogramModel joint_space_model() {
  return errfield::VariogramModel::parse("mat(sill=0.01,range=1,nu=2.5)+nug(sill=0.0004)@ard(60,45,50,200,150,400)");
}

void BM_SelectMaximin(benchmark::State& state) {
  const Eigen::MatrixXd candidates = joint_poses(state.range(0), 1);
  const Eigen::MatrixXd measured = joint_poses(state.range(1), 2);
  errfield::MaximinOptions o;
  o.count = 40;
  for (auto _ : state) benchmark::DoNotOptimize(errfield::select_maximin(candidates, measured, o));
}
BENCHMARK(BM_SelectMaximin)->ArgNames({"candidates", "measured"})->Args({10000, 500})->Unit(benchmark::kMillisecond)->UseRealTime();

errfield::VarianceReductionOptions::LinearTerm joint_functions_term(const Eigen::MatrixXd& candidates,
                                                                    const Eigen::MatrixXd& measured);

// A batch of 40 plus a look-ahead of 200 over state.range(0) candidates, state.range(1) measured.
void select_by_variance_reduction_case(benchmark::State& state, bool with_linear_term) {
  const Eigen::MatrixXd candidates = joint_poses(state.range(0), 1);
  const Eigen::MatrixXd measured = joint_poses(state.range(1), 2);
  const errfield::VariogramModel model = joint_space_model();
  errfield::VarianceReductionOptions o;
  o.count = 40;
  o.lookahead = 200;
  if (with_linear_term) o.linear_term = joint_functions_term(candidates, measured);
  for (auto _ : state) benchmark::DoNotOptimize(errfield::select_by_variance_reduction(candidates, measured, model, o));
}

void BM_SelectByVarianceReduction(benchmark::State& state) { select_by_variance_reduction_case(state, false); }
BENCHMARK(BM_SelectByVarianceReduction)
    ->ArgNames({"candidates", "measured"})
    ->Args({2000, 300})
    ->Args({10000, 500})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Joint error functions' design rows: each joint's Legendre polynomials of degree 1..8 of its scaled
// angle times a lever per component (a stand-in for the Jacobian column; a smooth function of the
// pose), and a coefficient covariance of (0.05 mrad)^2 with a mild correlation between neighbours.
constexpr int kJoints = 6, kDegree = 8, kComponents = 3;

Eigen::MatrixXd joint_functions_rows(const Eigen::MatrixXd& poses) {
  Eigen::MatrixXd rows(kComponents * poses.rows(), kJoints * kDegree);
  for (Eigen::Index c = 0; c < poses.rows(); ++c)
    for (int j = 0; j < kJoints; ++j) {
      const double u = poses(c, j) / 180.0;
      double previous = 1.0, current = u;  // Legendre recurrence: P0, P1
      for (int k = 1; k <= kDegree; ++k) {
        for (int m = 0; m < kComponents; ++m)
          rows(kComponents * c + m, j * kDegree + k - 1) = current * 0.5 * std::cos(poses(c, (j + m + 1) % kJoints) / 90.0 + m);
        const double next = ((2 * k + 1) * u * current - k * previous) / (k + 1);
        previous = current;
        current = next;
      }
    }
  return rows;
}

errfield::VarianceReductionOptions::LinearTerm joint_functions_term(const Eigen::MatrixXd& candidates,
                                                                    const Eigen::MatrixXd& measured) {
  constexpr int p = kJoints * kDegree;
  errfield::VarianceReductionOptions::LinearTerm term;
  term.components = kComponents;
  term.candidate_rows = joint_functions_rows(candidates);
  term.measured_rows = joint_functions_rows(measured);
  term.covariance = Eigen::MatrixXd::Identity(p, p);
  for (int i = 0; i + 1 < p; ++i) term.covariance(i, i + 1) = term.covariance(i + 1, i) = 0.3;
  term.covariance *= 0.05 * 0.05;
  return term;
}

void BM_SelectByVarianceReductionLinearTerm(benchmark::State& state) { select_by_variance_reduction_case(state, true); }
BENCHMARK(BM_SelectByVarianceReductionLinearTerm)
    ->ArgNames({"candidates", "measured"})
    ->Args({10000, 500})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_LocalErrorScale(benchmark::State& state) {
  const Eigen::MatrixXd candidates = joint_poses(state.range(0), 1);
  const Eigen::MatrixXd measured = joint_poses(state.range(1), 2);
  Eigen::MatrixXd values(measured.rows(), 3);
  for (Eigen::Index i = 0; i < measured.rows(); ++i)
    for (int k = 0; k < 3; ++k) values(i, k) = 0.1 * std::sin(measured(i, 1) / 40.0 + k) * std::cos(measured(i, 2) / 55.0);
  const errfield::VariogramModel model = joint_space_model();
  for (auto _ : state) benchmark::DoNotOptimize(errfield::local_error_scale(measured, values, model, candidates));
}
BENCHMARK(BM_LocalErrorScale)->ArgNames({"candidates", "measured"})->Args({10000, 500})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
