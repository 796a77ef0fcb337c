#include "dense_cholesky.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace errfield::kernels {

namespace detail::plain {
#include "dense_cholesky_eigen.inc"
}  // namespace detail::plain

#if defined(ERRFIELD_DENSE_AVX2)
namespace detail::avx2 {  // kernels/dense_cholesky_avx2.cpp
bool cholesky_lower_in_place(double* a, std::size_t n, std::size_t lda);
void lower_solve_in_place(const double* l, std::size_t ldl, std::size_t m, double* x, std::size_t ldx, std::size_t k);
void lower_transposed_product(const double* l, std::size_t ldl, std::size_t m, const double* b, std::size_t ldb,
                              std::size_t nc, double* c, std::size_t ldc);
}  // namespace detail::avx2
#endif

const DenseKernels& plain_dense_kernels() {
  static const DenseKernels k{detail::plain::cholesky_lower_in_place, detail::plain::lower_solve_in_place,
                              detail::plain::lower_transposed_product};
  return k;
}

const DenseKernels* avx2_dense_kernels() {
#if defined(ERRFIELD_DENSE_AVX2)
  static const DenseKernels k{detail::avx2::cholesky_lower_in_place, detail::avx2::lower_solve_in_place,
                              detail::avx2::lower_transposed_product};
  static const bool available = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return available ? &k : nullptr;
#else
  return nullptr;
#endif
}

bool dense_avx2_available() { return avx2_dense_kernels() != nullptr; }

namespace {
const DenseKernels& chosen() {
  static const DenseKernels& k = avx2_dense_kernels() ? *avx2_dense_kernels() : plain_dense_kernels();
  return k;
}
}  // namespace

bool cholesky_lower_in_place(double* a, std::size_t n, std::size_t lda) {
  return chosen().cholesky_lower_in_place(a, n, lda);
}

void lower_solve_in_place(const double* l, std::size_t ldl, std::size_t m, double* x, std::size_t ldx, std::size_t k) {
  chosen().lower_solve_in_place(l, ldl, m, x, ldx, k);
}

void lower_transposed_product(const double* l, std::size_t ldl, std::size_t m, const double* b, std::size_t ldb,
                              std::size_t nc, double* c, std::size_t ldc) {
  chosen().lower_transposed_product(l, ldl, m, b, ldb, nc, c, ldc);
}

}  // namespace errfield::kernels
