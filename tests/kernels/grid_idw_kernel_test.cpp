#include "grid_idw_kernel.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace errfield::kernels {
namespace grid_idw_kernel_test {

struct Case {
  GridIdwGeometry g{};
  std::vector<double> nodes;
  std::vector<double> targets;  // row-major n x 3
  std::ptrdiff_t n = 0;
};

// An anisotropic grid (different steps and counts per axis) with random values, and random
// targets that reach `margin` cells outside the box on every side.
template <int C>
Case make_case(std::ptrdiff_t n, double margin, unsigned seed) {
  Case c;
  const double origin[3] = {-120.0, 35.5, 1000.0};
  const double step[3] = {40.0, 12.5, 77.0};
  const int count[3] = {6, 4, 9};
  for (int a = 0; a < 3; ++a) {
    c.g.origin[a] = origin[a];
    c.g.step[a] = step[a];
    c.g.inv_step[a] = 1.0 / step[a];
    c.g.count[a] = count[a];
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  c.nodes.resize(static_cast<std::size_t>(count[0] * count[1] * count[2] * C));
  for (auto& v : c.nodes) v = nd(rng);
  c.n = n;
  c.targets.resize(static_cast<std::size_t>(3 * n));
  for (std::ptrdiff_t t = 0; t < n; ++t)
    for (int a = 0; a < 3; ++a) {
      std::uniform_real_distribution<double> u(origin[a] - margin * step[a],
                                               origin[a] + (count[a] - 1 + margin) * step[a]);
      c.targets[static_cast<std::size_t>(3 * t + a)] = u(rng);
    }
  return c;
}

template <int C>
void expect_kernel_matches_reference(double power, bool clamp) {
  Case c = make_case<C>(3000, 0.7, 11);
  // Put some targets exactly on vertices to exercise the exact branch.
  for (std::ptrdiff_t t = 0; t < 50; ++t) {
    const int i = static_cast<int>(t % 6), j = static_cast<int>(t % 4), k = static_cast<int>(t % 9);
    c.targets[static_cast<std::size_t>(3 * t)] = c.g.origin[0] + i * c.g.step[0];
    c.targets[static_cast<std::size_t>(3 * t + 1)] = c.g.origin[1] + j * c.g.step[1];
    c.targets[static_cast<std::size_t>(3 * t + 2)] = c.g.origin[2] + k * c.g.step[2];
  }
  GridIdwParams p;
  p.power = power;
  p.clamp = clamp;
  p.vertex_tolerance_sq = 1e-18;
  p.boundary_tolerance = 1e-9;
  p.threads = 2;
  std::vector<double> fast(static_cast<std::size_t>(c.n * C)), slow(fast.size());
  std::vector<std::uint8_t> sf(static_cast<std::size_t>(c.n)), ss(sf.size());
  grid_idw<C>(c.g, p, c.nodes.data(), c.targets.data(), 3, 1, c.n, fast.data(), sf.data());
  grid_idw_reference<C>(c.g, p, c.nodes.data(), c.targets.data(), 3, 1, c.n, slow.data(), ss.data());
  int outside = 0, clamped = 0;
  for (std::ptrdiff_t t = 0; t < c.n; ++t) {
    const auto ti = static_cast<std::size_t>(t);
    ASSERT_EQ(sf[ti], ss[ti]) << "target " << t;
    outside += sf[ti] == kGridOutside;
    clamped += sf[ti] == kGridClamped;
    for (int k = 0; k < C; ++k) {
      const double a = fast[ti * C + k], b = slow[ti * C + k];
      if (sf[ti] == kGridOutside) {
        EXPECT_TRUE(std::isnan(a) && std::isnan(b));
      } else {
        // Same formula, different arithmetic (1/sqrt vs pow, offsets vs absolute positions):
        // agreement to a few hundred ulps of the value scale (~1).
        EXPECT_NEAR(a, b, 1e-13) << "target " << t << " component " << k;
      }
    }
  }
  if (clamp) {
    EXPECT_EQ(outside, 0);
    EXPECT_GT(clamped, 500);
  } else {
    EXPECT_GT(outside, 500);
  }
}

TEST(GridIdwKernel, MatchesNaiveReference) {
  for (bool clamp : {false, true}) {
    for (double power : {1.0, 2.0, 1.7, 0.0}) {
      SCOPED_TRACE(::testing::Message() << "power " << power << " clamp " << clamp);
      expect_kernel_matches_reference<1>(power, clamp);
      expect_kernel_matches_reference<3>(power, clamp);
    }
  }
}

TEST(GridIdwKernel, ColumnMajorTargetsGiveTheSameResult) {
  Case c = make_case<1>(500, 0.0, 12);
  std::vector<double> col(c.targets.size());
  for (std::ptrdiff_t t = 0; t < c.n; ++t)
    for (int a = 0; a < 3; ++a)
      col[static_cast<std::size_t>(t + a * c.n)] = c.targets[static_cast<std::size_t>(3 * t + a)];
  GridIdwParams p;
  std::vector<double> row_out(static_cast<std::size_t>(c.n)), col_out(row_out.size());
  grid_idw<1>(c.g, p, c.nodes.data(), c.targets.data(), 3, 1, c.n, row_out.data(), nullptr);
  grid_idw<1>(c.g, p, c.nodes.data(), col.data(), 1, c.n, c.n, col_out.data(), nullptr);
  EXPECT_EQ(row_out, col_out);
}

TEST(GridIdwKernel, IdenticalResultsForAnyThreadCount) {
  Case c = make_case<3>(20000, 0.2, 13);
  GridIdwParams p;
  p.clamp = true;
  p.power = 1.3;
  std::vector<std::vector<double>> results;
  for (int threads : {1, 2, 3, 5}) {
    p.threads = threads;
    std::vector<double> out(static_cast<std::size_t>(3 * c.n));
    grid_idw<3>(c.g, p, c.nodes.data(), c.targets.data(), 3, 1, c.n, out.data(), nullptr);
    results.push_back(std::move(out));
  }
  for (std::size_t r = 1; r < results.size(); ++r) EXPECT_EQ(results[r], results[0]) << r;
}

}  // namespace
}  // namespace errfield::kernels
