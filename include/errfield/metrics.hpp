#pragma once
/// Metrics (lags) between locations. Use `EuclideanMetric` for task space (mm) or any plain
/// coordinates, `JointSpaceMetric` for joint vectors in degrees (SPEC eq. 16), and
/// `WeightedEuclideanMetric` when axes differ in importance or unit.

#include <cmath>
#include <utility>
#include <vector>

#include "errfield/concepts.hpp"
#include "errfield/error.hpp"

namespace errfield {

/// sqrt(sum_k (a_k - b_k)^2), in the unit of the coordinates. Thread-safe, no state.
struct EuclideanMetric {
  template <Location L>
  double operator()(const L& a, const L& b) const {
    double s = 0.0;
    const int n = LocationTraits<L>::size(a);
    for (int k = 0; k < n; ++k) {
      const double d = LocationTraits<L>::coordinate(a, k) - LocationTraits<L>::coordinate(b, k);
      s += d * d;
    }
    return std::sqrt(s);
  }
};

/// Joint-space lag of the paper (eq. 16): Euclidean distance between joint vectors, in degrees.
/// A distinct type so that a signature says which space its lags live in.
struct JointSpaceMetric : EuclideanMetric {};

/// sqrt(sum_k w_k (a_k - b_k)^2) with non-negative weights, one per coordinate.
class WeightedEuclideanMetric {
 public:
  /// Throws ArgumentError if a weight is negative or not finite.
  explicit WeightedEuclideanMetric(std::vector<double> weights) : weights_(std::move(weights)) {
    for (std::size_t k = 0; k < weights_.size(); ++k)
      if (!(weights_[k] >= 0.0) || !std::isfinite(weights_[k]))
        throw ArgumentError("WeightedEuclideanMetric: weight " + std::to_string(k) + " is " +
                            std::to_string(weights_[k]) + "; expected a finite value >= 0");
  }
  const std::vector<double>& weights() const noexcept { return weights_; }

  /// Precondition: the locations have exactly weights().size() coordinates.
  template <Location L>
  double operator()(const L& a, const L& b) const {
    double s = 0.0;
    for (std::size_t k = 0; k < weights_.size(); ++k) {
      const int i = static_cast<int>(k);
      const double d = LocationTraits<L>::coordinate(a, i) - LocationTraits<L>::coordinate(b, i);
      s += weights_[k] * d * d;
    }
    return std::sqrt(s);
  }

 private:
  std::vector<double> weights_;
};

}  // namespace errfield
