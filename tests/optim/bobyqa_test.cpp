// The NLopt wrapper shared by the variogram and likelihood fits (src/optim/bobyqa.hpp), tested on
// problems with closed-form minimizers.
#include "optim/bobyqa.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace bobyqa_test {

using errfield::detail::Bobyqa;

// f(x) = sum_k (x_k - c_k)^2 with c = (0.3, -2, 5): separable, so the box minimizer is c clamped.
double shifted_bowl(const double* x, void* evaluations) {
  ++*static_cast<int*>(evaluations);
  const double c[] = {0.3, -2.0, 5.0};
  double f = 0.0;
  for (int k = 0; k < 3; ++k) f += (x[k] - c[k]) * (x[k] - c[k]);
  return f;
}

TEST(Bobyqa, FindsTheClampedMinimumOfASeparableBowl) {
  const std::vector<double> lower{-1.0, -1.0, -1.0}, upper{1.0, 1.0, 1.0};
  Bobyqa bobyqa(lower, upper, 1e-12, 2000, "test");
  std::vector<double> x{0.9, 0.9, -0.9};
  int evaluations = 0;
  const auto out = bobyqa.minimize(&shifted_bowl, &evaluations, x);
  ASSERT_TRUE(out.converged) << bobyqa.describe(out, "bowl");
  EXPECT_FALSE(out.hit_evaluation_limit);
  EXPECT_NEAR(x[0], 0.3, 1e-6);
  EXPECT_DOUBLE_EQ(x[1], -1.0);  // BOBYQA keeps iterates inside the box, so the bound is exact
  EXPECT_DOUBLE_EQ(x[2], 1.0);
  EXPECT_NEAR(out.objective, 1.0 + 16.0, 1e-10);
  EXPECT_GT(evaluations, 0);
}

TEST(Bobyqa, ReportsTheEvaluationLimitAsNotConverged) {
  const std::vector<double> lower{-10.0, -10.0, -10.0}, upper{10.0, 10.0, 10.0};
  Bobyqa bobyqa(lower, upper, 1e-15, 8, "test");  // 2n+1 = 7 points set up the model: 8 is too few
  std::vector<double> x{9.0, 9.0, -9.0};
  int evaluations = 0;
  const auto out = bobyqa.minimize(&shifted_bowl, &evaluations, x);
  EXPECT_FALSE(out.converged);
  EXPECT_TRUE(out.hit_evaluation_limit);
  EXPECT_EQ(evaluations, 8);
  EXPECT_EQ(bobyqa.describe(out, "bowl"), "stopped at the evaluation limit (8)");
}

TEST(Bobyqa, OneOptimizerServesSeveralStartsWithTheirOwnSteps) {
  const std::vector<double> lower{-10.0, -10.0, -10.0}, upper{10.0, 10.0, 10.0};
  Bobyqa bobyqa(lower, upper, 1e-12, 2000, "test");
  for (const std::vector<double>& start : {std::vector<double>{9.0, 9.0, 9.0}, std::vector<double>{-9.0, 0.0, 1.0}}) {
    std::vector<double> x = start;
    const std::vector<double> step{0.5, 0.5, 0.5};
    int evaluations = 0;
    const auto out = bobyqa.minimize(&shifted_bowl, &evaluations, x, step);
    ASSERT_TRUE(out.converged);
    EXPECT_NEAR(x[0], 0.3, 1e-6);
    EXPECT_NEAR(x[1], -2.0, 1e-6);
    EXPECT_NEAR(x[2], 5.0, 1e-6);
  }
}

TEST(Bobyqa, RejectsMismatchedBoundsNamingTheCaller) {
  const std::vector<double> lower{0.0, 0.0}, upper{1.0};
  try {
    Bobyqa bobyqa(lower, upper, 1e-6, 10, "fit_variogram");
    FAIL() << "expected errfield::Error";
  } catch (const errfield::Error& e) {
    EXPECT_NE(std::string(e.what()).find("fit_variogram"), std::string::npos) << e.what();
  }
}

}  // namespace
