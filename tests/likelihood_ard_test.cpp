// Likelihood fits with ARD and vector values: the analytic gradient against central finite
// differences, the profiled likelihood against the plain formula at the profiled sill, vector =
// sum of its components, recovery of known ranges on a SIMULATED anisotropic field (within three
// standard errors), and the automatic model choice refusing ill-conditioned candidates.

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "errfield/kriging_likelihood.hpp"
#include "kriging/likelihood_profile.hpp"

namespace errfield {
namespace likelihood_ard_test {

// SIMULATED: N points in [0,100]^D, C components of a Gaussian field with an ARD Matérn 5/2
// covariance (ranges a_k) + white noise, drawn from the Cholesky factor written here.
struct Field {
  Eigen::MatrixXd x, z;
};
Field simulate(int n, const Eigen::VectorXd& a, double sill, double noise, int c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const int d = static_cast<int>(a.size());
  Field f;
  f.x.resize(n, d);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) f.x(i, k) = u(rng);
  Eigen::MatrixXd cov(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double r = (f.x.row(i) - f.x.row(j)).transpose().cwiseQuotient(a).norm();
      cov(i, j) = sill * (1.0 + r + r * r / 3.0) * std::exp(-r) + (i == j ? noise : 0.0);
    }
  Eigen::MatrixXd e(n, c);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < c; ++k) e(i, k) = g(rng);
  f.z = cov.llt().matrixL() * e;
  f.z.array() += 1.0;
  return f;
}

ModelComponent component(ModelKind kind, double nu = 0.5) {
  ModelComponent c;
  c.kind = kind;
  c.nu = nu;
  return c;
}

TEST(ProfiledLikelihood, GradientMatchesCentralFiniteDifferences) {
  const Field f = simulate(40, Eigen::Vector3d(20, 40, 70), 1.0, 0.05, 2, 3);
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(40, 1), none(40, 0);
  for (const auto& s : {component(ModelKind::Spherical), component(ModelKind::Exponential),
                        component(ModelKind::Gaussian), component(ModelKind::Wendland),
                        component(ModelKind::Matern, 1.5), component(ModelKind::Matern, 2.5)})
    for (const bool ard : {false, true})
      for (const bool restricted : {false, true}) {
        const Eigen::MatrixXd& drift = restricted ? ones : none;
        // Ranges long enough that sph/wen pairs sit well inside their support at these theta.
        std::vector<double> theta = ard ? std::vector<double>{std::log(90.0), std::log(120.0), std::log(150.0)}
                                        : std::vector<double>{std::log(110.0)};
        theta.push_back(std::log(0.07));
        std::vector<double> grad;
        detail::profiled_negative_log_likelihood(f.x, f.z, drift, s, ard, true, restricted, theta, &grad);
        for (std::size_t i = 0; i < theta.size(); ++i) {
          // Central differences: truncation O(h^2 f''') ~ 1e-10 at h = 1e-5 on O(1) derivatives;
          // rounding ~ 1e-16 * |f| / h ~ 1e-9 for |f| ~ 100.
          const double h = 1e-5;
          std::vector<double> tp = theta, tm = theta;
          tp[i] += h;
          tm[i] -= h;
          const double fd = (detail::profiled_negative_log_likelihood(f.x, f.z, drift, s, ard, true, restricted, tp, nullptr) -
                             detail::profiled_negative_log_likelihood(f.x, f.z, drift, s, ard, true, restricted, tm, nullptr)) /
                            (2.0 * h);
          EXPECT_NEAR(grad[i], fd, 1e-6 * std::max(1.0, std::abs(fd)))
              << model_kind_name(s.kind) << " nu " << s.nu << (ard ? " ard" : " iso")
              << (restricted ? " reml" : " ml simple") << " parameter " << i;
        }
      }
}

TEST(ProfiledLikelihood, EqualsThePlainFormulaAtTheProfiledSill) {
  const Field f = simulate(50, Eigen::Vector3d(20, 40, 70), 1.0, 0.05, 3, 4);
  const std::vector<double> theta{std::log(25.0), std::log(35.0), std::log(80.0), std::log(0.04)};
  double sigma2 = 0.0;
  LikelihoodFitOptions o;  // REML, ordinary
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(50, 1);
  const ModelComponent s = component(ModelKind::Matern, 2.5);
  const double profiled = detail::profiled_negative_log_likelihood(f.x, f.z, ones, s, true, true, true, theta, nullptr, &sigma2);
  // The model with one range 80 and ARD multipliers 25/80, 35/80, 1.
  ModelComponent m = s;
  m.sill = sigma2;
  m.range = 80.0;
  ModelComponent nug = component(ModelKind::Nugget);
  nug.sill = 0.04 * sigma2;
  const VariogramModel model({m, nug}, Anisotropy::ard({25.0 / 80.0, 35.0 / 80.0, 1.0}));
  const double plain = negative_log_likelihood(f.x, f.z, model, o);
  EXPECT_NEAR(profiled, plain, 1e-10 * std::abs(plain));
  // A vector value's likelihood is the sum of its components'.
  double sum = 0.0;
  for (int c = 0; c < 3; ++c) sum += negative_log_likelihood(f.x, f.z.col(c), model, o);
  EXPECT_NEAR(plain, sum, 1e-10 * std::abs(sum));
}

TEST(LikelihoodFit, ArdRangesRecoverTheTruthWithinThreeStandardErrors) {
  const Eigen::Vector3d truth(10, 30, 60);
  const Field f = simulate(200, truth, 2.0, 0.05, 3, 11);
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  const LikelihoodFitResult r = fit_likelihood(f.x, f.z, {component(ModelKind::Matern, 2.5)}, o);
  ASSERT_TRUE(r.converged) << r.message;
  ASSERT_EQ(r.ranges.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(std::isfinite(r.range_standard_errors[k]));
    EXPECT_LE(std::abs(r.ranges[k] - truth[k]), 3.0 * r.range_standard_errors[k])
        << "coordinate " << k << ": " << r.ranges[k] << " +- " << r.range_standard_errors[k] << ", truth " << truth[k];
  }
  EXPECT_EQ(r.model.anisotropy().type(), Anisotropy::Type::Ard);
  // The reported likelihood is that of the written model, and no nearby model is more likely.
  EXPECT_NEAR(r.negative_log_likelihood, negative_log_likelihood(f.x, f.z, r.model, o), 1e-9 * std::abs(r.negative_log_likelihood));
  for (double scale : {0.98, 1.02}) {
    std::vector<ModelComponent> c = r.model.components();
    c[0].range *= scale;
    EXPECT_GT(negative_log_likelihood(f.x, f.z, VariogramModel(c, r.model.anisotropy()), o), r.negative_log_likelihood);
    c = r.model.components();
    c[0].sill *= scale;
    EXPECT_GT(negative_log_likelihood(f.x, f.z, VariogramModel(c, r.model.anisotropy()), o), r.negative_log_likelihood);
  }
}

TEST(LikelihoodFit, ArdNeedsOneSupportedStructure) {
  const Field f = simulate(20, Eigen::Vector3d(20, 40, 70), 1.0, 0.05, 1, 5);
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  EXPECT_THROW(fit_likelihood(f.x, f.z, {component(ModelKind::Matern, 1.0)}, o), ArgumentError);
  EXPECT_THROW(fit_likelihood(f.x, f.z, {component(ModelKind::Spherical), component(ModelKind::Exponential)}, o),
               ArgumentError);
}

// 1-norm condition number from the explicit inverse (independent of the fit's estimate).
double condition_1norm(const Eigen::MatrixXd& x, const VariogramModel& m) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd k(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      Eigen::VectorXd d = (x.row(i) - x.row(j)).transpose(), md(d.size());
      m.anisotropy().apply(d.data(), md.data(), static_cast<int>(d.size()));
      k(i, j) = i == j ? m.sill() : m.covariance(md.norm());
    }
  const Eigen::MatrixXd inv = k.inverse();
  return k.cwiseAbs().colwise().sum().maxCoeff() * inv.cwiseAbs().colwise().sum().maxCoeff();
}

TEST(ModelChoice, PicksTheSmallestCriterionAmongWellConditionedFits) {
  const Field f = simulate(50, Eigen::Vector3d(8, 40, 200), 1.0, 0.02, 1, 21);
  ModelChoiceOptions o;
  o.max_condition_number = 1e4;  // strict, so that some candidates are refused
  const ModelChoice choice = choose_likelihood_model(f.x, f.z, o);
  // The limit applies to LAPACK-style 1-norm estimates (Hager/Higham), which in practice are within a
  // factor 3 of the exact value (Higham, Accuracy and Stability, sec. 15.3).
  EXPECT_LE(condition_1norm(f.x, choice.model), 3e4);
  double best = INFINITY;
  for (const auto& c : choice.candidates)
    if (c.accepted) best = std::min(best, c.criterion);
  EXPECT_DOUBLE_EQ(choice.fit.aic, best);
  // Ranges differing by a factor of 25 make ARD clearly more likely than one range.
  EXPECT_EQ(choice.model.anisotropy().type(), Anisotropy::Type::Ard) << choice.reason;
  EXPECT_FALSE(choice.reason.empty());
}

TEST(ModelChoice, TheSubsetDependsOnTheSamplesNotOnTheirOrder) {
  // Beyond choice_subsample the families are compared on a subset; the same rows in another order
  // (a file sorted differently) must see the same subset, hence the same criteria and model. Drawn
  // by row index, the subsets differed and so did the criteria (by whole units of AIC).
  const Field f = simulate(90, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 31);
  std::vector<Eigen::Index> permutation(90);
  for (Eigen::Index i = 0; i < 90; ++i) permutation[static_cast<std::size_t>(i)] = (37 * i + 11) % 90;  // 37 coprime to 90
  const Eigen::MatrixXd x2 = f.x(permutation, Eigen::all), z2 = f.z(permutation, Eigen::all);
  ModelChoiceOptions o;
  o.kinds = {ModelKind::Spherical, ModelKind::Gaussian};
  o.choice_subsample = 40;
  const ModelChoice a = choose_likelihood_model(f.x, f.z, o), b = choose_likelihood_model(x2, z2, o);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t k = 0; k < a.candidates.size(); ++k)
    EXPECT_NEAR(a.candidates[k].criterion, b.candidates[k].criterion, 1e-6 * std::abs(a.candidates[k].criterion)) << k;
  ASSERT_EQ(a.model.components().size(), b.model.components().size());
  EXPECT_EQ(a.model.components().front().kind, b.model.components().front().kind);
  EXPECT_NEAR(a.model.sill(), b.model.sill(), 1e-5 * a.model.sill());
  EXPECT_NEAR(a.model.nugget(), b.model.nugget(), 1e-5 * a.model.sill());
  EXPECT_NE(a.reason.find("random subset of 40 of the 90"), std::string::npos) << a.reason;
}

}  // namespace
}  // namespace errfield
