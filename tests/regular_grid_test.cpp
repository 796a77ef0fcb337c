#include "errfield/regular_grid.hpp"

#include <algorithm>
#include <numeric>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace errfield {
namespace regular_grid_test {

using ::testing::HasSubstr;

// Nodes of a grid as an N x 3 matrix, rows shuffled with `seed` (0: natural order).
Eigen::MatrixXd grid_points(const RegularGrid3& g, unsigned seed = 0) {
  std::vector<std::size_t> order(g.node_count());
  std::iota(order.begin(), order.end(), 0);
  if (seed) std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  Eigen::MatrixXd p(static_cast<Eigen::Index>(order.size()), 3);
  for (std::size_t r = 0; r < order.size(); ++r) p.row(static_cast<Eigen::Index>(r)) = g.node_position(order[r]).transpose();
  return p;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(RegularGrid3, NumbersNodesXFastestAndKnowsItsBox) {
  const RegularGrid3 g({10, 20, 30}, {1, 2, 4}, {3, 4, 5});
  EXPECT_EQ(g.node_count(), 60u);
  EXPECT_EQ(g.cell_count(), 2u * 3u * 4u);
  EXPECT_EQ(g.node_index(1, 0, 0), 1u);
  EXPECT_EQ(g.node_index(0, 1, 0), 3u);
  EXPECT_EQ(g.node_index(0, 0, 1), 12u);
  for (std::size_t n = 0; n < g.node_count(); ++n) {
    const auto ijk = g.node_indices(n);
    EXPECT_EQ(g.node_index(ijk[0], ijk[1], ijk[2]), n);
  }
  EXPECT_EQ(g.node_position(2, 3, 4), Eigen::Vector3d(12, 26, 46));
  EXPECT_EQ(g.upper(), Eigen::Vector3d(12, 26, 46));
  EXPECT_TRUE(g.contains({12, 26, 46}));
  EXPECT_FALSE(g.contains({12.001, 26, 46}));
  EXPECT_TRUE(g.contains({12.001, 26, 46}, 0.01));
}

TEST(RegularGrid3, RejectsDegenerateGeometry) {
  EXPECT_THROW(RegularGrid3({0, 0, 0}, {1, 0, 1}, {2, 2, 2}), ArgumentError);
  EXPECT_THROW(RegularGrid3({0, 0, 0}, {1, 1, 1}, {2, 1, 2}), ArgumentError);
  EXPECT_THROW(RegularGrid3({0, 0, std::nan("")}, {1, 1, 1}, {2, 2, 2}), ArgumentError);
}

TEST(DetectRegularGrid, RecoversGridAndNodeOrderFromShuffledSamples) {
  // The paper's grid: a 500 mm cube with 125 mm steps, here placed at robot-like coordinates.
  const RegularGrid3 g({1200, -250, 300}, {125, 125, 125}, {5, 5, 5});
  const Eigen::MatrixXd p = grid_points(g, 7);
  const GridDetection d = detect_regular_grid(p);
  EXPECT_EQ(d.grid.counts(), g.counts());
  EXPECT_NEAR((d.grid.origin() - g.origin()).norm(), 0.0, 1e-9);
  EXPECT_NEAR((d.grid.step() - g.step()).norm(), 0.0, 1e-12);
  ASSERT_EQ(d.sample_of_node.size(), g.node_count());
  for (std::size_t n = 0; n < g.node_count(); ++n)
    EXPECT_EQ(p.row(static_cast<Eigen::Index>(d.sample_of_node[n])).transpose(), g.node_position(n)) << n;
}

TEST(DetectRegularGrid, AcceptsCoordinatesRoundedToSevenDigits) {
  const RegularGrid3 g({0.1, 0.2, 0.3}, {1.0 / 3.0, 0.7, 2.0}, {4, 3, 2});
  Eigen::MatrixXd p = grid_points(g, 3);
  for (Eigen::Index i = 0; i < p.size(); ++i) p.data()[i] = std::round(p.data()[i] * 1e7) / 1e7;
  const GridDetection d = detect_regular_grid(p);
  EXPECT_EQ(d.grid.counts(), (std::array<int, 3>{4, 3, 2}));
  EXPECT_NEAR(d.grid.step().x(), 1.0 / 3.0, 1e-7);
}

TEST(DetectRegularGrid, MissingNodeIsNamedByIndicesAndCoordinates) {
  const RegularGrid3 g({0, 0, 0}, {125, 125, 125}, {5, 5, 5});
  Eigen::MatrixXd p = grid_points(g);
  // Drop node (2, 3, 1) = (250, 375, 125).
  const auto drop = static_cast<Eigen::Index>(g.node_index(2, 3, 1));
  Eigen::MatrixXd q(p.rows() - 1, 3);
  q << p.topRows(drop), p.bottomRows(p.rows() - drop - 1);
  const std::string m = message_of([&] { detect_regular_grid(q); });
  EXPECT_THAT(m, HasSubstr("node (2, 3, 1) at (250, 375, 125) has no sample"));
  EXPECT_THAT(m, HasSubstr("125 nodes, 124 samples"));
}

TEST(DetectRegularGrid, MissingPlaneCountsAllMissingNodes) {
  const RegularGrid3 g({0, 0, 0}, {1, 1, 1}, {4, 3, 3});
  const Eigen::MatrixXd p = grid_points(g);
  std::vector<Eigen::Index> keep;
  for (Eigen::Index r = 0; r < p.rows(); ++r)
    if (p(r, 0) != 2.0) keep.push_back(r);  // the whole plane x = 2 is missing
  Eigen::MatrixXd q(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t i = 0; i < keep.size(); ++i) q.row(static_cast<Eigen::Index>(i)) = p.row(keep[i]);
  const std::string m = message_of([&] { detect_regular_grid(q); });
  EXPECT_THAT(m, HasSubstr("node (2, 0, 0) at (2, 0, 0) has no sample"));
  EXPECT_THAT(m, HasSubstr("9 nodes are missing"));
}

TEST(DetectRegularGrid, UnevenSpacingNamesAxisAndValues) {
  const RegularGrid3 g({0, 0, 0}, {1, 1, 1}, {3, 3, 3});
  Eigen::MatrixXd p = grid_points(g);
  for (Eigen::Index r = 0; r < p.rows(); ++r)
    if (p(r, 1) == 2.0) p(r, 1) = 2.5;  // y planes 0, 1, 2.5
  const std::string m = message_of([&] { detect_regular_grid(p); });
  EXPECT_THAT(m, HasSubstr("uneven spacing on axis y"));
  EXPECT_THAT(m, HasSubstr("values 0, 1, 2.5"));
  EXPECT_THAT(m, HasSubstr("from 1 to 2.5"));
}

TEST(DetectRegularGrid, DuplicateNodeNamesBothRowsWithFileLines) {
  const RegularGrid3 g({0, 0, 0}, {1, 1, 1}, {2, 2, 2});
  Eigen::MatrixXd p(9, 3);
  p.topRows(8) = grid_points(g);
  p.row(8) = p.row(5);
  RowLabels labels{"grid.csv", {2, 3, 4, 5, 6, 7, 8, 9, 10}};
  try {
    detect_regular_grid(p, labels);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("grid.csv:10: duplicate grid node (1, 0, 1) at (1, 0, 1)"));
    EXPECT_THAT(e.what(), HasSubstr("grid.csv:7 ("));
    EXPECT_EQ(e.file(), "grid.csv");
    EXPECT_EQ(e.row(), 10u);
  }
}

TEST(DetectRegularGrid, RejectsFlatTooSmallAndNonFiniteInput) {
  Eigen::MatrixXd flat = grid_points(RegularGrid3({0, 0, 0}, {1, 1, 1}, {3, 3, 2}));
  flat.col(2).setConstant(5.0);
  EXPECT_THAT(message_of([&] { detect_regular_grid(flat); }), HasSubstr("have z = 5"));
  EXPECT_THAT(message_of([&] { detect_regular_grid(Eigen::MatrixXd::Zero(4, 3)); }), HasSubstr("at least 8"));
  Eigen::MatrixXd bad = grid_points(RegularGrid3({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
  bad(3, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THAT(message_of([&] { detect_regular_grid(bad); }), HasSubstr("sample 3: coordinate y is inf"));
  EXPECT_THROW(detect_regular_grid(Eigen::MatrixXd::Zero(8, 2)), ArgumentError);
}

TEST(DetectRegularGrid, NoisyCoordinatesAreNotMistakenForAHugeLattice) {
  // Planes that should coincide but scatter by 1e-3 (tolerance 1e-6 x extent): the smallest gap
  // would imply an absurd lattice; the message says so instead of listing thousands of nodes.
  Eigen::MatrixXd p = grid_points(RegularGrid3({0, 0, 0}, {100, 100, 100}, {3, 3, 3}));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  for (Eigen::Index i = 0; i < p.size(); ++i) p.data()[i] += u(rng);
  EXPECT_THAT(message_of([&] { detect_regular_grid(p); }), HasSubstr("not evenly spaced"));
  GridDetectionOptions loose;
  loose.relative_tolerance = 1e-4;
  EXPECT_EQ(detect_regular_grid(p, {}, loose).grid.counts(), (std::array<int, 3>{3, 3, 3}));
}

}  // namespace
}  // namespace errfield
