#pragma once
/// Hot loop of dense kriging variances: B := L^-1 B for a lower-triangular L (n x n) and many
/// right-hand sides (one per target), both column-major. The compiled version
/// (kernels/lower_triangular_solve.cpp) is blocked and register-tiled, reads the off-diagonal
/// part of L from a copy packed once into 8-row tiles (so the inner loop streams contiguous memory),
/// and is compiled for AVX2/FMA and chosen at run time when the CPU has them: the default build
/// targets plain x86-64, where Eigen's own solve runs at SSE2 speed. `lower_solve_reference` is the
/// naive version it is tested against.

#include <cstddef>
#include <vector>

namespace errfield::kernels {

/// L prepared for lower_solve: refers to L (which must outlive it and stay unchanged) and holds
/// a packed copy of its off-diagonal blocks (~n^2/2 doubles).
struct PackedLower {
  const double* l = nullptr;
  std::size_t ldl = 0;
  std::size_t n = 0;
  std::vector<double> tiles;        // per 8-row tile t: k = 0..k_end(t)-1, 8 values each
  std::vector<std::size_t> offset;  // start of tile t in `tiles`
};

/// Packs L (n x n lower triangular, leading dimension ldl >= n, non-zero diagonal). O(n^2).
PackedLower pack_lower(const double* l, std::size_t ldl, std::size_t n);

/// Whether the CPU runs the AVX2/FMA version (otherwise lower_solve is the naive reference and
/// callers with a faster fallback, e.g. Eigen's solve, should use that).
bool lower_solve_fast_available();

/// B := L^-1 B for B n x nrhs with leading dimension ldb >= n. O(n^2 nrhs); no allocation;
/// thread-safe for distinct B.
void lower_solve(const PackedLower& l, double* b, std::size_t ldb, std::size_t nrhs);

/// Naive column-by-column forward substitution; the reference for lower_solve.
inline void lower_solve_reference(const double* l, std::size_t ldl, std::size_t n, double* b, std::size_t ldb,
                                  std::size_t nrhs) {
  for (std::size_t j = 0; j < nrhs; ++j) {
    double* x = b + j * ldb;
    for (std::size_t i = 0; i < n; ++i) {
      double s = x[i];
      for (std::size_t k = 0; k < i; ++k) s -= l[i + k * ldl] * x[k];
      x[i] = s / l[i + i * ldl];
    }
  }
}

}  // namespace errfield::kernels
