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

double probability_within_radius(double radius_mm, const Eigen::Vector3d& variance) {
  if (!valid(variance) || std::isnan(radius_mm)) return kNaN;
  if (radius_mm < 0.0) return 0.0;
  const double r2 = radius_mm * radius_mm;
  if (variance.maxCoeff() == 0.0) return 1.0;
  if (equal_variances(variance)) return chi_square3_cdf(r2 / variance.maxCoeff());
  // E_u[F_3(r² / u'Λu)] over the unit sphere; by symmetry one octant, t = cos(theta) in [0, 1],
  // phi in [0, pi/2], surface element dt dphi, octant area pi/2.
  const Quadrature& q = quadrature();
  double sum = 0.0;
  for (int i = 0; i < kNodes; ++i) {
    const double t = q.x[static_cast<std::size_t>(i)];
    const double s2 = 1.0 - t * t;
    double inner = 0.0;
    for (int j = 0; j < kNodes; ++j) {
      const double phi = 0.5 * std::numbers::pi * q.x[static_cast<std::size_t>(j)];
      const double c = std::cos(phi), s = std::sin(phi);
      const double quad = s2 * (variance.x() * c * c + variance.y() * s * s) + variance.z() * t * t;
      inner += q.w[static_cast<std::size_t>(j)] * (quad > 0.0 ? chi_square3_cdf(r2 / quad) : 1.0);
    }
    sum += q.w[static_cast<std::size_t>(i)] * inner;
  }
  return sum;  // weights on [0,1]² sum to 1: the mean over the octant
}

double radius_with_probability(double probability, const Eigen::Vector3d& variance) {
  if (!valid(variance) || !(probability > 0.0 && probability < 1.0)) return kNaN;
  const double k = std::sqrt(chi_square3_quantile(probability));
  if (variance.maxCoeff() == 0.0) return 0.0;
  if (equal_variances(variance)) return std::sqrt(variance.maxCoeff()) * k;
  // Between the radii of the smallest and the largest variance (P is monotone in each variance).
  double lo = std::sqrt(variance.minCoeff()) * k, hi = std::sqrt(variance.maxCoeff()) * k;
  for (int i = 0; i < 100 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (probability_within_radius(mid, variance) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace errfield::compensation
