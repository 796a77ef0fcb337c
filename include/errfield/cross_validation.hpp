#pragma once
/// Cross-validation of scattered estimators (IDW, kriging, ...): how well does an estimator
/// predict a sample it was not given? Use it to choose a power, a neighbourhood or a variogram
/// model, and to report an honest prediction error (gstat's `krige.cv`).
///
/// - **Leave-one-out** (folds = 0): each sample is predicted from all the others.
/// - **k-fold** (folds = k): the samples are split into k folds of (nearly) equal size by a
///   seeded shuffle (the same seed gives the same folds on every platform); each fold is predicted
///   from the other k - 1.
///
/// The estimator is anything with `fit_predict(locations, values, query)` returning a
/// HoldOutPrediction (concept HoldOutEstimator): it fits on the training samples and predicts at
/// the held-out locations, optionally with a prediction variance (kriging). ScatteredIdwEstimator
/// (scattered_idw.hpp) is one; a kriging estimator plugs in the same way.
///
/// Per sample: the residual e_i = observed_i - predicted_i (gstat's convention). Summary over the
/// predicted samples: mean error (per component), mean |e|, max |e|, RMS = sqrt(mean |e|^2), where
/// |e| is the Euclidean norm for vector values; with variances (scalar values), the mean and mean
/// square of the z-scores e_i / sqrt(var_i) (~0 and ~1 for a well-calibrated kriging model).
/// Definitions: docs/idw.md.

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"
#include "errfield/error.hpp"

namespace errfield {

/// What an estimator returns for held-out locations. A NaN component marks a location it could not
/// predict (no neighbour in range, a failed solve); such samples are counted, not summarized.
template <Value V>
struct HoldOutPrediction {
  std::vector<V> value;          ///< one per query location
  std::vector<double> variance;  ///< one per query location, or empty when the estimator has none
};

/// An estimator cross_validate can use: fit on (locations, values), predict at `query`.
template <class E, class L, class V>
concept HoldOutEstimator =
    Location<L> && Value<V> &&
    requires(const E& e, std::span<const L> locations, std::span<const V> values, std::span<const L> query) {
      { e.fit_predict(locations, values, query) } -> std::same_as<HoldOutPrediction<V>>;
    };

/// An estimator that also predicts every sample from all the others in one pass (e.g. IDW: one
/// k-d tree, k + 1 neighbours minus the sample itself); cross_validate uses it for leave-one-out
/// instead of N refits. It must give what N calls of fit_predict would.
template <class E, class L, class V>
concept LeaveOneOutEstimator =
    HoldOutEstimator<E, L, V> && requires(const E& e, std::span<const L> locations, std::span<const V> values) {
      { e.leave_one_out(locations, values) } -> std::same_as<HoldOutPrediction<V>>;
    };

struct CrossValidationOptions {
  /// 0 = leave-one-out; otherwise the number of folds k, 2 <= k <= number of samples.
  std::size_t folds = 0;
  /// Seed of the fold assignment (k-fold only).
  std::uint64_t seed = 1;
  /// Throws ArgumentError when folds == 1.
  void validate() const;
};

/// Summary of the residuals of the predicted samples (units: those of the value, e.g. mm).
struct CrossValidationSummary {
  std::size_t samples = 0;            ///< all samples
  std::size_t predicted = 0;          ///< samples with a prediction
  std::vector<double> mean_error;     ///< per component: mean of observed - predicted
  double mean_abs_error = 0.0;        ///< mean |e|
  double max_abs_error = 0.0;         ///< max |e|
  std::size_t max_abs_index = 0;      ///< sample with the largest |e|
  double rms_error = 0.0;             ///< sqrt(mean |e|^2)
  std::optional<double> mean_z;       ///< mean of e / sqrt(var) (scalar values with variances)
  std::optional<double> mean_squared_z;  ///< mean of e^2 / var (gstat's MSDR)
};

template <Value V>
struct CrossValidationResult {
  std::vector<std::size_t> fold;  ///< fold of each sample (LOO: its own index)
  std::vector<V> predicted;       ///< NaN components where not predicted
  std::vector<V> residual;        ///< observed - predicted (NaN where not predicted)
  std::vector<double> variance;   ///< prediction variances, empty when the estimator has none
  CrossValidationSummary summary;
};

/// Fold of each of n samples: LOO gives fold i to sample i; k-fold shuffles 0..n-1 with a
/// SplitMix64-seeded generator (platform-independent) and deals the shuffled samples to folds
/// 0, 1, ..., k-1, 0, 1, ... Throws ArgumentError if k > n or k == 1.
std::vector<std::size_t> assign_folds(std::size_t n, const CrossValidationOptions& options);

/// Summary of residuals given as an N x C matrix (NaN rows = not predicted); `variance` empty or N.
CrossValidationSummary summarize_residuals(const Eigen::MatrixXd& residuals, std::span<const double> variance = {});

/// Cross-validates `estimator` on the samples. Throws ArgumentError for mismatched sizes, fewer
/// than 2 samples or bad options, and Error if the estimator returns the wrong number of
/// predictions; whatever the estimator throws propagates.
template <Location L, Value V, class E>
  requires HoldOutEstimator<E, L, V>
CrossValidationResult<V> cross_validate(const E& estimator, std::span<const L> locations, std::span<const V> values,
                                        const CrossValidationOptions& options = {});

// ---- implementation ------------------------------------------------------------------------------

template <Location L, Value V, class E>
  requires HoldOutEstimator<E, L, V>
CrossValidationResult<V> cross_validate(const E& estimator, std::span<const L> locations, std::span<const V> values,
                                        const CrossValidationOptions& options) {
  options.validate();
  const std::size_t n = locations.size();
  if (values.size() != n)
    throw ArgumentError("cross_validate: " + std::to_string(n) + " locations but " + std::to_string(values.size()) +
                        " values");
  if (n < 2) throw ArgumentError("cross_validate: " + std::to_string(n) + " samples; expected at least 2");
  constexpr int C = ValueTraits<V>::kComponents;
  CrossValidationResult<V> result;
  result.fold = assign_folds(n, options);
  const std::size_t folds = options.folds ? options.folds : n;
  result.predicted.assign(n, ValueTraits<V>::zero());
  result.residual.assign(n, ValueTraits<V>::zero());
  std::vector<double> variance(n, 0.0);
  bool has_variance = true;

  // Samples of each fold, in input order.
  std::vector<std::vector<std::size_t>> members(folds);
  for (std::size_t i = 0; i < n; ++i) members[result.fold[i]].push_back(i);

  if constexpr (LeaveOneOutEstimator<E, L, V>) {
    if (options.folds == 0) {
      const HoldOutPrediction<V> p = estimator.leave_one_out(locations, values);
      if (p.value.size() != n || (!p.variance.empty() && p.variance.size() != n))
        throw Error("cross_validate: the estimator's leave-one-out returned " + std::to_string(p.value.size()) +
                    " predictions and " + std::to_string(p.variance.size()) + " variances for " + std::to_string(n) +
                    " samples");
      for (std::size_t i = 0; i < n; ++i) {
        result.predicted[i] = p.value[i];
        result.residual[i] = V(values[i] - p.value[i]);
      }
      if (p.variance.empty()) has_variance = false;
      else variance = p.variance;
      members.clear();  // nothing left to refit
    }
  }

  std::vector<L> train_loc, query_loc;
  std::vector<V> train_val;
  for (std::size_t f = 0; f < members.size(); ++f) {
    const auto& held = members[f];
    if (held.empty()) continue;
    train_loc.clear();
    train_val.clear();
    query_loc.clear();
    std::size_t next = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (next < held.size() && held[next] == i) {
        query_loc.push_back(locations[i]);
        ++next;
      } else {
        train_loc.push_back(locations[i]);
        train_val.push_back(values[i]);
      }
    }
    const HoldOutPrediction<V> p = estimator.fit_predict(std::span<const L>(train_loc), std::span<const V>(train_val),
                                                         std::span<const L>(query_loc));
    if (p.value.size() != held.size() || (!p.variance.empty() && p.variance.size() != held.size()))
      throw Error("cross_validate: the estimator returned " + std::to_string(p.value.size()) + " predictions and " +
                  std::to_string(p.variance.size()) + " variances for " + std::to_string(held.size()) +
                  " held-out samples");
    if (p.variance.empty()) has_variance = false;
    for (std::size_t j = 0; j < held.size(); ++j) {
      const std::size_t i = held[j];
      result.predicted[i] = p.value[j];
      result.residual[i] = V(values[i] - p.value[j]);
      if (!p.variance.empty()) variance[i] = p.variance[j];
    }
  }
  if (has_variance) result.variance = std::move(variance);

  Eigen::MatrixXd residuals(static_cast<Eigen::Index>(n), C);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < C; ++c) residuals(static_cast<Eigen::Index>(i), c) = ValueTraits<V>::component(std::as_const(result.residual[i]), c);
  result.summary = summarize_residuals(residuals, result.variance);
  return result;
}

}  // namespace errfield
