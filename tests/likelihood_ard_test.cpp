// Likelihood fits with ARD and vector values: the analytic gradient against central finite
// differences, the profiled likelihood against the plain formula at the profiled sill, vector =
// sum of its components, recovery of known ranges on a SIMULATED anisotropic field (within three
// standard errors), and the automatic model choice refusing ill-conditioned candidates.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/range_plausibility.hpp"
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

TEST(ModelChoice, ConfirmationOnALargerSubsetIsOrderIndependentAndNamedInTheReason) {
  // confirm_subsample: the confirming fits see a second, larger subset instead of every sample.
  const Field f = simulate(90, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 31);
  ModelChoiceOptions o;
  o.kinds = {ModelKind::Spherical, ModelKind::Gaussian};
  o.choice_subsample = 40;
  const ModelChoice all = choose_likelihood_model(f.x, f.z, o);
  // At or beyond the sample count it is every sample: the same choice, to the bit.
  o.confirm_subsample = 90;
  const ModelChoice same = choose_likelihood_model(f.x, f.z, o);
  EXPECT_EQ(same.model.to_string(), all.model.to_string());
  EXPECT_EQ(same.reason, all.reason);
  // Below it: named in the reason, and the same subset whatever the rows' order.
  o.confirm_subsample = 60;
  std::vector<Eigen::Index> permutation(90);
  for (Eigen::Index i = 0; i < 90; ++i) permutation[static_cast<std::size_t>(i)] = (37 * i + 11) % 90;
  const ModelChoice a = choose_likelihood_model(f.x, f.z, o),
                    b = choose_likelihood_model(f.x(permutation, Eigen::all), f.z(permutation, Eigen::all), o);
  EXPECT_NE(a.reason.find("refitted on a subset of 60"), std::string::npos) << a.reason;
  EXPECT_EQ(a.model.components().front().kind, b.model.components().front().kind);
  EXPECT_NEAR(a.model.sill(), b.model.sill(), 1e-5 * a.model.sill());
  EXPECT_NEAR(a.model.nugget(), b.model.nugget(), 1e-5 * a.model.sill());
  // Its likelihood is another sample's: the all-sample criterion differs from the full confirmation's.
  EXPECT_NE(a.model.to_string(), all.model.to_string());
  // A confirming subset smaller than the ranking's is a contradiction.
  o.confirm_subsample = 30;
  EXPECT_THROW(choose_likelihood_model(f.x, f.z, o), ArgumentError);
}

// The plain fit_likelihood of one candidate family (default starts) and whether some range of it
// lies within 10 x the samples' extent along its coordinate (else it is a trend, which the choice
// sets aside: ModelChoiceOptions::pathological_range_factor).
struct PlainFit {
  LikelihoodFitResult fit;
  bool finite_range = true;
};
std::vector<PlainFit> plain_fits(const Field& f, const std::vector<ModelKind>& kinds, bool ard) {
  const Eigen::RowVectorXd extent = f.x.colwise().maxCoeff() - f.x.colwise().minCoeff();
  std::vector<PlainFit> out;
  for (const ModelKind kind : kinds)
    for (const double nu : kind == ModelKind::Matern ? std::vector<double>{1.5, 2.5} : std::vector<double>{0.5})
      for (int a = 0; a <= (ard ? 1 : 0); ++a) {
        LikelihoodFitOptions o;
        o.anisotropy = a ? LikelihoodFitOptions::Anisotropy::Ard : LikelihoodFitOptions::Anisotropy::None;
        PlainFit p{fit_likelihood(f.x, f.z, {component(kind, nu)}, o), false};
        const double range = p.fit.model.components().front().range;
        for (Eigen::Index k = 0; k < extent.size(); ++k) {
          const double along = a ? range * p.fit.model.anisotropy().parameters()[static_cast<std::size_t>(k)] : range;
          p.finite_range = p.finite_range || along <= 10.0 * (a ? extent[k] : extent.norm());
        }
        out.push_back(std::move(p));
      }
  return out;
}

TEST(ModelChoice, NoPlainFitOfACandidateFamilyBeatsTheChoice) {
  // Ranked with fewer starts than a plain fit (as interpolate --model auto ranks: 4 screened, one
  // run), the best three are fitted again with the plain fit's starts and their ranking estimate.
  // Before, the ranking fits were the answer: on this SIMULATED draw (40 points, 2-D) a plain sph
  // ARD fit reached an AIC 4.1 below the choice.
  const Field f = simulate(40, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 43);
  ModelChoiceOptions o;
  o.ranking_starts = 4;
  o.ranking_local_runs = 1;
  const ModelChoice choice = choose_likelihood_model(f.x, f.z, o);
  for (const PlainFit& p : plain_fits(f, o.kinds, true)) {
    if (p.finite_range) {
      EXPECT_LE(choice.fit.aic, p.fit.aic + 1e-9 * std::abs(p.fit.aic)) << p.fit.model.to_string() << "\n" << choice.reason;
    } else if (p.fit.aic < choice.fit.aic) {
      // A smaller AIC with no finite range is set aside, and the reason says so.
      EXPECT_NE(choice.reason.find("set aside as implausible"), std::string::npos) << choice.reason;
    }
  }
}

TEST(ModelChoice, CandidatesRankedOnASubsetAreConfirmedOnAllSamples) {
  // SIMULATED, 90 points, ranked on 40: the subset's best family (refitted alone on all samples, as
  // before) was 12.4 AIC units worse on all 90 than gau; the best three ranked are now all fitted
  // on every sample and the smallest AIC there wins.
  const Field f = simulate(90, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 36);
  ModelChoiceOptions o;
  o.kinds = {ModelKind::Spherical, ModelKind::Exponential, ModelKind::Gaussian};
  o.try_ard = false;
  o.choice_subsample = 40;
  const ModelChoice choice = choose_likelihood_model(f.x, f.z, o);
  for (const PlainFit& p : plain_fits(f, o.kinds, false))
    if (p.finite_range)
      EXPECT_LE(choice.fit.aic, p.fit.aic + 1e-9 * std::abs(p.fit.aic)) << p.fit.model.to_string() << "\n" << choice.reason;
  EXPECT_NE(choice.reason.find("random subset of 40 of the 90 samples, the best 3 refitted on all"), std::string::npos)
      << choice.reason;
}

TEST(ModelChoice, AnImplausibleWinnerIsSetAsideWithTheReason) {
  // SIMULATED draw whose smallest AIC is a spherical ARD model with a range ~600 x the samples'
  // extent (a trend seen as a variogram): before, it was returned without a word.
  const Field f = simulate(40, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 43);
  const ModelChoice choice = choose_likelihood_model(f.x, f.z, {});
  const std::vector<PlainFit> plain = plain_fits(f, {ModelKind::Spherical}, true);
  const PlainFit& trend = plain[1];  // sph@ard
  ASSERT_FALSE(trend.finite_range) << trend.fit.model.to_string();
  EXPECT_LT(trend.fit.aic, choice.fit.aic);
  ASSERT_FALSE(choice.warnings.empty()) << choice.reason;
  EXPECT_NE(choice.warnings.front().find("beyond 10 x the samples' extent"), std::string::npos) << choice.warnings.front();
  EXPECT_NE(choice.reason.find("set aside as implausible"), std::string::npos) << choice.reason;
  // The model returned has a finite range along some coordinate.
  const Eigen::RowVectorXd extent = f.x.colwise().maxCoeff() - f.x.colwise().minCoeff();
  const double range = choice.model.components().front().range;
  const bool ard = choice.model.anisotropy().type() == Anisotropy::Type::Ard;
  bool finite = false;
  for (Eigen::Index k = 0; k < 2; ++k)
    finite = finite || (ard ? range * choice.model.anisotropy().parameters()[static_cast<std::size_t>(k)] <= 10.0 * extent[k]
                            : range <= 10.0 * extent.norm());
  EXPECT_TRUE(finite) << choice.model.to_string();
}

TEST(RangePlausibility, AStripeFlatAlongOneCoordinateCountsTheLongRangeAtItsLimit) {
  // Issue 49: fulmar's indicator at 5 got exp@ard with a range of 2.5e8 along x and 92 m along y
  // over an extent of 249,605 x 455,995 m (the samples lie on survey lines, the closest 10 m apart):
  // the anisotropy ratio left the range beyond 10 x the extent out, so the stripe passed.
  Eigen::RowVectorXd extent(2);
  extent << 249605.0, 455995.0;
  const VariogramModel stripe(VariogramModel::parse("exp(sill=0.065,range=2.49605e8)+nug(6.5e-11)").components(),
                              Anisotropy::ard({1.0, 3.6757579698466787e-07}));
  const std::vector<std::string> why = implausible_range_shape(stripe, extent);
  ASSERT_EQ(why.size(), 1u);
  // The limit along x, 10 x 249,605 = 2,496,050 m, against 91.75 m along y.
  EXPECT_NE(why[0].find("anisotropy ratio 27205."), std::string::npos) << why[0];
  EXPECT_NE(why[0].find("counted as 2496050: a stripe, not a field"), std::string::npos) << why[0];
  // Flat along x with a range along y within the ratio of the limit: an answer, not a stripe.
  const VariogramModel flat(VariogramModel::parse("exp(sill=1,range=2.49605e8)").components(),
                            Anisotropy::ard({1.0, 1.2e-4}));  // 29,953 m along y: ratio 83
  EXPECT_TRUE(implausible_range_shape(flat, extent).empty());
  // Every range beyond the limit: a trend; two ranges within it compared as they are.
  const VariogramModel trend(VariogramModel::parse("exp(sill=1,range=1e8)").components(), Anisotropy::ard({1.0, 1.0}));
  ASSERT_EQ(implausible_range_shape(trend, extent).size(), 1u);
  EXPECT_NE(implausible_range_shape(trend, extent)[0].find("along every coordinate"), std::string::npos);
  const VariogramModel narrow(VariogramModel::parse("exp(sill=1,range=1e5)").components(), Anisotropy::ard({1.0, 0.001}));
  ASSERT_EQ(implausible_range_shape(narrow, extent).size(), 1u);
  EXPECT_NE(implausible_range_shape(narrow, extent)[0].find("anisotropy ratio 1000 > 100 (ranges 1e+05 and 100)"),
            std::string::npos)
      << implausible_range_shape(narrow, extent)[0];
}

TEST(RangePlausibility, NamesAStripeBelowTheSpacingAndATrendBeyondTheExtent) {
  // Issue 49's fulmar indicator: an ARD model with a range of 2.5e8 along x and 92 along y. Here:
  // exp(range 10) with multipliers 1e6 and 0.5 over a 100 x 100 extent whose samples are >= 20 apart.
  Eigen::RowVectorXd extent(2);
  extent << 100.0, 100.0;
  const VariogramModel stripe(VariogramModel::parse("exp(sill=1,range=10)+nug(0)").components(), Anisotropy::ard({1e6, 0.5}));
  const std::vector<std::string> why = implausible_ranges(stripe, extent, 20.0);
  ASSERT_EQ(why.size(), 2u);
  // exp's practical range is 3 x its range parameter (covariance 5 % of the sill): 3e7 along x, 15 along y.
  EXPECT_NE(why[0].find("along coordinate 1 (x) is 299573."), std::string::npos) << why[0];
  EXPECT_NE(why[0].find("x the samples' extent 100: a trend over the data"), std::string::npos) << why[0];
  EXPECT_NE(why[1].find("exp practical range 14.9786"), std::string::npos) << why[1];
  EXPECT_NE(why[1].find("along coordinate 2 (y) below the smallest sample spacing 20"), std::string::npos) << why[1];
  // A plausible isotropic model: nothing to say; one side only when asked.
  EXPECT_TRUE(implausible_ranges(VariogramModel::parse("sph(sill=1,range=40)"), extent, 20.0).empty());
  EXPECT_TRUE(implausible_ranges(stripe, extent, 0.0, std::numeric_limits<double>::infinity()).empty());
}

TEST(RangePlausibility, SmallestSpacingEqualsBruteForceAndSkipsRepeatedLocations) {
  const Field f = simulate(200, Eigen::Vector2d(15, 40), 1.0, 0.05, 1, 7);
  Eigen::MatrixXd x = f.x;
  x.row(5) = x.row(17);  // a repeated location is not a spacing
  double brute = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index j = i + 1; j < x.rows(); ++j) {
      const double d = (x.row(i) - x.row(j)).norm();
      if (d > 0.0) brute = std::min(brute, d);
    }
  EXPECT_EQ(smallest_sample_spacing(x), brute);
  EXPECT_EQ(smallest_sample_spacing(x.topRows(1)), std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace errfield
