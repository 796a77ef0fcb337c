#pragma once
/// The empirical (experimental) semivariogram of an error field: how different the errors at two
/// locations are, as a function of the lag between the locations. Use it to see over which
/// distances errors are similar (SPEC section 4, paper eqs. 15-18) and as the input of
/// fit_variogram (variogram_fit.hpp).
///
/// For the pairs (i, j) whose lag h_ij = metric(x_i, x_j) falls in bin k (N_k pairs):
///   Matheron         gamma_k = 1/(2 N_k) sum (z_i - z_j)^2
///   Cressie-Hawkins  gamma_k = 0.5 [ (1/N_k) sum |z_i - z_j|^(1/2) ]^4 / (0.457 + 0.494/N_k)
///   Dowd             gamma_k = 0.5 * 2.198 [ median |z_i - z_j| ]^2
/// Vector values (e.g. a 3-D position error): each component c has its own variogram
/// gamma_k[c], and the reported gamma_k is their sum. For Matheron that is exactly half the mean
/// squared norm of the difference, 1/(2 N_k) sum |z_i - z_j|^2. Units: value unit^2 (mm^2);
/// lags in the metric's unit. Formulas and conventions: docs/geostatistics.md.
///
/// Bins: edges e_0 < ... < e_n; half-open [e_k, e_{k+1}) by default (the paper's tables), or
/// gstat's convention ([e_0, e_1], then (e_k, e_{k+1}]); gstat's `boundaries=` argument is
/// e_1..e_n when e_0 = 0. Pairs outside [e_0, e_n] are ignored.
///
/// Cost: one pass over the N(N-1)/2 pairs, each lag computed once; memory O(N K + bins K C)
/// with C = kVariogramChunks fixed row chunks (never an N x N matrix). When the largest bin edge
/// (the cutoff) is short against the extent of the locations, only the pairs that can lie within
/// it are enumerated (options.pair_search; Euclidean, joint-space and weighted Euclidean metrics;
/// other metrics always use all pairs): in the common case - Euclidean or joint-space lags in 1 to
/// 3 dimensions, one value component, Matheron or Cressie-Hawkins, every pair, any direction but
/// a tilted dip test, equally spaced bins (at most 1024) - by sorted columns (pair_columns.hpp),
/// each pair in range once in an order of its own: the same pairs in every bin (counts exactly),
/// sums equal to the all-pairs ones up to the rounding of the summation order (a relative
/// ~m 2^-53 for m pairs), bit-identical for any thread count; otherwise by a cell list
/// (kernels/pair_cells.hpp) in the all-pairs order, the same result bit for bit. Either costs
/// O(N D) more memory (the cell list O(N) more per thread). Dowd's estimator needs
/// medians, hence a second pass and storage of every binned difference, bounded by
/// EmpiricalVariogramOptions::max_stored_differences. Parallel with OpenMP; the chunks
/// and the order in which their sums are merged do not depend on the number of threads, so the
/// result is bit-identical for any thread count. For one value component, Euclidean lags and
/// equal-width bins the pair loop runs an AVX2 or AVX-512 kernel when the CPU has it
/// (kernels/pair_binning_simd.hpp, chosen at run time), bit-identical to the portable one.
///
/// Cross-variograms (options.cross_variograms, Matheron only): for components a < b also
///   gamma_ab,k = 1/(2 N_k) sum (z_i[a] - z_j[a]) (z_i[b] - z_j[b])
/// over the same pairs (gstat's cross-variogram of collocated data), in
/// EmpiricalVariogram::cross_gamma; same single pass, same thread-independent result.
///
/// Directional variograms (gstat's alpha/tol.hor, per-coordinate): options.direction keeps only
/// the pairs whose separation points along a direction (variogram_direction.hpp); the others
/// fall in no bin. Same single pass, plus one angle test per pair, no SIMD kernel.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "errfield/concepts.hpp"
#include "errfield/error.hpp"
#include "errfield/metrics.hpp"
#include "errfield/variogram_direction.hpp"

namespace errfield {

enum class VariogramEstimator {
  Matheron,        ///< method of moments, mean of squared differences
  CressieHawkins,  ///< robust: fourth power of the mean root absolute difference, bias-corrected
  Dowd,            ///< robust: 1.099 median(|z_i - z_j|)^2; stores the binned differences (see options)
};

/// Which side of an edge a lag equal to the edge belongs to.
enum class BinConvention {
  HalfOpen,  ///< [e_k, e_{k+1}) for every bin (the paper's tables)
  Gstat,     ///< [e_0, e_1], then (e_k, e_{k+1}] (R gstat's `boundaries=`)
};

/// "matheron" / "cressie" / "dowd"; "paper" (HalfOpen) / "gstat". The parsers throw ArgumentError listing
/// the known names.
std::string_view estimator_name(VariogramEstimator e);
VariogramEstimator estimator_from_name(std::string_view name);
std::string_view convention_name(BinConvention c);
BinConvention convention_from_name(std::string_view name);

/// Lag-bin edges. Immutable value type.
class LagBins {
 public:
  /// Bins [lo + k w, lo + (k+1) w) for k = 0..n-1 with n = ceil((max_lag - lo) / w) (a quotient
  /// within 1e-9 of an integer counts as that integer), so the last edge is >= max_lag.
  /// Throws ArgumentError naming `width` (must be finite and > 0), `max_lag` (must be > lo) or
  /// `lo` (finite, >= 0), or when more than 10^7 bins would result.
  static LagBins uniform(double lo, double max_lag, double width);
  /// Explicit edges e_0 < e_1 < ... (at least two, finite, e_0 >= 0). Throws ArgumentError
  /// naming the first offending edge by index.
  static LagBins from_edges(std::vector<double> edges);
  /// R gstat's default when no bins are given: cutoff = 0.33333 x the diagonal of the
  /// coordinates' bounding box (any number of columns, one location per row), 15 bins of width
  /// cutoff / 15 from 0 - gstat's `variogram(z ~ 1, data)` in 2-D exactly (use
  /// BinConvention::Gstat for its boundaries); in other dimensions the same rule over all
  /// coordinates (gstat 2.1's own 3-D default is not). Throws ArgumentError when the locations do
  /// not span a positive diagonal.
  static LagBins gstat_default(const Eigen::MatrixXd& coordinates);

  const std::vector<double>& edges() const noexcept { return edges_; }
  std::size_t size() const noexcept { return edges_.size() - 1; }
  bool is_uniform() const noexcept { return uniform_; }
  double lag_lo(std::size_t k) const { return edges_.at(k); }
  double lag_hi(std::size_t k) const { return edges_.at(k + 1); }

 private:
  std::vector<double> edges_{0.0, 1.0};
  bool uniform_ = false;
};

/// How empirical_variogram finds the pairs: every pair, or only the pairs that sorted columns or a
/// cell list put within the largest bin edge (the cutoff). The same pairs either way; the sums are
/// the same bit for bit, or to the rounding of the summation order where the sorted columns run
/// (see empirical_variogram; docs/geostatistics.md).
enum class PairSearch {
  Automatic,  ///< columns or a cell list when the cutoff is short against the extent of the locations
  AllPairs,   ///< all N(N-1)/2 pairs
  CellList,   ///< columns or a cell list whenever the metric allows one (see empirical_variogram)
};

/// Numerical and sampling policy of empirical_variogram.
struct EmpiricalVariogramOptions {
  VariogramEstimator estimator = VariogramEstimator::Matheron;
  BinConvention convention = BinConvention::HalfOpen;
  /// Fraction of pairs used, in (0, 1]. Below 1 a pair is kept when a seeded hash of its index is
  /// below the fraction: deterministic, independent of threads, about fraction x N(N-1)/2 pairs.
  double pair_fraction = 1.0;
  std::uint64_t seed = 0;
  /// OpenMP threads; 0 = the OpenMP default. Does not change the result.
  int threads = 0;
  /// Dowd only: it keeps |z_i - z_j| of every binned pair (and component) to take medians, in a
  /// second pass. Above this many stored values (8 bytes each) empirical_variogram throws
  /// ResourceError before allocating; lower pair_fraction or raise the budget.
  std::uint64_t max_stored_differences = 25'000'000;
  /// The per-chunk sums (kVariogramChunks x (bins + 1) x (2 + components) doubles, fixed so the
  /// result does not depend on threads) grow with the number of bins: above this many bytes
  /// empirical_variogram throws ResourceError before allocating, naming the bin count (use fewer
  /// bins). 1 GiB allows ~700,000 bins for one component (`--bins 0:1e7:1` asked for 15 GB).
  std::uint64_t max_accumulator_bytes = std::uint64_t{1} << 30;
  /// Only the pairs whose separation points along this direction (variogram_direction.hpp);
  /// default: every pair. Checked against the location dimension by empirical_variogram.
  VariogramDirection direction;
  /// Which pairs are enumerated; does not change the result (only the time it takes).
  PairSearch pair_search = PairSearch::Automatic;
  /// Also the cross-variogram of every pair of components (EmpiricalVariogram::cross_gamma).
  /// Matheron only: validate() refuses it with cressie or dowd, whose transforms of |z_i - z_j|
  /// have no signed cross counterpart.
  bool cross_variograms = false;
  /// Throws ArgumentError naming the offending field.
  void validate() const;
};

/// One lag bin of the result. Empty bin: pairs = 0, lag_mean and gamma NaN.
struct VariogramBin {
  double lag_lo = 0.0;    ///< lower edge (lag unit)
  double lag_hi = 0.0;    ///< upper edge (lag unit)
  double lag_mean = 0.0;  ///< mean lag of the pairs in the bin
  double gamma = 0.0;     ///< semivariance, value unit^2 (sum over components)
  std::uint64_t pairs = 0;
};

/// Result of empirical_variogram.
struct EmpiricalVariogram {
  std::vector<VariogramBin> bins;
  /// bins x components: the variogram of each value component (NaN for an empty bin). For a
  /// scalar value its single column equals bins[k].gamma.
  Eigen::MatrixXd component_gamma;
  VariogramEstimator estimator = VariogramEstimator::Matheron;
  BinConvention convention = BinConvention::HalfOpen;
  double pair_fraction = 1.0;
  VariogramDirection direction;  ///< the pairs' direction filter (default: all)
  /// With options.cross_variograms: bins x K(K-1)/2, the cross-variogram of components a < b in
  /// column cross_column(a, b, K), i.e. the order (0,1), (0,2), ..., (1,2), ... (NaN for an empty
  /// bin); otherwise empty.
  Eigen::MatrixXd cross_gamma;
  int components() const noexcept { return static_cast<int>(component_gamma.cols()); }
  /// Column of the pair a < b in cross_gamma for K components.
  static int cross_column(int a, int b, int K) noexcept { return a * K - a * (a + 1) / 2 + (b - a - 1); }
  /// gamma_ab in bin k: component_gamma for a == b, cross_gamma otherwise (either order of a, b).
  /// Throws ArgumentError for a != b without cross variograms or for an index out of range.
  double gamma_of(std::size_t bin, int a, int b) const;
};

/// Empirical variogram of values (N x K, one row per location, K >= 1 components) at
/// `locations` (N >= 2) under `metric`. Throws ArgumentError for invalid options or mismatched
/// sizes, InputError (naming the row and column) for a non-finite coordinate or value,
/// ResourceError when Dowd's storage would exceed options.max_stored_differences.
/// Thread-safe (no shared state). Instantiated in the library for Eigen 1-, 2-, 3-, 6-D and
/// dynamic-size locations with EuclideanMetric, JointSpaceMetric and WeightedEuclideanMetric.
template <Location L, Metric<L> M>
EmpiricalVariogram empirical_variogram(std::span<const L> locations, const Eigen::MatrixXd& values,
                                       const M& metric, const LagBins& bins,
                                       const EmpiricalVariogramOptions& options = {});

/// Same for values of any Value type (double, Eigen::Vector3d, ...).
template <Location L, Metric<L> M, Value V>
EmpiricalVariogram empirical_variogram(std::span<const L> locations, std::span<const V> values,
                                       const M& metric, const LagBins& bins,
                                       const EmpiricalVariogramOptions& options = {}) {
  constexpr int K = ValueTraits<V>::kComponents;
  Eigen::MatrixXd flat(static_cast<Eigen::Index>(values.size()), K);
  for (std::size_t i = 0; i < values.size(); ++i)
    for (int c = 0; c < K; ++c)
      flat(static_cast<Eigen::Index>(i), c) = ValueTraits<V>::component(values[i], c);
  return empirical_variogram<L, M>(locations, flat, metric, bins, options);
}

/// Locations given as the rows of an N x D matrix (any D >= 1), e.g. columns read from a CSV.
/// Dispatches to the 1-, 2-, 3- and 6-D instantiations, dynamic size otherwise.
EmpiricalVariogram empirical_variogram(const Eigen::MatrixXd& coordinates,
                                       const Eigen::MatrixXd& values, const LagBins& bins,
                                       const EmpiricalVariogramOptions& options = {});

/// Number of fixed row chunks the pairs are split into (a constant, so that results do not depend
/// on the thread count).
inline constexpr std::size_t kVariogramChunks = 64;

}  // namespace errfield

#include "errfield/detail/empirical_variogram_impl.hpp"
