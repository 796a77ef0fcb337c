#pragma once
/// SIMD variants (AVX2, AVX-512) of the empirical variogram's Euclidean pair loop
/// (bin_pair_rows_euclidean in pair_binning.hpp) for its most common case: one value component,
/// equally spaced bins, every pair (no subsampling). Chosen at run time (KernelIsa,
/// best_kernel_isa) so the library still runs on any x86-64; compiled with GCC/Clang `target`
/// attributes and with floating-point contraction off, so every rounding is the baseline's.
///
/// Same result, bit for bit, as bin_pair_rows_euclidean: the squared lag is summed in axis order
/// without fused multiply-adds, vsqrtpd is correctly rounded like std::sqrt, the bin is decided
/// by the same exact rule (the vector guess defers lags within kNearEdge of an inner edge to
/// find_bin), and each bin's sums receive the pairs in the same order (i ascending, then j
/// ascending). What differs is the bookkeeping: 4 (AVX2) or 8 (AVX-512) pairs per step and one
/// 32-byte slot per bin, (lag sum, statistic sum, count, unused), updated with a single 256-bit
/// add of (h, w, 1, 0) per pair instead of three separate read-modify-writes; the slots live on
/// the stack (at most kSimdMaxBins bins) and are copied to the caller's sums at the end.
/// Plain pointers in, sums out: no allocation, no checks, no exceptions inside.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pair_binning.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ERRFIELD_KERNELS_HAVE_X86_SIMD 1
#include <immintrin.h>
#else
#define ERRFIELD_KERNELS_HAVE_X86_SIMD 0
#endif

namespace errfield::kernels {

/// Instruction set a kernel runs with. Baseline: the build's own target (SSE2 on x86-64).
enum class KernelIsa { Baseline, Avx2, Avx512 };

/// The best KernelIsa this CPU (and OS) runs. Cheap (reads flags libgcc filled in at start-up).
inline KernelIsa best_kernel_isa() noexcept {
#if ERRFIELD_KERNELS_HAVE_X86_SIMD
  if (__builtin_cpu_supports("avx512f")) return KernelIsa::Avx512;
  if (__builtin_cpu_supports("avx2")) return KernelIsa::Avx2;
#endif
  return KernelIsa::Baseline;
}

/// Whether this CPU runs kernels built for `isa` (Baseline always; AVX-512 implies AVX2 here).
inline bool kernel_isa_supported(KernelIsa isa) noexcept {
  return static_cast<int>(isa) <= static_cast<int>(best_kernel_isa());
}

/// Most bins the SIMD paths handle (their per-bin slots live on the stack: 32 bytes each).
inline constexpr std::size_t kSimdMaxBins = 1024;

/// Most points the SIMD paths take: they count pairs in doubles, exact below 2^53 pairs.
inline constexpr std::size_t kSimdMaxPoints = std::size_t{1} << 26;

#if ERRFIELD_KERNELS_HAVE_X86_SIMD

// AVX-512 implies FMA, and GCC contracts a * b + c into one fused multiply-add by default
// (-ffp-contract=fast), even across intrinsics: that would round differently from the baseline
// kernel. Both SIMD kernels therefore switch contraction off.
#if defined(__clang__)
#define ERRFIELD_KERNELS_NO_FP_CONTRACT
#define ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY _Pragma("clang fp contract(off)")
#else
#define ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((optimize("fp-contract=off")))
#define ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
#endif

namespace detail {

/// slots[4 k .. 4 k + 3] += p: bin k's (lag sum, statistic sum, count, unused) += (h, w, 1, 0).
__attribute__((target("avx2"), always_inline)) inline void add_to_slot(double* slots,
                                                                        std::size_t k,
                                                                        __m256d p) noexcept {
  double* q = slots + 4 * k;
  _mm256_store_pd(q, _mm256_add_pd(_mm256_load_pd(q), p));
}

/// Pairs (i, j) for j in [j_begin, i), one at a time: a row's tail after the vector steps. Same
/// arithmetic (and no contraction) as the vector steps, so the sums stay bit-identical.
template <PairStatistic S>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx2"))) inline void add_row_tail(
    double* slots, const double* xi, double zi, const double* coordinates, std::size_t n, std::size_t D,
    const double* values, const BinLayout& bins, std::size_t j_begin, std::size_t i) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  for (std::size_t j = j_begin; j < i; ++j) {
    double d = xi[0] - coordinates[j];
    double h2 = d * d;
    for (std::size_t a = 1; a < D; ++a) {
      d = xi[a] - coordinates[a * n + j];
      h2 += d * d;
    }
    const double h = std::sqrt(h2);
    const double w = pair_statistic<S>(zi - values[j]);
    const std::ptrdiff_t kb = find_bin(h, bins);
    add_to_slot(slots, kb < 0 ? bins.bins : static_cast<std::size_t>(kb), _mm256_set_pd(0.0, 1.0, w, h));
  }
}

/// Adds the B slots' (lag sum, statistic sum, count) to `out` (B includes the discard slot).
inline void flush_slots(const double* slots, std::size_t B, PairSums out) noexcept {
  for (std::size_t k = 0; k < B; ++k) {
    out.lag[k] += slots[4 * k];
    out.stat[k] += slots[4 * k + 1];
    out.count[k] += static_cast<std::uint64_t>(slots[4 * k + 2]);
  }
}

}  // namespace detail

namespace detail {

template <PairStatistic S, bool Gstat, int D_FIXED>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx2"))) void bin_pair_rows_euclidean_avx2(
    const double* coordinates, std::size_t n, int dimension, const double* values,
    const BinLayout& bins, std::size_t row_begin, std::size_t row_end, PairSums out) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  const std::size_t D = static_cast<std::size_t>(D_FIXED > 0 ? D_FIXED : dimension);
  const std::size_t B = bins.bins + 1;  // + the discard slot
  // Per bin (lag sum, statistic sum, count, unused): one 256-bit add per pair. Counts are
  // exact in doubles (fewer than 2^53 pairs, see kSimdMaxPoints).
  alignas(32) double slots[4 * (kSimdMaxBins + 1)];
  for (std::size_t k = 0; k < 4 * B; ++k) slots[k] = 0.0;

  const double e0 = bins.edges[0];
  const double en = bins.edges[bins.bins];
  const __m256d ve0 = _mm256_set1_pd(e0), ven = _mm256_set1_pd(en);
  const __m256d vinv = _mm256_set1_pd(bins.inv_width);
  const __m256d vlo = _mm256_set1_pd(detail::kNearEdge);
  const __m256d vhi = _mm256_set1_pd(1.0 - detail::kNearEdge);
  const __m256d vminus = _mm256_set1_pd(-1.0);
  const __m256d voutside = _mm256_set1_pd(static_cast<double>(bins.bins));
  const __m256d vabs = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFFll));
  const std::int32_t outside = static_cast<std::int32_t>(bins.bins);
  const __m256d vone_zero = _mm256_set_pd(0.0, 1.0, 0.0, 0.0);  // lanes 2, 3 = (1, 0)

  double xi[D_FIXED > 0 ? D_FIXED : 64];
  __m256d vxi[D_FIXED > 0 ? D_FIXED : 64];
  for (std::size_t i = row_begin; i < row_end; ++i) {
    for (std::size_t a = 0; a < D; ++a) {
      xi[a] = coordinates[a * n + i];
      vxi[a] = _mm256_set1_pd(xi[a]);
    }
    const double zi = values[i];
    const __m256d vzi = _mm256_set1_pd(zi);
    std::size_t j = 0;
    for (; j + 4 <= i; j += 4) {
      __m256d d = _mm256_sub_pd(vxi[0], _mm256_loadu_pd(coordinates + j));
      __m256d h = _mm256_mul_pd(d, d);
      for (std::size_t a = 1; a < D; ++a) {
        d = _mm256_sub_pd(vxi[a], _mm256_loadu_pd(coordinates + a * n + j));
        h = _mm256_add_pd(h, _mm256_mul_pd(d, d));
      }
      h = _mm256_sqrt_pd(h);
      const __m256d dz = _mm256_sub_pd(vzi, _mm256_loadu_pd(values + j));
      __m256d w;
      if constexpr (S == PairStatistic::SquaredDifference) w = _mm256_mul_pd(dz, dz);
      else w = _mm256_sqrt_pd(_mm256_and_pd(dz, vabs));
      // Bin codes as in detail::bin_codes, formed in doubles and converted once.
      const __m256d in = _mm256_and_pd(
          _mm256_cmp_pd(h, ve0, _CMP_GE_OQ),
          Gstat ? _mm256_cmp_pd(h, ven, _CMP_LE_OQ) : _mm256_cmp_pd(h, ven, _CMP_LT_OQ));
      // No clamping needed: lanes outside [e_0, e_n] take `outside` whatever their guess, and an
      // in-range guess lies in [0, n] (a guess that rounds to n sits at an edge: near).
      const __m256d g = _mm256_mul_pd(_mm256_sub_pd(h, ve0), vinv);
      const __m256d k = _mm256_round_pd(g, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
      const __m256d frac = _mm256_sub_pd(g, k);
      const __m256d near = _mm256_or_pd(_mm256_cmp_pd(frac, vlo, _CMP_LT_OQ),
                                        _mm256_cmp_pd(frac, vhi, _CMP_GT_OQ));
      const __m256d code_d = _mm256_blendv_pd(voutside, _mm256_blendv_pd(k, vminus, near), in);
      const __m128i code = _mm256_cvttpd_epi32(code_d);
      std::uint64_t c01 = static_cast<std::uint64_t>(_mm_cvtsi128_si64(code));
      std::uint64_t c23 = static_cast<std::uint64_t>(_mm_extract_epi64(code, 1));
      if (_mm256_movemask_pd(_mm256_and_pd(near, in)) != 0) {  // rare: decide on the stored edges
        alignas(32) double hs[4];
        alignas(16) std::int32_t c[4];
        _mm256_store_pd(hs, h);
        _mm_store_si128(reinterpret_cast<__m128i*>(c), code);
        for (int t = 0; t < 4; ++t) {
          if (c[t] >= 0) continue;
          const std::ptrdiff_t kb = find_bin(hs[t], bins);
          c[t] = kb < 0 ? outside : static_cast<std::int32_t>(kb);
        }
        const __m128i fixed = _mm_load_si128(reinterpret_cast<const __m128i*>(c));
        c01 = static_cast<std::uint64_t>(_mm_cvtsi128_si64(fixed));
        c23 = static_cast<std::uint64_t>(_mm_extract_epi64(fixed, 1));
      }
      // (h_t, w_t, 1, 0) per pair t, added in pair order.
      const __m256d lo = _mm256_unpacklo_pd(h, w);  // (h0, w0, h2, w2)
      const __m256d hi = _mm256_unpackhi_pd(h, w);  // (h1, w1, h3, w3)
      detail::add_to_slot(slots, c01 & 0xFFFFFFFFu, _mm256_blend_pd(vone_zero, lo, 0x3));
      detail::add_to_slot(slots, c01 >> 32, _mm256_blend_pd(vone_zero, hi, 0x3));
      detail::add_to_slot(slots, c23 & 0xFFFFFFFFu, _mm256_permute2f128_pd(lo, vone_zero, 0x31));
      detail::add_to_slot(slots, c23 >> 32, _mm256_permute2f128_pd(hi, vone_zero, 0x31));
    }
    detail::add_row_tail<S>(slots, xi, zi, coordinates, n, D, values, bins, j, i);  // the last < 4 pairs
  }
  detail::flush_slots(slots, B, out);
}

}  // namespace detail

namespace detail {

/// (h_p, w_p, 1, 0, h_q, w_q, 1, 0) for lanes p = 2 m, q = 2 m + 1 of h and w.
template <int M>
__attribute__((target("avx512f"), always_inline)) inline __m512d pair_slots_avx512(
    __m512d h, __m512d w, __m512d one_zero) noexcept {
  // Indices 0..7 pick from h, 8..15 from w; lanes 2, 3, 6, 7 are replaced by (1, 0).
  const __m512i idx = _mm512_set_epi64(0, 0, 8 + 2 * M + 1, 2 * M + 1, 0, 0, 8 + 2 * M, 2 * M);
  return _mm512_mask_blend_pd(0x33, one_zero, _mm512_permutex2var_pd(h, idx, w));
}

/// The bin rule's constants for 8 lags at once, made once per kernel call (bin_rule_avx512).
struct BinRuleAvx512 {
  __m512d first_edge, last_edge, inv_width, near_low, near_high, outside;
};

__attribute__((target("avx512f"), always_inline)) inline BinRuleAvx512 bin_rule_avx512(
    const BinLayout& bins) noexcept {
  return {_mm512_set1_pd(bins.edges[0]), _mm512_set1_pd(bins.edges[bins.bins]), _mm512_set1_pd(bins.inv_width),
          _mm512_set1_pd(kNearEdge), _mm512_set1_pd(1.0 - kNearEdge), _mm512_set1_pd(static_cast<double>(bins.bins))};
}

/// The bins of 8 lags h into c[0..7] (32-byte aligned), bins.bins for a lag outside every bin: the
/// truncated (h - e0) / width, except that a lag within kNearEdge (relative) of an inner edge is
/// decided by find_bin on the stored edges, so every pair lands where the scalar rule puts it.
template <bool Gstat>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx512f"), always_inline)) inline void bin_codes_avx512(
    const BinRuleAvx512& rule, const BinLayout& bins, __m512d h, std::int32_t* c) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  const __mmask8 in = _mm512_mask_cmp_pd_mask(_mm512_cmp_pd_mask(h, rule.first_edge, _CMP_GE_OQ), h, rule.last_edge,
                                              Gstat ? _CMP_LE_OQ : _CMP_LT_OQ);
  const __m512d g = _mm512_mul_pd(_mm512_sub_pd(h, rule.first_edge), rule.inv_width);
  const __m512d k = _mm512_mask_roundscale_pd(g, 0xFF, g, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC);
  const __m512d frac = _mm512_sub_pd(g, k);
  const __mmask8 near = _mm512_mask_cmp_pd_mask(in, frac, rule.near_low, _CMP_LT_OQ) |
                        _mm512_mask_cmp_pd_mask(in, frac, rule.near_high, _CMP_GT_OQ);
  _mm256_store_si256(reinterpret_cast<__m256i*>(c),
                     _mm512_maskz_cvttpd_epi32(0xFF, _mm512_mask_blend_pd(in, rule.outside, k)));
  if (near != 0) {  // rare: decide on the stored edges
    alignas(64) double hs[8];
    _mm512_store_pd(hs, h);
    for (int t = 0; t < 8; ++t) {
      if (((near >> t) & 1) == 0) continue;
      const std::ptrdiff_t kb = find_bin(hs[t], bins);
      c[t] = kb < 0 ? static_cast<std::int32_t>(bins.bins) : static_cast<std::int32_t>(kb);
    }
  }
}

template <PairStatistic S, bool Gstat, int D_FIXED>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx512f"))) void
bin_pair_rows_euclidean_avx512(const double* coordinates, std::size_t n, int dimension,
                               const double* values, const BinLayout& bins, std::size_t row_begin,
                               std::size_t row_end, PairSums out) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  const std::size_t D = static_cast<std::size_t>(D_FIXED > 0 ? D_FIXED : dimension);
  const std::size_t B = bins.bins + 1;  // + the discard slot
  alignas(64) double slots[4 * (kSimdMaxBins + 1)];
  for (std::size_t k = 0; k < 4 * B; ++k) slots[k] = 0.0;

  const BinRuleAvx512 rule = bin_rule_avx512(bins);
  const __m512d vone_zero = _mm512_set_pd(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);

  double xi[D_FIXED > 0 ? D_FIXED : 64];
  __m512d vxi[D_FIXED > 0 ? D_FIXED : 64];
  for (std::size_t i = row_begin; i < row_end; ++i) {
    for (std::size_t a = 0; a < D; ++a) {
      xi[a] = coordinates[a * n + i];
      vxi[a] = _mm512_set1_pd(xi[a]);
    }
    const double zi = values[i];
    const __m512d vzi = _mm512_set1_pd(zi);
    std::size_t j = 0;
    for (; j + 8 <= i; j += 8) {
      __m512d d = _mm512_sub_pd(vxi[0], _mm512_loadu_pd(coordinates + j));
      __m512d h = _mm512_mul_pd(d, d);
      for (std::size_t a = 1; a < D; ++a) {
        d = _mm512_sub_pd(vxi[a], _mm512_loadu_pd(coordinates + a * n + j));
        h = _mm512_add_pd(h, _mm512_mul_pd(d, d));
      }
      h = _mm512_mask_sqrt_pd(h, 0xFF, h);
      const __m512d dz = _mm512_sub_pd(vzi, _mm512_loadu_pd(values + j));
      __m512d w;
      if constexpr (S == PairStatistic::SquaredDifference) w = _mm512_mul_pd(dz, dz);
      else w = _mm512_mask_sqrt_pd(dz, 0xFF, _mm512_abs_pd(dz));
      alignas(32) std::int32_t c[8];
      detail::bin_codes_avx512<Gstat>(rule, bins, h, c);
      // (h_t, w_t, 1, 0) per pair t, added in pair order.
      const __m512d p01 = detail::pair_slots_avx512<0>(h, w, vone_zero);
      const __m512d p23 = detail::pair_slots_avx512<1>(h, w, vone_zero);
      const __m512d p45 = detail::pair_slots_avx512<2>(h, w, vone_zero);
      const __m512d p67 = detail::pair_slots_avx512<3>(h, w, vone_zero);
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[0]), _mm512_maskz_extractf64x4_pd(0xF, p01, 0));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[1]), _mm512_maskz_extractf64x4_pd(0xF, p01, 1));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[2]), _mm512_maskz_extractf64x4_pd(0xF, p23, 0));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[3]), _mm512_maskz_extractf64x4_pd(0xF, p23, 1));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[4]), _mm512_maskz_extractf64x4_pd(0xF, p45, 0));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[5]), _mm512_maskz_extractf64x4_pd(0xF, p45, 1));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[6]), _mm512_maskz_extractf64x4_pd(0xF, p67, 0));
      detail::add_to_slot(slots, static_cast<std::uint32_t>(c[7]), _mm512_maskz_extractf64x4_pd(0xF, p67, 1));
    }
    detail::add_row_tail<S>(slots, xi, zi, coordinates, n, D, values, bins, j, i);  // the last < 8 pairs
  }
  detail::flush_slots(slots, B, out);
}

}  // namespace detail

/// Rows [row_begin, row_end) of bin_pair_rows_euclidean for K = 1, a uniform layout with
/// bins.bins <= kSimdMaxBins, no subsampling; adds into `out` (zeroed by the caller) exactly what
/// bin_pair_rows_euclidean<S, false, 1, D_FIXED> adds. Call only when
/// kernel_isa_supported(KernelIsa::Avx2) (the caller checks). D_FIXED > 0 fixes the number of axes, otherwise
/// `dimension` (<= 64) is used.
template <PairStatistic S, int D_FIXED>
void bin_pair_rows_euclidean_avx2(const double* coordinates, std::size_t n, int dimension,
                                  const double* values, const BinLayout& bins,
                                  std::size_t row_begin, std::size_t row_end,
                                  PairSums out) noexcept {
  if (bins.gstat)
    detail::bin_pair_rows_euclidean_avx2<S, true, D_FIXED>(coordinates, n, dimension, values, bins,
                                                            row_begin, row_end, out);
  else
    detail::bin_pair_rows_euclidean_avx2<S, false, D_FIXED>(coordinates, n, dimension, values,
                                                             bins, row_begin, row_end, out);
}

/// AVX-512 (F) variant of bin_pair_rows_euclidean_avx2: eight pairs per step, same
/// cases, same sums bit for bit. Call only when kernel_isa_supported(KernelIsa::Avx512).
template <PairStatistic S, int D_FIXED>
void bin_pair_rows_euclidean_avx512(const double* coordinates, std::size_t n, int dimension,
                                    const double* values, const BinLayout& bins,
                                    std::size_t row_begin, std::size_t row_end,
                                    PairSums out) noexcept {
  if (bins.gstat)
    detail::bin_pair_rows_euclidean_avx512<S, true, D_FIXED>(coordinates, n, dimension, values,
                                                              bins, row_begin, row_end, out);
  else
    detail::bin_pair_rows_euclidean_avx512<S, false, D_FIXED>(coordinates, n, dimension, values,
                                                               bins, row_begin, row_end, out);
}

#endif  // ERRFIELD_KERNELS_HAVE_X86_SIMD

/// bin_pair_rows_euclidean with the instruction set `isa` (which the CPU must support, see
/// kernel_isa_supported): the AVX2 / AVX-512 path when the case is one they cover (K = 1, no
/// subsampling, no direction cone, uniform bins, at most kSimdMaxBins bins and kSimdMaxPoints points), the baseline
/// kernel otherwise. Same sums either way, bit for bit.
template <PairStatistic S, bool Subsample, int K_FIXED, int D_FIXED>
void bin_pair_rows_euclidean_isa(KernelIsa isa, const double* coordinates, std::size_t n,
                                 int dimension, const double* values, int components,
                                 const BinLayout& bins, std::uint64_t seed,
                                 std::uint64_t keep_below, std::size_t row_begin,
                                 std::size_t row_end, PairSums out,
                                 const DirectionCone* cone = nullptr) noexcept {
#if ERRFIELD_KERNELS_HAVE_X86_SIMD
  if constexpr (!Subsample && K_FIXED == 1) {
    if (isa != KernelIsa::Baseline && cone == nullptr && bins.uniform && bins.bins <= kSimdMaxBins &&
        n <= kSimdMaxPoints) {
      if (isa == KernelIsa::Avx512)
        bin_pair_rows_euclidean_avx512<S, D_FIXED>(coordinates, n, dimension, values, bins,
                                                   row_begin, row_end, out);
      else
        bin_pair_rows_euclidean_avx2<S, D_FIXED>(coordinates, n, dimension, values, bins,
                                                 row_begin, row_end, out);
      return;
    }
  }
#else
  (void)isa;
#endif
  bin_pair_rows_euclidean<S, Subsample, K_FIXED, D_FIXED>(coordinates, n, dimension, values,
                                                          components, bins, seed, keep_below,
                                                          row_begin, row_end, out, cone);
}

}  // namespace errfield::kernels
