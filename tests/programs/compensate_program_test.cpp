// `errfield compensate-program` on RAPID modules written to look like real ones (SIMULATED robot
// and data): bytes kept outside the rewritten numbers, the report's rows and statuses, confdata
// against an independent computation, and a round trip through the simulated true robot.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <regex>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/programs/abb_confdata.hpp"
#include "errfield/programs/program_text.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/robot/pose.hpp"
#include "program_test_support.hpp"
#include "support/cli_harness.hpp"

namespace errfield::programs {
namespace compensate_program_test {

using namespace errfield::robot;
namespace fs = std::filesystem;

// ---- an independent confdata: wrist centre as the closest point of axes 4 and 5, "in front" from
// 2-D geometry in the arm's vertical plane (axis 1 vertical), not from link frame 1's x axis.
Eigen::Vector3d closest_point_of_axes(const Eigen::Vector3d& p1, const Eigen::Vector3d& d1, const Eigen::Vector3d& p2,
                                      const Eigen::Vector3d& d2) {
  const Eigen::Vector3d w = p1 - p2;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double den = a * c - b * b;
  const double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
  return 0.5 * ((p1 + s * d1) + (p2 + t * d2));
}

struct ArmPlane {
  double ahead_axis1 = 0, side_lower_arm = 0;
};

ArmPlane arm_plane(const MdhModel& m, const JointVector& q) {
  KinematicFrames f;
  forward_kinematics_all(m, q, f);
  const Eigen::Vector3d wc = closest_point_of_axes(f.frames[4].translation(), f.frames[4].linear().col(2),
                                                   f.frames[5].translation(), f.frames[5].linear().col(2));
  const Eigen::Vector3d o1 = f.frames[1].translation(), z1 = f.frames[1].linear().col(2);
  // Forward at q1: the home posture's horizontal direction to the wrist turned by q1 about axis 1.
  JointVector home = JointVector::Zero();
  home[4] = 30.0;
  KinematicFrames h;
  forward_kinematics_all(m, home, h);
  const Eigen::Vector3d wh = closest_point_of_axes(h.frames[4].translation(), h.frames[4].linear().col(2),
                                                   h.frames[5].translation(), h.frames[5].linear().col(2));
  Eigen::Vector3d fwd0 = wh - o1;
  fwd0 -= fwd0.dot(z1) * z1;
  const Eigen::Vector3d fwd = Eigen::AngleAxisd(q[0] * M_PI / 180.0, z1) * fwd0.normalized();
  auto rz = [&](const Eigen::Vector3d& p) { return Eigen::Vector2d((p - o1).dot(fwd), (p - o1).dot(z1)); };
  const Eigen::Vector2d a = rz(f.frames[2].translation()), b = rz(f.frames[3].translation()), w = rz(wc);
  const Eigen::Vector2d arm = b - a, to_w = w - a;
  return {(wc - o1).dot(fwd), arm.x() * to_w.y() - arm.y() * to_w.x()};
}

AbbConfdata independent_confdata(const MdhModel& m, const JointVector& q) {
  JointVector home = JointVector::Zero();
  home[4] = 30.0;
  const ArmPlane ref = arm_plane(m, home), now = arm_plane(m, q);
  AbbConfdata c;
  c.cf1 = static_cast<int>(std::floor(q[0] / 90.0));
  c.cf4 = static_cast<int>(std::floor(q[3] / 90.0));
  c.cf6 = static_cast<int>(std::floor(q[5] / 90.0));
  c.cfx = 4 * (now.ahead_axis1 * ref.ahead_axis1 < 0) + 2 * (now.side_lower_arm * ref.side_lower_arm < 0) + (q[4] < 0);
  return c;
}

TEST(AbbConfdata, AgreesWithAnIndependentComputationFromJointAngles) {
  const MdhModel m = find_builtin_robot("er20-c10")->model;
  std::mt19937 rng(7);
  int seen[3][2] = {};  // each cfx bit seen clear and set
  for (int i = 0; i < 3000; ++i) {
    JointVector q;
    for (int k = 0; k < 6; ++k) {
      std::uniform_real_distribution<double> u(m.q_min_deg()[k], m.q_max_deg()[k]);
      q[k] = u(rng);
    }
    const ArmPlane p = arm_plane(m, q);
    if (std::abs(p.ahead_axis1) < 1.0 || std::abs(p.side_lower_arm) < 1.0 || std::abs(q[4]) < 1e-3) continue;  // on a boundary
    const AbbConfdata a = abb_confdata(m, q), b = independent_confdata(m, q);
    ASSERT_EQ(a, b) << "q = " << q.transpose() << ": " << a.to_string() << " vs " << b.to_string();
    for (int bit = 0; bit < 3; ++bit) ++seen[bit][(a.cfx >> bit) & 1];
  }
  for (int bit = 0; bit < 3; ++bit)
    EXPECT_TRUE(seen[bit][0] > 0 && seen[bit][1] > 0) << "cfx bit " << bit << " drawn on one side only";
  // By hand: home with axis 5 positive is [0,0,0,0]; quadrants round down.
  JointVector q = JointVector::Zero();
  q[4] = 30.0;
  EXPECT_EQ(abb_confdata(m, q), (AbbConfdata{0, 0, 0, 0}));
  q << -10.0, 0.0, 0.0, 190.0, -30.0, -95.0;
  EXPECT_EQ(abb_confdata(m, q), (AbbConfdata{-1, 2, -2, 1}));
}

TEST(ProgramText, ReplacementsChangeOnlyTheirSpans) {
  const std::string s = "a 1.5 b\r\n\xE9 -2 c";
  const std::string out = apply_replacements(s, {{{11, 13}, "-2.25"}, {{2, 5}, "7"}});
  EXPECT_EQ(out, "a 7 b\r\n\xE9 -2.25 c");
  EXPECT_EQ(line_of_offset(s, 10), 2u);
  EXPECT_EQ(format_program_number(-0.00001, 3), "0");
  EXPECT_EQ(format_program_number(512.3456, 3), "512.346");
  EXPECT_EQ(format_program_number(100.0, 3), "100");
}

// ---- the CLI on a SIMULATED robot and a kinematic model fitted on its SIMULATED readings.

using program_test_support::fixed;

std::string pose_text(const Eigen::Isometry3d& p) {
  const Eigen::Quaterniond q(p.linear());
  return "[" + fixed(p.translation().x(), 2) + "," + fixed(p.translation().y(), 2) + "," + fixed(p.translation().z(), 2) + "],[" +
         fixed(q.w(), 7) + "," + fixed(q.x(), 7) + "," + fixed(q.y(), 7) + "," + fixed(q.z(), 7) + "]";
}

using program_test_support::split_numbers;
using program_test_support::Numbers;

// A SIMULATED ER20-C10 with the paper's errors, its nominal description, the true geometry, and a
// kinematic model fitted on 125 grid readings (shared by the tests: fitted once).
struct RapidSetup {
  static constexpr const char* kDirectory = "errfield_programs_rapid";
  static constexpr const char* kSimulate = "--seed 1 --sample grid --step 125";
};
using CompensateProgram = program_test_support::FittedRobotTest<RapidSetup>;

// A Latin-1, CRLF module: a rotated tool and a work object declared in it, declared and inline
// robtargets (one declared target used twice), Offs, MoveAbsJ, 9E9 external axes, comments.
struct Module {
  std::string text;
  std::vector<Eigen::Isometry3d> intended;  // robot base frame, per literal in order of first use
  std::vector<JointVector> joints;          // the nominal joints they were made from
  Eigen::Isometry3d tool, wobj;
};

Module make_module(const MdhModel& nominal, const std::vector<JointVector>& training, int count) {
  Module m;
  // The simulated robot's tool (the ball the readings are of): the program's tool is that point,
  // declared rotated 30 deg about z (the rotation does not move the point).
  m.tool = nominal.tool();
  m.tool.linear() = m.tool.linear() * Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  m.wobj = Eigen::Isometry3d::Identity();
  m.wobj.translation() << 100.0, -50.0, 20.0;
  m.wobj.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const MdhModel with_tool = nominal.with_tool(m.tool);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-2.0, 2.0);
  std::string decl, body;
  const std::string crlf = "\r\n";
  for (int i = 0; i < count; ++i) {
    JointVector q = training[static_cast<std::size_t>(i * 7 + 3) % training.size()];
    for (int k = 0; k < 6; ++k) q[k] += jitter(rng);
    const Eigen::Isometry3d base = forward_kinematics(with_tool, q);
    m.intended.push_back(base);
    m.joints.push_back(q);
    const AbbConfdata c = independent_confdata(nominal, q);
    const std::string conf = "[" + std::to_string(c.cf1) + "," + std::to_string(c.cf4) + "," + std::to_string(c.cf6) + "," +
                             std::to_string(c.cfx) + "]";
    const std::string lit = "[" + pose_text(m.wobj.inverse() * base) + "," + conf + ",[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]";
    if (i % 2 == 0) {
      decl += "  CONST robtarget p" + std::to_string(i) + ":=" + lit + ";" + crlf;
      body += "    MoveL p" + std::to_string(i) + ", v200, fine, tGreifer\\WObj:=wVorrichtung;   ! Position " +
              std::to_string(i) + " \xFC" "ber dem Teil" + crlf;
    } else {
      body += "    MoveJ " + lit + ", v500, z10, tGreifer \\WObj:=wVorrichtung;" + crlf;
    }
  }
  body += "    MoveL Offs(p0,0,0,50), v100, z5, tGreifer\\WObj:=wVorrichtung;" + crlf;
  body += "    MoveL p0, v100, fine, tGreifer\\WObj:=wVorrichtung;  ! p0 again" + crlf;
  body += "    MoveAbsJ [[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, v1000, z50, tool0;" + crlf;
  const Eigen::Quaterniond tq(m.tool.linear()), wq(m.wobj.linear());
  std::string text = "%%%" + crlf + "  VERSION:1" + crlf + "  LANGUAGE:ENGLISH" + crlf + "%%%" + crlf + crlf +
                     "MODULE Zelle_G\xE4rtner" + crlf + "  ! Gr\xFC\xDF" "e: erzeugt von Hand, Ma\xDF" "e in mm" + crlf;
  text += "  PERS tooldata tGreifer:=[TRUE,[[" + fixed(m.tool.translation().x(), 4) + "," + fixed(m.tool.translation().y(), 4) +
          "," + fixed(m.tool.translation().z(), 4) + "],[" + fixed(tq.w(), 9) + "," + fixed(tq.x(), 9) + "," + fixed(tq.y(), 9) + "," +
          fixed(tq.z(), 9) + "]],[1.2,[0,0,50],[1,0,0,0],0,0,0]];" + crlf;
  // uframe o oframe: the user frame shifted 10 mm along its x, the object frame 10 mm back.
  const Eigen::Isometry3d uf = m.wobj * Eigen::Translation3d(10, 0, 0);
  const Eigen::Quaterniond uq(uf.linear());
  text += "  TASK PERS wobjdata wVorrichtung:=[FALSE,TRUE,\"\",[[" + fixed(uf.translation().x(), 6) + "," +
          fixed(uf.translation().y(), 6) + "," + fixed(uf.translation().z(), 6) + "],[" + fixed(uq.w(), 12) + "," + fixed(uq.x(), 12) +
          "," + fixed(uq.y(), 12) + "," + fixed(uq.z(), 12) + "]],[[-10,0,0],[1,0,0,0]]];" + crlf;
  text += decl + crlf + "  PROC main()" + crlf + "    ConfJ\\On;" + crlf + body + "  ENDPROC" + crlf + "ENDMODULE" + crlf;
  m.text = text;
  return m;
}

TEST_F(CompensateProgram, RoundTripThroughTheSimulatedRobotLandsNearerAndKeepsEveryOtherByte) {
  const MdhModel nom = nominal(), tru = truth();
  const Module m = make_module(nom, training_joints(), 12);
  const std::string in = write("cell.mod", m.text);
  const auto r = run("compensate-program --model " + shared("model.json") + " --program cell.mod --out out.mod --report r.csv");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(read("cell.mod"), m.text) << "the input is never modified";
  const std::string out = read("out.mod");
  // Every byte outside numbers is kept; numbers change only on lines of rewritten robtargets.
  const Numbers a = split_numbers(m.text);
  const std::vector<std::size_t> changed_at = program_test_support::changed_numbers(m.text, out);
  const std::size_t changed = changed_at.size();
  for (std::size_t i : changed_at) {
    const std::string line = program_test_support::line_text(m.text, a.lines[i]);
    EXPECT_TRUE(line.find("robtarget") != std::string::npos || line.find("MoveJ [") != std::string::npos) << line;
    EXPECT_NE(a.numbers[i], "9E+09");
  }
  EXPECT_GT(changed, 12u * 3u / 2u);

  // The report: one row per occurrence.
  const CsvTable rep = CsvTable::read(path("r.csv"));
  ASSERT_EQ(rep.header()[0], "file");
  const std::vector<std::string> head{"file", "line", "target", "status", "reason", "dx_mm", "dy_mm", "dz_mm",
                                      "q1", "q2", "q3", "q4", "q5", "q6"};
  for (std::size_t i = 0; i < head.size(); ++i) EXPECT_EQ(rep.header()[i], head[i]);
  ASSERT_EQ(rep.row_count(), 12u + 3u);
  std::map<std::string, int> status;
  for (std::size_t i = 0; i < rep.row_count(); ++i) ++status[std::string(rep.cell(i, 3))];
  EXPECT_EQ(status["ok"], 13) << read("r.csv");
  EXPECT_EQ(status["computed"], 1);
  EXPECT_EQ(status["unchanged"], 1);
  EXPECT_NE(std::string(rep.cell(12, 4)).find("p0"), std::string::npos) << "Offs names what it depends on";
  EXPECT_NE(r.out.find("13 ok, 1 computed, 1 unchanged, 0 refused"), std::string::npos) << r.out;

  // Run both programs through the controller (nominal IK, from the taught joints) and the SIMULATED
  // true robot: the compensated targets land nearer the intended ones.
  static const std::regex robtarget(
      R"(\[\[(-?[0-9.]+),(-?[0-9.]+),(-?[0-9.]+)\],\[(-?[0-9.]+),(-?[0-9.]+),(-?[0-9.]+),(-?[0-9.]+)\],\[)");
  auto targets_of = [](const std::string& text) {
    std::vector<Eigen::Isometry3d> t;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), robtarget); it != std::sregex_iterator(); ++it) {
      Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
      p.translation() << std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]);
      p.linear() = Eigen::Quaterniond(std::stod((*it)[4]), std::stod((*it)[5]), std::stod((*it)[6]), std::stod((*it)[7]))
                       .normalized()
                       .toRotationMatrix();
      t.push_back(p);
    }
    return t;
  };
  // Declared targets come first in the file, inline ones in the body: put them back in program order.
  auto in_order = [&](const std::vector<Eigen::Isometry3d>& t) {
    std::vector<Eigen::Isometry3d> o(12);
    std::size_t d = 0, l = 6;
    for (int i = 0; i < 12; ++i) o[static_cast<std::size_t>(i)] = i % 2 == 0 ? t[d++] : t[l++];
    return o;
  };
  const auto before = in_order(targets_of(m.text)), after = in_order(targets_of(out));
  ASSERT_EQ(targets_of(out).size(), 12u);  // MoveAbsJ's [[0,0,0,0,30,0],...] is no robtarget
  const MdhModel controller = nom.with_tool(m.tool), robot = tru.with_tool(tru.tool() * nom.tool().inverse() * m.tool);
  std::vector<Eigen::Isometry3d> before_base, after_base;
  for (std::size_t i = 0; i < 12; ++i) {
    before_base.push_back(m.wobj * before[i]);
    after_base.push_back(m.wobj * after[i]);
  }
  program_test_support::expect_lands_nearer(controller, robot, program_test_support::base_from_world(shared_), before_base,
                                            after_base, m.intended, m.joints);
}

}  // namespace compensate_program_test
}  // namespace errfield::programs
