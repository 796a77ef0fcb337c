// The likelihood's dense kernels (kernels/dense_cholesky.hpp), the plain build and the AVX2 + FMA one
// where the CPU has it, against textbook loops written here: the Cholesky recurrence, forward
// substitution and the loops of a triangular product, on strided matrices of sizes around Eigen's blocks.

#include "dense_cholesky.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace errfield {
namespace dense_cholesky_test {

struct Build {
  const char* name;
  bool (*cholesky)(double*, std::size_t, std::size_t);
  void (*solve)(const double*, std::size_t, std::size_t, double*, std::size_t, std::size_t);
  void (*product)(const double*, std::size_t, std::size_t, const double*, std::size_t, std::size_t, double*, std::size_t);
};

std::vector<Build> builds() {
  const kernels::DenseKernels& plain = kernels::plain_dense_kernels();
  std::vector<Build> b = {{"plain", plain.cholesky_lower_in_place, plain.lower_solve_in_place, plain.lower_transposed_product},
                          {"dispatched", kernels::cholesky_lower_in_place, kernels::lower_solve_in_place,
                           kernels::lower_transposed_product}};
  if (const kernels::DenseKernels* avx2 = kernels::avx2_dense_kernels())
    b.push_back({"avx2", avx2->cholesky_lower_in_place, avx2->lower_solve_in_place, avx2->lower_transposed_product});
  return b;
}

// A symmetric positive definite n x n matrix (leading dimension lda): G Gᵀ / n + I.
std::vector<double> spd(std::size_t n, std::size_t lda, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> g(n * n), a(lda * n, 7.0);  // 7.0: padding a kernel must not read as data
  for (double& x : g) x = u(rng);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t i = 0; i < n; ++i) {
      double s = i == j ? 1.0 : 0.0;
      for (std::size_t k = 0; k < n; ++k) s += g[i + k * n] * g[j + k * n] / static_cast<double>(n);
      a[i + j * lda] = s;
    }
  return a;
}

TEST(DenseCholesky, FactorEqualsTheCholeskyRecurrenceAndLeavesTheUpperTriangle) {
  std::mt19937 rng(11);
  for (const Build& b : builds())
    for (std::size_t n : {1u, 5u, 47u, 48u, 49u, 130u, 257u}) {
      const std::size_t lda = n + 2;
      const std::vector<double> a = spd(n, lda, rng);
      std::vector<double> ref(n * n, 0.0), got = a;
      for (std::size_t j = 0; j < n; ++j) {
        double d = a[j + j * lda];
        for (std::size_t k = 0; k < j; ++k) d -= ref[j + k * n] * ref[j + k * n];
        ref[j + j * n] = std::sqrt(d);
        for (std::size_t i = j + 1; i < n; ++i) {
          double s = a[i + j * lda];
          for (std::size_t k = 0; k < j; ++k) s -= ref[i + k * n] * ref[j + k * n];
          ref[i + j * n] = s / ref[j + j * n];
        }
      }
      ASSERT_TRUE(b.cholesky(got.data(), n, lda)) << b.name << " n " << n;
      for (std::size_t j = 0; j < n; ++j)
        for (std::size_t i = 0; i < lda; ++i) {
          if (i >= n || i < j) {
            EXPECT_EQ(got[i + j * lda], a[i + j * lda]) << b.name << " n " << n << " untouched at " << i << "," << j;
          } else {
            EXPECT_NEAR(got[i + j * lda], ref[i + j * n], 1e-12 * static_cast<double>(n)) << b.name << " n " << n;
          }
        }
    }
}

TEST(DenseCholesky, RefusesAMatrixThatIsNotPositiveDefinite) {
  for (const Build& b : builds()) {
    std::vector<double> a = {1.0, 2.0, 2.0, 1.0};  // eigenvalues 3 and -1
    EXPECT_FALSE(b.cholesky(a.data(), 2, 2)) << b.name;
  }
}

TEST(DenseCholesky, SolveAndTriangularProductEqualTheirLoops) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Build& b : builds())
    for (std::size_t m : {1u, 9u, 64u, 131u})
      for (std::size_t k : {1u, 3u, 64u}) {
        const std::size_t ldl = m + 1, ldx = m + 3;
        std::vector<double> l(ldl * m), x(ldx * k);
        for (double& v : l) v = u(rng) / std::sqrt(static_cast<double>(m));
        for (std::size_t i = 0; i < m; ++i) l[i + i * ldl] = 1.0 + std::abs(u(rng));
        for (double& v : x) v = u(rng);
        std::vector<double> ref = x, got = x;
        for (std::size_t c = 0; c < k; ++c)
          for (std::size_t i = 0; i < m; ++i) {
            double s = ref[i + c * ldx];
            for (std::size_t j = 0; j < i; ++j) s -= l[i + j * ldl] * ref[j + c * ldx];
            ref[i + c * ldx] = s / l[i + i * ldl];
          }
        b.solve(l.data(), ldl, m, got.data(), ldx, k);
        for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], ref[i], 1e-12 * static_cast<double>(m)) << b.name;

        // C (m x k) = Lᵀ B with L the lower triangle of `l` (its upper triangle is not read)
        std::vector<double> lu = l;
        for (std::size_t j = 0; j < m; ++j)
          for (std::size_t i = 0; i < j; ++i) lu[i + j * ldl] = 1e300;
        const std::size_t ldb = m + 2, ldc = m + 4;
        std::vector<double> bb(ldb * k), c(ldc * k, 5.0);
        for (double& v : bb) v = u(rng);
        b.product(lu.data(), ldl, m, bb.data(), ldb, k, c.data(), ldc);
        for (std::size_t j = 0; j < k; ++j)
          for (std::size_t i = 0; i < ldc; ++i) {
            if (i >= m) {
              EXPECT_EQ(c[i + j * ldc], 5.0) << b.name << " padding";
              continue;
            }
            double s = 0.0;
            for (std::size_t r = i; r < m; ++r) s += l[r + i * ldl] * bb[r + j * ldb];
            EXPECT_NEAR(c[i + j * ldc], s, 1e-13 * static_cast<double>(m)) << b.name;
          }
      }
}

}  // namespace dense_cholesky_test
}  // namespace errfield
