// Bad-input catalogue for robot data: robot JSON with a missing or wrongly-sized MD-H table,
// joint angles outside the limits, unreachable IK targets, and positions in metres where
// millimetres are expected (a warning, robot/input_checks.hpp).

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::run_errfield;
using testing::ScratchDir;

nlohmann::json er20_json() { return robot::MdhModel::er20_c10().to_json(); }

// Runs `fk` with the robot description `robot_json`; returns the result.
testing::CliResult fk_with_robot(const ScratchDir& dir, const std::string& robot_json) {
  dir.write("r.json", robot_json);
  dir.write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n");
  return run_errfield({"fk", "--input", "q.csv", "--robot", "r.json", "--out", "o.csv"}, dir.path());
}

TEST(RobotBadInput, JsonWithoutTheMdhTable) {
  ScratchDir dir;
  auto j = er20_json();
  j.erase("links");
  const auto r = fk_with_robot(dir, j.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("r.json"), HasSubstr("links: missing"), HasSubstr("6 link objects")));
}

TEST(RobotBadInput, JsonWithAWronglySizedTable) {
  ScratchDir dir;
  for (const std::size_t keep : {0u, 5u, 7u}) {
    auto j = er20_json();
    auto& links = j["links"];
    if (keep < links.size()) links.erase(links.begin() + static_cast<long>(keep), links.end());
    while (links.size() < keep) links.push_back(links[0]);
    const auto r = fk_with_robot(dir, j.dump());
    EXPECT_EQ(r.exit_code, 2) << keep;
    EXPECT_THAT(r.err, AllOf(HasSubstr("r.json"), HasSubstr("links"), HasSubstr(std::to_string(keep) + " entries")));
  }
}

TEST(RobotBadInput, JsonWithAMissingOrNonNumericField) {
  ScratchDir dir;
  auto j = er20_json();
  j["links"][2].erase("a_mm");
  auto r = fk_with_robot(dir, j.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("r.json"), HasSubstr("links[2].a_mm")));
  j = er20_json();
  j["links"][4]["d_mm"] = "12";
  r = fk_with_robot(dir, j.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("r.json"), HasSubstr("links[4].d_mm")));
  j = er20_json();
  j["links"][1]["q_min_deg"] = 120.0;  // above q_max_deg = 90
  r = fk_with_robot(dir, j.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("links[1].q_min_deg"), HasSubstr("q_max_deg")));
  r = fk_with_robot(dir, "{\"links\": [");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("r.json"), HasSubstr("not valid JSON")));
}

TEST(RobotBadInput, JointAnglesOutsideTheLimitsWarnWithRowJointAndValue) {
  ScratchDir dir;
  dir.write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n0,100,0,0,0,0\n0,0,0,0,200,0\n");
  const auto r = run_errfield({"fk", "--input", "q.csv", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("warning"), HasSubstr("q.csv line 3"), HasSubstr("q2 = 100"),
                           HasSubstr("[-150, 90]"), HasSubstr("2 rows")));
  dir.write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n10,-20,30,-40,50,-60\n");
  EXPECT_THAT(run_errfield({"fk", "--input", "q.csv", "--out", "o.csv"}, dir.path()).err, Not(HasSubstr("warning")));
}

TEST(RobotBadInput, UnreachableIkTargetIsReportedPerRowNotAsACrash) {
  ScratchDir dir;
  // 5 m from the base of a robot of ~2.5 m reach, next to a reachable pose.
  const auto t = robot::forward_kinematics(robot::MdhModel::er20_c10(),
                                           (robot::JointVector() << 10, -30, 20, 0, 40, 0).finished(),
                                           robot::EndFrame::tool);
  dir.write("p.csv", "x,y,z\n5000,0,0\n" + format_number(t.translation().x()) + "," +
                         format_number(t.translation().y()) + "," + format_number(t.translation().z()) + "\n");
  const auto r = run_errfield({"ik", "--input", "p.csv", "--position-only", "--out", "o.csv"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("1 of 2 targets solved"));
  const auto out = CsvTable::parse(dir.read("o.csv"), "o.csv");
  const auto status = out.column_index("status");
  EXPECT_NE(out.row(0)[status], "converged");
  EXPECT_GT(out.numeric_column("residual_mm")[0], 2000.0);  // at least 5000 - reach away
  EXPECT_EQ(out.row(1)[status], "converged");
}

TEST(RobotBadInput, PositionsInMetresWarn) {
  ScratchDir dir;
  dir.write("p.csv", "x,y,z\n1.2,0.1,0.9\n0.8,-0.3,1.1\n");
  auto r = run_errfield({"ik", "--input", "p.csv", "--position-only", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("warning"), HasSubstr("p.csv"), HasSubstr("metres"), HasSubstr("millimetres")));
  dir.write("p.csv", "x,y,z\n1200,100,900\n800,-300,1100\n");
  r = run_errfield({"ik", "--input", "p.csv", "--position-only", "--out", "o.csv"}, dir.path());
  EXPECT_THAT(r.err, Not(HasSubstr("metres")));
}

TEST(RobotBadInput, MetresCheckUsesReachAndBase) {
  const auto er20 = robot::MdhModel::er20_c10();
  EXPECT_NEAR(robot::reach_scale_mm(er20), 504 + 166.605 + 782.27 + 138.826 + 761.35 + 125, 1e-9);
  Eigen::MatrixXd metres(2, 3), mm(2, 3);
  metres << 1.2, 0.1, 0.9, 0.8, -0.3, 1.1;
  mm = metres * 1000.0;
  EXPECT_TRUE(robot::metres_instead_of_mm(metres, er20, "m.csv").has_value());
  EXPECT_FALSE(robot::metres_instead_of_mm(mm, er20, "m.csv").has_value());
  EXPECT_FALSE(robot::metres_instead_of_mm(Eigen::MatrixXd(0, 3), er20, "m.csv").has_value());
  // A base far from the world origin (a tracker frame): metres are still caught, millimetres are
  // still not flagged.
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() << 3000, -2000, 500;
  const auto moved = er20.with_base(base);
  Eigen::MatrixXd metres_moved = metres, mm_moved = mm;
  metres_moved.rowwise() += Eigen::RowVector3d(3, -2, 0.5);
  mm_moved.rowwise() += Eigen::RowVector3d(3000, -2000, 500);
  EXPECT_TRUE(robot::metres_instead_of_mm(metres_moved, moved, "m.csv").has_value());
  EXPECT_FALSE(robot::metres_instead_of_mm(mm_moved, moved, "m.csv").has_value());
}

}  // namespace
}  // namespace errfield
