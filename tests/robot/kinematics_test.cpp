#include "errfield/robot/kinematics.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/robot/inverse_kinematics.hpp"

namespace errfield::robot {
namespace kinematics_test {

constexpr double kDeg = std::numbers::pi / 180.0;

// Naive reference: the 4x4 matrix of SPEC eq. 1 (with Hayati beta inserted after Dx(a)) multiplied
// out link by link, written independently of the library's incremental form.
Eigen::Matrix4d naive_link(const MdhLink& l, double q_deg) {
  auto rx = [](double a) { Eigen::Matrix4d m = Eigen::Matrix4d::Identity(); m(1,1)=std::cos(a); m(1,2)=-std::sin(a); m(2,1)=std::sin(a); m(2,2)=std::cos(a); return m; };
  auto ry = [](double a) { Eigen::Matrix4d m = Eigen::Matrix4d::Identity(); m(0,0)=std::cos(a); m(0,2)=std::sin(a); m(2,0)=-std::sin(a); m(2,2)=std::cos(a); return m; };
  auto rz = [](double a) { Eigen::Matrix4d m = Eigen::Matrix4d::Identity(); m(0,0)=std::cos(a); m(0,1)=-std::sin(a); m(1,0)=std::sin(a); m(1,1)=std::cos(a); return m; };
  auto dx = [](double v) { Eigen::Matrix4d m = Eigen::Matrix4d::Identity(); m(0,3)=v; return m; };
  auto dz = [](double v) { Eigen::Matrix4d m = Eigen::Matrix4d::Identity(); m(2,3)=v; return m; };
  return rx(l.alpha_deg * kDeg) * dx(l.a_mm) * ry(l.beta_deg * kDeg) * rz((q_deg + l.theta0_deg) * kDeg) * dz(l.d_mm);
}

Eigen::Matrix4d naive_fk(const MdhModel& m, const JointVector& q) {
  Eigen::Matrix4d t = m.base().matrix();
  for (int i = 0; i < kJointCount; ++i) t = t * naive_link(m.link(i), q[i]);
  return t * m.tool().matrix();
}

JointVector random_joints(const MdhModel& m, std::mt19937_64& rng) {
  JointVector q;
  for (int i = 0; i < kJointCount; ++i) {
    std::uniform_real_distribution<double> u(std::max(m.link(i).q_min_deg, -170.0), std::min(m.link(i).q_max_deg, 170.0));
    q[i] = u(rng);
  }
  return q;
}

// A model with every kind of parameter non-trivial: perturbed table, non-zero betas, base and tool.
MdhModel perturbed_model() {
  auto links = MdhModel::er20_c10().links();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (auto& l : links) {
    l.alpha_deg += 0.3 * n(rng);
    l.a_mm += 2.0 * n(rng);
    l.theta0_deg += 0.3 * n(rng);
    l.d_mm += 2.0 * n(rng);
    l.beta_deg += 0.2 * n(rng);
  }
  return MdhModel("perturbed", links, to_isometry({100, -50, 20, 1.5, -2.0, 30.0}),
                  to_isometry({0.018, -0.012, 77.025, 0.011, -0.015, 0.008}));
}

TEST(Pose, RpyMatchesExplicitProductAndRoundTrips) {
  const Eigen::Matrix3d r = rotation_from_rpy_deg(10, -20, 30);
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                                   Eigen::AngleAxisd(-20 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                                   Eigen::AngleAxisd(10 * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_LT((r - expected).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::Vector3d e = rpy_deg_from_rotation(r);
  EXPECT_NEAR(e.x(), 10, 1e-12);
  EXPECT_NEAR(e.y(), -20, 1e-12);
  EXPECT_NEAR(e.z(), 30, 1e-12);
  // Tool pointing down: z axis of the tool is -z of the world.
  EXPECT_LT((rotation_from_rpy_deg(180, 0, 0).col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-15);
}

TEST(Pose, LogExpInverseIncludingNearPi) {
  for (double angle : {0.0, 1e-9, 0.3, 2.0, std::numbers::pi - 1e-8, std::numbers::pi}) {
    const Eigen::Vector3d w = angle * Eigen::Vector3d(1, -2, 0.5).normalized();
    const Eigen::Matrix3d r = rotation_exp(w);
    const Eigen::Matrix3d back = rotation_exp(rotation_log(r));
    EXPECT_LT((back - r).cwiseAbs().maxCoeff(), 1e-9) << "angle " << angle;
  }
}

TEST(Kinematics, ForwardMatchesNaiveMatrixProduct) {
  const MdhModel m = perturbed_model();
  std::mt19937_64 rng(1);
  for (int k = 0; k < 50; ++k) {
    const JointVector q = random_joints(m, rng);
    const Eigen::Matrix4d ref = naive_fk(m, q);
    const Eigen::Isometry3d t = forward_kinematics(m, q, EndFrame::tool);
    EXPECT_LT((t.matrix() - ref).cwiseAbs().maxCoeff(), 1e-9);  // mm; ~1e-13 relative at 2 m
    EXPECT_LT((forward_position(m, q) - ref.block<3, 1>(0, 3)).norm(), 1e-9);
    const Eigen::Isometry3d flange = forward_kinematics(m, q, EndFrame::flange);
    EXPECT_LT(((flange * m.tool()).matrix() - ref).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(Kinematics, Er20NominalZeroPoseIsTheTableSum) {
  // At q = 0 every alpha is +-90 or 0, so the flange position is a sum of table entries:
  // x = a1 + a2 + a3, z = d1 + d4 + d6 (SPEC Table 1).
  const auto p = forward_position(MdhModel::er20_c10(), JointVector::Zero(), EndFrame::flange);
  EXPECT_NEAR(p.x(), 166.605 - 782.27 - 138.826, 1e-9);
  EXPECT_NEAR(p.y(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), 504 + 761.35 + 125, 1e-9);
}

TEST(Kinematics, GeometricJacobianMatchesFiniteDifferences) {
  const MdhModel m = perturbed_model();
  std::mt19937_64 rng(2);
  const double h = 1e-6;  // rad; central differences: error ~h^2 * |P| ~ 1e-9 mm
  for (int k = 0; k < 20; ++k) {
    const JointVector q = random_joints(m, rng);
    for (EndFrame frame : {EndFrame::flange, EndFrame::tool}) {
      const auto j = geometric_jacobian(m, q, frame);
      const Eigen::Isometry3d t0 = forward_kinematics(m, q, frame);
      for (int c = 0; c < kJointCount; ++c) {
        JointVector qp = q, qm = q;
        qp[c] += h / kDeg;
        qm[c] -= h / kDeg;
        const auto tp = forward_kinematics(m, qp, frame), tm = forward_kinematics(m, qm, frame);
        const Eigen::Vector3d v = (tp.translation() - tm.translation()) / (2 * h);
        const Eigen::Vector3d w = (rotation_log(tp.linear() * t0.linear().transpose()) -
                                   rotation_log(tm.linear() * t0.linear().transpose())) / (2 * h);
        EXPECT_LT((j.block<3, 1>(0, c) - v).norm(), 1e-5) << "joint " << c + 1;  // mm/rad
        EXPECT_LT((j.block<3, 1>(3, c) - w).norm(), 1e-8) << "joint " << c + 1;
      }
    }
  }
}

TEST(Kinematics, IdentificationJacobianMatchesFiniteDifferences) {
  const MdhModel m = perturbed_model();
  std::mt19937_64 rng(3);
  for (int k = 0; k < 10; ++k) {
    const JointVector q = random_joints(m, rng);
    const IdentificationJacobian j = identification_jacobian(m, q);
    for (int c = 0; c < param::kCount; ++c) {
      const double h = parameter_is_angle(c) ? 1e-6 : 1e-4;
      ParameterVector d = ParameterVector::Zero();
      d[c] = h;
      const Eigen::Vector3d pp = forward_position(apply_parameter_increment(m, d), q);
      d[c] = -h;
      const Eigen::Vector3d pm = forward_position(apply_parameter_increment(m, d), q);
      const Eigen::Vector3d fd = (pp - pm) / (2 * h);
      EXPECT_LT((j.col(c) - fd).norm(), 2e-5 * std::max(1.0, j.col(c).norm() / 1000.0))
          << parameter_name(c) << " at sample " << k;
    }
  }
}

TEST(Kinematics, ParameterNamesAndUnits) {
  EXPECT_EQ(parameter_name(0), "link1.alpha");
  EXPECT_EQ(parameter_name(param::link_index(2, param::kBeta)), "link3.beta");
  EXPECT_EQ(parameter_name(param::kBaseRotation + 2), "base.rz");
  EXPECT_EQ(parameter_name(param::kToolTranslation), "tool.x");
  EXPECT_STREQ(parameter_unit(param::link_index(1, param::kD)), "mm");
  EXPECT_STREQ(parameter_unit(param::link_index(1, param::kTheta0)), "rad");
  EXPECT_THROW(parameter_name(param::kCount), ArgumentError);
}

TEST(MdhModel, JsonRoundTrip) {
  const MdhModel m = perturbed_model();
  const MdhModel back = MdhModel::from_json(nlohmann::json::parse(m.to_json().dump()), "mem");
  EXPECT_EQ(back.name(), m.name());
  for (int i = 0; i < kJointCount; ++i) {
    EXPECT_EQ(back.link(i).alpha_deg, m.link(i).alpha_deg);
    EXPECT_EQ(back.link(i).a_mm, m.link(i).a_mm);
    EXPECT_EQ(back.link(i).d_mm, m.link(i).d_mm);
    EXPECT_EQ(back.link(i).beta_deg, m.link(i).beta_deg);
    EXPECT_EQ(back.link(i).q_max_deg, m.link(i).q_max_deg);
  }
  EXPECT_LT((back.base().matrix() - m.base().matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((back.tool().matrix() - m.tool().matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(MdhModel, JsonErrorsNameTheField) {
  nlohmann::json j = MdhModel::er20_c10().to_json();
  auto expect_error = [](const nlohmann::json& bad, const std::string& needle) {
    try {
      MdhModel::from_json(bad, "r.json");
      ADD_FAILURE() << "expected InputError mentioning " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_EQ(e.file(), "r.json");
    }
  };
  auto bad = j;
  bad["links"][2]["a_mm"] = "x";
  expect_error(bad, "links[2].a_mm");
  bad = j;
  bad["links"][1].erase("d_mm");
  expect_error(bad, "links[1].d_mm: missing");
  bad = j;
  bad["links"].erase(5);
  expect_error(bad, "expected an array of 6");
  bad = j;
  bad["tool"]["rz_deg"] = nullptr;
  expect_error(bad, "tool.rz_deg");
  bad = j;
  bad["links"][0]["q_min_deg"] = 200;
  expect_error(bad, "links[0].q_min_deg");
  bad = j;
  bad["links"][0]["lenght"] = 1;
  expect_error(bad, "unknown field");
  bad = j;
  bad["units"]["length"] = "m";
  expect_error(bad, "units.length");
}

TEST(MdhModel, ConstructorRejectsNonFiniteAndBadLimits) {
  auto links = MdhModel::er20_c10().links();
  links[3].a_mm = std::nan("");
  EXPECT_THROW(MdhModel("x", links), ArgumentError);
  links = MdhModel::er20_c10().links();
  links[4].q_min_deg = 10;
  links[4].q_max_deg = 10;
  EXPECT_THROW(MdhModel("x", links), ArgumentError);
}

TEST(InverseKinematics, RoundTripFromNearbySeed) {
  const MdhModel m = perturbed_model();
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n(0.0, 3.0);
  int tested = 0;
  for (int k = 0; k < 200 && tested < 60; ++k) {
    JointVector q = random_joints(m, rng);
    q[4] = std::copysign(std::max(std::abs(q[4]), 20.0), q[4]);  // keep away from the wrist singularity
    const auto jac = geometric_jacobian(m, q);
    Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(jac);
    if (svd.singularValues()[5] < 0.05) continue;  // near another singularity: not a fair round trip
    ++tested;
    const Eigen::Isometry3d target = forward_kinematics(m, q);
    JointVector seed = q;
    for (int i = 0; i < kJointCount; ++i) seed[i] += n(rng);
    const IkResult r = inverse_kinematics(m, target, seed);
    ASSERT_TRUE(r.ok()) << to_string(r.status) << " residual " << r.position_residual_mm;
    const Eigen::Isometry3d back = forward_kinematics(m, r.q_deg);
    EXPECT_LT((back.translation() - target.translation()).norm(), 1e-7);
    EXPECT_LT(rotation_log(back.linear() * target.linear().transpose()).norm(), 1e-10);
    EXPECT_LT((r.q_deg - q).cwiseAbs().maxCoeff(), 1e-6);  // same branch as the seed
  }
  EXPECT_GE(tested, 40);
}

TEST(InverseKinematics, PositionOnly) {
  const MdhModel m = MdhModel::er20_c10();
  JointVector q;
  q << 10, -100, -20, 5, -60, 30;
  Eigen::Isometry3d target = forward_kinematics(m, q);
  target.translation() += Eigen::Vector3d(20, -10, 15);
  IkOptions o;
  o.position_only = true;
  const IkResult r = inverse_kinematics(m, target, q, o);
  ASSERT_TRUE(r.ok());
  EXPECT_LT((forward_position(m, r.q_deg) - target.translation()).norm(), 1e-7);
}

TEST(InverseKinematics, UnreachableAndLimitedTargetsReportStatusAndResidual) {
  const MdhModel m = MdhModel::er20_c10();
  JointVector seed;
  seed << 0, -90, 0, 0, -90, 0;
  const Eigen::Isometry3d far = to_isometry({5000, 0, 500, 180, 0, 0});
  const IkResult r = inverse_kinematics(m, far, seed);
  EXPECT_FALSE(r.ok());
  // 5 m is outside the reach sphere (sum of link lengths ~2.35 m): unreachable, even though the
  // best pose within the limits has a joint at a limit.
  EXPECT_EQ(r.status, IkStatus::unreachable) << to_string(r.status);
  EXPECT_GT(r.position_residual_mm, 2000.0);  // reach is ~1.9 m
  EXPECT_TRUE(m.within_limits(r.q_deg));
  // Beyond the sphere there is nothing to iterate (a plan of a cube out of reach once took minutes):
  // answered at the seed, with the residual of the seed's pose, by both solvers.
  EXPECT_EQ(r.iterations, 0);
  EXPECT_NEAR(r.position_residual_mm, (forward_position(m, seed) - far.translation()).norm(), 1e-9);
  const IkResult rm = inverse_kinematics_multistart(m, far);
  EXPECT_EQ(rm.status, IkStatus::unreachable);
  EXPECT_EQ(rm.iterations, 0);
  EXPECT_NEAR(rm.position_residual_mm, (forward_position(m, rm.q_deg) - far.translation()).norm(), 1e-9);

  // Reachable geometrically but only with J1 beyond its limit (J1 limits narrowed to [-10, 10]).
  auto links = m.links();
  links[0].q_min_deg = -10;
  links[0].q_max_deg = 10;
  const MdhModel narrow("narrow", links);
  JointVector q;
  q << 40, -100, -20, 0, -60, 0;
  const IkResult rl = inverse_kinematics(narrow, forward_kinematics(m, q), seed);
  EXPECT_EQ(rl.status, IkStatus::joint_limits);
  EXPECT_GT(rl.position_residual_mm, 100.0);
  EXPECT_TRUE(narrow.within_limits(rl.q_deg));
}

TEST(InverseKinematics, OptionsValidate) {
  IkOptions o;
  EXPECT_NO_THROW(o.validate());
  o.max_iterations = 0;
  EXPECT_THROW(o.validate(), ArgumentError);
}

}  // namespace
}  // namespace errfield::robot
