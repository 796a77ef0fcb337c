#pragma once
/// Kriging: the best linear unbiased predictor of an error field at new locations, with its
/// prediction variance. Use it instead of IDW when the data are irregular, when you want to know
/// how uncertain a prediction is, or when a fitted variogram says how the error decorrelates.
///
/// Variants (KrigingOptions::kind): simple (known mean), ordinary (unknown constant mean) and
/// universal (polynomial drift of order 0, 1 or 2 in the coordinates plus user drift functions).
/// External drift (KrigingOptions::covariates): covariate values given per sample and per target
/// add drift columns; ordinary kriging with covariates is kriging with external drift (gstat's
/// `krige(z ~ cov, ...)`), universal kriging with covariates has the polynomial drift plus them.
/// Back ends (KrigingOptions::backend), one interface:
///   - Dense: one Cholesky factorization of the N x N covariance; any N whose matrix fits in
///     memory (N up to ~20,000; the memory budget is checked and a ResourceError names the others).
///   - Local: the k nearest samples (or those within a radius) per target, a small dense solve per
///     target; N up to 10^6 and beyond.
///   - Sparse: compactly supported models (sph, wen, plus nugget) only; the sparse covariance is
///     factored once by CHOLMOD; for large N with a short range.
/// The mathematics, variance conventions and the choice of back end are in docs/kriging.md.
///
/// Conventions follow gstat's `krige`: the model is a VariogramModel in gstat's `vgm` vocabulary
/// (`range` of exp/gau is the scale parameter a, not the practical range); by default the nugget is
/// micro-scale variance, so kriging is exact at the data and the variance there is 0; optionally
/// the nugget is measurement error (NuggetTreatment::MeasurementError, like gstat's `Err`): the
/// prediction is then of the error-free signal and smooths the data.
///
/// Vector values (e.g. a 3-D position error) are kriged component by component with one shared
/// factorization (several right-hand sides). This is the intrinsic coregionalization model with
/// one variogram for every component: the weights, and hence the kriging variance, are the same
/// for all components; cross-covariances between components are not used. See docs/kriging.md.
/// To use them (a linear model of coregionalization), see Cokriging (cokriging.hpp).
///
/// Thread safety: a constructed Kriging object is immutable; predict() may be called concurrently.
/// predict() itself runs OpenMP over targets.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/error.hpp"
#include "errfield/metrics.hpp"
#include "errfield/row_labels.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

/// Which mean the field is assumed to have.
enum class KrigingKind {
  Simple,     ///< known constant mean (KrigingOptions::simple_mean)
  Ordinary,   ///< unknown constant mean, estimated jointly (weights sum to 1)
  Universal,  ///< unknown polynomial drift (KrigingOptions::drift_order) + drift_functions
};

/// How predictions are computed; all give the same answer where they overlap (tested).
enum class KrigingBackend { Dense, Local, Sparse };

/// What the nugget of the model stands for.
enum class NuggetTreatment {
  /// gstat's `krige` default: micro-scale variation. Exact at data points (variance 0 there),
  /// the variance far from data reaches the total sill.
  MicroScale,
  /// Measurement error (gstat's `Err`): predictions are of the error-free signal, smooth the data,
  /// and the variance is that of the signal (reaches sill - nugget far from the data).
  MeasurementError,
};

/// What to do with samples closer than KrigingOptions::duplicate_distance.
///
/// Average merges each group of k samples into one at its first sample's location, with the mean
/// value and the variance of that mean's observation error:
///   - measurement variances e_i: sum(e_i) / k^2 (the mean of independent measurements);
///   - NuggetTreatment::MeasurementError: the nugget is independent noise on every observation,
///     so the merged sample carries nugget / k (plus the above);
///   - NuggetTreatment::MicroScale: the nugget is real variation of the field at a scale below the
///     sample spacing; repeats at one location see the same micro-scale value, so averaging does
///     not reduce it: the merged sample keeps the full nugget in C(0) and only the measurement
///     variance is divided.
/// With identical locations and equal measurement variance within a group, predictions and
/// variances then equal those of kriging with every repeat kept as a separate sample (tested);
/// with unequal variances the merged value is the plain mean (unbiased, with its exact variance,
/// not the inverse-variance-weighted one). Cross-validation predicts merged samples, and the
/// residual variances use the merged sample's own noise.
enum class DuplicatePolicy {
  Error,    ///< throw InputError naming the two sample indices and their lag
  Average,  ///< merge each group into its first sample: mean value, variance of the mean (above)
};

/// Outcome of a factorization or a prediction. Ok and IllConditioned come with predictions.
enum class KrigingStatus {
  Ok,
  IllConditioned,       ///< solved, but the condition number exceeded max_condition_number
  NotPositiveDefinite,  ///< covariance not positive definite even after the jitter retries
  SingularDrift,        ///< drift terms linearly dependent at the samples (F'K^-1F singular);
                        ///< the message names the first covariate that is collinear, if any
  TooFewSamples,        ///< fewer samples (or neighbours) than drift terms, or none at all
};

std::string_view kriging_status_name(KrigingStatus status);
std::string_view kriging_kind_name(KrigingKind kind);
std::string_view kriging_backend_name(KrigingBackend backend);
/// "dense" | "local" | "sparse"; throws ArgumentError listing the choices.
KrigingBackend kriging_backend_from_name(std::string_view name);

/// Local back end: by which distance the neighbours of a target are chosen (and `radius` measured).
/// Model: the lag the variogram sees (the metric's weights and the model's anisotropy applied) -
/// the neighbours that matter most to the model. Euclidean: the plain Euclidean distance of the
/// coordinates as given, as R gstat does (its nmax/maxdist ignore anisotropy). Both are
/// defensible; they give different neighbourhoods, and so different predictions, only with an
/// anisotropic model or a weighted metric.
enum class NeighbourMetric { Model, Euclidean };
std::string_view neighbour_metric_name(NeighbourMetric metric);
/// "model" | "euclidean"; throws ArgumentError listing the choices.
NeighbourMetric neighbour_metric_from_name(std::string_view name);

/// A user drift function of the sample coordinates (the Location's own coordinates, not the
/// metric's embedding). Called once per sample and per target, never in a hot loop.
using DriftFunction = std::function<double(std::span<const double> coordinates)>;

/// Everything that decides how kriging is done. Plain data; call validate() (the Kriging
/// constructor does) to get an ArgumentError naming the first bad field.
struct KrigingOptions {
  KrigingKind kind = KrigingKind::Ordinary;
  /// Simple kriging mean, per value component: empty = 0, one entry = same for all components.
  std::vector<double> simple_mean;
  /// Universal kriging: polynomial drift order in the coordinates, 0, 1 or 2 (order 0 is a
  /// constant, i.e. ordinary kriging plus the drift_functions).
  int drift_order = 1;
  /// Universal kriging: extra drift terms (added to the polynomial ones).
  std::vector<DriftFunction> drift_functions;
  /// External drift: names of covariates whose values are known at every sample and target (e.g.
  /// a distance to a river, a temperature), each one more drift column after the polynomial terms
  /// and the drift_functions. Ordinary or universal kriging only (not simple). The values come
  /// with the data: Kriging's constructor and predict() taking a covariates matrix (one row per
  /// point, column j = covariates[j]); the names are used in messages. Duplicates merged by
  /// DuplicatePolicy::Average keep the covariates of their group's first sample.
  std::vector<std::string> covariates;
  NuggetTreatment nugget = NuggetTreatment::MicroScale;

  KrigingBackend backend = KrigingBackend::Dense;
  /// Local: number of nearest samples per target (gstat's nmax); 0 = no limit (then radius must
  /// be finite). Must be at least the number of drift terms.
  std::size_t neighbors = 0;
  /// Local: only samples at lag <= radius (gstat's maxdist: a sample at exactly the radius is
  /// included), lag unit; infinity = no limit. With `neighbors`, the k nearest of those; equal
  /// distances are taken in increasing sample order.
  double radius = std::numeric_limits<double>::infinity();
  /// Local: which distance chooses the neighbours and measures `radius` (NeighbourMetric).
  NeighbourMetric neighbour_metric = NeighbourMetric::Model;
  /// Local: a target with fewer neighbours than this (the k nearest within the radius, before the
  /// octant limit) is not predicted: NaN and status TooFewSamples (gstat's nmin, without its
  /// `force`). 0 = no minimum.
  std::size_t min_neighbours = 0;
  /// Local: keep at most this many of the neighbours (nearest first) in each quadrant (2-D), octant
  /// (3-D) or half (1-D) around the target, in the space `neighbour_metric` measures in (gstat's
  /// omax, applied after nmax/maxdist as gstat does; a sample on a dividing axis counts in one
  /// quadrant, turning around the target as gstat's rule). 0 = no limit. 1 to 3 coordinates.
  std::size_t octant_max = 0;

  bool compute_variance = true;
  /// Return the kriging weights of every target (dense: N per target; local: k per target).
  /// Not available with the sparse back end.
  bool keep_weights = false;

  /// Names of the samples for error messages ("S.csv:7"), e.g. from the CSV they were read
  /// from; used only when it labels exactly as many rows as there are samples (a subset, as in
  /// k-fold cross-validation, falls back to "samples i and j", 0-based).
  RowLabels sample_labels;
  /// Samples at lag <= duplicate_distance are duplicates (0 = only exactly equal locations).
  double duplicate_distance = 0.0;
  DuplicatePolicy duplicates = DuplicatePolicy::Error;

  /// Factorization policy: when the covariance is not numerically positive definite, add
  /// jitter = initial_jitter * total sill to the diagonal and retry, multiplying it by
  /// jitter_growth each time, at most max_jitter_retries times. The jitter used is reported.
  int max_jitter_retries = 4;
  double initial_jitter = 1e-12;
  double jitter_growth = 100.0;
  /// Above this (estimated, 1-norm) condition number the status is IllConditioned.
  double max_condition_number = 1e12;

  /// Dense: bytes the N x N matrices may take (K and its factor); beyond it ResourceError.
  std::size_t dense_memory_budget_bytes = std::size_t{4} << 30;
  /// Targets per batch of the dense/sparse variance solves (memory N x batch per thread; 64 keeps
  /// a batch in a 2 MiB L2 cache up to N ~ 4,000).
  std::size_t target_batch = 64;
  /// OpenMP threads for predict(); 0 = OpenMP's default.
  int threads = 0;

  /// Throws ArgumentError naming the field, its value and what is expected.
  void validate() const;
};

/// How the samples were factored.
struct KrigingReport {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;  ///< human-readable detail (empty when Ok and nothing to say)
  /// Estimated condition number of the covariance matrix (dense: 1-norm estimate from the
  /// Cholesky factor; sparse: CHOLMOD's rough estimate); NaN where not computed (local).
  double condition_number = std::numeric_limits<double>::quiet_NaN();
  double jitter = 0.0;               ///< absolute value added to the diagonal (0 = none)
  std::size_t samples_used = 0;      ///< after merging duplicates
  std::size_t merged_duplicates = 0; ///< samples folded into another by DuplicatePolicy::Average
  std::size_t drift_terms = 0;       ///< columns of the drift matrix F (0 for simple kriging)
  /// True when predictions are available (Ok or IllConditioned).
  bool usable() const { return status == KrigingStatus::Ok || status == KrigingStatus::IllConditioned; }
};

/// Kriging weights in compressed rows: the weights of target t are weight[k] on sample
/// sample[k] for k in [offset[t], offset[t+1]). Sample indices are those given to the constructor.
struct KrigingWeights {
  std::vector<std::size_t> offset;
  std::vector<std::size_t> sample;
  std::vector<double> weight;
};

/// Predictions at targets. Targets that could not be solved (local back end: too few
/// neighbours, singular local system) have NaN mean and variance, and `status`/`message` say how
/// many and which came first; with a usable status every value is finite.
template <class V>
struct KrigingPrediction {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::vector<V> mean;            ///< one per target
  std::vector<double> variance;   ///< one per target (same for every component); empty if not asked
  KrigingWeights weights;         ///< empty unless keep_weights
  std::size_t failed_targets = 0;
  bool usable() const { return status == KrigingStatus::Ok || status == KrigingStatus::IllConditioned; }
};

/// Cross-validation of kriging: per-sample prediction from the other samples (LOO) or from the
/// other folds (k-fold), residual = observed - predicted, and summaries.
template <class V>
struct KrigingCrossValidation {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  std::vector<V> prediction;    ///< one per (merged) sample
  std::vector<V> residual;      ///< observed - predicted
  std::vector<double> variance; ///< variance of the residual of the observation
  double mean_error = 0.0;      ///< mean residual (all components pooled)
  double rms_error = 0.0;       ///< sqrt(mean squared residual norm)
  double max_abs_error = 0.0;   ///< largest residual norm
  double mean_squared_z = 0.0;  ///< mean of |residual|^2 / (components * variance); ~1 if calibrated
};

/// A metric kriging can use: one that is Euclidean after scaling each coordinate, so that the
/// covariance models stay positive definite and a kd-tree can find neighbours. Specialize
/// `scales` (empty = unscaled) for another such metric.
template <class M>
struct EuclideanEmbedding;
template <>
struct EuclideanEmbedding<EuclideanMetric> {
  static std::vector<double> scales(const EuclideanMetric&) { return {}; }
};
template <>
struct EuclideanEmbedding<JointSpaceMetric> {
  static std::vector<double> scales(const JointSpaceMetric&) { return {}; }
};
template <>
struct EuclideanEmbedding<WeightedEuclideanMetric> {
  static std::vector<double> scales(const WeightedEuclideanMetric& m) {
    std::vector<double> s;
    for (double w : m.weights()) s.push_back(std::sqrt(w));
    return s;
  }
};

template <class M>
concept EmbeddableMetric = requires(const M& m) {
  { EuclideanEmbedding<M>::scales(m) } -> std::convertible_to<std::vector<double>>;
};

namespace detail {
class KrigingEngine;
/// Type-erased result of the engine: one row per target, one column per value component.
struct KrigingOutput {
  KrigingStatus status = KrigingStatus::Ok;
  std::string message;
  Eigen::MatrixXd mean;
  Eigen::VectorXd variance;
  Eigen::MatrixXd residual;  // cross-validation only
  KrigingWeights weights;
  std::size_t failed_targets = 0;
};
std::shared_ptr<const KrigingEngine> make_kriging_engine(Eigen::MatrixXd embedded, Eigen::MatrixXd raw,
                                                         Eigen::MatrixXd values,
                                                         Eigen::VectorXd measurement_variance,
                                                         const VariogramModel& model,
                                                         const KrigingOptions& options);
const KrigingReport& engine_report(const KrigingEngine& engine);
const KrigingOptions& engine_options(const KrigingEngine& engine);
KrigingOutput engine_predict(const KrigingEngine& engine, const Eigen::MatrixXd& embedded,
                             const Eigen::MatrixXd& raw);
/// engine_predict with the weights for this call (KrigingOptions::keep_weights's form).
KrigingOutput engine_predict_with_weights(const KrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                          const Eigen::MatrixXd& raw);
/// Block kriging: `embedded`/`raw` hold consecutive groups of `points_per_block` points, one group per
/// block (the same offsets in every group); one prediction per block (dense and local back ends).
KrigingOutput engine_predict_blocks(const KrigingEngine& engine, const Eigen::MatrixXd& embedded,
                                    const Eigen::MatrixXd& raw, const Eigen::VectorXd& block_weights);
KrigingOutput engine_leave_one_out(const KrigingEngine& engine);
Eigen::MatrixXd engine_leave_one_out_residuals_of(const KrigingEngine& engine, const Eigen::MatrixXd& values);
KrigingOutput engine_k_fold(const KrigingEngine& engine, int folds, std::uint64_t seed);
/// `raw` (D x M coordinates) with the covariates (M x k, k = options.covariates.size()) appended
/// as rows D..D+k-1, as the engine takes them. Throws ArgumentError when the covariates' shape
/// does not match and InputError naming the row (`labels`, or "<what> i") and the covariate when
/// a value is not finite.
Eigen::MatrixXd append_covariates(Eigen::MatrixXd raw, const Eigen::MatrixXd& covariates,
                                  const KrigingOptions& options, const char* what, const RowLabels* labels);
}  // namespace detail

/// Block kriging (gstat's `krige(..., block = c(dx, dy))`): the prediction of the average of the
/// field over a block centred on each target, with that average's error variance. The block
/// average is integrated by a product rule of points_per_axis points per coordinate: Gauss-Legendre
/// (gstat's default, 4 per axis) or a regular grid at -size/2 + (i + 0.5) size / n with equal
/// weights (gstat's `set = list(nblockdiscr = n)`). Covariances and drift terms are averaged over
/// the points with the rule's weights, and the block-to-block covariance over all their pairs
/// without the nugget (the micro-scale variation averages out over a block, as in gstat).
struct BlockDiscretization {
  std::vector<double> size;  ///< block extent along each coordinate, in the coordinates' unit (> 0)
  int points_per_axis = 4;
  enum class Rule { GaussLegendre, Regular } rule = Rule::GaussLegendre;
  /// D x points_per_axis^D offsets from the block centre, and their weights (summing to 1). Throws
  /// ArgumentError when `size` does not have `dimension` positive finite entries, points_per_axis
  /// is not in [1, 64], or the block has more than 4,096 points.
  Eigen::MatrixXd offsets(int dimension) const;
  Eigen::VectorXd weights(int dimension) const;
};

/// Kriging over samples of any Location type, Value type and Euclidean-embeddable Metric.
///
/// Construction validates the options and data (throws ArgumentError / InputError naming the
/// offending field, sample and value; ResourceError when the dense matrices exceed the budget) and,
/// for the dense and sparse back ends, factors the covariance once: O(N^3/3) dense. Numerical
/// outcomes of the factorization are in report(), never thrown.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
class Kriging {
 public:
  /// samples: N locations; values: N values; measurement_variance: empty or N values >= 0 in the
  /// value unit squared (added to the diagonal, per point; e.g. a tracker's variance).
  Kriging(std::span<const L> samples, std::span<const V> values, const VariogramModel& model,
          const KrigingOptions& options = {}, const M& metric = {},
          std::span<const double> measurement_variance = {})
      : Kriging(samples, values, Eigen::MatrixXd(), model, options, metric, measurement_variance) {}

  /// With external drift: covariates is N x k, row i the values at sample i of
  /// options.covariates[0..k-1] (k = 0: as the constructor above).
  Kriging(std::span<const L> samples, std::span<const V> values, const Eigen::MatrixXd& covariates,
          const VariogramModel& model, const KrigingOptions& options = {}, const M& metric = {},
          std::span<const double> measurement_variance = {})
      : scales_(EuclideanEmbedding<M>::scales(metric)), anisotropy_(model.anisotropy()) {
    options.validate();
    covariate_count_ = options.covariates.size();
    if (samples.size() != values.size())
      throw ArgumentError("kriging: " + std::to_string(samples.size()) + " sample locations but " +
                          std::to_string(values.size()) + " values; expected one value per location");
    if (!measurement_variance.empty() && measurement_variance.size() != samples.size())
      throw ArgumentError("kriging: " + std::to_string(measurement_variance.size()) +
                          " measurement variances for " + std::to_string(samples.size()) +
                          " samples; expected none or one per sample");
    if (samples.empty()) throw InputError("kriging: no samples");
    dimension_ = LocationTraits<L>::size(samples[0]);
    if (!anisotropy_.isotropic() && anisotropy_.dimension() != dimension_)
      throw ArgumentError("kriging: the model's anisotropy " + anisotropy_.to_string() + " is for " +
                          std::to_string(anisotropy_.dimension()) + " coordinates but locations have " +
                          std::to_string(dimension_));
    Eigen::MatrixXd raw = to_matrix(samples, "sample");
    Eigen::MatrixXd values_matrix(static_cast<Eigen::Index>(values.size()), kComponents);
    for (std::size_t i = 0; i < values.size(); ++i)
      for (int c = 0; c < kComponents; ++c) {
        const double v = ValueTraits<V>::component(values[i], c);
        if (!std::isfinite(v))
          throw InputError("kriging: value of sample " + std::to_string(i) + " (component " +
                           std::to_string(c) + ") is " + std::to_string(v) + "; expected a finite number");
        values_matrix(static_cast<Eigen::Index>(i), c) = v;
      }
    Eigen::VectorXd meas = Eigen::Map<const Eigen::VectorXd>(
        measurement_variance.data(), static_cast<Eigen::Index>(measurement_variance.size()));
    Eigen::MatrixXd embedded = embed(raw);
    if (covariate_count_ > 0 || covariates.size() > 0)
      raw = detail::append_covariates(std::move(raw), covariates, options, "sample", &options.sample_labels);
    engine_ = detail::make_kriging_engine(std::move(embedded), std::move(raw), std::move(values_matrix),
                                          std::move(meas), model, options);
  }

  /// Outcome of the set-up (factorization for dense/sparse).
  const KrigingReport& report() const { return detail::engine_report(*engine_); }

  /// Predicts at the targets. O(M N) for the means, plus O(M N^2) for dense variances; local
  /// O(M k^3). Throws ArgumentError when a target has the wrong dimension or a non-finite coordinate.
  KrigingPrediction<V> predict(std::span<const L> targets) const {
    if (covariate_count_ > 0)
      throw ArgumentError("kriging: the drift has " + std::to_string(covariate_count_) +
                          " covariate(s); pass their values at the targets (predict(targets, covariates))");
    Eigen::MatrixXd raw = to_matrix(targets, "target");
    return convert_prediction(detail::engine_predict(*engine_, embed(raw), raw));
  }

  /// predict(), and the kriging weights of this call's targets (KrigingPrediction::weights, as
  /// KrigingOptions::keep_weights gives them for every call): what a caller that needs the weights
  /// now and then asks for, without paying their extra solve on every prediction. Dense and local
  /// back ends (ArgumentError with the sparse one).
  KrigingPrediction<V> predict_with_weights(std::span<const L> targets) const {
    if (covariate_count_ > 0)
      throw ArgumentError("kriging: the drift has " + std::to_string(covariate_count_) +
                          " covariate(s); predict_with_weights takes none");
    Eigen::MatrixXd raw = to_matrix(targets, "target");
    return convert_prediction(detail::engine_predict_with_weights(*engine_, embed(raw), raw));
  }

  /// With external drift: covariates is M x k, row t the covariate values at target t. `labels`
  /// (optional) names the targets in errors ("T.csv:9").
  KrigingPrediction<V> predict(std::span<const L> targets, const Eigen::MatrixXd& covariates,
                               const RowLabels& labels = {.source = {}, .lines = {}, .noun = "target"}) const {
    Eigen::MatrixXd raw = to_matrix(targets, "target");
    Eigen::MatrixXd embedded = embed(raw);
    raw = detail::append_covariates(std::move(raw), covariates, engine_options(), "target", &labels);
    return convert_prediction(detail::engine_predict(*engine_, embedded, raw));
  }

  /// Block kriging at blocks centred on `centres` (see BlockDiscretization); with external drift,
  /// `covariates` (M x k) holds each block's covariate values (the block's average, as gstat takes
  /// them). Dense and local back ends (local: the neighbours of the block's centre). Throws
  /// ArgumentError for the sparse back end or a bad block.
  KrigingPrediction<V> predict_blocks(std::span<const L> centres, const BlockDiscretization& block,
                                      const Eigen::MatrixXd& covariates = {},
                                      const RowLabels& labels = {.source = {}, .lines = {}, .noun = "target"}) const {
    const Eigen::MatrixXd offsets = block.offsets(dimension_);
    const Eigen::Index g = offsets.cols(), m = static_cast<Eigen::Index>(centres.size());
    const Eigen::MatrixXd centre_raw = to_matrix(centres, "target");
    Eigen::MatrixXd raw(dimension_, m * g);
    for (Eigen::Index t = 0; t < m; ++t) raw.middleCols(t * g, g) = offsets.colwise() + centre_raw.col(t);
    const Eigen::MatrixXd embedded = embed(raw);
    if (covariate_count_ > 0 || covariates.size() > 0) {
      Eigen::MatrixXd with = detail::append_covariates(centre_raw, covariates, engine_options(), "target", &labels);
      raw.conservativeResize(with.rows(), Eigen::NoChange);
      for (Eigen::Index t = 0; t < m; ++t)
        raw.block(dimension_, t * g, with.rows() - dimension_, g).colwise() = with.col(t).tail(with.rows() - dimension_);
    }
    return convert_prediction(detail::engine_predict_blocks(*engine_, embedded, raw, block.weights(dimension_)));
  }

  /// Leave-one-out cross-validation: closed form for the dense back end (Dubrule 1983), one local
  /// solve per sample for the local back end; not offered for sparse (use k_fold).
  KrigingCrossValidation<V> leave_one_out() const {
    return convert_cv(detail::engine_leave_one_out(*engine_));
  }

  /// The residuals leave_one_out's weights give for other values at the same samples:
  /// v_i - sum_j w_ij v_j, one row per sample in the order given, any number of columns. The
  /// weights do not depend on the values, so this is how a quantity fitted beside the kriging (a
  /// regression on the same samples) enters a leave-one-out of the two together. Dense back end
  /// and no merged duplicates only (ArgumentError otherwise); one more O(N^3/3) pass.
  Eigen::MatrixXd leave_one_out_residuals_of(const Eigen::MatrixXd& values) const {
    return detail::engine_leave_one_out_residuals_of(*engine_, values);
  }

  /// k-fold cross-validation with a deterministic shuffle from `seed`; every back end.
  KrigingCrossValidation<V> k_fold(int folds, std::uint64_t seed = 1) const {
    return convert_cv(detail::engine_k_fold(*engine_, folds, seed));
  }

 private:
  static constexpr int kComponents = ValueTraits<V>::kComponents;

  Eigen::MatrixXd to_matrix(std::span<const L> points, const char* what) const {
    Eigen::MatrixXd m(dimension_, static_cast<Eigen::Index>(points.size()));
    for (std::size_t i = 0; i < points.size(); ++i) {
      const int d = LocationTraits<L>::size(points[i]);
      if (d != dimension_)
        throw ArgumentError(std::string("kriging: ") + what + " " + std::to_string(i) + " has " +
                            std::to_string(d) + " coordinates; expected " + std::to_string(dimension_));
      for (int k = 0; k < d; ++k) {
        const double x = LocationTraits<L>::coordinate(points[i], k);
        if (!std::isfinite(x))
          throw InputError(std::string("kriging: coordinate ") + std::to_string(k) + " of " + what +
                           " " + std::to_string(i) + " is " + std::to_string(x) +
                           "; expected a finite number");
        m(k, static_cast<Eigen::Index>(i)) = x;
      }
    }
    return m;
  }

  // The metric's scaling, then the model's anisotropy: the engine sees isotropic Euclidean lags,
  // so every back end (and the local back end's neighbour search) honours both.
  Eigen::MatrixXd embed(const Eigen::MatrixXd& raw) const {
    if (scales_.empty() && anisotropy_.isotropic()) return raw;
    if (!scales_.empty() && static_cast<int>(scales_.size()) != dimension_)
      throw ArgumentError("kriging: the metric has " + std::to_string(scales_.size()) +
                          " weights but locations have " + std::to_string(dimension_) + " coordinates");
    Eigen::MatrixXd e = raw;
    if (!scales_.empty())
      for (int k = 0; k < dimension_; ++k) e.row(k) *= scales_[static_cast<std::size_t>(k)];
    if (anisotropy_.isotropic()) return e;
    Eigen::MatrixXd mapped(e.rows(), e.cols());
    for (Eigen::Index j = 0; j < e.cols(); ++j) anisotropy_.apply(e.col(j).data(), mapped.col(j).data(), dimension_);
    return mapped;
  }

  static V row_value(const Eigen::MatrixXd& m, Eigen::Index r) {
    V v = ValueTraits<V>::zero();
    // Select the writable overload explicitly: for double, component(double) and
    // component(double&) are otherwise ambiguous on an lvalue.
    double& (*writable)(V&, int) = &ValueTraits<V>::component;
    for (int c = 0; c < kComponents; ++c) writable(v, c) = m(r, c);
    return v;
  }

  static KrigingPrediction<V> convert_prediction(detail::KrigingOutput out) {
    KrigingPrediction<V> p;
    p.status = out.status;
    p.message = std::move(out.message);
    p.failed_targets = out.failed_targets;
    p.mean.reserve(static_cast<std::size_t>(out.mean.rows()));
    for (Eigen::Index r = 0; r < out.mean.rows(); ++r) p.mean.push_back(row_value(out.mean, r));
    p.variance.assign(out.variance.data(), out.variance.data() + out.variance.size());
    p.weights = std::move(out.weights);
    return p;
  }

  static KrigingCrossValidation<V> convert_cv(detail::KrigingOutput out) {
    KrigingCrossValidation<V> cv;
    cv.status = out.status;
    cv.message = std::move(out.message);
    const Eigen::Index n = out.mean.rows();
    double sum = 0.0, sum_sq = 0.0, max_abs = 0.0, z2 = 0.0;
    std::size_t z_count = 0;
    for (Eigen::Index r = 0; r < n; ++r) {
      cv.prediction.push_back(row_value(out.mean, r));
      cv.residual.push_back(row_value(out.residual, r));
      const double norm2 = out.residual.row(r).squaredNorm();
      sum += out.residual.row(r).sum();
      sum_sq += norm2;
      max_abs = std::max(max_abs, std::sqrt(norm2));
      if (out.variance.size() == n && out.variance[r] > 0.0) {
        z2 += norm2 / (kComponents * out.variance[r]);
        ++z_count;
      }
    }
    cv.variance.assign(out.variance.data(), out.variance.data() + out.variance.size());
    if (n > 0) {
      cv.mean_error = sum / static_cast<double>(n * kComponents);
      cv.rms_error = std::sqrt(sum_sq / static_cast<double>(n));
      cv.max_abs_error = max_abs;
      cv.mean_squared_z = z_count ? z2 / static_cast<double>(z_count) : 0.0;
    }
    return cv;
  }

  const KrigingOptions& engine_options() const { return detail::engine_options(*engine_); }

  std::vector<double> scales_;
  Anisotropy anisotropy_;
  int dimension_ = 0;
  std::size_t covariate_count_ = 0;
  std::shared_ptr<const detail::KrigingEngine> engine_;
};

namespace detail {
/// A kriging prediction as cross_validate takes it: NaN values (and variances) for every query
/// when there are no predictions, and the variance of the residual of a new observation (plus the
/// nugget when it is measurement error).
template <Value V>
HoldOutPrediction<V> hold_out_prediction(KrigingPrediction<V> p, std::size_t queries, const VariogramModel& model,
                                         const KrigingOptions& options) {
  HoldOutPrediction<V> out;
  if (p.mean.size() != queries) {
    V nan_value = ValueTraits<V>::zero();
    double& (*writable)(V&, int) = &ValueTraits<V>::component;
    for (int c = 0; c < ValueTraits<V>::kComponents; ++c) writable(nan_value, c) = std::numeric_limits<double>::quiet_NaN();
    out.value.assign(queries, nan_value);
    if (options.compute_variance) out.variance.assign(queries, std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  out.value = std::move(p.mean);
  out.variance = std::move(p.variance);
  if (options.nugget == NuggetTreatment::MeasurementError)
    for (double& v : out.variance) v += model.nugget();
  return out;
}
}  // namespace detail

/// Kriging as a HoldOutEstimator for cross_validate (cross_validation.hpp), so that kriging and
/// IDW are validated on the same folds. fit_predict factors the training samples and predicts at
/// the held-out locations; the variance is that of the residual of a new observation there: the
/// kriging variance, plus the nugget when the nugget is measurement error. Targets that cannot be
/// predicted (unusable factorization, failed local solve) get NaN, which cross_validate counts.
/// For leave-one-out with the dense back end prefer Kriging::leave_one_out (closed form, one
/// factorization instead of N).
/// With external drift (options.covariates) use ExternalDriftKrigingEstimator below.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L> && EmbeddableMetric<M>
struct KrigingEstimator {
  VariogramModel model;
  KrigingOptions options;
  M metric{};

  HoldOutPrediction<V> fit_predict(std::span<const L> locations, std::span<const V> values,
                                   std::span<const L> query) const {
    const Kriging<L, V, M> kriging(locations, values, model, options, metric);
    return detail::hold_out_prediction(kriging.predict(query), query.size(), model, options);
  }
};

/// Kriging with external drift as a HoldOutEstimator for cross_validate: each location is the
/// `dimension` coordinates followed by the values of options.covariates at that point, so that
/// cross_validate draws the same folds as for KrigingEstimator on the coordinates alone (the
/// covariates travel with their samples). fit_predict as KrigingEstimator's.
template <Value V>
struct ExternalDriftKrigingEstimator {
  VariogramModel model;
  KrigingOptions options;
  Eigen::Index dimension = 0;

  HoldOutPrediction<V> fit_predict(std::span<const Eigen::VectorXd> locations, std::span<const V> values,
                                   std::span<const Eigen::VectorXd> query) const {
    auto split = [&](std::span<const Eigen::VectorXd> joined, std::vector<Eigen::VectorXd>& coords) {
      const auto k = static_cast<Eigen::Index>(options.covariates.size());
      Eigen::MatrixXd cov(static_cast<Eigen::Index>(joined.size()), k);
      coords.clear();
      for (std::size_t i = 0; i < joined.size(); ++i) {
        coords.emplace_back(joined[i].head(dimension));
        cov.row(static_cast<Eigen::Index>(i)) = joined[i].tail(k).transpose();
      }
      return cov;
    };
    std::vector<Eigen::VectorXd> train, test;
    const Eigen::MatrixXd train_cov = split(locations, train);
    const Eigen::MatrixXd test_cov = split(query, test);
    const Kriging<Eigen::VectorXd, V> kriging(std::span<const Eigen::VectorXd>(train), values, train_cov, model, options);
    KrigingPrediction<V> p;
    if (kriging.report().usable()) p = kriging.predict(std::span<const Eigen::VectorXd>(test), test_cov);
    return detail::hold_out_prediction(std::move(p), query.size(), model, options);
  }
};

}  // namespace errfield
