// The built-in robots against independent forward kinematics written here from the published
// numbers: the UR5e's standard D-H table as UR publishes it, the KR 16 as a chain of joint origins
// and axes (the datasheet's dimensions), so neither goes through errfield's MD-H code.

#include "errfield/robot/builtin_robots.hpp"

#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include <unistd.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::robot {
namespace builtin_robots_test {

constexpr double kDeg = std::numbers::pi / 180.0;

Eigen::Matrix4d rot(const Eigen::Vector3d& axis, double rad) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(rad, axis).toRotationMatrix();
  return m;
}
Eigen::Matrix4d trans(double x, double y, double z) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRightCorner<3, 1>() = Eigen::Vector3d(x, y, z);
  return m;
}

// Universal Robots support FAQ 45257: standard D-H in metres and radians, as published.
struct UrTable {
  double a[6], d[6];
};
const UrTable kUr5eTable{{0, -0.425, -0.3922, 0, 0, 0}, {0.1625, 0, 0, 0.1333, 0.0997, 0.0996}};
const UrTable kUr5Table{{0, -0.425, -0.39225, 0, 0, 0}, {0.089159, 0, 0, 0.10915, 0.09465, 0.0823}};
const UrTable kUr10Table{{0, -0.612, -0.5723, 0, 0, 0}, {0.1273, 0, 0, 0.163941, 0.1157, 0.0922}};

Eigen::Matrix4d ur_standard_dh(const UrTable& table, const JointVector& q_deg) {
  const double* a = table.a;
  const double* d = table.d;
  const double alpha[6] = {std::numbers::pi / 2, 0, 0, std::numbers::pi / 2, -std::numbers::pi / 2, 0};
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 6; ++i) {
    const double th = q_deg[i] * kDeg, ct = std::cos(th), st = std::sin(th), ca = std::cos(alpha[i]),
                 sa = std::sin(alpha[i]);
    Eigen::Matrix4d a_i;  // the textbook standard D-H matrix
    a_i << ct, -st * ca, st * sa, a[i] * ct, st, ct * ca, -ct * sa, a[i] * st, 0, sa, ca, d[i], 0, 0, 0, 1;
    t = t * a_i;
  }
  t.topRightCorner<3, 1>() *= 1000.0;  // m -> mm
  return t;
}

// KR 16 class arm from its datasheet dimensions (mm), as joint origins and axes at the zero pose
// (arm stretched along +x): A1 about z at the base; A2 about y, 260 forward and 675 up; A3 about y,
// 680 further; A4 about x, 35 above A3; A5 about y, 670 further; A6 about x at the wrist centre;
// the flange 158 beyond, its z out of the flange and its x up.
Eigen::Matrix4d kr16_chain(const JointVector& q_deg) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  Eigen::Matrix4d flange = trans(158, 0, 0);
  flange.topLeftCorner<3, 3>() << 0, 0, 1, 0, -1, 0, 1, 0, 0;  // columns: x6 = +z, y6 = -y, z6 = +x
  return rot(z, q_deg[0] * kDeg) * trans(260, 0, 675) * rot(y, q_deg[1] * kDeg) * trans(680, 0, 0) *
         rot(y, q_deg[2] * kDeg) * trans(0, 0, 35) * rot(x, q_deg[3] * kDeg) * trans(670, 0, 0) *
         rot(y, q_deg[4] * kDeg) * rot(x, q_deg[5] * kDeg) * flange;
}

JointVector random_joints(const MdhModel& m, std::mt19937_64& rng) {
  JointVector q;
  for (int j = 0; j < kJointCount; ++j)
    q[j] = std::uniform_real_distribution<double>(m.link(j).q_min_deg, m.link(j).q_max_deg)(rng);
  return q;
}

TEST(BuiltinRobots, UniversalRobotsMatchPublishedStandardDh) {
  for (const auto& [m, table] : {std::pair{ur5e(), kUr5eTable}, std::pair{ur5(), kUr5Table}, std::pair{ur10(), kUr10Table}}) {
    std::mt19937_64 rng(3);
    for (int k = 0; k < 200; ++k) {
      const JointVector q = random_joints(m, rng);
      const Eigen::Matrix4d want = ur_standard_dh(table, q);
      const Eigen::Matrix4d got = forward_kinematics(m, q, EndFrame::flange).matrix();
      EXPECT_LT((got.topLeftCorner<3, 3>() - want.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-12)
          << m.name() << " " << q.transpose();
      EXPECT_LT((got.topRightCorner<3, 1>() - want.topRightCorner<3, 1>()).norm(), 1e-9) << m.name() << " " << q.transpose();
    }
  }
  const MdhModel m = ur5e();
  // Zero pose, by hand: the arm lies along -x, the wrist offsets d4 and d6 along -y, d5 down:
  // flange at x = a2 + a3 = -817.2, y = -(d4 + d6) = -232.9, z = d1 - d5 = 62.8 mm.
  const Eigen::Vector3d p0 = forward_kinematics(m, JointVector::Zero(), EndFrame::flange).translation();
  EXPECT_NEAR(p0.x(), -817.2, 1e-9);
  EXPECT_NEAR(p0.y(), -232.9, 1e-9);
  EXPECT_NEAR(p0.z(), 62.8, 1e-9);
  // The same for the CB3 UR5 (-817.25, -191.45, -5.491) and UR10 (-1184.3, -256.141, 11.6).
  EXPECT_LT((forward_kinematics(ur5(), JointVector::Zero(), EndFrame::flange).translation() -
             Eigen::Vector3d(-817.25, -191.45, -5.491)).norm(), 1e-9);
  EXPECT_LT((forward_kinematics(ur10(), JointVector::Zero(), EndFrame::flange).translation() -
             Eigen::Vector3d(-1184.3, -256.141, 11.6)).norm(), 1e-9);
}

TEST(BuiltinRobots, Kr16MatchesJointAxisChainFromDatasheet) {
  const MdhModel m = kr16();
  std::mt19937_64 rng(4);
  for (int k = 0; k < 200; ++k) {
    const JointVector q = random_joints(m, rng);
    const Eigen::Matrix4d want = kr16_chain(q);
    const Eigen::Matrix4d got = forward_kinematics(m, q, EndFrame::flange).matrix();
    EXPECT_LT((got.topLeftCorner<3, 3>() - want.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-12) << q.transpose();
    EXPECT_LT((got.topRightCorner<3, 1>() - want.topRightCorner<3, 1>()).norm(), 1e-9) << q.transpose();
  }
  // Zero pose: wrist centre at the datasheet reach 260 + 680 + 670 = 1610 mm, 675 + 35 high; the
  // home pose (A2 -90, A3 90): upper arm vertical, forearm horizontal.
  JointVector home;
  home << 0, -90, 90, 0, 0, 0;
  EXPECT_LT((forward_kinematics(m, JointVector::Zero(), EndFrame::flange).translation() -
             Eigen::Vector3d(1610 + 158, 0, 710)).norm(), 1e-9);
  EXPECT_LT((forward_kinematics(m, home, EndFrame::flange).translation() - Eigen::Vector3d(1088, 0, 1390)).norm(), 1e-9);
}

TEST(BuiltinRobots, FoundByNameCaseInsensitively) {
  ASSERT_NE(find_builtin_robot("KR16"), nullptr);
  EXPECT_EQ(find_builtin_robot("KR16")->model.name(), "KR16");
  ASSERT_NE(find_builtin_robot("er20"), nullptr);
  EXPECT_EQ(find_builtin_robot("er20")->name, "er20-c10");
  ASSERT_NE(find_builtin_robot("UR10"), nullptr);
  EXPECT_EQ(find_builtin_robot("UR10")->model.name(), "UR10");
  EXPECT_EQ(find_builtin_robot("ur5")->model.name(), "UR5");
  EXPECT_EQ(find_builtin_robot("ur"), nullptr);
  EXPECT_EQ(builtin_robot_names(), "er20-c10, kr16, ur5e, ur5, ur10");
}

// A user who keeps each robot's outputs in a folder named after it ("kr16/") still means the
// built-in robot; a file of that name is the user's robot JSON.
TEST(BuiltinRobots, NameBeatsADirectoryButNotAFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("errfield_builtin_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "kr16");
  std::ofstream(dir / "ur5e") << "{}";
  const auto old = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  const BuiltinRobot* from_dir = builtin_robot_unless_file("kr16");
  const BuiltinRobot* from_file = builtin_robot_unless_file("ur5e");
  const BuiltinRobot* absent = builtin_robot_unless_file("er20-c10");
  std::filesystem::current_path(old);
  std::filesystem::remove_all(dir);
  ASSERT_NE(from_dir, nullptr);
  EXPECT_EQ(from_dir->name, "kr16");
  EXPECT_EQ(from_file, nullptr);
  ASSERT_NE(absent, nullptr);
  EXPECT_EQ(builtin_robot_unless_file("not-a-robot"), nullptr);
}

TEST(BuiltinRobots, DefaultCubesAreReachableOnOneBranch) {
  for (const BuiltinRobot& r : builtin_robots()) {
    MeasurementCube cube;
    cube.min_corner_mm = r.cube_min_mm;
    cube.size_mm = r.cube_size_mm;
    cube.orientation = rotation_from_rpy_deg(r.cube_rpy_deg.x(), r.cube_rpy_deg.y(), r.cube_rpy_deg.z());
    const IkResult seed = cube_seed(r.model, cube);
    ASSERT_TRUE(seed.ok()) << r.name;
    for (const Eigen::Vector3d& p : cube.grid(cube.size_mm / 4)) {
      const IkResult s = solve_cube_pose(r.model, cube, p, seed.q_deg);
      ASSERT_TRUE(s.ok()) << r.name << " " << p.transpose();
      // One branch: no joint far from the seed (a flip moves a joint by ~180 deg).
      EXPECT_LT((s.q_deg - seed.q_deg).cwiseAbs().maxCoeff(), 120.0) << r.name << " " << p.transpose();
      EXPECT_TRUE(r.model.within_limits(s.q_deg)) << r.name;
    }
  }
}

}  // namespace
}  // namespace errfield::robot
