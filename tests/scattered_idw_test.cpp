#include "errfield/scattered_idw.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

namespace errfield {
namespace scattered_idw_test {

// Manhattan distance: a metric without a k-d tree, so ScatteredIdw falls back to brute force.
struct ManhattanMetric {
  template <Location L>
  double operator()(const L& a, const L& b) const {
    double s = 0.0;
    for (int k = 0; k < LocationTraits<L>::size(a); ++k)
      s += std::abs(LocationTraits<L>::coordinate(a, k) - LocationTraits<L>::coordinate(b, k));
    return s;
  }
};

static_assert(HoldOutEstimator<ScatteredIdwEstimator<Eigen::Vector3d, double>, Eigen::Vector3d, double>);
static_assert(HoldOutEstimator<ScatteredIdwEstimator<Eigen::VectorXd, Eigen::Vector3d>, Eigen::VectorXd, Eigen::Vector3d>);
static_assert(!HoldOutEstimator<ScatteredIdw<Eigen::Vector3d, double>, Eigen::Vector3d, double>);
static_assert(!HoldOutEstimator<ScatteredIdwEstimator<Eigen::Vector3d, double>, Eigen::Vector3d, Eigen::Vector3d>);

// Naive IDW straight from the definition: all distances, sort by (distance, index), keep the k
// nearest and those within the radius, weights 1/d^p; exact when a distance is 0.
template <class L, class V, class M>
V brute_force_idw(const std::vector<L>& locs, const std::vector<V>& vals, const L& x, double p, std::size_t k,
                  double radius, const M& metric) {
  std::vector<std::pair<double, std::size_t>> d;
  for (std::size_t i = 0; i < locs.size(); ++i) d.emplace_back(metric(x, locs[i]), i);
  std::sort(d.begin(), d.end());
  if (k > 0 && d.size() > k) d.resize(k);
  std::erase_if(d, [&](const auto& e) { return e.first > radius; });
  if (d.empty()) return detail::nan_value<V>();
  if (d.front().first == 0.0) return vals[d.front().second];
  V num = ValueTraits<V>::zero();
  double den = 0.0;
  for (const auto& [dist, i] : d) {
    const double w = 1.0 / std::pow(dist, p);
    num = V(num + w * vals[i]);
    den += w;
  }
  return V(num / den);
}

template <int D>
std::vector<Eigen::Matrix<double, D, 1>> random_points(std::size_t n, int dim, double scale, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, scale);
  std::vector<Eigen::Matrix<double, D, 1>> pts(n);
  for (auto& p : pts) {
    p.resize(dim);
    for (int k = 0; k < dim; ++k) p[k] = u(rng);
  }
  return pts;
}

template <class L>
std::vector<double> smooth_values(const std::vector<L>& pts) {
  std::vector<double> v;
  for (const auto& p : pts) v.push_back(std::sin(p[0] / 150.0) + 0.3 * std::cos(p[1] / 90.0) + 1e-3 * p.sum());
  return v;
}

double rel_diff(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

TEST(ScatteredIdw, KdTreeMatchesBruteForce3D) {
  const auto locs = random_points<3>(800, 3, 500.0, 1);
  const auto vals = smooth_values(locs);
  const auto targets = random_points<3>(300, 3, 500.0, 2);
  struct Case {
    double p;
    std::size_t k;
    double r;
  };
  for (const Case c : {Case{2.0, 8, INFINITY}, Case{1.0, 1, INFINITY}, Case{3.3, 20, INFINITY}, Case{2.0, 0, 80.0},
                       Case{1.5, 12, 60.0}, Case{2.0, 0, INFINITY}, Case{0.0, 5, INFINITY}, Case{2.0, 5000, INFINITY}}) {
    ScatteredIdwOptions o;
    o.power = c.p;
    o.neighbors = c.k;
    o.radius = c.r;
    const ScatteredIdw<Eigen::Vector3d, double> idw(locs, vals, o);
    EXPECT_TRUE(idw.uses_tree());
    const auto pred = idw.predict(targets);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const double ref = brute_force_idw(locs, vals, targets[t], c.p, c.k, c.r, EuclideanMetric{});
      if (std::isnan(ref)) {
        EXPECT_TRUE(std::isnan(pred[t]));
      } else {
        // Same weights up to rounding (the estimator scales them by the nearest distance).
        EXPECT_LT(rel_diff(pred[t], ref), 1e-13) << "p " << c.p << " k " << c.k << " r " << c.r << " target " << t;
      }
    }
  }
}

TEST(ScatteredIdw, DynamicDimensionJointSpaceMatchesBruteForce) {
  // 6-D joint vectors in degrees with a dynamic-size location (what the CLI uses).
  const auto locs = random_points<Eigen::Dynamic>(600, 6, 90.0, 3);
  const auto vals = smooth_values(locs);
  const auto targets = random_points<Eigen::Dynamic>(200, 6, 90.0, 4);
  ScatteredIdwOptions o;
  o.neighbors = 10;
  o.radius = 60.0;
  const ScatteredIdw<Eigen::VectorXd, double, JointSpaceMetric> idw(locs, vals, o);
  EXPECT_TRUE(idw.uses_tree());
  EXPECT_EQ(idw.dimension(), 6);
  const auto pred = idw.predict(targets);
  int predicted = 0;
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const double ref = brute_force_idw(locs, vals, targets[t], 2.0, 10, 60.0, EuclideanMetric{});
    if (std::isnan(ref)) {
      EXPECT_TRUE(std::isnan(pred[t]));
    } else {
      ++predicted;
      EXPECT_LT(rel_diff(pred[t], ref), 1e-13) << t;
    }
  }
  EXPECT_GT(predicted, 50);
}

TEST(ScatteredIdw, OtherMetricsUseBruteForceAndWeightedEuclideanUsesScaledTree) {
  const auto locs = random_points<3>(400, 3, 100.0, 5);
  const auto vals = smooth_values(locs);
  const auto targets = random_points<3>(100, 3, 100.0, 6);
  ScatteredIdwOptions o;
  o.neighbors = 7;
  o.power = 1.5;
  const ScatteredIdw<Eigen::Vector3d, double, ManhattanMetric> manhattan(locs, vals, o);
  EXPECT_FALSE(manhattan.uses_tree());
  const WeightedEuclideanMetric weighted({1.0, 4.0, 0.25});
  const ScatteredIdw<Eigen::Vector3d, double, WeightedEuclideanMetric> w(locs, vals, o, weighted);
  EXPECT_TRUE(w.uses_tree());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    EXPECT_LT(rel_diff(manhattan(targets[t]), brute_force_idw(locs, vals, targets[t], 1.5, 7, INFINITY, ManhattanMetric{})),
              1e-13);
    EXPECT_LT(rel_diff(w(targets[t]), brute_force_idw(locs, vals, targets[t], 1.5, 7, INFINITY, weighted)), 1e-13);
  }
}

TEST(ScatteredIdw, ExactAtDataAndConstantReproduced) {
  const auto locs = random_points<3>(200, 3, 50.0, 7);
  const auto vals = smooth_values(locs);
  ScatteredIdwOptions o;
  o.neighbors = 6;
  const ScatteredIdw<Eigen::Vector3d, double> idw(locs, vals, o);
  const auto at_data = idw.predict(locs);
  for (std::size_t i = 0; i < locs.size(); ++i) EXPECT_EQ(at_data[i], vals[i]) << i;

  const std::vector<Eigen::Vector3d> constant(locs.size(), Eigen::Vector3d(0.2, -0.1, 0.05));
  const ScatteredIdw<Eigen::Vector3d, Eigen::Vector3d> c(locs, constant, o);
  for (const auto& v : c.predict(random_points<3>(100, 3, 50.0, 8))) {
    EXPECT_DOUBLE_EQ(v.x(), 0.2);
    EXPECT_DOUBLE_EQ(v.y(), -0.1);
    EXPECT_DOUBLE_EQ(v.z(), 0.05);
  }
}

TEST(ScatteredIdw, TwoSamplesOnALineClosedForm) {
  // Samples at 0 and 10 on a line, values 1 and 3; at x = 2.5 with p = 2: w = 1/6.25 and 1/56.25.
  const std::vector<double> locs{0.0, 10.0};
  const std::vector<double> vals{1.0, 3.0};
  const ScatteredIdw<double, double> idw(locs, vals);
  const double w0 = 1 / 6.25, w1 = 1 / 56.25;
  EXPECT_NEAR(idw(2.5), (w0 * 1 + w1 * 3) / (w0 + w1), 1e-15);
  EXPECT_EQ(idw(10.0), 3.0);
}

TEST(ScatteredIdw, ThreadCountDoesNotChangeResults) {
  const auto locs = random_points<3>(3000, 3, 500.0, 9);
  const auto vals = smooth_values(locs);
  const auto targets = random_points<3>(5000, 3, 500.0, 10);
  std::vector<std::vector<double>> results;
  for (int threads : {1, 2, 3}) {
    ScatteredIdwOptions o;
    o.neighbors = 12;
    o.threads = threads;
    results.push_back(ScatteredIdw<Eigen::Vector3d, double>(locs, vals, o).predict(targets));
  }
  EXPECT_EQ(results[1], results[0]);
  EXPECT_EQ(results[2], results[0]);
}

TEST(ScatteredIdw, NoNeighbourWithinRadiusIsReportedAsStatusAndNaN) {
  const std::vector<Eigen::Vector3d> locs{{0, 0, 0}, {1, 0, 0}};
  const std::vector<double> vals{1.0, 2.0};
  ScatteredIdwOptions o;
  o.radius = 1.0;
  const ScatteredIdw<Eigen::Vector3d, double> idw(locs, vals, o);
  const std::vector<Eigen::Vector3d> targets{{0.5, 0, 0}, {5, 5, 5}, {2, 0, 0}};
  std::vector<double> out(3);
  std::vector<ScatteredIdwStatus> status(3);
  idw.predict_with_status(targets, out, status);
  EXPECT_EQ(status[0], ScatteredIdwStatus::Predicted);
  EXPECT_DOUBLE_EQ(out[0], 1.5);
  EXPECT_EQ(status[1], ScatteredIdwStatus::NoNeighbours);
  EXPECT_TRUE(std::isnan(out[1]));
  // The radius is inclusive: (2, 0, 0) is exactly 1 from the second sample.
  EXPECT_EQ(status[2], ScatteredIdwStatus::Predicted);
  EXPECT_EQ(out[2], 2.0);
}

TEST(ScatteredIdw, RejectsBadInput) {
  const std::vector<Eigen::Vector3d> locs{{0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW((ScatteredIdw<Eigen::Vector3d, double>(locs, {1.0})), ArgumentError);
  EXPECT_THROW((ScatteredIdw<Eigen::Vector3d, double>({}, {})), ArgumentError);
  EXPECT_THROW((ScatteredIdw<Eigen::Vector3d, double>(locs, {1.0, std::nan("")})), InputError);
  ScatteredIdwOptions o;
  o.power = -2;
  EXPECT_THROW((ScatteredIdw<Eigen::Vector3d, double>(locs, {1.0, 2.0}, o)), ArgumentError);
  o = {};
  o.radius = 0;
  EXPECT_THROW((ScatteredIdw<Eigen::Vector3d, double>(locs, {1.0, 2.0}, o)), ArgumentError);
  std::vector<Eigen::VectorXd> ragged{Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(2)};
  EXPECT_THROW((ScatteredIdw<Eigen::VectorXd, double>(ragged, {1.0, 2.0})), ArgumentError);
  const ScatteredIdw<Eigen::VectorXd, double> ok({Eigen::VectorXd::Zero(3)}, {1.0});
  const std::vector<Eigen::VectorXd> wrong{Eigen::VectorXd::Zero(4)};
  EXPECT_THROW(ok.predict(wrong), ArgumentError);
}

}  // namespace
}  // namespace errfield
