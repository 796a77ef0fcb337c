#include "errfield/cross_validation.hpp"

#include <cmath>
#include <limits>
#include <numeric>

namespace errfield {
namespace {

// SplitMix64 (Steele, Lea, Flood 2014): a fixed, documented generator, so that the folds of a
// seed are the same with every standard library.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, bound) without modulo bias (rejection of the short last block).
  std::uint64_t below(std::uint64_t bound) {
    const std::uint64_t threshold = (0 - bound) % bound;
    for (;;) {
      const std::uint64_t r = next();
      if (r >= threshold) return r % bound;
    }
  }
};

}  // namespace

void CrossValidationOptions::validate() const {
  if (folds == 1)
    throw ArgumentError("CrossValidationOptions::folds is 1; expected 0 (leave-one-out) or at least 2");
}

std::vector<std::size_t> assign_folds(std::size_t n, const CrossValidationOptions& options) {
  options.validate();
  std::vector<std::size_t> fold(n);
  if (options.folds == 0) {
    std::iota(fold.begin(), fold.end(), std::size_t{0});
    return fold;
  }
  if (options.folds > n)
    throw ArgumentError("cross-validation: " + std::to_string(options.folds) + " folds for " + std::to_string(n) +
                        " samples; expected at most one fold per sample");
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  SplitMix64 rng{options.seed};
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.below(i)]);
  for (std::size_t r = 0; r < n; ++r) fold[order[r]] = r % options.folds;
  return fold;
}

CrossValidationSummary summarize_residuals(const Eigen::MatrixXd& residuals, std::span<const double> variance) {
  CrossValidationSummary s;
  const auto n = static_cast<std::size_t>(residuals.rows());
  const auto c = static_cast<std::size_t>(residuals.cols());
  if (!variance.empty() && variance.size() != n)
    throw ArgumentError("summarize_residuals: " + std::to_string(n) + " residuals but " +
                        std::to_string(variance.size()) + " variances");
  s.samples = n;
  s.mean_error.assign(c, 0.0);
  double sum_abs = 0.0, sum_sq = 0.0, sum_z = 0.0, sum_z2 = 0.0;
  std::size_t z_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = residuals.row(static_cast<Eigen::Index>(i));
    if (!row.allFinite()) continue;
    ++s.predicted;
    for (std::size_t k = 0; k < c; ++k) s.mean_error[k] += row(static_cast<Eigen::Index>(k));
    const double sq = row.squaredNorm();
    const double abs = std::sqrt(sq);
    sum_abs += abs;
    sum_sq += sq;
    if (abs > s.max_abs_error || s.predicted == 1) {
      s.max_abs_error = abs;
      s.max_abs_index = i;
    }
    if (c == 1 && !variance.empty() && variance[i] > 0.0 && std::isfinite(variance[i])) {
      const double z = row(0) / std::sqrt(variance[i]);
      sum_z += z;
      sum_z2 += z * z;
      ++z_count;
    }
  }
  if (s.predicted == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean_error.assign(c, nan);
    s.mean_abs_error = s.max_abs_error = s.rms_error = nan;
    return s;
  }
  const double m = static_cast<double>(s.predicted);
  for (auto& e : s.mean_error) e /= m;
  s.mean_abs_error = sum_abs / m;
  s.rms_error = std::sqrt(sum_sq / m);
  if (z_count > 0) {
    s.mean_z = sum_z / static_cast<double>(z_count);
    s.mean_squared_z = sum_z2 / static_cast<double>(z_count);
  }
  return s;
}

}  // namespace errfield
