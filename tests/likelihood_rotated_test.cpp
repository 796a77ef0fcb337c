// Rotated-anisotropy likelihood fit (LikelihoodFitOptions::Anisotropy::Rotated). SIMULATED fields:
// Gaussian draws with a rotated anisotropic exponential covariance built here by hand (the major
// axis written as a unit vector (sin a, cos a), a clockwise from +y, not through the library's
// Anisotropy), then fitted. The truth must lie within 3 standard errors of the mean of the
// replicated estimates (standard error = the replicates' standard deviation / sqrt(R)), and the
// fitted model's likelihood must be at least that of the truth on every replicate.

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "errfield/kriging_likelihood.hpp"

namespace errfield {
namespace likelihood_rotated_test {

constexpr double kRad = std::numbers::pi / 180.0;

struct Truth {
  double angle_deg, range, ratio, sill, nugget;
};

// N points uniform in [0, 100]^2 and one draw of the field (exp covariance + nugget).
void simulate(const Truth& t, int n, std::uint64_t seed, Eigen::MatrixXd* x, Eigen::MatrixXd* z) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 1.0);
  x->resize(n, 2);
  for (int i = 0; i < n; ++i) (*x)(i, 0) = u(rng), (*x)(i, 1) = u(rng);
  const Eigen::Vector2d major(std::sin(t.angle_deg * kRad), std::cos(t.angle_deg * kRad));
  const Eigen::Vector2d minor(major.y(), -major.x());
  Eigen::MatrixXd k(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector2d s = x->row(i).transpose() - x->row(j).transpose();
      const double a = s.dot(major) / t.range, b = s.dot(minor) / (t.range * t.ratio);
      k(i, j) = t.sill * std::exp(-std::sqrt(a * a + b * b)) + (i == j ? t.nugget : 0.0);
    }
  const Eigen::LLT<Eigen::MatrixXd> llt(k);
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) w(i) = g(rng);
  *z = llt.matrixL() * w;
}

// Angle difference modulo 180 (an axis), in (-90, 90].
double axis_difference(double a, double b) {
  double d = std::fmod(a - b, 180.0);
  if (d > 90.0) d -= 180.0;
  if (d <= -90.0) d += 180.0;
  return d;
}

TEST(LikelihoodRotatedStudy, RecoversAngleAndRatioIn2DWithinTheirStandardErrors) {
  const Truth truth{30.0, 40.0, 0.3, 1.0, 0.02};
  const int replicates = 8, n = 120;
  std::vector<double> angle, ratio, range, angle_se;
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
  o.starts = 3;
  o.local_runs = 1;
  ModelComponent exp;
  exp.kind = ModelKind::Exponential;
  for (int r = 0; r < replicates; ++r) {
    Eigen::MatrixXd x, z;
    simulate(truth, n, 100 + static_cast<std::uint64_t>(r), &x, &z);
    const LikelihoodFitResult fit = fit_likelihood(x, z, {exp}, o);
    ASSERT_EQ(fit.model.anisotropy().type(), Anisotropy::Type::Rotated);
    ASSERT_EQ(fit.angles_deg.size(), 1u);
    const auto& p = fit.model.anisotropy().parameters();
    EXPECT_EQ(p[0], fit.angles_deg[0]);
    EXPECT_LE(p[1], 1.0);  // written with the major axis first, as gstat
    angle.push_back(truth.angle_deg + axis_difference(p[0], truth.angle_deg));
    ratio.push_back(p[1]);
    range.push_back(fit.model.components()[0].range);
    angle_se.push_back(fit.angle_standard_errors_deg[0]);
    // The optimum is at least as likely as the truth (written in errfield's syntax).
    const VariogramModel true_model(
        {{ModelKind::Exponential, truth.sill, truth.range, 0.5}, {ModelKind::Nugget, truth.nugget, 0.0, 0.5}},
        Anisotropy::rotated({truth.angle_deg, truth.ratio}));
    EXPECT_LE(fit.negative_log_likelihood, negative_log_likelihood(x, z, true_model, o) + 1e-6);
    // The reported nll is that of the model as written (the rotation composed correctly).
    EXPECT_NEAR(fit.negative_log_likelihood, negative_log_likelihood(x, z, fit.model, o),
                1e-8 * std::fabs(fit.negative_log_likelihood));
  }
  auto mean_sd = [](const std::vector<double>& v) {
    double m = 0.0, s = 0.0;
    for (double x : v) m += x;
    m /= static_cast<double>(v.size());
    for (double x : v) s += (x - m) * (x - m);
    return std::pair{m, std::sqrt(s / static_cast<double>(v.size() - 1))};
  };
  const auto [am, asd] = mean_sd(angle);
  const auto [rm, rsd] = mean_sd(ratio);
  const double sqrt_r = std::sqrt(static_cast<double>(replicates));
  RecordProperty("angle_mean", std::to_string(am));
  RecordProperty("angle_sd", std::to_string(asd));
  RecordProperty("ratio_mean", std::to_string(rm));
  RecordProperty("ratio_sd", std::to_string(rsd));
  EXPECT_LE(std::fabs(am - truth.angle_deg), 3.0 * asd / sqrt_r) << "angle sd " << asd;
  EXPECT_LE(std::fabs(rm - truth.ratio), 3.0 * rsd / sqrt_r) << "ratio sd " << rsd;
  // The profile curvature's standard error is of the size of the replicates' spread (within 3x).
  double se = 0.0;
  for (double s : angle_se) se += s;
  se /= static_cast<double>(angle_se.size());
  EXPECT_GT(se, asd / 3.0);
  EXPECT_LT(se, asd * 3.0);
}

// 3-D: too slow for replications here (~200 ARD fits per fit), so one small draw: the fitted model
// as written (azimuth, dip, rotation, two ratios composed by the library; the frame re-sorted by
// range, which inverts the library's rotation) is at least as likely as the truth, built by hand
// as an ellipsoid with its major axis horizontal at azimuth 30.
TEST(LikelihoodRotatedStudy, ThreeDimensionalFitIsAtLeastAsLikelyAsTheTruth) {
  const int n = 60;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(n, 3);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) x(i, k) = u(rng);
  const double a = 30.0 * kRad;
  const Eigen::Vector3d major(std::sin(a), std::cos(a), 0.0), minor1(std::cos(a), -std::sin(a), 0.0), up(0, 0, 1);
  Eigen::MatrixXd k(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d s = x.row(i).transpose() - x.row(j).transpose();
      const double h = std::sqrt(std::pow(s.dot(major) / 60.0, 2) + std::pow(s.dot(minor1) / 30.0, 2) +
                                 std::pow(s.dot(up) / 15.0, 2));
      k(i, j) = std::exp(-h) + (i == j ? 0.02 : 0.0);
    }
  const Eigen::LLT<Eigen::MatrixXd> llt(k);
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) w(i) = g(rng);
  const Eigen::MatrixXd z = Eigen::MatrixXd(llt.matrixL()) * w;
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
  o.starts = 2;
  o.local_runs = 1;
  ModelComponent exp;
  exp.kind = ModelKind::Exponential;
  const LikelihoodFitResult fit = fit_likelihood(x, z, {exp}, o);
  ASSERT_EQ(fit.angles_deg.size(), 3u);
  ASSERT_EQ(fit.model.anisotropy().parameters().size(), 5u);
  // Written as gstat wants it: the longest range first (ratios <= 1), angles in [0, 360).
  const auto& p = fit.model.anisotropy().parameters();
  EXPECT_LE(p[3], 1.0);
  EXPECT_LE(p[4], 1.0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(p[static_cast<std::size_t>(k)], 0.0);
    EXPECT_LT(p[static_cast<std::size_t>(k)], 360.0);
  }
  // gstat's anis(30, 0, 0, 0.5, 0.25): major axis horizontal at azimuth 30, minor 1 horizontal.
  const VariogramModel truth({{ModelKind::Exponential, 1.0, 60.0, 0.5}, {ModelKind::Nugget, 0.02, 0.0, 0.5}},
                             Anisotropy::rotated({30.0, 0.0, 0.0, 0.5, 0.25}));
  EXPECT_LE(fit.negative_log_likelihood, negative_log_likelihood(x, z, truth, o) + 1e-6) << fit.model.to_string();
  EXPECT_NEAR(fit.negative_log_likelihood, negative_log_likelihood(x, z, fit.model, o),
              1e-8 * std::fabs(fit.negative_log_likelihood));
}

TEST(LikelihoodRotated, RefusesOtherDimensions) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Random(20, 4), z = Eigen::MatrixXd::Random(20, 1);
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
  ModelComponent exp;
  exp.kind = ModelKind::Exponential;
  EXPECT_THROW(fit_likelihood(x, z, {exp}, o), ArgumentError);
}

}  // namespace
}  // namespace errfield
