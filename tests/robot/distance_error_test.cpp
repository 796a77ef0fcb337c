#include "errfield/robot/distance_error.hpp"

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace errfield::robot {
namespace distance_error_test {

Eigen::Vector3d random_vector(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> n(0.0, scale);
  return {n(rng), n(rng), n(rng)};
}

TEST(DistanceError, ExactFormIsTheDifferenceOfLengths) {
  const BasePoint b = BasePoint::fixed({100, 200, 300});
  const Eigen::Vector3d p(400, 600, 300), pa(403, 604, 300);  // nominal 500 (3-4-5), actual 505
  EXPECT_NEAR(distance_error(b, p, pa), 5.0, 1e-12);
  const BasePoint r = BasePoint::robot_position({0, 0, 0}, {0, 0, 1});
  EXPECT_NEAR(distance_error(r, Eigen::Vector3d(0, 0, 100), Eigen::Vector3d(0, 0, 100)), -1.0, 1e-12);
  EXPECT_NEAR(distance_error(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 100),
                             Eigen::Vector3d(0, 0, 100)),
              -1.0, 1e-12);
}

TEST(DistanceError, LinearizationErrorIsSecondOrder) {
  // |exact − linear| <= |dP − dP0|² / L (the tangential part's Pythagorean excess), for fixed and
  // robot-position bases.
  std::mt19937_64 rng(1);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d p0 = random_vector(rng, 500), p = random_vector(rng, 500);
    const Eigen::Vector3d dp = random_vector(rng, 0.5), dp0 = random_vector(rng, 0.5);
    const double len = (p - p0).norm();
    if (len < 100) continue;
    const BasePoint fixed = BasePoint::fixed(p0);
    EXPECT_NEAR(distance_error(fixed, p, p + dp), linearized_distance_error(fixed, p, dp), dp.squaredNorm() / len);
    const BasePoint robot = BasePoint::robot_position(p0, p0 + dp0);
    EXPECT_NEAR(distance_error(robot, p, p + dp), linearized_distance_error(robot, p, dp),
                (dp - dp0).squaredNorm() / len);
  }
}

TEST(DistanceError, ProjectionIsAlongTheBaseToTargetDirection) {
  const Eigen::Vector3d p0(0, 0, 0), p(300, 400, 0);
  const Eigen::Vector3d dp = project_distance_error(0.2, p0, p);
  EXPECT_NEAR(dp.x(), 0.12, 1e-15);
  EXPECT_NEAR(dp.y(), 0.16, 1e-15);
  EXPECT_EQ(dp.z(), 0.0);
  // Its linearized distance error is the scalar back (n · (dL m) = dL).
  EXPECT_NEAR(linearized_distance_error(BasePoint::fixed(p0), p, dp), 0.2, 1e-15);
  EXPECT_THROW(project_distance_error(0.1, p, p), ArgumentError);
}

TEST(DistanceError, RecoversTheFullVectorFromFourBases) {
  std::mt19937_64 rng(2);
  const std::vector<Eigen::Vector3d> bases{{0, 0, 0}, {1500, 0, 0}, {0, 1500, 0}, {0, 0, 1500}};
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d p = Eigen::Vector3d(600, 500, 400) + random_vector(rng, 100);
    const Eigen::Vector3d dp = random_vector(rng, 0.5);
    std::vector<double> dl;
    for (const auto& b : bases) dl.push_back(distance_error(BasePoint::fixed(b), p, p + dp));
    const auto exact = recover_position_error(bases, dl, p, true);
    ASSERT_TRUE(exact.ok) << exact.message;
    EXPECT_LT((exact.position_error_mm - dp).norm(), 1e-10);  // exact equations, no noise
    EXPECT_LT(exact.residual_rms_mm, 1e-12);
    EXPECT_LT(exact.condition_number, 10.0);
    const auto linear = recover_position_error(bases, dl, p, false);
    EXPECT_LT((linear.position_error_mm - dp).norm(), 3 * dp.squaredNorm() / 500.0);  // O(|dP|²/L)
  }
}

TEST(DistanceError, DilutionPredictsNoiseAmplification) {
  // With per-distance noise sigma, the RMS of the dP error is sigma * dilution (least-squares theory).
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  const std::vector<Eigen::Vector3d> bases{{0, 0, 0}, {1500, 0, 0}, {0, 1500, 0}, {0, 0, 1500}, {1500, 1500, 0}};
  const Eigen::Vector3d p(700, 600, 500);
  double sq = 0;
  const int n = 4000;
  double dilution = 0;
  for (int k = 0; k < n; ++k) {
    std::vector<double> dl;
    for (std::size_t b = 0; b < bases.size(); ++b) dl.push_back(noise(rng));  // true dP = 0
    const auto r = recover_position_error(bases, dl, p, false);
    sq += r.position_error_mm.squaredNorm();
    dilution = r.dilution;
  }
  const double rms = std::sqrt(sq / n);
  EXPECT_NEAR(rms, 0.01 * dilution, 0.05 * 0.01 * dilution);  // 4000 samples: ~1.3% sampling error
}

TEST(DistanceError, DegenerateGeometryIsReportedNotSolved) {
  const Eigen::Vector3d p(500, 500, 0);
  // All bases and the point in the plane z = 0: the z component is unobservable.
  const std::vector<Eigen::Vector3d> planar{{0, 0, 0}, {1000, 0, 0}, {0, 1000, 0}, {1000, 1000, 0}};
  const std::vector<double> dl{0.1, 0.2, 0.3, 0.4};
  const auto r = recover_position_error(planar, dl, p);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("coplanar"), std::string::npos);
  const std::vector<Eigen::Vector3d> two{{0, 0, 0}, {1000, 0, 0}};
  EXPECT_FALSE(recover_position_error(two, std::vector<double>{0.1, 0.2}, p).ok);
  EXPECT_THROW(recover_position_error(two, std::vector<double>{0.1}, p), ArgumentError);
}

}  // namespace
}  // namespace errfield::robot
