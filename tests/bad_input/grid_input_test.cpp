// Bad-input catalogue, regular-grid detection at library level: a grid with a missing node or
// uneven spacing, and a duplicated node, raise InputError (the exact class) naming the file, the
// node and, for a duplicate, both file lines. The CLI side: cli_input_test.cpp
// (GridWithAMissingNode, GridWithUnevenSpacing, DuplicateGridNode).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/regular_grid.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace grid_input_test {

using namespace testing::cli_common;

// x, y, z of a 2 x 2 x 2 unit grid plus what `extra` adds, with file lines 2, 3, ...
struct Points {
  Eigen::MatrixXd xyz;
  RowLabels labels;
  explicit Points(const std::vector<Eigen::Vector3d>& p) : xyz(static_cast<Eigen::Index>(p.size()), 3) {
    labels.source = "g.csv";
    for (std::size_t i = 0; i < p.size(); ++i) {
      xyz.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
      labels.lines.push_back(i + 2);
    }
  }
};

std::vector<Eigen::Vector3d> cube(const std::vector<double>& xs) {
  std::vector<Eigen::Vector3d> p;
  for (double z : {0.0, 1.0})
    for (double y : {0.0, 1.0})
      for (double x : xs) p.emplace_back(x, y, z);
  return p;
}

InputError grid_error(const Points& p) {
  try {
    detect_regular_grid(p.xyz, p.labels);
  } catch (const InputError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got: " << e.what();
    return InputError("");
  }
  ADD_FAILURE() << "expected InputError, nothing thrown";
  return InputError("");
}

TEST(GridBadInput, MissingNode) {
  auto p = cube({0.0, 1.0, 2.0});
  p.erase(p.begin() + 10);  // (1, 1, 1)
  const InputError e = grid_error(Points(p));
  EXPECT_EQ(e.file(), "g.csv");
  EXPECT_THAT(e.what(), AllOf(HasSubstr("g.csv"), HasSubstr("(1, 1, 1) has no sample")));
}

TEST(GridBadInput, UnevenSpacingIsAMissingNodeOfTheFinestStep) {
  const InputError e = grid_error(Points(cube({0.0, 1.0, 3.0})));
  EXPECT_EQ(e.file(), "g.csv");
  EXPECT_THAT(e.what(), AllOf(HasSubstr("x [0, 3] step 1"), HasSubstr("(2, 0, 0) has no sample")));
}

TEST(GridBadInput, DuplicateNodeNamesBothLines) {
  auto p = cube({0.0, 1.0});
  p.push_back(p[3]);  // line 5 again as line 10
  const InputError e = grid_error(Points(p));
  EXPECT_EQ(e.file(), "g.csv");
  EXPECT_THAT(e.what(), AllOf(HasSubstr("g.csv:10: duplicate grid node"), HasSubstr("g.csv:5 (")));
}

}  // namespace
}  // namespace errfield
