#pragma once
/// Hot loop of the empirical variogram: visits the pairs (i, j), j < i, of a range of rows once,
/// computes each lag once, finds its bin and adds the pair's statistics to per-bin sums. Use it
/// through errfield::empirical_variogram (empirical_variogram.hpp), which validates input, splits
/// the rows into fixed chunks, runs them in parallel and merges the sums in a fixed order.
///
/// Plain pointers in, sums out: no allocation, no checks, no exceptions inside. Every kernel here
/// has a naive reference (`*_reference`) that the tests compare it with.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pair_direction.hpp"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace errfield::kernels {

/// What is summed per pair and component c, with d = z_i[c] - z_j[c]:
/// SquaredDifference sums d^2 (Matheron), RootAbsDifference sums |d|^(1/2) (Cressie–Hawkins).
/// CrossProducts sums d_c^2 for every c, then d_a d_b for every a < b (cross-variograms).
enum class PairStatistic { SquaredDifference, RootAbsDifference, CrossProducts };

/// Sums per bin that statistic S keeps for K components: K, or K + K(K-1)/2 for CrossProducts.
constexpr std::size_t pair_statistic_width(PairStatistic s, std::size_t K) noexcept {
  return s == PairStatistic::CrossProducts ? K + K * (K - 1) / 2 : K;
}

/// Bin edges e_0 < e_1 < ... < e_n (n = bins) and which bin a lag h belongs to:
/// half-open  [e_k, e_{k+1}) for every k;
/// gstat      [e_0, e_1] for k = 0, then (e_k, e_{k+1}].
/// `uniform` with `inv_width` = 1/(e_1 - e_0) lets the lookup guess the bin by division and
/// correct the guess against the stored edges, so it agrees exactly with the comparison rule.
struct BinLayout {
  const double* edges = nullptr;  ///< n + 1 values
  std::size_t bins = 0;           ///< n >= 1
  bool gstat = false;
  bool uniform = false;
  double inv_width = 0.0;
};

/// Bin index of lag h, or -1 when h lies outside every bin (or is NaN).
inline std::ptrdiff_t find_bin(double h, const BinLayout& b) noexcept {
  const double* e = b.edges;
  const std::size_t n = b.bins;
  if (!b.gstat) {
    if (!(h >= e[0] && h < e[n])) return -1;
  } else {
    if (!(h >= e[0] && h <= e[n])) return -1;
  }
  std::size_t k;
  if (b.uniform) {
    const double guess = (h - e[0]) * b.inv_width;
    k = guess < static_cast<double>(n) ? static_cast<std::size_t>(guess) : n - 1;
  } else {
    // Binary search for the last edge <= h among e_0..e_{n-1}.
    std::size_t lo = 0, hi = n;  // invariant: e[lo] <= h, answer in [lo, hi)
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      if (e[mid] <= h) lo = mid;
      else hi = mid;
    }
    k = lo;
  }
  // Correct the guess to the comparison rule (half-open: e_k <= h < e_{k+1}).
  while (k > 0 && h < e[k]) --k;
  while (k + 1 < n && h >= e[k + 1]) ++k;
  // gstat: a lag equal to an inner edge e_k belongs to the bin below it, (e_{k-1}, e_k].
  if (b.gstat && k > 0 && h == e[k]) --k;
  return static_cast<std::ptrdiff_t>(k);
}

/// splitmix64 of the seed and the pair's index p = i (i - 1) / 2 + j: a fixed pseudo-random
/// number per pair, the same whichever thread or chunk visits it.
inline std::uint64_t pair_hash(std::uint64_t seed, std::uint64_t i, std::uint64_t j) noexcept {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (i * (i - 1) / 2 + j + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Per-bin sums of one chunk of rows. `stat` holds bins x components values, bin-major.
struct PairSums {
  std::uint64_t* count = nullptr;
  double* lag = nullptr;
  double* stat = nullptr;
};

namespace detail {

/// h[t] = sqrt(h[t]) for t < m (h[t] >= 0). Packed SSE2 square roots where available: a plain
/// std::sqrt loop does not vectorize while errno semantics are on (-fmath-errno, GCC's default).
/// Both give the correctly rounded square root, so results do not depend on the path.
inline void sqrt_block(double* h, std::size_t m) noexcept {
  std::size_t t = 0;
#if defined(__SSE2__)
  for (; t + 2 <= m; t += 2) _mm_storeu_pd(h + t, _mm_sqrt_pd(_mm_loadu_pd(h + t)));
#endif
  for (; t < m; ++t) h[t] = std::sqrt(h[t]);
}

template <PairStatistic S>
inline double pair_statistic(double d) noexcept {
  if constexpr (S == PairStatistic::RootAbsDifference) return std::sqrt(std::fabs(d));
  else return d * d;
}

/// Adds one pair's statistics (z_i, z_j: K components) to its bin's pair_statistic_width(S, K)
/// sums `s`: per component first, then for CrossProducts the products (z_i[a] - z_j[a])
/// (z_i[b] - z_j[b]) in the order (0,1), (0,2), ..., (1,2), ...
template <PairStatistic S>
inline void add_pair_statistics(const double* zi, const double* zj, std::size_t K, double* s) noexcept {
  for (std::size_t c = 0; c < K; ++c) s[c] += pair_statistic<S>(zi[c] - zj[c]);
  if constexpr (S == PairStatistic::CrossProducts) {
    std::size_t p = K;
    for (std::size_t a = 0; a < K; ++a)
      for (std::size_t b = a + 1; b < K; ++b) s[p++] += (zi[a] - zj[a]) * (zi[b] - zj[b]);
  }
}
}  // namespace detail

namespace detail {

/// Relative distance to the nearest edge below which bin_codes defers to the exact lookup. The
/// guess (h - e_0) / w is within a few ulp (of a quotient < 10^7) of the exact position.
inline constexpr double kNearEdge = 1e-6;

/// Bin codes of lags h[0..m) for a uniform layout: the bin index, `bins.bins` for a lag outside
/// every bin, or -1 when the lag is so close to an inner edge that only a comparison with the
/// stored edge can tell (find_bin decides those). Vectorized with SSE2 where available.
template <bool Gstat>
inline void bin_codes(const double* h, std::int32_t* code, std::size_t m,
                      const BinLayout& b) noexcept {
  const double e0 = b.edges[0];
  const double en = b.edges[b.bins];
  const double inv_w = b.inv_width;
  const double top = static_cast<double>(b.bins) - 0.5;
  const std::int32_t outside = static_cast<std::int32_t>(b.bins);
  std::size_t t = 0;
#if defined(__SSE2__)
  const __m128d ve0 = _mm_set1_pd(e0), ven = _mm_set1_pd(en), vinv = _mm_set1_pd(inv_w);
  const __m128d vtop = _mm_set1_pd(top), vzero = _mm_setzero_pd();
  const __m128d vlo = _mm_set1_pd(kNearEdge), vhi = _mm_set1_pd(1.0 - kNearEdge);
  const __m128i vout = _mm_set1_epi32(outside), vminus = _mm_set1_epi32(-1);
  for (; t + 2 <= m; t += 2) {
    const __m128d x = _mm_loadu_pd(h + t);
    const __m128d in = _mm_and_pd(_mm_cmpge_pd(x, ve0), Gstat ? _mm_cmple_pd(x, ven) : _mm_cmplt_pd(x, ven));
    __m128d g = _mm_mul_pd(_mm_sub_pd(x, ve0), vinv);
    g = _mm_min_pd(_mm_max_pd(g, vzero), vtop);
    const __m128i k = _mm_cvttpd_epi32(g);
    const __m128d frac = _mm_sub_pd(g, _mm_cvtepi32_pd(k));
    const __m128d near = _mm_or_pd(_mm_cmplt_pd(frac, vlo), _mm_cmpgt_pd(frac, vhi));
    // 64-bit lane masks -> two 32-bit lanes in the low half.
    const __m128i in32 = _mm_shuffle_epi32(_mm_castpd_si128(in), 0x08);
    const __m128i near32 = _mm_shuffle_epi32(_mm_castpd_si128(near), 0x08);
    const __m128i kk = _mm_or_si128(_mm_and_si128(near32, vminus), _mm_andnot_si128(near32, k));
    const __m128i c = _mm_or_si128(_mm_and_si128(in32, kk), _mm_andnot_si128(in32, vout));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(code + t), c);
  }
#endif
  for (; t < m; ++t) {
    const double x = h[t];
    const bool in = Gstat ? (x >= e0 && x <= en) : (x >= e0 && x < en);
    double g = (x - e0) * inv_w;
    g = g > 0.0 ? g : 0.0;
    g = g < top ? g : top;
    const std::int32_t k = static_cast<std::int32_t>(g);
    const double frac = g - static_cast<double>(k);
    const bool near = frac < kNearEdge || frac > 1.0 - kNearEdge;
    code[t] = in ? (near ? -1 : k) : outside;
  }
}

/// Adds the pairs (i, j) for j in [j0, j0 + m), with lags h[0..m), to `out`, whose arrays have
/// bins + 1 slots (the last collects lags outside every bin and is discarded). For K_FIXED == 1,
/// w[t] already holds the pair statistic; otherwise it is computed here from `values`.
template <PairStatistic S, bool Subsample, int K_FIXED>
inline void accumulate_lags(std::size_t i, std::size_t j0, std::size_t m, const double* h,
                            const double* w, std::int32_t* code, const double* values,
                            int components, const BinLayout& bins, std::uint64_t seed,
                            std::uint64_t keep_below, PairSums out) noexcept {
  const std::size_t K = static_cast<std::size_t>(K_FIXED > 0 ? K_FIXED : components);
  const double* zi = values + i * K;
  if (bins.uniform) {
    if (bins.gstat) bin_codes<true>(h, code, m, bins);
    else bin_codes<false>(h, code, m, bins);
  } else {
    for (std::size_t t = 0; t < m; ++t) code[t] = -1;
  }
  for (std::size_t t = 0; t < m; ++t) {
    const std::size_t j = j0 + t;
    if constexpr (Subsample) {
      if (pair_hash(seed, i, j) >= keep_below) continue;
    }
    std::size_t kb;
    if (code[t] >= 0) {
      kb = static_cast<std::size_t>(code[t]);
    } else {
      const std::ptrdiff_t k = find_bin(h[t], bins);
      kb = k < 0 ? bins.bins : static_cast<std::size_t>(k);
    }
    out.count[kb] += 1;
    out.lag[kb] += h[t];
    if constexpr (K_FIXED == 1) {
      out.stat[kb] += w[t];
    } else {
      add_pair_statistics<S>(zi, values + j * K, K, out.stat + kb * pair_statistic_width(S, K));
    }
  }
}

/// w[t] = statistic of z_i - z[j0 + t] for a scalar value (vectorized).
template <PairStatistic S>
inline void scalar_statistics(double zi, const double* z, std::size_t m, double* w) noexcept {
  for (std::size_t t = 0; t < m; ++t) {
    const double d = zi - z[t];
    w[t] = S == PairStatistic::SquaredDifference ? d * d : std::fabs(d);
  }
  if constexpr (S == PairStatistic::RootAbsDifference) sqrt_block(w, m);
}

inline constexpr std::size_t kLagBlock = 256;

}  // namespace detail

/// Adds every pair (i, j) with row_begin <= i < row_end and j < i whose lag falls in a bin to
/// `out` (which the caller zeroed; bins + 1 slots per array, the last one a discard slot).
/// `values` is row-major N x K. With `Subsample`, a pair is kept only when
/// pair_hash(seed, i, j) < keep_below. K_FIXED > 0 fixes K at compile time.
/// Any Location/Metric: the lag is metric(x_i, x_j). Cost: one metric call per pair; no allocation.
/// A non-null `cone` drops the pairs whose separation is outside it (pair_direction.hpp).
template <PairStatistic S, bool Subsample, int K_FIXED, class L, class M>
void bin_pair_rows(const L* locations, const double* values, int components, const M& metric,
                   const BinLayout& bins, std::uint64_t seed, std::uint64_t keep_below,
                   std::size_t row_begin, std::size_t row_end, PairSums out,
                   const DirectionCone* cone = nullptr) noexcept {
  alignas(64) double h[detail::kLagBlock];
  alignas(64) double w[detail::kLagBlock];
  alignas(64) std::int32_t code[detail::kLagBlock];
  for (std::size_t i = row_begin; i < row_end; ++i) {
    const L& li = locations[i];
    for (std::size_t j0 = 0; j0 < i; j0 += detail::kLagBlock) {
      const std::size_t m = i - j0 < detail::kLagBlock ? i - j0 : detail::kLagBlock;
      for (std::size_t t = 0; t < m; ++t) h[t] = metric(li, locations[j0 + t]);
      if (cone != nullptr) mask_directions(*cone, i, j0, m, h);
      if constexpr (K_FIXED == 1) detail::scalar_statistics<S>(values[i], values + j0, m, w);
      detail::accumulate_lags<S, Subsample, K_FIXED>(i, j0, m, h, w, code, values, components,
                                                     bins, seed, keep_below, out);
    }
  }
}

/// Same as bin_pair_rows for the Euclidean distance, with coordinates stored by axis
/// (`coordinates[a * n + i]` is axis a of point i, D axes, D_FIXED > 0 fixes D at compile time,
/// D <= 64): h = sqrt(sum_a (x_i[a] - x_j[a])^2), summed in axis order like EuclideanMetric, so
/// the lags are bit-identical to it; the axis loops vectorize.
template <PairStatistic S, bool Subsample, int K_FIXED, int D_FIXED>
void bin_pair_rows_euclidean(const double* coordinates, std::size_t n, int dimension,
                             const double* values, int components, const BinLayout& bins,
                             std::uint64_t seed, std::uint64_t keep_below, std::size_t row_begin,
                             std::size_t row_end, PairSums out,
                             const DirectionCone* cone = nullptr) noexcept {
  const std::size_t D = static_cast<std::size_t>(D_FIXED > 0 ? D_FIXED : dimension);
  alignas(64) double h[detail::kLagBlock];
  alignas(64) double w[detail::kLagBlock];
  alignas(64) std::int32_t code[detail::kLagBlock];
  double xi[D_FIXED > 0 ? D_FIXED : 64];
  for (std::size_t i = row_begin; i < row_end; ++i) {
    for (std::size_t a = 0; a < D; ++a) xi[a] = coordinates[a * n + i];
    for (std::size_t j0 = 0; j0 < i; j0 += detail::kLagBlock) {
      const std::size_t m = i - j0 < detail::kLagBlock ? i - j0 : detail::kLagBlock;
      {
        const double* x = coordinates + j0;
        const double x0 = xi[0];
        for (std::size_t t = 0; t < m; ++t) {
          const double d = x0 - x[t];
          h[t] = d * d;
        }
      }
      for (std::size_t a = 1; a < D; ++a) {
        const double* x = coordinates + a * n + j0;
        const double xa = xi[a];
        for (std::size_t t = 0; t < m; ++t) {
          const double d = xa - x[t];
          h[t] += d * d;
        }
      }
      detail::sqrt_block(h, m);
      if (cone != nullptr) mask_directions(*cone, i, j0, m, h);
      if constexpr (K_FIXED == 1) detail::scalar_statistics<S>(values[i], values + j0, m, w);
      detail::accumulate_lags<S, Subsample, K_FIXED>(i, j0, m, h, w, code, values, components,
                                                     bins, seed, keep_below, out);
    }
  }
}

/// Second pass of Dowd's estimator: writes |z_i[c] - z_j[c]| of every binned pair of rows
/// [row_begin, row_end) to `out + cursor[k] * K + c` and advances cursor[k] (k = the pair's bin).
/// The caller sizes the regions from a first counting pass over the same rows; the pairs and
/// bins are those of bin_pair_rows (same subsampling, same lags, exact edge rule).
template <bool Subsample, class L, class M>
void store_pair_differences(const L* locations, const double* values, int components,
                            const M& metric, const BinLayout& bins, std::uint64_t seed,
                            std::uint64_t keep_below, std::size_t row_begin, std::size_t row_end,
                            std::uint64_t* cursor, double* out,
                            const DirectionCone* cone = nullptr) noexcept {
  const std::size_t K = static_cast<std::size_t>(components);
  for (std::size_t i = row_begin; i < row_end; ++i) {
    const double* zi = values + i * K;
    for (std::size_t j = 0; j < i; ++j) {
      if constexpr (Subsample) {
        if (pair_hash(seed, i, j) >= keep_below) continue;
      }
      double h = metric(locations[i], locations[j]);
      if (cone != nullptr) mask_directions(*cone, i, j, 1, &h);
      const std::ptrdiff_t k = find_bin(h, bins);
      if (k < 0) continue;
      const double* zj = values + j * K;
      double* o = out + cursor[k]++ * K;
      for (std::size_t c = 0; c < K; ++c) o[c] = std::fabs(zi[c] - zj[c]);
    }
  }
}

/// Naive reference for bin_pair_rows over all rows: the same pairs, bins found by a linear scan
/// over the edges with the comparison rule written out, sums in pair order (i, j < i).
template <class L, class M>
void bin_pairs_reference(const L* locations, const double* values, std::size_t n_points,
                         int components, const M& metric, const double* edges, std::size_t bins,
                         bool gstat, PairStatistic statistic, double keep_fraction,
                         std::uint64_t seed, PairSums out) {
  const long double threshold = static_cast<long double>(keep_fraction) * 18446744073709551616.0L;
  for (std::size_t i = 1; i < n_points; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (keep_fraction < 1.0 && static_cast<long double>(pair_hash(seed, i, j)) >= threshold)
        continue;
      const double h = metric(locations[i], locations[j]);
      std::ptrdiff_t bin = -1;
      for (std::size_t k = 0; k < bins; ++k) {
        const bool inside = gstat ? (k == 0 ? (h >= edges[0] && h <= edges[1])
                                            : (h > edges[k] && h <= edges[k + 1]))
                                  : (h >= edges[k] && h < edges[k + 1]);
        if (inside) {
          bin = static_cast<std::ptrdiff_t>(k);
          break;
        }
      }
      if (bin < 0) continue;
      const std::size_t b = static_cast<std::size_t>(bin);
      out.count[b] += 1;
      out.lag[b] += h;
      for (int c = 0; c < components; ++c) {
        const double d = values[i * components + c] - values[j * components + c];
        out.stat[b * components + c] +=
            statistic == PairStatistic::SquaredDifference ? d * d : std::sqrt(std::fabs(d));
      }
    }
  }
}

}  // namespace errfield::kernels
