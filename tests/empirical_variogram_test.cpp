#include "errfield/empirical_variogram.hpp"
#include "errfield/variogram_cloud.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "pair_binning.hpp"
#include "pair_binning_simd.hpp"

namespace errfield {
namespace empirical_variogram_test {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Summation order differs between the chunked kernel and the sequential reference; each sum has
// at most ~10^5 terms of one sign, so the relative difference is below 10^5 * 2^-53 ~ 1e-11.
constexpr double kSumTolerance = 1e-11;

struct Reference {
  std::vector<std::uint64_t> count;
  std::vector<double> lag_mean;
  Eigen::MatrixXd gamma;  // bins x K
};

// Brute force over all pairs with the naive kernel, and the estimator formulas written out again.
template <class L, class M>
Reference reference(const std::vector<L>& loc, const Eigen::MatrixXd& values, const M& metric,
                    const std::vector<double>& edges, bool gstat, VariogramEstimator est,
                    double fraction = 1.0, std::uint64_t seed = 0) {
  const std::size_t B = edges.size() - 1;
  const int K = static_cast<int>(values.cols());
  std::vector<double> z(loc.size() * K);
  for (std::size_t i = 0; i < loc.size(); ++i)
    for (int c = 0; c < K; ++c) z[i * K + c] = values(static_cast<Eigen::Index>(i), c);
  Reference r;
  r.count.assign(B, 0);
  std::vector<double> lag(B, 0.0), stat(B * K, 0.0);
  const auto statistic = est == VariogramEstimator::Matheron
                             ? kernels::PairStatistic::SquaredDifference
                             : kernels::PairStatistic::RootAbsDifference;
  kernels::bin_pairs_reference(loc.data(), z.data(), loc.size(), K, metric, edges.data(), B, gstat,
                               statistic, fraction, seed,
                               kernels::PairSums{r.count.data(), lag.data(), stat.data()});
  r.lag_mean.resize(B);
  r.gamma.resize(static_cast<Eigen::Index>(B), K);
  for (std::size_t b = 0; b < B; ++b) {
    const double n = static_cast<double>(r.count[b]);
    r.lag_mean[b] = lag[b] / n;
    for (int c = 0; c < K; ++c) {
      const double s = stat[b * K + c];
      r.gamma(static_cast<Eigen::Index>(b), c) =
          est == VariogramEstimator::Matheron
              ? s / n / 2.0
              : std::pow(s / n, 4.0) / (0.457 + 0.494 / n) / 2.0;
    }
  }
  return r;
}

void expect_matches(const EmpiricalVariogram& v, const Reference& r) {
  ASSERT_EQ(v.bins.size(), r.count.size());
  for (std::size_t b = 0; b < r.count.size(); ++b) {
    SCOPED_TRACE("bin " + std::to_string(b));
    EXPECT_EQ(v.bins[b].pairs, r.count[b]);
    if (r.count[b] == 0) {
      EXPECT_TRUE(std::isnan(v.bins[b].gamma));
      EXPECT_TRUE(std::isnan(v.bins[b].lag_mean));
      continue;
    }
    EXPECT_NEAR(v.bins[b].lag_mean, r.lag_mean[b], kSumTolerance * r.lag_mean[b]);
    double total = 0.0;
    for (int c = 0; c < r.gamma.cols(); ++c) {
      const double g = r.gamma(static_cast<Eigen::Index>(b), c);
      EXPECT_NEAR(v.component_gamma(static_cast<Eigen::Index>(b), c), g, 4 * kSumTolerance * g);
      total += g;
    }
    EXPECT_NEAR(v.bins[b].gamma, total, 4 * kSumTolerance * total);
  }
}

// Integer coordinates make many lags equal to bin edges, so the tie rules are exercised.
std::vector<Vec3> integer_points(std::size_t n, int extent, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> u(0, extent);
  std::vector<Vec3> p(n);
  for (auto& x : p) x = Vec3(u(rng), u(rng), u(rng));
  return p;
}

Eigen::MatrixXd random_values(std::size_t n, int k, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd v(static_cast<Eigen::Index>(n), k);
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    for (int c = 0; c < k; ++c) v(i, c) = g(rng) + 0.01 * static_cast<double>(i);
  return v;
}

TEST(EmpiricalVariogram, MatchesBruteForceAcrossEstimatorsConventionsAndEdges) {
  const auto loc = integer_points(400, 12, 1);
  const std::vector<std::vector<double>> edge_sets = {
      LagBins::uniform(0.0, 20.0, 2.0).edges(),   // uniform, many ties at even integer lags
      {0.0, 1.0, 3.0, 4.0, 7.5, 9.0, 15.0},       // explicit, irregular
      {2.0, 5.0, 8.0, 11.0},                      // uniform explicit edges, not starting at 0
  };
  for (int k : {1, 3, 2}) {
    const Eigen::MatrixXd values = random_values(loc.size(), k, 7 + k);
    for (const auto& edges : edge_sets)
      for (auto conv : {BinConvention::HalfOpen, BinConvention::Gstat})
        for (auto est : {VariogramEstimator::Matheron, VariogramEstimator::CressieHawkins}) {
          SCOPED_TRACE("K=" + std::to_string(k) + " edges " + std::to_string(edges.size()) + " " +
                       std::string(convention_name(conv)) + " " + std::string(estimator_name(est)));
          EmpiricalVariogramOptions o;
          o.convention = conv;
          o.estimator = est;
          const auto v = empirical_variogram<Vec3, EuclideanMetric>(
              std::span<const Vec3>(loc), values, EuclideanMetric{}, LagBins::from_edges(edges), o);
          expect_matches(v, reference(loc, values, EuclideanMetric{}, edges,
                                      conv == BinConvention::Gstat, est));
        }
  }
}

TEST(EmpiricalVariogram, GenericMetricsAndDynamicLocationsMatchBruteForce) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 90.0);
  std::vector<Vec6> q(300);
  std::vector<Eigen::VectorXd> qd(300);
  for (std::size_t i = 0; i < q.size(); ++i) {
    for (int a = 0; a < 6; ++a) q[i][a] = u(rng);
    qd[i] = q[i];
  }
  const Eigen::MatrixXd values = random_values(q.size(), 1, 5);
  const auto bins = LagBins::uniform(0.0, 150.0, 10.0);
  const WeightedEuclideanMetric weighted({1.0, 2.0, 0.5, 1.0, 0.25, 3.0});
  expect_matches(empirical_variogram<Vec6, WeightedEuclideanMetric>(std::span<const Vec6>(q), values,
                                                                    weighted, bins),
                 reference(q, values, weighted, bins.edges(), false, VariogramEstimator::Matheron));
  expect_matches(
      empirical_variogram<Vec6, JointSpaceMetric>(std::span<const Vec6>(q), values, JointSpaceMetric{}, bins),
      reference(q, values, JointSpaceMetric{}, bins.edges(), false, VariogramEstimator::Matheron));
  expect_matches(empirical_variogram<Eigen::VectorXd, EuclideanMetric>(
                     std::span<const Eigen::VectorXd>(qd), values, EuclideanMetric{}, bins),
                 reference(qd, values, EuclideanMetric{}, bins.edges(), false,
                           VariogramEstimator::Matheron));
  // A user-defined metric (Chebyshev) goes through the generic path.
  auto chebyshev = [](const Vec6& a, const Vec6& b) { return (a - b).cwiseAbs().maxCoeff(); };
  expect_matches(empirical_variogram<Vec6, decltype(chebyshev)>(std::span<const Vec6>(q), values,
                                                                chebyshev, bins),
                 reference(q, values, chebyshev, bins.edges(), false, VariogramEstimator::Matheron));
}

TEST(EmpiricalVariogram, LinearFieldOnRegularGridHasClosedForm) {
  // v = c x on x = 0, 1, ..., n-1: every pair at lag h has (v_i - v_j)^2 = c^2 h^2, so
  // gamma(h) = c^2 h^2 / 2 exactly, with n - h pairs; bins [h - 0.5, h + 0.5) isolate each lag.
  const int n = 50;
  const double c = 0.75;  // exact in binary, so c^2 h^2 / 2 is exact too
  std::vector<double> x(n), v(n);
  for (int i = 0; i < n; ++i) {
    x[i] = i;
    v[i] = c * i;
  }
  const auto bins = LagBins::uniform(0.5, 20.5, 1.0);
  const auto vg = empirical_variogram<double, EuclideanMetric, double>(
      std::span<const double>(x), std::span<const double>(v), EuclideanMetric{}, bins);
  for (std::size_t b = 0; b < bins.size(); ++b) {
    const double h = static_cast<double>(b + 1);
    EXPECT_EQ(vg.bins[b].pairs, static_cast<std::uint64_t>(n - static_cast<int>(h)));
    EXPECT_DOUBLE_EQ(vg.bins[b].lag_mean, h);
    EXPECT_DOUBLE_EQ(vg.bins[b].gamma, c * c * h * h / 2.0);
  }
}

TEST(EmpiricalVariogram, VectorGammaIsHalfMeanSquaredNormAndSumOfComponents) {
  const auto loc = integer_points(200, 30, 11);
  std::vector<Vec3> err(loc.size());
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  for (auto& e : err) e = Vec3(g(rng), 2.0 * g(rng), 0.5 * g(rng));
  const auto bins = LagBins::uniform(0.0, 40.0, 5.0);
  const auto v = empirical_variogram<Vec3, EuclideanMetric, Vec3>(
      std::span<const Vec3>(loc), std::span<const Vec3>(err), EuclideanMetric{}, bins);
  ASSERT_EQ(v.components(), 3);
  for (std::size_t b = 0; b < bins.size(); ++b) {
    double sum = 0.0;
    std::uint64_t n = 0;
    for (std::size_t i = 1; i < loc.size(); ++i)
      for (std::size_t j = 0; j < i; ++j) {
        const double h = (loc[i] - loc[j]).norm();
        if (h >= bins.lag_lo(b) && h < bins.lag_hi(b)) {
          sum += (err[i] - err[j]).squaredNorm();
          ++n;
        }
      }
    ASSERT_EQ(v.bins[b].pairs, n);
    if (n == 0) continue;
    EXPECT_NEAR(v.bins[b].gamma, sum / (2.0 * n), 1e-12 * sum / n);
    EXPECT_NEAR(v.bins[b].gamma, v.component_gamma.row(static_cast<Eigen::Index>(b)).sum(), 1e-14 * sum / n);
  }
}

TEST(EmpiricalVariogram, BitIdenticalForAnyThreadCount) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 2000.0);
  std::vector<Vec3> loc(3000);
  for (auto& p : loc) p = Vec3(u(rng), u(rng), u(rng));
  const Eigen::MatrixXd values = random_values(loc.size(), 1, 4);
  const auto bins = LagBins::uniform(0.0, 3000.0, 150.0);
  for (double fraction : {1.0, 0.3})
    for (auto est : {VariogramEstimator::Matheron, VariogramEstimator::CressieHawkins}) {
      EmpiricalVariogramOptions o;
      o.estimator = est;
      o.pair_fraction = fraction;
      o.threads = 1;
      const auto one = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                  EuclideanMetric{}, bins, o);
      o.threads = 2;
      const auto two = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                  EuclideanMetric{}, bins, o);
      o.threads = 3;
      const auto three = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                    EuclideanMetric{}, bins, o);
      for (std::size_t b = 0; b < bins.size(); ++b) {
        EXPECT_EQ(one.bins[b].pairs, two.bins[b].pairs);
        EXPECT_EQ(one.bins[b].pairs, three.bins[b].pairs);
        // Bitwise equality, NaN == NaN for empty bins.
        EXPECT_EQ(std::memcmp(&one.bins[b].gamma, &two.bins[b].gamma, sizeof(double)), 0);
        EXPECT_EQ(std::memcmp(&one.bins[b].gamma, &three.bins[b].gamma, sizeof(double)), 0);
        EXPECT_EQ(std::memcmp(&one.bins[b].lag_mean, &two.bins[b].lag_mean, sizeof(double)), 0);
      }
    }
}

TEST(EmpiricalVariogram, SubsamplingIsDeterministicAndKeepsTheRequestedFraction) {
  const auto loc = integer_points(600, 50, 21);
  const Eigen::MatrixXd values = random_values(loc.size(), 1, 8);
  const auto bins = LagBins::uniform(0.0, 100.0, 10.0);
  EmpiricalVariogramOptions o;
  o.pair_fraction = 0.25;
  o.seed = 1234;
  const auto v = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                            EuclideanMetric{}, bins, o);
  expect_matches(v, reference(loc, values, EuclideanMetric{}, bins.edges(), false,
                              VariogramEstimator::Matheron, 0.25, 1234));
  std::uint64_t kept = 0;
  for (const auto& b : v.bins) kept += b.pairs;
  const double total = 600.0 * 599.0 / 2.0;  // every pair is within 100 (max lag 50 sqrt 3)
  // Binomial(total, 0.25): standard deviation sqrt(total * 0.25 * 0.75) ~ 164; allow 5 sigma.
  EXPECT_NEAR(static_cast<double>(kept), 0.25 * total, 5.0 * std::sqrt(total * 0.25 * 0.75));
  o.seed = 99;
  const auto other = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                EuclideanMetric{}, bins, o);
  EXPECT_NE(other.bins[3].pairs, v.bins[3].pairs);  // a different seed draws different pairs
}

TEST(EmpiricalVariogram, MatrixOverloadDispatchesEveryDimension) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int d : {1, 2, 3, 4, 6}) {
    Eigen::MatrixXd x(150, d);
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      for (int a = 0; a < d; ++a) x(i, a) = u(rng);
    std::vector<Eigen::VectorXd> loc(150);
    for (Eigen::Index i = 0; i < x.rows(); ++i) loc[static_cast<std::size_t>(i)] = x.row(i).transpose();
    const Eigen::MatrixXd values = random_values(150, 2, 3);
    const auto bins = LagBins::uniform(0.0, 12.0, 1.5);
    expect_matches(empirical_variogram(x, values, bins),
                   reference(loc, values, EuclideanMetric{}, bins.edges(), false,
                             VariogramEstimator::Matheron));
  }
}

TEST(EmpiricalVariogram, RejectsBadBinsOptionsAndData) {
  EXPECT_THROW(LagBins::uniform(0.0, 100.0, 0.0), ArgumentError);
  EXPECT_THROW(LagBins::uniform(0.0, 100.0, -5.0), ArgumentError);
  EXPECT_THROW(LagBins::uniform(0.0, 0.0, 5.0), ArgumentError);
  EXPECT_THROW(LagBins::uniform(0.0, 1e9, 1e-3), ArgumentError);
  EXPECT_THROW(LagBins::from_edges({0.0}), ArgumentError);
  EXPECT_THROW(LagBins::from_edges({0.0, 10.0, 10.0}), ArgumentError);
  EXPECT_THROW(LagBins::from_edges({0.0, 10.0, 5.0}), ArgumentError);
  EXPECT_THROW(LagBins::from_edges({-1.0, 10.0}), ArgumentError);
  try {
    LagBins::uniform(0.0, 100.0, 0.0);
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("width"), std::string::npos) << e.what();
  }
  try {
    LagBins::from_edges({0.0, 10.0, 5.0});
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("edges[2]"), std::string::npos) << e.what();
  }
  const auto bins = LagBins::uniform(0.0, 10.0, 1.0);
  EXPECT_EQ(bins.size(), 10u);
  EXPECT_EQ(LagBins::uniform(0.0, 10.5, 1.0).size(), 11u);  // last bin reaches past max_lag
  std::vector<Vec3> loc{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 2, 0)};
  Eigen::MatrixXd values(3, 1);
  values << 1.0, 2.0, 3.0;
  const std::span<const Vec3> s(loc);
  EmpiricalVariogramOptions o;
  o.pair_fraction = 0.0;
  EXPECT_THROW(empirical_variogram<Vec3>(s, values, EuclideanMetric{}, bins, o), ArgumentError);
  o.pair_fraction = 1.5;
  EXPECT_THROW(empirical_variogram<Vec3>(s, values, EuclideanMetric{}, bins, o), ArgumentError);
  o = {};
  o.threads = -1;
  EXPECT_THROW(empirical_variogram<Vec3>(s, values, EuclideanMetric{}, bins, o), ArgumentError);
  EXPECT_THROW(empirical_variogram<Vec3>(s.first(1), values.topRows(1), EuclideanMetric{}, bins), InputError);
  EXPECT_THROW(empirical_variogram<Vec3>(s, values.topRows(2), EuclideanMetric{}, bins), ArgumentError);
  values(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(empirical_variogram<Vec3>(s, values, EuclideanMetric{}, bins), InputError);
  values(1, 0) = 2.0;
  loc[2][1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(empirical_variogram<Vec3>(std::span<const Vec3>(loc), values, EuclideanMetric{}, bins),
               InputError);
  EXPECT_THROW(estimator_from_name("dowd2"), ArgumentError);
  EXPECT_THROW(convention_from_name("left"), ArgumentError);
}

TEST(EmpiricalVariogram, DowdMatchesMediansOfBruteForceDifferences) {
  const auto loc = integer_points(250, 20, 31);
  const Eigen::MatrixXd values = random_values(loc.size(), 2, 12);
  const auto bins = LagBins::from_edges({0.0, 3.0, 6.0, 10.0, 15.0, 25.0, 40.0});
  for (auto conv : {BinConvention::HalfOpen, BinConvention::Gstat})
    for (double fraction : {1.0, 0.5}) {
      EmpiricalVariogramOptions o;
      o.estimator = VariogramEstimator::Dowd;
      o.convention = conv;
      o.pair_fraction = fraction;
      o.seed = 5;
      o.threads = 2;
      const auto v = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                EuclideanMetric{}, bins, o);
      o.threads = 1;
      const auto v1 = empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values,
                                                                 EuclideanMetric{}, bins, o);
      const auto& e = bins.edges();
      for (std::size_t b = 0; b < bins.size(); ++b) {
        double total = 0.0;
        std::uint64_t n = 0;
        for (int c = 0; c < 2; ++c) {
          std::vector<double> d;
          for (std::size_t i = 1; i < loc.size(); ++i)
            for (std::size_t j = 0; j < i; ++j) {
              if (fraction < 1.0 && static_cast<long double>(kernels::pair_hash(5, i, j)) >=
                                        static_cast<long double>(fraction) * 18446744073709551616.0L)
                continue;
              const double h = (loc[i] - loc[j]).norm();
              const bool in = conv == BinConvention::Gstat
                                  ? (b == 0 ? h >= e[0] && h <= e[1] : h > e[b] && h <= e[b + 1])
                                  : h >= e[b] && h < e[b + 1];
              if (in) d.push_back(std::fabs(values(static_cast<Eigen::Index>(i), c) -
                                            values(static_cast<Eigen::Index>(j), c)));
            }
          n = d.size();
          std::sort(d.begin(), d.end());
          const double med = d.size() % 2 ? d[d.size() / 2] : 0.5 * (d[d.size() / 2 - 1] + d[d.size() / 2]);
          const double g = 1.099 * med * med;
          EXPECT_NEAR(v.component_gamma(static_cast<Eigen::Index>(b), c), g, 1e-15 * g);
          total += g;
        }
        ASSERT_EQ(v.bins[b].pairs, n);
        EXPECT_NEAR(v.bins[b].gamma, total, 1e-14 * total);
        EXPECT_EQ(v.bins[b].gamma, v1.bins[b].gamma);  // thread count does not matter
      }
    }
}

TEST(EmpiricalVariogram, DowdRespectsItsMemoryBudget) {
  const auto loc = integer_points(300, 20, 1);
  const Eigen::MatrixXd values = random_values(loc.size(), 1, 2);
  EmpiricalVariogramOptions o;
  o.estimator = VariogramEstimator::Dowd;
  o.max_stored_differences = 1000;  // far fewer than the ~45,000 binned pairs
  try {
    empirical_variogram<Vec3, EuclideanMetric>(std::span<const Vec3>(loc), values, EuclideanMetric{},
                                               LagBins::uniform(0.0, 40.0, 5.0), o);
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("pair_fraction"), std::string::npos) << e.what();
  }
}

TEST(PairBinningKernel, FindBinFollowsTheTieRules) {
  const std::vector<double> e{0.0, 1.0, 2.0, 4.0};
  kernels::BinLayout half{e.data(), 3, false, false, 1.0};
  kernels::BinLayout gs{e.data(), 3, true, false, 1.0};
  EXPECT_EQ(kernels::find_bin(0.0, half), 0);
  EXPECT_EQ(kernels::find_bin(1.0, half), 1);
  EXPECT_EQ(kernels::find_bin(3.999, half), 2);
  EXPECT_EQ(kernels::find_bin(4.0, half), -1);
  EXPECT_EQ(kernels::find_bin(0.0, gs), 0);
  EXPECT_EQ(kernels::find_bin(1.0, gs), 0);
  EXPECT_EQ(kernels::find_bin(2.0, gs), 1);
  EXPECT_EQ(kernels::find_bin(4.0, gs), 2);
  EXPECT_EQ(kernels::find_bin(4.0000001, gs), -1);
  EXPECT_EQ(kernels::find_bin(-0.5, gs), -1);
  EXPECT_EQ(kernels::find_bin(std::numeric_limits<double>::quiet_NaN(), half), -1);
}

// The Euclidean kernel through bin_pair_rows_euclidean_isa: the AVX2 and AVX-512 paths (those this
// CPU has) must give the baseline kernel's sums bit for bit, and both the naive reference's counts
// exactly and its sums to rounding. Integer coordinates put many lags exactly on bin edges (the
// near-edge branch); max lags below the diameter put pairs outside every bin; odd row lengths
// exercise the scalar tail; e_0 > 0 and both conventions and statistics are covered.
template <int D>
void check_isa_paths(std::size_t n, const std::vector<double>& edges, bool gstat,
                     kernels::PairStatistic stat, int dynamic_dimension = 0) {
  using kernels::KernelIsa;
  constexpr int kD = D > 0 ? D : 4;
  const int dim = D > 0 ? D : dynamic_dimension;
  std::mt19937_64 rng(100 + n + edges.size() + (gstat ? 1 : 0));
  std::uniform_int_distribution<int> coord(0, 9);
  std::normal_distribution<double> g(0.0, 1.0);
  using P = Eigen::Matrix<double, kD, 1>;
  std::vector<P> loc(n);
  std::vector<double> soa(n * kD), z(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < dim; ++a) soa[a * n + i] = loc[i][a] = coord(rng);
    z[i] = g(rng);
  }
  const auto bins = LagBins::from_edges(edges);
  ASSERT_TRUE(bins.is_uniform());
  EmpiricalVariogramOptions o;
  o.convention = gstat ? BinConvention::Gstat : BinConvention::HalfOpen;
  const kernels::BinLayout layout = detail::variogram_bin_layout(bins, o);
  const std::size_t B = bins.size() + 1;
  struct Sums {
    std::vector<std::uint64_t> count;
    std::vector<double> lag, stat;
    explicit Sums(std::size_t b) : count(b, 0), lag(b, 0.0), stat(b, 0.0) {}
    kernels::PairSums view() { return {count.data(), lag.data(), stat.data()}; }
  };
  auto run = [&](KernelIsa isa, std::size_t r0, std::size_t r1) {
    Sums s(B);
    if (stat == kernels::PairStatistic::SquaredDifference)
      kernels::bin_pair_rows_euclidean_isa<kernels::PairStatistic::SquaredDifference, false, 1, D>(
          isa, soa.data(), n, dim, z.data(), 1, layout, 0, 0, r0, r1, s.view());
    else
      kernels::bin_pair_rows_euclidean_isa<kernels::PairStatistic::RootAbsDifference, false, 1, D>(
          isa, soa.data(), n, dim, z.data(), 1, layout, 0, 0, r0, r1, s.view());
    return s;
  };
  Sums ref(B);
  kernels::bin_pairs_reference(loc.data(), z.data(), n, 1, EuclideanMetric{}, edges.data(),
                               bins.size(), gstat, stat, 1.0, 0, ref.view());
  const Sums base = run(KernelIsa::Baseline, 1, n);
  for (std::size_t b = 0; b + 1 < B; ++b) {
    SCOPED_TRACE("bin " + std::to_string(b));
    EXPECT_EQ(base.count[b], ref.count[b]);
    EXPECT_NEAR(base.lag[b], ref.lag[b], kSumTolerance * ref.lag[b]);
    EXPECT_NEAR(base.stat[b], ref.stat[b], kSumTolerance * ref.stat[b]);
  }
  for (KernelIsa isa : {KernelIsa::Avx2, KernelIsa::Avx512}) {
    if (!kernels::kernel_isa_supported(isa)) continue;  // reported by the test below
    SCOPED_TRACE(isa == KernelIsa::Avx2 ? "AVX2" : "AVX-512");
    for (auto [r0, r1] : {std::pair<std::size_t, std::size_t>{1, n}, {n / 3, n - 5}}) {
      const Sums a = run(isa, r0, r1);
      const Sums b = run(KernelIsa::Baseline, r0, r1);
      EXPECT_EQ(a.count, b.count);
      EXPECT_EQ(std::memcmp(a.lag.data(), b.lag.data(), B * sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(a.stat.data(), b.stat.data(), B * sizeof(double)), 0);
    }
  }
}

TEST(PairBinningKernel, SimdPathsAreBitIdenticalToBaselineAndAllMatchTheReference) {
  using kernels::PairStatistic;
  if (!kernels::kernel_isa_supported(kernels::KernelIsa::Avx2))
    std::printf("note: this CPU has no AVX2; only the baseline kernel is checked here\n");
  else if (!kernels::kernel_isa_supported(kernels::KernelIsa::Avx512))
    std::printf("note: this CPU has no AVX-512; its kernel is not checked here\n");
  const std::vector<double> from0 = LagBins::uniform(0.0, 9.0, 1.5).edges();   // many ties
  const std::vector<double> shifted = {2.0, 3.0, 4.0, 5.0, 6.0, 7.0};          // e_0 > 0
  for (bool gstat : {false, true})
    for (auto st : {PairStatistic::SquaredDifference, PairStatistic::RootAbsDifference}) {
      SCOPED_TRACE(std::string(gstat ? "gstat " : "half-open ") +
                   (st == PairStatistic::SquaredDifference ? "squared" : "root-abs"));
      check_isa_paths<3>(203, from0, gstat, st);
      check_isa_paths<3>(150, shifted, gstat, st);
      check_isa_paths<2>(121, from0, gstat, st);
      check_isa_paths<6>(98, from0, gstat, st);
      check_isa_paths<0>(77, shifted, gstat, st, 4);
    }
}

TEST(PairBinningKernel, IsaDispatchFallsBackOutsideTheAvx2Cases) {
  // Non-uniform bins, more than kSimdMaxBins bins: the dispatcher must take the baseline path
  // (and thus still give the reference's counts) whatever ISA it is given.
  using kernels::KernelIsa;
  const std::size_t n = 60;
  std::vector<double> soa(n), z(n);
  for (std::size_t i = 0; i < n; ++i) {
    soa[i] = static_cast<double>(i * i % 17);
    z[i] = static_cast<double>(i % 5);
  }
  std::vector<double> many(kernels::kSimdMaxBins + 2);
  for (std::size_t k = 0; k < many.size(); ++k) many[k] = 0.01 * static_cast<double>(k);
  for (const auto& edges : {std::vector<double>{0.0, 1.0, 3.0, 4.0, 7.5, 17.0}, many}) {
    const auto bins = LagBins::from_edges(edges);
    const kernels::BinLayout layout = detail::variogram_bin_layout(bins, {});
    const std::size_t B = bins.size() + 1;
    std::vector<std::uint64_t> c(B, 0), rc(B, 0);
    std::vector<double> l(B, 0.0), s(B, 0.0), rl(B, 0.0), rs(B, 0.0);
    kernels::bin_pair_rows_euclidean_isa<kernels::PairStatistic::SquaredDifference, false, 1, 1>(
        kernels::best_kernel_isa(), soa.data(), n, 1, z.data(), 1, layout, 0, 0, 1, n,
        kernels::PairSums{c.data(), l.data(), s.data()});
    EXPECT_FALSE(bins.is_uniform() && bins.size() <= kernels::kSimdMaxBins);
    kernels::bin_pairs_reference(soa.data(), z.data(), n, 1, EuclideanMetric{}, edges.data(),
                                 bins.size(), false, kernels::PairStatistic::SquaredDifference, 1.0,
                                 0, kernels::PairSums{rc.data(), rl.data(), rs.data()});
    for (std::size_t b = 0; b + 1 < B; ++b) EXPECT_EQ(c[b], rc[b]) << "bin " << b;
  }
}

static_assert(Location<Vec3> && Location<Vec6> && Location<Eigen::VectorXd> && Location<double>);
static_assert(Metric<EuclideanMetric, Vec3> && Metric<WeightedEuclideanMetric, Vec6>);
static_assert(Value<double> && Value<Vec3>);
static_assert(!Location<int> && !Metric<int, Vec3>);

// The cloud against a brute-force pair list (3-D, a vector value): every pair within the cutoff,
// including one exactly at it, in gstat's order (left > right); the budget refuses one pair more
// than it allows and accepts exactly as many.
TEST(VariogramCloud, ListsEveryPairWithinTheCutoffInGstatsOrderAndKeepsItsBudget) {
  std::mt19937_64 rng(36);
  std::uniform_int_distribution<int> u(0, 20);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(60, 3), z(60, 2);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (int a = 0; a < 3; ++a) x(i, a) = u(rng);  // integers: distances exactly at the cutoff occur
    z(i, 0) = g(rng);
    z(i, 1) = g(rng);
  }
  VariogramCloudOptions o;
  o.cutoff = 9.0;
  const VariogramCloud c = variogram_cloud(x, z, o);
  std::size_t k = 0, at_cutoff = 0;
  for (Eigen::Index i = 1; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) {
      const double h = (x.row(i) - x.row(j)).norm();
      if (h > 9.0) continue;
      at_cutoff += h == 9.0;
      ASSERT_LT(k, c.size());
      EXPECT_EQ(c.left[k], i);
      EXPECT_EQ(c.right[k], j);
      EXPECT_EQ(c.dist[k], h);
      EXPECT_DOUBLE_EQ(c.gamma[k], 0.5 * (z.row(i) - z.row(j)).squaredNorm());
      ++k;
    }
  EXPECT_EQ(k, c.size());
  EXPECT_GT(at_cutoff, 0u);
  o.max_pairs = c.size();
  EXPECT_EQ(variogram_cloud(x, z, o).size(), c.size());
  o.max_pairs = c.size() - 1;
  EXPECT_THROW(variogram_cloud(x, z, o), ResourceError);
  o.cutoff = 0.0;
  EXPECT_THROW(variogram_cloud(x, z, o), ArgumentError);
}

// The map with different cell widths in x and y (gstat has one width; the rule is its rule per
// axis) against the nearest cell centre, on continuous coordinates where no lag is half-way
// between two centres: each pair twice (+s and -s), so the map is symmetric through the origin.
TEST(VariogramMap, CountsEachLagVectorInItsNearestCellTwiceAndIsSymmetric) {
  std::mt19937_64 rng(3636);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(80, 2), z(80, 1);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    x(i, 0) = u(rng);
    x(i, 1) = 0.5 * u(rng);
    z(i, 0) = g(rng);
  }
  VariogramMapOptions o;
  o.cutoff = 40.0;
  o.width_x = 10.0;
  o.width_y = 5.0;
  const VariogramMap m = variogram_map(x, z, o);
  ASSERT_EQ(m.columns, 9);
  ASSERT_EQ(m.rows, 17);
  std::vector<std::uint64_t> n(m.pairs.size(), 0);
  std::vector<double> sum(m.pairs.size(), 0.0);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < x.rows(); ++j) {  // both orders: +s and -s
      if (i == j) continue;
      const double sx = x(i, 0) - x(j, 0), sy = x(i, 1) - x(j, 1);
      for (int r = 0; r < m.rows; ++r)
        for (int c = 0; c < m.columns; ++c)
          if (std::fabs(sx - m.lag_x[static_cast<std::size_t>(c)]) < 5.0 && std::fabs(sy - m.lag_y[static_cast<std::size_t>(r)]) < 2.5) {
            const auto k = static_cast<std::size_t>(r * m.columns + c);
            ++n[k];
            sum[k] += 0.5 * (z(i, 0) - z(j, 0)) * (z(i, 0) - z(j, 0));
          }
    }
  for (std::size_t k = 0; k < n.size(); ++k) {
    EXPECT_EQ(m.pairs[k], n[k]) << "cell " << k;
    if (n[k] == 0) {
      EXPECT_TRUE(std::isnan(m.gamma[k]));
    } else {
      EXPECT_NEAR(m.gamma[k], sum[k] / static_cast<double>(n[k]), 1e-12 * sum[k]);
    }
    EXPECT_EQ(m.pairs[k], m.pairs[m.pairs.size() - 1 - k]);  // symmetric through the origin
  }
  const Eigen::MatrixXd x3(2, 3);
  EXPECT_THROW(variogram_map(x3, Eigen::MatrixXd::Zero(2, 1), o), ArgumentError);
}

}  // namespace
}  // namespace errfield
