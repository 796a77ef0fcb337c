// Calibration from distances on robot geometries other than the ER20-C10 (issue 19, item 4): the
// parameters it identifies must be the ones the data support, so that its held-out 3-D accuracy
// matches an independent least-squares calibration written here (Gauss–Newton on every MD-H
// parameter and the tool, finite-difference Jacobian, truncated-SVD minimum-norm steps toward
// nominal). All data are SIMULATED: by errfield's simulator with MD-H deviations drawn here plus
// joint compliance and transmission error (cube_experiment), or by a purely geometric truth
// written in this file with Gaussian noise on each distance (joint_box_experiment).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numeric>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/random.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::robot {
namespace calibration_distance_geometry_test {

// A true arm: every MD-H parameter of the nominal one off by an assembly-sized amount (0.1 deg,
// 1 mm, 1-sigma), Hayati beta where consecutive axes are parallel, and the tool point off by 0.5 mm.
MdhModel true_arm(const MdhModel& nominal, std::uint64_t seed, double scale = 1.0) {
  SimulationRng rng(seed);
  auto links = nominal.links();
  for (std::size_t i = 0; i < links.size(); ++i) {
    links[i].alpha_deg += rng.normal(0, 0.1 * scale);
    links[i].a_mm += rng.normal(0, 1.0 * scale);
    links[i].theta0_deg += rng.normal(0, 0.1 * scale);
    links[i].d_mm += rng.normal(0, 1.0 * scale);
    if (i > 0 && std::abs(std::remainder(nominal.links()[i].alpha_deg, 180.0)) < 1e-9)
      links[i].beta_deg += rng.normal(0, 0.05 * scale);
  }
  Eigen::Isometry3d tool = nominal.tool();
  tool.translation() += Eigen::Vector3d(rng.normal(0, 0.5 * scale), rng.normal(0, 0.5 * scale), rng.normal(0, 0.5 * scale));
  return MdhModel("truth", links, nominal.base(), tool);
}

// Joints uniform in a box (deg), inside the nominal limits.
struct JointBox {
  JointVector lo, hi;
};

std::vector<JointVector> poses_in(const JointBox& box, std::size_t n, SimulationRng& rng) {
  std::vector<JointVector> q(n);
  for (auto& v : q)
    for (int j = 0; j < kJointCount; ++j) v[j] = rng.uniform(box.lo[j], box.hi[j]);
  return q;
}

// One calibration experiment: distances from base poses (robot positions, each measured once)
// to scattered poses, and held-out poses where the 3-D error is scored. `truth` gives where the
// arm really is at commanded joints.
struct Experiment {
  MdhModel nominal;
  std::function<Eigen::Vector3d(const JointVector&)> truth;
  std::vector<DistanceMeasurement> data;
  std::vector<JointVector> heldout;

  // Mean 3-D error of `model` at the held-out poses after the best rigid motion onto the truth
  // (distances fix a model only up to one; a tracker registration removes it in use).
  double heldout_mean_mm(const MdhModel& model) const {
    Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(heldout.size())), b(3, a.cols());
    for (std::size_t i = 0; i < heldout.size(); ++i) {
      a.col(static_cast<Eigen::Index>(i)) = forward_position(model, heldout[i]);
      b.col(static_cast<Eigen::Index>(i)) = truth(heldout[i]);
    }
    const Eigen::Matrix4d t = Eigen::umeyama(a, b, false);
    const Eigen::Matrix3Xd moved = (t.topLeftCorner<3, 3>() * a).colwise() + t.topRightCorner<3, 1>();
    return (moved - b).colwise().norm().mean();
  }

  double distance_rms_mm(const MdhModel& model) const {
    double sq = 0;
    for (const auto& d : data)
      sq += std::pow(d.distance_mm - (forward_position(model, d.q_a_deg) - forward_position(model, d.q_b_deg)).norm(), 2);
    return std::sqrt(sq / static_cast<double>(data.size()));
  }
};

// A purely geometric truth (true_arm) and joints uniform in a box; each distance gets Gaussian
// noise of `noise_mm`.
Experiment joint_box_experiment(const MdhModel& nominal, const JointBox& box, std::size_t poses, std::size_t bases,
                                double noise_mm, std::uint64_t seed) {
  const MdhModel arm = true_arm(nominal, seed);
  Experiment e{nominal, [arm](const JointVector& q) { return forward_position(arm, q); }, {}, {}};
  SimulationRng rng(seed * 7919 + 17);
  const std::vector<JointVector> b = poses_in(box, bases, rng);
  for (const auto& q : poses_in(box, poses, rng))
    for (const auto& qb : b)
      e.data.push_back({q, qb, (e.truth(q) - e.truth(qb)).norm() + rng.normal(0, noise_mm)});
  e.heldout = poses_in(box, 200, rng);
  return e;
}

// Poses as a tracker campaign takes them: positions uniform in the robot's built-in cube, the tool
// within `spread_deg` of tool-down (tilt and turn), solved by IK of `nominal` on the cube seed's
// branch.
std::vector<JointVector> cube_poses(const BuiltinRobot& robot, const MdhModel& nominal, double spread_deg,
                                    std::size_t n, SimulationRng& rng) {
  MeasurementCube cube;
  cube.min_corner_mm = robot.cube_min_mm;
  cube.size_mm = robot.cube_size_mm;
  cube.orientation = to_isometry({0, 0, 0, robot.cube_rpy_deg.x(), robot.cube_rpy_deg.y(), robot.cube_rpy_deg.z()}).linear();
  const IkResult centre = cube_seed(nominal, cube);
  EXPECT_TRUE(centre.ok()) << robot.name << ": the cube's centre is not reachable";
  constexpr double kRad = 3.14159265358979323846 / 180.0;
  std::vector<JointVector> q;
  for (std::size_t tries = 0; q.size() < n && centre.ok(); ++tries) {
    if (tries > 50 * n + 1000) {  // a cube mostly out of reach is a mistake in the geometry, not data
      ADD_FAILURE() << robot.name << ": only " << q.size() << " of " << tries << " cube poses reachable";
      break;
    }
    const double azimuth = rng.uniform(0, 2 * 3.14159265358979323846);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = cube.orientation *
                    Eigen::AngleAxisd(rng.uniform(0, spread_deg) * kRad,
                                      Eigen::Vector3d(std::cos(azimuth), std::sin(azimuth), 0)) *
                    Eigen::AngleAxisd(rng.uniform(-spread_deg, spread_deg) * kRad, Eigen::Vector3d::UnitZ());
    pose.translation() = cube.min_corner_mm + cube.size_mm * Eigen::Vector3d(rng.uniform01(), rng.uniform01(), rng.uniform01());
    const IkResult r = inverse_kinematics(nominal, pose, centre.q_deg);
    if (r.ok() && (r.q_deg - centre.q_deg).cwiseAbs().maxCoeff() < 120.0) q.push_back(r.q_deg);
  }
  return q;
}

// Poses in the robot's cube (cube_poses). The truth is errfield's simulator (SIMULATED) with the
// MD-H deviations of true_arm's size drawn here, plus what a kinematic model cannot express: the
// paper set-up's joint compliance under gravity and cyclic transmission error; repeatability and
// tracker noise on every reading.
Experiment cube_experiment(const BuiltinRobot& robot, const Eigen::Isometry3d& tool, double spread_deg,
                           std::size_t poses, std::size_t bases, std::uint64_t seed) {
  SimulatorConfig config = SimulatorConfig::paper_default();
  config.nominal = robot.model.with_tool(tool);
  SimulationRng rng(seed * 7919 + 29);
  for (int i = 0; i < kJointCount; ++i) {
    const bool parallel = i > 0 && std::abs(std::remainder(robot.model.link(i).alpha_deg, 180.0)) < 1e-9;
    config.geometry.link[static_cast<std::size_t>(i)] = {rng.normal(0, 0.1), rng.normal(0, 1.0), rng.normal(0, 0.1),
                                                         rng.normal(0, 1.0), parallel ? rng.normal(0, 0.05) : 0.0};
  }
  config.geometry.tool = {rng.normal(0, 0.5), rng.normal(0, 0.5), rng.normal(0, 0.5), 0, 0, 0};
  const auto sim = std::make_shared<SimulatedRobot>(config);
  Experiment e{config.nominal, [sim](const JointVector& q) { return sim->true_position(q); }, {}, {}};
  std::vector<Eigen::Vector3d> base_reading;
  const std::vector<JointVector> b = cube_poses(robot, config.nominal, spread_deg, bases, rng);
  for (const auto& qb : b) base_reading.push_back(sim->measure(sim->move(qb, rng), rng));
  for (const auto& q : cube_poses(robot, config.nominal, spread_deg, poses, rng)) {
    const Eigen::Vector3d reading = sim->measure(sim->move(q, rng), rng);
    for (std::size_t k = 0; k < b.size(); ++k) e.data.push_back({q, b[k], (reading - base_reading[k]).norm()});
  }
  e.heldout = cube_poses(robot, config.nominal, spread_deg, 200, rng);
  return e;
}

// The same campaign on a purely geometric truth (true_arm), as a simulator written outside errfield
// would make it: nothing but MD-H and tool deviations, Gaussian noise of `noise_mm` on each distance.
Experiment geometric_cube_experiment(const BuiltinRobot& robot, const Eigen::Isometry3d& tool, double spread_deg,
                                     std::size_t poses, std::size_t bases, double noise_mm, std::uint64_t seed,
                                     double deviation_scale = 1.0) {
  const MdhModel nominal = robot.model.with_tool(tool);
  const MdhModel arm = true_arm(nominal, seed, deviation_scale);
  Experiment e{nominal, [arm](const JointVector& q) { return forward_position(arm, q); }, {}, {}};
  SimulationRng rng(seed * 7919 + 31);
  const std::vector<JointVector> b = cube_poses(robot, nominal, spread_deg, bases, rng);
  for (const auto& q : cube_poses(robot, nominal, spread_deg, poses, rng))
    for (const auto& qb : b) e.data.push_back({q, qb, (e.truth(q) - e.truth(qb)).norm() + rng.normal(0, noise_mm)});
  e.heldout = cube_poses(robot, nominal, spread_deg, 200, rng);
  return e;
}

// The joints as a controller log records them: rounded to multiples of `step_deg` (0.01, 0.001).
// The arm went where the exact joints put it; calibration sees only the rounded ones.
Experiment with_joints_rounded(Experiment e, double step_deg) {
  auto round = [step_deg](JointVector q) {
    for (int j = 0; j < kJointCount; ++j) q[j] = std::round(q[j] / step_deg) * step_deg;
    return q;
  };
  for (auto& d : e.data) {
    d.q_a_deg = round(d.q_a_deg);
    d.q_b_deg = round(d.q_b_deg);
  }
  return e;
}

// ---- the independent least-squares reference ----------------------------------------------------

// Parameters: per link alpha, a, theta0, d (and beta where the axes are parallel), then the tool
// x, y, z. Angles are carried as rad × 1000 mm (1 mrad ~ 1 mm at a metre), lengths in mm, so a
// minimum-norm step treats a milliradian like a millimetre.
struct ReferenceParameters {
  explicit ReferenceParameters(const MdhModel& m) : nominal(m) {
    for (int i = 0; i < kJointCount; ++i) {
      for (int f = 0; f < 4; ++f) fields.push_back({i, f});
      if (i > 0 && std::abs(std::remainder(m.link(i).alpha_deg, 180.0)) < 1e-9) fields.push_back({i, 4});
    }
    for (int c = 0; c < 3; ++c) fields.push_back({-1, c});
  }
  Eigen::Index size() const { return static_cast<Eigen::Index>(fields.size()); }

  MdhModel model(const Eigen::VectorXd& x) const {
    constexpr double kLever = 1000.0;
    const double deg = 180.0 / 3.14159265358979323846 / kLever;  // deg per (rad × lever) unit
    auto links = nominal.links();
    Eigen::Isometry3d tool = nominal.tool();
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const double v = x[static_cast<Eigen::Index>(k)];
      const auto [i, f] = fields[k];
      if (i < 0) {
        tool.translation()[f] += v;
        continue;
      }
      MdhLink& l = links[static_cast<std::size_t>(i)];
      if (f == 0) l.alpha_deg += v * deg;
      if (f == 1) l.a_mm += v;
      if (f == 2) l.theta0_deg += v * deg;
      if (f == 3) l.d_mm += v;
      if (f == 4) l.beta_deg += v * deg;
    }
    return MdhModel("reference", links, nominal.base(), tool);
  }

  MdhModel nominal;
  std::vector<std::pair<int, int>> fields;  // (link or -1 for the tool, field)
};

Eigen::VectorXd predicted_distances(const MdhModel& m, const std::vector<DistanceMeasurement>& data) {
  Eigen::VectorXd p(static_cast<Eigen::Index>(data.size()));
  for (std::size_t i = 0; i < data.size(); ++i)
    p[static_cast<Eigen::Index>(i)] = (forward_position(m, data[i].q_a_deg) - forward_position(m, data[i].q_b_deg)).norm();
  return p;
}

// Gauss–Newton from nominal; each step is the truncated-SVD (minimum-norm) solution of the
// linearised problem, keeping the singular directions above `rcond` × the largest, so directions
// the data cannot see stay at nominal. Central differences of 1e-3 units (µm, µrad × 1000).
MdhModel reference_calibration(const MdhModel& nominal, const std::vector<DistanceMeasurement>& data, double rcond,
                               const std::vector<std::pair<int, int>>& only = {}) {
  ReferenceParameters par(nominal);
  if (!only.empty()) par.fields = only;
  Eigen::VectorXd measured(static_cast<Eigen::Index>(data.size()));
  for (std::size_t i = 0; i < data.size(); ++i) measured[static_cast<Eigen::Index>(i)] = data[i].distance_mm;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(par.size());
  for (int it = 0; it < 15; ++it) {
    const Eigen::VectorXd r = measured - predicted_distances(par.model(x), data);
    Eigen::MatrixXd j(r.size(), par.size());
    for (Eigen::Index k = 0; k < par.size(); ++k) {
      constexpr double h = 1e-3;
      Eigen::VectorXd xp = x, xm = x;
      xp[k] += h;
      xm[k] -= h;
      j.col(k) = (predicted_distances(par.model(xp), data) - predicted_distances(par.model(xm), data)) / (2 * h);
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(j, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd s = svd.singularValues();
    Eigen::VectorXd step = Eigen::VectorXd::Zero(par.size());
    for (Eigen::Index k = 0; k < s.size(); ++k)
      if (s[k] > rcond * s[0]) step += svd.matrixV().col(k) * (svd.matrixU().col(k).dot(r) / s[k]);
    x += step;
    if (step.norm() < 1e-7) break;
  }
  return par.model(x);
}

// ---- geometries ---------------------------------------------------------------------------------

// KR 16: the region a tracker sees in front of the arm (`errfield simulate --robot kr16` example box).
JointBox kr16_box() {
  JointBox b;
  b.lo << -150, -130, 70, -90, -110, -180;
  b.hi << 150, -30, 150, 90, 110, 180;
  return b;
}

// A KR 16-class arm that is none of the built-ins, as an outside simulator's arm would be: the
// KR 16's structure (shoulder offset, upper arm, forearm with elbow offset, spherical wrist) with
// every length changed by tens of percent, a lateral offset at the elbow (link3.d, which the
// built-ins lack), a base-frame offset (link1.a) and a narrower wrist range. Seeded so a study
// can draw several; seed 0 is the one the CI test uses. Its cube is where the KR 16's is, scaled
// with the arm's reach, at tool-down.
BuiltinRobot generated_kr16_class(std::uint64_t seed) {
  SimulationRng rng(seed + 4001);
  auto scaled = [&](double v, double lo, double hi) { return v * rng.uniform(lo, hi); };
  const double base_height = scaled(675, 0.8, 0.9);  // 540-608
  const double shoulder = scaled(260, 1.2, 1.35);     // 312-351
  const double upper_arm = scaled(680, 0.8, 0.9);     // 544-612
  const double elbow = scaled(35, 1.8, 2.6);          // 63-91
  const double forearm = scaled(670, 1.15, 1.25);     // 770-838
  const double flange = scaled(158, 0.7, 0.8);        // 111-126
  const double lateral = scaled(40, 0.8, 1.2);        // 32-48
  const double base_offset = scaled(25, 0.8, 1.2);    // 20-30
  const std::array<MdhLink, kJointCount> links{{
      {0.0, base_offset, 0.0, base_height, 0.0, -170.0, 170.0},
      {-90.0, shoulder, 0.0, 0.0, 0.0, -150.0, 30.0},
      {0.0, upper_arm, -90.0, lateral, 0.0, -120.0, 150.0},
      {-90.0, elbow, 0.0, forearm, 0.0, -350.0, 350.0},
      {90.0, 0.0, 0.0, 0.0, 0.0, -120.0, 120.0},
      {-90.0, 0.0, 0.0, flange, 0.0, -350.0, 350.0},
  }};
  const BuiltinRobot& kr = *find_builtin_robot("kr16");
  const double reach = shoulder + upper_arm + std::hypot(elbow, forearm);
  const double s = reach / (260.0 + 680.0 + std::hypot(35.0, 670.0));
  return {"kr16-class-" + std::to_string(seed), "generated KR 16-class arm", "calibration_distance_geometry_test",
          MdhModel("KR16-class", links), Eigen::Vector3d(kr.cube_min_mm.x() * s, kr.cube_min_mm.y() * s, kr.cube_min_mm.z()),
          kr.cube_size_mm * s, kr.cube_rpy_deg};
}

JointBox er20_box() {
  JointBox b;
  b.lo << -60, -140, -60, -90, -100, -90;
  b.hi << 60, -60, 30, 90, -20, 90;
  return b;
}

CalibrationOptions plain() {
  CalibrationOptions o;
  o.robust.enabled = false;
  return o;
}

// Held-out 3-D mean (mm) of errfield's distance calibration and of the reference (rcond 1e-3,
// the default cap's), summed over seeds.
struct Scores {
  double errfield = 0, reference = 0, nominal = 0, worst_ratio = 0;
  int seeds = 0;
};

Scores compare(const std::function<Experiment(std::uint64_t)>& make, int first_seed, int seeds,
               const char* print_label = nullptr) {
  Scores s;
  for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
    const Experiment e = make(static_cast<std::uint64_t>(seed));
    const MdhModel ref = reference_calibration(e.nominal, e.data, 1e-3);
    const CalibrationResult r = calibrate_distances(e.nominal, e.data, plain());
    EXPECT_TRUE(r.converged) << r.report();
    const double hr = e.heldout_mean_mm(ref), he = e.heldout_mean_mm(r.model), hn = e.heldout_mean_mm(e.nominal);
    s.reference += hr;
    s.errfield += he;
    s.nominal += hn;
    s.worst_ratio = std::max(s.worst_ratio, he / hr);
    ++s.seeds;
    if (print_label)
      std::printf("%s seed %d: held-out 3-D mean nominal %.3f reference %.3f errfield %.3f (%.2fx); distance RMS "
                  "%.4f / %.4f mm\n",
                  print_label, seed, hn, hr, he, he / hr, e.distance_rms_mm(ref), e.distance_rms_mm(r.model));
  }
  if (print_label)
    std::printf("%s MEAN over %d seeds: nominal %.3f reference %.3f errfield %.3f, ratio %.3f, worst seed %.2fx\n",
                print_label, s.seeds, s.nominal / s.seeds, s.reference / s.seeds, s.errfield / s.seeds,
                s.errfield / s.reference, s.worst_ratio);
  return s;
}

const Eigen::Isometry3d kTool(Eigen::Translation3d(0, 0, 120));

// The case: a KR 16 measured at one constant tool orientation in its cube, distances from
// one base pose, 120 poses, joint compliance and transmission error the model cannot express.
// Removing weakly identifiable parameters one at a time (the former selection) kept a subset that
// had to absorb what the removed ones carried: link4.a moved by 35 mm, the distances fitted twice
// as badly as the reference, held-out 3-D error 1.14x the reference over seeds 1-10 (1.83x on
// seed 9).
TEST(CalibrationDistanceGeometry, Kr16AtOneOrientationMatchesLeastSquares) {
  const BuiltinRobot& kr16_arm = *find_builtin_robot("kr16");
  const Scores s = compare([&](std::uint64_t seed) { return cube_experiment(kr16_arm, kTool, 0.0, 120, 1, seed); }, 1, 10);
  ASSERT_LT(s.reference, 0.5 * s.nominal);  // the reference calibrates: the comparison means something
  EXPECT_LE(s.errfield, 1.10 * s.reference);
  EXPECT_LE(s.worst_ratio, 1.2);
}

// Well-spread orientations and a second arm (UR5e), and the built-in ER20-C10: no worse.
TEST(CalibrationDistanceGeometry, OtherArmsAndOrientationsMatchLeastSquares) {
  for (const char* name : {"ur5e", "er20-c10"})
    for (double spread : {0.0, 30.0}) {
      SCOPED_TRACE(std::string(name) + ", orientation spread " + std::to_string(spread) + " deg");
      const BuiltinRobot& arm = *find_builtin_robot(name);
      const Scores s = compare([&](std::uint64_t seed) { return cube_experiment(arm, kTool, spread, 120, 1, seed); }, 1, 4);
      ASSERT_LT(s.reference, 0.6 * s.nominal);
      EXPECT_LE(s.errfield, 1.10 * s.reference);
    }
}

// Issue 35 item 7: a KR 16-class arm none of the built-ins is (generated_kr16_class(0): other link
// lengths, an elbow offset, a lateral offset at the elbow), at one orientation from one base pose,
// on errfield's simulator and on a purely geometric truth off by three times true_arm's deviations
// (0.3 deg / 3 mm, 0.03 mm noise). There a weak parameter removed at nominal (link4.alpha, 47 %
// determined; at 0.01 mm noise on seed 5 link4.a then moved by -79 mm) and the fixed Tikhonov
// weight held real deviations back: errfield was 3.5x the reference over seeds 1-10 (18x on the
// worst seed) before the F tests of solve_calibration (docs/robot.md).
TEST(CalibrationDistanceGeometry, GeneratedKr16ClassMatchesLeastSquares) {
  const BuiltinRobot arm = generated_kr16_class(0);
  const Scores sim = compare([&](std::uint64_t seed) { return cube_experiment(arm, kTool, 0.0, 120, 1, seed); }, 1, 10);
  ASSERT_LT(sim.reference, 0.5 * sim.nominal);
  EXPECT_LE(sim.errfield, 1.10 * sim.reference);
  EXPECT_LE(sim.worst_ratio, 1.2);
  const Scores off = compare(
      [&](std::uint64_t seed) { return geometric_cube_experiment(arm, kTool, 0.0, 120, 1, 0.03, seed, 3.0); }, 1, 10);
  ASSERT_LT(off.reference, 0.1 * off.nominal);
  EXPECT_LE(off.errfield, 1.10 * off.reference);
  EXPECT_LE(off.worst_ratio, 2.0);  // measured 1.44 (1.55 before reselect_at_solution), against 18x before
}

// Issue 47 item 15: an arm off by five times true_arm's deviations (0.5 deg / 5 mm, the tool 2.5 mm)
// measured to 0.01 mm. At one tool orientation several wrist parameters are exact combinations of
// others at nominal and were removed for good; at the real arm they are not, and the fit left four
// times the noise on the distances (held-out 3.0x the reference over seeds 1-10, 14x on seed 6).
// They are chosen again at the fitted model (reselect_at_solution). And where the data hold what
// no parameter expresses, that reselection must not run away: the built-in ER20-C10 at one
// orientation on errfield's simulator (joint compliance) moved its tool by 288 mm on seed 5
// (11x the reference) until the move was bounded.
TEST(CalibrationDistanceGeometry, ParametersRedundantOnlyAtNominalAreFittedWhenTheDataAskForThem) {
  const BuiltinRobot arm = generated_kr16_class(0);
  const Scores x5 = compare(
      [&](std::uint64_t seed) { return geometric_cube_experiment(arm, kTool, 0.0, 120, 1, 0.01, seed, 5.0); }, 1, 10);
  ASSERT_LT(x5.reference, 0.01 * x5.nominal);
  EXPECT_LE(x5.errfield, 1.10 * x5.reference);  // measured 1.04
  EXPECT_LE(x5.worst_ratio, 1.6);               // measured 1.39
  const Scores x3 = compare(
      [&](std::uint64_t seed) { return geometric_cube_experiment(arm, kTool, 0.0, 120, 1, 0.01, seed, 3.0); }, 1, 10);
  EXPECT_LE(x3.errfield, 1.10 * x3.reference);  // measured 1.035, 1.46 before
  // At 0.03 mm the F statistic of the four parameters the reselection adds is small: the test at
  // the 0.01 % level (6.0 for four) takes them where a flat 10 per parameter did not.
  const Scores x3_noisier = compare(
      [&](std::uint64_t seed) { return geometric_cube_experiment(arm, kTool, 0.0, 120, 1, 0.03, seed, 3.0); }, 1, 10);
  EXPECT_LE(x3_noisier.errfield, 1.05 * x3_noisier.reference);  // measured 1.010; 1.095 at a flat 10
  const BuiltinRobot& er20 = *find_builtin_robot("er20-c10");
  const Scores sim = compare([&](std::uint64_t seed) { return cube_experiment(er20, kTool, 0.0, 120, 1, seed); }, 1, 10);
  EXPECT_LE(sim.errfield, 1.10 * sim.reference);  // measured 1.006; 2.15 with the move unbounded
  EXPECT_LE(sim.worst_ratio, 1.2);                // measured 1.12; 11.45 unbounded
}

// ---- the study ----------------------------------------------------------------------------------

// The figures in docs/robot.md ("Distances: regularized toward nominal"): every arm, one or 30 deg
// of orientation spread, 1 or 3 base poses, 10 seeds each; and purely geometric truths over a
// joint box. Run: build/tests/robot_tests --gtest_filter='CalibrationDistanceGeometryStudy.*'
TEST(CalibrationDistanceGeometryStudy, ErrfieldAgainstTheReference) {
  for (const char* name : {"kr16", "er20-c10", "ur5e"}) {
    const BuiltinRobot& robot = *find_builtin_robot(name);
    for (double spread : {0.0, 30.0})
      for (std::size_t bases : {1, 3}) {
        const std::string label = std::string(name) + ", cube, orientation spread " + std::to_string(int(spread)) +
                                  " deg, " + std::to_string(bases) + " base pose(s)";
        const Scores s = compare([&](std::uint64_t seed) { return cube_experiment(robot, kTool, spread, 120, bases, seed); },
                                 1, 10, label.c_str());
        EXPECT_LE(s.errfield, 1.10 * s.reference) << label;
      }
  }
  const Scores k = compare([](std::uint64_t seed) { return joint_box_experiment(kr16().with_tool(kTool), kr16_box(), 120, 1, 0.03, seed); },
                           1, 10, "kr16, joint box, geometric truth");
  EXPECT_LE(k.errfield, 1.10 * k.reference);
  const Scores e = compare([](std::uint64_t seed) { return joint_box_experiment(MdhModel::er20_c10().with_tool(kTool), er20_box(), 120, 1, 0.03, seed); },
                           1, 10, "er20-c10, joint box, geometric truth");
  EXPECT_LE(e.errfield, 1.10 * e.reference);
}

// Issue 35 item 7: a KR 16-class arm none of the tests use (generated_kr16_class), and what a
// simulator written outside errfield may do differently: a purely geometric truth, distance noise
// from 0.01 to 0.1 mm, joints recorded to 0.01 or 0.001 deg, 60 poses, 1 to 5 base poses, one
// orientation or 30 deg of spread, deviations 3 and 5 times true_arm's; and two more generated
// arms. 10 seeds each; the figures are in docs/robot.md ("Distances: regularized toward nominal").
// Within 10 % of the reference asserted at true_arm's deviations; the larger ones are what is left.
// Run: build/tests/robot_tests --gtest_filter='CalibrationDistanceGeometryStudy.GeneratedKr16Class'
TEST(CalibrationDistanceGeometryStudy, GeneratedKr16Class) {
  struct Variant {
    std::string label;
    std::function<Experiment(const BuiltinRobot&, std::uint64_t)> make;
    bool asserted = true;
  };
  auto sim = [](double spread, std::size_t poses, std::size_t bases, double round_deg) {
    return [=](const BuiltinRobot& arm, std::uint64_t seed) {
      Experiment e = cube_experiment(arm, kTool, spread, poses, bases, seed);
      return round_deg > 0 ? with_joints_rounded(std::move(e), round_deg) : e;
    };
  };
  auto geo = [](double spread, std::size_t poses, std::size_t bases, double noise, double round_deg,
                double deviation = 1.0) {
    return [=](const BuiltinRobot& arm, std::uint64_t seed) {
      Experiment e = geometric_cube_experiment(arm, kTool, spread, poses, bases, noise, seed, deviation);
      return round_deg > 0 ? with_joints_rounded(std::move(e), round_deg) : e;
    };
  };
  const std::vector<Variant> variants{
      {"simulator, 0 deg, 120 poses, 1 base", sim(0, 120, 1, 0)},
      {"simulator, 0 deg, 120 poses, 3 bases", sim(0, 120, 3, 0)},
      {"simulator, 0 deg, 120 poses, 5 bases", sim(0, 120, 5, 0)},
      {"simulator, 30 deg, 120 poses, 1 base", sim(30, 120, 1, 0)},
      {"simulator, 0 deg, 60 poses, 1 base", sim(0, 60, 1, 0)},
      {"simulator, 0 deg, 120 poses, 1 base, joints to 0.01 deg", sim(0, 120, 1, 0.01)},
      {"simulator, 0 deg, 120 poses, 1 base, joints to 0.001 deg", sim(0, 120, 1, 0.001)},
      {"simulator, 0 deg, 60 poses, 1 base, joints to 0.01 deg", sim(0, 60, 1, 0.01)},
      {"geometric, 0 deg, 120 poses, 1 base, 0.01 mm", geo(0, 120, 1, 0.01, 0)},
      {"geometric, 0 deg, 120 poses, 1 base, 0.03 mm", geo(0, 120, 1, 0.03, 0)},
      {"geometric, 0 deg, 120 poses, 1 base, 0.1 mm", geo(0, 120, 1, 0.1, 0)},
      {"geometric, 0 deg, 60 poses, 1 base, 0.03 mm", geo(0, 60, 1, 0.03, 0)},
      {"geometric, 0 deg, 120 poses, 3 bases, 0.03 mm", geo(0, 120, 3, 0.03, 0)},
      {"geometric, 30 deg, 120 poses, 1 base, 0.03 mm", geo(30, 120, 1, 0.03, 0)},
      {"geometric, 0 deg, 120 poses, 1 base, 0.03 mm, joints to 0.01 deg", geo(0, 120, 1, 0.03, 0.01)},
      {"geometric, 0 deg, 60 poses, 1 base, 0.03 mm, joints to 0.01 deg", geo(0, 60, 1, 0.03, 0.01)},
      {"geometric, 0 deg, 120 poses, 1 base, 0.03 mm, joints to 0.001 deg", geo(0, 120, 1, 0.03, 0.001)},
      {"geometric joint box, 120 poses, 1 base, 0.03 mm",
       [](const BuiltinRobot& arm, std::uint64_t seed) {
         return joint_box_experiment(arm.model.with_tool(kTool), kr16_box(), 120, 1, 0.03, seed);
       }},
      {"geometric x3, 0 deg, 120 poses, 1 base, 0.01 mm", geo(0, 120, 1, 0.01, 0, 3), false},
      {"geometric x3, 0 deg, 120 poses, 1 base, 0.03 mm", geo(0, 120, 1, 0.03, 0, 3), false},
      {"geometric x3, 0 deg, 60 poses, 1 base, 0.03 mm", geo(0, 60, 1, 0.03, 0, 3), false},
      {"geometric x3, 0 deg, 120 poses, 1 base, 0.03 mm, joints to 0.01 deg", geo(0, 120, 1, 0.03, 0.01, 3), false},
      {"geometric x5, 0 deg, 120 poses, 1 base, 0.01 mm", geo(0, 120, 1, 0.01, 0, 5), false},
      {"geometric x5, 0 deg, 60 poses, 1 base, 0.03 mm, joints to 0.01 deg", geo(0, 60, 1, 0.03, 0.01, 5), false},
  };
  for (std::uint64_t arm_seed : {0, 1, 2})
    for (const Variant& v : variants) {
      if (arm_seed > 0 && v.label.find("1 base") == std::string::npos) continue;
      const BuiltinRobot arm = generated_kr16_class(arm_seed);
      const std::string label = arm.name + ", " + v.label;
      const Scores s = compare([&](std::uint64_t seed) { return v.make(arm, seed); }, 1, 10, label.c_str());
      if (v.asserted) EXPECT_LE(s.errfield, 1.10 * s.reference) << label;
    }
}

}  // namespace calibration_distance_geometry_test
}  // namespace errfield::robot
