// FlangeErrorCovariance (compensation/model/flange_error_covariance.hpp): from the fields' stacked
// leave-one-out residuals, the covariance of a point predicted from their combination. Checked
// against closed forms: for errors that are an exact rigid motion of the flange per pose, the
// least-squares combination reproduces the motion at any point, so its covariance is
// [I, -[p]x] Cov(t, w) [I, -[p]x]' in the flange frame, rotated into the robot frame.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "errfield/compensation/model/flange_error_covariance.hpp"

namespace errfield::compensation {
namespace flange_error_covariance_test {

Eigen::Matrix3d cross(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The least-squares rigid-motion combination (robot frame) of the points `flange_points` on a flange
// turned by `r`, predicting the point `p` (flange frame), written out here: C = [I, -[Rp]x] (A'A)^-1 A'.
Eigen::MatrixXd combination(const std::vector<Eigen::Vector3d>& flange_points, const Eigen::Matrix3d& r,
                            const Eigen::Vector3d& p) {
  const auto k = static_cast<Eigen::Index>(flange_points.size());
  Eigen::MatrixXd a(3 * k, 6);
  for (Eigen::Index j = 0; j < k; ++j) {
    a.block<3, 3>(3 * j, 0).setIdentity();
    a.block<3, 3>(3 * j, 3) = -cross(r * flange_points[static_cast<std::size_t>(j)]);
  }
  Eigen::Matrix<double, 3, 6> at;
  at << Eigen::Matrix3d::Identity(), -cross(r * p);
  return at * (a.transpose() * a).ldlt().solve(a.transpose());
}

TEST(FlangeErrorCovariance, ARigidMotionPerPoseGivesTheMotionsCovarianceAtAnyPoint) {
  const std::vector<Eigen::Vector3d> points{{0, 0, 100}, {150, 0, 100}, {0, 150, 100}};
  std::mt19937_64 rng(3);
  std::normal_distribution<double> z;
  // (t, w) in the flange frame with a correlated covariance: t in mm, w in rad.
  Eigen::Matrix<double, 6, 6> l = Eigen::Matrix<double, 6, 6>::Zero();
  l.diagonal() << 0.02, 0.03, 0.01, 2e-4, 1e-4, 3e-4;
  l(3, 0) = 5e-5;
  l(5, 1) = -1e-4;
  std::vector<Eigen::VectorXd> stacked;
  std::vector<double> field_variance;
  Eigen::Matrix<double, 6, 6> second_moment = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 200; ++i) {
    Eigen::Matrix<double, 6, 1> u;
    for (int c = 0; c < 6; ++c) u[c] = z(rng);
    const Eigen::Matrix<double, 6, 1> motion = l * u;
    second_moment += motion * motion.transpose() / 200.0;
    Eigen::VectorXd e(9);
    for (int j = 0; j < 3; ++j) e.segment<3>(3 * j) = motion.head<3>() + motion.tail<3>().cross(points[static_cast<std::size_t>(j)]);
    stacked.push_back(e);
    field_variance.push_back(0.002 + 0.001 * (i % 3));
  }
  const std::optional<FlangeErrorCovariance> c = FlangeErrorCovariance::of(stacked, field_variance, Eigen::Vector3d::Zero());
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->poses, 200u);
  EXPECT_EQ(c->point_count(), 3u);
  double mean = 0.0;
  for (double v : field_variance) mean += v / 200.0;
  EXPECT_NEAR(c->mean_field_variance_mm2, mean, 1e-15);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(75, 75, 100), Eigen::Vector3d(-100, 300, 250), Eigen::Vector3d(0, 0, 100)}) {
    Eigen::Matrix<double, 3, 6> lever;
    lever << Eigen::Matrix3d::Identity(), -cross(p);
    const Eigen::Matrix3d want = r * lever * second_moment * lever.transpose() * r.transpose();
    // At twice the mean field variance, twice the covariance.
    const Eigen::Matrix3d got = c->covariance_at(r, combination(points, r, p), 2.0 * mean);
    EXPECT_LT((got - 2.0 * want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff()) << p.transpose();
  }
}

TEST(FlangeErrorCovariance, EachPointsNoiseComesOffItsOwnBlock) {
  // Independent noise on each point's readings: the mean outer product less the noise is the
  // motion's part (here none: only noise), up to the sampling spread, and never negative definite.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> z;
  const Eigen::Vector2d noise_sd(0.01, 0.02);
  std::vector<Eigen::VectorXd> stacked;
  Eigen::MatrixXd moment = Eigen::MatrixXd::Zero(6, 6);
  for (int i = 0; i < 400; ++i) {
    Eigen::VectorXd e(6);
    for (int c = 0; c < 6; ++c) e[c] = noise_sd[c / 3] * z(rng);
    moment += e * e.transpose() / 400.0;
    stacked.push_back(e);
  }
  const Eigen::Vector2d noise_var = noise_sd.cwiseAbs2();
  const std::optional<FlangeErrorCovariance> c =
      FlangeErrorCovariance::of(stacked, std::vector<double>(400, 1e-3), noise_var);
  ASSERT_TRUE(c.has_value());
  Eigen::MatrixXd want = moment;
  for (int j = 0; j < 2; ++j) want.block<3, 3>(3 * j, 3 * j).diagonal().array() -= noise_var[j];
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c->field_covariance_mm2);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-15);
  // The nearest positive semi-definite matrix: it differs by the negative eigenvalues alone.
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(want).eigenvalues();
  EXPECT_NEAR((c->field_covariance_mm2 - want).norm(), lambda.cwiseMin(0.0).norm(), 1e-12);
  // What is left is the sampling spread of 400 draws, far below the noise taken off.
  EXPECT_LT(c->field_covariance_mm2.cwiseAbs().maxCoeff(), 0.25 * noise_var.minCoeff());
}

TEST(FlangeErrorCovariance, TooFewPosesOrNoVarianceClaimNothing) {
  std::vector<Eigen::VectorXd> stacked(FlangeErrorCovariance::kMinimumPoses - 1, Eigen::VectorXd::Ones(6));
  EXPECT_FALSE(FlangeErrorCovariance::of(stacked, std::vector<double>(stacked.size(), 1.0), Eigen::Vector2d::Zero()));
  stacked.push_back(Eigen::VectorXd::Ones(6));
  EXPECT_TRUE(FlangeErrorCovariance::of(stacked, std::vector<double>(stacked.size(), 1.0), Eigen::Vector2d::Zero()));
  EXPECT_FALSE(FlangeErrorCovariance::of(stacked, std::vector<double>(stacked.size(), 0.0), Eigen::Vector2d::Zero()));
}

}  // namespace flange_error_covariance_test
}  // namespace errfield::compensation
