#include "errfield/cross_validation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "errfield/scattered_idw.hpp"

namespace errfield {
namespace cross_validation_test {

std::vector<Eigen::Vector3d> random_points(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::vector<Eigen::Vector3d> p(n);
  for (auto& x : p) x = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

std::vector<double> field(const std::vector<Eigen::Vector3d>& p) {
  std::vector<double> v;
  for (const auto& x : p) v.push_back(0.3 * std::sin(x.x() / 120.0) + 1e-3 * x.y() - 5e-4 * x.z());
  return v;
}

// Predicts the mean of the training values, with a fixed variance: a stand-in for an estimator
// with a prediction variance (kriging), to test the interface and the z-score summary.
struct MeanEstimator {
  double variance = 4.0;
  HoldOutPrediction<double> fit_predict(std::span<const Eigen::Vector3d>, std::span<const double> values,
                                        std::span<const Eigen::Vector3d> query) const {
    const double mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
    return {std::vector<double>(query.size(), mean), std::vector<double>(query.size(), variance)};
  }
};
static_assert(HoldOutEstimator<MeanEstimator, Eigen::Vector3d, double>);

struct BrokenEstimator {
  HoldOutPrediction<double> fit_predict(std::span<const Eigen::Vector3d>, std::span<const double>,
                                        std::span<const Eigen::Vector3d>) const {
    return {{1.0}, {}};
  }
};

TEST(AssignFolds, LeaveOneOutAndBalancedDeterministicKFold) {
  EXPECT_EQ(assign_folds(4, {}), (std::vector<std::size_t>{0, 1, 2, 3}));
  CrossValidationOptions o;
  o.folds = 4;
  o.seed = 42;
  const auto a = assign_folds(103, o);
  EXPECT_EQ(a, assign_folds(103, o));  // same seed, same folds
  std::vector<std::size_t> sizes(4, 0);
  for (auto f : a) ++sizes.at(f);
  EXPECT_EQ(*std::max_element(sizes.begin(), sizes.end()) - *std::min_element(sizes.begin(), sizes.end()), 1u);
  o.seed = 43;
  EXPECT_NE(a, assign_folds(103, o));
  // Shuffled: the folds are not simply i mod k.
  std::size_t in_order = 0;
  for (std::size_t i = 0; i < a.size(); ++i) in_order += a[i] == i % 4;
  EXPECT_LT(in_order, 60u);
  o.folds = 1;
  EXPECT_THROW(assign_folds(10, o), ArgumentError);
  o.folds = 11;
  EXPECT_THROW(assign_folds(10, o), ArgumentError);
}

TEST(CrossValidate, LeaveOneOutIdwEqualsRefittingWithoutEachSample) {
  const auto locs = random_points(120, 1);
  const auto vals = field(locs);
  ScatteredIdwEstimator<Eigen::Vector3d, double> est;
  est.options.neighbors = 8;
  const auto cv = cross_validate(est, std::span<const Eigen::Vector3d>(locs), std::span<const double>(vals));
  ASSERT_EQ(cv.residual.size(), locs.size());
  EXPECT_TRUE(cv.variance.empty());
  double sum = 0, sum_abs = 0, sum_sq = 0, max_abs = 0;
  for (std::size_t i = 0; i < locs.size(); ++i) {
    std::vector<Eigen::Vector3d> l = locs;
    std::vector<double> v = vals;
    l.erase(l.begin() + static_cast<std::ptrdiff_t>(i));
    v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
    ScatteredIdwOptions o;
    o.neighbors = 8;
    const double pred = ScatteredIdw<Eigen::Vector3d, double>(l, v, o)(locs[i]);
    EXPECT_EQ(cv.predicted[i], pred) << i;
    EXPECT_EQ(cv.residual[i], vals[i] - pred) << i;
    EXPECT_EQ(cv.fold[i], i);
    sum += vals[i] - pred;
    sum_abs += std::abs(vals[i] - pred);
    sum_sq += (vals[i] - pred) * (vals[i] - pred);
    max_abs = std::max(max_abs, std::abs(vals[i] - pred));
  }
  const auto& s = cv.summary;
  EXPECT_EQ(s.predicted, 120u);
  EXPECT_NEAR(s.mean_error[0], sum / 120, 1e-15);
  EXPECT_NEAR(s.mean_abs_error, sum_abs / 120, 1e-15);
  EXPECT_NEAR(s.rms_error, std::sqrt(sum_sq / 120), 1e-15);
  EXPECT_EQ(s.max_abs_error, max_abs);
  EXPECT_EQ(std::abs(cv.residual[s.max_abs_index]), max_abs);
}

TEST(CrossValidate, KFoldPredictsEachFoldFromTheOthers) {
  const auto locs = random_points(60, 2);
  std::vector<Eigen::Vector3d> vals;
  for (const auto& p : locs) vals.emplace_back(1e-3 * p.x(), -2e-3 * p.y(), 0.1);
  ScatteredIdwEstimator<Eigen::Vector3d, Eigen::Vector3d> est;
  est.options.power = 1.0;
  CrossValidationOptions o;
  o.folds = 5;
  o.seed = 7;
  const auto cv = cross_validate(est, std::span<const Eigen::Vector3d>(locs), std::span<const Eigen::Vector3d>(vals), o);
  EXPECT_EQ(cv.fold, assign_folds(60, o));
  for (std::size_t f = 0; f < 5; ++f) {
    std::vector<Eigen::Vector3d> tl, tv;
    for (std::size_t i = 0; i < 60; ++i)
      if (cv.fold[i] != f) {
        tl.push_back(locs[i]);
        tv.push_back(vals[i]);
      }
    ScatteredIdwOptions io;
    io.power = 1.0;
    const ScatteredIdw<Eigen::Vector3d, Eigen::Vector3d> idw(tl, tv, io);
    for (std::size_t i = 0; i < 60; ++i)
      if (cv.fold[i] == f) {
        EXPECT_EQ(cv.predicted[i], idw(locs[i])) << i;
      }
  }
  // Vector residuals: |e| is the Euclidean norm; the z component is constant, so its error is 0.
  EXPECT_NEAR(cv.summary.mean_error[2], 0.0, 1e-15);
  double max_norm = 0;
  for (const auto& r : cv.residual) max_norm = std::max(max_norm, r.norm());
  EXPECT_EQ(cv.summary.max_abs_error, max_norm);
}

TEST(CrossValidate, VarianceGivesZScoresAndWrongCountsAreAnError) {
  const auto locs = random_points(10, 3);
  const std::vector<double> vals{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const auto cv = cross_validate(MeanEstimator{}, std::span<const Eigen::Vector3d>(locs), std::span<const double>(vals));
  ASSERT_EQ(cv.variance.size(), 10u);
  // LOO mean of the others: (55 - v) / 9, residual v - (55 - v) / 9 = (10 v - 55) / 9; z = residual / 2.
  double mz = 0, mz2 = 0;
  for (int v = 1; v <= 10; ++v) {
    const double e = (10.0 * v - 55.0) / 9.0;
    EXPECT_NEAR(cv.residual[static_cast<std::size_t>(v - 1)], e, 1e-14);
    mz += e / 2 / 10;
    mz2 += e * e / 4 / 10;
  }
  ASSERT_TRUE(cv.summary.mean_z.has_value());
  EXPECT_NEAR(*cv.summary.mean_z, mz, 1e-14);
  EXPECT_NEAR(*cv.summary.mean_squared_z, mz2, 1e-14);
  CrossValidationOptions two;
  two.folds = 2;  // 5 held-out samples per fold, but the estimator returns 1 prediction
  EXPECT_THROW(
      cross_validate(BrokenEstimator{}, std::span<const Eigen::Vector3d>(locs), std::span<const double>(vals), two),
      Error);
}

TEST(SummarizeResiduals, SkipsUnpredictedRowsAndUsesNorms) {
  Eigen::MatrixXd r(4, 2);
  r << 3, 4,  //
      std::nan(""), std::nan(""),  //
      -1, 0,  //
      0, 0;
  const auto s = summarize_residuals(r);
  EXPECT_EQ(s.samples, 4u);
  EXPECT_EQ(s.predicted, 3u);
  EXPECT_DOUBLE_EQ(s.mean_error[0], 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.mean_error[1], 4.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.mean_abs_error, 2.0);
  EXPECT_DOUBLE_EQ(s.max_abs_error, 5.0);
  EXPECT_EQ(s.max_abs_index, 0u);
  EXPECT_DOUBLE_EQ(s.rms_error, std::sqrt(26.0 / 3.0));
  EXPECT_FALSE(s.mean_z.has_value());
}

}  // namespace
}  // namespace errfield
