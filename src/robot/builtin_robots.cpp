#include "errfield/robot/builtin_robots.hpp"

#include <algorithm>
#include <filesystem>
#include <cctype>

namespace errfield::robot {

MdhModel kr16() {
  // KUKA KR 16-2 (KR C2 generation) datasheet, principal dimensions (mm): A2 axis 675 above the
  // floor and 260 in front of A1; A2 -> A3 680; A4 axis 35 above A3; A3 -> wrist centre 670 (so the
  // wrist centre reaches 260 + 680 + 670 = 1610 from A1, the datasheet's 1611 mm reach); wrist
  // centre -> flange 158. Axis ranges from the same datasheet: A1 +-185, A2 [-155, 35],
  // A3 [-130, 154], A4 +-350, A5 +-130, A6 +-350.
  // errfield's joint convention (derived for this table, docs/robot.md): zero = upper arm and
  // forearm horizontal along +x; q1 turns about +z, q2, q3, q5 about +y (positive lowers the arm),
  // q4 and q6 about +x along the forearm; frame 6 z points out of the flange. A KUKA controller may
  // count some axes the other way round: check one known pose with `errfield fk`.
  const std::array<MdhLink, kJointCount> links{{
      {0.0, 0.0, 0.0, 675.0, 0.0, -185.0, 185.0},
      {-90.0, 260.0, 0.0, 0.0, 0.0, -155.0, 35.0},
      {0.0, 680.0, -90.0, 0.0, 0.0, -130.0, 154.0},
      {-90.0, 35.0, 0.0, 670.0, 0.0, -350.0, 350.0},
      {90.0, 0.0, 0.0, 0.0, 0.0, -130.0, 130.0},
      {-90.0, 0.0, 0.0, 158.0, 0.0, -350.0, 350.0},
  }};
  return MdhModel("KR16", links);
}

namespace {

// A Universal Robots arm from its published standard D-H lengths (mm): every UR arm has
// alpha = (90, 0, 0, 90, -90, 0) deg, theta offsets 0 and a1 = a4 = a5 = a6 = 0.
// Standard D-H Rz(q_i) Dz(d_i) Dx(a_i) Rx(alpha_i) regrouped as modified D-H: link i takes
// alpha_{i-1}, a_{i-1} of the previous standard row (0 for i = 1) and its own d_i; the last
// row's Dx(a_6) Rx(alpha_6) is the identity here, so frame 6 is UR's tool flange frame.
// Joint ranges: +-360 deg on every joint (UR datasheets, CB3 and e-Series alike).
MdhModel universal_robot(std::string name, double d1, double a2, double a3, double d4, double d5, double d6) {
  const std::array<MdhLink, kJointCount> links{{
      {0.0, 0.0, 0.0, d1, 0.0, -360.0, 360.0},
      {90.0, 0.0, 0.0, 0.0, 0.0, -360.0, 360.0},
      {0.0, a2, 0.0, 0.0, 0.0, -360.0, 360.0},
      {0.0, a3, 0.0, d4, 0.0, -360.0, 360.0},
      {90.0, 0.0, 0.0, d5, 0.0, -360.0, 360.0},
      {-90.0, 0.0, 0.0, d6, 0.0, -360.0, 360.0},
  }};
  return MdhModel(std::move(name), links);
}

}  // namespace

// Universal Robots, "Parameters for calculations of kinematics and dynamics" (UR support FAQ
// 45257), standard D-H, i = 1..6, alpha = (90, 0, 0, 90, -90, 0) deg:
MdhModel ur5e() {
  // e-Series software 5.1: a = (0, -425, -392.2, 0, 0, 0), d = (162.5, 0, 0, 133.3, 99.7, 99.6) mm.
  return universal_robot("UR5e", 162.5, -425.0, -392.2, 133.3, 99.7, 99.6);
}

MdhModel ur5() {
  // CB3 UR5: a = (0, -425, -392.25, 0, 0, 0), d = (89.159, 0, 0, 109.15, 94.65, 82.3) mm.
  return universal_robot("UR5", 89.159, -425.0, -392.25, 109.15, 94.65, 82.3);
}

MdhModel ur10() {
  // CB3 UR10: a = (0, -612, -572.3, 0, 0, 0), d = (127.3, 0, 0, 163.941, 115.7, 92.2) mm.
  return universal_robot("UR10", 127.3, -612.0, -572.3, 163.941, 115.7, 92.2);
}

const std::vector<BuiltinRobot>& builtin_robots() {
  // Cubes: inside each arm's reach at tool-down orientation (rx = 180), away from the base column
  // and from full stretch, so one IK branch covers the cube (tests/robot/builtin_robots_test.cpp).
  // The ER20-C10's is the paper's cube raised 150 mm and moved 50 mm out: without the paper's ball
  // (whose angles turn the flange) the paper's cube needs wrist angles beyond the joint limits.
  static const std::vector<BuiltinRobot> robots{
      {"er20-c10", "Efort ER20-C10, 20 kg, reach ~1.7 m (the paper's robot)",
       "SPEC Table 1 (the paper's MD-H table); joint limits plausible for the class", MdhModel::er20_c10(),
       Eigen::Vector3d(800, -250, 500), 500.0, Eigen::Vector3d(180, 0, 0)},
      {"kr16", "KUKA KR 16 class arm, 16 kg, reach 1.61 m to the wrist centre",
       "KUKA KR 16-2 datasheet principal dimensions and axis ranges", kr16(), Eigen::Vector3d(900, -250, 300), 500.0,
       Eigen::Vector3d(180, 0, 0)},
      {"ur5e", "Universal Robots UR5e, 5 kg, reach 850 mm",
       "Universal Robots D-H parameters (support FAQ 45257), standard D-H converted to modified D-H", ur5e(),
       Eigen::Vector3d(-550, -150, 100), 300.0, Eigen::Vector3d(180, 0, 0)},
      {"ur5", "Universal Robots UR5 (CB3), 5 kg, reach 850 mm",
       "Universal Robots D-H parameters (support FAQ 45257, CB3 UR5), standard D-H converted to modified D-H", ur5(),
       Eigen::Vector3d(-550, -150, 50), 300.0, Eigen::Vector3d(180, 0, 0)},
      {"ur10", "Universal Robots UR10 (CB3), 10 kg, reach 1300 mm",
       "Universal Robots D-H parameters (support FAQ 45257, CB3 UR10), standard D-H converted to modified D-H", ur10(),
       Eigen::Vector3d(-840, -230, 150), 460.0, Eigen::Vector3d(180, 0, 0)},
  };
  return robots;
}

const BuiltinRobot* find_builtin_robot(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (n == "er20" || n == "er20c10") n = "er20-c10";
  for (const BuiltinRobot& r : builtin_robots())
    if (r.name == n) return &r;
  return nullptr;
}

const BuiltinRobot* builtin_robot_unless_file(const std::string& name_or_path) {
  const BuiltinRobot* b = find_builtin_robot(name_or_path);
  if (!b) return nullptr;
  std::error_code ec;
  const auto status = std::filesystem::status(name_or_path, ec);
  const bool user_file = !ec && std::filesystem::exists(status) && !std::filesystem::is_directory(status);
  return user_file ? nullptr : b;
}

std::string builtin_robot_names() {
  std::string s;
  for (const BuiltinRobot& r : builtin_robots()) s += (s.empty() ? "" : ", ") + r.name;
  return s;
}

}  // namespace errfield::robot
