#include "errfield/concepts.hpp"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/metrics.hpp"

namespace errfield {
namespace concepts_test {

// Positive and negative checks of the three contracts: a wrong type must be rejected at compile
// time with the concept's name, not deep inside an estimator.
static_assert(Location<Eigen::Vector3d>);
static_assert(Location<Eigen::Matrix<double, 6, 1>>);
static_assert(Location<Eigen::VectorXd>);
static_assert(Location<std::array<double, 6>>);
static_assert(Location<double>);
static_assert(!Location<int>);
static_assert(!Location<std::string>);
static_assert(!Location<std::vector<double>>);

static_assert(Metric<EuclideanMetric, Eigen::Vector3d>);
static_assert(Metric<JointSpaceMetric, std::array<double, 6>>);
static_assert(Metric<WeightedEuclideanMetric, Eigen::VectorXd>);
static_assert(!Metric<int, Eigen::Vector3d>);
static_assert(!Metric<EuclideanMetric, std::string>);

static_assert(Value<double>);
static_assert(Value<Eigen::Vector3d>);
static_assert(Value<Eigen::Matrix<double, 6, 1>>);
static_assert(!Value<std::string>);
static_assert(!Value<int*>);

TEST(Metrics, EuclideanMatchesHandComputedDistance) {
  const Eigen::Vector3d a(1, 2, 3), b(4, 6, 3);
  EXPECT_DOUBLE_EQ(EuclideanMetric{}(a, b), 5.0);
  const std::array<double, 6> q1{0, 0, 0, 0, 0, 0}, q2{3, 4, 0, 0, 0, 12};
  EXPECT_DOUBLE_EQ(JointSpaceMetric{}(q1, q2), 13.0);
  EXPECT_DOUBLE_EQ(EuclideanMetric{}(2.0, -1.0), 3.0);
}

TEST(Metrics, WeightedEuclideanScalesEachAxis) {
  const WeightedEuclideanMetric m({4.0, 1.0, 0.0});
  const Eigen::Vector3d a(0, 0, 0), b(1, 2, 100);
  EXPECT_DOUBLE_EQ(m(a, b), std::sqrt(4.0 * 1 + 1.0 * 4));
  EXPECT_THROW(WeightedEuclideanMetric({1.0, -1.0}), ArgumentError);
}

TEST(ValueTraits, ComponentsAndNorms) {
  EXPECT_EQ(ValueTraits<double>::kComponents, 1);
  EXPECT_EQ(ValueTraits<Eigen::Vector3d>::kComponents, 3);
  EXPECT_DOUBLE_EQ(ValueTraits<Eigen::Vector3d>::squared_norm(Eigen::Vector3d(1, 2, 2)), 9.0);
  EXPECT_DOUBLE_EQ(ValueTraits<double>::squared_norm(-3.0), 9.0);
}

}  // namespace
}  // namespace errfield

namespace errfield {
namespace concepts_test {

TEST(ValueTraits, ComponentAccessOnMutableAndConstScalars) {
  // Both overloads must be callable on a plain variable without ambiguity.
  double v = 1.5;
  ValueTraits<double>::component(v, 0) = 2.5;
  const double c = v;
  EXPECT_EQ(ValueTraits<double>::component(c, 0), 2.5);
  Eigen::Vector3d x(1, 2, 3);
  ValueTraits<Eigen::Vector3d>::component(x, 1) = 7.0;
  EXPECT_EQ(x[1], 7.0);
}

}  // namespace
}  // namespace errfield
