#pragma once
/// Cokriging: the joint best linear unbiased predictor of the P components of a vector value (e.g.
/// a robot's ex, ey, ez position errors) at new locations, with the P x P covariance of its
/// prediction errors, under a linear model of coregionalization (CoregionalizationModel). Use it
/// instead of Kriging's vector values when the components are correlated with each other
/// differently at different ranges: Kriging then uses one shared variogram for every component
/// and ignores the cross-covariances; cokriging lets a component borrow from the others.
///
/// Each component's value at a target is a linear combination of all components at all (or the k
/// nearest) samples; the NP x NP system has the P x P blocks C(h_ij) of the model. The system and
/// its variance are in docs/kriging.md ("Cokriging").
///
/// Heterotopic data: a component that was not measured at a sample is NaN there (gstat's separate
/// data sets per variable, e.g. the secondary at 60 % of the primary's locations). The system then
/// has one row per measured (sample, component) only, so a sample with fewer components gives fewer
/// rows; a sample needs at least one measured component. Ordinary and universal cokriging keep one
/// unbiasedness condition per component (the weights of the predicted component sum to 1, of each
/// other component to 0, as gstat); a component measured at none of the samples used (all of them,
/// or the local back end's neighbours) cannot be predicted there: its mean and covariance entries
/// are NaN, while the other components are predicted as if it did not exist. In leave-one-out, a
/// component not measured at the left-out sample has NaN prediction, residual and covariance.
///
/// Options are KrigingOptions; what cokriging supports of them:
///   - kind: Simple (known mean per component, simple_mean: empty = 0, 1 entry for all or one per
///     component), Ordinary (one unknown mean per component, gstat's multivariable default) or
///     Universal (the same polynomial drift of drift_order in the coordinates per component, each
///     with its own coefficients);
///   - nugget: MicroScale (default, exact at the data) or MeasurementError (the nugget matrix is
///     observation noise; predictions of the error-free signal);
///   - backend: Dense (one factorization of the NP x NP matrix; dense_memory_budget_bytes checked)
///     or Local (the `neighbors` nearest samples and/or those within `radius`, by the same
///     neighbour search as Kriging, neighbour_metric included; gstat's nmax/maxdist);
///   - jitter, condition, threads, sample_labels, compute_variance as for Kriging.
/// Refused with an ArgumentError naming the option: the sparse back end, covariates,
/// drift_functions, keep_weights, DuplicatePolicy::Average (duplicates are refused, naming the
/// samples, as DuplicatePolicy::Error does).
///
/// Thread safety: a constructed Cokriging is immutable; predict() may be called concurrently. It
/// runs OpenMP over targets; every target is computed the same way whatever the thread count, so
/// the results are bit-identical for any number of threads.

#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/anisotropy.hpp"
#include "errfield/concepts.hpp"
#include "errfield/coregionalization_model.hpp"
#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield {

/// Cokriging predictions at M targets. A target that could not be solved (local back end: too
/// few neighbours, singular local system) has NaN mean and covariance; `status`, `message` and
/// `failed_targets` say how many and which came first, as KrigingPrediction does.
template <class V>
struct CokrigingPrediction {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::vector<V> mean;  ///< one per target: the P predicted components
  /// One P x P matrix per target: the covariance of the prediction errors of the components
  /// (variances on the diagonal, value unit^2). Empty unless options.compute_variance.
  std::vector<Eigen::MatrixXd> covariance;
  std::size_t failed_targets = 0;
  bool usable() const { return status == KrigingStatus::Ok || status == KrigingStatus::IllConditioned; }
  /// Prediction variance of component c at target t.
  double variance(std::size_t t, int c) const { return covariance[t](c, c); }
};

/// Leave-one-out cross-validation of cokriging: every component of sample i predicted from the
/// other samples (all components of sample i left out together).
template <class V>
struct CokrigingCrossValidation {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::vector<V> prediction;               ///< one per sample
  std::vector<V> residual;                 ///< observed - predicted
  /// P x P covariance of the residual of the observation (the prediction error plus the
  /// observation's noise when the nugget is measurement error), one per sample.
  std::vector<Eigen::MatrixXd> covariance;
  double rms_error = 0.0;       ///< sqrt(mean squared residual norm)
  double max_abs_error = 0.0;   ///< largest residual norm
  /// Mean over samples and components of residual_c^2 / covariance(c, c); ~1 when calibrated.
  double mean_squared_z = 0.0;
};

namespace detail {
class CokrigingEngine;
/// Type-erased result of the engine: one row per target.
struct CokrigingOutput {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  Eigen::MatrixXd mean;        // M x P
  Eigen::MatrixXd covariance;  // M x P*P, entry (a, b) in column a + P*b; empty without variances
  Eigen::MatrixXd residual;    // M x P, leave-one-out only
  std::size_t failed_targets = 0;
};
/// embedded: D x N coordinates after the metric and anisotropy; raw: D x N as given (drift and
/// the Euclidean neighbour search); values N x P.
std::shared_ptr<const CokrigingEngine> make_cokriging_engine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw,
                                                             Eigen::MatrixXd values,
                                                             const CoregionalizationModel& model,
                                                             const KrigingOptions& options);
const KrigingReport& cokriging_report(const CokrigingEngine& engine);
CokrigingOutput cokriging_predict(const CokrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                  const Eigen::MatrixXd& raw);
CokrigingOutput cokriging_leave_one_out(const CokrigingEngine& engine);

/// D x M matrix of the points' coordinates; throws ArgumentError for a wrong dimension and
/// InputError for a non-finite coordinate, naming `what` ("sample", "target") and its index.
template <Location L>
Eigen::MatrixXd cokriging_coordinates(std::span<const L> points, int dimension, const char* what) {
  Eigen::MatrixXd m(dimension, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int d = LocationTraits<L>::size(points[i]);
    if (d != dimension)
      throw ArgumentError(std::string("cokriging: ") + what + " " + std::to_string(i) + " has " + std::to_string(d) +
                          " coordinates; expected " + std::to_string(dimension));
    for (int k = 0; k < d; ++k) {
      const double x = LocationTraits<L>::coordinate(points[i], k);
      if (!std::isfinite(x))
        throw InputError(std::string("cokriging: coordinate ") + std::to_string(k) + " of " + what + " " +
                         std::to_string(i) + " is " + std::to_string(x) + "; expected a finite number");
      m(k, static_cast<Eigen::Index>(i)) = x;
    }
  }
  return m;
}

/// The metric's per-coordinate scales (empty = none), then the anisotropy: the lags the model sees.
Eigen::MatrixXd cokriging_embedding(const Eigen::MatrixXd& raw, const std::vector<double>& scales,
                                    const Anisotropy& anisotropy);
}  // namespace detail

/// Cokriging over samples of any Location type, a P-component Value type (P = the model's
/// component count) and a Euclidean-embeddable Metric.
///
/// Construction validates the options and data (ArgumentError / InputError naming the offending
/// option, sample and component; ResourceError when the dense NP x NP matrices exceed
/// dense_memory_budget_bytes) and, for the dense back end, factors the NP x NP covariance once:
/// O((NP)^3 / 3). Numerical outcomes of the factorization are in report(), never thrown.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
class Cokriging {
 public:
  static constexpr int kComponents = ValueTraits<V>::kComponents;

  /// samples: N locations; values: N values of P = kComponents components each, NaN where a
  /// component was not measured (at least one measured per sample; InputError otherwise).
  Cokriging(std::span<const L> samples, std::span<const V> values, const CoregionalizationModel& model,
            const KrigingOptions& options = {}, const M& metric = {})
      : scales_(EuclideanEmbedding<M>::scales(metric)), anisotropy_(model.anisotropy()) {
    if (model.components() != kComponents)
      throw ArgumentError("cokriging: the model has " + std::to_string(model.components()) +
                          " component(s) but the values have " + std::to_string(kComponents) +
                          "; expected a coregionalization model with one row and column per value component");
    if (samples.size() != values.size())
      throw ArgumentError("cokriging: " + std::to_string(samples.size()) + " sample locations but " +
                          std::to_string(values.size()) + " values; expected one value per location");
    if (samples.empty()) throw InputError("cokriging: no samples");
    dimension_ = LocationTraits<L>::size(samples[0]);
    if (!anisotropy_.isotropic() && anisotropy_.dimension() != dimension_)
      throw ArgumentError("cokriging: the model's anisotropy " + anisotropy_.to_string() + " is for " +
                          std::to_string(anisotropy_.dimension()) + " coordinates but locations have " +
                          std::to_string(dimension_));
    if (!scales_.empty() && static_cast<int>(scales_.size()) != dimension_)
      throw ArgumentError("cokriging: the metric has " + std::to_string(scales_.size()) +
                          " weights but locations have " + std::to_string(dimension_) + " coordinates");
    Eigen::MatrixXd raw = detail::cokriging_coordinates(samples, dimension_, "sample");
    Eigen::MatrixXd z(static_cast<Eigen::Index>(values.size()), kComponents);
    for (std::size_t i = 0; i < values.size(); ++i)
      for (int c = 0; c < kComponents; ++c) {
        const double v = ValueTraits<V>::component(values[i], c);
        if (std::isinf(v))
          throw InputError("cokriging: value of sample " + std::to_string(i) + " (component " + std::to_string(c) +
                           ") is " + std::to_string(v) + "; expected a finite number (or NaN where not measured)");
        z(static_cast<Eigen::Index>(i), c) = v;
      }
    Eigen::MatrixXd embedded = detail::cokriging_embedding(raw, scales_, anisotropy_);
    engine_ = detail::make_cokriging_engine(std::move(embedded), std::move(raw), std::move(z), model, options);
  }

  /// Outcome of the set-up (the dense factorization; Ok for local).
  const KrigingReport& report() const { return detail::cokriging_report(*engine_); }

  /// Predicts at the targets: dense O(M (NP)^2 P), local O(M (kP)^3). Throws ArgumentError when a
  /// target has the wrong dimension, InputError for a non-finite coordinate.
  CokrigingPrediction<V> predict(std::span<const L> targets) const {
    const Eigen::MatrixXd raw = detail::cokriging_coordinates(targets, dimension_, "target");
    detail::CokrigingOutput out =
        detail::cokriging_predict(*engine_, detail::cokriging_embedding(raw, scales_, anisotropy_), raw);
    CokrigingPrediction<V> p;
    p.status = out.status;
    p.message = std::move(out.message);
    p.failed_targets = out.failed_targets;
    for (Eigen::Index t = 0; t < out.mean.rows(); ++t) p.mean.push_back(row_value(out.mean, t));
    for (Eigen::Index t = 0; t < out.covariance.rows(); ++t) p.covariance.push_back(row_matrix(out.covariance, t));
    return p;
  }

  /// Leave-one-out: all components of each sample left out together. Dense: closed form from the
  /// one factorization (the block form of Dubrule 1983); local: one neighbourhood solve per sample.
  CokrigingCrossValidation<V> leave_one_out() const {
    detail::CokrigingOutput out = detail::cokriging_leave_one_out(*engine_);
    CokrigingCrossValidation<V> cv;
    cv.status = out.status;
    cv.message = std::move(out.message);
    const Eigen::Index n = out.mean.rows();
    double sum_sq = 0.0, max_abs = 0.0, z2 = 0.0;
    std::size_t z_count = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      cv.prediction.push_back(row_value(out.mean, i));
      cv.residual.push_back(row_value(out.residual, i));
      cv.covariance.push_back(row_matrix(out.covariance, i));
      // Components not measured at sample i (NaN residual) do not count.
      const double norm2 = out.residual.row(i).unaryExpr([](double r) { return std::isnan(r) ? 0.0 : r; }).squaredNorm();
      if (!std::isfinite(norm2) || out.residual.row(i).array().isNaN().all()) continue;
      sum_sq += norm2;
      max_abs = std::max(max_abs, std::sqrt(norm2));
      for (int c = 0; c < kComponents; ++c) {
        const double v = cv.covariance.back()(c, c);
        if (v > 0.0 && !std::isnan(out.residual(i, c))) {
          z2 += out.residual(i, c) * out.residual(i, c) / v;
          ++z_count;
        }
      }
    }
    if (n > 0) {
      cv.rms_error = std::sqrt(sum_sq / static_cast<double>(n));
      cv.max_abs_error = max_abs;
      cv.mean_squared_z = z_count ? z2 / static_cast<double>(z_count) : 0.0;
    }
    return cv;
  }

 private:
  static V row_value(const Eigen::MatrixXd& m, Eigen::Index r) {
    V v = ValueTraits<V>::zero();
    double& (*writable)(V&, int) = &ValueTraits<V>::component;
    for (int c = 0; c < kComponents; ++c) writable(v, c) = m(r, c);
    return v;
  }
  static Eigen::MatrixXd row_matrix(const Eigen::MatrixXd& m, Eigen::Index r) {
    Eigen::MatrixXd c(kComponents, kComponents);
    for (int b = 0; b < kComponents; ++b)
      for (int a = 0; a < kComponents; ++a) c(a, b) = m(r, a + kComponents * b);
    return c;
  }

  std::vector<double> scales_;
  Anisotropy anisotropy_;
  int dimension_ = 0;
  std::shared_ptr<const detail::CokrigingEngine> engine_;
};

}  // namespace errfield
