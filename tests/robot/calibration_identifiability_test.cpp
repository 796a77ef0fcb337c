// Kinematic calibration on data it did not generate (issue 10, item 4): joints recorded to a few
// decimals must not make noise-level parameters identifiable, the reported condition number is
// that of the parameters kept, and distance calibration's frame is aligned over configurations.

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "errfield/robot/calibration.hpp"
#include "errfield/robot/random.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::robot {
namespace calibration_identifiability_test {

JointVector rounded(const JointVector& q, int decimals) {
  if (decimals < 0) return q;
  const double f = std::pow(10.0, decimals);
  JointVector r;
  for (int j = 0; j < kJointCount; ++j) r[j] = std::round(q[j] * f) / f;
  return r;
}

// `errfield simulate --seed 1 --measure distances` in the library: the default simulated robot,
// the paper cube's 125 grid points at tool-down, distances from the corner node (a robot position
// measured once) to the other 124. The controller's joints are recorded to `decimals` decimals
// (-1: exactly); the robot moved at the unrounded ones.
struct CubeDistances {
  SimulatedRobot sim{SimulatorConfig::paper_default()};
  MeasurementCube cube = paper_cube();
  JointVector seed, qb;
  std::vector<DistanceMeasurement> data;

  explicit CubeDistances(int decimals, std::uint64_t stream = 1) {
    const MdhModel& nominal = sim.nominal();
    seed = cube_seed(nominal, cube).q_deg;
    const Eigen::Vector3d b = paper_base_point_nominal();
    qb = solve_cube_pose(nominal, cube, b, seed).q_deg;
    SimulationRng rng(stream);
    const Eigen::Vector3d base_measured = sim.measure(sim.move(qb, rng), rng);
    for (const auto& p : cube.grid(125)) {
      if ((p - b).norm() < 1) continue;
      const JointVector q = solve_cube_pose(nominal, cube, p, seed).q_deg;
      data.push_back({rounded(qb, decimals), rounded(q, decimals),
                      (sim.measure(sim.move(q, rng), rng) - base_measured).norm()});
    }
  }

  // Mean |error| of the distance from the base pose to 64 held-out poses (one random target per
  // cell) that `model` predicts, against the true distance. Frame-free, like the data: distances
  // leave the identified model's frame free.
  double heldout_mean_mm(const MdhModel& model) const {
    SimulationRng rng(99);
    double sum = 0;
    const auto targets = cube.random_per_cell(125, rng);
    for (const auto& p : targets) {
      const JointVector q = solve_cube_pose(sim.nominal(), cube, p, seed).q_deg;
      const double predicted = (forward_position(model, q) - forward_position(model, qb)).norm();
      sum += std::abs(predicted - (sim.true_position(q) - sim.true_position(qb)).norm());
    }
    return sum / static_cast<double>(targets.size());
  }
};

CalibrationOptions plain() {
  CalibrationOptions o;
  o.robust.enabled = false;
  return o;
}

// The reproduction: with joints rounded to 6 decimals the tool offset (whose column, at one
// constant orientation, only the rounding moves) was identified as (193364, 82946, 124810) mm and
// LM hit its iteration limit. Rounding at 6 or 3 decimals must leave the calibration where the
// exact joints put it: converged, no parameter moved beyond a physically plausible size, and the
// same held-out accuracy.
TEST(CalibrationRounding, RoundedJointsDoNotRunAway) {
  const CubeDistances exact(-1);
  const CalibrationResult ref = calibrate_distances(exact.sim.nominal(), exact.data, plain());
  ASSERT_TRUE(ref.converged) << ref.report();
  const double none = exact.heldout_mean_mm(exact.sim.nominal());
  const double ref_heldout = exact.heldout_mean_mm(ref.model);
  EXPECT_LT(ref_heldout, 0.3 * none) << ref.report();
  for (int decimals : {6, 3}) {
    SCOPED_TRACE(std::to_string(decimals) + " decimals");
    const CubeDistances data(decimals);
    for (bool robust : {false, true}) {
      SCOPED_TRACE(robust ? "igg3" : "plain least squares");
      CalibrationOptions o = plain();
      o.robust.enabled = robust;
      const CalibrationResult r = calibrate_distances(data.sim.nominal(), data.data, o);
      EXPECT_NE(r.message, "LM iteration limit reached") << r.report();
      // The simulated deviations are below 3 mm and 0.17 deg per parameter; kept parameters trade
      // off along weakly determined directions by a few times that, a runaway by 1e5 mm.
      for (const auto& p : r.parameters) EXPECT_LT(std::abs(p.increment), p.unit == "mm" ? 50.0 : 5.0) << p.name;
      for (const char* tool : {"tool.x", "tool.y", "tool.z"})
        EXPECT_TRUE(std::none_of(r.parameters.begin(), r.parameters.end(),
                                 [&](const ParameterEstimate& p) { return p.name == tool; }))
            << tool << " identified from rounding noise\n" << r.report();
      const double heldout = data.heldout_mean_mm(r.model);
      EXPECT_LT(heldout, 0.3 * none) << r.report();
      if (!robust) EXPECT_NEAR(heldout, ref_heldout, 0.1 * ref_heldout) << r.report();
    }
  }
}

// The condition number reported is the one of the kept parameters' Jacobian in physical units
// (mm, and rad × reach, reach = Σ(|a| + |d|) + |tool|), recomputed here from the public Jacobian
// (the issue saw 4e5–5e8 reported against a documented 1e3 that did not belong to the kept set).
// From distances the cap no longer bounds it: it sets the Tikhonov weight toward nominal,
// 0.1 · (largest singular value / cap)², so the weight scales with 1 / cap².
TEST(CalibrationRounding, ConditionNumberIsThatOfTheKeptParameters) {
  const CubeDistances data(6);
  const MdhModel& nominal = data.sim.nominal();
  std::vector<double> weights;
  for (double cap : {1e3, 1e2}) {
    CalibrationOptions o = plain();
    o.max_condition_number = cap;
    const CalibrationResult r = calibrate_distances(nominal, data.data, o);
    double reach = nominal.tool().translation().norm();
    for (const MdhLink& l : nominal.links()) reach += std::abs(l.a_mm) + std::abs(l.d_mm);
    EXPECT_DOUBLE_EQ(r.reach_mm, reach);
    std::vector<int> kept;
    for (const auto& p : r.parameters) kept.push_back(p.index);
    ASSERT_FALSE(kept.empty());
    Eigen::MatrixXd j = distance_identification_jacobian(nominal, data.data, {}, kept);
    for (std::size_t c = 0; c < kept.size(); ++c)
      if (parameter_is_angle(kept[c])) j.col(static_cast<Eigen::Index>(c)) /= reach;
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(j).singularValues();
    const double cond = sv[0] / sv[sv.size() - 1];
    EXPECT_NEAR(r.condition_number, cond, 1e-6 * cond) << r.report();
    EXPECT_NE(r.report().find("condition number"), std::string::npos);
    EXPECT_NE(r.report().find("Tikhonov weight"), std::string::npos);
    weights.push_back(r.regularization);
  }
  ASSERT_GT(weights[0], 0.0);
  EXPECT_NEAR(weights[1] / weights[0], 100.0, 1e-6);
}

// Distances leave the frame free; the identified model is placed by the least-squares rigid fit
// to the initial model over the measured configurations, each counted once. At that optimum the
// centroids agree and the cross-covariance of the centred point sets is symmetric (Kabsch: the
// identity is the best rotation iff H = Σ a bᵀ is symmetric positive semidefinite). Counting the
// base point once per pair (124 times) moved the centroid onto it.
TEST(CalibrationRounding, FrameAlignedOverConfigurationsNotPairs) {
  const CubeDistances data(-1);
  const MdhModel& nominal = data.sim.nominal();
  const CalibrationResult r = calibrate_distances(nominal, data.data, plain());
  std::vector<JointVector> q{data.data.front().q_a_deg};  // the base pose, once
  for (const auto& d : data.data) q.push_back(d.q_b_deg);
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (const auto& qk : q) {
    ca += forward_position(r.model, qk);
    cb += forward_position(nominal, qk);
  }
  ca /= static_cast<double>(q.size());
  cb /= static_cast<double>(q.size());
  EXPECT_LT((ca - cb).norm(), 1e-6);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (const auto& qk : q) h += (forward_position(r.model, qk) - ca) * (forward_position(nominal, qk) - cb).transpose();
  EXPECT_LT((h - h.transpose()).norm(), 1e-9 * h.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (h + h.transpose())).eigenvalues().minCoeff(), 0.0);
}

// Anti-parallel consecutive axes (alpha = 180 deg, as URDF imports write a joint turning the other
// way) are as singular for d/theta0 as parallel ones: a small tilt between them is only Hayati's
// beta. The true arm has that tilt; the calibration must offer beta and recover it.
TEST(CalibrationParallelAxes, AntiParallelAxesGetBeta) {
  std::array<MdhLink, kJointCount> links = MdhModel::er20_c10().links();
  ASSERT_NEAR(links[2].alpha_deg, 0.0, 1e-12);  // joints 2 and 3 parallel in the ER20-C10
  links[2].alpha_deg = 180.0;
  const MdhModel nominal = MdhModel::er20_c10().with_links(links);
  for (const double alpha : {180.0, -180.0, 179.9999999, 0.0}) {
    std::array<MdhLink, kJointCount> l = links;
    l[2].alpha_deg = alpha;
    const std::vector<int> c = default_candidates(nominal.with_links(l), false);
    EXPECT_NE(std::find(c.begin(), c.end(), param::link_index(2, param::kBeta)), c.end()) << alpha;
  }
  links[2].beta_deg = 0.05;
  links[2].a_mm += 0.3;
  links[3].d_mm -= 0.2;
  const MdhModel truth = nominal.with_links(links);
  std::mt19937_64 rng(7);
  std::vector<PositionMeasurement> data;
  for (int i = 0; i < 150; ++i) {
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) {
      const MdhLink& lj = nominal.link(j);
      q[j] = std::uniform_real_distribution<double>(0.6 * lj.q_min_deg, 0.6 * lj.q_max_deg)(rng);
    }
    data.push_back({q, forward_position(truth, q)});
  }
  const CalibrationResult r = calibrate_positions(nominal, data, plain());
  ASSERT_TRUE(r.converged) << r.report();
  const auto beta = std::find_if(r.parameters.begin(), r.parameters.end(),
                                 [](const ParameterEstimate& p) { return p.index == param::link_index(2, param::kBeta); });
  ASSERT_NE(beta, r.parameters.end()) << r.report();
  EXPECT_NEAR(beta->nominal + beta->increment, 0.05, 1e-6);
  // noise-free data: the identified model reproduces every position
  EXPECT_LT(r.after.rms_mm, 1e-6) << r.report();
}

}  // namespace
}  // namespace errfield::robot
