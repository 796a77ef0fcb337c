// errfield's arm configuration flags (robot/arm_configuration.hpp) against the controllers' own
// configuration data for the built-in robots, each side computed independently: the KUKA Status
// bits of the KR16 from its datasheet geometry written out here in closed form (wrist root point in
// the A1 frame, the A3 angle at which the elbow is stretched), and the elbow and wrist choices of the
// UR5e's analytic inverse kinematics (signs of q3 and q5). docs/robot.md, "Arm configuration",
// states the mapping these tests check.

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "errfield/robot/arm_configuration.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield {
namespace arm_configuration_test {

constexpr double kDeg = std::numbers::pi / 180.0;

/// Joints drawn uniformly inside the model's limits (clipped to +-180 deg), deterministic.
robot::JointVector random_joints(const robot::MdhModel& m, std::mt19937& rng) {
  robot::JointVector q;
  for (int j = 0; j < robot::kJointCount; ++j) {
    const auto& l = m.link(static_cast<std::size_t>(j));
    std::uniform_real_distribution<double> u(std::max(l.q_min_deg, -180.0), std::min(l.q_max_deg, 180.0));
    q[j] = u(rng);
  }
  return q;
}

/// KR 16 datasheet geometry (mm) in errfield's joint convention (docs/robot.md): A2 axis 260 in front
/// of A1, upper arm 680, A4 axis 35 above A3, A3 -> wrist root point 670; q2 and q3 about +y, so
/// positive lowers the arm. x of the wrist root point in the A1 frame (which turns with A1).
double kr16_wrist_x_in_a1(const robot::JointVector& q) {
  const double a2 = q[1] * kDeg, a23 = (q[1] + q[2]) * kDeg;
  return 260.0 + 680.0 * std::cos(a2) + 670.0 * std::cos(a23) + 35.0 * std::sin(a23);
}

/// The A3 angle (deg) at which the wrist root point lies on the line through A2 and A3 (the elbow
/// stretched): the forearm's 35 mm offset over 670 mm tilts the wrist point atan(35/670) above the
/// forearm axis.
double kr16_stretched_a3_deg() { return std::atan2(35.0, 670.0) / kDeg; }

TEST(ArmConfiguration, Kr16FlagsAreKukaStatusBits) {
  const robot::MdhModel m = robot::kr16();
  std::mt19937 rng(11);
  int checked = 0, overhead = 0, bent_down = 0, wrist_negative = 0;
  for (int i = 0; i < 2000; ++i) {
    const robot::JointVector q = random_joints(m, rng);
    const robot::ArmConfiguration c = robot::arm_configuration(m, q);
    // Status bit 0 (overhead area): the wrist root point has x < 0 in the A1 frame <=> s-.
    const double wx = kr16_wrist_x_in_a1(q);
    robot::KinematicFrames f;
    robot::forward_kinematics_all(m, q, f);
    const double wrist_distance = (f.frames[5].translation() - f.frames[1].translation()).norm();
    if (std::abs(wx) > std::sin(1.5 * kDeg) * wrist_distance) {
      EXPECT_EQ(c.shoulder, wx > 0 ? 1 : -1) << "q " << q.transpose();
      overhead += wx < 0;
    }
    // Status bit 1: A3 at or beyond the stretched angle <=> e+ (sense found at KUKA's home
    // A2 = -90, A3 = 90, whose Status is 'B010').
    const double from_stretched = q[2] - kr16_stretched_a3_deg();
    if (std::abs(from_stretched) > 1.5) {
      EXPECT_EQ(c.elbow, from_stretched > 0 ? 1 : -1) << "q " << q.transpose();
      bent_down += from_stretched > 0;
    }
    // Status bit 2 (wrist): the sign of A5 <=> w.
    if (std::abs(q[4]) > 1.5) {
      EXPECT_EQ(c.wrist, q[4] > 0 ? 1 : -1) << "q " << q.transpose();
      wrist_negative += q[4] < 0;
    }
    ++checked;
  }
  // Both sides of every boundary were visited.
  EXPECT_GT(overhead, 20);
  EXPECT_GT(bent_down, 200);
  EXPECT_LT(bent_down, checked - 200);
  EXPECT_GT(wrist_negative, 200);
  // KUKA's home position: Status 'B010' = basic area, bit 1 set.
  robot::JointVector home;
  home << 0, -90, 90, 0, 30, 0;
  const robot::ArmConfiguration h = robot::arm_configuration(m, home);
  EXPECT_EQ(h.shoulder, 1);
  EXPECT_EQ(h.elbow, 1);
}

TEST(ArmConfiguration, Ur5eElbowAndWristAreTheSignsOfQ3AndQ5) {
  // UR's analytic IK returns up to 8 solutions: two shoulder (q1), two wrist (q5 = +-acos(...)) and
  // two elbow (q3 = +-acos(...)) choices; with UR's own joint values (the built-in table is UR's),
  // the elbow and wrist choices are the signs of q3 and q5.
  const robot::MdhModel m = robot::ur5e();
  std::mt19937 rng(5);
  int elbow_negative = 0, wrist_negative = 0;
  for (int i = 0; i < 2000; ++i) {
    const robot::JointVector q = random_joints(m, rng);
    const robot::ArmConfiguration c = robot::arm_configuration(m, q);
    const double q3 = std::remainder(q[2], 360.0), q5 = std::remainder(q[4], 360.0);
    if (std::abs(q3) > 1.5 && std::abs(std::abs(q3) - 180.0) > 1.5) {
      EXPECT_EQ(c.elbow, std::sin(q3 * kDeg) > 0 ? 1 : -1) << "q " << q.transpose();
      elbow_negative += q3 < 0;
    }
    if (std::abs(q5) > 1.5 && std::abs(std::abs(q5) - 180.0) > 1.5) {
      EXPECT_EQ(c.wrist, std::sin(q5 * kDeg) > 0 ? 1 : -1) << "q " << q.transpose();
      wrist_negative += q5 < 0;
    }
  }
  EXPECT_GT(elbow_negative, 200);
  EXPECT_GT(wrist_negative, 200);
}

TEST(ArmConfiguration, Ur5eShoulderIsTheShoulderChoiceOfUrsAnalyticIk) {
  // UR's analytic IK (standard D-H, d4 = 133.3 mm, d6 = 99.6 mm): with p05 the point d6 behind the
  // flange along its z axis, q1 = atan2(p05y, p05x) +- acos(d4 / |p05xy|) + 90 deg. Which sign
  // reproduces q1 is the shoulder choice; it must be errfield's shoulder flag (one fixed sense).
  const robot::MdhModel m = robot::ur5e();
  std::mt19937 rng(8);
  int plus = 0, minus = 0, same = 0, opposite = 0;
  for (int i = 0; i < 2000; ++i) {
    const robot::JointVector q = random_joints(m, rng);
    const Eigen::Isometry3d flange = robot::forward_kinematics(m, q, robot::EndFrame::flange);
    const Eigen::Vector3d p05 = flange.translation() - 99.6 * flange.linear().col(2);
    const double r = std::hypot(p05.x(), p05.y());
    if (r < 133.3 * 1.05) continue;  // within 5 % of the shoulder singularity
    const double phi = std::atan2(p05.y(), p05.x()), psi = std::acos(133.3 / r);
    auto off = [&](double q1) { return std::abs(std::remainder(q1 - q[0] * kDeg, 2.0 * std::numbers::pi)); };
    const double e_plus = off(phi + psi + std::numbers::pi / 2), e_minus = off(phi - psi + std::numbers::pi / 2);
    ASSERT_LT(std::min(e_plus, e_minus), 1e-9) << "q " << q.transpose();
    if (std::abs(psi) < 1.5 * kDeg) continue;
    const int choice = e_plus < e_minus ? 1 : -1;
    (choice > 0 ? plus : minus) += 1;
    const int s = robot::arm_configuration(m, q).shoulder;
    if (s == 0) continue;
    (s == choice ? same : opposite) += 1;
  }
  EXPECT_GT(plus, 200);
  EXPECT_GT(minus, 200);
  // s+ is the "- acos" solution (docs/robot.md), on every sample away from the band.
  EXPECT_EQ(same, 0);
  EXPECT_GT(opposite, 1000);
}

}  // namespace arm_configuration_test
}  // namespace errfield
