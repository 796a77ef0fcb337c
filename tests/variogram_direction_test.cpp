// Directional empirical variograms (variogram_direction.hpp) against a brute-force pair loop
// written here with angles from atan2/acos (the library compares cosines), on every pair path:
// the Euclidean fast path, the generic metric path, subsampling, Dowd's second pass.

#include "errfield/variogram_direction.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/empirical_variogram.hpp"
#include "pair_direction.hpp"

namespace errfield {
namespace variogram_direction_test {

constexpr double kDeg = 180.0 / std::numbers::pi;
// Sums of up to ~10^5 same-sign terms in a different order: relative difference < 1e-11.
constexpr double kSumTolerance = 1e-11;

// Angle (deg, in [0, 90]) between the axis through `dir_deg` and the one through `angle_deg`,
// both measured in the same plane: lines, so modulo 180.
double line_angle(double angle_deg, double dir_deg) {
  double d = std::fmod(std::fabs(angle_deg - dir_deg), 180.0);
  return std::min(d, 180.0 - d);
}

struct Brute {
  std::vector<std::uint64_t> count;
  std::vector<double> lag_mean, gamma;
  double closest_to_boundary_deg = 1e300;  // how close any pair came to a tolerance boundary
};

// Matheron over the pairs `accept(s)` keeps (s = x_i - x_j), bins [e_k, e_{k+1}), all components.
template <class Accept>
Brute brute_force(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const std::vector<double>& edges,
                  Accept accept) {
  const std::size_t B = edges.size() - 1;
  Brute r;
  r.count.assign(B, 0);
  std::vector<double> lag(B, 0.0), sq(B, 0.0);
  for (Eigen::Index i = 1; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) {
      const Eigen::VectorXd s = (x.row(i) - x.row(j)).transpose();
      double margin = 1e300;
      const bool keep = accept(s, margin);
      r.closest_to_boundary_deg = std::min(r.closest_to_boundary_deg, margin);
      if (!keep) continue;
      const double h = s.norm();
      for (std::size_t k = 0; k < B; ++k)
        if (h >= edges[k] && h < edges[k + 1]) {
          ++r.count[k];
          lag[k] += h;
          sq[k] += (z.row(i) - z.row(j)).squaredNorm();
        }
    }
  for (std::size_t k = 0; k < B; ++k) {
    r.lag_mean.push_back(lag[k] / static_cast<double>(r.count[k]));
    r.gamma.push_back(sq[k] / (2.0 * static_cast<double>(r.count[k])));
  }
  return r;
}

void expect_same(const EmpiricalVariogram& v, const Brute& b) {
  ASSERT_EQ(v.bins.size(), b.count.size());
  for (std::size_t k = 0; k < b.count.size(); ++k) {
    SCOPED_TRACE("bin " + std::to_string(k));
    EXPECT_EQ(v.bins[k].pairs, b.count[k]);
    if (b.count[k] == 0) continue;
    EXPECT_NEAR(v.bins[k].lag_mean, b.lag_mean[k], kSumTolerance * b.lag_mean[k]);
    EXPECT_NEAR(v.bins[k].gamma, b.gamma[k], kSumTolerance * b.gamma[k]);
  }
}

Eigen::MatrixXd random_points(int n, int d, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  Eigen::MatrixXd x(n, d);
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < d; ++a) x(i, a) = u(rng);
  return x;
}

Eigen::MatrixXd field(const Eigen::MatrixXd& x, int components, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 0.1);
  Eigen::MatrixXd z(x.rows(), components);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int c = 0; c < components; ++c)
      z(i, c) = std::sin(x(i, 0) / (10.0 + 5.0 * c)) + 0.3 * std::cos(x(i, x.cols() - 1) / 30.0) + g(rng);
  return z;
}

const std::vector<double> kEdges{0, 10, 20, 30, 45, 60, 80, 100};

TEST(VariogramDirection, GstatHorizontalMatchesBruteForceIn2D) {
  const Eigen::MatrixXd x = random_points(300, 2, 11);
  const Eigen::MatrixXd z = field(x, 1, 12);
  const auto bins = LagBins::from_edges(kEdges);
  for (double alpha : {0.0, 30.0, 90.0, 135.0, 200.0}) {
    for (double tol : {10.0, 22.5, 45.0}) {
      SCOPED_TRACE("alpha " + std::to_string(alpha) + " tol " + std::to_string(tol));
      EmpiricalVariogramOptions o;
      o.direction = VariogramDirection::gstat(alpha, tol);
      const auto brute = brute_force(x, z, kEdges, [&](const Eigen::VectorXd& s, double& margin) {
        const double a = line_angle(std::atan2(s(0), s(1)) * kDeg, alpha);  // clockwise from +y
        margin = std::fabs(a - tol);
        return a <= tol;
      });
      ASSERT_GT(brute.closest_to_boundary_deg, 1e-7) << "a pair lies on the boundary; pick other data";
      expect_same(empirical_variogram(x, z, bins, o), brute);
      // Generic metric path (weights 1: the same lags) and one thread give the same pairs.
      std::vector<Eigen::Vector2d> loc;
      for (Eigen::Index i = 0; i < x.rows(); ++i) loc.emplace_back(x(i, 0), x(i, 1));
      o.threads = 1;
      expect_same(empirical_variogram<Eigen::Vector2d>(std::span<const Eigen::Vector2d>(loc), z,
                                                       WeightedEuclideanMetric({1.0, 1.0}), bins, o),
                  brute);
    }
  }
}

TEST(VariogramDirection, GstatDipMatchesBruteForceIn3DWithVectorValues) {
  const Eigen::MatrixXd x = random_points(250, 3, 21);
  const Eigen::MatrixXd z = field(x, 3, 22);
  const auto bins = LagBins::from_edges(kEdges);
  struct Case { double alpha, tol_hor, beta, tol_ver; };
  for (const Case c : {Case{45, 22.5, 0, 90}, Case{45, 30, 30, 20}, Case{0, 90, 60, 25}, Case{120, 15, -20, 40}}) {
    SCOPED_TRACE("alpha " + std::to_string(c.alpha) + " beta " + std::to_string(c.beta));
    EmpiricalVariogramOptions o;
    o.direction = VariogramDirection::gstat(c.alpha, c.tol_hor, c.beta, c.tol_ver);
    const auto brute = brute_force(x, z, kEdges, [&](const Eigen::VectorXd& s, double& margin) {
      bool keep = true;
      if (c.tol_hor < 90) {
        const double a = line_angle(std::atan2(s(0), s(1)) * kDeg, c.alpha);
        margin = std::min(margin, std::fabs(a - c.tol_hor));
        keep = keep && a <= c.tol_hor;
      }
      if (c.tol_ver < 90) {  // dip of the pair, up from the horizontal plane
        const double dip = std::atan2(s(2), std::hypot(s(0), s(1))) * kDeg;
        const double a = line_angle(dip, c.beta);
        margin = std::min(margin, std::fabs(a - c.tol_ver));
        keep = keep && a <= c.tol_ver;
      }
      return keep;
    });
    ASSERT_GT(brute.closest_to_boundary_deg, 1e-7);
    const auto v = empirical_variogram(x, z, bins, o);
    expect_same(v, brute);
    std::uint64_t total = 0;
    for (const auto& b : v.bins) total += b.pairs;
    EXPECT_GT(total, 100u) << "too few pairs for the test to mean something";
  }
}

TEST(VariogramDirection, AxisConesIn6DMatchBruteForceAndPartitionAt45Degrees) {
  const Eigen::MatrixXd x = random_points(400, 6, 31);
  const Eigen::MatrixXd z = field(x, 1, 32);
  const auto bins = LagBins::from_edges(kEdges);
  EmpiricalVariogramOptions all;
  const auto omni = empirical_variogram(x, z, bins, all);
  std::vector<std::uint64_t> sum(kEdges.size() - 1, 0);
  for (int k = 0; k < 6; ++k) {
    SCOPED_TRACE("axis " + std::to_string(k));
    for (double tol : {30.0, 45.0}) {
      EmpiricalVariogramOptions o;
      o.direction = VariogramDirection::axis(k, 6, tol);
      const auto brute = brute_force(x, z, kEdges, [&](const Eigen::VectorXd& s, double& margin) {
        const double a = std::acos(std::fabs(s(k)) / s.norm()) * kDeg;
        margin = std::fabs(a - tol);
        return a <= tol;
      });
      ASSERT_GT(brute.closest_to_boundary_deg, 1e-7);
      const auto v = empirical_variogram(x, z, bins, o);
      expect_same(v, brute);
      if (tol == 45.0)
        for (std::size_t b = 0; b < sum.size(); ++b) sum[b] += v.bins[b].pairs;
    }
  }
  // 45-degree axis cones are disjoint; in 6-D they do not cover every direction.
  for (std::size_t b = 0; b < sum.size(); ++b) EXPECT_LE(sum[b], omni.bins[b].pairs);
}

TEST(VariogramDirection, FourSectorsPartitionThePairsIn2D) {
  const Eigen::MatrixXd x = random_points(200, 2, 41);
  const Eigen::MatrixXd z = field(x, 1, 42);
  const auto bins = LagBins::uniform(0, 150, 15);
  const auto omni = empirical_variogram(x, z, bins);
  std::vector<std::uint64_t> sum(bins.size(), 0);
  std::vector<double> sq(bins.size(), 0.0);
  for (double alpha : {0.0, 45.0, 90.0, 135.0}) {
    EmpiricalVariogramOptions o;
    o.direction = VariogramDirection::gstat(alpha, 22.5);
    const auto v = empirical_variogram(x, z, bins, o);
    for (std::size_t b = 0; b < sum.size(); ++b)
      if (v.bins[b].pairs) {
        sum[b] += v.bins[b].pairs;
        sq[b] += 2.0 * v.bins[b].gamma * static_cast<double>(v.bins[b].pairs);
      }
  }
  for (std::size_t b = 0; b < sum.size(); ++b) {
    EXPECT_EQ(sum[b], omni.bins[b].pairs);
    if (sum[b]) EXPECT_NEAR(sq[b], 2.0 * omni.bins[b].gamma * static_cast<double>(sum[b]), 1e-10 * sq[b]);
  }
}

TEST(VariogramDirection, SubsamplingAndDowdKeepTheSameDirectionalPairs) {
  const Eigen::MatrixXd x = random_points(200, 2, 51);
  const Eigen::MatrixXd z = field(x, 1, 52);
  const auto bins = LagBins::from_edges(kEdges);
  EmpiricalVariogramOptions o;
  o.direction = VariogramDirection::gstat(60.0, 20.0);
  const auto full = empirical_variogram(x, z, bins, o);
  // Dowd's second pass stores exactly the binned pairs of the first (it would overrun otherwise):
  // the median over a bin's pairs, recomputed here from the same filter.
  o.estimator = VariogramEstimator::Dowd;
  const auto dowd = empirical_variogram(x, z, bins, o);
  for (std::size_t k = 0; k < kEdges.size() - 1; ++k) {
    std::vector<double> d;
    for (Eigen::Index i = 1; i < x.rows(); ++i)
      for (Eigen::Index j = 0; j < i; ++j) {
        const double sx = x(i, 0) - x(j, 0), sy = x(i, 1) - x(j, 1);
        const double h = std::hypot(sx, sy);
        if (line_angle(std::atan2(sx, sy) * kDeg, 60.0) <= 20.0 && h >= kEdges[k] && h < kEdges[k + 1])
          d.push_back(std::fabs(z(i, 0) - z(j, 0)));
      }
    ASSERT_EQ(dowd.bins[k].pairs, d.size());
    ASSERT_EQ(full.bins[k].pairs, d.size());
    if (d.empty()) continue;
    std::sort(d.begin(), d.end());
    const double med = d.size() % 2 ? d[d.size() / 2] : 0.5 * (d[d.size() / 2 - 1] + d[d.size() / 2]);
    EXPECT_NEAR(dowd.bins[k].gamma, 1.099 * med * med, 1e-12 * dowd.bins[k].gamma);
  }
  o.estimator = VariogramEstimator::Matheron;
  o.pair_fraction = 0.5;
  const auto half = empirical_variogram(x, z, bins, o);
  for (std::size_t k = 0; k < half.bins.size(); ++k) EXPECT_LE(half.bins[k].pairs, full.bins[k].pairs);
}

// The block kernel (squares, no branch) against the per-pair rule it restates (cosines).
TEST(VariogramDirection, BlockMaskAgreesWithThePerPairRule) {
  const int n = 300;
  for (int d : {2, 3, 6}) {
    const Eigen::MatrixXd x = random_points(n, d, 70 + static_cast<std::uint64_t>(d));
    std::vector<double> soa(static_cast<std::size_t>(n * d));
    for (int a = 0; a < d; ++a)
      for (int i = 0; i < n; ++i) soa[static_cast<std::size_t>(a * n + i)] = x(i, a);
    std::vector<double> u(static_cast<std::size_t>(d), 0.0);
    u[0] = 0.6, u[1] = 0.8;
    kernels::DirectionCone cones[3];
    for (auto& c : cones) c.coordinates = soa.data(), c.n = n, c.dimension = d;
    cones[0].axis = u.data(), cones[0].cos_tol = std::cos(25.0 / kDeg);
    if (d <= 3) {
      cones[1].gstat = cones[2].gstat = true;
      cones[1].check_hor = true, cones[1].hor_x = std::sin(0.7), cones[1].hor_y = std::cos(0.7);
      cones[1].cos_tol_hor = std::cos(20.0 / kDeg);
      cones[2] = cones[1];
      cones[2].check_ver = d == 3, cones[2].ver_xy = std::cos(0.4), cones[2].ver_z = std::sin(0.4);
      cones[2].cos_tol_ver = std::cos(30.0 / kDeg);
    }
    for (int k = 0; k < (d <= 3 ? 3 : 1); ++k) {
      int kept = 0;
      for (std::size_t i = 1; i < static_cast<std::size_t>(n); ++i) {
        std::vector<double> h(i, 1.0);
        kernels::mask_directions(cones[k], i, 0, i, h.data());
        for (std::size_t j = 0; j < i; ++j) {
          double s[64];
          for (int a = 0; a < d; ++a) s[a] = soa[static_cast<std::size_t>(a * n) + i] - soa[static_cast<std::size_t>(a * n) + j];
          ASSERT_EQ(kernels::direction_accepts(cones[k], s), !std::isnan(h[j])) << "d " << d << " cone " << k;
          kept += !std::isnan(h[j]);
        }
      }
      EXPECT_GT(kept, 0);
    }
  }
}

TEST(VariogramDirection, RejectsDirectionsThatDoNotFitTheData) {
  const Eigen::MatrixXd x6 = random_points(20, 6, 61), x2 = random_points(20, 2, 62);
  const Eigen::MatrixXd z = field(x6, 1, 63);
  const auto bins = LagBins::from_edges(kEdges);
  EmpiricalVariogramOptions o;
  o.direction = VariogramDirection::gstat(0.0, 22.5);
  EXPECT_THROW(empirical_variogram(x6, z, bins, o), ArgumentError);  // alpha needs 2-D or 3-D
  o.direction = VariogramDirection::gstat(0.0, 22.5, 30.0, 10.0);
  EXPECT_THROW(empirical_variogram(x2, z, bins, o), ArgumentError);  // a dip needs 3-D
  o.direction = VariogramDirection::axis(2, 3, 30.0);
  EXPECT_THROW(empirical_variogram(x2, z, bins, o), ArgumentError);  // 3 entries for 2 coordinates
  EXPECT_THROW(VariogramDirection::gstat(0.0, 181.0), ArgumentError);
  EXPECT_THROW(VariogramDirection::gstat(0.0, -1.0), ArgumentError);
  EXPECT_THROW(VariogramDirection::along({0.0, 0.0}, 10.0), ArgumentError);
  EXPECT_THROW(VariogramDirection::axis(6, 6, 10.0), ArgumentError);
  EXPECT_EQ(VariogramDirection::gstat(45, 22.5).to_string(), "alpha=45,tol.hor=22.5");
}

}  // namespace
}  // namespace errfield
