#pragma once
// Template body of errfield::empirical_variogram (see empirical_variogram.hpp). Validation happens
// here, before the parallel region; the pair loop itself is kernels/pair_binning.hpp.

#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "pair_binning.hpp"
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

template <kernels::PairStatistic S, bool Sub, int K, class L, class M>
void run_variogram_chunk_k(const VariogramJob<L, M>& job, std::size_t r0, std::size_t r1,
                           kernels::PairSums out) {
  if (job.soa == nullptr) {
    kernels::bin_pair_rows<S, Sub, K>(job.locations, job.values, job.components, *job.metric,
                                      job.layout, job.seed, job.keep_below, r0, r1, out, job.cone);
    return;
  }
  auto euclid = [&]<int D>() {
    kernels::bin_pair_rows_euclidean_isa<S, Sub, K, D>(job.isa, job.soa, job.n, job.dimension,
                                                       job.values, job.components, job.layout,
                                                       job.seed, job.keep_below, r0, r1, out,
                                                       job.cone);
  };
  switch (job.dimension) {
    case 1: euclid.template operator()<1>(); break;
    case 2: euclid.template operator()<2>(); break;
    case 3: euclid.template operator()<3>(); break;
    case 6: euclid.template operator()<6>(); break;
    default: euclid.template operator()<0>();
  }
}

template <kernels::PairStatistic S, bool Sub, class L, class M>
void run_variogram_chunk_s(const VariogramJob<L, M>& job, std::size_t r0, std::size_t r1,
                           kernels::PairSums out) {
  if (job.components == 1) run_variogram_chunk_k<S, Sub, 1>(job, r0, r1, out);
  else if (job.components == 3) run_variogram_chunk_k<S, Sub, 3>(job, r0, r1, out);
  else run_variogram_chunk_k<S, Sub, 0>(job, r0, r1, out);
}

template <class L, class M>
void run_variogram_chunk(const VariogramJob<L, M>& job, kernels::PairStatistic stat,
                         bool subsample, std::size_t r0, std::size_t r1, kernels::PairSums out) {
  using kernels::PairStatistic;
  if (stat == PairStatistic::SquaredDifference) {
    if (subsample) run_variogram_chunk_s<PairStatistic::SquaredDifference, true>(job, r0, r1, out);
    else run_variogram_chunk_s<PairStatistic::SquaredDifference, false>(job, r0, r1, out);
  } else {
    if (subsample) run_variogram_chunk_s<PairStatistic::RootAbsDifference, true>(job, r0, r1, out);
    else run_variogram_chunk_s<PairStatistic::RootAbsDifference, false>(job, r0, r1, out);
  }
}

/// The plain Euclidean metrics take the axis-major fast path (same lags, bit for bit).
template <class M>
inline constexpr bool kPlainEuclidean =
    std::is_same_v<M, EuclideanMetric> || std::is_same_v<M, JointSpaceMetric>;
inline constexpr int kMaxFastDimension = 64;

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

  detail::check_variogram_accumulators(bins.size(), K, options);
  const std::vector<std::size_t> rows = detail::variogram_chunk_rows(n);
  const std::size_t C = rows.size() - 1;
  const std::size_t B = bins.size() + 1;  // + a discard slot for lags outside every bin
  std::vector<std::uint64_t> count(C * B, 0);
  std::vector<double> lag(C * B, 0.0);
  std::vector<double> stat(C * B * Ks, 0.0);
  const kernels::BinLayout layout = detail::variogram_bin_layout(bins, options);
  // Dowd's first pass counts pairs (and sums lags); its medians come from the second pass.
  const kernels::PairStatistic statistic = options.estimator == VariogramEstimator::CressieHawkins
                                               ? kernels::PairStatistic::RootAbsDifference
                                               : kernels::PairStatistic::SquaredDifference;
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
  const kernels::DirectionCone* cone_ptr = options.direction.is_all() ? nullptr : &cone;
  const detail::VariogramJob<L, M> job{locations.data(), &metric, soa.empty() ? nullptr : soa.data(),
                                       n, dim, z.data(), K, layout, options.seed, keep_below,
                                       kernels::best_kernel_isa(), cone_ptr};
  const std::ptrdiff_t chunks = static_cast<std::ptrdiff_t>(C);
  auto run = [&](std::ptrdiff_t c) {
    const std::size_t cu = static_cast<std::size_t>(c);
    kernels::PairSums out{count.data() + cu * B, lag.data() + cu * B, stat.data() + cu * B * Ks};
    detail::run_variogram_chunk(job, statistic, subsample, rows[cu], rows[cu + 1], out);
  };
  // Each chunk owns its sums, so which thread runs it does not matter.
  if (options.threads > 0) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(options.threads)
    for (std::ptrdiff_t c = 0; c < chunks; ++c) run(c);
  } else {
#pragma omp parallel for schedule(dynamic, 1)
    for (std::ptrdiff_t c = 0; c < chunks; ++c) run(c);
  }
  EmpiricalVariogram result = detail::finalize_variogram(bins, options, K, C, count, lag, stat);
  result.direction = options.direction;
  if (options.estimator == VariogramEstimator::Dowd) {
    // Second pass: every binned difference goes to its bin's region; chunk c writes after the
    // chunks before it, so the stored multiset (and its median) does not depend on threads.
    std::vector<std::uint64_t> cursor = detail::dowd_offsets(count, C, bins.size(), K, options);
    std::vector<double> stored(cursor.back() * Ks);  // last entry: number of stored pairs
    const std::vector<std::uint64_t> offsets = cursor;
    auto store = [&](std::ptrdiff_t c) {
      const std::size_t cu = static_cast<std::size_t>(c);
      if (subsample)
        kernels::store_pair_differences<true>(locations.data(), z.data(), K, metric, layout,
                                              options.seed, keep_below, rows[cu], rows[cu + 1],
                                              cursor.data() + cu * B, stored.data(), cone_ptr);
      else
        kernels::store_pair_differences<false>(locations.data(), z.data(), K, metric, layout,
                                               options.seed, keep_below, rows[cu], rows[cu + 1],
                                               cursor.data() + cu * B, stored.data(), cone_ptr);
    };
    if (options.threads > 0) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(options.threads)
      for (std::ptrdiff_t c = 0; c < chunks; ++c) store(c);
    } else {
#pragma omp parallel for schedule(dynamic, 1)
      for (std::ptrdiff_t c = 0; c < chunks; ++c) store(c);
    }
    detail::finalize_dowd(result, stored, offsets, C);
  }
  return result;
}

// Compiled once in the library (src/empirical_variogram.cpp).
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
