// Blocked forward substitution with many right-hand sides (kernels/lower_triangular_solve.hpp).
//
// Rows are processed in blocks of kRowBlock: the block's rows first receive the update
// B_I -= L_{I,0:I} B_{0:I} (a GEMM, ~all of the flops) through an 8 x 4 register tile of 256-bit
// vectors reading L from 8-row packed tiles, then a small triangular solve with the diagonal block.
// The tiled solve is compiled for AVX2 + FMA only (function target attribute) and chosen at run
// time when the CPU has both, so the library stays portable (plain x86-64 build) while this loop
// runs at AVX2/FMA speed. Without them, lower_solve falls back to the naive reference.

#include "lower_triangular_solve.hpp"

#include <algorithm>

namespace errfield::kernels {
namespace {

typedef double v4d __attribute__((vector_size(32), aligned(8)));

constexpr std::size_t kRowBlock = 64;
constexpr std::size_t kTile = 8;

// k_end of the tile starting at row r: the first row of its row block.
inline std::size_t tile_k_end(std::size_t r) { return r / kRowBlock * kRowBlock; }

}  // namespace

PackedLower pack_lower(const double* l, std::size_t ldl, std::size_t n) {
  PackedLower p;
  p.l = l;
  p.ldl = ldl;
  p.n = n;
  std::size_t total = 0;
  for (std::size_t r = 0; r + kTile <= n; r += kTile) {
    p.offset.push_back(total);
    total += kTile * tile_k_end(r);
  }
  p.tiles.resize(total);
  std::size_t t = 0;
  for (std::size_t r = 0; r + kTile <= n; r += kTile, ++t) {
    double* dst = p.tiles.data() + p.offset[t];
    for (std::size_t k = 0; k < tile_k_end(r); ++k)
      for (std::size_t i = 0; i < kTile; ++i) dst[k * kTile + i] = l[(r + i) + k * ldl];
  }
  return p;
}

// Unaligned vector access through the 8-byte-aligned vector type (GCC vector types alias their
// element type). Macros rather than functions: a helper without the clone's target would not be
// inlined into the AVX2 clone and would pass vectors through memory.
#define ERRFIELD_LOAD4(p) (*reinterpret_cast<const v4d*>(p))
#define ERRFIELD_STORE4(p, v) (*reinterpret_cast<v4d*>(p) = (v))

namespace {

__attribute__((target("avx2,fma")))
void lower_solve_fma(const PackedLower& pl, double* b, std::size_t ldb, std::size_t nrhs) {
  const double* l = pl.l;
  const std::size_t ldl = pl.ldl, n = pl.n;
  for (std::size_t i0 = 0; i0 < n; i0 += kRowBlock) {
    const std::size_t rows = std::min(kRowBlock, n - i0);
    const std::size_t k_end = i0;  // columns 0..i0-1 of L feed the update
    if (k_end > 0) {
      std::size_t i = 0;
      for (; i + kTile <= rows; i += kTile) {
        const double* a = pl.tiles.data() + pl.offset[(i0 + i) / kTile];  // a[k * 8 + r]
        std::size_t j = 0;
        for (; j + 4 <= nrhs; j += 4) {
          const double* b0 = b + j * ldb;
          const double* b1 = b0 + ldb;
          const double* b2 = b1 + ldb;
          const double* b3 = b2 + ldb;
          v4d c00 = {0, 0, 0, 0}, c01 = c00, c10 = c00, c11 = c00, c20 = c00, c21 = c00, c30 = c00, c31 = c00;
          for (std::size_t k = 0; k < k_end; ++k) {
            const v4d a0 = ERRFIELD_LOAD4(a + k * kTile);
            const v4d a1 = ERRFIELD_LOAD4(a + k * kTile + 4);
            const double x0 = b0[k], x1 = b1[k], x2 = b2[k], x3 = b3[k];
            c00 += a0 * x0;
            c01 += a1 * x0;
            c10 += a0 * x1;
            c11 += a1 * x1;
            c20 += a0 * x2;
            c21 += a1 * x2;
            c30 += a0 * x3;
            c31 += a1 * x3;
          }
          double* d0 = b + j * ldb + i0 + i;
          ERRFIELD_STORE4(d0, ERRFIELD_LOAD4(d0) - c00);
          ERRFIELD_STORE4(d0 + 4, ERRFIELD_LOAD4(d0 + 4) - c01);
          ERRFIELD_STORE4(d0 + ldb, ERRFIELD_LOAD4(d0 + ldb) - c10);
          ERRFIELD_STORE4(d0 + ldb + 4, ERRFIELD_LOAD4(d0 + ldb + 4) - c11);
          ERRFIELD_STORE4(d0 + 2 * ldb, ERRFIELD_LOAD4(d0 + 2 * ldb) - c20);
          ERRFIELD_STORE4(d0 + 2 * ldb + 4, ERRFIELD_LOAD4(d0 + 2 * ldb + 4) - c21);
          ERRFIELD_STORE4(d0 + 3 * ldb, ERRFIELD_LOAD4(d0 + 3 * ldb) - c30);
          ERRFIELD_STORE4(d0 + 3 * ldb + 4, ERRFIELD_LOAD4(d0 + 3 * ldb + 4) - c31);
        }
        for (; j < nrhs; ++j) {  // leftover right-hand sides
          const double* bj = b + j * ldb;
          v4d c0 = {0, 0, 0, 0}, c1 = c0;
          for (std::size_t k = 0; k < k_end; ++k) {
            c0 += ERRFIELD_LOAD4(a + k * kTile) * bj[k];
            c1 += ERRFIELD_LOAD4(a + k * kTile + 4) * bj[k];
          }
          double* d0 = b + j * ldb + i0 + i;
          ERRFIELD_STORE4(d0, ERRFIELD_LOAD4(d0) - c0);
          ERRFIELD_STORE4(d0 + 4, ERRFIELD_LOAD4(d0 + 4) - c1);
        }
      }
      for (; i < rows; ++i)  // leftover rows (only in the last, partial tile)
        for (std::size_t j = 0; j < nrhs; ++j) {
          const double* bj = b + j * ldb;
          double s = 0.0;
          for (std::size_t k = 0; k < k_end; ++k) s += l[i0 + i + k * ldl] * bj[k];
          b[j * ldb + i0 + i] -= s;
        }
    }
    // diagonal block
    for (std::size_t j = 0; j < nrhs; ++j) {
      double* x = b + j * ldb + i0;
      for (std::size_t r = 0; r < rows; ++r) {
        double s = x[r];
        for (std::size_t k = 0; k < r; ++k) s -= l[(i0 + r) + (i0 + k) * ldl] * x[k];
        x[r] = s / l[(i0 + r) + (i0 + r) * ldl];
      }
    }
  }
}

#undef ERRFIELD_LOAD4
#undef ERRFIELD_STORE4

}  // namespace

bool lower_solve_fast_available() {
  static const bool available = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return available;
}

void lower_solve(const PackedLower& pl, double* b, std::size_t ldb, std::size_t nrhs) {
  if (lower_solve_fast_available()) lower_solve_fma(pl, b, ldb, nrhs);
  else lower_solve_reference(pl.l, pl.ldl, pl.n, b, ldb, nrhs);
}

}  // namespace errfield::kernels
