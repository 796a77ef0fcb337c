#pragma once
// Template body of errfield::empirical_variogram (see empirical_variogram.hpp). Validation happens
// here, before the parallel region; the pair loop itself is kernels/pair_binning.hpp.

#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "pair_binning.hpp"
#include "pair_cells.hpp"
#include "pair_columns.hpp"
#include "pair_direction.hpp"
#include "pair_binning_simd.hpp"

namespace errfield {
namespace detail {

/// Row boundaries r_0 = 1 <= r_1 <= ... <= r_C = n of the fixed chunks, balanced by pair count
/// (row i holds i pairs). Depends on n only.
std::vector<std::size_t> variogram_chunk_rows(std::size_t n);
/// Throws unless values is n x K with K >= 1 and every entry finite (InputError naming row and
/// column, 0-based).
void check_variogram_values(const Eigen::MatrixXd& values, std::size_t n_locations);
/// Throws ResourceError when the per-chunk sums for `bins` bins and `components` exceed
/// options.max_accumulator_bytes.
void check_variogram_accumulators(std::size_t bins, int components, const EmpiricalVariogramOptions& options);
kernels::BinLayout variogram_bin_layout(const LagBins& bins, const EmpiricalVariogramOptions& o);
/// ceil(fraction * 2^64) for fraction < 1.
std::uint64_t variogram_keep_below(double fraction);
/// Dowd: checks the storage budget (throws ResourceError) and returns, per chunk and bin, the
/// first slot (in pairs) of the chunk's differences in bin-major storage: C x (bins + 1) entries
/// (the discard slot's unused) and, last, the total number of stored pairs.
std::vector<std::uint64_t> dowd_offsets(const std::vector<std::uint64_t>& count, std::size_t chunks,
                                        std::size_t bins, int components,
                                        const EmpiricalVariogramOptions& o);
/// Dowd: replaces gamma by 1.099 median^2 per bin and component, from the stored differences.
void finalize_dowd(EmpiricalVariogram& v, std::vector<double>& stored,
                   const std::vector<std::uint64_t>& offsets, std::size_t chunks);
/// Merges the per-chunk sums in chunk order and turns them into gamma per bin and component.
EmpiricalVariogram finalize_variogram(const LagBins& bins, const EmpiricalVariogramOptions& o,
                                      int components, std::size_t chunks,
                                      const std::vector<std::uint64_t>& count,
                                      const std::vector<double>& lag,
                                      const std::vector<double>& stat);
/// The kernel's cone for `direction` over axis-major coordinates (dimension x n); `unit` keeps
/// the vector a Vector cone points into alive.
kernels::DirectionCone variogram_direction_cone(const VariogramDirection& direction,
                                                const double* coordinates, std::size_t n,
                                                int dimension);
[[noreturn]] void throw_bad_coordinate(std::size_t row, int coordinate, double value);
[[noreturn]] void throw_dimension_mismatch(std::size_t row, int dimension, int expected);

/// A cell list with the arrays kernels::CellList points into (built by build_variogram_cells).
struct VariogramCells {
  std::vector<double> coordinates;  ///< cell-ordered, axis-major, all axes
  std::vector<std::uint32_t> point, position, cell_of, cell_start;
  kernels::CellList list;
  bool built() const noexcept { return list.axes > 0; }
};

/// The automatic choice (PairSearch::Automatic) takes the cell list when its estimated share of
/// the pairs, prod_a min(1, (3 c_a - 2) / c_a^2) over the gridded axes with c_a cells, is at most
/// kCellListMaxFraction and there are at least kCellListMinPoints locations (measured crossover:
/// docs/variogram.md).
inline constexpr double kCellListMaxFraction = 0.5;
inline constexpr std::size_t kCellListMinPoints = 1000;

/// Builds a cell list over axis-major coordinates (dimension x n) for pairs whose difference on
/// axis a is at most axis_bound[a] (infinite: that axis cannot be gridded) and returns true, or
/// returns false when no axis can be gridded, n does not fit the 32-bit indices, or (unless
/// `force`) the cell list would not pay: it estimates the fraction of the pairs it would visit and
/// uses the cell list below kCellListMaxFraction, for n >= kCellListMinPoints.
bool build_variogram_cells(const double* axis_major, std::size_t n, int dimension,
                           const std::vector<double>& axis_bound, bool force, VariogramCells& cells);

/// Points sorted into columns (kernels/pair_columns.hpp) with the arrays kernels::SortedColumns
/// points into (built by build_variogram_columns).
struct VariogramColumns {
  std::vector<double> coordinates;  ///< sorted, axis-major, all axes
  std::vector<double> values;       ///< sorted, one component
  std::vector<std::uint32_t> column_start;
  kernels::SortedColumns list;
  bool built() const noexcept { return list.n > 0; }
};

/// Builds the sorted columns of n points (axis-major coordinates, dimension 1..3, one value per
/// point) for a Euclidean cutoff and returns true, or returns false when n does not fit or (unless
/// `force`) the columns would not pay: n < kCellListMinPoints, or their estimated share of the
/// pairs visited is above `max_share` (column_max_share).
bool build_variogram_columns(const double* axis_major, const double* values, std::size_t n,
                             int dimension, double cutoff, bool force, double max_share,
                             VariogramColumns& columns);

/// The largest estimated share of visited pairs for which Automatic takes the sorted columns.
/// With AVX-512 they are never slower than all pairs (measured, N = 20,000 in a 500 cube: as fast
/// at a cutoff of the whole side, 3x faster at half of it; docs/benchmarks.md): 1, always. Their
/// portable kernel takes one pair at a time against the all-pairs loop's vectors: the cell
/// list's rule, kCellListMaxFraction.
inline double column_max_share(kernels::KernelIsa isa) noexcept {
  return isa == kernels::KernelIsa::Avx512 ? 1.0 : kCellListMaxFraction;
}

/// One thread's workspace for the cell list (kernels::CellListScratch over n points).
struct VariogramCellScratch {
  std::vector<double> lag_of;
  std::vector<std::uint64_t> bits, summary;
  explicit VariogramCellScratch(std::size_t n)
      : lag_of(n), bits((n + 63) / 64, 0), summary((n + 4095) / 4096, 0) {}
  kernels::CellListScratch view() noexcept { return {lag_of.data(), bits.data(), summary.data()}; }
};

/// Threads a parallel region with `threads` (0: OpenMP's default) can have at most, and the calling
/// thread's index in its team (0 outside a parallel region).
int variogram_team_size(int threads);
int variogram_thread_index();

/// The largest difference on each axis that a pair with lag <= cutoff can have under `metric`, for
/// the metrics whose form is known (Euclidean and joint-space: the cutoff itself; weighted
/// Euclidean: cutoff / sqrt(w_a), infinite for w_a = 0). False for any other metric.
template <class M>
bool variogram_axis_bounds(const M& metric, int dimension, double cutoff, std::vector<double>& bound) {
  bound.assign(static_cast<std::size_t>(dimension), cutoff);
  if constexpr (std::is_same_v<M, EuclideanMetric> || std::is_same_v<M, JointSpaceMetric>) {
    return true;
  } else if constexpr (std::is_same_v<M, WeightedEuclideanMetric>) {
    const std::vector<double>& w = metric.weights();
    if (w.size() > static_cast<std::size_t>(dimension)) return false;
    for (std::size_t a = 0; a < bound.size(); ++a)
      bound[a] = a < w.size() && w[a] > 0.0 ? cutoff / std::sqrt(w[a])
                                            : std::numeric_limits<double>::infinity();
    return true;
  } else {
    (void)metric;
    return false;
  }
}

/// Everything one chunk needs; `soa` (axis-major coordinates) is set when the Euclidean fast
/// path applies, `dimension` is then the number of axes.
template <class L, class M>
struct VariogramJob {
  const L* locations;
  const M* metric;
  const double* soa;
  std::size_t n;
  int dimension;
  const double* values;
  int components;
  kernels::BinLayout layout;
  std::uint64_t seed;
  std::uint64_t keep_below;
  kernels::KernelIsa isa;  ///< instruction set of the Euclidean fast path (same result either way)
  const kernels::DirectionCone* cone;  ///< null: every direction
};

/// A chunk's view of the cell list: the grid, the direction cone over its cell-ordered
/// coordinates (null: every direction) and the running thread's workspace.
struct VariogramCellRun {
  const kernels::CellList* list;
  const kernels::DirectionCone* cone;
  kernels::CellListScratch scratch;
};

/// The plain Euclidean metrics take the axis-major fast path (same lags, bit for bit).
template <class M>
inline constexpr bool kPlainEuclidean =
    std::is_same_v<M, EuclideanMetric> || std::is_same_v<M, JointSpaceMetric>;
inline constexpr int kMaxFastDimension = 64;

/// Calls f.template operator()<D>() with the Euclidean fast path's compile-time dimension D (0:
/// any). A location type of fixed size has one possible D, so only that one is instantiated; a
/// dynamic one (Eigen::VectorXd) takes D = 0, the loop over a run-time number of axes, whatever
/// `dimension` is. Every D is a copy of the pair loops per statistic, component count and
/// instruction set: dispatching VectorXd on 1, 2, 3 and 6 as well made its three instantiations
/// 70 of the library's 160 CPU s in this file (Release, gcc 12). Callers with 1, 2, 3 or 6 axes
/// and a speed concern use the fixed-size types (empirical_variogram of an Eigen::MatrixXd does).
template <class L, class F>
void with_euclidean_dimension(int dimension, F&& f) {
  constexpr int kD = LocationTraits<L>::kDimension;
  (void)dimension;
  if constexpr (kD == 1 || kD == 2 || kD == 3 || kD == 6) f.template operator()<kD>();
  else f.template operator()<0>();
}

/// visit(i, j, h, m) with batches of the pairs of rows [r0, r1) within the cutoff, in the
/// all-pairs order, with the lags the all-pairs loop computes (the Euclidean fast path's or the
/// metric's).
template <class L, class M, class Visit>
void for_each_cell_pair(const VariogramJob<L, M>& job, const VariogramCellRun& cells,
                        std::size_t r0, std::size_t r1, Visit&& visit) {
  const kernels::CellList& g = *cells.list;
  const double cutoff = job.layout.edges[job.layout.bins];
  if (job.soa == nullptr) {
    auto lags = [&](std::size_t i, std::size_t, std::size_t p0, std::size_t m, double* h) {
      const L& li = job.locations[i];
      for (std::size_t t = 0; t < m; ++t) h[t] = (*job.metric)(li, job.locations[g.point[p0 + t]]);
    };
    kernels::for_each_pair_in_cells<false>(g, r0, r1, cutoff, cells.cone, lags, cells.scratch, visit);
    return;
  }
  if constexpr (kPlainEuclidean<M>) {  // soa is only set for these
    with_euclidean_dimension<L>(job.dimension, [&]<int D>() {
      auto lags = [&](std::size_t, std::size_t pi, std::size_t p0, std::size_t m, double* h2) {
        kernels::cell_squared_euclidean_lags<D>(g, pi, p0, m, h2);
      };
      kernels::for_each_pair_in_cells<true>(g, r0, r1, cutoff, cells.cone, lags, cells.scratch, visit);
    });
  }
}

/// The cell list's counterpart of bin_pair_rows: the same pairs in the same order, so the same sums.
template <kernels::PairStatistic S, bool Sub, int K_FIXED, class L, class M>
void bin_cell_pairs(const VariogramJob<L, M>& job, const VariogramCellRun& cells, std::size_t r0,
                    std::size_t r1, kernels::PairSums out) {
  for_each_cell_pair(job, cells, r0, r1,
                     [&](std::size_t i, const std::uint32_t* j, const double* h, std::size_t m) {
    kernels::accumulate_pair_batch<S, Sub, K_FIXED>(i, j, h, m, job.values, job.components,
                                                    job.layout, job.seed, job.keep_below, out);
  });
}

/// The cell list's counterpart of store_pair_differences (Dowd's second pass).
template <bool Sub, class L, class M>
void store_cell_differences(const VariogramJob<L, M>& job, const VariogramCellRun& cells,
                            std::size_t r0, std::size_t r1, std::uint64_t* cursor, double* out) {
  const std::size_t K = static_cast<std::size_t>(job.components);
  for_each_cell_pair(job, cells, r0, r1,
                     [&](std::size_t i, const std::uint32_t* j, const double* h, std::size_t m) {
    const double* zi = job.values + i * K;
    for (std::size_t t = 0; t < m; ++t) {
      if constexpr (Sub) {
        if (kernels::pair_hash(job.seed, i, j[t]) >= job.keep_below) continue;
      }
      const std::ptrdiff_t k = kernels::find_bin(h[t], job.layout);
      if (k < 0) continue;
      const double* zj = job.values + static_cast<std::size_t>(j[t]) * K;
      double* o = out + cursor[k]++ * K;
      for (std::size_t c = 0; c < K; ++c) o[c] = std::fabs(zi[c] - zj[c]);
    }
  });
}

template <kernels::PairStatistic S, bool Sub, int K, class L, class M>
void run_variogram_chunk_k(const VariogramJob<L, M>& job, const VariogramCellRun* cells,
                           std::size_t r0, std::size_t r1, kernels::PairSums out) {
  if (cells != nullptr) {
    bin_cell_pairs<S, Sub, K>(job, *cells, r0, r1, out);
    return;
  }
  if (job.soa == nullptr) {
    kernels::bin_pair_rows<S, Sub, K>(job.locations, job.values, job.components, *job.metric,
                                      job.layout, job.seed, job.keep_below, r0, r1, out, job.cone);
    return;
  }
  if constexpr (kPlainEuclidean<M>) {  // soa is only set for these
    with_euclidean_dimension<L>(job.dimension, [&]<int D>() {
      kernels::bin_pair_rows_euclidean_isa<S, Sub, K, D>(job.isa, job.soa, job.n, job.dimension,
                                                         job.values, job.components, job.layout,
                                                         job.seed, job.keep_below, r0, r1, out,
                                                         job.cone);
    });
  }
}

template <kernels::PairStatistic S, bool Sub, class L, class M>
void run_variogram_chunk_s(const VariogramJob<L, M>& job, const VariogramCellRun* cells,
                           std::size_t r0, std::size_t r1, kernels::PairSums out) {
  // Cross products need two components or more; one run-time-K instantiation serves them all.
  if constexpr (S == kernels::PairStatistic::CrossProducts) run_variogram_chunk_k<S, Sub, 0>(job, cells, r0, r1, out);
  else if (job.components == 1) run_variogram_chunk_k<S, Sub, 1>(job, cells, r0, r1, out);
  else if (job.components == 3) run_variogram_chunk_k<S, Sub, 3>(job, cells, r0, r1, out);
  else run_variogram_chunk_k<S, Sub, 0>(job, cells, r0, r1, out);
}

/// Sums of rows [r0, r1) into `out`: over all pairs, or over the cell list's when `cells` is set.
template <class L, class M>
void run_variogram_chunk(const VariogramJob<L, M>& job, const VariogramCellRun* cells,
                         kernels::PairStatistic stat, bool subsample, std::size_t r0,
                         std::size_t r1, kernels::PairSums out) {
  using kernels::PairStatistic;
  if (stat == PairStatistic::CrossProducts) {
    if (subsample) run_variogram_chunk_s<PairStatistic::CrossProducts, true>(job, cells, r0, r1, out);
    else run_variogram_chunk_s<PairStatistic::CrossProducts, false>(job, cells, r0, r1, out);
  } else if (stat == PairStatistic::SquaredDifference) {
    if (subsample) run_variogram_chunk_s<PairStatistic::SquaredDifference, true>(job, cells, r0, r1, out);
    else run_variogram_chunk_s<PairStatistic::SquaredDifference, false>(job, cells, r0, r1, out);
  } else {
    if (subsample) run_variogram_chunk_s<PairStatistic::RootAbsDifference, true>(job, cells, r0, r1, out);
    else run_variogram_chunk_s<PairStatistic::RootAbsDifference, false>(job, cells, r0, r1, out);
  }
}

/// Sums of the column pairs of rows [p0, p1) (positions in the sorted order) into `out`.
/// `slots`: kernels::column_slot_doubles(bins) doubles, 32-byte aligned.
inline void run_column_chunk(kernels::KernelIsa isa, const kernels::SortedColumns& g,
                             const kernels::BinLayout& layout, kernels::PairStatistic stat,
                             std::size_t p0, std::size_t p1, double* slots, kernels::PairSums out) {
  using kernels::PairStatistic;
  auto with = [&]<PairStatistic S>() {
    switch (g.dimension) {
      case 1: kernels::bin_column_pairs<S, 1>(isa, g, layout, p0, p1, slots, out); break;
      case 2: kernels::bin_column_pairs<S, 2>(isa, g, layout, p0, p1, slots, out); break;
      default: kernels::bin_column_pairs<S, 3>(isa, g, layout, p0, p1, slots, out);
    }
  };
  if (stat == PairStatistic::SquaredDifference) with.template operator()<PairStatistic::SquaredDifference>();
  else with.template operator()<PairStatistic::RootAbsDifference>();
}

/// Runs chunk(c, scratch) for c = 0..chunks-1 on `threads` OpenMP threads (0: the default),
/// dynamically scheduled; `scratch` is the running thread's cell-list workspace (one per thread,
/// allocated here before the parallel region when `cell_points` > 0, else empty).
template <class Chunk>
void for_each_variogram_chunk(int threads, std::size_t chunks, std::size_t cell_points, Chunk&& chunk) {
  std::vector<VariogramCellScratch> scratch;
  if (cell_points > 0) {
    const int team = variogram_team_size(threads);
    scratch.reserve(static_cast<std::size_t>(team));
    for (int t = 0; t < team; ++t) scratch.emplace_back(cell_points);
  }
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(chunks);
  auto body = [&] {
    kernels::CellListScratch mine;
    if (!scratch.empty()) mine = scratch[static_cast<std::size_t>(variogram_thread_index())].view();
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t c = 0; c < count; ++c) chunk(static_cast<std::size_t>(c), mine);
  };
  // Each chunk owns its sums, so which thread runs it does not matter.
  if (threads > 0) {
#pragma omp parallel num_threads(threads)
    body();
  } else {
#pragma omp parallel
    body();
  }
}


}  // namespace detail

template <Location L, Metric<L> M>
EmpiricalVariogram empirical_variogram(std::span<const L> locations, const Eigen::MatrixXd& values,
                                       const M& metric, const LagBins& bins,
                                       const EmpiricalVariogramOptions& options) {
  options.validate();
  const std::size_t n = locations.size();
  detail::check_variogram_values(values, n);
  const int dim = n ? LocationTraits<L>::size(locations[0]) : 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int d = LocationTraits<L>::size(locations[i]);
    if (d != dim) detail::throw_dimension_mismatch(i, d, dim);
    for (int c = 0; c < d; ++c) {
      const double x = LocationTraits<L>::coordinate(locations[i], c);
      if (!std::isfinite(x)) detail::throw_bad_coordinate(i, c, x);
    }
  }
  options.direction.check_dimension(dim);
  const int K = static_cast<int>(values.cols());
  const std::size_t Ks = static_cast<std::size_t>(K);
  std::vector<double> z(n * Ks);  // row-major copy: one row per location
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < K; ++c) z[i * Ks + static_cast<std::size_t>(c)] = values(static_cast<Eigen::Index>(i), c);

  // Dowd's first pass counts pairs (and sums lags); its medians come from the second pass.
  const kernels::PairStatistic statistic = options.cross_variograms ? kernels::PairStatistic::CrossProducts
                                           : options.estimator == VariogramEstimator::CressieHawkins
                                               ? kernels::PairStatistic::RootAbsDifference
                                               : kernels::PairStatistic::SquaredDifference;
  const std::size_t W = kernels::pair_statistic_width(statistic, Ks);  // sums per bin
  detail::check_variogram_accumulators(bins.size(), static_cast<int>(W), options);
  const std::vector<std::size_t> rows = detail::variogram_chunk_rows(n);
  const std::size_t C = rows.size() - 1;
  const std::size_t B = bins.size() + 1;  // + a discard slot for lags outside every bin
  std::vector<std::uint64_t> count(C * B, 0);
  std::vector<double> lag(C * B, 0.0);
  std::vector<double> stat(C * B * W, 0.0);
  const kernels::BinLayout layout = detail::variogram_bin_layout(bins, options);
  const bool subsample = options.pair_fraction < 1.0;
  const std::uint64_t keep_below = subsample ? detail::variogram_keep_below(options.pair_fraction) : 0;
  std::vector<double> soa;
  if constexpr (detail::kPlainEuclidean<M>) {
    if (dim <= detail::kMaxFastDimension) {
      soa.resize(n * static_cast<std::size_t>(dim));
      for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < dim; ++a)
          soa[static_cast<std::size_t>(a) * n + i] = LocationTraits<L>::coordinate(locations[i], a);
    }
  }
  // A direction filter reads coordinate differences, whatever the metric: axis-major copy.
  std::vector<double> cone_coordinates;
  kernels::DirectionCone cone;
  if (!options.direction.is_all()) {
    if (soa.empty()) {
      cone_coordinates.resize(n * static_cast<std::size_t>(dim));
      for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < dim; ++a)
          cone_coordinates[static_cast<std::size_t>(a) * n + i] = LocationTraits<L>::coordinate(locations[i], a);
    }
    cone = detail::variogram_direction_cone(options.direction,
                                            soa.empty() ? cone_coordinates.data() : soa.data(), n, dim);
  }
  // A cone of 90 degrees or more keeps every pair: the omnidirectional loops, same pairs.
  const kernels::DirectionCone* cone_ptr =
      options.direction.is_all() || !kernels::cone_selects(cone) ? nullptr : &cone;
  const detail::VariogramJob<L, M> job{locations.data(), &metric, soa.empty() ? nullptr : soa.data(),
                                       n, dim, z.data(), K, layout, options.seed, keep_below,
                                       kernels::best_kernel_isa(), cone_ptr};
  // Sorted columns for the common case (Euclidean, 1-3 axes, one component, Matheron or
  // Cressie-Hawkins, every pair, every direction or a cone that does not depend on the pair's
  // orientation, equally spaced bins): each pair within the last edge once, in an order of its
  // own (same pairs and bins, sums to rounding: docs/geostatistics.md).
  detail::VariogramColumns columns;
  kernels::DirectionCone column_cone;
  if (options.pair_search != PairSearch::AllPairs && !soa.empty() && dim >= 1 && dim <= 3 && K == 1 &&
      !subsample && (cone_ptr == nullptr || kernels::cone_is_symmetric(cone)) &&
      options.estimator != VariogramEstimator::Dowd && layout.uniform &&
      bins.size() <= kernels::kSimdMaxBins &&
      detail::build_variogram_columns(soa.data(), z.data(), n, dim, bins.edges().back(),
                                      options.pair_search == PairSearch::CellList,
                                      detail::column_max_share(job.isa), columns) &&
      cone_ptr != nullptr) {
    column_cone = cone;  // the same test on the sorted copy of the coordinates
    column_cone.coordinates = columns.coordinates.data();
    columns.list.cone = &column_cone;
  }
  if (columns.built()) {
    // One workspace of slot copies per thread, 32-byte aligned, allocated before the region.
    const std::size_t slot_doubles = kernels::column_slot_doubles(bins.size()) + 4;
    const std::size_t team = static_cast<std::size_t>(detail::variogram_team_size(options.threads));
    std::vector<double> slots(team * slot_doubles);
    detail::for_each_variogram_chunk(options.threads, C, 0, [&](std::size_t c, kernels::CellListScratch) {
      double* mine = slots.data() + static_cast<std::size_t>(detail::variogram_thread_index()) * slot_doubles;
      mine += (4 - (reinterpret_cast<std::uintptr_t>(mine) / sizeof(double)) % 4) % 4;
      kernels::PairSums out{count.data() + c * B, lag.data() + c * B, stat.data() + c * B * Ks};
      detail::run_column_chunk(job.isa, columns.list, layout, statistic, n * c / C, n * (c + 1) / C,
                               mine, out);
    });
    EmpiricalVariogram result = detail::finalize_variogram(bins, options, K, C, count, lag, stat);
    result.direction = options.direction;
    return result;
  }
  // Cell list: only the pairs that can lie within the last edge, in the all-pairs order.
  detail::VariogramCells cells;
  kernels::DirectionCone cell_cone;
  std::vector<double> bound;
  if (options.pair_search != PairSearch::AllPairs &&
      detail::variogram_axis_bounds(metric, dim, bins.edges().back(), bound)) {
    const double* axis_major = !soa.empty() ? soa.data() : cone_coordinates.data();
    std::vector<double> copy;
    if (soa.empty() && cone_coordinates.empty()) {
      copy.resize(n * static_cast<std::size_t>(dim));
      for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < dim; ++a)
          copy[static_cast<std::size_t>(a) * n + i] = LocationTraits<L>::coordinate(locations[i], a);
      axis_major = copy.data();
    }
    if (detail::build_variogram_cells(axis_major, n, dim, bound,
                                      options.pair_search == PairSearch::CellList, cells) &&
        cone_ptr != nullptr) {
      cell_cone = cone;  // the same test on the cell-ordered copy of the coordinates
      cell_cone.coordinates = cells.coordinates.data();
    }
  }
  const std::size_t cell_points = cells.built() ? n : 0;
  auto cell_run = [&](kernels::CellListScratch scratch) {
    return detail::VariogramCellRun{&cells.list, cone_ptr != nullptr ? &cell_cone : nullptr, scratch};
  };
  detail::for_each_variogram_chunk(options.threads, C, cell_points,
                                   [&](std::size_t c, kernels::CellListScratch scratch) {
    kernels::PairSums out{count.data() + c * B, lag.data() + c * B, stat.data() + c * B * W};
    const detail::VariogramCellRun run = cell_run(scratch);
    detail::run_variogram_chunk(job, cells.built() ? &run : nullptr, statistic, subsample, rows[c],
                                rows[c + 1], out);
  });
  EmpiricalVariogram result = detail::finalize_variogram(bins, options, K, C, count, lag, stat);
  result.direction = options.direction;
  if (options.estimator == VariogramEstimator::Dowd) {
    // Second pass: every binned difference goes to its bin's region; chunk c writes after the
    // chunks before it, so the stored multiset (and its median) does not depend on threads.
    std::vector<std::uint64_t> cursor = detail::dowd_offsets(count, C, bins.size(), K, options);
    std::vector<double> stored(cursor.back() * Ks);  // last entry: number of stored pairs
    const std::vector<std::uint64_t> offsets = cursor;
    detail::for_each_variogram_chunk(options.threads, C, cell_points,
                                     [&](std::size_t cu, kernels::CellListScratch scratch) {
      if (cells.built()) {
        const detail::VariogramCellRun run = cell_run(scratch);
        if (subsample)
          detail::store_cell_differences<true>(job, run, rows[cu], rows[cu + 1],
                                               cursor.data() + cu * B, stored.data());
        else
          detail::store_cell_differences<false>(job, run, rows[cu], rows[cu + 1],
                                                cursor.data() + cu * B, stored.data());
      } else if (subsample)
        kernels::store_pair_differences<true>(locations.data(), z.data(), K, metric, layout,
                                              options.seed, keep_below, rows[cu], rows[cu + 1],
                                              cursor.data() + cu * B, stored.data(), cone_ptr);
      else
        kernels::store_pair_differences<false>(locations.data(), z.data(), K, metric, layout,
                                               options.seed, keep_below, rows[cu], rows[cu + 1],
                                               cursor.data() + cu * B, stored.data(), cone_ptr);
    });
    detail::finalize_dowd(result, stored, offsets, C);
  }
  return result;
}

// Compiled once in the library (src/variogram/empirical_variogram.cpp).
namespace detail {
using Location6d = Eigen::Matrix<double, 6, 1>;
}  // namespace detail
#define ERRFIELD_VARIOGRAM_EXTERN(L, M)                                                          \
  extern template EmpiricalVariogram empirical_variogram<L, M>(                                  \
      std::span<const L>, const Eigen::MatrixXd&, const M&, const LagBins&,                       \
      const EmpiricalVariogramOptions&);
#define ERRFIELD_VARIOGRAM_EXTERN_METRICS(L)          \
  ERRFIELD_VARIOGRAM_EXTERN(L, EuclideanMetric)       \
  ERRFIELD_VARIOGRAM_EXTERN(L, JointSpaceMetric)      \
  ERRFIELD_VARIOGRAM_EXTERN(L, WeightedEuclideanMetric)
ERRFIELD_VARIOGRAM_EXTERN_METRICS(double)
ERRFIELD_VARIOGRAM_EXTERN_METRICS(Eigen::Vector2d)
ERRFIELD_VARIOGRAM_EXTERN_METRICS(Eigen::Vector3d)
ERRFIELD_VARIOGRAM_EXTERN_METRICS(detail::Location6d)
ERRFIELD_VARIOGRAM_EXTERN_METRICS(Eigen::VectorXd)
#undef ERRFIELD_VARIOGRAM_EXTERN_METRICS
#undef ERRFIELD_VARIOGRAM_EXTERN

}  // namespace errfield
