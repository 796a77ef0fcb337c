#pragma once
/// Conditional Gaussian simulation: realisations of the field that honour the samples and the
/// variogram model, for propagating an uncertainty into a decision the pointwise kriging variance
/// cannot answer (the probability that a whole path stays within a tolerance, the spread of a
/// maximum, of an average over a region).
///
/// Method: conditioning by kriging. For each draw, an unconditional realisation Y of a zero-mean
/// Gaussian field with the model's covariance is simulated at the samples and the targets together
/// (with the samples' observation noise added at the samples); then
///
///   Z_sim(x) = Z*(x) + [ Y(x) - Y*(x) ]
///
/// where Z* and Y* are the kriging predictions from the samples' data and from Y at the samples,
/// with the same weights. Z_sim is then a draw from the conditional distribution the kriging
/// describes: its mean over draws is the kriging mean and its variance the kriging variance
/// (exactly, for an exact Y and the dense back end; the drift of universal kriging or external
/// drift is filtered by the weights, so Y needs none). At a sample location without nugget every
/// draw reproduces the datum. The kriging of all draws shares one set of weights: one set-up (one
/// Cholesky for the dense back end, one solve per target for the local one) for any number of draws.
///
/// The unconditional realisation Y:
///  - Cholesky (exact): the covariance of the distinct locations factored once (pivoted LDL').
///    O(M^3/3) for M distinct locations (samples + targets); the default up to 2,000 of them.
///  - Sequential (approximate): along a random path, each location's value is drawn from its
///    simple-kriging distribution given the `neighbours` nearest locations simulated before it
///    (in the model's metric: anisotropy applied). O(M k^3) for k neighbours. Exact when k covers
///    every earlier location; with a few tens of neighbours the screening effect makes it close
///    for the usual models (measured: ConditionalSimulationStudy, docs/kriging.md). Draws are grouped: one
///    path (and one set of neighbour weights) serves `draws_per_path` draws (default 100).
///
/// Nugget: with NuggetTreatment::MicroScale it is part of the simulated field (independent between
/// distinct locations, the same at one location); with MeasurementError the field is the signal
/// and the nugget is noise of the samples' observations only. A sample's measurement variance is
/// noise of its observation.
///
/// Reproducible: the same inputs and seed give the same draws, bit for bit, for any thread count
/// (random numbers are drawn in one fixed order; the parallel loops compute independent items).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/kriging.hpp"

namespace errfield {

enum class UnconditionalMethod { Auto, Cholesky, Sequential };
std::string_view unconditional_method_name(UnconditionalMethod method);
/// "auto" | "cholesky" | "sequential"; throws ArgumentError listing the choices.
UnconditionalMethod unconditional_method_from_name(std::string_view name);

struct SimulationOptions {
  std::size_t draws = 1;  ///< number of realisations (at least 1)
  std::uint64_t seed = 1;
  UnconditionalMethod method = UnconditionalMethod::Auto;
  /// Auto: Cholesky up to this many distinct locations (samples + targets), sequential beyond.
  std::size_t cholesky_limit = 2000;
  /// Sequential: earlier-simulated locations each location is conditioned on. 60 by measurement
  /// (docs/kriging.md): with 30, the draws of a gau model were 8 % too variable (sph 2 %); with 60
  /// every model tried was within 1 % of the exact draws.
  std::size_t neighbours = 60;
  /// Sequential: draws that share one random path (and its neighbour weights). 1 = a path per draw.
  /// 100 (10 before issue 36), as gstat, whose draws all share one path: the path's neighbour
  /// search and solves are most of the cost, so 100 draws cost about one path. Each draw has the
  /// same distribution whatever this is; draws on one path share its (small) approximation error.
  std::size_t draws_per_path = 100;
  /// Bytes the draws and the kriging of them may take (the (samples + targets) x draws x components
  /// doubles, three times over); beyond it ResourceError before any work.
  std::size_t memory_budget_bytes = std::size_t{4} << 30;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

/// Realisations at the targets, with the kriging they are conditioned by.
template <class V>
struct SimulationResult {
  KrigingStatus status = KrigingStatus::Ok;  ///< of the kriging (as KrigingPrediction's)
  std::string message;
  std::vector<V> mean;                 ///< the kriging mean, one per target
  std::vector<double> variance;        ///< the kriging variance, one per target
  std::vector<std::vector<V>> draws;   ///< draws[k][t]: realisation k at target t (NaN where not kriged)
  std::size_t failed_targets = 0;
  std::string method;                  ///< "cholesky" or "sequential (60 neighbours, 100 draws per random path, ...)"
  bool usable() const { return status == KrigingStatus::Ok || status == KrigingStatus::IllConditioned; }
};

namespace detail {

/// Places (D x M, column-major, already embedded: metric scales and anisotropy applied) where a
/// zero-mean Gaussian field is simulated. Returns M x columns values, each column an independent
/// realisation with covariance C(h) of `model` for h > 0 and `zero_lag_variance` at h = 0 (the
/// same value at coincident places).
Eigen::MatrixXd simulate_unconditional_embedded(const Eigen::MatrixXd& places, const VariogramModel& model,
                                                double zero_lag_variance, std::size_t columns,
                                                const SimulationOptions& options, std::string& method);

struct SimulationOutput {
  KrigingOutput kriging;            ///< mean (T x C) and variance of the data's kriging
  std::vector<Eigen::MatrixXd> draws;  ///< T x C each
  std::string method;
};

SimulationOutput simulate_conditional_embedded(Eigen::MatrixXd sample_embedded, Eigen::MatrixXd sample_raw,
                                               Eigen::MatrixXd values, Eigen::VectorXd measurement_variance,
                                               const Eigen::MatrixXd& target_embedded, const Eigen::MatrixXd& target_raw,
                                               const VariogramModel& model, const KrigingOptions& kriging,
                                               const SimulationOptions& options);

/// Locations as a D x n matrix (throws naming `what` and the index for a wrong dimension or a
/// non-finite coordinate), and their embedding for the covariance (metric scales, then anisotropy).
template <Location L>
Eigen::MatrixXd locations_as_columns(std::span<const L> points, int dimension, const char* what) {
  Eigen::MatrixXd m(dimension, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int d = LocationTraits<L>::size(points[i]);
    if (d != dimension)
      throw ArgumentError(std::string("simulation: ") + what + " " + std::to_string(i) + " has " + std::to_string(d) +
                          " coordinates; expected " + std::to_string(dimension));
    for (int k = 0; k < d; ++k) {
      const double x = LocationTraits<L>::coordinate(points[i], k);
      if (!std::isfinite(x))
        throw InputError(std::string("simulation: coordinate ") + std::to_string(k) + " of " + what + " " +
                         std::to_string(i) + " is " + std::to_string(x) + "; expected a finite number");
      m(k, static_cast<Eigen::Index>(i)) = x;
    }
  }
  return m;
}
Eigen::MatrixXd embed_columns(const Eigen::MatrixXd& raw, const std::vector<double>& scales, const Anisotropy& anisotropy);

}  // namespace detail

/// Unconditional realisations of a zero-mean Gaussian field with the covariance of `model` (nugget
/// included: independent between distinct locations) at `locations`: columns x draws values, one
/// column per draw. Throws ArgumentError for an unbounded model or bad options.
template <Location L, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
Eigen::MatrixXd simulate_unconditional(std::span<const L> locations, const VariogramModel& model,
                                       const SimulationOptions& options = {}, const M& metric = {}) {
  options.validate();
  if (locations.empty()) return Eigen::MatrixXd(0, static_cast<Eigen::Index>(options.draws));
  const int dimension = LocationTraits<L>::size(locations[0]);
  const Eigen::MatrixXd raw = detail::locations_as_columns(locations, dimension, "location");
  std::string method;
  return detail::simulate_unconditional_embedded(
      detail::embed_columns(raw, EuclideanEmbedding<M>::scales(metric), model.anisotropy()), model, model.sill(),
      options.draws, options, method);
}

/// Conditional realisations at `targets` given the samples (see above). The kriging options
/// (kind, drift, nugget treatment, back end, neighbourhood, duplicates) are those of Kriging and
/// mean the same; with the local back end the conditioning uses each target's neighbourhood.
/// Throws as Kriging's constructor does, and ResourceError beyond the memory budget; the kriging's
/// numerical outcome is in the result's status.
/// External drift (KrigingOptions::covariates): `sample_covariates` (N x k) and `target_covariates`
/// (T x k) hold the covariates' values, as Kriging's constructor and predict take them.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
SimulationResult<V> simulate_conditional(std::span<const L> samples, std::span<const V> values,
                                         const Eigen::MatrixXd& sample_covariates, std::span<const L> targets,
                                         const Eigen::MatrixXd& target_covariates, const VariogramModel& model,
                                         const KrigingOptions& kriging = {}, const SimulationOptions& options = {},
                                         const M& metric = {}, std::span<const double> measurement_variance = {}) {
  kriging.validate();
  options.validate();
  constexpr int kComponents = ValueTraits<V>::kComponents;
  if (samples.size() != values.size())
    throw ArgumentError("simulation: " + std::to_string(samples.size()) + " sample locations but " +
                        std::to_string(values.size()) + " values; expected one value per location");
  if (!measurement_variance.empty() && measurement_variance.size() != samples.size())
    throw ArgumentError("simulation: " + std::to_string(measurement_variance.size()) + " measurement variances for " +
                        std::to_string(samples.size()) + " samples; expected none or one per sample");
  if (samples.empty()) throw InputError("simulation: no samples");
  const int dimension = LocationTraits<L>::size(samples[0]);
  const std::vector<double> scales = EuclideanEmbedding<M>::scales(metric);
  Eigen::MatrixXd sample_raw = detail::locations_as_columns(samples, dimension, "sample");
  Eigen::MatrixXd target_raw = detail::locations_as_columns(targets, dimension, "target");
  Eigen::MatrixXd value_matrix(static_cast<Eigen::Index>(values.size()), kComponents);
  for (std::size_t i = 0; i < values.size(); ++i)
    for (int c = 0; c < kComponents; ++c) {
      const double v = ValueTraits<V>::component(values[i], c);
      if (!std::isfinite(v))
        throw InputError("simulation: value of sample " + std::to_string(i) + " (component " + std::to_string(c) +
                         ") is " + std::to_string(v) + "; expected a finite number");
      value_matrix(static_cast<Eigen::Index>(i), c) = v;
    }
  Eigen::VectorXd meas = Eigen::Map<const Eigen::VectorXd>(measurement_variance.data(),
                                                           static_cast<Eigen::Index>(measurement_variance.size()));
  Eigen::MatrixXd sample_embedded = detail::embed_columns(sample_raw, scales, model.anisotropy());
  const Eigen::MatrixXd target_embedded = detail::embed_columns(target_raw, scales, model.anisotropy());
  // The engine takes the covariates as rows after the coordinates (the drift's, not the lags').
  if (!kriging.covariates.empty() || sample_covariates.size() > 0 || target_covariates.size() > 0) {
    sample_raw = detail::append_covariates(std::move(sample_raw), sample_covariates, kriging, "sample",
                                           &kriging.sample_labels);
    target_raw = detail::append_covariates(std::move(target_raw), target_covariates, kriging, "target", nullptr);
  }
  detail::SimulationOutput out = detail::simulate_conditional_embedded(
      std::move(sample_embedded), std::move(sample_raw), std::move(value_matrix), std::move(meas), target_embedded,
      target_raw, model, kriging, options);

  auto row_value = [](const Eigen::MatrixXd& m, Eigen::Index r) {
    V v = ValueTraits<V>::zero();
    double& (*writable)(V&, int) = &ValueTraits<V>::component;
    for (int c = 0; c < kComponents; ++c) writable(v, c) = m(r, c);
    return v;
  };
  SimulationResult<V> result;
  result.status = out.kriging.status;
  result.message = std::move(out.kriging.message);
  result.failed_targets = out.kriging.failed_targets;
  result.method = std::move(out.method);
  for (Eigen::Index r = 0; r < out.kriging.mean.rows(); ++r) result.mean.push_back(row_value(out.kriging.mean, r));
  result.variance.assign(out.kriging.variance.data(), out.kriging.variance.data() + out.kriging.variance.size());
  for (Eigen::MatrixXd& d : out.draws) {
    std::vector<V> draw;
    draw.reserve(static_cast<std::size_t>(d.rows()));
    for (Eigen::Index r = 0; r < d.rows(); ++r) draw.push_back(row_value(d, r));
    result.draws.push_back(std::move(draw));
    d = Eigen::MatrixXd();  // the next draw reuses its memory rather than fresh pages
  }
  return result;
}

/// Without covariates.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
SimulationResult<V> simulate_conditional(std::span<const L> samples, std::span<const V> values,
                                         std::span<const L> targets, const VariogramModel& model,
                                         const KrigingOptions& kriging = {}, const SimulationOptions& options = {},
                                         const M& metric = {}, std::span<const double> measurement_variance = {}) {
  return simulate_conditional<L, V, M>(samples, values, Eigen::MatrixXd(), targets, Eigen::MatrixXd(), model, kriging,
                                       options, metric, measurement_variance);
}

}  // namespace errfield
