// The Vecchia likelihood (LikelihoodMethod::Vecchia): with every predecessor as a neighbour it is
// the exact likelihood (an identity, checked against a dense formula written here and against the
// exact path, for every ordering); its analytic gradient against central finite differences; the
// same bits on 1 and 2 threads; the neighbour sets against a brute-force search; and, at N = 400
// with 30 neighbours, its value and fitted parameters close to the exact ones. SIMULATED fields.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <omp.h>

#include "errfield/error.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "kriging/likelihood_profile.hpp"
#include "kriging/likelihood_vecchia.hpp"
#include "kriging/vecchia_neighbours.hpp"

namespace errfield {
namespace likelihood_vecchia_test {

// SIMULATED: N points in [0,100]^D, C components of a Gaussian field with an ARD Matérn 3/2
// covariance (ranges a) + white noise, from a dense Cholesky factor.
struct Field {
  Eigen::MatrixXd x, z;
};
Field simulate(int n, const Eigen::VectorXd& a, double noise, int c, unsigned seed) {
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
      cov(i, j) = (1.0 + r) * std::exp(-r) + (i == j ? noise : 0.0);
    }
  Eigen::MatrixXd e(n, c);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < c; ++k) e(i, k) = g(rng);
  f.z = cov.llt().matrixL() * e;
  f.z.array() += 2.0;
  return f;
}

// Ordinary-kriging REML by the dense formula, for an isotropic exp(sill, range) + nugget:
// 0.5 [C log|K| + C log|1'K^-1 1| + sum_c (z_c - b_c)'K^-1(z_c - b_c) + C (N - 1) log 2 pi].
double dense_reml(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, double sill, double range, double nugget) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd k(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      k(i, j) = sill * std::exp(-(x.row(i) - x.row(j)).norm() / range) + (i == j ? nugget : 0.0);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(k);
  const double logdet = ldlt.vectorD().array().log().sum();
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  const Eigen::VectorXd kinv1 = ldlt.solve(ones);
  const double g = ones.dot(kinv1);
  double quad = 0.0;
  for (Eigen::Index c = 0; c < z.cols(); ++c) {
    const double mean = kinv1.dot(z.col(c)) / g;
    const Eigen::VectorXd r = z.col(c).array() - mean;
    quad += r.dot(ldlt.solve(r));
  }
  const double cc = static_cast<double>(z.cols());
  return 0.5 * (cc * logdet + cc * std::log(g) + quad + cc * static_cast<double>(n - 1) * std::log(2.0 * std::numbers::pi));
}

LikelihoodFitOptions vecchia(int m, VecchiaOrdering ordering = VecchiaOrdering::MaxMin) {
  LikelihoodFitOptions o;
  o.method = LikelihoodMethod::Vecchia;
  o.vecchia_neighbours = m;
  o.vecchia_ordering = ordering;
  return o;
}

ModelComponent component(ModelKind kind, double nu = 0.5) {
  ModelComponent c;
  c.kind = kind;
  c.nu = nu;
  return c;
}

TEST(VecchiaLikelihood, WithEveryPredecessorEqualsTheDenseFormula) {
  const Field f = simulate(60, Eigen::Vector3d(30, 50, 80), 0.05, 2, 11);
  const VariogramModel model = VariogramModel::parse("exp(sill=1.3,range=40) + nug(sill=0.07)");
  const double reference = dense_reml(f.x, f.z, 1.3, 40.0, 0.07);
  for (const auto ordering : {VecchiaOrdering::MaxMin, VecchiaOrdering::Random, VecchiaOrdering::Coordinate})
    EXPECT_NEAR(negative_log_likelihood(f.x, f.z, model, vecchia(59, ordering)), reference, 1e-10 * std::abs(reference))
        << "ordering " << static_cast<int>(ordering);
}

TEST(VecchiaLikelihood, WithEveryPredecessorEqualsTheExactPathForEveryKindOfMean) {
  const Field f = simulate(50, Eigen::Vector3d(30, 50, 80), 0.05, 3, 12);
  LikelihoodFitOptions exact;
  exact.method = LikelihoodMethod::Exact;
  const std::vector<VariogramModel> models{
      VariogramModel::parse("mat(sill=1,range=30,nu=1.5) + nug(sill=0.05)"),
      VariogramModel::parse("sph(sill=0.6,range=70) + gau(sill=0.5,range=25) + nug(sill=0.02)"),
      VariogramModel(VariogramModel::parse("exp(sill=1,range=60) + nug(sill=0.1)").components(),
                     Anisotropy::ard({0.4, 0.7, 1.0}))};
  for (const auto& model : models)
    for (int variant = 0; variant < 4; ++variant) {
      LikelihoodFitOptions e = exact, v = vecchia(49);
      for (auto* o : {&e, &v}) {
        o->restricted = variant != 1;
        o->kind = variant == 2 ? KrigingKind::Universal : variant == 3 ? KrigingKind::Simple : KrigingKind::Ordinary;
        o->simple_mean = 2.0;
      }
      const double want = negative_log_likelihood(f.x, f.z, model, e);
      EXPECT_NEAR(negative_log_likelihood(f.x, f.z, model, v), want, 1e-10 * std::abs(want))
          << model.to_string() << " variant " << variant;
    }
}

TEST(VecchiaLikelihood, ProfiledWithEveryPredecessorEqualsTheExactProfileAndItsGradient) {
  const Field f = simulate(45, Eigen::Vector3d(30, 50, 80), 0.05, 2, 13);
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(45, 1);
  const detail::VecchiaNeighbours nb = detail::find_vecchia_neighbours(f.x.transpose(), 44, VecchiaOrdering::MaxMin);
  const std::vector<double> log_ranges{std::log(35.0), std::log(60.0), std::log(90.0)};
  const double g = 0.06;
  Eigen::MatrixXd u = f.x.transpose();
  for (int k = 0; k < 3; ++k) u.row(k) /= std::exp(log_ranges[static_cast<std::size_t>(k)]);
  std::vector<double> theta = log_ranges;
  theta.push_back(std::log(g));
  const ModelComponent s = component(ModelKind::Matern, 2.5);
  std::vector<double> exact_gradient;
  double exact_sigma2 = 0.0, sigma2 = 0.0;
  const double want = detail::profiled_negative_log_likelihood(f.x, f.z, ones, s, true, true, true, theta,
                                                              &exact_gradient, &exact_sigma2);
  std::vector<double> gradient(4);
  const double got = detail::vecchia_profiled_nll(u, f.z, ones, nb, detail::correlation_of(s), g, true, true, true,
                                                  gradient.data(), &sigma2);
  EXPECT_NEAR(got, want, 1e-10 * std::abs(want));
  EXPECT_NEAR(sigma2, exact_sigma2, 1e-10 * exact_sigma2);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(gradient[i], exact_gradient[i], 1e-7 * std::max(1.0, std::abs(want)));
}

TEST(VecchiaLikelihood, GradientMatchesCentralFiniteDifferences) {
  const Field f = simulate(70, Eigen::Vector3d(20, 40, 70), 0.05, 2, 14);
  const Eigen::Index n = f.x.rows();
  // Universal drift of order 1 (4 columns), so the REML and GLS terms of the gradient all count.
  Eigen::MatrixXd drift(n, 4);
  drift.col(0).setOnes();
  drift.rightCols(3) = (f.x.array() - 50.0) / 50.0;
  const Eigen::MatrixXd none(n, 0);
  const detail::VecchiaNeighbours nb = detail::find_vecchia_neighbours(f.x.transpose(), 8, VecchiaOrdering::MaxMin);
  for (const auto& s : {component(ModelKind::Spherical), component(ModelKind::Exponential), component(ModelKind::Gaussian),
                        component(ModelKind::Wendland), component(ModelKind::Matern, 1.5), component(ModelKind::Matern, 2.5)})
    for (const bool ard : {false, true})
      for (const bool restricted : {false, true}) {
        const Eigen::MatrixXd& fm = restricted ? drift : none;
        std::vector<double> theta = ard ? std::vector<double>{std::log(90.0), std::log(120.0), std::log(150.0)}
                                        : std::vector<double>{std::log(110.0)};
        theta.push_back(std::log(0.07));
        auto nll = [&](const std::vector<double>& t, double* grad) {
          Eigen::MatrixXd u = f.x.transpose();
          for (int k = 0; k < 3; ++k) u.row(k) /= std::exp(t[static_cast<std::size_t>(ard ? k : 0)]);
          return detail::vecchia_profiled_nll(u, f.z, fm, nb, detail::correlation_of(s), std::exp(t.back()), ard, true,
                                              restricted, grad, nullptr);
        };
        std::vector<double> grad(theta.size());
        nll(theta, grad.data());
        for (std::size_t i = 0; i < theta.size(); ++i) {
          const double h = 1e-5;  // as the exact profile's test: truncation ~1e-10, rounding ~1e-9
          std::vector<double> tp = theta, tm = theta;
          tp[i] += h;
          tm[i] -= h;
          const double fd = (nll(tp, nullptr) - nll(tm, nullptr)) / (2.0 * h);
          EXPECT_NEAR(grad[i], fd, 1e-6 * std::max(1.0, std::abs(fd)))
              << model_kind_name(s.kind) << " nu " << s.nu << (ard ? " ard" : " iso")
              << (restricted ? " reml universal" : " ml simple") << " parameter " << i;
        }
      }
}

TEST(VecchiaLikelihood, SameBitsOnOneAndTwoThreads) {
  const Field f = simulate(300, Eigen::Vector2d(20, 40), 0.05, 2, 15);
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(300, 1);
  const int before = omp_get_max_threads();
  double value[2];
  std::vector<double> gradient[2];
  std::vector<Eigen::Index> sets[2];
  for (int t = 0; t < 2; ++t) {
    omp_set_num_threads(t + 1);
    const detail::VecchiaNeighbours nb = detail::find_vecchia_neighbours(f.x.transpose() / 30.0, 20, VecchiaOrdering::MaxMin);
    sets[t] = nb.sets;
    gradient[t].resize(3);
    value[t] = detail::vecchia_profiled_nll(f.x.transpose() / 30.0, f.z, ones, nb,
                                            detail::correlation_of(component(ModelKind::Matern, 1.5)), 0.05, true, true,
                                            true, gradient[t].data(), nullptr);
  }
  omp_set_num_threads(before);
  EXPECT_EQ(sets[0], sets[1]);
  EXPECT_EQ(value[0], value[1]);
  EXPECT_EQ(gradient[0], gradient[1]);
}

TEST(VecchiaNeighbours, AreTheNearestPredecessorsFoundByBruteForce) {
  const Field f = simulate(700, Eigen::Vector3d(30, 30, 30), 0.05, 1, 16);
  const Eigen::MatrixXd p = f.x.transpose();
  for (const auto ordering : {VecchiaOrdering::MaxMin, VecchiaOrdering::Random, VecchiaOrdering::Coordinate}) {
    const detail::VecchiaNeighbours nb = detail::find_vecchia_neighbours(p, 12, ordering);
    ASSERT_EQ(nb.order.size(), 700u);
    std::vector<Eigen::Index> sorted = nb.order;
    std::sort(sorted.begin(), sorted.end());
    for (Eigen::Index i = 0; i < 700; ++i) ASSERT_EQ(sorted[static_cast<std::size_t>(i)], i);
    for (std::size_t i = 0; i < 700; ++i) {
      std::vector<double> d;
      for (std::size_t j = 0; j < i; ++j) d.push_back((p.col(nb.order[i]) - p.col(nb.order[j])).squaredNorm());
      std::sort(d.begin(), d.end());
      const std::size_t k = nb.offsets[i + 1] - nb.offsets[i];
      ASSERT_EQ(k, std::min<std::size_t>(i, 12));
      for (std::size_t a = 0; a < k; ++a)
        ASSERT_EQ((p.col(nb.order[i]) - p.col(nb.sets[nb.offsets[i] + a])).squaredNorm(), d[a])
            << "ordering " << static_cast<int>(ordering) << " position " << i << " neighbour " << a;
    }
  }
  // Max-min: each next point is the farthest from those placed (checked for the first 50).
  const detail::VecchiaNeighbours nb = detail::find_vecchia_neighbours(p, 12, VecchiaOrdering::MaxMin);
  for (std::size_t i = 1; i < 50; ++i) {
    auto gap = [&](Eigen::Index q) {
      double m = 1e300;
      for (std::size_t j = 0; j < i; ++j) m = std::min(m, (p.col(q) - p.col(nb.order[j])).squaredNorm());
      return m;
    };
    double farthest = 0.0;
    for (std::size_t j = i; j < 700; ++j) farthest = std::max(farthest, gap(nb.order[j]));
    EXPECT_EQ(gap(nb.order[i]), farthest) << "position " << i;
  }
}

TEST(VecchiaLikelihood, ThirtyNeighboursAgreeWithTheExactFitAtFourHundredSamples) {
  const Field f = simulate(400, Eigen::Vector2d(15, 35), 0.1, 1, 17);
  LikelihoodFitOptions exact, approx = vecchia(30);
  exact.method = LikelihoodMethod::Exact;
  for (auto* o : {&exact, &approx}) {
    o->anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
    o->starts = 3;
    o->local_runs = 1;
  }
  const ModelComponent s = component(ModelKind::Matern, 1.5);
  const LikelihoodFitResult e = fit_likelihood(f.x, f.z, {s}, exact);
  const LikelihoodFitResult v = fit_likelihood(f.x, f.z, {s}, approx);
  // At the exact estimate the approximate log-density differs by less than 0.01 per sample (the
  // study below: +6.4 at N = 1000 with a 10 % nugget, which slows Vecchia's convergence in m).
  const double at_exact = negative_log_likelihood(f.x, f.z, e.model, approx);
  EXPECT_NEAR(at_exact, e.negative_log_likelihood, 0.01 * 400);
  std::printf("exact: %s (ranges %g +- %g, %g +- %g)\nvecchia: %s (ranges %g, %g)\n", e.model.to_string().c_str(),
              e.ranges[0], e.range_standard_errors[0], e.ranges[1], e.range_standard_errors[1],
              v.model.to_string().c_str(), v.ranges[0], v.ranges[1]);
  ASSERT_EQ(v.ranges.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k)
    EXPECT_NEAR(v.ranges[k], e.ranges[k], 2.0 * e.range_standard_errors[k]) << "range " << k;
  const double nugget_ratio_e = e.model.nugget() / e.model.sill(), nugget_ratio_v = v.model.nugget() / v.model.sill();
  EXPECT_NEAR(nugget_ratio_v, nugget_ratio_e, 0.25 * nugget_ratio_e);
}

TEST(VecchiaLikelihood, ModelChoiceRefitsAllSamplesByVecchiaFromTheSubsetsEstimate) {
  // As the robot fit beyond 3,000 samples, scaled down: the family chosen on a subset of 60, the
  // refit of all 200 by the Vecchia likelihood (forced here), started from the subset's estimate.
  const Field f = simulate(200, Eigen::Vector2d(15, 35), 0.1, 1, 18);
  ModelChoiceOptions o;
  o.fit.method = LikelihoodMethod::Vecchia;
  o.fit.vecchia_neighbours = 20;
  o.fit.starts = 3;
  o.fit.local_runs = 1;
  o.kinds = {ModelKind::Matern};
  o.matern_nu = {1.5};
  o.try_isotropic = false;
  o.choice_subsample = 60;
  const ModelChoice choice = choose_likelihood_model(f.x, f.z, o);
  EXPECT_NE(choice.reason.find("refitted on all"), std::string::npos) << choice.reason;
  EXPECT_NE(choice.fit.message.find("Vecchia likelihood, 20 neighbours"), std::string::npos) << choice.fit.message;
  EXPECT_GT(choice.model.nugget(), 0.0);
  EXPECT_EQ(choice.model.anisotropy().type(), Anisotropy::Type::Ard);
  // The refit is a local optimum of the Vecchia likelihood it reports: nudging the nugget or all
  // ranges together (which leaves the neighbour sets as they are) does not lower it. (Nudging one
  // ARD range changes the sets, and with them the approximation, by a few tenths here.)
  LikelihoodFitOptions v = vecchia(20);
  const double at = negative_log_likelihood(f.x, f.z, choice.model, v);
  EXPECT_NEAR(at, choice.fit.negative_log_likelihood, 1e-9 * std::abs(at));
  for (const double factor : {0.97, 1.03}) {
    std::vector<ModelComponent> c = choice.model.components();
    c.back().sill *= factor;  // the nugget
    EXPECT_GE(negative_log_likelihood(f.x, f.z, VariogramModel(c, choice.model.anisotropy()), v), at - 1e-6);
    std::vector<ModelComponent> r = choice.model.components();
    r.front().range *= factor;
    EXPECT_GE(negative_log_likelihood(f.x, f.z, VariogramModel(r, choice.model.anisotropy()), v), at - 1e-6);
  }
}

TEST(VecchiaLikelihood, BudgetsAreCheckedBeforeAnyWork) {
  LikelihoodFitOptions exact;
  exact.method = LikelihoodMethod::Exact;
  EXPECT_THROW(check_likelihood_budget(kMaxLikelihoodSamples + 1, 1, exact), ResourceError);
  EXPECT_NO_THROW(check_likelihood_budget(kMaxLikelihoodSamples + 1, 1, LikelihoodFitOptions{}));
  EXPECT_THROW(check_likelihood_budget(kMaxVecchiaLikelihoodSamples + 1, 1, LikelihoodFitOptions{}), ResourceError);
  LikelihoodFitOptions small = vecchia(30);
  small.vecchia_memory_budget_bytes = 1 << 20;
  EXPECT_THROW(check_likelihood_budget(100000, 3, small), ResourceError);
  LikelihoodFitOptions bad = vecchia(0);
  EXPECT_THROW(bad.validate(), ArgumentError);
}

}  // namespace likelihood_vecchia_test
}  // namespace errfield

namespace errfield {
namespace likelihood_vecchia_test {

// Not run in CI: how the Vecchia REML of a fixed model approaches the exact one as m grows, per
// ordering (docs/kriging.md, "Vecchia likelihood").
TEST(VecchiaAccuracyStudy, NllAgainstNeighboursAndOrdering) {
  const Field f = simulate(1000, Eigen::Vector2d(15, 35), 0.1, 1, 17);
  const VariogramModel model(VariogramModel::parse("mat(sill=1,range=35,nu=1.5) + nug(sill=0.1)").components(),
                             Anisotropy::ard({15.0 / 35.0, 1.0}));
  LikelihoodFitOptions exact;
  exact.method = LikelihoodMethod::Exact;
  const double want = negative_log_likelihood(f.x, f.z, model, exact);
  std::printf("exact REML nll %.4f (N = 1000)\n", want);
  for (const auto ordering : {VecchiaOrdering::MaxMin, VecchiaOrdering::Random, VecchiaOrdering::Coordinate})
    for (const int m : {5, 10, 20, 30, 50, 100}) {
      const double got = negative_log_likelihood(f.x, f.z, model, vecchia(m, ordering));
      std::printf("ordering %d m %3d: nll - exact = %+.4f\n", static_cast<int>(ordering), m, got - want);
    }
}

}  // namespace likelihood_vecchia_test
}  // namespace errfield
