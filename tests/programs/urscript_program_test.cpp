// `errfield compensate-program` on URScript programs written to look like Polyscope's (SIMULATED
// UR5 and data): the pose conversion against an independent computation, bytes kept outside the
// rewritten numbers, the report's rows, the TCP refused by name, and a round trip through the
// simulated true robot.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <regex>

#include <Eigen/Dense>

#include "errfield/csv_table.hpp"
#include "errfield/programs/urscript_program.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "program_test_support.hpp"
#include "support/cli_harness.hpp"

namespace errfield::programs {
namespace urscript_program_test {

using namespace errfield::robot;
namespace fs = std::filesystem;
using program_test_support::split_numbers;

TEST(UrscriptPose, MetresAndRotationVectorAgreeWithAngleAxis) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0), angle(0.0, M_PI);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double a = angle(rng);
    const std::array<double, 6> p{u(rng), u(rng), u(rng), a * axis.x(), a * axis.y(), a * axis.z()};
    const Eigen::Isometry3d t = urscript_pose(p);
    EXPECT_LT((t.translation() - 1000.0 * Eigen::Vector3d(p[0], p[1], p[2])).norm(), 1e-9);
    const Eigen::Matrix3d by_hand = Eigen::AngleAxisd(a, axis).toRotationMatrix();
    ASSERT_LT((t.linear() - by_hand).norm(), 1e-12);
    const std::array<double, 6> back = urscript_pose_of(t);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k)], 1e-12);
    const Eigen::Vector3d w(back[3], back[4], back[5]);
    EXPECT_LT((Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() - by_hand).norm(), 1e-9);
  }
  // By hand: a quarter turn about z turns x onto y.
  EXPECT_LT((urscript_pose({0, 0, 0, 0, 0, M_PI / 2}).linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
}

TEST(ProgramNumberSpelling, KeepsThePointStyleOfTheOriginal) {
  EXPECT_EQ(format_program_number_like(".417101", 0.4171234567, 6), ".417123");
  EXPECT_EQ(format_program_number_like("-.191", -0.19, 6), "-.19");
  EXPECT_EQ(format_program_number_like("0.5", 0.25, 6), "0.25");
  EXPECT_EQ(format_program_number_like("100.0", 101.0, 3), "101.0");
  EXPECT_EQ(format_program_number_like("100", 101.0, 3), "101");
}

TEST(UrscriptRewrite, KeepsTheRotationVectorOnTheWrittenSideOfPi) {
  // Written: pi - 0.0001 rad about +z. Turned 0.001 rad further the angle passes pi: the same
  // rotation is (pi + 0.0009) about +z or (pi - 0.0009) about -z; the first is nearest the written.
  const std::string text = "set_tcp(p[0, 0, 0, 0, 0, 0])\nmovel(p[.4, -.1, .3, 0.0, 0.0, 3.141493], a=1.2)\n";
  const auto targets = read_urscript_targets({"r.script", text});
  ASSERT_EQ(targets.size(), 1u);
  ASSERT_TRUE(targets[0].rewrite);
  Eigen::Isometry3d now = targets[0].pose_in_frame;
  now.linear() = Eigen::AngleAxisd(3.141493 + 0.001, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  now.translation() += Eigen::Vector3d(0.5, 0.0, 0.0);
  const std::string out = apply_replacements(text, targets[0].rewrite(now));
  EXPECT_EQ(out, "set_tcp(p[0, 0, 0, 0, 0, 0])\nmovel(p[.4005, -.1, .3, 0.0, 0.0, 3.142493], a=1.2)\n");
}

// ---- the CLI on a SIMULATED UR5 and a kinematic model fitted on its SIMULATED readings.

using program_test_support::fixed;

// Polyscope's spelling: no zero before the point (".417101473398", "-.191099784478").
std::string polyscope(double v) {
  std::string s = fixed(v, 12);
  if (s.rfind("0.", 0) == 0) s.erase(0, 1);
  if (s.rfind("-0.", 0) == 0) s.erase(1, 1);
  return s;
}

struct UrSetup {
  static constexpr const char* kDirectory = "errfield_programs_ur";
  static constexpr const char* kSimulate = "--robot ur5 --seed 3 --sample grid --step 75";
};
using CompensateUrscript = program_test_support::FittedRobotTest<UrSetup>;

struct Script {
  std::string text;
  std::vector<Eigen::Isometry3d> intended;  // robot base frame, point i
  std::vector<JointVector> joints;
  Eigen::Isometry3d tool;
};

// Pose p[...] text of a pose in mm; the rotation vector from Eigen's AngleAxis (independent of
// urscript_pose_of).
std::string pose_text(const Eigen::Isometry3d& p, bool polyscope_style) {
  const Eigen::AngleAxisd aa(p.linear());
  const Eigen::Vector3d w = aa.angle() * aa.axis();
  const double v[6] = {p.translation().x() / 1000, p.translation().y() / 1000, p.translation().z() / 1000, w.x(), w.y(), w.z()};
  std::string s = "p[";
  for (int k = 0; k < 6; ++k) s += (k ? ", " : "") + (polyscope_style ? polyscope(v[k]) : fixed(v[k], 6));
  return s + "]";
}

// A Polyscope-like script: set_tcp, waypoints stored as poses and joint lists, movej to joints,
// movel to variables and inline poses, movec, pose_trans and get_inverse_kin. CRLF line ends.
Script make_script(const MdhModel& nominal, const std::vector<JointVector>& training, int count) {
  Script s;
  s.tool = nominal.tool();
  s.tool.linear() = s.tool.linear() * Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const MdhModel with_tool = nominal.with_tool(s.tool);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> jitter(-2.0, 2.0);
  const std::string nl = "\r\n";
  std::string vars, body;
  for (int i = 0; i < count; ++i) {
    JointVector q = training[static_cast<std::size_t>(i * 7 + 2) % training.size()];
    for (int k = 0; k < 6; ++k) q[k] += jitter(rng);
    s.joints.push_back(q);
    s.intended.push_back(forward_kinematics(with_tool, q));
  }
  for (int i = 0; i < count - 2; ++i) {
    const std::string w = "Waypoint_" + std::to_string(i);
    if (i % 2 == 0) {
      vars += "  global " + w + "_p=" + pose_text(s.intended[static_cast<std::size_t>(i)], true) + nl;
      std::string q = "  global " + w + "_q=[";
      JointVector stored = s.joints[static_cast<std::size_t>(i)];
      // Waypoint_0_q holds axis 2 a whole turn from the solution the IK finds (UR joints turn +-360
      // deg): the same configuration.
      if (i == 0) stored[1] += stored[1] > 0 ? -360.0 : 360.0;
      for (int k = 0; k < 6; ++k) q += (k ? ", " : "") + polyscope(stored[k] * M_PI / 180);
      vars += q + "]" + nl;
      body += "  movel(" + w + "_p, a=1.2, v=0.25)" + nl;
    } else {
      body += "  movel(" + pose_text(s.intended[static_cast<std::size_t>(i)], false) + ", a=1.2, v=0.25, r=0.001)  # point " +
              std::to_string(i) + nl;
    }
  }
  body += "  movec(" + pose_text(s.intended[static_cast<std::size_t>(count - 2)], false) + ", " +
          pose_text(s.intended[static_cast<std::size_t>(count - 1)], false) + ", a=1.2, v=0.25, r=0, mode=0)  # points" + nl;
  const Eigen::AngleAxisd ta(s.tool.linear());
  const Eigen::Vector3d tw = ta.angle() * ta.axis();
  s.text = "def zelle():" + nl + "  # Gr\xFC\xDF" "e: written by hand (SIMULATED), metres and radians" + nl + "  set_tcp(p[" +
           fixed(s.tool.translation().x() / 1000, 6) + ", " + fixed(s.tool.translation().y() / 1000, 6) + ", " +
           fixed(s.tool.translation().z() / 1000, 6) + ", " + fixed(tw.x(), 9) + ", " + fixed(tw.y(), 9) + ", " + fixed(tw.z(), 9) + "])" + nl +
           "  set_payload(1.0)" + nl + vars + "  movej(Waypoint_0_q, a=1.4, v=1.05)" + nl + body +
           "  movel(pose_trans(Waypoint_0_p, p[0, 0, -0.05, 0, 0, 0]), a=1.2, v=0.25)" + nl +
           "  movej(get_inverse_kin(Waypoint_2_p, qnear=Waypoint_2_q), a=1.4, v=1.05)" + nl + "end" + nl;
  return s;
}

Eigen::Isometry3d pose_of_numbers(const std::smatch& m, int first) {
  std::array<double, 6> v{};
  for (int k = 0; k < 6; ++k) v[static_cast<std::size_t>(k)] = std::stod(m[first + k]);
  const Eigen::Vector3d w(v[3], v[4], v[5]);
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() << 1000 * v[0], 1000 * v[1], 1000 * v[2];
  if (w.norm() > 0) p.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  return p;
}

std::map<int, Eigen::Isometry3d> points_of(const std::string& text, int count) {
  const std::string n = R"(([-+]?[0-9.]+(?:e[-+]?[0-9]+)?))";
  const std::string pose = R"(p\[)" + n + ", " + n + ", " + n + ", " + n + ", " + n + ", " + n + R"(\])";
  const std::regex waypoint("Waypoint_([0-9]+)_p=" + pose), inline_point("movel\\(" + pose + ".*# point ([0-9]+)"),
      circle("movec\\(" + pose + ", " + pose);
  std::map<int, Eigen::Isometry3d> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), waypoint); it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[1])] = pose_of_numbers(*it, 2);
  for (auto it = std::sregex_iterator(text.begin(), text.end(), inline_point); it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[7])] = pose_of_numbers(*it, 1);
  std::smatch m;
  if (std::regex_search(text, m, circle)) {
    out[count - 2] = pose_of_numbers(m, 1);
    out[count - 1] = pose_of_numbers(m, 7);
  }
  return out;
}

TEST_F(CompensateUrscript, RoundTripThroughTheSimulatedRobotLandsNearerAndKeepsEveryOtherByte) {
  const MdhModel nom = nominal(), tru = truth();
  constexpr int kPoints = 10;
  const Script s = make_script(nom, training_joints(), kPoints);
  write("zelle.script", s.text);
  const auto r = run("compensate-program --model " + shared("model.json") + " --program zelle.script --out out.script --report r.csv");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(read("zelle.script"), s.text);
  const std::string out = read("out.script");
  const auto a = split_numbers(s.text);
  const std::vector<std::size_t> changed_at = program_test_support::changed_numbers(s.text, out);
  const std::size_t changed = changed_at.size();
  for (std::size_t i : changed_at) {
    const std::string line = program_test_support::line_text(s.text, a.lines[i]);
    EXPECT_TRUE(line.find("_p=p[") != std::string::npos || line.find("movel(p[") != std::string::npos ||
                line.find("movec(p[") != std::string::npos)
        << line;
  }
  EXPECT_GT(changed, 2u * kPoints);

  // The report: movej to joints, 8 movel, movec's two poses, pose_trans, get_inverse_kin.
  const CsvTable rep = CsvTable::read(path("r.csv"));
  ASSERT_EQ(rep.row_count(), 1u + kPoints + 2u) << read("r.csv");
  auto row = [&](std::size_t i, std::size_t col) { return std::string(rep.cell(i, col)); };
  EXPECT_EQ(row(0, 3), "unchanged");
  for (std::size_t i = 1; i <= kPoints; ++i) EXPECT_EQ(row(i, 3), "ok") << row(i, 2) << ": " << row(i, 4);
  EXPECT_EQ(row(kPoints + 1, 3), "computed");
  EXPECT_NE(row(kPoints + 1, 4).find("Waypoint_0_p"), std::string::npos) << row(kPoints + 1, 4);
  EXPECT_EQ(row(kPoints + 2, 3), "computed");
  EXPECT_NE(row(kPoints + 2, 4).find("Waypoint_2_p"), std::string::npos) << row(kPoints + 2, 4);
  EXPECT_NE(r.out.find("factory kinematic calibration"), std::string::npos) << r.out;

  const auto before = points_of(s.text, kPoints), after = points_of(out, kPoints);
  ASSERT_EQ(before.size(), static_cast<std::size_t>(kPoints));
  ASSERT_EQ(after.size(), static_cast<std::size_t>(kPoints));
  const MdhModel controller = nom.with_tool(s.tool), robot = tru.with_tool(tru.tool() * nom.tool().inverse() * s.tool);
  std::vector<Eigen::Isometry3d> before_base, after_base;
  for (int i = 0; i < kPoints; ++i) {
    before_base.push_back(before.at(i));
    after_base.push_back(after.at(i));
  }
  program_test_support::expect_lands_nearer(controller, robot, program_test_support::base_from_world(shared_), before_base,
                                            after_base, s.intended, s.joints);
}

TEST_F(CompensateUrscript, TheTcpBeforeAnySetTcpIsRefusedByNameAndGivenByOption) {
  const Eigen::Isometry3d flange_point = nominal().tool();
  const Eigen::Isometry3d pose = forward_kinematics(nominal(),
                                                    training_joints()[10]);
  const std::string text = "def t():\n  movej([0, -1.57, 1.57, -1.57, -1.57, 0])\n  movel(" + pose_text(pose, false) + ")\nend\n";
  write("t.script", text);
  auto r = run("compensate-program --model " + shared("model.json") + " --program t.script --out o.script --report r.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output().find("set_tcp"), std::string::npos) << r.output();
  EXPECT_NE(r.output().find("--tool tcp="), std::string::npos) << r.output();
  EXPECT_FALSE(fs::exists(path("o.script")));
  const Eigen::Vector3d t = flange_point.translation() / 1000;
  const Eigen::AngleAxisd aa(flange_point.linear());
  const Eigen::Vector3d w = aa.angle() * aa.axis();
  r = run("compensate-program --model " + shared("model.json") + " --program t.script --out o.script --report r.csv --tool tcp=" +
          fixed(t.x(), 7) + "," + fixed(t.y(), 7) + "," + fixed(t.z(), 7) + "," + fixed(w.x(), 9) + "," + fixed(w.y(), 9) + "," + fixed(w.z(), 9));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable rep = CsvTable::read(path("r.csv"));
  ASSERT_EQ(rep.row_count(), 2u);
  EXPECT_EQ(std::string(rep.cell(0, 3)), "unchanged");
  EXPECT_EQ(std::string(rep.cell(1, 3)), "ok") << std::string(rep.cell(1, 4));
}

}  // namespace urscript_program_test
}  // namespace errfield::programs
