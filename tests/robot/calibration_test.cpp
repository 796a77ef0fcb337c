#include "errfield/robot/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "errfield/error.hpp"
#include "errfield/robot/random.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::robot {
namespace calibration_test {

// A "true" robot: the ER20-C10 with the paper ball as tool, every MD-H parameter, the tool and
// the base perturbed (purely geometric, so a perfect calibration exists).
MdhModel true_model(const MdhModel& nominal, std::uint64_t seed, double scale = 1.0) {
  SimulationRng rng(seed);
  auto links = nominal.links();
  for (std::size_t i = 0; i < links.size(); ++i) {
    links[i].alpha_deg += scale * rng.normal(0, 0.05);
    links[i].a_mm += scale * rng.normal(0, 0.8);
    links[i].theta0_deg += scale * rng.normal(0, 0.05);
    links[i].d_mm += scale * rng.normal(0, 0.8);
    if (i == 2) links[i].beta_deg += scale * rng.normal(0, 0.03);  // joints 2-3 parallel: Hayati tilt
  }
  Eigen::Isometry3d tool = nominal.tool();
  tool.translation() += scale * Eigen::Vector3d(rng.normal(0, 0.3), rng.normal(0, 0.3), rng.normal(0, 0.3));
  return MdhModel("truth", links, nominal.base(), tool);
}

std::vector<JointVector> random_configurations(const MdhModel& m, std::size_t n, std::uint64_t seed) {
  SimulationRng rng(seed);
  std::vector<JointVector> q(n);
  for (auto& v : q) {
    v << rng.uniform(-60, 60), rng.uniform(-140, -60), rng.uniform(-60, 30), rng.uniform(-90, 90),
        rng.uniform(-100, -20), rng.uniform(-90, 90);
    EXPECT_TRUE(m.within_limits(v));
  }
  return q;
}

MdhModel nominal_model() { return MdhModel::er20_c10().with_tool(paper_ball()); }

TEST(Igg3, WeightFunction) {
  EXPECT_EQ(igg3_weight(0.0, 1.5, 3.0), 1.0);
  EXPECT_EQ(igg3_weight(1.5, 1.5, 3.0), 1.0);
  EXPECT_NEAR(igg3_weight(2.0, 1.5, 3.0), (1.5 / 2.0) * std::pow(1.0 / 1.5, 2), 1e-15);
  EXPECT_EQ(igg3_weight(3.0001, 1.5, 3.0), 0.0);
  // Continuous at k0 and k1.
  EXPECT_NEAR(igg3_weight(1.5 + 1e-9, 1.5, 3.0), 1.0, 1e-8);
  EXPECT_NEAR(igg3_weight(3.0 - 1e-9, 1.5, 3.0), 0.0, 1e-8);
}

TEST(Calibration, PositionsNoiseFreeRecoverTheTruth) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model(nominal, 1).with_base(to_isometry({1.2, -0.8, 0.5, 0.02, -0.03, 0.05}));
  std::vector<PositionMeasurement> data;
  for (const auto& q : random_configurations(nominal, 60, 2)) data.push_back({q, forward_position(truth, q)});
  CalibrationOptions o;
  o.robust.enabled = false;
  const CalibrationResult r = calibrate_positions(nominal, data, o);
  ASSERT_TRUE(r.converged) << r.report();
  EXPECT_GT(r.before.rms_mm, 1.0);
  EXPECT_LT(r.after.rms_mm, 1e-8);
  // The identifiable combinations are recovered: the identified model predicts the true tool
  // position at configurations not used for identification to 1e-6 mm.
  for (const auto& q : random_configurations(nominal, 40, 3))
    EXPECT_LT((forward_position(r.model, q) - forward_position(truth, q)).norm(), 1e-6);
  // The structural redundancies of a 6R arm with parallel axes 2-3 are found and explained.
  bool d3_removed = false;
  for (const auto& rm : r.removed) d3_removed = d3_removed || rm.name == "link3.d" || rm.name == "link2.d";
  EXPECT_TRUE(d3_removed) << r.report();
  EXPECT_TRUE(std::isfinite(r.condition_number));
}

TEST(Calibration, DistancesNoiseFreeRecoverTheTruthUpToRigidMotion) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model(nominal, 4);
  const auto bases = random_configurations(nominal, 4, 5);
  std::vector<DistanceMeasurement> data;
  for (const auto& q : random_configurations(nominal, 80, 6))
    for (const auto& b : bases) data.push_back({q, b, (forward_position(truth, q) - forward_position(truth, b)).norm()});
  CalibrationOptions o;
  o.robust.enabled = false;
  // Noise-free: the cap sets distance calibration's regularization toward nominal (a noise
  // policy); at 1e8 its weight is 1e-17 of the largest squared singular value, negligible.
  o.max_condition_number = 1e8;
  const CalibrationResult r = calibrate_distances(nominal, data, o);
  ASSERT_TRUE(r.converged) << r.report();
  EXPECT_LT(r.after.rms_mm, 1e-8) << r.report();
  // Distances are all that is identifiable: predicted distances between new configurations agree.
  const auto test = random_configurations(nominal, 30, 7);
  for (std::size_t i = 0; i + 1 < test.size(); ++i) {
    const double want = (forward_position(truth, test[i]) - forward_position(truth, test[i + 1])).norm();
    const double got = (forward_position(r.model, test[i]) - forward_position(r.model, test[i + 1])).norm();
    EXPECT_NEAR(got, want, 1e-6);
  }
  bool base_removed = false;
  for (const auto& rm : r.removed) base_removed = base_removed || rm.name.rfind("base.", 0) == 0;
  EXPECT_FALSE(base_removed);  // never a candidate by default
}

// ---- fixed base points ------------------------------------------------------------------------

// The truth for fixed-point calibration: every MD-H parameter perturbed except the four that
// place the robot in the world (link1.alpha, a, theta0, d): distances to points whose coordinates
// are identified too cannot see those (a common rigid motion of robot and points), so they define
// the frame and stay nominal.
MdhModel true_model_fixed_frame(const MdhModel& nominal, std::uint64_t seed) {
  MdhModel t = true_model(nominal, seed);
  auto links = t.links();
  links[0] = nominal.links()[0];
  return MdhModel("truth", links, nominal.base(), t.tool());
}

std::vector<Eigen::Vector3d> true_fixed_points() {
  // Nests around the paper cube (robot base frame, mm), not on the joint-1 axis.
  return {{1500, 650, 150}, {600, -700, 250}, {1300, -500, 1100}};
}

std::vector<DistanceMeasurement> fixed_point_data(const MdhModel& truth, const std::vector<Eigen::Vector3d>& points,
                                                  std::size_t poses, std::uint64_t seed, double noise_mm = 0.0) {
  SimulationRng rng(seed + 1000);
  std::vector<DistanceMeasurement> data;
  for (const auto& q : random_configurations(truth, poses, seed))
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double d = (forward_position(truth, q) - points[k]).norm() + (noise_mm > 0 ? rng.normal(0, noise_mm) : 0.0);
      data.push_back({q, JointVector::Zero(), d, static_cast<int>(k)});
    }
  return data;
}

std::vector<Eigen::Vector3d> perturbed(std::vector<Eigen::Vector3d> p) {
  const Eigen::Vector3d offsets[] = {{0.8, -0.5, 1.1}, {-1.2, 0.4, 0.6}, {0.3, 0.9, -0.7}};
  for (std::size_t k = 0; k < p.size(); ++k) p[k] += offsets[k % 3];
  return p;
}

TEST(Calibration, FixedBaseJacobianMatchesFiniteDifferences) {
  const MdhModel m = true_model(nominal_model(), 20);
  const std::vector<Eigen::Vector3d> points = {{1500, 650, 150}, {600, -700, 250}};
  const auto q = random_configurations(m, 4, 21);
  std::vector<DistanceMeasurement> data;
  for (const auto& qi : q) {
    data.push_back({qi, JointVector::Zero(), 0.0, 0});
    data.push_back({qi, JointVector::Zero(), 0.0, 1});
  }
  data.push_back({q[0], q[1], 0.0});  // a robot-position pair in the same data
  std::vector<int> all;
  for (int c = 0; c < param::kCount + 6; ++c) all.push_back(c);
  const Eigen::MatrixXd jac = distance_identification_jacobian(m, data, points, all);
  ASSERT_EQ(jac.rows(), static_cast<Eigen::Index>(data.size()));
  ASSERT_EQ(jac.cols(), param::kCount + 6);
  // Independent prediction: the distance straight from forward kinematics and the point.
  auto predict = [&](const MdhModel& mm, const std::vector<Eigen::Vector3d>& b, const DistanceMeasurement& d) {
    const Eigen::Vector3d pb = d.fixed_base >= 0 ? b[static_cast<std::size_t>(d.fixed_base)] : forward_position(mm, d.q_b_deg);
    return (forward_position(mm, d.q_a_deg) - pb).norm();
  };
  const double h = 1e-6;
  for (int c = 0; c < param::kCount + 6; ++c) {
    MdhModel mp = m, mn = m;
    std::vector<Eigen::Vector3d> bp = points, bn = points;
    if (c < param::kCount) {
      ParameterVector delta = ParameterVector::Zero();
      delta[c] = h;
      mp = apply_parameter_increment(m, delta);
      mn = apply_parameter_increment(m, -delta);
    } else {
      bp[static_cast<std::size_t>((c - param::kCount) / 3)][(c - param::kCount) % 3] += h;
      bn[static_cast<std::size_t>((c - param::kCount) / 3)][(c - param::kCount) % 3] -= h;
    }
    for (std::size_t i = 0; i < data.size(); ++i) {
      const double fd = (predict(mp, bp, data[i]) - predict(mn, bn, data[i])) / (2 * h);
      EXPECT_NEAR(jac(static_cast<Eigen::Index>(i), c), fd, 1e-4 * std::max(1.0, std::abs(fd)))
          << "column " << c << " row " << i;
    }
  }
  // The point's own columns are −nᵀ: unit length, zero for rows of other points and for pairs.
  EXPECT_NEAR(jac.block(0, param::kCount, 1, 3).norm(), 1.0, 1e-12);
  EXPECT_EQ(jac.block(0, param::kCount + 3, 1, 3).norm(), 0.0);
  EXPECT_EQ(jac.block(static_cast<Eigen::Index>(data.size()) - 1, param::kCount, 1, 6).norm(), 0.0);
}

// Noise-free distances to fixed points whose nominal position is off by about 1 mm: the robot and
// the points are recovered (one point and three points), and the robot's placement parameters are
// removed as redundant with the point coordinates, with that reason.
TEST(Calibration, FixedBasesNoiseFreeRecoverRobotAndPoints) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model_fixed_frame(nominal, 22);
  for (std::size_t count : {1u, 3u}) {
    SCOPED_TRACE(std::to_string(count) + " fixed point(s)");
    std::vector<Eigen::Vector3d> points = true_fixed_points();
    points.resize(count);
    const auto data = fixed_point_data(truth, points, 120 / count, 23);
    CalibrationOptions o;
    o.robust.enabled = false;
    o.max_condition_number = 1e8;  // noise-free: negligible regularization (see above)
    const CalibrationResult r = calibrate_distances(nominal, data, perturbed(points), o);
    ASSERT_TRUE(r.converged) << r.report();
    EXPECT_GT(r.before.rms_mm, 0.5);
    EXPECT_LT(r.after.rms_mm, 1e-8) << r.report();
    ASSERT_EQ(r.base_points.size(), count);
    for (std::size_t k = 0; k < count; ++k) {
      for (int c = 0; c < 3; ++c) EXPECT_TRUE(r.base_points[k].identified[c]) << r.report();
      EXPECT_LT((r.base_points[k].position_mm - points[k]).norm(), 1e-6) << r.report();
      EXPECT_EQ((r.base_points[k].nominal_mm - perturbed(points)[k]).norm(), 0.0);
    }
    for (const auto& q : random_configurations(nominal, 30, 24))
      EXPECT_LT((forward_position(r.model, q) - forward_position(truth, q)).norm(), 1e-6);
    for (const char* name : {"link1.alpha", "link1.a", "link1.theta0", "link1.d"}) {
      const auto it = std::find_if(r.removed.begin(), r.removed.end(), [&](const RemovedParameter& p) { return p.name == name; });
      ASSERT_NE(it, r.removed.end()) << name << "\n" << r.report();
      EXPECT_NE(it->reason.find("redundant"), std::string::npos) << it->reason;
      EXPECT_NE(it->reason.find("base point"), std::string::npos) << it->reason;
    }
    for (const auto& p : r.parameters) EXPECT_NE(p.name.rfind("link1.", 0), 0u) << p.name;
    EXPECT_NE(r.report().find("fixed base point 0"), std::string::npos);
    // The invariance (a common rigid motion of robot and points) does not depend on how many
    // points there are: with well-spread poses the same candidates go, 1 point or 3.
    std::vector<std::string> names;
    for (const auto& p : r.removed) names.push_back(p.name);
    EXPECT_EQ(names, (std::vector<std::string>{"link1.alpha", "link1.a", "link1.theta0", "link1.d", "link3.d",
                                               "link6.theta0", "link6.d"}))
        << r.report();
  }
}

// With 0.01 mm noise the standard errors are plausible: each true coordinate within 3 sigma, and
// the sigmas neither zero nor larger than the nominal offset.
TEST(Calibration, FixedBasesWithNoiseHavePlausibleStandardErrors) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model_fixed_frame(nominal, 25);
  const auto points = true_fixed_points();
  const auto data = fixed_point_data(truth, points, 60, 26, 0.01);
  const CalibrationResult r = calibrate_distances(nominal, data, perturbed(points));
  ASSERT_TRUE(r.converged) << r.report();
  EXPECT_LT(r.after.rms_mm, 0.015) << r.report();
  for (std::size_t k = 0; k < points.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const BasePointEstimate& b = r.base_points[k];
      ASSERT_TRUE(b.identified[c]);
      EXPECT_GT(b.standard_error_mm[c], 1e-4) << r.report();
      EXPECT_LT(b.standard_error_mm[c], 0.2) << r.report();
      EXPECT_LT(std::abs(b.position_mm[c] - points[k][c]), 3 * b.standard_error_mm[c])
          << "point " << k << " coordinate " << c << "\n" << r.report();
    }
}

TEST(Calibration, FixedBaseBadInput) {
  const MdhModel nominal = nominal_model();
  const auto data = fixed_point_data(nominal, {{1500, 650, 150}, {600, -700, 250}}, 30, 27);
  // The data name point 1 but only one point is given.
  using Points = std::vector<Eigen::Vector3d>;
  EXPECT_THROW(calibrate_distances(nominal, data, Points{{1500, 650, 150}}), InputError);
  EXPECT_THROW(calibrate_distances(nominal, data), InputError);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(calibrate_distances(nominal, data, Points{{1500, 650, 150}, {nan, 0, 0}}), InputError);
  // Too few distinct poses for the robot and the point: the guard names the count, no fit.
  const auto few = fixed_point_data(nominal, {{1500, 650, 150}}, 8, 28);
  try {
    calibrate_distances(nominal, few, Points{{1500, 650, 150}});
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("need at least"), std::string::npos) << e.what();
  }
}

TEST(Calibration, RegistrationFindsTrackerFrameAndReflector) {
  const MdhModel nominal = nominal_model();
  const Eigen::Isometry3d tracker_from_robot = to_isometry({2500, -300, 200, 0.5, -0.3, 178});
  Eigen::Isometry3d reflector = nominal.tool();
  reflector.translation() += Eigen::Vector3d(0.4, -0.2, 0.7);
  const MdhModel truth = nominal.with_tool(reflector).with_base(tracker_from_robot);
  std::vector<PositionMeasurement> data;
  for (const auto& q : random_configurations(nominal, 20, 8)) data.push_back({q, forward_position(truth, q)});
  const CalibrationResult r = register_tracker(nominal, data);  // nominal base = identity: far start
  ASSERT_TRUE(r.converged) << r.report();
  EXPECT_EQ(r.parameters.size(), 9u) << r.report();
  EXPECT_LT((r.model.base().matrix() - tracker_from_robot.matrix()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((r.model.tool().translation() - reflector.translation()).norm(), 1e-8);
  EXPECT_LT(r.after.max_abs_mm, 1e-8);
}

// Three reflector nests on one plate, read at every pose, in a far tracker frame: registration and
// calibration with the two further points located from starts 3 mm off. Every point is predicted at
// new poses to 1e-6 mm (the flange's orientation is determined), where a calibration from the
// tool point alone, the others carried rigidly from their true offsets, misses them by far more.
TEST(Calibration, SeveralFlangePointsLocateThemselvesAndFixTheFlangeOrientation) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model(nominal, 31).with_base(to_isometry({2400, -350, 150, 0.4, -0.2, 177}));
  const std::vector<Eigen::Vector3d> offsets = {{150.0, 20.0, 60.0}, {-40.0, 140.0, 90.0}};
  auto at_point = [](const MdhModel& m, const Eigen::Vector3d& p) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() = p;
    return m.with_tool(t);
  };
  std::vector<PositionMeasurement> data;
  for (const auto& q : random_configurations(nominal, 40, 32)) {
    data.push_back({q, forward_position(truth, q), 0});
    for (int k = 1; k <= 2; ++k)
      data.push_back({q, forward_position(at_point(truth, offsets[static_cast<std::size_t>(k - 1)]), q), k});
  }
  const std::vector<Eigen::Vector3d> start = {offsets[0] + Eigen::Vector3d(3, -2, 1), offsets[1] + Eigen::Vector3d(-1, 2, -3)};
  CalibrationOptions o;
  const CalibrationResult reg = register_tracker(nominal, data, start, o);
  ASSERT_TRUE(reg.converged) << reg.report();
  std::vector<Eigen::Vector3d> located;
  for (const auto& p : reg.flange_points) located.push_back(p.position_mm);
  ASSERT_EQ(located.size(), 2u);
  const CalibrationResult r = calibrate_positions(reg.model, data, located, o);
  ASSERT_TRUE(r.converged) << r.report();
  EXPECT_LT(r.after.max_abs_mm, 1e-7) << r.report();
  ASSERT_EQ(r.flange_points.size(), 2u);
  EXPECT_NE(r.report().find("flange point 2 (flange frame, mm)"), std::string::npos);
  // Single-point calibration of the same poses, the other points carried by their true offsets.
  std::vector<PositionMeasurement> tool_only;
  for (const auto& d : data)
    if (d.flange_point == 0) tool_only.push_back(d);
  const CalibrationResult single = calibrate_positions(register_tracker(nominal, tool_only, o).model, tool_only, o);
  double worst_multi = 0.0, worst_single = 0.0;
  for (const auto& q : random_configurations(nominal, 30, 33)) {
    EXPECT_LT((forward_position(r.model, q) - forward_position(truth, q)).norm(), 1e-6);
    for (std::size_t k = 0; k < 2; ++k) {
      const Eigen::Vector3d want = forward_position(at_point(truth, offsets[k]), q);
      worst_multi = std::max(worst_multi, (forward_position(at_point(r.model, r.flange_points[k].position_mm), q) - want).norm());
      worst_single = std::max(worst_single, (forward_position(at_point(single.model, offsets[k]), q) - want).norm());
    }
  }
  EXPECT_LT(worst_multi, 1e-6) << r.report();
  EXPECT_GT(worst_single, 0.05) << single.report();
  // A measurement naming a point that was not given is refused.
  std::vector<PositionMeasurement> bad = data;
  bad.back().flange_point = 3;
  EXPECT_THROW(calibrate_positions(reg.model, bad, located, o), ArgumentError);
}

// With tracker-like noise and 5% gross outliers, IGG3 reweighting recovers the robot better than
// plain least squares (prediction error against the truth at new configurations).
TEST(Calibration, Igg3BeatsPlainLeastSquaresWithOutliers) {
  const MdhModel nominal = nominal_model();
  const MdhModel truth = true_model(nominal, 9);
  const auto bases = random_configurations(nominal, 3, 10);
  SimulationRng rng(11);
  std::vector<DistanceMeasurement> data;
  std::size_t outliers = 0;
  for (const auto& q : random_configurations(nominal, 100, 12))
    for (const auto& b : bases) {
      double d = (forward_position(truth, q) - forward_position(truth, b)).norm() + rng.normal(0, 0.01);
      if (rng.uniform01() < 0.05) {
        d += (rng.uniform01() < 0.5 ? -1 : 1) * rng.uniform(0.5, 2.0);  // a gross error (wrong target, beam break)
        ++outliers;
      }
      data.push_back({q, b, d});
    }
  ASSERT_GT(outliers, 5u);
  CalibrationOptions plain;
  plain.robust.enabled = false;
  const CalibrationResult ls = calibrate_distances(nominal, data, plain);
  CalibrationOptions igg3;
  igg3.robust.enabled = true;
  const CalibrationResult robust = calibrate_distances(nominal, data, igg3);
  auto prediction_rms = [&](const MdhModel& m) {
    const auto test = random_configurations(nominal, 60, 13);
    double s = 0;
    for (std::size_t i = 0; i + 1 < test.size(); ++i) {
      const double want = (forward_position(truth, test[i]) - forward_position(truth, test[i + 1])).norm();
      const double got = (forward_position(m, test[i]) - forward_position(m, test[i + 1])).norm();
      s += (got - want) * (got - want);
    }
    return std::sqrt(s / static_cast<double>(test.size() - 1));
  };
  const double e_ls = prediction_rms(ls.model), e_robust = prediction_rms(robust.model);
  EXPECT_LT(e_robust, 0.5 * e_ls) << "IGG3 " << e_robust << " mm vs LS " << e_ls << " mm\n" << robust.report();
  EXPECT_LT(e_robust, 0.02);  // near the 0.01 mm noise level
  EXPECT_GE(robust.rejected, outliers * 8 / 10);
  EXPECT_TRUE(robust.converged) << robust.report();
  EXPECT_LT(robust.weight_change, 1e-3);

  // One reweighting round cannot settle weights that must first find the outliers: the result is
  // reported as not converged, with the reason, instead of "converged".
  CalibrationOptions one_round = igg3;
  one_round.robust.max_rounds = 1;
  const CalibrationResult cut = calibrate_distances(nominal, data, one_round);
  EXPECT_FALSE(cut.converged);
  EXPECT_EQ(cut.rounds, 1);
  EXPECT_GE(cut.weight_change, 1e-3);
  EXPECT_NE(cut.message.find("IGG3 weights still changing after 1 weighting rounds"), std::string::npos)
      << cut.message;
  EXPECT_NE(cut.report().find(cut.message), std::string::npos);
}

TEST(Calibration, CompensatedJointsPutTheIdentifiedToolOnTarget) {
  const MdhModel nominal = nominal_model();
  const MdhModel identified = true_model(nominal, 14);
  const MeasurementCube cube = paper_cube();
  const IkResult seed = cube_seed(nominal, cube);
  ASSERT_TRUE(seed.ok());
  SimulationRng rng(15);
  for (const auto& p : cube.random_per_cell(250, rng)) {
    const IkResult r = compensated_joints(nominal, identified, cube.pose(p), seed.q_deg);
    ASSERT_TRUE(r.ok()) << to_string(r.status);
    EXPECT_LT((forward_position(identified, r.q_deg) - p).norm(), 1e-6);
    // Orientation as the controller (nominal model) knows it is the target's.
    EXPECT_LT(rotation_log(forward_kinematics(nominal, r.q_deg).linear() * cube.orientation.transpose()).norm(), 1e-9);
  }
}

TEST(Calibration, BadOptionsAndTooFewData) {
  CalibrationOptions o;
  o.robust.k1 = 1.0;
  EXPECT_THROW(o.validate(), ArgumentError);
  o = {};
  o.candidates = {99};
  EXPECT_THROW(o.validate(), ArgumentError);
  const MdhModel nominal = nominal_model();
  std::vector<PositionMeasurement> few{{JointVector::Zero(), Eigen::Vector3d::Zero()}};
  EXPECT_THROW(calibrate_positions(nominal, few), InputError);
  EXPECT_THROW(register_tracker(nominal, few), InputError);
}

}  // namespace
}  // namespace errfield::robot
