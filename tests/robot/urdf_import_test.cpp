// URDF import: conversion to MD-H checked against the test's own FK of the URDFs it writes
// (support/urdf_writer: 4x4 products from the URDF definitions), the ER20-C10 round trip, the
// conventions the docs promise, and the refusals through the CLI (exit 2, message names the joint).

#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/urdf_import.hpp"
#include "support/cli_harness.hpp"
#include "support/urdf_writer.hpp"

namespace errfield::robot {
namespace urdf_import_test {

using ::testing::HasSubstr;
using testing::TestUrdfJoint;
using testing::urdf_xml;

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<JointVector> random_joints(const MdhModel& m, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<JointVector> qs;
  for (int s = 0; s < n; ++s) {
    JointVector q;
    for (int i = 0; i < kJointCount; ++i)
      q[i] = std::uniform_real_distribution<double>(m.link(i).q_min_deg, m.link(i).q_max_deg)(rng);
    qs.push_back(q);
  }
  return qs;
}

// Largest |p| and rotation-entry difference between the model's tool FK and the test's URDF FK.
std::pair<double, double> max_fk_difference(const MdhModel& m, const std::vector<TestUrdfJoint>& js,
                                            const std::string& base, const std::string& tip,
                                            const Eigen::Matrix4d& tool = Eigen::Matrix4d::Identity()) {
  double dp = 0, dr = 0;
  for (const JointVector& q : random_joints(m, 300, 3)) {
    const Eigen::Matrix4d a = forward_kinematics(m, q, EndFrame::tool).matrix();
    const Eigen::Matrix4d b = testing::test_urdf_fk(js, base, tip, q) * tool;
    dp = std::max(dp, (a.block<3, 1>(0, 3) - b.block<3, 1>(0, 3)).norm());
    dr = std::max(dr, (a.block<3, 3>(0, 0) - b.block<3, 3>(0, 0)).cwiseAbs().maxCoeff());
  }
  return {dp, dr};
}

MdhModel import_arm(const std::vector<TestUrdfJoint>& js, const std::string& base, const std::string& tip,
                const Eigen::Isometry3d& tool = Eigen::Isometry3d::Identity()) {
  const UrdfChain chain = parse_urdf_chain(urdf_xml("test_arm", js), base, tip, "test.urdf");
  const MdhModel m = MdhModel::from_json(mdh_from_urdf_chain(chain, tool).to_json());
  const UrdfVerification v = verify_urdf_import(m, chain, tool, 500, 2);
  EXPECT_TRUE(v.passed) << v.max_position_mm << " mm, " << v.max_rotation_rad << " rad";
  return m;
}

class UrdfImport : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!urdf_support_available()) GTEST_SKIP() << "built without urdfdom (liburdfdom-dev)";
  }
};

TEST_F(UrdfImport, Er20RoundTripReproducesTableAndFk) {
  const MdhModel er20 = MdhModel::er20_c10().with_tool(to_isometry({18.2, 10.4, 132.4, 0.124, -0.085, 14.5}));
  const auto js = testing::urdf_joints_of(er20);
  // Tip at the flange: the table comes back as SPEC Table 1 with identity base and tool.
  const MdhModel flange = import_arm(js, "base_link", "flange");
  for (int i = 0; i < kJointCount; ++i) {
    const MdhLink &a = flange.link(i), &b = er20.link(i);
    EXPECT_NEAR(a.alpha_deg, b.alpha_deg, 1e-12) << "link " << i + 1;
    EXPECT_NEAR(a.a_mm, b.a_mm, 1e-10) << "link " << i + 1;
    EXPECT_NEAR(a.theta0_deg, b.theta0_deg, 1e-12) << "link " << i + 1;
    EXPECT_NEAR(a.d_mm, b.d_mm, 1e-10) << "link " << i + 1;
    EXPECT_EQ(a.beta_deg, 0.0);
    EXPECT_NEAR(a.q_min_deg, b.q_min_deg, 1e-12);
    EXPECT_NEAR(a.q_max_deg, b.q_max_deg, 1e-12);
  }
  EXPECT_LT((flange.base().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((flange.tool().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  // Tip at tool0 (flange · tool): same FK as the original JSON model, tool included.
  const MdhModel tool0 = import_arm(js, "base_link", "tool0");
  double dp = 0;
  for (const JointVector& q : random_joints(er20, 1000, 7))
    dp = std::max(dp, (forward_kinematics(tool0, q).translation() - forward_kinematics(er20, q).translation()).norm());
  EXPECT_LT(dp, 1e-9);
  // And a base: the model's world frame is the URDF's base_link.
  const MdhModel based = er20.with_base(to_isometry({250, -120, 40, 2.0, -1.0, 35.0}));
  const auto [p, r] = max_fk_difference(import_arm(testing::urdf_joints_of(based), "base_link", "tool0"),
                                        testing::urdf_joints_of(based), "base_link", "tool0");
  EXPECT_LT(p, 1e-9);
  EXPECT_LT(r, 1e-12);
}

std::vector<TestUrdfJoint> messy_arm() { return testing::general_test_arm(); }

TestUrdfJoint& joint(std::vector<TestUrdfJoint>& js, const std::string& name) {
  for (auto& j : js)
    if (j.name == name) return j;
  throw std::runtime_error("no joint " + name);
}

TEST_F(UrdfImport, ArbitraryFramesAndAxesGiveTheUrdfFk) {
  const auto js = messy_arm();
  const Eigen::Isometry3d tool = to_isometry({5, -3, 40, 10, 0, 30});
  for (const std::string base : {"world", "base_link"}) {
    const MdhModel m = import_arm(js, base, "tool_tip", tool);
    const auto [p, r] = max_fk_difference(m, js, base, "tool_tip", tool.matrix());
    EXPECT_LT(p, 1e-9) << base;
    EXPECT_LT(r, 1e-12) << base;
    // Joint angles map 1:1, limits included (j1 turns about -z: no sign flip in the JSON).
    EXPECT_NEAR(m.link(0).q_min_deg, -2.9 / kDeg, 1e-9);
    EXPECT_NEAR(m.link(5).q_max_deg, 6.0 / kDeg, 1e-9);
  }
}

TEST_F(UrdfImport, WristOffsetArm) {
  // UR-like: shoulder offset, parallel 2-3-4, wrist axes offset (no spherical wrist).
  std::vector<TestUrdfJoint> js = {
      {"shoulder_pan", "base_link", "shoulder"}, {"shoulder_lift", "shoulder", "upper_arm"},
      {"elbow", "upper_arm", "forearm"},         {"wrist_1", "forearm", "wrist_1_link"},
      {"wrist_2", "wrist_1_link", "wrist_2_link"}, {"wrist_3", "wrist_2_link", "wrist_3_link"}};
  const double h = std::numbers::pi / 2;
  js[0].xyz_m = {0, 0, 0.1625};
  js[1].rpy_rad = {h, 0, 0};
  js[2].xyz_m = {-0.425, 0, 0};
  js[3].xyz_m = {-0.3922, 0, 0.1333};
  js[4].xyz_m = {0, -0.0997, 0}, js[4].rpy_rad = {h, 0, 0};
  js[5].xyz_m = {0, 0.0996, 0}, js[5].rpy_rad = {h, std::numbers::pi, std::numbers::pi};
  const MdhModel m = import_arm(js, "base_link", "wrist_3_link");
  const auto [p, r] = max_fk_difference(m, js, "base_link", "wrist_3_link");
  EXPECT_LT(p, 1e-9);
  EXPECT_LT(r, 1e-12);
  // The wrist offsets survive as lengths: d5 (along axis 5) and d6 (flange on axis 6).
  EXPECT_NEAR(std::abs(m.link(4).d_mm), 99.7, 1e-9);
  EXPECT_NEAR(std::abs(m.link(5).d_mm), 99.6, 1e-9);
  // Parallel axes 2-3 and 3-4: alpha 0 or 180, no beta, and the link lengths.
  for (int i : {2, 3}) {
    EXPECT_NEAR(std::abs(std::remainder(m.link(i).alpha_deg, 180.0)), 0.0, 1e-12) << i;
    EXPECT_EQ(m.link(i).beta_deg, 0.0);
  }
  EXPECT_NEAR(std::abs(m.link(2).a_mm), 425.0, 1e-9);
  EXPECT_NEAR(std::abs(m.link(3).a_mm), 392.2, 1e-9);
}

TEST_F(UrdfImport, ParallelAxesIncludingRoundedAngles) {
  // Axes 2, 3 and 4 parallel; axis 3 anti-parallel to 2 (alpha 180); the origin of joint 4 is
  // written with a rounded pi/2 (rpy 1.5708), which tilts axis 4 by 3.7e-6 rad off axis 3 towards
  // the normal between them (along y of joint 3's frame): that tilt is Hayati's beta.
  std::vector<TestUrdfJoint> js = {{"a", "base_link", "l1"}, {"b", "l1", "l2"}, {"c", "l2", "l3"},
                                   {"d", "l3", "l4"},        {"e", "l4", "l5"}, {"f", "l5", "l6"}};
  js[0].xyz_m = {0, 0, 0.5};
  js[1].xyz_m = {0.2, 0, 0}, js[1].rpy_rad = {std::numbers::pi / 2, 0, 0};
  js[2].xyz_m = {0.7, 0.1, 0.05}, js[2].axis = {0, 0, -1};
  js[3].xyz_m = {0, 0.6, -0.1}, js[3].rpy_rad = {1.5708, 0, 0}, js[3].axis = {0, -1, 0};
  js[4].xyz_m = {0.1, 0, 0.2}, js[4].rpy_rad = {0, 1.5707963267948966, 0};
  js[5].xyz_m = {0, 0, 0.1}, js[5].rpy_rad = {0, -1.5707963267948966, 0};
  const MdhModel m = import_arm(js, "base_link", "l6");
  const auto [p, r] = max_fk_difference(m, js, "base_link", "l6");
  EXPECT_LT(p, 1e-9);
  EXPECT_LT(r, 1e-12);
  EXPECT_NEAR(std::abs(m.link(2).alpha_deg), 180.0, 1e-12);  // axis 3 = -axis 2
  EXPECT_EQ(m.link(2).beta_deg, 0.0);
  EXPECT_NEAR(std::abs(m.link(2).a_mm), std::hypot(700.0, 100.0), 1e-9);  // distance of the parallel axes
  EXPECT_GT(std::abs(m.link(3).beta_deg), 1e-4);  // the rounded pi/2: 3.7e-6 rad = 2.1e-4 deg
  EXPECT_LT(std::abs(m.link(3).beta_deg), 1e-3);
  EXPECT_NEAR(std::abs(m.link(3).a_mm), 600.0, 1e-3);
}

TEST_F(UrdfImport, IntersectingAxes) {
  // Axes 1-2 intersect (no shoulder offset) and 4-5-6 form a spherical wrist.
  std::vector<TestUrdfJoint> js = {{"j1", "base", "l1"}, {"j2", "l1", "l2"}, {"j3", "l2", "l3"},
                                   {"j4", "l3", "l4"},   {"j5", "l4", "l5"}, {"j6", "l5", "l6"}};
  const double h = std::numbers::pi / 2;
  js[0].xyz_m = {0, 0, 0.45};
  js[1].rpy_rad = {-h, 0, 0};
  js[2].xyz_m = {0.7, 0, 0}, js[2].rpy_rad = {0, 0, 0.3};
  js[3].xyz_m = {0.1, 0.5, 0}, js[3].rpy_rad = {h, 0, 0};
  js[4].rpy_rad = {-h, 0, 0}, js[4].axis = {0, 0, -1};
  js[5].rpy_rad = {h, 0, 0};
  TestUrdfJoint flange{"j_flange", "l6", "flange", "fixed"};
  flange.xyz_m = {0, 0, 0.08};
  js.push_back(flange);
  const MdhModel m = import_arm(js, "base", "flange");
  const auto [p, r] = max_fk_difference(m, js, "base", "flange");
  EXPECT_LT(p, 1e-9);
  EXPECT_LT(r, 1e-12);
  EXPECT_NEAR(m.link(1).a_mm, 0.0, 1e-12);  // a_1: axes 1 and 2 intersect
  EXPECT_NEAR(m.link(4).a_mm, 0.0, 1e-12);  // a_4, a_5: spherical wrist
  EXPECT_NEAR(m.link(5).a_mm, 0.0, 1e-12);
  EXPECT_NEAR(m.link(4).d_mm, 0.0, 1e-12);  // d_5: axis 5 meets axis 4 where axis 6 does
  EXPECT_NEAR(m.link(5).d_mm, 80.0, 1e-9);  // the flange on axis 6
  EXPECT_NEAR(m.link(0).d_mm, 450.0, 1e-9);
  EXPECT_LT((m.tool().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(UrdfImport, VerificationCatchesAWrongModel) {
  const auto js = messy_arm();
  const UrdfChain chain = parse_urdf_chain(urdf_xml("a", js), "base_link", "tool_tip");
  auto links = mdh_from_urdf_chain(chain).links();
  links[3].d_mm += 1e-8;  // 10 pm: still above the 1e-9 mm tolerance
  const UrdfVerification v = verify_urdf_import(mdh_from_urdf_chain(chain).with_links(links), chain);
  EXPECT_FALSE(v.passed);
  EXPECT_GT(v.max_position_mm, 5e-9);
}

// ---- refusals, through the CLI ----------------------------------------------------------------

class UrdfImportCli : public errfield::testing::CliTest {
 protected:
  void SetUp() override {
    if (!urdf_support_available()) GTEST_SKIP() << "built without urdfdom (liburdfdom-dev)";
  }
  errfield::testing::CliResult import_text(const std::string& xml, const std::string& base = "base_link",
                                           const std::string& tip = "tool_tip") {
    write("arm.urdf", xml);
    return run("import-urdf --urdf " + path("arm.urdf") + " --base " + base + " --tip " + tip + " --out " +
               path("robot.json"));
  }
  void expect_refused(const errfield::testing::CliResult& r, const std::vector<std::string>& words) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    for (const auto& w : words) EXPECT_THAT(r.err, HasSubstr(w));
    EXPECT_FALSE(std::filesystem::exists(path("robot.json")));
  }
};

TEST_F(UrdfImportCli, WritesJsonThatFkAcceptsAndPrintsTheCheck) {
  const auto js = messy_arm();
  write("arm.urdf", urdf_xml("messy", js));
  const auto r = run("import-urdf --urdf " + path("arm.urdf") + " --base base_link --tip tool_tip --tool 1,2,3,4,5,6 --out " +
                     path("robot.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("largest difference"));
  EXPECT_THAT(r.out, HasSubstr(": ok"));
  const MdhModel m = MdhModel::load(path("robot.json"));
  EXPECT_EQ(m.name(), "messy");
  const auto [p, rr] = max_fk_difference(m, js, "base_link", "tool_tip", to_isometry({1, 2, 3, 4, 5, 6}).matrix());
  EXPECT_LT(p, 1e-9);
  write("q.csv", "q1,q2,q3,q4,q5,q6\n10,20,30,40,50,60\n");
  const auto fk = run("fk --input " + path("q.csv") + " --robot " + path("robot.json") + " --out " + path("p.csv"));
  EXPECT_EQ(fk.exit_code, 0) << fk.err;
}

TEST_F(UrdfImportCli, RefusesPrismaticJoint) {
  auto js = messy_arm();
  joint(js, "j3").type = "prismatic";
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j3'", "prismatic"});
}

TEST_F(UrdfImportCli, RefusesContinuousJoint) {
  auto js = messy_arm();
  joint(js, "j6").type = "continuous";
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j6'", "continuous", "revolute"});
}

TEST_F(UrdfImportCli, RefusesNonUnitAxis) {
  auto js = messy_arm();
  joint(js, "j2").axis = {0, 2, 0};
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j2'", "unit vector", "length 2"});
}

TEST_F(UrdfImportCli, RefusesWrongJointCount) {
  auto js = messy_arm();
  expect_refused(import_text(urdf_xml("a", js), "base_link", "l5"), {"5 revolute joints", "j1, j2, j3, j4, j5",
                                                                     "exactly 6"});
  TestUrdfJoint j7{"j7", "tool_tip", "extra"};
  js.push_back(j7);
  expect_refused(import_text(urdf_xml("a", js), "base_link", "extra"), {"7 revolute joints", "j7"});
}

TEST_F(UrdfImportCli, RefusesMovingBranchButIgnoresFixedOnes) {
  auto js = messy_arm();
  TestUrdfJoint cam{"camera_pan", "l3", "camera"};
  js.push_back(cam);
  expect_refused(import_text(urdf_xml("a", js)), {"link 'l3'", "branches", "camera_pan"});
  js.back().type = "fixed";  // a sensor frame on the chain is fine
  EXPECT_EQ(import_text(urdf_xml("a", js)).exit_code, 0);
}

TEST_F(UrdfImportCli, RefusesMissingLinksAndReversedChain) {
  const std::string xml = urdf_xml("a", messy_arm());
  expect_refused(import_text(xml, "base_lnk"), {"--base", "no link named 'base_lnk'", "base_link"});
  expect_refused(import_text(xml, "base_link", "tool"), {"--tip", "no link named 'tool'"});
  expect_refused(import_text(xml, "tool_tip", "base_link"), {"'base_link' is not below base link 'tool_tip'"});
}

TEST_F(UrdfImportCli, RefusesMalformedFiles) {
  auto js = messy_arm();
  expect_refused(import_text("<robot name=\"x\"><link name=\"a\"></robot>"), {"not a valid URDF"});
  joint(js, "j4").write_limit = false;
  expect_refused(import_text(urdf_xml("a", js)), {"not a valid URDF", "j4"});
  js = messy_arm();
  joint(js, "j5").extra = "    <mimic joint=\"j4\" multiplier=\"1\"/>\n";
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j5'", "mimics joint 'j4'"});
  js = messy_arm();
  joint(js, "j5").lower_rad = 1.0, joint(js, "j5").upper_rad = -1.0;
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j5'", "lower < upper"});
  const auto r = run("import-urdf --urdf " + path("missing.urdf") + " --base a --tip b --out " + path("robot.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("missing.urdf"));
  write("arm.urdf", urdf_xml("a", messy_arm()));
  const auto t = run("import-urdf --urdf " + path("arm.urdf") + " --base base_link --tip tool_tip --tool 1,2,3 --out " +
                     path("robot.json"));
  EXPECT_EQ(t.exit_code, 2);
  EXPECT_THAT(t.err, HasSubstr("--tool"));
}

// ---- issue 20: adversarial inputs ---------------------------------------------------------------

// 100,000 nested elements (700 kB) segfaulted urdfdom's recursive parser after 5.8 s; parse time grew
// quadratically with depth. Refused before parsing, naming the limit.
TEST_F(UrdfImportCli, RefusesDeepNestingBeforeParsing) {
  std::string deep = "<robot name=\"deep\">";
  for (int i = 0; i < 100000; ++i) deep += "<a>";
  for (int i = 0; i < 100000; ++i) deep += "</a>";
  deep += "</robot>\n";
  const auto start = std::chrono::steady_clock::now();
  const auto r = import_text(deep);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  expect_refused(r, {"arm.urdf", "nested more than " + std::to_string(kMaxUrdfDepth), "Input limits"});
  EXPECT_LT(seconds, 2.0);  // a linear scan; the parser took 5.8 s here before crashing
  // The limit counts elements, not comments, CDATA or self-closing tags.
  std::string xml = urdf_xml("a", messy_arm());
  std::string flat = "<!-- <a><a><a> -->";
  for (int i = 0; i < kMaxUrdfDepth + 10; ++i) flat += "<x/>";
  xml.insert(xml.find("</robot>"), flat);
  EXPECT_EQ(import_text(xml).exit_code, 0);
}

// A 100 MB URDF took 11 s and 2.2 GB before it was rejected; now its size is refused as it is read.
TEST_F(UrdfImportCli, RefusesAFileBeyondTheByteLimit) {
  std::string xml = urdf_xml("a", messy_arm());
  xml.insert(xml.find("</robot>"), "<!--" + std::string(kMaxUrdfBytes, ' ') + "-->");
  const auto r = import_text(xml);
  expect_refused(r, {"arm.urdf", std::to_string(kMaxUrdfBytes >> 20) + " MiB"});
}

// A <!DOCTYPE> gave "Could not find the 'robot' element".
TEST_F(UrdfImportCli, RefusesDoctypeSayingSo) {
  std::string xml = urdf_xml("a", messy_arm());
  xml.insert(xml.find("<robot"), "<!DOCTYPE robot [ <!ENTITY len \"0.5\"> ]>\n");
  expect_refused(import_text(xml), {"arm.urdf:2", "<!DOCTYPE>", "not supported"});
}

// A link that is the child of two joints was accepted (urdfdom kept one parent silently).
TEST_F(UrdfImportCli, RefusesALinkWithTwoParentJoints) {
  auto js = messy_arm();
  TestUrdfJoint twin{"j3_twin", "base_link", "l3", "fixed"};
  js.push_back(twin);
  expect_refused(import_text(urdf_xml("a", js)), {"link 'l3'", "two joints", "'j3'", "'j3_twin'", "tree"});
}

// Joint limits of +-1e300 rad were accepted (and became +-5.7e301 deg in the robot JSON).
TEST_F(UrdfImportCli, RefusesAbsurdJointLimits) {
  auto js = messy_arm();
  joint(js, "j2").lower_rad = -1e300, joint(js, "j2").upper_rad = 1e300;
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j2'", "beyond +-100 rad"});
  js = messy_arm();
  joint(js, "j2").lower_rad = -kMaxUrdfJointLimit_rad, joint(js, "j2").upper_rad = kMaxUrdfJointLimit_rad;
  EXPECT_EQ(import_text(urdf_xml("a", js)).exit_code, 0);  // at the bound: accepted
}

// An offset of 1e-300 m (neither 0 nor physical) was accepted; 0 (coincident axes) must stay legal,
// and so must the rounding residue of a printed angle (6e-17).
TEST_F(UrdfImportCli, RefusesDenormalOffsetsButAcceptsZeroAndRoundingResidue) {
  auto js = messy_arm();
  joint(js, "j4").xyz_m = {1e-300, 0.0, 0.0};
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j4'", "xyz component 1", "neither 0 nor a physical size"});
  js = messy_arm();
  joint(js, "j4").rpy_rad.x() = 1e-300;
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j4'", "rpy component 1"});
  js = messy_arm();
  joint(js, "j4").xyz_m = {2e3, 0.0, 0.0};
  expect_refused(import_text(urdf_xml("a", js)), {"joint 'j4'", "beyond 1000 m"});
  js = messy_arm();
  joint(js, "j4").xyz_m = {0.0, 0.0, 0.0};
  joint(js, "j5").xyz_m = {6.123233995736766e-17, 0.0, 0.1};
  const auto ok = import_text(urdf_xml("a", js));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST_F(UrdfImportCli, DocsExample) {
  // The URDF shown in docs/robot.md, imported as the docs show; the table derived there by hand.
  const std::string doc = read_text(ERRFIELD_SOURCE_DIR "/docs/robot.md");
  const auto section = doc.find("### `errfield import-urdf`");
  ASSERT_NE(section, std::string::npos);
  // The fence is "```xml file=demo.urdf" (tests/docs/run_doc_commands.py writes the block to that file).
  const auto fence = doc.find("```xml", section);
  ASSERT_NE(fence, std::string::npos);
  const auto begin = doc.find('\n', fence) + 1;
  const auto end = doc.find("```", begin);
  write("demo.urdf", doc.substr(begin, end - begin));
  // README.md's --help examples read data/demo_6r.urdf: the same text, so the two cannot drift.
  EXPECT_EQ(read_text(ERRFIELD_SOURCE_DIR "/data/demo_6r.urdf"), doc.substr(begin, end - begin))
      << "data/demo_6r.urdf differs from the URDF block in docs/robot.md";
  const auto r = run("import-urdf --urdf " + path("demo.urdf") + " --base base_link --tip tool0 --out " + path("demo.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MdhModel m = MdhModel::load(path("demo.json"));
  const double expected[6][4] = {{0, 0, 0, 450},     {-90, 150, 90, 0}, {0, -600, 0, 0},
                                 {-90, -120, 0, -620}, {90, 0, 0, 0},     {90, 0, 0, 80}};
  for (int i = 0; i < kJointCount; ++i) {
    EXPECT_NEAR(m.link(i).alpha_deg, expected[i][0], 1e-12) << "row " << i + 1;
    EXPECT_NEAR(m.link(i).a_mm, expected[i][1], 1e-12) << "row " << i + 1;
    EXPECT_NEAR(m.link(i).theta0_deg, expected[i][2], 1e-12) << "row " << i + 1;
    EXPECT_NEAR(m.link(i).d_mm, expected[i][3], 1e-12) << "row " << i + 1;
  }
  EXPECT_NEAR(m.link(3).q_min_deg, -3.316 / kDeg, 1e-9);
  EXPECT_LT((m.base().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((m.tool().matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
}

// Issue 35: an <origin rpy> of 1e20 rad was accepted (urdfdom turns it into some quaternion at
// once, where the value no longer shows); angles beyond kMaxUrdfOriginAngle_rad or not finite are
// refused from the text, naming the line, the element and the value.
TEST_F(UrdfImportCli, RefusesAbsurdOriginAngles) {
  for (const char* angle : {"1e20", "-250", "nan", "inf"}) {
    auto js = messy_arm();
    joint(js, "j3").rpy_rad = Eigen::Vector3d(0.25, 0.5, 0.75);
    std::string xml = urdf_xml("a", js);
    const std::string written = "rpy=\"0.25 0.5 0.75\"";
    const auto at = xml.find(written);
    ASSERT_NE(at, std::string::npos) << xml;
    xml.replace(at, written.size(), std::string("rpy=\"0.25 ") + angle + " 0.75\"");
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    expect_refused(import_text(xml), {"arm.urdf:" + std::to_string(line) + ": <origin rpy=", "component 2 = " + std::string(angle)});
  }
  // Within one turn, or a few (xacro writes ${2*pi}), is accepted.
  auto js = messy_arm();
  joint(js, "j3").rpy_rad = Eigen::Vector3d(0.25, 6.5, 0.75);
  EXPECT_EQ(import_text(urdf_xml("a", js)).exit_code, 0);
}

}  // namespace
}  // namespace errfield::robot
