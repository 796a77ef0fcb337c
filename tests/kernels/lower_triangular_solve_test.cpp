// The blocked, vectorized lower-triangular solve against its naive reference.

#include "lower_triangular_solve.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace errfield {
namespace lower_triangular_solve_test {

TEST(LowerTriangularSolve, EqualsNaiveForwardSubstitution) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // sizes around the 8-row tile, the 4-column tile and the 64-row block
  for (std::size_t n : {1u, 7u, 8u, 9u, 63u, 64u, 65u, 130u, 300u})
    for (std::size_t nrhs : {1u, 3u, 4u, 5u, 17u}) {
      const std::size_t ldl = n + 3, ldb = n + 1;
      std::vector<double> l(ldl * n), b(ldb * nrhs);
      for (auto& x : l) x = u(rng) / std::sqrt(static_cast<double>(n));
      for (std::size_t i = 0; i < n; ++i) l[i + i * ldl] = 1.0 + std::abs(u(rng));  // well conditioned
      for (auto& x : b) x = u(rng);
      std::vector<double> ref = b;
      kernels::lower_solve_reference(l.data(), ldl, n, ref.data(), ldb, nrhs);
      kernels::lower_solve(kernels::pack_lower(l.data(), ldl, n), b.data(), ldb, nrhs);
      for (std::size_t j = 0; j < nrhs; ++j)
        for (std::size_t i = 0; i < n; ++i)
          // different summation order (and FMA): agreement to a few ulps times n
          EXPECT_NEAR(b[i + j * ldb], ref[i + j * ldb], 1e-13 * static_cast<double>(n) * (1.0 + std::abs(ref[i + j * ldb])))
              << "n " << n << " nrhs " << nrhs << " at " << i << "," << j;
      // padding rows of B between n and ldb are untouched
      if (ldb > n) {
        EXPECT_EQ(b[n], ref[n]);
      }
    }
}

}  // namespace
}  // namespace errfield
