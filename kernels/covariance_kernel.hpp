#pragma once
/// Hot loop of kriging: covariances between two sets of points, C(h) = sill - gamma(h), from a
/// bounded VariogramModel flattened once into plain numbers so that the inner loop is a switch over
/// a few terms, with no virtual call, allocation or model lookup per pair.
///
/// The reference this kernel is tested against is VariogramModel::covariance itself
/// (tests/kernels/covariance_kernel_test.cpp).
///
/// Points are stored column-major, one point per column (D rows), coordinates already in the
/// Euclidean embedding of the metric (see kriging.hpp), so h is the Euclidean distance.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "errfield/error.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::kernels {

/// A bounded variogram model as covariance terms. Immutable after construction; thread-safe.
class CovarianceKernel {
 public:
  /// Throws ArgumentError when the model is unbounded (pow, lin): no covariance exists.
  explicit CovarianceKernel(const VariogramModel& model) {
    if (!model.bounded())
      throw ArgumentError("kriging: variogram model '" + model.to_string() +
                          "' is unbounded (pow or lin); kriging here needs a covariance, i.e. a "
                          "model with a sill (nug, sph, exp, gau, mat, wen)");
    for (const auto& c : model.components()) {
      if (c.kind == ModelKind::Nugget) {
        nugget_ += c.sill;
      } else {
        terms_.push_back(c);
      }
      sill_ += c.sill;
    }
  }

  /// Total sill (nugget included) = C(0) of the observed process.
  double sill() const { return sill_; }
  /// Sum of the nugget components.
  double nugget() const { return nugget_; }

  /// Covariance at lag h > 0 (the nugget does not contribute); the caller decides what C(0) is.
  double at_positive_lag(double h) const {
    double c = 0.0;
    for (const auto& t : terms_) c += t.sill - gamma_of(t, h);
    return c;
  }
  /// Covariance with the value `zero_value` used at exactly h = 0.
  double operator()(double h, double zero_value) const {
    return h > 0.0 ? at_positive_lag(h) : zero_value;
  }
  /// out[i] = (*this)(lags[i], zero_value) for i < n, bit for bit (the same operations in the
  /// same order), term by term over all the lags: a spherical term is then a loop the compiler
  /// vectorizes (a division and a select per lag, no branch), which the sequential simulation's
  /// ~1,800 covariances per location were waiting on. `lags` and `out` do not overlap.
  void at_lags(const double* lags, std::size_t n, double zero_value, double* out) const {
    for (std::size_t i = 0; i < n; ++i) out[i] = 0.0;
    for (const auto& t : terms_) {
      if (t.kind == ModelKind::Spherical) {
        const double sill = t.sill, range = t.range;
        for (std::size_t i = 0; i < n; ++i) {
          // gamma_of's expression; beyond the range r = 1 exactly, so g = sill * 1.0 = sill as there,
          // without a branch (which would keep the division scalar: it must not run speculatively).
          const double r = std::min(lags[i], range) / range;
          out[i] += sill - sill * (1.5 * r - 0.5 * r * r * r);
        }
      } else {
        for (std::size_t i = 0; i < n; ++i)
          if (lags[i] > 0.0) out[i] += t.sill - gamma_of(t, lags[i]);
      }
    }
    for (std::size_t i = 0; i < n; ++i)
      if (!(lags[i] > 0.0)) out[i] = zero_value;
  }

 private:
  /// ModelComponent::gamma with the common kinds inline (the same expressions, so the same
  /// values bit for bit): the call costs more than a spherical term itself, and conditional
  /// simulation's sequential paths evaluate ~2,000 covariances per location.
  static double gamma_of(const ModelComponent& t, double h) {
    if (h > 0.0) {
      if (t.kind == ModelKind::Spherical) {
        if (h >= t.range) return t.sill;
        const double r = h / t.range;
        return t.sill * (1.5 * r - 0.5 * r * r * r);
      }
      if (t.kind == ModelKind::Exponential) return t.sill * -std::expm1(-h / t.range);
      if (t.kind == ModelKind::Gaussian) {
        const double r = h / t.range;
        return t.sill * -std::expm1(-r * r);
      }
    }
    return t.gamma(h);
  }

  std::vector<ModelComponent> terms_;
  double nugget_ = 0.0;
  double sill_ = 0.0;
};

/// Euclidean distance between column i of a (D x *) and column j of b.
inline double column_distance(const double* a, const double* b, int dimension) {
  double s = 0.0;
  for (int k = 0; k < dimension; ++k) {
    const double d = a[k] - b[k];
    s += d * d;
  }
  return std::sqrt(s);
}

/// out(i, j) = C(|a_i - b_j|) for i < na, j < nb, column-major with leading dimension ld >= na;
/// exactly coincident points get `zero_value`. a: D x na, b: D x nb, both column-major.
/// O(na nb (D + terms)); no allocation.
inline void covariance_block(const CovarianceKernel& kernel, const double* a, std::size_t na,
                             const double* b, std::size_t nb, int dimension, double zero_value,
                             double* out, std::size_t ld) {
  for (std::size_t j = 0; j < nb; ++j) {
    const double* bj = b + j * static_cast<std::size_t>(dimension);
    double* col = out + j * ld;
    for (std::size_t i = 0; i < na; ++i)
      col[i] = kernel(column_distance(a + i * static_cast<std::size_t>(dimension), bj, dimension),
                      zero_value);
  }
}

}  // namespace errfield::kernels
