// Cross-variograms of EmpiricalVariogram (options.cross_variograms) against a brute-force double
// loop over the pairs, and their determinism.

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/empirical_variogram.hpp"

namespace errfield {
namespace cross_variogram_test {

// Simulated data: uniform 2-D locations (integer coordinates, so lags hit bin edges) and P
// correlated components (a shared smooth part plus noise).
struct Sample {
  Eigen::MatrixXd x, z;
};

Sample simulated(int n, int P, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> u(0, 500);
  std::normal_distribution<double> g(0.0, 1.0);
  Sample s{Eigen::MatrixXd(n, 2), Eigen::MatrixXd(n, P)};
  for (int i = 0; i < n; ++i) {
    s.x(i, 0) = u(rng);
    s.x(i, 1) = u(rng);
    const double shared = std::sin(s.x(i, 0) / 80.0) + std::cos(s.x(i, 1) / 120.0);
    for (int c = 0; c < P; ++c) s.z(i, c) = (c % 2 ? -1.0 : 1.0) * (0.5 + c) * shared + 0.3 * g(rng);
  }
  return s;
}

// gamma_ab of every bin and N by a plain double loop, with the bin rule written out again; also
// sum |products| / (2N), the scale of the rounding error of any summation order.
struct BruteForce {
  std::vector<std::uint64_t> pairs;
  std::vector<Eigen::MatrixXd> gamma, scale;
};

BruteForce brute_force(const Sample& s, const std::vector<double>& edges, bool gstat) {
  const std::size_t B = edges.size() - 1;
  const Eigen::Index P = s.z.cols();
  BruteForce r{std::vector<std::uint64_t>(B, 0), std::vector<Eigen::MatrixXd>(B, Eigen::MatrixXd::Zero(P, P)),
               std::vector<Eigen::MatrixXd>(B, Eigen::MatrixXd::Zero(P, P))};
  for (Eigen::Index i = 0; i < s.x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) {
      const double h = (s.x.row(i) - s.x.row(j)).norm();
      for (std::size_t k = 0; k < B; ++k) {
        const bool in = gstat ? (k == 0 ? h >= edges[0] && h <= edges[1] : h > edges[k] && h <= edges[k + 1])
                              : h >= edges[k] && h < edges[k + 1];
        if (!in) continue;
        ++r.pairs[k];
        for (Eigen::Index a = 0; a < P; ++a)
          for (Eigen::Index b = 0; b < P; ++b) {
            const double p = (s.z(i, a) - s.z(j, a)) * (s.z(i, b) - s.z(j, b));
            r.gamma[k](a, b) += p;
            r.scale[k](a, b) += std::abs(p);
          }
        break;
      }
    }
  for (std::size_t k = 0; k < B; ++k)
    if (r.pairs[k] > 0) {
      r.gamma[k] /= 2.0 * static_cast<double>(r.pairs[k]);
      r.scale[k] /= 2.0 * static_cast<double>(r.pairs[k]);
    }
  return r;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(CrossVariogram, MatchesABruteForceDoubleLoopForBothConventionsAndPairSearches) {
  const Sample s = simulated(200, 3, 1);
  for (bool gstat : {false, true})
    for (PairSearch search : {PairSearch::AllPairs, PairSearch::CellList}) {
      const LagBins bins = LagBins::uniform(0.0, 300.0, 25.0);
      EmpiricalVariogramOptions o;
      o.convention = gstat ? BinConvention::Gstat : BinConvention::HalfOpen;
      o.cross_variograms = true;
      o.pair_search = search;
      const EmpiricalVariogram v = empirical_variogram(s.x, s.z, bins, o);
      const BruteForce ref = brute_force(s, bins.edges(), gstat);
      ASSERT_EQ(v.cross_gamma.rows(), static_cast<Eigen::Index>(bins.size()));
      ASSERT_EQ(v.cross_gamma.cols(), 3);
      for (std::size_t k = 0; k < bins.size(); ++k) {
        ASSERT_EQ(v.bins[k].pairs, ref.pairs[k]) << "bin " << k;
        ASSERT_GT(ref.pairs[k], 0u);
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            EXPECT_NEAR(v.gamma_of(k, a, b), ref.gamma[k](a, b), 1e-13 * ref.scale[k](a, b))
                << "bin " << k << " components " << a << "," << b << (gstat ? " gstat" : " half-open");
      }
    }
}

TEST(CrossVariogram, IsSymmetricAndItsDiagonalIsTheDirectVariogramBitForBit) {
  const Sample s = simulated(150, 4, 2);
  const LagBins bins = LagBins::uniform(0.0, 400.0, 40.0);
  for (bool directional : {false, true}) {
    EmpiricalVariogramOptions o;
    if (directional) o.direction = VariogramDirection::gstat(45.0, 22.5);
    const EmpiricalVariogram direct = empirical_variogram(s.x, s.z, bins, o);
    o.cross_variograms = true;
    const EmpiricalVariogram cross = empirical_variogram(s.x, s.z, bins, o);
    ASSERT_EQ(cross.cross_gamma.cols(), 6);
    // Column order (0,1), (0,2), (0,3), (1,2), (1,3), (2,3).
    int column = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) EXPECT_EQ(EmpiricalVariogram::cross_column(a, b, 4), column++);
    for (std::size_t k = 0; k < bins.size(); ++k) {
      EXPECT_EQ(cross.bins[k].pairs, direct.bins[k].pairs);
      EXPECT_TRUE(same_bits(cross.bins[k].gamma, direct.bins[k].gamma));
      for (int a = 0; a < 4; ++a) {
        EXPECT_TRUE(same_bits(cross.gamma_of(k, a, a), direct.component_gamma(static_cast<Eigen::Index>(k), a)));
        for (int b = 0; b < 4; ++b) EXPECT_TRUE(same_bits(cross.gamma_of(k, a, b), cross.gamma_of(k, b, a)));
      }
    }
  }
}

TEST(CrossVariogram, BitIdenticalForAnyThreadCountWithSubsamplingAndCellLists) {
  const Sample s = simulated(1200, 3, 3);
  const LagBins bins = LagBins::uniform(0.0, 120.0, 10.0);
  for (PairSearch search : {PairSearch::AllPairs, PairSearch::CellList})
    for (double fraction : {1.0, 0.4}) {
      EmpiricalVariogramOptions o;
      o.cross_variograms = true;
      o.pair_search = search;
      o.pair_fraction = fraction;
      o.threads = 1;
      const EmpiricalVariogram one = empirical_variogram(s.x, s.z, bins, o);
      for (int threads : {2, 3}) {
        o.threads = threads;
        const EmpiricalVariogram other = empirical_variogram(s.x, s.z, bins, o);
        ASSERT_EQ(other.cross_gamma.size(), one.cross_gamma.size());
        EXPECT_EQ(std::memcmp(other.cross_gamma.data(), one.cross_gamma.data(),
                              sizeof(double) * static_cast<std::size_t>(one.cross_gamma.size())), 0)
            << threads << " threads, fraction " << fraction;
        for (std::size_t k = 0; k < bins.size(); ++k) EXPECT_EQ(other.bins[k].pairs, one.bins[k].pairs);
      }
    }
}

TEST(CrossVariogram, RefusesTheRobustEstimatorsAndAnswersOnlyWhenComputed) {
  const Sample s = simulated(30, 2, 4);
  const LagBins bins = LagBins::uniform(0.0, 400.0, 100.0);
  for (VariogramEstimator e : {VariogramEstimator::CressieHawkins, VariogramEstimator::Dowd}) {
    EmpiricalVariogramOptions o;
    o.cross_variograms = true;
    o.estimator = e;
    try {
      (void)empirical_variogram(s.x, s.z, bins, o);
      ADD_FAILURE() << "accepted cross_variograms with " << estimator_name(e);
    } catch (const ArgumentError& err) {
      EXPECT_NE(std::string(err.what()).find(std::string(estimator_name(e))), std::string::npos) << err.what();
      EXPECT_NE(std::string(err.what()).find("Matheron"), std::string::npos) << err.what();
    }
  }
  const EmpiricalVariogram plain = empirical_variogram(s.x, s.z, bins);
  EXPECT_EQ(plain.cross_gamma.size(), 0);
  EXPECT_THROW((void)plain.gamma_of(0, 0, 1), ArgumentError);
  EXPECT_NO_THROW((void)plain.gamma_of(0, 1, 1));
  EXPECT_THROW((void)plain.gamma_of(0, 2, 2), ArgumentError);
}

}  // namespace cross_variogram_test
}  // namespace errfield
