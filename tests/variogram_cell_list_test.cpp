// The empirical variogram's pair searches against the all-pairs loop and against a brute force
// over all pairs written here. The ordered cell list (kernels/pair_cells.hpp: directions, vector
// values, Dowd, subsampling, weighted metrics, more than 3 axes) visits the same pairs in the same
// order: bit for bit. The sorted columns (kernels/pair_columns.hpp: Euclidean, 1-3 axes, one
// component, Matheron or Cressie-Hawkins, every pair or a direction cone that does not depend on
// the pair's orientation) visit each pair in range once in another
// order: pair counts exactly, sums to the rounding of a different summation order (see
// order_tolerance). Small simulated data: uniform random locations, part of them on a lattice so
// that lags equal the cutoff and the bin edges, and points land on cell boundaries; duplicates
// included.

#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>
#include <tuple>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/empirical_variogram.hpp"
#include "pair_columns.hpp"

namespace errfield {
namespace variogram_cell_list_test {

// n locations in [0, 1]^D: a third on the lattice of step `step` (lags that are exact multiples of
// it, so equal to edges and cutoffs chosen as multiples), a tenth duplicating earlier rows, the
// rest uniform. Simulated.
Eigen::MatrixXd simulated_locations(std::size_t n, int dimension, double step, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(static_cast<Eigen::Index>(n), dimension);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const int kind = static_cast<int>(i % 10);
    if (kind == 9 && i > 0) {
      x.row(i) = x.row(static_cast<Eigen::Index>(rng() % static_cast<std::uint64_t>(i)));
      continue;
    }
    for (int a = 0; a < dimension; ++a) {
      const double r = u(rng);
      x(i, a) = kind < 3 ? std::round(r / step) * step : r;
    }
  }
  return x;
}

Eigen::MatrixXd simulated_values(std::size_t n, int components, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd v(static_cast<Eigen::Index>(n), components);
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    for (int c = 0; c < components; ++c) v(i, c) = g(rng) + 0.3 * std::sin(static_cast<double>(i));
  return v;
}

EmpiricalVariogram run(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const LagBins& bins,
                       EmpiricalVariogramOptions o, PairSearch search, int threads = 2) {
  o.pair_search = search;
  o.threads = threads;
  return empirical_variogram(x, z, bins, o);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_bit_identical(const EmpiricalVariogram& a, const EmpiricalVariogram& b) {
  ASSERT_EQ(a.bins.size(), b.bins.size());
  ASSERT_EQ(a.components(), b.components());
  for (std::size_t k = 0; k < a.bins.size(); ++k) {
    SCOPED_TRACE("bin " + std::to_string(k));
    EXPECT_EQ(a.bins[k].pairs, b.bins[k].pairs);
    EXPECT_TRUE(same_bits(a.bins[k].gamma, b.bins[k].gamma)) << a.bins[k].gamma << " vs " << b.bins[k].gamma;
    EXPECT_TRUE(same_bits(a.bins[k].lag_mean, b.bins[k].lag_mean))
        << a.bins[k].lag_mean << " vs " << b.bins[k].lag_mean;
    for (int c = 0; c < a.components(); ++c)
      EXPECT_TRUE(same_bits(a.component_gamma(static_cast<Eigen::Index>(k), c),
                            b.component_gamma(static_cast<Eigen::Index>(k), c)));
  }
}

// Matheron over every pair (i, j < i), written out: h = sqrt(sum_a w_a d_a^2) in axis order (the
// library's arithmetic, so the bin of a lag equal to an edge is decided identically), bins by the
// comparison rule, sums in pair order.
struct BruteForce {
  std::vector<std::uint64_t> pairs;
  std::vector<double> lag_mean, gamma;
};

// `keep` (optional): whether the pair with separation s = x_i - x_j (x.cols() entries) counts.
BruteForce brute_force(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const std::vector<double>& e,
                       bool gstat, const std::vector<double>& weights = {},
                       const std::function<bool(const double*)>& keep = {}) {
  const std::size_t bins = e.size() - 1;
  BruteForce r{std::vector<std::uint64_t>(bins, 0), std::vector<double>(bins, 0.0),
               std::vector<double>(bins, 0.0)};
  for (Eigen::Index i = 1; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) {
      double s = 0.0;
      for (Eigen::Index a = 0; a < x.cols(); ++a) {
        const double d = x(i, a) - x(j, a);
        s += weights.empty() ? d * d : weights[static_cast<std::size_t>(a)] * d * d;
      }
      const double h = std::sqrt(s);
      if (keep) {
        double sep[64];
        for (Eigen::Index a = 0; a < x.cols(); ++a) sep[a] = x(i, a) - x(j, a);
        if (!keep(sep)) continue;
      }
      for (std::size_t k = 0; k < bins; ++k) {
        const bool in = gstat ? (k == 0 ? h >= e[0] && h <= e[1] : h > e[k] && h <= e[k + 1])
                              : h >= e[k] && h < e[k + 1];
        if (!in) continue;
        r.pairs[k] += 1;
        r.lag_mean[k] += h;
        for (Eigen::Index c = 0; c < z.cols(); ++c) {
          const double d = z(i, c) - z(j, c);
          r.gamma[k] += d * d;
        }
        break;
      }
    }
  for (std::size_t k = 0; k < bins; ++k) {
    const double m = static_cast<double>(r.pairs[k]);
    r.lag_mean[k] /= m;
    r.gamma[k] /= 2.0 * m;
  }
  return r;
}

// Two sums of the same m >= 1 non-negative terms in different orders (chunks, slot copies) each
// lie within (m - 1) u S of the exact sum S (u = 2^-53, Higham's bound for recursive summation in
// any order), so they differ by at most 2 m u S; gamma and the mean lag add one division each, and
// Cressie-Hawkins raises a mean to the 4th power (4 times its relative error). Hence 8 (m + 2) u,
// relative: rounding-level, ~1e-11 for the few thousand pairs per bin here.
double order_tolerance(std::uint64_t pairs) {
  return 8.0 * (static_cast<double>(pairs) + 2.0) * std::ldexp(1.0, -53);
}

void expect_matches_brute_force(const EmpiricalVariogram& v, const BruteForce& r) {
  ASSERT_EQ(v.bins.size(), r.pairs.size());
  for (std::size_t k = 0; k < r.pairs.size(); ++k) {
    SCOPED_TRACE("bin " + std::to_string(k));
    EXPECT_EQ(v.bins[k].pairs, r.pairs[k]);
    if (r.pairs[k] == 0) continue;
    const double tol = order_tolerance(r.pairs[k]);
    EXPECT_NEAR(v.bins[k].lag_mean, r.lag_mean[k], tol * r.lag_mean[k]);
    EXPECT_NEAR(v.bins[k].gamma, r.gamma[k], tol * r.gamma[k]);
  }
}

// The same pairs in every bin (counts exactly) and the same sums up to the summation order.
void expect_equal_to_rounding(const EmpiricalVariogram& a, const EmpiricalVariogram& b) {
  ASSERT_EQ(a.bins.size(), b.bins.size());
  ASSERT_EQ(a.components(), b.components());
  for (std::size_t k = 0; k < a.bins.size(); ++k) {
    SCOPED_TRACE("bin " + std::to_string(k));
    ASSERT_EQ(a.bins[k].pairs, b.bins[k].pairs);
    if (a.bins[k].pairs == 0) {
      EXPECT_TRUE(std::isnan(a.bins[k].gamma) && std::isnan(b.bins[k].gamma));
      continue;
    }
    const double tol = order_tolerance(a.bins[k].pairs);
    EXPECT_NEAR(a.bins[k].lag_mean, b.bins[k].lag_mean, tol * b.bins[k].lag_mean);
    EXPECT_NEAR(a.bins[k].gamma, b.bins[k].gamma, tol * b.bins[k].gamma);
    for (int c = 0; c < a.components(); ++c) {
      const double g = b.component_gamma(static_cast<Eigen::Index>(k), c);
      EXPECT_NEAR(a.component_gamma(static_cast<Eigen::Index>(k), c), g, tol * g);
    }
  }
}

// Whether empirical_variogram takes the sorted columns for these inputs (when a cell list is
// forced): the fast path's conditions, documented in empirical_variogram.hpp. Every direction
// but gstat's dip test with a nonzero dip (which depends on the pair's orientation).
bool takes_columns(int dimension, int components, const EmpiricalVariogramOptions& o) {
  const VariogramDirection& d = o.direction;
  const bool oriented = d.kind() == VariogramDirection::Kind::Gstat && d.tol_ver_deg() < 90.0 &&
                        d.beta_deg() != 0.0 && dimension == 3;
  return dimension <= 3 && components == 1 && !oriented && o.pair_fraction == 1.0 &&
         o.estimator != VariogramEstimator::Dowd;
}

// The direction rule of docs/geostatistics.md ("Directional variograms") restated for one pair
// s = x_i - x_j as the library decides it in floating point: squared cosines against the squared
// cosine of the tolerance, no test at 90 degrees or more. On a lattice many pairs lie exactly on
// a tolerance boundary (45 degrees); rounding then decides, and every pair loop must decide alike.
bool in_cone(const VariogramDirection& d, const double* s, int dimension) {
  constexpr double kRad = std::numbers::pi / 180.0;
  if (d.kind() == VariogramDirection::Kind::Gstat) {
    const double norm2 = s[0] * s[0] + s[1] * s[1];
    if (d.tol_hor_deg() < 90.0) {
      const double dot = s[0] * std::sin(d.alpha_deg() * kRad) + s[1] * std::cos(d.alpha_deg() * kRad);
      const double c = std::cos(d.tol_hor_deg() * kRad);
      if (!(dot * dot >= c * c * norm2)) return false;
    }
    if (d.tol_ver_deg() < 90.0 && dimension == 3) {
      const double v = std::sqrt(norm2) * std::cos(d.beta_deg() * kRad) + s[2] * std::sin(d.beta_deg() * kRad);
      const double c = std::cos(d.tol_ver_deg() * kRad);
      if (!(v * v >= c * c * (norm2 + s[2] * s[2]))) return false;
    }
    return true;
  }
  if (d.kind() == VariogramDirection::Kind::All || d.tol_deg() >= 90.0) return true;
  double dot = 0.0, norm2 = 0.0;
  for (int a = 0; a < dimension; ++a) {
    dot += s[a] * d.unit()[static_cast<std::size_t>(a)];
    norm2 += s[a] * s[a];
  }
  const double c = std::cos(d.tol_deg() * kRad);
  return dot * dot >= c * c * norm2;
}

// Bit for bit where the ordered cell list runs, to rounding where the sorted columns do.
void expect_as_all_pairs(const EmpiricalVariogram& cells, const EmpiricalVariogram& all, bool columns) {
  if (columns) expect_equal_to_rounding(cells, all);
  else expect_bit_identical(cells, all);
}

TEST(VariogramCellList, EqualsAllPairsAndBruteForceInOneToSixDimensionsForCutoffsUpToTheExtent) {
  for (int dimension : {1, 2, 3, 4, 6}) {
    const std::size_t n = dimension == 1 ? 300 : 500;
    const Eigen::MatrixXd x = simulated_locations(n, dimension, 0.05, 11 + dimension);
    const Eigen::MatrixXd z = simulated_values(n, 1, 3 + dimension);
    // Cutoffs 0.05 .. 1 of the extent, multiples of the lattice step: lattice lags hit them exactly.
    for (double cutoff : {0.05, 0.1, 0.25, 0.5, 1.0}) {
      for (auto convention : {BinConvention::HalfOpen, BinConvention::Gstat}) {
        SCOPED_TRACE("D=" + std::to_string(dimension) + " cutoff " + std::to_string(cutoff) + " " +
                     std::string(convention_name(convention)));
        const LagBins bins = LagBins::uniform(0.0, cutoff, cutoff / 5.0);
        EmpiricalVariogramOptions o;
        o.convention = convention;
        const EmpiricalVariogram cells = run(x, z, bins, o, PairSearch::CellList);
        expect_as_all_pairs(cells, run(x, z, bins, o, PairSearch::AllPairs), takes_columns(dimension, 1, o));
        expect_matches_brute_force(cells, brute_force(x, z, bins.edges(), convention == BinConvention::Gstat));
        std::uint64_t in_range = 0;
        for (const auto& b : cells.bins) in_range += b.pairs;
        EXPECT_GT(in_range, 0u);
      }
    }
  }
}

TEST(VariogramCellList, LatticeWithCutoffEqualToTheCellSideKeepsEveryPairAtTheCutoff) {
  // A 9 x 9 lattice of step 0.125 (exact in binary) and a cutoff of exactly 0.125: the 2 x 8 x 9
  // axis-neighbour pairs have lag exactly 0.125 = the last edge, and their points sit in adjacent
  // cells, each within 1e-6 of a cell boundary. Under gstat's convention the last bin (0.0625,
  // 0.125] holds exactly those pairs; under the half-open one no bin does.
  Eigen::MatrixXd x(81, 2);
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) x.row(a * 9 + b) << 0.125 * a, 0.125 * b;
  const Eigen::MatrixXd z = simulated_values(81, 1, 5);
  const LagBins bins = LagBins::from_edges({0.0, 0.0625, 0.125});
  for (auto convention : {BinConvention::Gstat, BinConvention::HalfOpen}) {
    EmpiricalVariogramOptions o;
    o.convention = convention;
    const EmpiricalVariogram cells = run(x, z, bins, o, PairSearch::CellList);
    expect_equal_to_rounding(cells, run(x, z, bins, o, PairSearch::AllPairs));  // sorted columns
    expect_matches_brute_force(cells, brute_force(x, z, bins.edges(), convention == BinConvention::Gstat));
    EXPECT_EQ(cells.bins[0].pairs, 0u);
    EXPECT_EQ(cells.bins[1].pairs, convention == BinConvention::Gstat ? 144u : 0u);
  }
}

TEST(VariogramCellList, EqualsAllPairsForDirectionsVectorValuesEstimatorsAndSubsampling) {
  struct Case {
    int dimension;
    VariogramDirection direction;
  };
  const std::vector<Case> cases = {
      {2, VariogramDirection::gstat(30.0, 22.5)},
      {3, VariogramDirection::gstat(45.0, 22.5, 30.0, 20.0)},
      {6, VariogramDirection::axis(1, 6, 30.0)},
      {3, VariogramDirection()},
  };
  for (const Case& c : cases) {
    const Eigen::MatrixXd x = simulated_locations(400, c.dimension, 0.05, 21 + c.dimension);
    for (int components : {1, 3, 2}) {
      const Eigen::MatrixXd z = simulated_values(400, components, 9 + components);
      for (auto estimator : {VariogramEstimator::Matheron, VariogramEstimator::CressieHawkins,
                             VariogramEstimator::Dowd})
        for (double fraction : {1.0, 0.5}) {
          if (fraction < 1.0 && estimator != VariogramEstimator::Matheron) continue;  // CI time
          SCOPED_TRACE("D=" + std::to_string(c.dimension) + " K=" + std::to_string(components) + " " +
                       std::string(estimator_name(estimator)) + " fraction " + std::to_string(fraction));
          EmpiricalVariogramOptions o;
          o.direction = c.direction;
          o.estimator = estimator;
          o.pair_fraction = fraction;
          o.seed = 17;
          const LagBins bins = LagBins::uniform(0.0, 0.3, 0.05);
          expect_as_all_pairs(run(x, z, bins, o, PairSearch::CellList),
                              run(x, z, bins, o, PairSearch::AllPairs),
                              takes_columns(c.dimension, components, o));
        }
    }
  }
}

// Directional variograms on the sorted columns (issue 36): on integer lattices in 2-D and 3-D,
// where pairs lie exactly on 45-degree boundaries and on the axes, the same pairs as the all-pairs
// loop and as the rule restated here (counts exactly, sums to rounding); gstat's dip test with a
// nonzero dip keeps the ordered cell list (bit for bit). A tolerance of 90 degrees keeps every
// pair, the ones at right angles included.
TEST(VariogramCellList, DirectionsOnTheSortedColumnsKeepThePairsOnTheToleranceBoundaryAlike) {
  struct Case {
    int dimension;
    VariogramDirection direction;
  };
  const std::vector<Case> cases = {
      {2, VariogramDirection::gstat(0.0, 45.0)},    {2, VariogramDirection::gstat(45.0, 45.0)},
      {2, VariogramDirection::gstat(0.0, 0.0)},    {2, VariogramDirection::gstat(90.0, 22.5)},
      {2, VariogramDirection::gstat(135.0, 22.5)},  {2, VariogramDirection::gstat(30.0, 90.0)},
      {2, VariogramDirection::along({1.0, 1.0}, 45.0)}, {2, VariogramDirection::axis(0, 2, 45.0)},
      {2, VariogramDirection::along({1.0, 0.0}, 90.0)}, {3, VariogramDirection::gstat(0.0, 45.0, 0.0, 45.0)},
      {3, VariogramDirection::gstat(90.0, 90.0, 0.0, 45.0)}, {3, VariogramDirection::axis(2, 3, 45.0)},
      {3, VariogramDirection::along({1.0, 1.0, 1.0}, 30.0)}, {3, VariogramDirection::gstat(45.0, 45.0, 30.0, 20.0)},
  };
  // SIMULATED values on a 24 x 24 (2-D) or 10 x 10 x 6 (3-D) integer lattice, cutoff 5.
  auto lattice = [](int dimension) {
    const int nx = dimension == 2 ? 24 : 10, ny = nx, nz = dimension == 2 ? 1 : 6;
    Eigen::MatrixXd x(nx * ny * nz, dimension);
    Eigen::Index r = 0;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i, ++r) {
          x(r, 0) = i;
          x(r, 1) = j;
          if (dimension == 3) x(r, 2) = k;
        }
    return x;
  };
  const LagBins bins = LagBins::uniform(0.0, 5.0, 1.0);
  for (const Case& c : cases) {
    SCOPED_TRACE("D=" + std::to_string(c.dimension) + " " + c.direction.to_string());
    const Eigen::MatrixXd x = lattice(c.dimension);
    const Eigen::MatrixXd z = simulated_values(static_cast<std::size_t>(x.rows()), 1, 71);
    EmpiricalVariogramOptions o;
    o.convention = BinConvention::Gstat;  // lags equal to the edges (1, 2, ..., 5) count
    o.direction = c.direction;
    const EmpiricalVariogram fast = run(x, z, bins, o, PairSearch::CellList);
    expect_as_all_pairs(fast, run(x, z, bins, o, PairSearch::AllPairs), takes_columns(c.dimension, 1, o));
    const BruteForce brute = brute_force(x, z, bins.edges(), true, {}, [&](const double* s) {
      return in_cone(c.direction, s, c.dimension);
    });
    expect_matches_brute_force(fast, brute);
    std::uint64_t kept = 0, omni = 0;
    for (const auto& b : fast.bins) kept += b.pairs;
    EmpiricalVariogramOptions every = o;
    every.direction = VariogramDirection();
    for (const auto& b : run(x, z, bins, every, PairSearch::AllPairs).bins) omni += b.pairs;
    EXPECT_GT(kept, 0u);
    const bool everything = c.direction.kind() == VariogramDirection::Kind::Gstat
                                ? c.direction.tol_hor_deg() >= 90.0 && c.direction.tol_ver_deg() >= 90.0
                                : c.direction.tol_deg() >= 90.0;
    if (everything) EXPECT_EQ(kept, omni);
    else EXPECT_LT(kept, omni);
  }
}

TEST(VariogramCellList, WeightedMetricEqualsAllPairsAndBruteForceIncludingAZeroWeight) {
  const std::size_t n = 400;
  const Eigen::MatrixXd x = simulated_locations(n, 3, 0.05, 31);
  const Eigen::MatrixXd z = simulated_values(n, 1, 32);
  std::vector<Eigen::Vector3d> loc(n);
  for (std::size_t i = 0; i < n; ++i) loc[i] = x.row(static_cast<Eigen::Index>(i)).transpose();
  for (const std::vector<double>& w : {std::vector<double>{1.0, 4.0, 0.25}, std::vector<double>{9.0, 0.0, 1.0}}) {
    SCOPED_TRACE("weights " + std::to_string(w[0]) + " " + std::to_string(w[1]) + " " + std::to_string(w[2]));
    const WeightedEuclideanMetric metric(w);
    const LagBins bins = LagBins::uniform(0.0, 0.2, 0.04);
    EmpiricalVariogramOptions o;
    o.threads = 2;
    auto with = [&](PairSearch s) {
      o.pair_search = s;
      return empirical_variogram<Eigen::Vector3d, WeightedEuclideanMetric>(
          std::span<const Eigen::Vector3d>(loc), z, metric, bins, o);
    };
    const EmpiricalVariogram cells = with(PairSearch::CellList);
    expect_bit_identical(cells, with(PairSearch::AllPairs));
    expect_matches_brute_force(cells, brute_force(x, z, bins.edges(), false, w));
  }
}

TEST(VariogramCellList, BitIdenticalForOneAndTwoThreads) {
  const Eigen::MatrixXd x = simulated_locations(600, 3, 0.05, 41);
  const Eigen::MatrixXd z = simulated_values(600, 3, 42);
  const LagBins bins = LagBins::uniform(0.0, 0.2, 0.02);
  for (auto estimator : {VariogramEstimator::Matheron, VariogramEstimator::Dowd}) {
    EmpiricalVariogramOptions o;
    o.estimator = estimator;
    expect_bit_identical(run(x, z, bins, o, PairSearch::CellList, 1), run(x, z, bins, o, PairSearch::CellList, 2));
  }
}

TEST(VariogramCellList, SortedColumnsBitIdenticalForOneTwoAndThreeThreads) {
  const Eigen::MatrixXd x = simulated_locations(600, 3, 0.05, 43);
  const Eigen::MatrixXd z = simulated_values(600, 1, 44);
  const LagBins bins = LagBins::uniform(0.0, 0.2, 0.02);
  for (auto estimator : {VariogramEstimator::Matheron, VariogramEstimator::CressieHawkins}) {
    EmpiricalVariogramOptions o;
    o.estimator = estimator;
    const EmpiricalVariogram one = run(x, z, bins, o, PairSearch::CellList, 1);
    expect_bit_identical(one, run(x, z, bins, o, PairSearch::CellList, 2));
    expect_bit_identical(one, run(x, z, bins, o, PairSearch::CellList, 3));
  }
}

// The AVX-512 column kernel adds the same pairs in the same order to the same slot copies as the
// portable one: equal sums bit for bit, for a whole range of rows and for uneven chunks of it.
TEST(VariogramCellList, SortedColumnsAvx512KernelEqualsPortableKernelBitForBit) {
  if (!kernels::kernel_isa_supported(kernels::KernelIsa::Avx512)) GTEST_SKIP() << "no AVX-512 on this CPU";
  const std::size_t n = 700;
  for (int dimension : {1, 2, 3}) {
    const Eigen::MatrixXd x = simulated_locations(n, dimension, 0.05, 61 + dimension);
    const Eigen::MatrixXd z = simulated_values(n, 1, 62);
    std::vector<double> axis_major(n * static_cast<std::size_t>(dimension));
    for (std::size_t i = 0; i < n; ++i)
      for (int a = 0; a < dimension; ++a)
        axis_major[static_cast<std::size_t>(a) * n + i] = x(static_cast<Eigen::Index>(i), a);
    const LagBins bins = LagBins::uniform(0.0, 0.15, 0.01);
    detail::VariogramColumns columns;
    ASSERT_TRUE(detail::build_variogram_columns(axis_major.data(), z.data(), n, dimension, 0.15, true, 1.0, columns));
    // Every direction, and a direction cone on the sorted coordinates (gstat's in 2-D and 3-D, a
    // vector's in any dimension).
    std::vector<VariogramDirection> directions{VariogramDirection(), VariogramDirection::axis(0, dimension, 40.0)};
    if (dimension == 2) directions.push_back(VariogramDirection::gstat(30.0, 20.0));
    if (dimension == 3) directions.push_back(VariogramDirection::gstat(30.0, 20.0, 0.0, 30.0));
    std::vector<kernels::DirectionCone> cones;
    for (const VariogramDirection& d : directions)
      cones.push_back(detail::variogram_direction_cone(d, columns.coordinates.data(), n, dimension));
    for (std::size_t cone = 0; cone < cones.size(); ++cone) {
      for (bool gstat : {false, true})
        for (auto statistic : {kernels::PairStatistic::SquaredDifference, kernels::PairStatistic::RootAbsDifference}) {
          SCOPED_TRACE("D=" + std::to_string(dimension) + (gstat ? " gstat " : " paper ") + directions[cone].to_string());
          columns.list.cone = directions[cone].is_all() ? nullptr : &cones[cone];
          EmpiricalVariogramOptions o;
          o.convention = gstat ? BinConvention::Gstat : BinConvention::HalfOpen;
          const kernels::BinLayout layout = detail::variogram_bin_layout(bins, o);
          const std::size_t B = bins.size() + 1;
          auto sums = [&](kernels::KernelIsa isa, std::size_t chunks) {
            std::vector<std::uint64_t> count(B, 0);
            std::vector<double> lag(B, 0.0), stat(B, 0.0);
            alignas(64) static double slots[kernels::column_slot_doubles(64)];
            for (std::size_t c = 0; c < chunks; ++c)
              detail::run_column_chunk(isa, columns.list, layout, statistic, n * c / chunks, n * (c + 1) / chunks,
                                       slots, kernels::PairSums{count.data(), lag.data(), stat.data()});
            std::uint64_t total = 0;
            for (std::size_t k = 0; k < bins.size(); ++k) total += count[k];
            EXPECT_GT(total, 0u);
            return std::make_tuple(count, lag, stat);
          };
          for (std::size_t chunks : {std::size_t{1}, std::size_t{7}}) {
            const auto [c0, l0, s0] = sums(kernels::KernelIsa::Baseline, chunks);
            const auto [c1, l1, s1] = sums(kernels::KernelIsa::Avx512, chunks);
            for (std::size_t k = 0; k < B; ++k) {
              EXPECT_EQ(c0[k], c1[k]);
              EXPECT_TRUE(same_bits(l0[k], l1[k])) << l0[k] << " vs " << l1[k];
              EXPECT_TRUE(same_bits(s0[k], s1[k])) << s0[k] << " vs " << s1[k];
            }
          }
        }
    }
  }
}

TEST(VariogramCellList, AutomaticChoiceTakesTheSortedColumnsForEnoughPointsAndAnyCutoffWithAvx512) {
  const std::size_t n = 2000;
  const Eigen::MatrixXd x = simulated_locations(n, 3, 0.05, 53);
  const Eigen::MatrixXd z = simulated_values(n, 1, 54);
  auto chooses = [&](double cutoff, std::size_t points, bool force, kernels::KernelIsa isa) {
    std::vector<double> axis_major(3 * points);
    for (std::size_t i = 0; i < points; ++i)
      for (std::size_t a = 0; a < 3; ++a)
        axis_major[a * points + i] = x(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(a));
    detail::VariogramColumns columns;
    return detail::build_variogram_columns(axis_major.data(), z.data(), points, 3, cutoff, force,
                                           detail::column_max_share(isa), columns);
  };
  using kernels::KernelIsa;
  EXPECT_TRUE(chooses(0.1, n, false, KernelIsa::Baseline));
  EXPECT_FALSE(chooses(1.0, n, false, KernelIsa::Baseline));   // portable kernel: all pairs is faster
  EXPECT_TRUE(chooses(1.0, n, false, KernelIsa::Avx512));      // AVX-512: never slower than all pairs
  EXPECT_FALSE(chooses(0.1, 500, false, KernelIsa::Avx512));   // too few points to pay for the sorting
  EXPECT_TRUE(chooses(1.0, 500, true, KernelIsa::Baseline));   // forced: one column, sorted, still exact
}

TEST(VariogramCellList, AutomaticChoiceTakesTheCellListOnlyForShortCutoffsAndEnoughPoints) {
  const std::size_t n = 2000;
  const Eigen::MatrixXd x = simulated_locations(n, 3, 0.05, 51);
  auto chooses = [&](double cutoff, std::size_t points, bool force) {
    std::vector<double> axis_major(3 * points);
    for (std::size_t i = 0; i < points; ++i)
      for (std::size_t a = 0; a < 3; ++a)
        axis_major[a * points + i] = x(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(a));
    detail::VariogramCells cells;
    return detail::build_variogram_cells(axis_major.data(), points, 3, std::vector<double>(3, cutoff),
                                         force, cells);
  };
  EXPECT_TRUE(chooses(0.1, n, false));
  EXPECT_FALSE(chooses(0.6, n, false));        // 2 cells per axis: nothing to skip
  EXPECT_FALSE(chooses(0.1, 500, false));      // too few points to pay for the grid
  EXPECT_TRUE(chooses(0.1, 500, true));
  EXPECT_FALSE(chooses(1.0, n, true));         // one cell per axis: not even forced
  // And the automatic result is the all-pairs one.
  const Eigen::MatrixXd z = simulated_values(n, 1, 52);
  const LagBins bins = LagBins::uniform(0.0, 0.1, 0.01);
  expect_equal_to_rounding(run(x, z, bins, {}, PairSearch::Automatic), run(x, z, bins, {}, PairSearch::AllPairs));
}

}  // namespace variogram_cell_list_test
}  // namespace errfield
