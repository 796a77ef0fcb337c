#pragma once
/// Cell-list enumeration of the empirical variogram's pairs: visits only the pairs (i, j), j < i,
/// that can have a lag within the largest bin edge (the cutoff), in exactly the order of the
/// all-pairs loop (pair_binning.hpp) - i ascending, then j ascending - so that every bin's sums
/// receive the same terms in the same order and come out bit-identical.
///
/// How: the points are sorted into a uniform grid over at most three coordinate axes whose cell
/// side is at least the largest coordinate difference a pair within the cutoff can have on that
/// axis (so a pair in range lies in the same or an adjacent cell on every gridded axis); within a
/// cell the points keep their original order. For row i the candidates are the points of the
/// 3^g neighbouring cells with an original index below i (a prefix of each cell, found by binary
/// search). Their lags are computed in blocks from a cell-ordered copy of the coordinates, with the
/// arithmetic of the all-pairs loop (same lag, bit for bit); the ones within the cutoff are marked
/// in a two-level bitmap over the original index j, and the bitmap is then read in ascending j:
/// a counting sort, O(candidates + N / 4096) per row.
///
/// Plain pointers in; the caller owns the grid (CellList) and one CellListScratch per thread. No
/// allocation, no checks, no exceptions inside.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pair_binning.hpp"
#include "pair_direction.hpp"

namespace errfield::kernels {

/// Most axes a cell list grids (the others are left to the lag test).
inline constexpr int kCellListMaxAxes = 3;
/// Most cells per bound (CellList::reach).
inline constexpr std::size_t kCellListMaxReach = 4;

/// A uniform grid over `axes` coordinate axes of n points (built by the caller).
struct CellList {
  std::size_t n = 0;
  int dimension = 0;                   ///< D: axes of `coordinates`
  const double* coordinates = nullptr;  ///< cell-ordered, axis-major: coordinates[a * n + p]
  const std::uint32_t* point = nullptr;     ///< original index of cell-ordered position p
  const std::uint32_t* position = nullptr;  ///< cell-ordered position of original point i
  const std::uint32_t* cell_of = nullptr;   ///< cell of original point i
  const std::uint32_t* cell_start = nullptr;  ///< first position of each cell; cells + 1 entries
  int axes = 0;                                    ///< gridded axes, 1..kCellListMaxAxes
  std::size_t cells_per_axis[kCellListMaxAxes] = {1, 1, 1};
  std::size_t stride[kCellListMaxAxes] = {1, 1, 1};  ///< cell = sum_a index_a * stride[a]
  /// Cells per bound: a pair within the cutoff is at most `reach` cells apart on a gridded axis.
  std::size_t reach = 1;
  int axis[kCellListMaxAxes] = {0, 0, 0};            ///< coordinate of each gridded axis
  double origin[kCellListMaxAxes] = {0.0, 0.0, 0.0};  ///< lower edge of cell 0
  double side[kCellListMaxAxes] = {1.0, 1.0, 1.0};    ///< cell width, >= bound / reach
  /// 1 / the largest difference on the axis of a pair within the cutoff (the cell list skips a
  /// cell when sum_a (gap_a * inv_bound_a)^2 > 1 for the gaps between a point and the cell).
  double inv_bound[kCellListMaxAxes] = {0.0, 0.0, 0.0};
};

/// Per-thread workspace: `lag_of` has n entries, `bits` ceil(n / 64), `summary` ceil(n / 4096),
/// the two bitmaps zeroed before the first row (the kernel leaves them zeroed).
struct CellListScratch {
  double* lag_of = nullptr;
  std::uint64_t* bits = nullptr;
  std::uint64_t* summary = nullptr;
};

/// Squared Euclidean lags of the point at cell-ordered position pi against positions
/// [p0, p0 + m), m <= kLagBlock: the axis order and operations of bin_pair_rows_euclidean, whose
/// lag is the correctly rounded square root of exactly this sum. D_FIXED > 0 fixes the number of
/// axes, otherwise cells.dimension.
template <int D_FIXED>
void cell_squared_euclidean_lags(const CellList& cells, std::size_t pi, std::size_t p0,
                                 std::size_t m, double* h2) noexcept {
  const std::size_t D = static_cast<std::size_t>(D_FIXED > 0 ? D_FIXED : cells.dimension);
  const std::size_t n = cells.n;
  {
    const double* x = cells.coordinates + p0;
    const double x0 = cells.coordinates[pi];
    for (std::size_t t = 0; t < m; ++t) {
      const double d = x0 - x[t];
      h2[t] = d * d;
    }
  }
  for (std::size_t a = 1; a < D; ++a) {
    const double* x = cells.coordinates + a * n + p0;
    const double xa = cells.coordinates[a * n + pi];
    for (std::size_t t = 0; t < m; ++t) {
      const double d = xa - x[t];
      h2[t] += d * d;
    }
  }
}

/// Calls visit(i, j, h, m) with batches (at most kLagBlock pairs, j and h arrays) of the pairs
/// (i, j), j < i, of rows [row_begin, row_end) whose lag h is <= cutoff and that the cone keeps
/// (null: no cone; its coordinates must be the cell-ordered copy), in ascending (i, j) over all
/// batches. `lags(i, pi, p0, m, out)` gives row i (at cell-ordered position pi) against positions
/// [p0, p0 + m): with Squared, squared Euclidean lags h^2 (cell_squared_euclidean_lags), whose
/// correctly rounded square root is the lag; otherwise the lags themselves (any metric).
/// Every pair with h <= cutoff is visited provided the grid's cells are at least as wide as the
/// largest per-axis difference of such a pair.
template <bool Squared, class Lags, class Visit>
void for_each_pair_in_cells(const CellList& g, std::size_t row_begin, std::size_t row_end,
                            double cutoff, const DirectionCone* cone, const Lags& lags,
                            CellListScratch scratch, Visit&& visit) noexcept {
  constexpr std::size_t kBlock = detail::kLagBlock;
  alignas(64) double key[kBlock];
  alignas(64) double kept_key[kBlock];
  alignas(64) std::uint32_t kept_j[kBlock];
  alignas(64) double batch_h[kBlock];
  alignas(64) std::uint32_t batch_j[kBlock];
  // A pre-filter on the squared lag that keeps every pair whose rounded square root is <= cutoff
  // (sqrt is monotonic and correctly rounded; 1e-12 covers the rounding of cutoff^2 many times
  // over); the exact test follows on the square root.
  const double pre = Squared ? cutoff * cutoff * (1.0 + 1e-12) : cutoff;
  const int axes = g.axes;
  for (std::size_t i = row_begin; i < row_end; ++i) {
    const std::size_t pi = g.position[i];
    const std::size_t ci = g.cell_of[i];
    std::size_t index[kCellListMaxAxes] = {0, 0, 0};
    {
      std::size_t rest = ci;
      for (int a = axes - 1; a >= 0; --a) {
        index[a] = rest / g.stride[a];
        rest -= index[a] * g.stride[a];
      }
    }
    // Cells within `reach` on each axis whose box can hold a point within the bound of point i:
    // gap2[a][c - lo[a]] = (gap between x_i and cell c on axis a, in bounds)^2, the gap shortened
    // by a millionth of a cell so that rounding in the cell assignment cannot drop a pair.
    std::size_t lo[kCellListMaxAxes] = {0, 0, 0}, hi[kCellListMaxAxes] = {0, 0, 0};
    double gap2[kCellListMaxAxes][2 * kCellListMaxReach + 1] = {};
    for (int a = 0; a < axes; ++a) {
      lo[a] = index[a] > g.reach ? index[a] - g.reach : 0;
      hi[a] = index[a] + g.reach < g.cells_per_axis[a] ? index[a] + g.reach : g.cells_per_axis[a] - 1;
      const double x = g.coordinates[static_cast<std::size_t>(g.axis[a]) * g.n + pi];
      const double slack = 1e-6 * g.side[a];
      for (std::size_t c = lo[a]; c <= hi[a]; ++c) {
        const double below = g.origin[a] + static_cast<double>(c) * g.side[a];
        double gap = c < index[a] ? x - (below + g.side[a]) : c > index[a] ? below - x : 0.0;
        gap = gap > slack ? (gap - slack) * g.inv_bound[a] : 0.0;
        gap2[a][c - lo[a]] = gap * gap;
      }
    }
    constexpr double kReachable = 1.0 + 1e-9;  // rounding of the sum of squares, far over
    std::uint32_t largest = 0;  // largest marked j, to bound the bitmap scan
    bool any = false;
    for (std::size_t c2 = lo[2]; c2 <= hi[2]; ++c2)
      for (std::size_t c1 = lo[1]; c1 <= hi[1]; ++c1) {
        const double g21 = gap2[2][c2 - lo[2]] + gap2[1][c1 - lo[1]];
        if (!(g21 <= kReachable)) continue;
        for (std::size_t c0 = lo[0]; c0 <= hi[0]; ++c0) {
          if (!(g21 + gap2[0][c0 - lo[0]] <= kReachable)) continue;
          const std::size_t cell = c0 * g.stride[0] + c1 * g.stride[1] + c2 * g.stride[2];
          const std::uint32_t* first = g.point + g.cell_start[cell];
          const std::uint32_t* last = g.point + g.cell_start[cell + 1];
          // Points of the cell with an original index below i: a prefix (ascending within a cell).
          const std::size_t end = static_cast<std::size_t>(
              std::lower_bound(first, last, static_cast<std::uint32_t>(i)) - g.point);
          for (std::size_t p0 = static_cast<std::size_t>(first - g.point); p0 < end; p0 += kBlock) {
            const std::size_t m = end - p0 < kBlock ? end - p0 : kBlock;
            lags(i, pi, p0, m, key);
            if (cone != nullptr) mask_directions(*cone, pi, p0, m, key);  // NaN: rejected
            std::size_t kept = 0;  // branch-free compaction: most candidates are out of range
            for (std::size_t t = 0; t < m; ++t) {
              kept_j[kept] = g.point[p0 + t];
              kept_key[kept] = key[t];
              kept += key[t] <= pre ? 1 : 0;
            }
            for (std::size_t t = 0; t < kept; ++t) {
              const double h = Squared ? std::sqrt(kept_key[t]) : kept_key[t];
              if (!(h <= cutoff)) continue;
              const std::uint32_t j = kept_j[t];
              scratch.lag_of[j] = h;
              scratch.bits[j >> 6] |= std::uint64_t{1} << (j & 63);
              scratch.summary[j >> 12] |= std::uint64_t{1} << ((j >> 6) & 63);
              largest = j > largest ? j : largest;
              any = true;
            }
          }
        }
      }
    if (!any) continue;
    // Read the marks in ascending j, clearing them for the next row.
    std::size_t m = 0;
    for (std::size_t s = 0; s <= (largest >> 12); ++s) {
      std::uint64_t words = scratch.summary[s];
      scratch.summary[s] = 0;
      while (words != 0) {
        const std::size_t w = (s << 6) + static_cast<std::size_t>(std::countr_zero(words));
        words &= words - 1;
        std::uint64_t b = scratch.bits[w];
        scratch.bits[w] = 0;
        while (b != 0) {
          const std::size_t j = (w << 6) + static_cast<std::size_t>(std::countr_zero(b));
          b &= b - 1;
          batch_j[m] = static_cast<std::uint32_t>(j);
          batch_h[m] = scratch.lag_of[j];
          if (++m == kBlock) {
            visit(i, batch_j, batch_h, m);
            m = 0;
          }
        }
      }
    }
    if (m > 0) visit(i, batch_j, batch_h, m);
  }
}

/// Adds a batch of pairs (i, j[t]) with lags h[t], t < m <= kLagBlock, to `out` as
/// accumulate_lags does for a block of contiguous j (same bin rule, same order, same arithmetic;
/// the last slot of out's arrays collects lags outside every bin). `values` is row-major N x K.
template <PairStatistic S, bool Subsample, int K_FIXED>
void accumulate_pair_batch(std::size_t i, const std::uint32_t* j, const double* h, std::size_t m,
                           const double* values, int components, const BinLayout& bins,
                           std::uint64_t seed, std::uint64_t keep_below, PairSums out) noexcept {
  const std::size_t K = static_cast<std::size_t>(K_FIXED > 0 ? K_FIXED : components);
  alignas(64) std::int32_t code[detail::kLagBlock];
  if (bins.uniform) {
    if (bins.gstat) detail::bin_codes<true>(h, code, m, bins);
    else detail::bin_codes<false>(h, code, m, bins);
  } else {
    for (std::size_t t = 0; t < m; ++t) code[t] = -1;
  }
  const double* zi = values + i * K;
  for (std::size_t t = 0; t < m; ++t) {
    if constexpr (Subsample) {
      if (pair_hash(seed, i, j[t]) >= keep_below) continue;
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
    detail::add_pair_statistics<S>(zi, values + static_cast<std::size_t>(j[t]) * K, K,
                                   out.stat + kb * pair_statistic_width(S, K));
  }
}

}  // namespace errfield::kernels
