// Matérn model over its whole parameter domain (0 < nu <= 100), including the corners the fuzzer
// found (a NaN gamma for large nu): against closed forms at half-integer nu and against the
// small-lag series 1 - rho(r) = r^2/(4(nu-1)) - r^4/(32(nu-1)(nu-2)) + ... elsewhere.

#include <cmath>

#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {
namespace variogram_model_matern_test {

double matern_gamma(double nu, double r) {
  return VariogramModel({{ModelKind::Matern, 1.0, 1.0, nu}}).gamma(r);
}

TEST(MaternModel, MatchesClosedFormsAtHalfIntegers) {
  for (double r : {1e-3, 0.1, 0.5, 1.0, 3.0, 10.0, 50.0}) {
    // rho = e^-r (nu = 1/2), (1 + r) e^-r (3/2), (1 + r + r^2/3) e^-r (5/2).
    EXPECT_NEAR(matern_gamma(0.5, r), -std::expm1(-r), 1e-13) << r;
    EXPECT_NEAR(matern_gamma(1.5, r), 1.0 - (1.0 + r) * std::exp(-r), 1e-13) << r;
    EXPECT_NEAR(matern_gamma(2.5, r), 1.0 - (1.0 + r + r * r / 3.0) * std::exp(-r), 1e-13) << r;
  }
}

TEST(MaternModel, HalfIntegersAgreeWithTheBesselDefinition) {
  // gamma at nu = 0.5, 1.5, 2.5 is computed from the closed forms (issue 49: the Bessel function was a
  // third of --model auto's time); here against the definition 1 - 2^(1-nu)/Gamma(nu) r^nu K_nu(r),
  // evaluated with the standard library's Bessel function, and against nu a hair away (continuity).
  for (double nu : {0.5, 1.5, 2.5})
    for (double r : {1e-6, 1e-3, 0.05, 0.3, 1.0, 2.7, 8.0, 30.0, 200.0}) {
      const double definition = 1.0 - std::pow(2.0, 1.0 - nu) / std::tgamma(nu) * std::pow(r, nu) * std::cyl_bessel_k(nu, r);
      EXPECT_NEAR(matern_gamma(nu, r), definition, 1e-14) << "nu " << nu << " r " << r;
      EXPECT_NEAR(matern_gamma(nu, r), matern_gamma(nu + 1e-9, r), 1e-8) << "nu " << nu << " r " << r;
    }
}

// 1 - rho(r) from the power series of r^nu K_nu(r) (non-integer or large nu; terms up to r^10):
// sum_{k>=1} (-1)^(k+1) (r/2)^(2k) / (k! (nu-1)(nu-2)...(nu-k)), the r^(2 nu) part omitted
// (below 1e-40 here).
double series_gamma(double nu, double r) {
  double sum = 0.0, term = 1.0;
  for (int k = 1; k <= 5; ++k) {
    term *= -(r / 2) * (r / 2) / (k * (nu - k));
    sum -= term;
  }
  return sum;
}

TEST(MaternModel, SmallLagsFollowTheSeriesForLargeNu) {
  // For nu = 20..100 at r = 1e-2..1e-4, K_nu(r) overflows for the larger nu (nu = 100 below
  // r ~ 0.06) and the code's truncated series is used; elsewhere the direct product. Both must
  // agree with the longer series. Tolerance: gamma is 1 - rho, so its absolute error is that of
  // rho, a few ulps of 1 plus K_nu's relative accuracy: 1e-14 (x sill).
  for (double nu : {20.0, 50.0, 99.5, 100.0}) {
    for (double r : {1e-2, 1e-3, 1e-4}) {
      EXPECT_NEAR(matern_gamma(nu, r), series_gamma(nu, r), 1e-14) << "nu=" << nu << " r=" << r;
    }
  }
  // The series itself against the closed form rho = e^-r (1 + r + 2r^2/5 + r^3/15) at nu = 7/2,
  // r = 1e-3, where the omitted r^(2 nu) = r^7 part is 1e-21.
  const double r = 1e-3;
  EXPECT_NEAR(series_gamma(3.5, r), 1.0 - (1.0 + r + 0.4 * r * r + r * r * r / 15.0) * std::exp(-r),
              1e-15);
}

TEST(MaternModel, NeverNaNAndWithinZeroAndSillOverTheDomain) {
  for (double nu : {0.01, 0.5, 1.0, 1.5, 7.0, 50.0, 100.0})
    for (double r : {0.0, 4.5e-312, 1e-300, 1e-15, 1e-9, 1e-3, 0.5, 1.0, 10.0, 100.0, 699.0, 701.0, 1e6}) {
      const double g = matern_gamma(nu, r);
      EXPECT_FALSE(std::isnan(g)) << nu << " " << r;
      EXPECT_GE(g, 0.0) << nu << " " << r;
      EXPECT_LE(g, 1.0 + 1e-12) << nu << " " << r;
    }
}

TEST(MaternModel, HugeSillsStayWithinZeroAndSillAtTinyLags) {
  // Found by fuzzing: mat(sill=1e308, range=4.1e302, nu=0.5) at h = 1e-300 gave NaN, because
  // sill * Gamma(1-nu) overflowed before (r/2)^(2 nu) = 0 multiplied it.
  const VariogramModel model({{ModelKind::Matern, 1e308, 4.1e302, 0.5}});
  for (double h : {1e-300, 1e-9, 1.0, 1e300}) {
    const double g = model.gamma(h);
    EXPECT_FALSE(std::isnan(g)) << h;
    EXPECT_GE(g, 0.0) << h;
    EXPECT_LE(g, 1e308) << h;
  }
  // At nu = 1/2 the model is exponential: gamma = sill (1 - e^(-h/range)) ~ sill h / range.
  // r = h / range is subnormal here (~39 significant bits), hence the 1e-9 relative tolerance.
  EXPECT_NEAR(model.gamma(1e-9) / (1e308 * 1e-9 / 4.1e302), 1.0, 1e-9);
}

TEST(MaternModel, TinyLagsWithSmallNuAreNotZero) {
  // For nu < 1, gamma ~ Gamma(1-nu)/Gamma(1+nu) (r/2)^(2 nu) stays visible at tiny lags (1.4e-6
  // at nu = 0.01, r = 1e-290), on both sides of the switch to the series at r = 1e-300 (K_nu
  // throws for subnormal r). Tolerance: absolute error 1e-16 of gamma over gamma ~1e-6, plus the
  // next series term, O(r^2) relative.
  for (double r : {1e-290, 2e-300, 5e-301, 1e-305, 1e-310}) {
    const double lead = std::tgamma(0.99) / std::tgamma(1.01) * std::pow(r / 2.0, 0.02);
    EXPECT_NEAR(matern_gamma(0.01, r) / lead, 1.0, 1e-9) << r;
  }
  // nu = 1/2 is the exponential model: gamma = 1 - e^-r, 0 to double precision this close to 0.
  for (double r : {2e-300, 5e-301, 1e-310}) EXPECT_NEAR(matern_gamma(0.5, r), r, 1e-16) << r;
}

TEST(MaternModel, RejectsNuOutsideTheDomain) {
  for (double nu : {0.0, -1.0, 100.5, 1e308, std::nan("")})
    EXPECT_THROW(VariogramModel({{ModelKind::Matern, 1.0, 1.0, nu}}), ArgumentError) << nu;
  try {
    VariogramModel::parse("mat(sill=1,range=9,nu=1e308)");
    FAIL() << "expected ArgumentError";
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("nu"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace errfield
