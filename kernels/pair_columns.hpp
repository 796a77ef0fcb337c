#pragma once
/// Sorted-column enumeration of the empirical variogram's pairs for its most common case:
/// Euclidean lags in 1 to 3 dimensions, one value component, equally spaced bins, every pair (no
/// subsampling), in every direction or in a symmetric direction cone (pair_direction.hpp, tested
/// on each pair within the cutoff with the all-pairs loop's arithmetic). It visits each unordered pair that can lie within the cutoff
/// once and adds it to per-bin sums, in an order of its own: the lags, and so every pair's bin and
/// every bin's pair count, are those of the all-pairs loop (pair_binning.hpp) bit for bit, the sums
/// differ from it only by the rounding of a different summation order. Use it through
/// errfield::empirical_variogram, which chooses it (and otherwise the ordered cell list of
/// pair_cells.hpp, which keeps the all-pairs order for the other cases).
///
/// How: the points are sorted into columns - a uniform grid over up to two coordinate axes whose
/// cell side is at least cutoff / reach - and, within a column, by a third axis (the sort axis,
/// the one with the largest extent). Point p then meets the points of its own column after it
/// and the points of the columns ahead of it in a half stencil ((d1, d2) with d2 > 0, or d2 = 0
/// and d1 > 0, |d| <= reach): each pair exactly once. In each column only the points within the
/// cutoff of p on the sort axis can be in range, a contiguous run whose ends only move forward as
/// p advances (a sweep), and a column farther from p than the cutoff is skipped. Their squared
/// lags are computed 8 at a time (AVX-512)
/// or one at a time (any CPU), the candidates within the cutoff are packed into a buffer and
/// binned from there, so the vector work per pair in range does not pay for the candidates out
/// of it.
///
/// Summation order (the same for both instruction sets, so their sums agree bit for bit): the
/// pairs within the cutoff form one stream per call, in the order p ascending, then the stencil's
/// columns in their fixed order, then the column's points ascending; the k-th pair of the stream
/// is added to copy k mod kColumnSlotCopies of the per-bin sums, and the copies are added to the
/// caller's sums in copy order at the end. Several copies break the chain of dependent additions
/// when consecutive pairs fall in the same bin.
/// Plain pointers in, sums out: no allocation, no checks, no exceptions inside.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pair_binning.hpp"
#include "pair_binning_simd.hpp"
#include "pair_direction.hpp"

namespace errfield::kernels {

/// Most columns per bound (SortedColumns::reach).
inline constexpr std::size_t kColumnMaxReach = 4;
/// Copies of the per-bin sums that consecutive pairs in range rotate through.
inline constexpr std::size_t kColumnSlotCopies = 4;

/// Points sorted into columns (built by the caller, see the file comment). Positions p = 0..n-1
/// are the sorted order; the arrays are indexed by position.
struct SortedColumns {
  std::size_t n = 0;
  int dimension = 0;                    ///< D: 1..3 axes of `coordinates`
  const double* coordinates = nullptr;  ///< sorted, axis-major: coordinates[a * n + p]
  const double* values = nullptr;       ///< sorted, one component
  const std::uint32_t* column_start = nullptr;  ///< first position of each column; columns + 1 entries
  int sort_axis = 0;  ///< coordinate ascending within a column
  int grid_axes = 0;  ///< 0..2 gridded axes (0: a single column)
  int grid_axis[2] = {0, 0};
  std::size_t columns_per_axis[2] = {1, 1};  ///< column = index_0 + index_1 * columns_per_axis[0]
  std::size_t reach = 1;  ///< a pair within the cutoff is at most `reach` columns apart per axis
  double origin[2] = {0.0, 0.0};  ///< lower edge of column 0 on each gridded axis
  double side[2] = {1.0, 1.0};    ///< column width, >= cutoff / reach
  double cutoff = 0.0;            ///< the largest bin edge
  /// Null: every direction. Otherwise a symmetric cone (cone_is_symmetric) over `coordinates`:
  /// only the pairs it keeps are binned.
  const DirectionCone* cone = nullptr;
};

/// Doubles of the per-bin sum copies a call needs (the caller's workspace, one per thread).
inline constexpr std::size_t column_slot_doubles(std::size_t bins) noexcept {
  return kColumnSlotCopies * (bins + 1) * 4;
}

namespace detail {

/// Positions [lo, hi) of candidates of one point in one column of its stencil.
struct ColumnRun {
  std::size_t lo, hi;
};

/// Most columns in a half stencil: (reach + 1) + reach (2 reach + 1).
inline constexpr std::size_t kColumnMaxRuns =
    (kColumnMaxReach + 1) + kColumnMaxReach * (2 * kColumnMaxReach + 1);

/// The half stencil of one column and, per stencil column, the run of points within the cutoff
/// of the current point on the sort axis. The points of a column come in ascending order on the
/// sort axis, so both ends of every run only move forward: a sweep, O(1) amortized per point
/// and stencil column (a binary search per run cost more than the candidates it saves).
struct ColumnSweep {
  std::size_t column = ~std::size_t{0};
  std::size_t count = 0;
  std::size_t end[kColumnMaxRuns] = {};  ///< one past the column's last position
  std::size_t lo[kColumnMaxRuns] = {}, hi[kColumnMaxRuns] = {};
  long offset[kColumnMaxRuns][2] = {};  ///< (d0, d1) of the stencil column
  bool own[kColumnMaxRuns] = {};        ///< p's own column: the points after p

  /// Starts the sweep of `column` (its runs at the columns' first points).
  void start(const SortedColumns& g, std::size_t c) noexcept {
    column = c;
    count = 0;
    const std::size_t n0 = g.columns_per_axis[0];
    const long k0 = static_cast<long>(c % n0), k1 = static_cast<long>(c / n0);
    const long r = static_cast<long>(g.reach);
    const long hi0 = g.grid_axes >= 1 ? std::min(r, static_cast<long>(n0) - 1 - k0) : 0;
    const long lo0 = g.grid_axes >= 1 ? std::max(-r, -k0) : 0;
    const long hi1 = g.grid_axes >= 2 ? std::min(r, static_cast<long>(g.columns_per_axis[1]) - 1 - k1) : 0;
    for (long d1 = 0; d1 <= hi1; ++d1)
      for (long d0 = d1 == 0 ? 0 : lo0; d0 <= hi0; ++d0) {
        const std::size_t col = static_cast<std::size_t>(k0 + d0) + static_cast<std::size_t>(k1 + d1) * n0;
        lo[count] = hi[count] = g.column_start[col];
        end[count] = g.column_start[col + 1];
        offset[count][0] = d0;
        offset[count][1] = d1;
        own[count] = d0 == 0 && d1 == 0;
        ++count;
      }
  }
};

/// The runs of the points that can lie within the cutoff of the point at position p (in the
/// sweep's column) and come after it in the half stencil; returns their number. Conservative: a
/// run may hold points out of range (the lag test drops them), never misses one in range.
inline std::size_t column_runs(const SortedColumns& g, std::size_t p, ColumnSweep& sweep,
                               ColumnRun* runs) noexcept {
  const std::size_t n = g.n;
  const double* s = g.coordinates + static_cast<std::size_t>(g.sort_axis) * n;
  const double xs = s[p];
  // 1e-9 (relative) covers the rounding of x +- reach and of the lag, far over.
  const double reach_s = g.cutoff * (1.0 + 1e-9);
  const double below = xs - reach_s, above = xs + reach_s;
  const double cutoff2 = g.cutoff * g.cutoff;
  // p's squared gap to the stencil columns on each gridded axis (offset d = -reach..reach),
  // shortened by a millionth of a column so that rounding in the column assignment cannot drop
  // a pair; a column farther than the cutoff is skipped.
  const std::size_t n0 = g.columns_per_axis[0];
  const std::size_t k[2] = {sweep.column % n0, sweep.column / n0};
  const long r = static_cast<long>(g.reach);
  double gap2[2][2 * kColumnMaxReach + 1] = {};
  for (int a = 0; a < g.grid_axes; ++a) {
    const double x = g.coordinates[static_cast<std::size_t>(g.grid_axis[a]) * n + p];
    const double slack = 1e-6 * g.side[a];
    for (long d = -r; d <= r; ++d) {
      const double edge = g.origin[a] + static_cast<double>(static_cast<long>(k[a]) + d) * g.side[a];
      double gap = d < 0 ? x - (edge + g.side[a]) : d > 0 ? edge - x : 0.0;
      gap = gap > slack ? gap - slack : 0.0;
      gap2[a][d + r] = gap * gap;
    }
  }
  std::size_t count = 0;
  for (std::size_t c = 0; c < sweep.count; ++c) {
    std::size_t lo = sweep.lo[c], hi = sweep.hi[c];
    const std::size_t last = sweep.end[c];
    if (sweep.own[c]) {
      lo = p + 1;
    } else {
      while (lo < last && s[lo] < below) ++lo;
    }
    if (hi < lo) hi = lo;
    while (hi < last && s[hi] <= above) ++hi;
    sweep.lo[c] = lo;
    sweep.hi[c] = hi;
    if (hi == lo) continue;
    const double g2 = gap2[0][sweep.offset[c][0] + r] + gap2[1][sweep.offset[c][1] + r];
    if (!(g2 <= cutoff2 * (1.0 + 1e-9))) continue;
    runs[count++] = {lo, hi};
  }
  return count;
}

/// Column of position p: the last c with column_start[c] <= p.
inline std::size_t column_of_position(const SortedColumns& g, std::size_t p) noexcept {
  const std::size_t columns = g.columns_per_axis[0] * g.columns_per_axis[1];
  const std::uint32_t* c = std::upper_bound(g.column_start, g.column_start + columns + 1,
                                            static_cast<std::uint32_t>(p));
  return static_cast<std::size_t>(c - g.column_start) - 1;
}

/// Adds the slot copies' (lag sum, statistic sum, count) to `out` in copy order; B bins + 1.
inline void flush_column_slots(const double* slots, std::size_t B, PairSums out) noexcept {
  for (std::size_t k = 0; k < B; ++k)
    for (std::size_t c = 0; c < kColumnSlotCopies; ++c) {
      const double* q = slots + (c * B + k) * 4;
      out.lag[k] += q[0];
      out.stat[k] += q[1];
      out.count[k] += static_cast<std::uint64_t>(q[2]);
    }
}

/// Adds the stream's pair number `index` with squared lag h2 and value difference dz.
template <PairStatistic S>
inline void add_column_pair(double* slots, std::size_t B, const BinLayout& bins, std::size_t index,
                            double h2, double dz) noexcept {
  const double h = std::sqrt(h2);
  const double w = pair_statistic<S>(dz);
  const std::ptrdiff_t kb = find_bin(h, bins);
  double* q = slots + ((index % kColumnSlotCopies) * B + (kb < 0 ? bins.bins : static_cast<std::size_t>(kb))) * 4;
  q[0] += h;
  q[1] += w;
  q[2] += 1.0;
}

/// Portable kernel (any CPU): rows [p_begin, p_end), pairs one at a time.
template <PairStatistic S, int D>
void bin_column_pairs_baseline(const SortedColumns& g, const BinLayout& bins, std::size_t p_begin,
                               std::size_t p_end, double* slots, PairSums out) noexcept {
  const std::size_t B = bins.bins + 1;
  const std::size_t n = g.n;
  for (std::size_t k = 0; k < column_slot_doubles(bins.bins); ++k) slots[k] = 0.0;
  // Keeps every pair whose rounded square root is <= cutoff (see for_each_pair_in_cells).
  const double pre = g.cutoff * g.cutoff * (1.0 + 1e-12);
  ColumnRun runs[kColumnMaxRuns];
  ColumnSweep sweep;
  std::size_t stream = 0;
  std::size_t column = p_begin < p_end ? column_of_position(g, p_begin) : 0;
  for (std::size_t p = p_begin; p < p_end; ++p) {
    while (g.column_start[column + 1] <= p) ++column;
    if (column != sweep.column) sweep.start(g, column);
    const std::size_t m = column_runs(g, p, sweep, runs);
    double xp[3] = {0.0, 0.0, 0.0};
    for (int a = 0; a < D; ++a) xp[a] = g.coordinates[static_cast<std::size_t>(a) * n + p];
    const double vp = g.values[p];
    for (std::size_t r = 0; r < m; ++r)
      for (std::size_t q = runs[r].lo; q < runs[r].hi; ++q) {
        double d[3] = {xp[0] - g.coordinates[q], 0.0, 0.0};
        double h2 = d[0] * d[0];
        for (int a = 1; a < D; ++a) {
          d[a] = xp[a] - g.coordinates[static_cast<std::size_t>(a) * n + q];
          h2 += d[a] * d[a];
        }
        if (!(h2 <= pre)) continue;
        if (g.cone != nullptr && !cone_keeps_pair(*g.cone, d[0], d[1], d[2])) continue;
        add_column_pair<S>(slots, B, bins, stream++, h2, vp - g.values[q]);
      }
  }
  flush_column_slots(slots, B, out);
}

#if ERRFIELD_KERNELS_HAVE_X86_SIMD

/// Bins `groups` groups of 8 buffered pairs (squared lag, value difference), lane t of a group
/// into copy t mod kColumnSlotCopies (groups start at stream indices that are multiples of 8).
template <PairStatistic S, bool Gstat>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx512f"))) inline void drain_column_pairs_avx512(
    const double* h2s, const double* dzs, std::size_t groups, double* slots, std::size_t B,
    const BinLayout& bins) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  static_assert(kColumnSlotCopies == 4, "lane t of 8 goes to copy t & 3");
  const BinRuleAvx512 rule = bin_rule_avx512(bins);
  const __m512d vone_zero = _mm512_set_pd(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
  double* copy[4] = {slots, slots + B * 4, slots + 2 * B * 4, slots + 3 * B * 4};
  for (std::size_t gi = 0; gi < groups; ++gi) {
    const __m512d h = _mm512_mask_sqrt_pd(_mm512_setzero_pd(), 0xFF, _mm512_loadu_pd(h2s + 8 * gi));
    const __m512d dz = _mm512_loadu_pd(dzs + 8 * gi);
    __m512d w;
    if constexpr (S == PairStatistic::SquaredDifference) w = _mm512_mul_pd(dz, dz);
    else w = _mm512_mask_sqrt_pd(dz, 0xFF, _mm512_abs_pd(dz));
    alignas(32) std::int32_t c[8];
    bin_codes_avx512<Gstat>(rule, bins, h, c);  // the all-pairs kernel's rule
    const __m512d p01 = pair_slots_avx512<0>(h, w, vone_zero);
    const __m512d p23 = pair_slots_avx512<1>(h, w, vone_zero);
    const __m512d p45 = pair_slots_avx512<2>(h, w, vone_zero);
    const __m512d p67 = pair_slots_avx512<3>(h, w, vone_zero);
    add_to_slot(copy[0], static_cast<std::uint32_t>(c[0]), _mm512_maskz_extractf64x4_pd(0xF, p01, 0));
    add_to_slot(copy[1], static_cast<std::uint32_t>(c[1]), _mm512_maskz_extractf64x4_pd(0xF, p01, 1));
    add_to_slot(copy[2], static_cast<std::uint32_t>(c[2]), _mm512_maskz_extractf64x4_pd(0xF, p23, 0));
    add_to_slot(copy[3], static_cast<std::uint32_t>(c[3]), _mm512_maskz_extractf64x4_pd(0xF, p23, 1));
    add_to_slot(copy[0], static_cast<std::uint32_t>(c[4]), _mm512_maskz_extractf64x4_pd(0xF, p45, 0));
    add_to_slot(copy[1], static_cast<std::uint32_t>(c[5]), _mm512_maskz_extractf64x4_pd(0xF, p45, 1));
    add_to_slot(copy[2], static_cast<std::uint32_t>(c[6]), _mm512_maskz_extractf64x4_pd(0xF, p67, 0));
    add_to_slot(copy[3], static_cast<std::uint32_t>(c[7]), _mm512_maskz_extractf64x4_pd(0xF, p67, 1));
  }
}

/// cone_keeps_pair for 8 separations (d0, d1, d2) at once, with its arithmetic lane by lane: the
/// lanes of `lanes` the cone keeps. D: the axes (d2 unused below 3).
template <int D>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx512f"))) inline __mmask8 cone_mask_avx512(
    const DirectionCone& c, __m512d d0, __m512d d1, __m512d d2, __mmask8 lanes) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  if (c.gstat) {
    const __m512d norm2 = _mm512_add_pd(_mm512_mul_pd(d0, d0), _mm512_mul_pd(d1, d1));
    if (c.check_hor && c.cos_tol_hor > 0.0) {
      const __m512d dot = _mm512_add_pd(_mm512_mul_pd(d0, _mm512_set1_pd(c.hor_x)),
                                        _mm512_mul_pd(d1, _mm512_set1_pd(c.hor_y)));
      const __m512d k = _mm512_set1_pd(c.cos_tol_hor * c.cos_tol_hor);
      lanes = _mm512_mask_cmp_pd_mask(lanes, _mm512_mul_pd(dot, dot), _mm512_mul_pd(k, norm2), _CMP_GE_OQ);
    }
    if constexpr (D > 2) {
      if (c.check_ver && c.cos_tol_ver > 0.0) {
        const __m512d v = _mm512_add_pd(_mm512_mul_pd(_mm512_mask_sqrt_pd(norm2, 0xFF, norm2), _mm512_set1_pd(c.ver_xy)),
                                        _mm512_mul_pd(d2, _mm512_set1_pd(c.ver_z)));
        const __m512d k = _mm512_set1_pd(c.cos_tol_ver * c.cos_tol_ver);
        const __m512d all2 = _mm512_add_pd(norm2, _mm512_mul_pd(d2, d2));
        lanes = _mm512_mask_cmp_pd_mask(lanes, _mm512_mul_pd(v, v), _mm512_mul_pd(k, all2), _CMP_GE_OQ);
      }
    }
    return lanes;
  }
  if (!(c.cos_tol > 0.0)) return lanes;
  // 0 + x is x (up to the sign of a zero, which squares away): the scalar sums from 0.
  __m512d dot = _mm512_mul_pd(d0, _mm512_set1_pd(c.axis[0]));
  __m512d norm2 = _mm512_mul_pd(d0, d0);
  if constexpr (D > 1) {
    dot = _mm512_add_pd(dot, _mm512_mul_pd(d1, _mm512_set1_pd(c.axis[1])));
    norm2 = _mm512_add_pd(norm2, _mm512_mul_pd(d1, d1));
  }
  if constexpr (D > 2) {
    dot = _mm512_add_pd(dot, _mm512_mul_pd(d2, _mm512_set1_pd(c.axis[2])));
    norm2 = _mm512_add_pd(norm2, _mm512_mul_pd(d2, d2));
  }
  const __m512d k = _mm512_set1_pd(c.cos_tol * c.cos_tol);
  return _mm512_mask_cmp_pd_mask(lanes, _mm512_mul_pd(dot, dot), _mm512_mul_pd(k, norm2), _CMP_GE_OQ);
}

/// AVX-512 kernel: the baseline's pairs, stream and sums, 8 candidates per step.
template <PairStatistic S, bool Gstat, int D>
ERRFIELD_KERNELS_NO_FP_CONTRACT __attribute__((target("avx512f"))) void bin_column_pairs_avx512(
    const SortedColumns& g, const BinLayout& bins, std::size_t p_begin, std::size_t p_end,
    double* slots, PairSums out) noexcept {
  ERRFIELD_KERNELS_NO_FP_CONTRACT_BODY
  constexpr std::size_t kBuffer = 256;  // pairs in range buffered before binning
  const std::size_t B = bins.bins + 1;
  const std::size_t n = g.n;
  for (std::size_t k = 0; k < column_slot_doubles(bins.bins); ++k) slots[k] = 0.0;
  const double pre = g.cutoff * g.cutoff * (1.0 + 1e-12);
  const __m512d vpre = _mm512_set1_pd(pre);
  alignas(64) double h2s[kBuffer + 8] = {};
  alignas(64) double dzs[kBuffer + 8] = {};
  std::size_t buffered = 0;  // always < kBuffer between steps; starts at a multiple of 8 of the stream
  ColumnRun runs[kColumnMaxRuns];
  ColumnSweep sweep;
  const double* x0 = g.coordinates;
  const double* x1 = g.coordinates + (D > 1 ? n : 0);
  const double* x2 = g.coordinates + (D > 2 ? 2 * n : 0);
  const DirectionCone* cone = g.cone;
  std::size_t column = p_begin < p_end ? column_of_position(g, p_begin) : 0;
  for (std::size_t p = p_begin; p < p_end; ++p) {
    while (g.column_start[column + 1] <= p) ++column;
    if (column != sweep.column) sweep.start(g, column);
    const std::size_t m = column_runs(g, p, sweep, runs);
    const __m512d vx0 = _mm512_set1_pd(x0[p]);
    const __m512d vx1 = _mm512_set1_pd(x1[p]);
    const __m512d vx2 = _mm512_set1_pd(x2[p]);
    const __m512d vv = _mm512_set1_pd(g.values[p]);
    for (std::size_t r = 0; r < m; ++r) {
      const std::size_t hi = runs[r].hi;
      for (std::size_t q = runs[r].lo; q < hi; q += 8) {
        const __mmask8 lanes = hi - q >= 8 ? __mmask8{0xFF} : static_cast<__mmask8>((1u << (hi - q)) - 1u);
        const __m512d d0 = _mm512_sub_pd(vx0, _mm512_maskz_loadu_pd(lanes, x0 + q));
        __m512d d1 = _mm512_setzero_pd(), d2 = _mm512_setzero_pd();
        __m512d h2 = _mm512_mul_pd(d0, d0);
        if constexpr (D > 1) {
          d1 = _mm512_sub_pd(vx1, _mm512_maskz_loadu_pd(lanes, x1 + q));
          h2 = _mm512_add_pd(h2, _mm512_mul_pd(d1, d1));
        }
        if constexpr (D > 2) {
          d2 = _mm512_sub_pd(vx2, _mm512_maskz_loadu_pd(lanes, x2 + q));
          h2 = _mm512_add_pd(h2, _mm512_mul_pd(d2, d2));
        }
        // No branch on `keep`: about half the steps keep nothing, unpredictably; storing 0 lanes
        // costs less than the mispredictions.
        __mmask8 keep = _mm512_mask_cmp_pd_mask(lanes, h2, vpre, _CMP_LE_OQ);
        if (cone != nullptr) keep = cone_mask_avx512<D>(*cone, d0, d1, d2, keep);
        const __m512d dz = _mm512_sub_pd(vv, _mm512_maskz_loadu_pd(keep, g.values + q));
        // Register-form compress then a plain store (the memory form is slow on some CPUs).
        _mm512_storeu_pd(h2s + buffered, _mm512_maskz_compress_pd(keep, h2));
        _mm512_storeu_pd(dzs + buffered, _mm512_maskz_compress_pd(keep, dz));
        buffered += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(keep)));
        if (buffered >= kBuffer - 8) {
          const std::size_t groups = buffered / 8;
          drain_column_pairs_avx512<S, Gstat>(h2s, dzs, groups, slots, B, bins);
          const std::size_t rest = buffered - 8 * groups;
          for (std::size_t t = 0; t < rest; ++t) {
            h2s[t] = h2s[8 * groups + t];
            dzs[t] = dzs[8 * groups + t];
          }
          buffered = rest;
        }
      }
    }
  }
  const std::size_t groups = buffered / 8;
  drain_column_pairs_avx512<S, Gstat>(h2s, dzs, groups, slots, B, bins);
  for (std::size_t t = 8 * groups; t < buffered; ++t)
    add_column_pair<S>(slots, B, bins, t, h2s[t], dzs[t]);  // t mod 4 = the stream's index mod 4
  flush_column_slots(slots, B, out);
}

#endif  // ERRFIELD_KERNELS_HAVE_X86_SIMD

}  // namespace detail

/// Adds the pairs of rows [p_begin, p_end) (positions in g's order) with their half stencil to
/// `out` (bins + 1 slots per array, the last a discard slot for lags outside every bin).
/// `slots`: column_slot_doubles(bins.bins) doubles of workspace. `bins` must be uniform;
/// D = g.dimension (1..3). `isa` must be supported by the CPU (kernel_isa_supported); AVX-512
/// runs 8 candidates per step, anything else the portable loop: the same sums bit for bit.
template <PairStatistic S, int D>
void bin_column_pairs(KernelIsa isa, const SortedColumns& g, const BinLayout& bins,
                      std::size_t p_begin, std::size_t p_end, double* slots,
                      PairSums out) noexcept {
  static_assert(D >= 1 && D <= 3);
#if ERRFIELD_KERNELS_HAVE_X86_SIMD
  if (isa == KernelIsa::Avx512) {
    if (bins.gstat) detail::bin_column_pairs_avx512<S, true, D>(g, bins, p_begin, p_end, slots, out);
    else detail::bin_column_pairs_avx512<S, false, D>(g, bins, p_begin, p_end, slots, out);
    return;
  }
#else
  (void)isa;
#endif
  detail::bin_column_pairs_baseline<S, D>(g, bins, p_begin, p_end, slots, out);
}

}  // namespace errfield::kernels
