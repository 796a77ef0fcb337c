#pragma once
/// Hot loops of the exact likelihood (kriging/likelihood_profile.cpp): the Cholesky factor of an
/// N x N correlation matrix and, for the gradient, its inverse from blocks of triangular solves and
/// products. They are nearly all of a REML fit's time (at 1,941 samples, 0.55 s per evaluation and
/// 21-24 evaluations per model). The default build targets plain x86-64, where Eigen's matrix
/// products run at SSE2 speed; these functions run Eigen's own algorithms compiled for AVX2 + FMA
/// (kernels/dense_cholesky_avx2.cpp) when the CPU has them, and the plain build's otherwise. Each
/// call is single-threaded and the same computation whatever the number of threads calling it.
/// Matrices are column-major with a leading dimension.

#include <cstddef>

namespace errfield::kernels {

/// True when the AVX2 + FMA versions run on this CPU.
bool dense_avx2_available();

/// A = L Lᵀ in place: the lower triangle of the n x n matrix `a` (leading dimension lda) is read
/// and overwritten by L; the strict upper triangle is left as it was. False when A is not positive
/// definite (a pivot that is not positive; `a` is then partly overwritten).
bool cholesky_lower_in_place(double* a, std::size_t n, std::size_t lda);

/// X := L⁻¹ X, with L the lower triangle of the m x m matrix `l` (leading dimension ldl) and X
/// m x k (leading dimension ldx).
void lower_solve_in_place(const double* l, std::size_t ldl, std::size_t m, double* x, std::size_t ldx, std::size_t k);

/// C := Lᵀ B, with L the lower triangle of the m x m matrix `l` (leading dimension ldl; the strict
/// upper triangle is not read), B m x nc (ldb) and C m x nc (ldc): the triangular product, half the
/// flops of a general one.
void lower_transposed_product(const double* l, std::size_t ldl, std::size_t m, const double* b, std::size_t ldb,
                              std::size_t nc, double* c, std::size_t ldc);

/// The three functions of one build, for tests and benchmarks that compare the builds.
struct DenseKernels {
  bool (*cholesky_lower_in_place)(double* a, std::size_t n, std::size_t lda);
  void (*lower_solve_in_place)(const double* l, std::size_t ldl, std::size_t m, double* x, std::size_t ldx, std::size_t k);
  void (*lower_transposed_product)(const double* l, std::size_t ldl, std::size_t m, const double* b, std::size_t ldb,
                                   std::size_t nc, double* c, std::size_t ldc);
};
/// The plain build's functions (what runs on every CPU).
const DenseKernels& plain_dense_kernels();
/// The AVX2 + FMA build's functions; null where that build was not compiled (CMakeLists.txt says
/// when) or the CPU lacks AVX2 or FMA.
const DenseKernels* avx2_dense_kernels();

}  // namespace errfield::kernels
