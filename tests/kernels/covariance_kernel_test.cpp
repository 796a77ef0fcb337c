// The covariance kernel against its naive reference, VariogramModel::covariance.

#include "covariance_kernel.hpp"

#include <random>

#include <gtest/gtest.h>

namespace errfield {
namespace covariance_kernel_test {

TEST(CovarianceKernel, BlockEqualsModelCovariance) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 50.0);
  const int d = 3;
  std::vector<double> a(d * 7), b(d * 5);
  for (auto& x : a) x = u(rng);
  for (auto& x : b) x = u(rng);
  for (int k = 0; k < d; ++k) b[k] = a[k];  // one coincident pair (a_0, b_0)
  for (const char* text : {"sph(sill=2,range=30)+nug(0.5)", "exp(1,10)+gau(0.5,20)", "mat(sill=1,range=5,nu=1.5)+nug(0.1)",
                           "wen(1,25)"}) {
    const auto model = VariogramModel::parse(text);
    const kernels::CovarianceKernel kernel(model);
    std::vector<double> out(8 * 5, -1.0);  // leading dimension 8 > 7 rows
    kernels::covariance_block(kernel, a.data(), 7, b.data(), 5, d, 123.0, out.data(), 8);
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 7; ++i) {
        double h2 = 0.0;
        for (int k = 0; k < d; ++k) h2 += (a[i * d + k] - b[j * d + k]) * (a[i * d + k] - b[j * d + k]);
        const double expected = h2 == 0.0 ? 123.0 : model.covariance(std::sqrt(h2));
        EXPECT_NEAR(out[j * 8 + i], expected, 1e-14 * model.sill()) << text << " " << i << "," << j;
      }
    EXPECT_DOUBLE_EQ(kernel.sill(), model.sill());
    EXPECT_DOUBLE_EQ(kernel.nugget(), model.nugget());
  }
  EXPECT_THROW(kernels::CovarianceKernel(VariogramModel::parse("pow(1,1.5)")), ArgumentError);
}

TEST(CovarianceKernel, AtLagsIsTheScalarKernelBitForBit) {
  // The batch form the sequential simulation uses: the same number as operator() at every lag
  // (zero lag, inside and beyond a spherical range, several terms of several kinds).
  std::vector<double> lags{0.0, 1e-300, 0.5, 3.0, 29.999999999999996, 30.0, 30.000000000000004, 45.0, 1e6};
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 80.0);
  for (int i = 0; i < 200; ++i) lags.push_back(u(rng));
  for (const char* text : {"sph(sill=2,range=30)+nug(0.5)", "sph(1,30)+sph(0.5,70)+nug(0.1)", "exp(1,10)+sph(0.5,20)",
                           "mat(sill=1,range=5,nu=1.5)+gau(0.5,20)", "wen(1,25)"}) {
    const kernels::CovarianceKernel kernel(VariogramModel::parse(text));
    std::vector<double> out(lags.size(), -1.0);
    kernel.at_lags(lags.data(), lags.size(), 7.0, out.data());
    for (std::size_t i = 0; i < lags.size(); ++i) EXPECT_EQ(out[i], kernel(lags[i], 7.0)) << text << " at lag " << lags[i];
  }
}

}  // namespace
}  // namespace errfield
