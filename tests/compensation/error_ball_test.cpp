// The 3-D error ball (error_ball.hpp) against computations written here: the chi-square(3) CDF by
// Simpson integration of its density, a table value of its 95 % quantile, the two-equal-variances
// case as a 1-D integral (Z1² + Z2² is exponential), and Monte Carlo for three unequal variances.
#include "errfield/compensation/model/error_ball.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace errfield::compensation {
namespace error_ball_test {

/// Composite Simpson rule of f on [a, b] with n (even) intervals.
template <class F>
double simpson(F f, double a, double b, int n) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * f(a + i * h);
  return s * h / 3.0;
}

TEST(ErrorBall, ChiSquare3CdfIsTheIntegralOfItsDensity) {
  // density of chi-square(3): sqrt(x) exp(-x/2) / (2^(3/2) Gamma(3/2)); sqrt(x) is smooth in t = sqrt(x)
  for (double x : {0.1, 1.0, 3.0, 7.8147, 20.0}) {
    const double by_t = simpson(
        [](double t) { return 2.0 * t * t * std::exp(-0.5 * t * t) / (std::pow(2.0, 1.5) * std::tgamma(1.5)); }, 0.0,
        std::sqrt(x), 2000);
    EXPECT_NEAR(chi_square3_cdf(x), by_t, 1e-12) << x;
  }
  EXPECT_EQ(chi_square3_cdf(0.0), 0.0);
  EXPECT_EQ(chi_square3_cdf(-1.0), 0.0);
}

TEST(ErrorBall, EqualVariancesGiveTheChiSquareQuantile) {
  // chi2_3(0.95) = 7.814727903251178 (scipy.stats.chi2.ppf(0.95, 3)): r95 = 2.7955 sigma
  const double sigma = 0.03;
  EXPECT_NEAR(radius_with_probability(0.95, Eigen::Vector3d::Constant(sigma * sigma)),
              sigma * std::sqrt(7.814727903251178), 1e-12);
  EXPECT_NEAR(probability_within_radius(sigma * std::sqrt(7.814727903251178), Eigen::Vector3d::Constant(sigma * sigma)),
              0.95, 1e-12);
}

TEST(ErrorBall, TwoEqualVariancesMatchAOneDimensionalIntegral) {
  // P(a (Z1² + Z2²) + c Z3² <= r²) = int phi(z) (1 - exp(-(r² - c z²) / (2a))) dz over c z² <= r²,
  // since Z1² + Z2² is exponential with mean 2.
  const double a = 0.01, c = 0.0009;
  const Eigen::Vector3d v(a, a, c);
  for (double r : {0.05, 0.12, 0.2, 0.3}) {
    const double zmax = r / std::sqrt(c);
    const double expected = simpson(
        [&](double z) {
          return std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi) *
                 (1.0 - std::exp(-std::max(0.0, r * r - c * z * z) / (2.0 * a)));
        },
        -zmax, zmax, 20000);
    EXPECT_NEAR(probability_within_radius(r, v), expected, 1e-9) << r;
    // and the other axis order (the quadrature is not symmetric in the axes)
    EXPECT_NEAR(probability_within_radius(r, Eigen::Vector3d(c, a, a)), expected, 1e-9) << r;
  }
}

TEST(ErrorBall, UnequalVariancesMatchMonteCarlo) {
  const Eigen::Vector3d v(0.04, 0.01, 0.0025);  // sigmas 0.2, 0.1, 0.05: variance ratio 16
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> z;
  constexpr int n = 400000;
  const double radii[] = {0.1, 0.2, 0.35};
  int inside[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d e(std::sqrt(v.x()) * z(rng), std::sqrt(v.y()) * z(rng), std::sqrt(v.z()) * z(rng));
    for (int k = 0; k < 3; ++k) inside[k] += e.norm() <= radii[k];
  }
  for (int k = 0; k < 3; ++k) {
    const double p = probability_within_radius(radii[k], v);
    const double se = std::sqrt(p * (1.0 - p) / n);  // binomial standard error of the estimate
    EXPECT_NEAR(static_cast<double>(inside[k]) / n, p, 4.0 * se) << radii[k];
  }
  // the radius inverts the probability
  const double r95 = radius_with_probability(0.95, v);
  EXPECT_NEAR(probability_within_radius(r95, v), 0.95, 1e-10);
  EXPECT_GT(r95, std::sqrt(7.814727903251178 * v.minCoeff()));
  EXPECT_LT(r95, std::sqrt(7.814727903251178 * v.maxCoeff()));
}

// The radius (safeguarded Newton steps) inverts the probability at any anisotropy and probability,
// including a zero variance and ratios of a million, where a step can leave the bracket.
TEST(ErrorBall, TheRadiusInvertsTheProbabilityAtAnyAnisotropy) {
  const Eigen::Vector3d cases[] = {{1.0, 1e-6, 1e-6}, {1.0, 1.0, 1e-6}, {1e-6, 0.3, 1.0}, {1.0, 0.0, 0.0},
                                   {2.0, 1.0, 0.5},   {1.0, 0.999, 1.0}, {4e-4, 1e-4, 2.5e-5}};
  for (const Eigen::Vector3d& v : cases)
    for (double p : {0.05, 0.5, 0.95, 0.999}) {
      const double r = radius_with_probability(p, v);
      ASSERT_TRUE(std::isfinite(r)) << v.transpose() << " p " << p;
      EXPECT_NEAR(probability_within_radius(r, v), p, 1e-10) << v.transpose() << " p " << p;
      // and it is the smallest such radius: a little less holds less
      EXPECT_LT(probability_within_radius(r * (1.0 - 1e-6), v), p) << v.transpose() << " p " << p;
    }
}

TEST(ErrorBall, RefusesWhatIsNoVariance) {
  EXPECT_TRUE(std::isnan(probability_within_radius(0.1, Eigen::Vector3d(0.01, -0.01, 0.01))));
  EXPECT_TRUE(std::isnan(probability_within_radius(0.1, Eigen::Vector3d(0.01, NAN, 0.01))));
  EXPECT_TRUE(std::isnan(radius_with_probability(1.0, Eigen::Vector3d::Constant(0.01))));
  EXPECT_TRUE(std::isnan(radius_with_probability(0.95, Eigen::Vector3d::Constant(NAN))));
  EXPECT_EQ(probability_within_radius(0.0, Eigen::Vector3d::Zero()), 1.0);
}

}  // namespace
}  // namespace errfield::compensation
