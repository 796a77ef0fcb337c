#include "errfield/robot/simulator.hpp"

#include <cmath>
#include <numbers>

#include <Eigen/Dense>
#include <iostream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/robot/distance_error.hpp"
#include "errfield/compensation/model_fitting.hpp"

namespace errfield::robot {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SimulationRng, MomentsOfUniformAndNormal) {
  SimulationRng rng(42);
  const int n = 200000;
  double su = 0, su2 = 0, sn = 0, sn2 = 0, sn4 = 0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    su2 += u * u;
    const double z = rng.normal();
    sn += z;
    sn2 += z * z;
    sn4 += z * z * z * z;
  }
  // Tolerances ~5 standard errors of each estimate at n = 2e5.
  EXPECT_NEAR(su / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(su2 / n - 0.25, 1.0 / 12, 5 * 0.075 / std::sqrt(n));
  EXPECT_NEAR(sn / n, 0.0, 5 / std::sqrt(n));
  EXPECT_NEAR(sn2 / n, 1.0, 5 * std::sqrt(2.0 / n));
  EXPECT_NEAR(sn4 / n, 3.0, 5 * std::sqrt(96.0 / n));
}

TEST(SimulationRng, SameSeedSameStream) {
  SimulationRng a(7), b(7), c(8);
  for (int i = 0; i < 10; ++i) {
    const double x = a.normal();
    EXPECT_EQ(x, b.normal());
    EXPECT_NE(x, c.normal());
  }
  // The engine is std::mt19937_64, whose 10000th output the C++ standard fixes.
  std::mt19937_64 e;
  e.discard(9999);
  EXPECT_EQ(e(), 9981545732273789042ULL);
}

SimulatorConfig compliance_only() {
  SimulatorConfig c = SimulatorConfig::paper_default();
  c.geometry = {};
  c.absorb_rigid_part = false;
  c.transmission = {};
  return c;
}

TEST(Simulator, ComplianceMatchesVirtualWork) {
  // Independent check of the gravity torques: tau_j = -dV/dq_j with V = sum m_b g h_b the
  // potential energy, differentiated numerically through FK. Deflection = tau / k.
  const SimulatorConfig c = compliance_only();
  const SimulatedRobot robot(c);
  const auto& cm = c.compliance;
  auto potential = [&](const JointVector& q) {
    KinematicFrames f;
    forward_kinematics_all(robot.true_geometry(), q, f);
    double v = 0;
    for (int i = 0; i < kJointCount; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const Eigen::Vector3d o = f.frames[k + 1].translation();
      const Eigen::Vector3d p = i + 1 < kJointCount ? Eigen::Vector3d(0.5 * (o + f.frames[k + 2].translation()))
                                                    : Eigen::Vector3d(o + 50.0 * f.frames[k + 1].linear().col(2));
      v -= cm.link_mass_kg[k] * cm.gravity_world.dot(p * 1e-3);
    }
    v -= cm.payload_kg * cm.gravity_world.dot(f.tool().translation() * 1e-3);
    return v;  // J
  };
  JointVector q;
  q << 12, -110, -25, 8, -50, 30;
  const JointVector dq = robot.joint_deflection_deg(q);
  for (int j = 0; j < kJointCount; ++j) {
    const double h = 1e-5;  // rad
    JointVector qp = q, qm = q;
    qp[j] += h / kDeg;
    qm[j] -= h / kDeg;
    const double tau = -(potential(qp) - potential(qm)) / (2 * h);
    const double expected = tau / cm.stiffness_nm_per_rad[static_cast<std::size_t>(j)] / kDeg;
    EXPECT_NEAR(dq[j], expected, 1e-6 * std::abs(expected) + 1e-12) << "joint " << j + 1;
  }
  EXPECT_NEAR(dq[0], 0.0, 1e-12);  // vertical axis: no gravity torque
  EXPECT_GT(std::abs(dq[1]), 1e-3);  // shoulder sags by a noticeable amount (> 0.001 deg)
}

TEST(Simulator, TransmissionErrorIsTheConfiguredSine) {
  SimulatorConfig c = compliance_only();
  c.compliance = {};
  c.transmission.amplitude_deg = {0, 0.01, 0, 0, 0, 0};
  c.transmission.harmonic = {0, 6, 0, 0, 0, 0};
  c.transmission.phase_deg = {0, 30, 0, 0, 0, 0};
  const SimulatedRobot robot(c);
  JointVector q;
  q << 0, -100, -20, 0, -60, 0;
  EXPECT_NEAR(robot.joint_deflection_deg(q)[1], 0.01 * std::sin((6 * -100 + 30) * kDeg), 1e-15);
  EXPECT_EQ(robot.joint_deflection_deg(q)[2], 0.0);
}

TEST(Simulator, RigidPartOfGeometricErrorIsAbsorbed) {
  // Deviations of link 1 only (alpha_0, a_0, theta0_1, d_1, beta_1) all act before joint 1's
  // rotation or commute with it, so they move the whole arm rigidly: after absorption the true
  // geometry must coincide with the nominal one everywhere, while without it the error is mm-sized.
  SimulatorConfig c = SimulatorConfig::paper_default();
  c.compliance = {};
  c.transmission = {};
  c.geometry = {};
  c.geometry.link[0] = {0.05, 0.8, -0.07, 1.2, 0.03};
  const SimulatedRobot with(c);
  c.absorb_rigid_part = false;
  const SimulatedRobot without(c);
  SimulationRng rng(3);
  for (int k = 0; k < 50; ++k) {
    JointVector q;
    for (int i = 0; i < kJointCount; ++i) q[i] = rng.uniform(-120, 120);
    const Eigen::Vector3d nominal = forward_position(c.nominal, q);
    EXPECT_LT((forward_position(with.true_geometry(), q) - nominal).norm(), 1e-9);
    EXPECT_GT((forward_position(without.true_geometry(), q) - nominal).norm(), 0.5);
  }
}

TEST(Simulator, DeterministicForASeed) {
  const SimulatedRobot robot(SimulatorConfig::paper_default());
  JointVector q;
  q << 5, -100, -30, 0, -50, 160;
  SimulationRng a(9), b(9);
  const Eigen::Vector3d m1 = robot.measure(robot.move(q, a), a);
  const Eigen::Vector3d m2 = robot.measure(robot.move(q, b), b);
  EXPECT_EQ(m1, m2);
}

TEST(Simulator, NoiseLevelsAreTheConfiguredOnes) {
  const SimulatorConfig c = SimulatorConfig::paper_default();
  const SimulatedRobot robot(c);
  JointVector q;
  q << 5, -100, -30, 0, -50, 160;
  const Eigen::Vector3d truth = robot.true_position(q);
  SimulationRng rng(10);
  const int n = 20000;
  double s_rep = 0, s_trk = 0;
  const Eigen::Vector3d in_tracker = c.tracker.tracker_from_world * truth;
  for (int i = 0; i < n; ++i) {
    s_rep += (robot.move(q, rng) - truth).squaredNorm();
    s_trk += (robot.measure(truth, rng) - in_tracker).squaredNorm();
  }
  const double sigma_rep = std::sqrt(s_rep / (3 * n));
  const double sigma_trk = std::sqrt(s_trk / (3 * n));
  EXPECT_NEAR(sigma_rep, c.repeatability_sigma_mm, 0.02 * c.repeatability_sigma_mm);  // ~0.4% std error
  const double expected_trk = c.tracker.sigma_constant_mm + c.tracker.sigma_per_m_mm * in_tracker.norm() * 1e-3;
  EXPECT_NEAR(sigma_trk, expected_trk, 0.02 * expected_trk);
}

TEST(Simulator, PaperCubeIsReachableOnOneBranch) {
  const SimulatedRobot robot(SimulatorConfig::paper_default());
  const MeasurementCube cube = paper_cube();
  const IkResult seed = cube_seed(robot.nominal(), cube);
  ASSERT_TRUE(seed.ok());
  for (const auto& p : cube.grid(125)) {
    const IkResult r = solve_cube_pose(robot.nominal(), cube, p, seed.q_deg);
    ASSERT_TRUE(r.ok()) << p.transpose();
    EXPECT_LT((r.q_deg - seed.q_deg).cwiseAbs().maxCoeff(), 90.0);  // no wrist flips
  }
  EXPECT_EQ(cube.grid(125).size(), 125u);
  SimulationRng rng(1);
  const auto samples = cube.random_per_cell(125, rng);
  ASSERT_EQ(samples.size(), 64u);
  // Sample i lies in cell i (x fastest).
  for (int i = 0; i < 64; ++i) {
    const Eigen::Vector3d cell = ((samples[static_cast<std::size_t>(i)] - cube.min_corner_mm) / 125.0).array().floor();
    EXPECT_EQ(cell.x() + 4 * cell.y() + 16 * cell.z(), i);
  }
  EXPECT_THROW(cube.grid(120), ArgumentError);
}

TEST(Simulator, DefaultErrorSizeIsThePapers) {
  // The tuning target of SimulatorConfig::paper_default (docs/robot.md): uncompensated distance
  // error on the paper's own metric — the distance to its base point P0(0,0,0) of the measurement
  // frame, the tracker itself (a fixed point) — over 64 random cube points at tool-down
  // orientation, of about the paper's "none" row (mean 0.514 mm, max 1.346 mm). Noise-free truth,
  // the tracker's true position, three sample sets.
  const SimulatedRobot robot(SimulatorConfig::paper_default());
  const MeasurementCube cube = paper_cube();
  const IkResult seed = cube_seed(robot.nominal(), cube);
  ASSERT_TRUE(seed.ok());
  // As the paper and `reproduce` do, the tracker is placed in the robot frame by a registration on
  // the 125 grid nodes (here noise-free), which absorbs the rigid part of the error in the cube.
  std::vector<Eigen::Vector3d> truth, nominal;
  for (const auto& p : cube.grid(125)) {
    truth.push_back(robot.true_position(solve_cube_pose(robot.nominal(), cube, p, seed.q_deg).q_deg));
    nominal.push_back(p);
  }
  const Eigen::Isometry3d robot_from_world = compensation::fit_registration(truth, nominal).robot_from_tracker;
  const Eigen::Vector3d p0 = robot_from_world * robot.config().tracker.tracker_from_world.inverse().translation();
  for (std::uint64_t s = 1; s <= 3; ++s) {
    SimulationRng rng(s);
    double mx = 0, mean = 0;
    const auto pts = cube.random_per_cell(125, rng);
    for (const auto& p : pts) {
      const IkResult r = solve_cube_pose(robot.nominal(), cube, p, seed.q_deg);
      ASSERT_TRUE(r.ok());
      const double dl = std::abs((robot_from_world * robot.true_position(r.q_deg) - p0).norm() - (p - p0).norm());
      mx = std::max(mx, dl);
      mean += dl / static_cast<double>(pts.size());
    }
    std::cout << "[ none, distance to the tracker ] mean " << mean << " mm, max " << mx << " mm\n";
    EXPECT_GT(mean, 0.8 * 0.514);
    EXPECT_LT(mean, 1.25 * 0.514);
    EXPECT_GT(mx, 0.7 * 1.346);
  }
}

TEST(SimulatorConfig, JsonRoundTripAndFieldErrors) {
  const SimulatorConfig c = SimulatorConfig::paper_default();
  const SimulatorConfig back = SimulatorConfig::from_json(nlohmann::json::parse(c.to_json().dump()), "mem");
  EXPECT_EQ(back.seed, c.seed);
  EXPECT_EQ(back.geometry.link, c.geometry.link);
  EXPECT_EQ(back.compliance.stiffness_nm_per_rad, c.compliance.stiffness_nm_per_rad);
  EXPECT_EQ(back.transmission.harmonic, c.transmission.harmonic);
  EXPECT_LT((back.tracker.tracker_from_world.matrix() - c.tracker.tracker_from_world.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  JointVector q;
  q << 5, -100, -30, 0, -50, 160;
  EXPECT_LT((SimulatedRobot(back).true_position(q) - SimulatedRobot(c).true_position(q)).norm(), 1e-9);

  auto expect_error = [](const nlohmann::json& j, const std::string& needle) {
    try {
      SimulatorConfig::from_json(j, "sim.json");
      ADD_FAILURE() << "expected InputError with " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_error({{"compliance", {{"stiffness_nm_per_rad", {1, 2, 3}}}}}, "compliance.stiffness_nm_per_rad");
  expect_error({{"compliance", {{"payload_kg", -1}}}}, "payload_kg");
  expect_error({{"tracker", {{"sigma_per_m", 1}}}}, "tracker.sigma_per_m");
  expect_error({{"geometry", {{"links", {{{"a_mm", "x"}}, {}, {}, {}, {}, {}}}}}}, "geometry.links[0].a_mm");
}

}  // namespace
}  // namespace errfield::robot
