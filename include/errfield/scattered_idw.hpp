#pragma once
/// Inverse-distance weighting over scattered samples: the value at a target is the weighted mean
/// of its neighbours' values, with weights 1/d^p,
///
///     v(x) = sum_i w_i v_i / sum_i w_i,   w_i = 1 / d(x, x_i)^p,
///
/// over the k nearest samples (`neighbors`, gstat's nmax) and/or those within `radius` (gstat's
/// maxdist), or all samples. A target within `exact_distance` of a sample takes that sample's
/// value (the mean of all such samples), so the estimator is exact at the data. Use it for
/// measurements that do not form a regular grid (for a complete regular 3-D grid and the paper's
/// 8-vertex rule use GridIdw). Formulas and conventions: docs/idw.md.
///
/// Generic over the Location (fixed or dynamic dimension: Eigen vectors, std::array, double),
/// the Metric and the Value. Neighbours are found with a k-d tree (nanoflann) for the Euclidean
/// metrics (EuclideanMetric, JointSpaceMetric, WeightedEuclideanMetric — the weights become a
/// scaling of the axes) and by brute force for any other metric. Ties at the k-th distance are
/// broken arbitrarily by the tree and by index by brute force.
///
/// Immutable after construction; queries are const and thread-safe. Batch prediction runs in
/// parallel (OpenMP over targets) and gives identical results for any thread count.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "errfield/concepts.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/detail/neighbour_search.hpp"
#include "errfield/detail/value_layout.hpp"
#include "errfield/error.hpp"
#include "errfield/metrics.hpp"

namespace errfield {

struct ScatteredIdwOptions {
  /// Power p >= 0 of the weights 1/d^p. Default 2, as gstat's idw().
  double power = 2.0;
  /// Use the k nearest samples (gstat's nmax); 0 = no limit.
  std::size_t neighbors = 0;
  /// Use only samples with d <= radius (gstat's maxdist), in the metric's unit; infinity = no limit.
  double radius = std::numeric_limits<double>::infinity();
  /// A target with a sample at d <= exact_distance takes that sample's value. >= 0.
  double exact_distance = 0.0;
  /// OpenMP threads for batch predictions; 0 = OpenMP's default.
  int threads = 0;
  /// Throws ArgumentError naming the field when out of domain.
  void validate() const;
};

/// Outcome of one target in ScatteredIdw::predict_with_status.
enum class ScatteredIdwStatus : std::uint8_t {
  Predicted = 0,     ///< weighted mean of >= 1 neighbours (or exact at a sample)
  NoNeighbours = 1,  ///< no sample within `radius`: the value is NaN
};

template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L>
class ScatteredIdw {
 public:
  using LocationType = L;
  using ValueType = V;

  /// Throws ArgumentError if the sizes differ, there are no samples, locations differ in their
  /// number of coordinates or an option is out of domain; InputError naming the sample if a
  /// coordinate or a value is not finite.
  ScatteredIdw(std::vector<L> locations, std::vector<V> values, const ScatteredIdwOptions& options = {},
               M metric = {});

  std::size_t size() const noexcept { return locations_.size(); }
  /// Number of coordinates of every location.
  int dimension() const noexcept { return dim_; }
  /// Whether neighbours come from a k-d tree (Euclidean metrics) rather than brute force.
  bool uses_tree() const noexcept { return tree_.has_value(); }
  const ScatteredIdwOptions& options() const noexcept { return options_; }

  /// Value at one target; NaN components when no sample lies within `radius`.
  V operator()(const L& target) const;
  /// Values at many targets (NaN where no sample lies within `radius`). Throws ArgumentError if a
  /// target has the wrong number of coordinates (checked before any work).
  std::vector<V> predict(std::span<const L> targets) const;
  /// As predict, with a status per target. Throws only for sizes that do not match.
  void predict_with_status(std::span<const L> targets, std::span<V> out, std::span<ScatteredIdwStatus> status) const;
  /// Leave-one-out: each sample predicted from all the others (the same neighbours and weights as
  /// an estimator fitted without it), from this one tree: k + 1 neighbours minus the sample itself.
  /// O(N k log N) instead of N refits.
  std::vector<V> predict_leave_one_out() const;

 private:
  struct Workspace {
    std::vector<double> query;
    std::vector<detail::EuclideanNeighbourIndex::Index> idx;
    std::vector<double> d2;
    std::vector<std::pair<detail::EuclideanNeighbourIndex::Index, double>> found;
    std::vector<std::pair<double, std::size_t>> candidates;  // (distance, sample)
  };
  Workspace make_workspace() const;
  static constexpr std::size_t kNoSample = static_cast<std::size_t>(-1);
  // `exclude`: a sample left out (leave-one-out), kNoSample for none.
  ScatteredIdwStatus predict_one(const L& target, Workspace& ws, V& out, std::size_t exclude = kNoSample) const;
  void gather(const L& target, Workspace& ws, std::size_t exclude) const;
  template <class F>
  void for_each_target(std::ptrdiff_t n, F&& work) const;
  void check_targets(std::span<const L> targets) const;

  static constexpr bool kTreeMetric =
      std::is_base_of_v<EuclideanMetric, M> || std::is_same_v<M, WeightedEuclideanMetric>;

  std::vector<L> locations_;
  std::vector<V> values_;
  ScatteredIdwOptions options_;
  M metric_;
  int dim_ = 0;
  std::vector<double> scale_;  // per-axis scale for the tree (sqrt of the metric's weights)
  std::optional<detail::EuclideanNeighbourIndex> tree_;  // set for the Euclidean metrics
};

/// The ScatteredIdw estimator for cross_validate (HoldOutEstimator): fits on the training samples
/// and predicts at the held-out locations; no prediction variance.
template <Location L, Value V, class M = EuclideanMetric>
  requires Metric<M, L>
struct ScatteredIdwEstimator {
  ScatteredIdwOptions options;
  M metric{};

  HoldOutPrediction<V> fit_predict(std::span<const L> locations, std::span<const V> values,
                                   std::span<const L> query) const {
    const ScatteredIdw<L, V, M> idw(std::vector<L>(locations.begin(), locations.end()),
                                    std::vector<V>(values.begin(), values.end()), options, metric);
    return HoldOutPrediction<V>{idw.predict(query), {}};
  }
  HoldOutPrediction<V> leave_one_out(std::span<const L> locations, std::span<const V> values) const {
    const ScatteredIdw<L, V, M> idw(std::vector<L>(locations.begin(), locations.end()),
                                    std::vector<V>(values.begin(), values.end()), options, metric);
    return HoldOutPrediction<V>{idw.predict_leave_one_out(), {}};
  }
};

// ---- implementation ------------------------------------------------------------------------------

namespace detail {
void validate_scattered_idw_options(double power, double radius, double exact_distance, int threads);
}

inline void ScatteredIdwOptions::validate() const {
  detail::validate_scattered_idw_options(power, radius, exact_distance, threads);
}

template <Location L, Value V, class M>
  requires Metric<M, L>
ScatteredIdw<L, V, M>::ScatteredIdw(std::vector<L> locations, std::vector<V> values,
                                    const ScatteredIdwOptions& options, M metric)
    : locations_(std::move(locations)), values_(std::move(values)), options_(options), metric_(std::move(metric)) {
  options_.validate();
  if (locations_.size() != values_.size())
    throw ArgumentError("ScatteredIdw: " + std::to_string(locations_.size()) + " locations but " +
                        std::to_string(values_.size()) + " values");
  if (locations_.empty()) throw ArgumentError("ScatteredIdw: no samples; expected at least 1");
  if (locations_.size() >= (std::size_t{1} << 32))
    throw ArgumentError("ScatteredIdw: " + std::to_string(locations_.size()) + " samples; at most 2^32 - 1");
  dim_ = LocationTraits<L>::size(locations_.front());
  if (dim_ < 1) throw ArgumentError("ScatteredIdw: locations have no coordinates");
  for (std::size_t i = 0; i < locations_.size(); ++i) {
    const int d = LocationTraits<L>::size(locations_[i]);
    if (d != dim_)
      throw ArgumentError("ScatteredIdw: sample " + std::to_string(i) + " has " + std::to_string(d) +
                          " coordinates; sample 0 has " + std::to_string(dim_));
    for (int k = 0; k < d; ++k)
      if (!std::isfinite(LocationTraits<L>::coordinate(locations_[i], k)))
        throw InputError("ScatteredIdw: coordinate " + std::to_string(k) + " of sample " + std::to_string(i) +
                         " is not finite");
    if (!detail::value_is_finite(values_[i]))
      throw InputError("ScatteredIdw: the value of sample " + std::to_string(i) + " is not finite");
  }
  if constexpr (kTreeMetric) {
    scale_.assign(static_cast<std::size_t>(dim_), 1.0);
    if constexpr (std::is_same_v<M, WeightedEuclideanMetric>) {
      if (metric_.weights().size() != static_cast<std::size_t>(dim_))
        throw ArgumentError("ScatteredIdw: the metric has " + std::to_string(metric_.weights().size()) +
                            " weights for locations with " + std::to_string(dim_) + " coordinates");
      for (int k = 0; k < dim_; ++k) scale_[static_cast<std::size_t>(k)] = std::sqrt(metric_.weights()[static_cast<std::size_t>(k)]);
    }
    std::vector<double> flat(locations_.size() * static_cast<std::size_t>(dim_));
    for (std::size_t i = 0; i < locations_.size(); ++i)
      for (int k = 0; k < dim_; ++k)
        flat[i * static_cast<std::size_t>(dim_) + static_cast<std::size_t>(k)] =
            scale_[static_cast<std::size_t>(k)] * LocationTraits<L>::coordinate(locations_[i], k);
    tree_.emplace(std::move(flat), static_cast<std::size_t>(dim_));
  }
}

template <Location L, Value V, class M>
  requires Metric<M, L>
typename ScatteredIdw<L, V, M>::Workspace ScatteredIdw<L, V, M>::make_workspace() const {
  Workspace ws;
  ws.query.resize(static_cast<std::size_t>(dim_));
  // one more for leave-one-out (the sample itself comes back among its nearest)
  const std::size_t k = options_.neighbors ? std::min(options_.neighbors + 1, locations_.size()) : 0;
  ws.idx.resize(k);
  ws.d2.resize(k);
  ws.candidates.reserve(k ? k : locations_.size());
  return ws;
}

// Fills ws.candidates with (metric distance, sample) of the neighbours to use.
template <Location L, Value V, class M>
  requires Metric<M, L>
void ScatteredIdw<L, V, M>::gather(const L& target, Workspace& ws, std::size_t exclude) const {
  ws.candidates.clear();
  const double radius = options_.radius;
  const bool limited_radius = std::isfinite(radius);
  const std::size_t available = locations_.size() - (exclude == kNoSample ? 0 : 1);
  const std::size_t k = options_.neighbors ? std::min(options_.neighbors, available) : 0;
  auto keep = [&](std::size_t i) {
    if (i == exclude) return;
    const double d = metric_(target, locations_[i]);
    if (!limited_radius || d <= radius) ws.candidates.emplace_back(d, i);
  };
  if constexpr (kTreeMetric) {
    for (int c = 0; c < dim_; ++c)
      ws.query[static_cast<std::size_t>(c)] = scale_[static_cast<std::size_t>(c)] * LocationTraits<L>::coordinate(target, c);
    const auto& tree = *tree_;
    if (k > 0) {
      const std::size_t want = exclude == kNoSample ? k : k + 1;
      const std::size_t found = tree.knn(ws.query.data(), want, ws.idx.data(), ws.d2.data());
      // Nearest first; the excluded sample is skipped, and without it (a duplicate location
      // may push it out of the first k + 1) the k nearest others are kept.
      std::size_t kept = 0;
      for (std::size_t j = 0; j < found && kept < k; ++j) {
        if (ws.idx[j] == exclude) continue;
        keep(ws.idx[j]);
        ++kept;
      }
      return;
    }
    if (limited_radius) {
      // Slightly wider in the tree; the exact metric decides membership.
      const double r = radius * (1.0 + 1e-12);
      tree.within(ws.query.data(), r * r, ws.found);
      for (const auto& f : ws.found) keep(f.first);
      return;
    }
  }
  for (std::size_t i = 0; i < locations_.size(); ++i) keep(i);
  if (k > 0 && ws.candidates.size() > k) {
    std::nth_element(ws.candidates.begin(), ws.candidates.begin() + static_cast<std::ptrdiff_t>(k - 1),
                     ws.candidates.end());
    ws.candidates.resize(k);
  }
}

template <Location L, Value V, class M>
  requires Metric<M, L>
ScatteredIdwStatus ScatteredIdw<L, V, M>::predict_one(const L& target, Workspace& ws, V& out,
                                                     std::size_t exclude) const {
  gather(target, ws, exclude);
  if (ws.candidates.empty()) {
    out = detail::nan_value<V>();
    return ScatteredIdwStatus::NoNeighbours;
  }
  double dmin = ws.candidates.front().first;
  for (const auto& c : ws.candidates) dmin = std::min(dmin, c.first);
  if (dmin <= options_.exact_distance) {
    // Exact at the data: the mean of the samples at (or within exact_distance of) the target.
    V sum = ValueTraits<V>::zero();
    double count = 0.0;
    for (const auto& c : ws.candidates)
      if (c.first <= options_.exact_distance) {
        sum = V(sum + values_[c.second]);
        count += 1.0;
      }
    out = V((1.0 / count) * sum);
    return ScatteredIdwStatus::Predicted;
  }
  // Weights relative to the nearest neighbour, (dmin / d)^p in (0, 1]: the same ratios as 1/d^p
  // without overflow for tiny distances or large powers.
  V acc = ValueTraits<V>::zero();
  double wsum = 0.0;
  const double p = options_.power;
  for (const auto& c : ws.candidates) {
    const double r = dmin / c.first;
    const double w = p == 1.0 ? r : (p == 2.0 ? r * r : std::pow(r, p));
    wsum += w;
    acc = V(acc + w * values_[c.second]);
  }
  out = V((1.0 / wsum) * acc);
  return ScatteredIdwStatus::Predicted;
}

template <Location L, Value V, class M>
  requires Metric<M, L>
void ScatteredIdw<L, V, M>::check_targets(std::span<const L> targets) const {
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const int d = LocationTraits<L>::size(targets[t]);
    if (d != dim_)
      throw ArgumentError("ScatteredIdw: target " + std::to_string(t) + " has " + std::to_string(d) +
                          " coordinates; the samples have " + std::to_string(dim_));
  }
}

template <Location L, Value V, class M>
  requires Metric<M, L>
V ScatteredIdw<L, V, M>::operator()(const L& target) const {
  check_targets(std::span<const L>(&target, 1));
  Workspace ws = make_workspace();
  V out = ValueTraits<V>::zero();
  predict_one(target, ws, out);
  return out;
}

template <Location L, Value V, class M>
  requires Metric<M, L>
std::vector<V> ScatteredIdw<L, V, M>::predict(std::span<const L> targets) const {
  std::vector<V> out(targets.size(), ValueTraits<V>::zero());
  std::vector<ScatteredIdwStatus> status(targets.size());
  predict_with_status(targets, out, status);
  return out;
}

template <Location L, Value V, class M>
  requires Metric<M, L>
void ScatteredIdw<L, V, M>::predict_with_status(std::span<const L> targets, std::span<V> out,
                                                std::span<ScatteredIdwStatus> status) const {
  if (out.size() != targets.size() || status.size() != targets.size())
    throw ArgumentError("ScatteredIdw::predict_with_status: " + std::to_string(targets.size()) + " targets, out has " +
                        std::to_string(out.size()) + " and status " + std::to_string(status.size()) + " entries");
  check_targets(targets);
  const auto n = static_cast<std::ptrdiff_t>(targets.size());
  // Each target is computed independently with the same operations: results do not depend on
  // the thread count or schedule.
  auto work = [&](Workspace& ws, std::ptrdiff_t t) {
    const auto i = static_cast<std::size_t>(t);
    status[i] = predict_one(targets[i], ws, out[i]);
  };
  for_each_target(n, work);
}

template <Location L, Value V, class M>
  requires Metric<M, L>
std::vector<V> ScatteredIdw<L, V, M>::predict_leave_one_out() const {
  std::vector<V> out(locations_.size(), ValueTraits<V>::zero());
  for_each_target(static_cast<std::ptrdiff_t>(locations_.size()), [&](Workspace& ws, std::ptrdiff_t t) {
    const auto i = static_cast<std::size_t>(t);
    predict_one(locations_[i], ws, out[i], i);
  });
  return out;
}

template <Location L, Value V, class M>
  requires Metric<M, L>
template <class F>
void ScatteredIdw<L, V, M>::for_each_target(std::ptrdiff_t n, F&& work) const {
  // Small batches (a cross-validation fold, a single target) run serially: starting a parallel
  // region costs more than they do.
  const bool parallel = n >= 256;
  if (options_.threads > 0) {
#pragma omp parallel num_threads(options_.threads) if (parallel)
    {
      Workspace ws = make_workspace();
#pragma omp for schedule(dynamic, 64)
      for (std::ptrdiff_t t = 0; t < n; ++t) work(ws, t);
    }
  } else {
#pragma omp parallel if (parallel)
    {
      Workspace ws = make_workspace();
#pragma omp for schedule(dynamic, 64)
      for (std::ptrdiff_t t = 0; t < n; ++t) work(ws, t);
    }
  }
}

extern template class ScatteredIdw<Eigen::Vector3d, double>;
extern template class ScatteredIdw<Eigen::Vector3d, Eigen::Vector3d>;
extern template class ScatteredIdw<Eigen::VectorXd, double>;

}  // namespace errfield
