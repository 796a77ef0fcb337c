#include "errfield/compensation/model/error_ball.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace errfield::compensation {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kNodes = 48;

/// Gauss-Legendre nodes and weights on [0, 1] (Newton on the Legendre polynomial, Golub-Welsch
/// would need an eigen-solver for no gain at 48 nodes).
struct Quadrature {
  std::array<double, kNodes> x{}, w{};
  /// cos² and sin² of the azimuth phi = (pi/2) x at each node (the inner loop's, computed once).
  std::array<double, kNodes> cos2{}, sin2{};
  Quadrature() {
    for (int i = 0; i < kNodes; ++i) {
      double z = std::cos(std::numbers::pi * (i + 0.75) / (kNodes + 0.5));
      double dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = z;
        for (int k = 2; k <= kNodes; ++k) {
          const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = kNodes * (z * p1 - p0) / (z * z - 1.0);
        const double step = p1 / dp;
        z -= step;
        if (std::abs(step) < 1e-15) break;
      }
      x[static_cast<std::size_t>(i)] = 0.5 * (1.0 - z);  // [-1, 1] -> [0, 1]
      w[static_cast<std::size_t>(i)] = 1.0 / ((1.0 - z * z) * dp * dp);  // 2/((1-z²)P'²) halved
    }
    for (int j = 0; j < kNodes; ++j) {
      const double phi = 0.5 * std::numbers::pi * x[static_cast<std::size_t>(j)];
      cos2[static_cast<std::size_t>(j)] = std::cos(phi) * std::cos(phi);
      sin2[static_cast<std::size_t>(j)] = std::sin(phi) * std::sin(phi);
    }
  }
};

const Quadrature& quadrature() {
  static const Quadrature q;
  return q;
}

bool valid(const Eigen::Vector3d& v) { return v.allFinite() && (v.array() >= 0.0).all(); }

bool equal_variances(const Eigen::Vector3d& v) { return v.maxCoeff() - v.minCoeff() <= 1e-12 * v.maxCoeff(); }

/// The chi-square(3) quantile of p, by bisection (F_3 is monotone; 200 halvings reach double precision).
double chi_square3_quantile(double p) {
  double lo = 0.0, hi = 1.0;
  while (chi_square3_cdf(hi) < p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi_square3_cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double chi_square3_cdf(double x) {
  if (!(x > 0.0)) return std::isnan(x) ? kNaN : 0.0;
  if (std::isinf(x)) return 1.0;
  return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / std::numbers::pi) * std::exp(-0.5 * x);
}

namespace {

/// P(|e| <= r) for unequal variances, and with `derivative` dP/dr: E_u[F_3(r² / u'Λu)] over the unit
/// sphere; by symmetry one octant, t = cos(theta) in [0, 1], phi in [0, pi/2], surface element
/// dt dphi, octant area pi/2. dP/dr = E_u[f_3(r² / q) 2r / q], f_3(x) = sqrt(x / 2pi) exp(-x/2).
double octant_probability(double r, const Eigen::Vector3d& variance, double* derivative) {
  const Quadrature& q = quadrature();
  const double r2 = r * r;
  double sum = 0.0, dsum = 0.0;
  for (int i = 0; i < kNodes; ++i) {
    const double t = q.x[static_cast<std::size_t>(i)];
    const double s2 = 1.0 - t * t;
    double inner = 0.0, dinner = 0.0;
    for (int j = 0; j < kNodes; ++j) {
      const auto k = static_cast<std::size_t>(j);
      const double quad = s2 * (variance.x() * q.cos2[k] + variance.y() * q.sin2[k]) + variance.z() * t * t;
      if (!(quad > 0.0)) {
        inner += q.w[k];
        continue;
      }
      const double x = r2 / quad;
      const double root = std::sqrt(0.5 * x), e = std::exp(-0.5 * x);
      inner += q.w[k] * (std::erf(root) - std::sqrt(2.0 * x / std::numbers::pi) * e);
      if (derivative) dinner += q.w[k] * std::sqrt(x / (2.0 * std::numbers::pi)) * e * 2.0 * r / quad;
    }
    sum += q.w[static_cast<std::size_t>(i)] * inner;
    dsum += q.w[static_cast<std::size_t>(i)] * dinner;
  }
  if (derivative) *derivative = dsum;
  return sum;  // weights on [0,1]² sum to 1: the mean over the octant
}

}  // namespace

double probability_within_radius(double radius_mm, const Eigen::Vector3d& variance) {
  if (!valid(variance) || std::isnan(radius_mm)) return kNaN;
  if (radius_mm < 0.0) return 0.0;
  const double r2 = radius_mm * radius_mm;
  if (variance.maxCoeff() == 0.0) return 1.0;
  if (equal_variances(variance)) return chi_square3_cdf(r2 / variance.maxCoeff());
  return octant_probability(radius_mm, variance, nullptr);
}

double radius_with_probability(double probability, const Eigen::Vector3d& variance) {
  if (!valid(variance) || !(probability > 0.0 && probability < 1.0)) return kNaN;
  const double k = std::sqrt(chi_square3_quantile(probability));
  if (variance.maxCoeff() == 0.0) return 0.0;
  if (equal_variances(variance)) return std::sqrt(variance.maxCoeff()) * k;
  // Between the radii of the smallest and the largest variance (P is monotone in each variance).
  // Newton's steps on P(r) = probability, kept inside that bracket (a step that leaves it halves it
  // instead): 4-6 quadratures where bisection took ~40 (validate scores a radius per row and per
  // pose: 17 s of a real 831-pose probe validation).
  double lo = std::sqrt(variance.minCoeff()) * k, hi = std::sqrt(variance.maxCoeff()) * k;
  double r = std::sqrt(variance.mean()) * k;
  for (int i = 0; i < 100 && hi - lo > 1e-12 * hi; ++i) {
    double slope = 0.0;
    const double miss = octant_probability(r, variance, &slope) - probability;
    if (miss == 0.0) return r;
    (miss < 0.0 ? lo : hi) = r;
    const double step = slope > 0.0 ? miss / slope : 0.0;
    const double next = r - step;
    if (slope > 0.0 && next > lo && next < hi) {
      if (std::abs(step) <= 1e-13 * r) return next;
      r = next;
    } else {
      r = 0.5 * (lo + hi);
    }
  }
  return r;
}

}  // namespace errfield::compensation
