#include "errfield/compensation/compensation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "errfield/error.hpp"
#include "errfield/compensation/error_fields.hpp"
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

}  // namespace
}  // namespace errfield::compensation
