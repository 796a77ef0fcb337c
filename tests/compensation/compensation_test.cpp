#include "errfield/compensation/model/compensation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "errfield/error.hpp"
#include "errfield/compensation/model/error_fields.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/model/registration.hpp"
#include "errfield/compensation/tools/tool_location.hpp"
#include "errfield/variogram_model.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/simulator.hpp"

namespace errfield::compensation {
using namespace errfield::robot;
namespace compensation_test {

TEST(CompensationMethod, NamesRoundTrip) {
  for (auto m : all_methods()) EXPECT_EQ(method_from_name(method_name(m)), m);
  EXPECT_EQ(method_name(CompensationMethod::distance_idw), "distance-idw");
  EXPECT_EQ(method_name(CompensationMethod::kinematic_kriging), "kinematic+kriging");
  try {
    method_from_name("distance-IDW");
    FAIL() << "expected ArgumentError";
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("distance-idw"), std::string::npos) << e.what();
  }
}

TEST(ProbabilityWithin, GaussianClosedForm) {
  EXPECT_NEAR(probability_within(0.25, 0.25 * 0.25), 0.682689492137, 1e-10);      // ±1 sigma
  EXPECT_NEAR(probability_within(0.25, 0.125 * 0.125), 0.954499736104, 1e-10);    // ±2 sigma
  EXPECT_EQ(probability_within(0.25, 0.0), 1.0);
  EXPECT_TRUE(std::isnan(probability_within(0.25, NAN)));
}

// Eqs. 19-23 written out independently: 8 vertices, weights 1/d normalized, projection on m.
TEST(DistanceIdwField, MatchesThePapersFormulasByHand) {
  const RegularGrid3 grid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, 100, 100), {2, 2, 2});
  std::vector<double> dl(8);
  for (std::size_t n = 0; n < 8; ++n) dl[n] = 0.1 * static_cast<double>(n) - 0.3;
  const Eigen::Vector3d base(-500, 300, 1000);
  const auto field = make_distance_idw_field(grid, dl, base);
  const Eigen::Vector3d p(30, 70, 45);
  double wsum = 0, acc = 0;
  for (std::size_t n = 0; n < 8; ++n) {
    const double w = 1.0 / (p - grid.node_position(n)).norm();
    wsum += w;
    acc += w * dl[n];
  }
  const double expected_dl = acc / wsum;
  const Eigen::Vector3d m = (p - base) / (p - base).norm();
  const ErrorPrediction e = field->predict(p, JointVector::Zero());
  EXPECT_TRUE(e.inside_region);
  EXPECT_NEAR(e.distance_error_mm, expected_dl, 1e-14);
  EXPECT_LT((e.position_error_mm - expected_dl * m).norm(), 1e-14);
  EXPECT_TRUE(std::isnan(e.variance_mm2));
  // exact at a vertex
  EXPECT_DOUBLE_EQ(field->predict(grid.node_position(5), JointVector::Zero()).distance_error_mm, dl[5]);
  // outside: refused, nothing extrapolated
  const ErrorPrediction out = field->predict(Eigen::Vector3d(101, 50, 50), JointVector::Zero());
  EXPECT_FALSE(out.inside_region);
  EXPECT_EQ(out.position_error_mm, Eigen::Vector3d::Zero());
}

TEST(DistanceIdwField, RefusesTargetsAtTheBasePoint) {
  const RegularGrid3 grid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, 100, 100), {2, 2, 2});
  const auto field = make_distance_idw_field(grid, std::vector<double>(8, 0.1), Eigen::Vector3d(0, 0, 0));
  EXPECT_FALSE(field->predict(Eigen::Vector3d(0, 0, 0.5), JointVector::Zero()).inside_region);
  EXPECT_TRUE(field->predict(Eigen::Vector3d(50, 50, 50), JointVector::Zero()).inside_region);
}

struct CubeFixture : ::testing::Test {
  MdhModel nominal = SimulatorConfig::paper_default().nominal;
  MeasurementCube cube = paper_cube();
  JointVector seed = cube_seed(nominal, cube).q_deg;
  RegularGrid3 grid{cube.min_corner_mm, Eigen::Vector3d::Constant(250), {3, 3, 3}};
  JointVector joints_at(const Eigen::Vector3d& p) const {
    const IkResult r = solve_cube_pose(nominal, cube, p, seed);
    EXPECT_TRUE(r.ok());
    return r.q_deg;
  }
};

TEST_F(CubeFixture, CommandMovesAgainstThePredictedError) {
  const Eigen::Vector3d v(0.3, -0.2, 0.5);
  const CompensationModel model(CompensationMethod::position_idw, nominal,
                                make_position_idw_field(grid, std::vector<Eigen::Vector3d>(grid.node_count(), v)));
  const Eigen::Vector3d p = cube.center() + Eigen::Vector3d(60, -110, 35);
  const CompensatedTarget c = model.compensate_joints(nominal, joints_at(p));
  ASSERT_TRUE(c.ok());
  EXPECT_LT((c.prediction.position_error_mm - v).norm(), 1e-12);  // IDW reproduces a constant
  EXPECT_LT((c.command_position_mm - (p - v)).norm(), 1e-9);
  const Eigen::Isometry3d reached = forward_kinematics(nominal, c.q_command_deg);
  EXPECT_LT((reached.translation() - (p - v)).norm(), 1e-6);
  EXPECT_LT((reached.linear() - cube.orientation).norm(), 1e-8);  // orientation kept
  // the same through compensate() from the pose
  const CompensatedTarget c2 = model.compensate(nominal, cube.pose(p), seed);
  ASSERT_TRUE(c2.ok());
  EXPECT_LT((c2.q_command_deg - c.q_command_deg).norm(), 1e-6);
}

TEST_F(CubeFixture, KinematicModelSolvesOnItsOwnModel) {
  auto links = nominal.links();
  links[1].a_mm += 0.8;
  links[2].theta0_deg += 0.05;
  const MdhModel identified = nominal.with_links(links);
  const CompensationModel model(CompensationMethod::kinematic, identified, nullptr);
  const Eigen::Vector3d p = cube.center();
  const CompensatedTarget c = model.compensate_joints(nominal, joints_at(p));
  ASSERT_TRUE(c.ok());
  EXPECT_LT((forward_position(identified, c.q_command_deg) - p).norm(), 1e-6);
  EXPECT_GT((c.q_command_deg - c.q_nominal_deg).norm(), 1e-3);
}

TEST_F(CubeFixture, OutsideTargetsAreRefusedNotExtrapolated) {
  const CompensationModel model(
      CompensationMethod::position_idw, nominal,
      make_position_idw_field(grid, std::vector<Eigen::Vector3d>(grid.node_count(), Eigen::Vector3d(1, 0, 0))));
  const Eigen::Vector3d p = cube.min_corner_mm - Eigen::Vector3d(40, 0, 0);
  const CompensatedTarget c = model.compensate_joints(nominal, joints_at(p));
  EXPECT_FALSE(c.ok());
  EXPECT_FALSE(c.prediction.inside_region);
  EXPECT_EQ(c.q_command_deg, c.q_nominal_deg);
}

TEST_F(CubeFixture, JsonRoundTripPredictsTheSame) {
  std::vector<double> dl(grid.node_count());
  for (std::size_t n = 0; n < dl.size(); ++n) dl[n] = std::sin(0.7 * static_cast<double>(n));
  const CompensationModel model(CompensationMethod::distance_idw, nominal,
                                make_distance_idw_field(grid, dl, Eigen::Vector3d(-1500, 300, 200)));
  const CompensationModel back = CompensationModel::from_json(nlohmann::json::parse(model.to_json().dump()), "m.json");
  EXPECT_EQ(back.method(), CompensationMethod::distance_idw);
  const Eigen::Vector3d p = cube.center() + Eigen::Vector3d(12, 99, -140);
  const auto a = model.field()->predict(p, JointVector::Zero());
  const auto b = back.field()->predict(p, JointVector::Zero());
  EXPECT_DOUBLE_EQ(a.distance_error_mm, b.distance_error_mm);
  EXPECT_LT((a.position_error_mm - b.position_error_mm).norm(), 1e-15);
}

TEST(CompensationModelJson, BadInputNamesTheProblem) {
  auto expect_error = [](const nlohmann::json& j, const std::string& needle) {
    try {
      CompensationModel::from_json(j, "model.json");
      FAIL() << "expected InputError for " << j.dump();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("model.json"), std::string::npos) << e.what();
    }
  };
  expect_error(nlohmann::json::array(), "JSON object");
  expect_error({{"format", "other"}}, "format");
  nlohmann::json good = CompensationModel(CompensationMethod::none, MdhModel::er20_c10(), nullptr).to_json();
  nlohmann::json j = good;
  j["method"] = "magic";
  expect_error(j, "magic");
  j = good;
  j["field"] = {{"kind", "distance-idw"}, {"power", 1}, {"grid", {{"origin_mm", {0, 0, 0}}, {"step_mm", {1, 1, 1}}, {"counts", {2, 2, 2}}}},
                {"base_point_mm", {5, 5, 5}}, {"node_distance_error_mm", {1, 2, 3}}};
  expect_error(j, "node_distance_error_mm");
}

// A robot nested in a model: file() is the plain path (scripts and the fuzz contract rely on it),
// the member path is in the message and the column.
TEST(CompensationModelJson, NestedRobotErrorNamesFileAndMemberPath) {
  nlohmann::json j = CompensationModel(CompensationMethod::none, MdhModel::er20_c10(), nullptr).to_json();
  j["command_model"]["links"][2]["a_mm"] = "x";
  try {
    CompensationModel::from_json(j, "model.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "model.json");
    EXPECT_EQ(e.column(), "command_model.links[2].a_mm");
    EXPECT_EQ(std::string(e.what()).rfind("model.json: command_model.links[2].a_mm: expected a number", 0), 0u)
        << e.what();
  }
}


// ---- Tool points away from the measured reflector (issue 34) ----------------------------------

/// A kinematic+kriging model in joint space whose field holds `values` at joints `q` (reflector: the
/// paper's ball), with a registration the tests map readings through.
CompensationModel tool_point_model(const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& values) {
  const MdhModel robot = MdhModel::er20_c10().with_tool(paper_ball());
  FieldSamples samples;
  for (const JointVector& v : q) {
    samples.joints_deg.push_back(v);
    samples.position_mm.push_back(forward_position(robot, v));
  }
  KrigingFieldOptions o;
  o.space = FieldSpace::joint;
  o.model = VariogramModel::parse("gau(sill=0.01,range=60)+nug(0.0001)");
  o.region_margin_deg = 90.0;
  Registration reg;
  reg.robot_from_tracker = Eigen::Translation3d(1500, -200, 300) * Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized());
  reg.residual_rms_mm = 0.05;
  reg.points = q.size();
  return CompensationModel(CompensationMethod::kinematic_kriging, robot, make_vector_kriging_field(samples, values, o))
      .with_nominal_model(robot)
      .with_registration(reg);
}

std::vector<JointVector> joints_in_box(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-30.0, 30.0);
  std::vector<JointVector> q(n);
  for (auto& v : q)
    for (int k = 0; k < 6; ++k) v[k] = u(rng) + (k == 4 ? 45.0 : 0.0);
  return q;
}

Eigen::Isometry3d tool_at(const CompensationModel& m, const Eigen::Vector3d& p) {
  Eigen::Isometry3d t = m.command_model().tool();
  t.translation() = p;
  return t;
}

// The prior's reading of the residual, checked against the process it assumes: residuals made of
// independent wrist-angle errors of standard deviation s give a per-axis orientation variance of the
// flange, measured here over the same draws, of about s² (trace 3 s²): the prior must find it.
TEST(ToolPoints, OrientationPriorFindsTheFlangeRotationOfEqualWristAngleErrors) {
  const MdhModel robot = MdhModel::er20_c10().with_tool(paper_ball());
  const std::vector<JointVector> q = joints_in_box(300, 11);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> z;
  const double s = 1e-3;  // rad
  std::vector<Eigen::Vector3d> r;
  double w2 = 0.0;
  for (const JointVector& v : q) {
    Eigen::Matrix<double, 6, 1> dq;
    for (int k = 0; k < 6; ++k) dq[k] = k >= 3 ? s * z(rng) : 0.0;
    const Eigen::Matrix<double, 6, 6> j = geometric_jacobian(robot, v, EndFrame::tool);
    r.push_back(j.topRows<3>() * dq);
    w2 += (j.bottomRows<3>() * dq).squaredNorm();
  }
  const double per_axis = w2 / (3.0 * static_cast<double>(q.size()));  // measured
  const OrientationPrior p = tool_point_model(q, r).orientation_prior();
  ASSERT_TRUE(p.known());
  EXPECT_EQ(p.samples, q.size());
  // 900 residual numbers and 900 rotation numbers: a few % sampling error; 15 % is 3-4 of it.
  EXPECT_NEAR(p.data_sigma_rad * p.data_sigma_rad / per_axis, 1.0, 0.15);
  EXPECT_NEAR(p.sigma_rad * p.sigma_rad,
              p.data_sigma_rad * p.data_sigma_rad + kOrientationPriorFloorRad * kOrientationPriorFloorRad +
                  kUnlocatedOrientationRad * kUnlocatedOrientationRad,
              1e-18);
  EXPECT_NEAR(p.max_lever_mm, kMaxLeverResidualRatio * p.residual_rms_mm / (std::sqrt(2.0) * p.sigma_rad), 1e-9);
}

// Away from the reflector the variance grows by sigma² (|L|² I - L Lᵀ) per axis (checked against
// Monte Carlo of w x L, w ~ N(0, sigma² I)); beyond max_lever_mm the row is refused.
TEST(ToolPoints, LeverAddsTheRotationCovarianceAndIsRefusedBeyondTheSupportedLever) {
  const std::vector<JointVector> q = joints_in_box(40, 3);
  std::vector<Eigen::Vector3d> v;
  for (const JointVector& x : q) v.emplace_back(0.1 * std::sin(x[0] / 20), 0.05 * std::cos(x[1] / 15), 0.02 * x[2] / 30);
  const CompensationModel model = tool_point_model(q, v);
  const OrientationPrior& prior = model.orientation_prior();
  ASSERT_TRUE(prior.known());
  const JointVector at = (q[3] + q[4]) / 2;
  const Eigen::Vector3d lever_flange(120, -40, 30);
  const CompensationModel moved = model.with_working_tool(tool_at(model, model.measured_point_mm() + lever_flange));
  const ErrorPrediction a = model.predict_error(at), b = moved.predict_error(at);
  ASSERT_TRUE(a.inside_region && b.inside_region);
  EXPECT_EQ(a.orientation_variance_mm2, 0.0);
  // Monte Carlo of the projection
  const Eigen::Vector3d lever = forward_kinematics(model.command_model(), at, EndFrame::flange).linear() * lever_flange;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> z;
  Eigen::Vector3d mc = Eigen::Vector3d::Zero();
  const int draws = 200000;
  for (int i = 0; i < draws; ++i) {
    const Eigen::Vector3d w = prior.sigma_rad * Eigen::Vector3d(z(rng), z(rng), z(rng));
    mc += w.cross(lever).cwiseAbs2();
  }
  mc /= draws;
  const Eigen::Vector3d added = b.axis_variance_mm2 - a.axis_variance_mm2;
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(added[k] / mc[k], 1.0, 0.02) << k;  // MC error ~0.3 %
  EXPECT_NEAR(b.variance_mm2 - a.variance_mm2, 2.0 * prior.sigma_rad * prior.sigma_rad * lever_flange.squaredNorm(), 1e-12);
  EXPECT_NEAR(b.orientation_variance_mm2, b.variance_mm2 - a.variance_mm2, 1e-12);
  // the field's value is the same at any point of the flange
  EXPECT_NEAR((b.position_error_mm - a.position_error_mm).norm(), 0.0, 1e-12);
  // refused just beyond the supported lever, ok just inside it
  const Eigen::Vector3d dir = lever_flange.normalized();
  const auto at_lever = [&](double l) {
    return predict_position(model.with_working_tool(tool_at(model, model.measured_point_mm() + l * dir)), at).status;
  };
  EXPECT_EQ(at_lever(0.99 * prior.max_lever_mm), PredictionStatus::ok);
  EXPECT_EQ(at_lever(1.01 * prior.max_lever_mm), PredictionStatus::orientation_unknown);
  EXPECT_EQ(status_name(PredictionStatus::orientation_unknown), "orientation-unknown");
}

/// Fields (joint space, exact at their samples: no nugget) of the displacement a small rigid motion
/// (t_i, w_i) of the flange gives at `point` (flange frame) at each sample joint q_i.
std::shared_ptr<const ErrorField> rigid_motion_field(const MdhModel& robot, const std::vector<JointVector>& q,
                                                     const std::vector<Eigen::Vector3d>& t,
                                                     const std::vector<Eigen::Vector3d>& w, const Eigen::Vector3d& point) {
  FieldSamples samples;
  std::vector<Eigen::Vector3d> values;
  for (std::size_t i = 0; i < q.size(); ++i) {
    samples.joints_deg.push_back(q[i]);
    samples.position_mm.push_back(forward_position(robot, q[i]));
    const Eigen::Matrix3d r = forward_kinematics(robot, q[i], EndFrame::flange).linear();
    values.push_back(t[i] + w[i].cross(r * point));
  }
  KrigingFieldOptions o;
  o.space = FieldSpace::joint;
  o.model = VariogramModel::parse("exp(sill=0.01,range=60)");
  o.region_margin_deg = 90.0;
  return make_vector_kriging_field(samples, values, o);
}

// Several points with fields of their own: elsewhere the prediction is the flange's rigid motion
// their fields imply. At a sample joint the fields hold exactly t + w x (R p_j) for the motion drawn
// there, so with three points off one line a fourth point's prediction is that motion's value at it
// (the closed form below); with two points, the motion less its rotation about their line (which
// they cannot see), and the variance adds the prior's sigma² |u x (x - x1)|² for it.
TEST(ToolPoints, FieldsAtSeveralPointsPredictAnotherFromTheFlangesRigidMotion) {
  const Eigen::Vector3d p1(0, 0, 100), p2(150, 0, 100), p3(0, 150, 100), p4(60, 90, 40);
  const MdhModel nominal = MdhModel::er20_c10();
  Eigen::Isometry3d own = Eigen::Isometry3d::Identity();
  own.translation() = p1;
  const MdhModel robot = nominal.with_tool(own);
  const std::vector<JointVector> q = joints_in_box(30, 17);
  std::mt19937_64 rng(23);
  std::normal_distribution<double> z;
  std::vector<Eigen::Vector3d> t, w;
  for (std::size_t i = 0; i < q.size(); ++i) {
    t.emplace_back(0.05 * z(rng), 0.05 * z(rng), 0.05 * z(rng));
    w.emplace_back(1e-3 * z(rng), 1e-3 * z(rng), 1e-3 * z(rng));
  }
  const CompensationModel one(CompensationMethod::kinematic_kriging, robot, rigid_motion_field(robot, q, t, w, p1));
  const CompensationModel three = one.with_nominal_model(robot).with_flange_points(
      {{"a", p1, nullptr}, {"b", p2, rigid_motion_field(robot, q, t, w, p2)}, {"c", p3, rigid_motion_field(robot, q, t, w, p3)}});
  const CompensationModel two = one.with_nominal_model(robot).with_flange_points(
      {{"a", p1, nullptr}, {"b", p2, rigid_motion_field(robot, q, t, w, p2)}});
  auto at = [&](const Eigen::Vector3d& p) {
    Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
    tool.translation() = p;
    return robot.with_tool(tool);
  };
  const OrientationPrior& prior = two.orientation_prior();
  ASSERT_TRUE(prior.known());
  for (std::size_t i : {3u, 11u, 29u}) {
    const Eigen::Matrix3d r = forward_kinematics(robot, q[i], EndFrame::flange).linear();
    const Eigen::Vector3d x4 = r * p4, x1 = r * p1, u = (r * (p2 - p1)).normalized();
    const ErrorPrediction e3 = three.predict_error_at(q[i], at(p4));
    ASSERT_TRUE(e3.inside_region);
    EXPECT_LT((e3.position_error_mm - (t[i] + w[i].cross(x4))).norm(), 1e-6) << i;
    EXPECT_EQ(e3.orientation_variance_mm2, 0.0);
    // at a labelled point (within kSameFlangePointMm), that point's own field
    const ErrorPrediction at_b = three.predict_error_at(q[i], at(p2 + Eigen::Vector3d(0.3, 0, 0)));
    EXPECT_LT((at_b.position_error_mm - (t[i] + w[i].cross(r * p2))).norm(), 1e-6) << i;
    const ErrorPrediction e2 = two.predict_error_at(q[i], at(p4));
    const Eigen::Vector3d about_line = w[i].dot(u) * u.cross(x4 - x1);
    EXPECT_LT((e2.position_error_mm - (t[i] + w[i].cross(x4) - about_line)).norm(), 1e-6) << i;
    const Eigen::Vector3d moved = u.cross(x4 - x1);
    const double s2 = prior.sigma_rad * prior.sigma_rad;
    EXPECT_NEAR(e2.orientation_variance_mm2, s2 * moved.squaredNorm(), 1e-9 * s2 * moved.squaredNorm());
    // the fields are exact here (no nugget): the variance is the unobservable rotation's alone
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(e2.axis_variance_mm2[k], s2 * moved[k] * moved[k], 1e-9) << i << " " << k;
  }
  // Away from the samples the fields' variances combine: never below the largest share of one.
  const JointVector between = (q[3] + q[4]) / 2;
  const ErrorPrediction e = three.predict_error_at(between, at(p4));
  ASSERT_TRUE(e.inside_region && std::isfinite(e.variance_mm2));
  EXPECT_GT(e.variance_mm2, 0.0);
}

// Readings the model itself predicts at a point are located back to that point exactly: the field's
// translation and the joint functions' displacement and rotation of the flange enter locate_tool as
// they enter the prediction (a second, independent path: the functions through the Jacobian at the point).
TEST(ToolPoints, LocateToolRecoversThePointTheModelPredicts) {
  const std::vector<JointVector> q = joints_in_box(40, 4);
  std::vector<Eigen::Vector3d> v;
  for (const JointVector& x : q) v.emplace_back(0.1 * std::sin(x[0] / 20), 0.05 * std::cos(x[1] / 15), 0.02 * x[2] / 30);
  JointErrorFunctions f;
  f.degree = 2;
  for (int k = 0; k < 6; ++k) {
    f.lo_deg[static_cast<std::size_t>(k)] = -40.0 + (k == 4 ? 45.0 : 0.0);
    f.hi_deg[static_cast<std::size_t>(k)] = 40.0 + (k == 4 ? 45.0 : 0.0);
  }
  f.coefficients_mrad = Eigen::MatrixXd(6, 2);
  f.coefficients_mrad << 0.3, -0.2, 0.5, 0.1, -0.4, 0.2, 0.8, -0.3, 1.2, 0.4, -0.9, 0.6;
  const CompensationModel model = tool_point_model(q, v).with_joint_error_functions(f);
  const Eigen::Vector3d point = model.measured_point_mm() + Eigen::Vector3d(120, -40, 30);
  const CompensationModel at_point = model.with_working_tool(tool_at(model, point));
  MeasurementSet d;
  d.source = "readings.csv";
  for (const JointVector& x : joints_in_box(12, 8)) {
    const PointPrediction p = predict_position(at_point, x);
    ASSERT_TRUE(p.ok());
    d.id.push_back("r");
    d.q_deg.push_back(x);
    d.measured_mm.push_back(*p.tracker_mm);
  }
  const ToolLocation t = locate_tool(model, d);
  EXPECT_LT((t.tool_mm - point).norm(), 1e-6);
  EXPECT_LT(t.residual_rms_mm, 1e-6);
  EXPECT_EQ(t.readings, 12u);
  EXPECT_GE(t.orientations, 3u);
  EXPECT_NEAR(t.lever_mm, (point - model.measured_point_mm()).norm(), 1e-6);
  // noise of 0.05 mm per coordinate: the point within a few standard deviations, which say so
  std::mt19937_64 rng(2);
  std::normal_distribution<double> z(0.0, 0.05);
  for (auto& m : d.measured_mm) m += Eigen::Vector3d(z(rng), z(rng), z(rng));
  const ToolLocation noisy = locate_tool(model, d);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(noisy.sd_mm[k], 0.005);
    EXPECT_LT(noisy.sd_mm[k], 0.05);
    EXPECT_LT(std::abs(noisy.tool_mm[k] - point[k]), 4.0 * noisy.sd_mm[k]) << k;
  }
}

TEST(ToolPoints, LocateToolRefusesTooFewOrientationsAndReadingsOfTwoPoints) {
  const std::vector<JointVector> q = joints_in_box(40, 4);
  std::vector<Eigen::Vector3d> v(q.size(), Eigen::Vector3d(0.01, 0.02, -0.01));
  for (std::size_t i = 0; i < v.size(); ++i) v[i].x() += 0.001 * static_cast<double>(i % 7);
  const CompensationModel model = tool_point_model(q, v);
  const Eigen::Vector3d p1 = model.measured_point_mm() + Eigen::Vector3d(100, 0, 0);
  const Eigen::Vector3d p2 = p1 + Eigen::Vector3d(0, 0, 60);
  auto readings = [&](const std::vector<JointVector>& joints, bool mixed) {
    MeasurementSet d;
    d.source = "readings.csv";
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const PointPrediction p =
          predict_position(model.with_working_tool(tool_at(model, mixed && i % 2 ? p2 : p1)), joints[i]);
      d.id.push_back("r" + std::to_string(i));
      d.q_deg.push_back(joints[i]);
      d.measured_mm.push_back(*p.tracker_mm);
    }
    return d;
  };
  // two orientations (the wrist's joints the same, only q1..q3 apart by a few degrees)
  std::vector<JointVector> two = joints_in_box(2, 6);
  for (int i = 0; i < 6; ++i) {
    JointVector x = two[static_cast<std::size_t>(i % 2)];
    x[0] += 0.5 * (i + 1);  // a repeated pose is refused for itself (another message)
    two.push_back(x);
  }
  try {
    locate_tool(model, readings(two, false));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("distinct flange orientation"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "readings.csv");
  }
  try {
    locate_tool(model, readings(joints_in_box(12, 8), true));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not one point rigidly attached"), std::string::npos) << e.what();
  }
}

TEST(ToolPoints, WorkingToolRoundTripsThroughJsonAndIsChecked) {
  const std::vector<JointVector> q = joints_in_box(40, 4);
  std::vector<Eigen::Vector3d> v;
  for (const JointVector& x : q) v.emplace_back(0.1 * std::sin(x[0] / 20), 0.0, 0.01);
  const CompensationModel model =
      tool_point_model(q, v).with_working_tool(Eigen::Translation3d(15, 2, 30) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  const CompensationModel back = CompensationModel::from_json(model.to_json(), "m.json");
  ASSERT_TRUE(back.working_tool().has_value());
  EXPECT_TRUE(back.working_tool()->isApprox(*model.working_tool(), 1e-12));
  const PointPrediction a = predict_position(model, q[5]), b = predict_position(back, q[5]);
  ASSERT_TRUE(a.position_mm.allFinite()) << "a lever of 34 mm is within what the model supports";
  EXPECT_LT((a.position_mm - b.position_mm).norm(), 1e-9);
  EXPECT_NEAR(a.error.variance_mm2, b.error.variance_mm2, 1e-12);
  nlohmann::json j = model.to_json();
  j["working_tool"]["x_mm"] = 2500.0;
  try {
    CompensationModel::from_json(j, "m.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("working_tool"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2000"), std::string::npos) << e.what();
  }
}

// compensate --frame tracker: a pose in the tracker frame, mapped with the registration, by hand.
// Registration: a quarter turn about z and (100, -50, 10) mm; the pose (10, 20, 30) mm, tool down
// (rx 180). In the robot frame: position Rz(90)(10, 20, 30) + t = (80, -40, 40); orientation
// Rz(90) Rx(180), i.e. rx 180, ry 0, rz 90.
TEST(PosesInRobotFrame, AQuarterTurnAndAShiftByHand) {
  Registration r;
  r.robot_from_tracker = Eigen::Translation3d(100.0, -50.0, 10.0) * Eigen::AngleAxisd(std::numbers::pi / 2.0, Eigen::Vector3d::UnitZ());
  Eigen::MatrixXd tracker(2, 6);
  tracker << 10.0, 20.0, 30.0, 180.0, 0.0, 0.0,  //
      std::nan(""), 0.0, 0.0, 0.0, 0.0, 0.0;
  const Eigen::MatrixXd robot = poses_in_robot_frame(r, tracker);
  ASSERT_EQ(robot.rows(), 2);
  const double expected[6] = {80.0, -40.0, 40.0, 180.0, 0.0, 90.0};
  for (int k = 0; k < 6; ++k) {
    if (k == 3) {
      // rx = +-180 are one angle.
      EXPECT_NEAR(std::abs(robot(0, k)), expected[k], 1e-9);
      continue;
    }
    EXPECT_NEAR(robot(0, k), expected[k], 1e-9) << k;
  }
  EXPECT_FALSE(robot.row(1).allFinite());  // a row with a NaN stays non-finite
  EXPECT_THROW(poses_in_robot_frame(r, Eigen::MatrixXd::Zero(1, 3)), InputError);
}

}  // namespace
}  // namespace errfield::compensation
