// Cross-check of errfield's MD-H forward kinematics and geometric Jacobian against Orocos KDL, an
// independent implementation (KDL::Frame::DH_Craig1989 for the link transforms, a KDL::Chain with
// ChainFkSolverPos_recursive and ChainJntToJacSolver). Built by tests/CMakeLists.txt only when
// find_package(orocos_kdl) succeeds; otherwise compiled with ERRFIELD_NO_KDL and skipped.

#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"

#ifndef ERRFIELD_NO_KDL
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/frames.hpp>
#endif

namespace errfield::robot {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

MdhModel test_model() {
  // Perturbed ER20-C10 table with a base and a tool, so no entry is a special value.
  auto links = MdhModel::er20_c10().links();
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (auto& l : links) {
    l.alpha_deg += 0.5 * n(rng);
    l.a_mm += 3.0 * n(rng);
    l.theta0_deg += 0.5 * n(rng);
    l.d_mm += 3.0 * n(rng);
  }
  return MdhModel("kdl-check", links, to_isometry({250, -120, 40, 2.0, -1.0, 35.0}),
                  to_isometry({18.231, 10.452, 32.416, 0.124, -0.085, 14.5}));
}

#ifndef ERRFIELD_NO_KDL
KDL::Frame to_kdl(const Eigen::Isometry3d& t) {
  const auto& r = t.linear();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    KDL::Vector(t.translation().x(), t.translation().y(), t.translation().z()));
}

Eigen::Matrix4d to_eigen(const KDL::Frame& f) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = f.M(i, j);
    m(i, 3) = f.p(i);
  }
  return m;
}

// The MD-H product base · Π Rx Dx Rz Dz · tool regrouped into KDL segments (a joint turns about z
// at the segment's start): [base · Rx(a0) Dx(a0) Rz(th0_1)] · Rz(q1) · [Dz(d1) Rx(a1) Dx(a1) Rz(th0_2)]
// · Rz(q2) ··· Rz(q6) · [Dz(d6) · tool].
KDL::Chain to_chain(const MdhModel& m) {
  KDL::Chain chain;
  auto dh = [&](int i) {  // Rx(alpha_{i}) Dx(a_{i}) Rz(theta0_{i+1}) with d = 0
    const MdhLink& l = m.link(i);
    return KDL::Frame::DH_Craig1989(l.a_mm, l.alpha_deg * kDeg, 0.0, l.theta0_deg * kDeg);
  };
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), to_kdl(m.base()) * dh(0)));
  for (int i = 0; i < kJointCount; ++i) {
    const KDL::Frame dz(KDL::Vector(0, 0, m.link(i).d_mm));
    const KDL::Frame tip = i + 1 < kJointCount ? dz * dh(i + 1) : dz * to_kdl(m.tool());
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), tip));
  }
  return chain;
}
#endif

TEST(KdlPeer, ForwardKinematicsAndJacobianAgreeWithOrocosKdl) {
#ifdef ERRFIELD_NO_KDL
  GTEST_SKIP() << "Orocos KDL (Debian liborocos-kdl-dev) not found at configure time; KDL cross-check skipped";
#else
  const MdhModel m = test_model();
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-170.0, 170.0);
  // 1) Link transforms straight from KDL::Frame::DH_Craig1989, multiplied out.
  // 2) The same chain through KDL's recursive FK and Jacobian solvers.
  const KDL::Chain chain = to_chain(m);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac_solver(chain);
  for (int k = 0; k < 200; ++k) {
    JointVector q;
    for (int i = 0; i < kJointCount; ++i) q[i] = u(rng);
    KDL::Frame direct = to_kdl(m.base());
    for (int i = 0; i < kJointCount; ++i) {
      const MdhLink& l = m.link(i);
      direct = direct * KDL::Frame::DH_Craig1989(l.a_mm, l.alpha_deg * kDeg, l.d_mm, (l.theta0_deg + q[i]) * kDeg);
    }
    direct = direct * to_kdl(m.tool());
    const Eigen::Matrix4d ours = forward_kinematics(m, q, EndFrame::tool).matrix();
    // Tolerance 1e-9 mm on positions (and 1e-12 on rotation entries): both compute the same
    // product in double precision; at ~2 m the rounding is ~1e-12 mm.
    EXPECT_LT((ours.block<3, 1>(0, 3) - to_eigen(direct).block<3, 1>(0, 3)).norm(), 1e-9) << "sample " << k;
    EXPECT_LT((ours.block<3, 3>(0, 0) - to_eigen(direct).block<3, 3>(0, 0)).cwiseAbs().maxCoeff(), 1e-12);

    KDL::JntArray jq(kJointCount);
    for (int i = 0; i < kJointCount; ++i) jq(i) = q[i] * kDeg;
    KDL::Frame solved;
    ASSERT_GE(fk.JntToCart(jq, solved), 0);
    EXPECT_LT((ours.block<3, 1>(0, 3) - to_eigen(solved).block<3, 1>(0, 3)).norm(), 1e-9) << "sample " << k;

    KDL::Jacobian kj(kJointCount);
    ASSERT_GE(jac_solver.JntToJac(jq, kj), 0);
    const auto j = geometric_jacobian(m, q, EndFrame::tool);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < kJointCount; ++c) EXPECT_NEAR(j(r, c), kj(r, c), 1e-9) << "J(" << r << "," << c << ")";
  }
#endif
}

TEST(KdlPeer, BuiltinUr5eAgreesWithKdlStandardDhChain) {
#ifdef ERRFIELD_NO_KDL
  GTEST_SKIP() << "Orocos KDL (Debian liborocos-kdl-dev) not found at configure time; KDL cross-check skipped";
#else
  // UR's published standard D-H table (support FAQ 45257, mm and rad) as a KDL chain of
  // KDL::Frame::DH segments (standard convention), against errfield's modified D-H conversion.
  const double a[6] = {0, -425, -392.2, 0, 0, 0}, d[6] = {162.5, 0, 0, 133.3, 99.7, 99.6};
  const double alpha[6] = {std::numbers::pi / 2, 0, 0, std::numbers::pi / 2, -std::numbers::pi / 2, 0};
  KDL::Chain chain;
  for (int i = 0; i < kJointCount; ++i)
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::DH(a[i], alpha[i], d[i], 0.0)));
  KDL::ChainFkSolverPos_recursive fk(chain);
  const MdhModel m = ur5e();
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-360.0, 360.0);
  for (int k = 0; k < 200; ++k) {
    JointVector q;
    KDL::JntArray jq(kJointCount);
    for (int i = 0; i < kJointCount; ++i) {
      q[i] = u(rng);
      jq(i) = q[i] * kDeg;
    }
    KDL::Frame solved;
    ASSERT_GE(fk.JntToCart(jq, solved), 0);
    const Eigen::Matrix4d ours = forward_kinematics(m, q, EndFrame::flange).matrix();
    EXPECT_LT((ours.block<3, 1>(0, 3) - to_eigen(solved).block<3, 1>(0, 3)).norm(), 1e-9) << "sample " << k;
    EXPECT_LT((ours.block<3, 3>(0, 0) - to_eigen(solved).block<3, 3>(0, 0)).cwiseAbs().maxCoeff(), 1e-12);
  }
#endif
}

}  // namespace
}  // namespace errfield::robot
