// Cross-check of the URDF import against Orocos KDL's kdl_parser (Debian libkdl-parser-dev), an
// independent URDF -> kinematic chain implementation: kdl_parser builds a KDL::Tree from the same
// URDF text, KDL::Tree::getChain takes base -> tip, ChainFkSolverPos_recursive evaluates it; the
// MD-H model errfield imports (read back from its JSON) must agree to 1e-9 mm on 1,000 random joint
// vectors. Built by tests/CMakeLists.txt with kdl_parser when urdfdom, KDL and kdl_parser are found;
// otherwise compiled with ERRFIELD_NO_KDL_PARSER and skipped.

#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/urdf_import.hpp"
#include "support/urdf_writer.hpp"

#ifndef ERRFIELD_NO_KDL_PARSER
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#endif

namespace errfield::robot {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

#ifndef ERRFIELD_NO_KDL_PARSER
void expect_agrees_with_kdl(const std::string& xml, const std::string& base, const std::string& tip) {
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromString(xml, tree));
  KDL::Chain kdl_chain;
  ASSERT_TRUE(tree.getChain(base, tip, kdl_chain));
  ASSERT_EQ(kdl_chain.getNrOfJoints(), 6u);
  KDL::ChainFkSolverPos_recursive solver(kdl_chain);

  const UrdfChain chain = parse_urdf_chain(xml, base, tip, "peer.urdf");
  const MdhModel m = MdhModel::from_json(mdh_from_urdf_chain(chain).to_json());
  std::mt19937_64 rng(21);
  double dp = 0, dr = 0;
  for (int s = 0; s < 1000; ++s) {
    JointVector q;
    KDL::JntArray qk(6);
    for (int i = 0; i < kJointCount; ++i) {
      q[i] = std::uniform_real_distribution<double>(m.link(i).q_min_deg, m.link(i).q_max_deg)(rng);
      qk(static_cast<unsigned>(i)) = q[i] * kDeg;
    }
    KDL::Frame f;
    ASSERT_GE(solver.JntToCart(qk, f), 0);
    const Eigen::Isometry3d t = forward_kinematics(m, q, EndFrame::tool);
    for (int r = 0; r < 3; ++r) {
      dp = std::max(dp, std::abs(t.translation()[r] - 1000.0 * f.p(r)));
      for (int c = 0; c < 3; ++c) dr = std::max(dr, std::abs(t.linear()(r, c) - f.M(r, c)));
    }
  }
  EXPECT_LT(dp, 1e-9) << base << " -> " << tip << ": largest position difference (mm)";
  EXPECT_LT(dr, 1e-12) << base << " -> " << tip << ": largest rotation-entry difference";
}
#endif

TEST(UrdfKdlPeer, ImportedModelAgreesWithKdlParserChain) {
#ifdef ERRFIELD_NO_KDL_PARSER
  GTEST_SKIP() << "urdfdom, Orocos KDL or kdl_parser (Debian liburdfdom-dev, liborocos-kdl-dev, libkdl-parser-dev) "
                  "not found at configure time; kdl_parser cross-check skipped";
#else
  // Awkward frames, oblique axes, fixed joints inside and beyond the chain.
  expect_agrees_with_kdl(testing::urdf_xml("general", testing::general_test_arm()), "world", "tool_tip");
  // The built-in ER20-C10 with a base and a tool, written as a ROS-Industrial-style URDF.
  const MdhModel er20 = MdhModel::er20_c10()
                            .with_base(to_isometry({250, -120, 40, 2.0, -1.0, 35.0}))
                            .with_tool(to_isometry({18.231, 10.452, 132.416, 0.124, -0.085, 14.5}));
  expect_agrees_with_kdl(testing::urdf_xml("er20", testing::urdf_joints_of(er20)), "base_link", "tool0");
#endif
}

}  // namespace
}  // namespace errfield::robot
