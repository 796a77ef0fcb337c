// fit_coregionalization (Goulard-Voltz and gstat's fit.lmc) against tables built from known
// models and against linear least squares written out here.

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "errfield/coregionalization_fit.hpp"
#include "errfield/error.hpp"

namespace errfield {
namespace coregionalization_fit_test {

// Bins at lags 20, 45, ..., with pair counts varying so the weightings differ.
CrossVariogramTable table_of(const CoregionalizationModel& m, int bins) {
  CrossVariogramTable t;
  for (int j = 0; j < bins; ++j) {
    const double h = 20.0 + 25.0 * j;
    t.lag.push_back(h);
    t.pairs.push_back(static_cast<std::uint64_t>(50 + 13 * j + (j % 3) * 40));
    t.gamma.push_back(m.gamma_matrix(h));
  }
  return t;
}

std::vector<ModelComponent> template_of(const CoregionalizationModel& m) {
  std::vector<ModelComponent> out;
  for (const auto& s : m.structures()) out.push_back({.kind = s.kind, .sill = 1.0, .range = s.range, .nu = s.nu});
  return out;
}

double weight(const CrossVariogramTable& t, std::size_t j, LmcWeighting w) {
  const double n = static_cast<double>(t.pairs[j]);
  return w == LmcWeighting::Nj ? n : w == LmcWeighting::NjOverH2 ? n / (t.lag[j] * t.lag[j]) : 1.0;
}

// Q(B) = sum_j w_j ||G_j - sum_k B_k g_k(h_j)||_F^2, written out entry by entry.
double objective(const CrossVariogramTable& t, const CoregionalizationModel& m, LmcWeighting w) {
  double q = 0.0;
  for (std::size_t j = 0; j < t.lag.size(); ++j)
    for (int a = 0; a < m.components(); ++a)
      for (int b = 0; b < m.components(); ++b) {
        const double r = t.gamma[j](a, b) - m.gamma(a, b, t.lag[j]);
        q += weight(t, j, w) * r * r;
      }
  return q;
}

// A PSD three-component LMC: nugget, spherical (range 300) and exponential (range 80).
CoregionalizationModel known_model() {
  Eigen::MatrixXd nug(3, 3), sph(3, 3), exp(3, 3);
  nug << 0.05, 0.01, 0.0, 0.01, 0.08, -0.02, 0.0, -0.02, 0.04;
  sph << 1.0, 0.6, -0.3, 0.6, 0.9, -0.1, -0.3, -0.1, 0.5;
  exp << 0.3, -0.1, 0.05, -0.1, 0.2, 0.0, 0.05, 0.0, 0.25;
  return CoregionalizationModel({{.kind = ModelKind::Nugget, .sills = nug},
                                 {.kind = ModelKind::Spherical, .range = 300.0, .sills = sph},
                                 {.kind = ModelKind::Exponential, .range = 80.0, .sills = exp}},
                                {}, {"ex", "ey", "ez"});
}

TEST(CoregionalizationFit, BothMethodsRecoverAKnownLmcFromItsExactVariograms) {
  const CoregionalizationModel truth = known_model();
  const CrossVariogramTable t = table_of(truth, 20);
  for (LmcFitMethod method : {LmcFitMethod::GoulardVoltz, LmcFitMethod::Gstat})
    for (LmcWeighting w : {LmcWeighting::NjOverH2, LmcWeighting::Nj, LmcWeighting::Unweighted}) {
      CoregionalizationFitOptions o;
      o.method = method;
      o.weighting = w;
      const CoregionalizationFitResult r = fit_coregionalization(t, template_of(truth), o, {"ex", "ey", "ez"});
      EXPECT_TRUE(r.converged);
      EXPECT_EQ(r.bins_used, 20u);
      EXPECT_EQ(r.model.component_names(), truth.component_names());
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::MatrixXd& fitted = r.model.structures()[k].sills;
        const Eigen::MatrixXd& expected = truth.structures()[k].sills;
        EXPECT_LT((fitted - expected).cwiseAbs().maxCoeff(), 1e-8)
            << lmc_fit_method_name(method) << " " << lmc_weighting_name(w) << " structure " << k << "\n" << fitted;
        EXPECT_GE(r.smallest_eigenvalue_before_projection[k], 0.0);
      }
      EXPECT_LT(r.weighted_residual, 1e-20);
    }
}

// Exact variograms whose spherical matrix is not PSD (cross sill 1.3 > sqrt(1 x 1)): unconstrained
// fits reproduce it; the LMC must not.
CrossVariogramTable invalid_table() {
  Eigen::MatrixXd nug(2, 2), sph(2, 2);
  nug << 0.1, 0.02, 0.02, 0.2;
  sph << 1.0, 1.3, 1.3, 1.0;
  CrossVariogramTable t;
  for (int j = 0; j < 15; ++j) {
    const double h = 15.0 + 30.0 * j;
    const double g = ModelComponent{.kind = ModelKind::Spherical, .sill = 1.0, .range = 250.0}.gamma(h);
    t.lag.push_back(h);
    t.pairs.push_back(static_cast<std::uint64_t>(100 + 7 * j));
    t.gamma.push_back(nug + g * sph);
  }
  return t;
}

TEST(CoregionalizationFit, GoulardVoltzIsPsdWhenTheUnconstrainedFitIsNotAndNotWorseThanGstat) {
  const CrossVariogramTable t = invalid_table();
  const std::vector<ModelComponent> structures{{.kind = ModelKind::Nugget}, {.kind = ModelKind::Spherical, .range = 250.0}};
  for (LmcWeighting w : {LmcWeighting::NjOverH2, LmcWeighting::Nj, LmcWeighting::Unweighted}) {
    CoregionalizationFitOptions o;
    o.weighting = w;
    const CoregionalizationFitResult gv = fit_coregionalization(t, structures, o);
    o.method = LmcFitMethod::Gstat;
    const CoregionalizationFitResult gs = fit_coregionalization(t, structures, o);
    // The spherical matrix was projected: its eigenvalue 1 - 1.3 = -0.3 before projection in gstat's
    // method, negative in Goulard-Voltz's last update too.
    EXPECT_NEAR(gs.smallest_eigenvalue_before_projection[1], -0.3, 1e-9);
    EXPECT_LT(gv.smallest_eigenvalue_before_projection[1], 0.0);
    for (const CoregionalizationFitResult* r : {&gv, &gs})
      for (const auto& s : r->model.structures()) {
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s.sills);
        EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-12 * eig.eigenvalues().cwiseAbs().maxCoeff());
      }
    EXPECT_TRUE(gv.converged);
    EXPECT_GT(gv.iterations, 1);
    // Both reported residuals are the objective written out above.
    EXPECT_NEAR(gv.weighted_residual, objective(t, gv.model, w), 1e-12 * objective(t, gv.model, w));
    EXPECT_NEAR(gs.weighted_residual, objective(t, gs.model, w), 1e-12 * objective(t, gs.model, w));
    EXPECT_LE(gv.weighted_residual, gs.weighted_residual);
    EXPECT_GT(gv.weighted_residual, 0.0);
    // A constrained minimum: no small PSD-preserving step along a random direction lowers Q.
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<CoregionalizationStructure> moved = gv.model.structures();
      for (auto& s : moved) {
        Eigen::MatrixXd d(2, 2);
        d << g(rng), g(rng), 0.0, g(rng);
        d(1, 0) = d(0, 1);
        const Eigen::MatrixXd candidate = s.sills + 1e-4 * d;
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(candidate);
        if (eig.eigenvalues().minCoeff() >= 0.0) s.sills = candidate;
      }
      EXPECT_GE(objective(t, CoregionalizationModel(moved), w), gv.weighted_residual * (1.0 - 1e-12));
    }
  }
}

TEST(CoregionalizationFit, GstatMethodIsSeparateWeightedLinearLeastSquares) {
  // Noisy symmetric variograms around known_model (simulated noise); normal equations per entry.
  const CoregionalizationModel truth = known_model();
  CrossVariogramTable t = table_of(truth, 18);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 0.01);
  for (auto& m : t.gamma)
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) m(a, b) = m(b, a) = m(a, b) + g(rng);
  const std::vector<ModelComponent> structures = template_of(truth);
  CoregionalizationFitOptions o;
  o.method = LmcFitMethod::Gstat;
  const CoregionalizationFitResult r = fit_coregionalization(t, structures, o);
  Eigen::MatrixXd xtwx = Eigen::MatrixXd::Zero(3, 3);
  std::vector<Eigen::MatrixXd> xtwy(3, Eigen::MatrixXd::Zero(3, 3));
  for (std::size_t j = 0; j < t.lag.size(); ++j) {
    const double w = t.pairs[j] / (t.lag[j] * t.lag[j]);
    Eigen::Vector3d x;
    for (int k = 0; k < 3; ++k) {
      ModelComponent unit = structures[static_cast<std::size_t>(k)];
      x(k) = unit.gamma(t.lag[j]);
    }
    xtwx += w * x * x.transpose();
    for (int k = 0; k < 3; ++k) xtwy[static_cast<std::size_t>(k)] += w * x(k) * t.gamma[j];
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(xtwx);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      Eigen::Vector3d rhs;
      for (int k = 0; k < 3; ++k) rhs(k) = xtwy[static_cast<std::size_t>(k)](a, b);
      const Eigen::Vector3d sills = ldlt.solve(rhs);
      for (int k = 0; k < 3; ++k) {
        ASSERT_GE(r.smallest_eigenvalue_before_projection[static_cast<std::size_t>(k)], 0.0);  // no projection here
        if (a == b) {
          ASSERT_GT(sills(k), 0.0);  // no direct sill fixed at 0 either
        }
        EXPECT_NEAR(r.model.structures()[static_cast<std::size_t>(k)].sills(a, b), sills(k), 1e-10)
            << "entry " << a << "," << b << " structure " << k;
      }
    }
}

TEST(CoregionalizationFit, GstatMethodFixesNegativeDirectSillsAtZeroAndRefits) {
  // Component 0's direct variogram is 1.2 g_sph(h) - 0.05: unconstrained its nugget is -0.05; gstat's
  // fit.variogram fixes it at 0 and refits the spherical sill alone: sum w x y / sum w x^2.
  CrossVariogramTable t;
  const ModelComponent sph{.kind = ModelKind::Spherical, .sill = 1.0, .range = 200.0};
  double sxy = 0.0, sxx = 0.0;
  for (int j = 0; j < 12; ++j) {
    const double h = 10.0 + 20.0 * j;
    const double x = sph.gamma(h);
    Eigen::MatrixXd m(2, 2);
    m << 1.2 * x - 0.05, 0.1 * x, 0.1 * x, 0.5 * x + 0.02;
    t.lag.push_back(h);
    t.pairs.push_back(80);
    t.gamma.push_back(m);
    const double w = 80.0 / (h * h);
    sxy += w * x * m(0, 0);
    sxx += w * x * x;
  }
  CoregionalizationFitOptions o;
  o.method = LmcFitMethod::Gstat;
  const CoregionalizationFitResult r = fit_coregionalization(t, {{.kind = ModelKind::Nugget}, sph}, o);
  EXPECT_EQ(r.model.structures()[0].sills(0, 0), 0.0);
  EXPECT_NEAR(r.model.structures()[1].sills(0, 0), sxy / sxx, 1e-12);
  EXPECT_NEAR(r.model.structures()[0].sills(1, 1), 0.02, 1e-12);
  EXPECT_NEAR(r.model.structures()[1].sills(1, 1), 0.5, 1e-12);
}

TEST(CoregionalizationFit, RangesFittedToTheMeanDirectVariogramRecoverACommonRange) {
  const CoregionalizationModel truth = known_model();
  // One spherical structure and a nugget: the mean direct variogram is exactly nug + sph(300).
  const CoregionalizationModel two({truth.structures()[0], truth.structures()[1]});
  const CrossVariogramTable t = table_of(two, 20);
  const std::vector<ModelComponent> ranged =
      fit_coregionalization_ranges(t, {{.kind = ModelKind::Nugget}, {.kind = ModelKind::Spherical, .range = 0.0}});
  ASSERT_EQ(ranged.size(), 2u);
  EXPECT_EQ(ranged[0].kind, ModelKind::Nugget);
  EXPECT_NEAR(ranged[1].range, 300.0, 1e-5 * 300.0);
}

TEST(CoregionalizationFit, HeterotopicTableFitsEachVariogramOverItsOwnLagsAndBins) {
  // Heterotopic data: every direct and cross variogram with lags and pairs of its own, some bins
  // empty for some entries (NaN gamma there). The exact variograms of a known LMC, each at its own
  // lags: fitted alone per entry (gstat's fit.lmc), every entry is recovered; fitting at the
  // shared lag of a bin instead would not (the lags differ by up to 12).
  const CoregionalizationModel truth = known_model();
  const int P = truth.components();
  CrossVariogramTable t;
  for (int j = 0; j < 14; ++j) {
    const double h = 20.0 + 25.0 * j;
    Eigen::MatrixXd lag(P, P), pairs(P, P), gamma(P, P);
    for (int a = 0; a < P; ++a)
      for (int b = a; b < P; ++b) {
        const bool empty = a != b && j % 4 == 1;  // cross-variograms without pairs in some bins
        const double own = h + 3.0 * (a + 2 * b) - 4.0;
        lag(a, b) = lag(b, a) = empty ? std::nan("") : own;
        pairs(a, b) = pairs(b, a) = empty ? 0.0 : 30.0 + 7.0 * j + 5.0 * (a + b);
        gamma(a, b) = gamma(b, a) = empty ? std::nan("") : truth.gamma(a, b, own);
      }
    t.lag.push_back(h);
    t.pairs.push_back(1000);
    t.gamma.push_back(gamma);
    t.entry_lag.push_back(lag);
    t.entry_pairs.push_back(pairs);
  }
  ASSERT_TRUE(t.heterotopic());
  CoregionalizationFitOptions o;
  o.method = LmcFitMethod::Gstat;
  const CoregionalizationFitResult r = fit_coregionalization(t, template_of(truth), o);
  for (std::size_t k = 0; k < truth.structures().size(); ++k)
    for (int a = 0; a < P; ++a)
      for (int b = 0; b < P; ++b)
        // Exact data, a 3-unknown least-squares fit each: rounding only (sills are O(1)).
        EXPECT_NEAR(r.model.structures()[k].sills(a, b), truth.structures()[k].sills(a, b), 1e-10)
            << "structure " << k << ", entry " << a << "," << b;
  EXPECT_NEAR(r.weighted_residual, 0.0, 1e-18);
  EXPECT_NEAR(coregionalization_weighted_residual(t, r.model, o.weighting), r.weighted_residual, 1e-18);
  // Goulard-Voltz (its update is exact only with one weight per bin) and fitted ranges (the direct
  // variograms' lags differ) are refused, naming what to do.
  o.method = LmcFitMethod::GoulardVoltz;
  EXPECT_THROW(fit_coregionalization(t, template_of(truth), o), ArgumentError);
  EXPECT_THROW(fit_coregionalization_ranges(t, template_of(truth)), ArgumentError);
}

TEST(CoregionalizationFit, RejectsMisuseNamingTheProblem) {
  const CrossVariogramTable t = table_of(known_model(), 10);
  auto message = [](auto f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message([&] { fit_coregionalization(t, {{.kind = ModelKind::Power, .range = 1.5}}); }).find("pow"),
            std::string::npos);
  EXPECT_NE(message([&] { fit_coregionalization(t, {}); }).find("no structures"), std::string::npos);
  CrossVariogramTable one;
  one.lag = {10.0, 20.0};
  one.pairs = {5, 5};
  one.gamma = {Eigen::MatrixXd::Constant(1, 1, 0.1), Eigen::MatrixXd::Constant(1, 1, 0.2)};
  EXPECT_NE(message([&] { fit_coregionalization(one, {{.kind = ModelKind::Spherical, .range = 10.0}}); })
                .find("at least 2"),
            std::string::npos);
  CrossVariogramTable asym = t;
  asym.gamma[3](0, 1) += 0.5;
  EXPECT_NE(message([&] { fit_coregionalization(asym, template_of(known_model())); }).find("bin 3"), std::string::npos);
  EXPECT_THROW(lmc_fit_method_from_name("ols"), ArgumentError);
  EXPECT_EQ(lmc_weighting_from_name("6"), LmcWeighting::Unweighted);
  EXPECT_EQ(lmc_weighting_from_name("7"), LmcWeighting::NjOverH2);
}

}  // namespace coregionalization_fit_test
}  // namespace errfield
