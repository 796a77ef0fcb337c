#include "errfield/grid_idw.hpp"

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace errfield {
namespace grid_idw_test {

using ::testing::HasSubstr;

// The paper's grid: 500 mm cube, 125 mm step, 5 x 5 x 5 nodes.
const RegularGrid3 kPaperGrid({0, 0, 0}, {125, 125, 125}, {5, 5, 5});

std::vector<double> node_values_of(const RegularGrid3& g, const std::function<double(const Eigen::Vector3d&)>& f) {
  std::vector<double> v(g.node_count());
  for (std::size_t n = 0; n < v.size(); ++n) v[n] = f(g.node_position(n));
  return v;
}

Eigen::MatrixXd random_targets(const RegularGrid3& g, int n, unsigned seed, double margin = 0.0) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd t(n, 3);
  for (int a = 0; a < 3; ++a) {
    std::uniform_real_distribution<double> u(g.lower()[a] - margin, g.upper()[a] + margin);
    for (int i = 0; i < n; ++i) t(i, a) = u(rng);
  }
  return t;
}

TEST(GridIdw, ReproducesAConstantFieldToRounding) {
  const std::vector<double> v(kPaperGrid.node_count(), 0.3141);
  for (double p : {0.0, 1.0, 2.0, 3.5}) {
    GridIdwOptions o;
    o.power = p;
    const GridIdw<double> idw(kPaperGrid, v, o);
    const auto pred = idw.predict(random_targets(kPaperGrid, 2000, 1));
    // A weighted mean of equal values: exact up to the rounding of the sums (a few ulps).
    for (double x : pred) EXPECT_DOUBLE_EQ(x, 0.3141) << "p = " << p;
  }
  const std::vector<Eigen::Vector3d> v3(kPaperGrid.node_count(), Eigen::Vector3d(0.1, -0.2, 0.05));
  const GridIdw<Eigen::Vector3d> idw3(kPaperGrid, v3);
  for (const auto& x : idw3.predict(random_targets(kPaperGrid, 500, 2))) {
    EXPECT_DOUBLE_EQ(x.x(), 0.1);
    EXPECT_DOUBLE_EQ(x.y(), -0.2);
    EXPECT_DOUBLE_EQ(x.z(), 0.05);
  }
}

TEST(GridIdw, ExactAtEveryVertexAndWithinTheVertexTolerance) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0, 0.5);
  std::vector<double> v(kPaperGrid.node_count());
  for (auto& x : v) x = g(rng);
  const GridIdw<double> idw(kPaperGrid, v);
  for (std::size_t n = 0; n < v.size(); ++n) {
    const Eigen::Vector3d p = kPaperGrid.node_position(n);
    EXPECT_EQ(idw(p), v[n]) << n;
    // 1e-10 of the step is inside the default vertex tolerance (1e-9 of the step).
    EXPECT_EQ(idw(p + Eigen::Vector3d(125e-10, -125e-10, 0)), v[n]) << n;
  }
}

TEST(GridIdw, LinearFieldAlongACellEdgeMatchesClosedForm) {
  // f = 2 + 0.01 x. A target on the edge y = z = 125 of cell (1, 1, 1) at x = 125 + s h, h = 125:
  // the four x0-side vertices are at distances s h, sqrt(s^2 + 1) h (twice), sqrt(s^2 + 2) h, and
  // symmetrically with 1 - s on the x1 side (SPEC eq. 20 with p = 1).
  const auto v = node_values_of(kPaperGrid, [](const Eigen::Vector3d& p) { return 2.0 + 0.01 * p.x(); });
  const GridIdw<double> idw(kPaperGrid, v);
  for (double s : {0.1, 0.25, 0.5, 0.8}) {
    auto side = [](double t) { return 1.0 / t + 2.0 / std::sqrt(t * t + 1.0) + 1.0 / std::sqrt(t * t + 2.0); };
    const double w0 = side(s), w1 = side(1.0 - s);
    const double f0 = 2.0 + 0.01 * 125, f1 = 2.0 + 0.01 * 250;
    const double expected = (w0 * f0 + w1 * f1) / (w0 + w1);
    EXPECT_NEAR(idw({125 + s * 125, 125, 125}), expected, 1e-14) << s;
  }
  // By symmetry the mid-plane of a cell and its centre give the mean of the two planes' values,
  // for every power, and IDW never leaves the range of the vertex values.
  for (double p : {0.5, 1.0, 2.0, 4.0}) {
    GridIdwOptions o;
    o.power = p;
    const GridIdw<double> q(kPaperGrid, v, o);
    EXPECT_NEAR(q({187.5, 140, 333}), 2.0 + 0.01 * 187.5, 1e-14) << p;
    EXPECT_NEAR(q({437.5, 437.5, 62.5}), 2.0 + 0.01 * 437.5, 1e-14) << p;
    const double inside = q({130, 10, 10});
    EXPECT_GT(inside, 2.0 + 0.01 * 125);
    EXPECT_LT(inside, 2.0 + 0.01 * 250);
  }
}

TEST(GridIdw, PowerTwoOnAFaceDiagonalMatchesClosedForm) {
  // One cell, values 1 at vertex (0,0,0) and 0 elsewhere: the result is w_000 / sum w.
  const RegularGrid3 g({0, 0, 0}, {1, 1, 1}, {2, 2, 2});
  std::vector<double> v(8, 0.0);
  v[0] = 1.0;
  GridIdwOptions o;
  o.power = 2.0;
  const GridIdw<double> idw(g, v, o);
  const double a = 0.3;  // target (a, a, 0)
  const double d2[8] = {2 * a * a,
                        (1 - a) * (1 - a) + a * a,
                        a * a + (1 - a) * (1 - a),
                        2 * (1 - a) * (1 - a),
                        2 * a * a + 1,
                        (1 - a) * (1 - a) + a * a + 1,
                        a * a + (1 - a) * (1 - a) + 1,
                        2 * (1 - a) * (1 - a) + 1};
  double sum = 0;
  for (double d : d2) sum += 1.0 / d;
  EXPECT_NEAR(idw({a, a, 0}), (1.0 / d2[0]) / sum, 1e-15);
}

TEST(GridIdw, OutsideTargetIsAnErrorNamingTargetAndBounds) {
  const GridIdw<double> idw(kPaperGrid, std::vector<double>(125, 1.0));
  try {
    idw({510, 20, -3});
    FAIL() << "expected OutsideGridError";
  } catch (const OutsideGridError& e) {
    EXPECT_THAT(e.what(), HasSubstr("(510, 20, -3) is outside the grid [0, 500] x [0, 500] x [0, 500]"));
    EXPECT_THAT(e.what(), HasSubstr("x 10 above, z 3 below"));
  }
  Eigen::MatrixXd t = random_targets(kPaperGrid, 10, 4);
  t(6, 1) = 500.5;
  try {
    idw.predict(t, RowLabels{"targets.csv", {2, 3, 4, 5, 6, 7, 8, 9, 10, 11}});
    FAIL() << "expected OutsideGridError";
  } catch (const OutsideGridError& e) {
    EXPECT_THAT(e.what(), HasSubstr("targets.csv:8: target ("));
    EXPECT_EQ(e.row(), 8u);
  }
  // Within the boundary tolerance (1e-9 of the step) a target still counts as inside.
  EXPECT_DOUBLE_EQ(idw({500 + 1e-8, 0, 0}), 1.0);
}

TEST(GridIdw, ClampUsesTheNearestCellAndReportsStatus) {
  const auto v = node_values_of(kPaperGrid, [](const Eigen::Vector3d& p) { return p.x() + 2 * p.y() - p.z(); });
  GridIdwOptions o;
  o.clamp = true;
  const GridIdw<double> clamped(kPaperGrid, v, o);
  const GridIdw<double> strict(kPaperGrid, v);
  // Random targets up to 200 mm outside: inside ones are unaffected by clamping, outside ones are
  // NaN without it and finite with it.
  const Eigen::MatrixXd t = random_targets(kPaperGrid, 400, 5, 200.0);
  std::vector<double> out_c(400), out_s(400);
  std::vector<GridIdwStatus> st_c(400), st_s(400);
  clamped.predict_with_status(t, out_c, st_c);
  strict.predict_with_status(t, out_s, st_s);
  int outside = 0;
  for (int i = 0; i < 400; ++i) {
    const bool in = kPaperGrid.contains(t.row(i).transpose());
    outside += !in;
    EXPECT_EQ(st_c[i], in ? GridIdwStatus::Inside : GridIdwStatus::Clamped);
    EXPECT_EQ(st_s[i], in ? GridIdwStatus::Inside : GridIdwStatus::Outside);
    if (in) {
      EXPECT_EQ(out_c[i], out_s[i]);
    } else {
      EXPECT_TRUE(std::isnan(out_s[i]));
      EXPECT_TRUE(std::isfinite(out_c[i]));
    }
  }
  EXPECT_GT(outside, 100);
  // A target straight beyond the centre of the face x = 500 of cell (3, 1, 1): by symmetry in y and z
  // the result is a mix of the x = 375 and x = 500 planes' values with the closed-form weights.
  const double y = 187.5, z = 187.5, x = 600;
  auto plane = [](double dx) { return 4.0 / std::sqrt(dx * dx + 2 * 62.5 * 62.5); };
  const double w500 = plane(x - 500), w375 = plane(x - 375);
  const double f = 2 * y - z;  // mean of the y, z part over the 4 vertices of a face
  const double expected = (w500 * (500 + f) + w375 * (375 + f)) / (w500 + w375);
  EXPECT_NEAR(clamped({x, y, z}), expected, 1e-12);
  EXPECT_THROW(strict({x, y, z}), OutsideGridError);
}

TEST(GridIdw, NonFiniteTargetIsOutsideEvenWhenClamping) {
  GridIdwOptions o;
  o.clamp = true;
  const GridIdw<double> idw(kPaperGrid, std::vector<double>(125, 1.0), o);
  EXPECT_THROW(idw({std::nan(""), 1, 1}), OutsideGridError);
  std::vector<Eigen::Vector3d> t{{1, 1, 1}, {std::numeric_limits<double>::infinity(), 1, 1}};
  std::vector<double> out(2);
  std::vector<GridIdwStatus> st(2);
  idw.predict_with_status(t, out, st);
  EXPECT_EQ(st[0], GridIdwStatus::Inside);
  EXPECT_EQ(st[1], GridIdwStatus::Outside);
  EXPECT_TRUE(std::isnan(out[1]));
}

TEST(GridIdw, FromShuffledSamplesEqualsDirectConstruction) {
  const RegularGrid3 g({-100, 50, 7}, {50, 25, 10}, {4, 3, 6});
  std::mt19937_64 rng(6);
  std::normal_distribution<double> nd(0, 1);
  std::vector<Eigen::Vector3d> values(g.node_count());
  for (auto& x : values) x = Eigen::Vector3d(nd(rng), nd(rng), nd(rng));
  std::vector<std::size_t> order(g.node_count());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  Eigen::MatrixXd pts(static_cast<Eigen::Index>(order.size()), 3);
  std::vector<Eigen::Vector3d> shuffled;
  for (std::size_t r = 0; r < order.size(); ++r) {
    pts.row(static_cast<Eigen::Index>(r)) = g.node_position(order[r]).transpose();
    shuffled.push_back(values[order[r]]);
  }
  const auto a = GridIdw<Eigen::Vector3d>::from_samples(pts, shuffled);
  const GridIdw<Eigen::Vector3d> b(g, values);
  const Eigen::MatrixXd t = random_targets(g, 300, 7);
  const auto pa = a.predict(t), pb = b.predict(t);
  for (std::size_t i = 0; i < pa.size(); ++i) EXPECT_NEAR((pa[i] - pb[i]).norm(), 0.0, 1e-12);
  // The span-of-points overload agrees with the matrix overload.
  std::vector<Eigen::Vector3d> tv;
  for (Eigen::Index i = 0; i < t.rows(); ++i) tv.push_back(t.row(i).transpose());
  const auto pc = b.predict(tv);
  for (std::size_t i = 0; i < pa.size(); ++i) EXPECT_EQ(pc[i], pb[i]);
}

TEST(GridIdw, IdenticalPredictionsForAnyThreadCount) {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> nd(0, 1);
  std::vector<Eigen::Vector3d> v(kPaperGrid.node_count());
  for (auto& x : v) x = Eigen::Vector3d(nd(rng), nd(rng), nd(rng));
  const Eigen::MatrixXd t = random_targets(kPaperGrid, 10000, 9);  // above the serial threshold
  std::vector<std::vector<Eigen::Vector3d>> results;
  for (int threads : {1, 2, 3}) {
    GridIdwOptions o;
    o.threads = threads;
    results.push_back(GridIdw<Eigen::Vector3d>(kPaperGrid, v, o).predict(t));
  }
  EXPECT_EQ(results[1], results[0]);
  EXPECT_EQ(results[2], results[0]);
}

TEST(GridIdw, RejectsBadOptionsAndValues) {
  GridIdwOptions o;
  o.power = -1;
  EXPECT_THROW(GridIdw<double>(kPaperGrid, std::vector<double>(125, 1.0), o), ArgumentError);
  EXPECT_THROW(GridIdw<double>(kPaperGrid, std::vector<double>(124, 1.0)), ArgumentError);
  std::vector<double> v(125, 1.0);
  v[7] = std::nan("");
  EXPECT_THROW(GridIdw<double>(kPaperGrid, v), InputError);
}

}  // namespace
}  // namespace errfield
