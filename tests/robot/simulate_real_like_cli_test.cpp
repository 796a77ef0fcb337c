// `errfield simulate` options that make SIMULATED data look like real measurements (issue 10,
// item 8) and the built-in robots by name (item 9), through the real executable. Each property is
// checked against an independent computation: FK of the written joints, a second run with the
// option off (same seed), the written true geometry.

#include <cmath>
#include <numbers>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/kinematics.hpp"
#include "support/cli_harness.hpp"

namespace errfield::robot {
namespace simulate_real_like_cli_test {

constexpr double kDeg = std::numbers::pi / 180.0;

class SimulateRealLike : public errfield::testing::CliTest {
 protected:
  std::vector<JointVector> joints(const CsvTable& t) const {
    const Eigen::MatrixXd m = t.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
    std::vector<JointVector> q(static_cast<std::size_t>(m.rows()));
    for (Eigen::Index i = 0; i < m.rows(); ++i) q[static_cast<std::size_t>(i)] = m.row(i).transpose();
    return q;
  }
  Eigen::Vector3d xyz(const CsvTable& t, std::size_t i, const std::string& p = "") const {
    return {t.numeric_cell(i, t.column_index(p + "x")), t.numeric_cell(i, t.column_index(p + "y")),
            t.numeric_cell(i, t.column_index(p + "z"))};
  }
};

TEST_F(SimulateRealLike, ScatteredUr5eWithSpreadRoundedJointsOffsetAndOutliers) {
  const std::string common = "simulate --robot ur5e --seed 5 --sample scattered:40 --orientation-spread 30 --truth-columns";
  auto r = run(common + " --joint-decimals 2 --tool-offset 10,-5,20 --outliers 0.1:5 --robot-out " + path("n.json") +
               " --truth-out " + path("true.json") + " --out " + path("d.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = read("d.csv");
  EXPECT_NE(text.find("# SIMULATED"), std::string::npos);
  EXPECT_NE(text.find("recorded to 2 decimals"), std::string::npos);
  const CsvTable t = CsvTable::read(path("d.csv"));
  ASSERT_EQ(t.row_count(), 41u);  // one base row + 40 targets
  const MdhModel nominal = MdhModel::load(path("n.json"));
  EXPECT_EQ(nominal.links()[2].a_mm, ur5e().links()[2].a_mm);
  const auto q = joints(t);
  const BuiltinRobot& ur = *find_builtin_robot("ur5e");
  const Eigen::Matrix3d center = rotation_from_rpy_deg(ur.cube_rpy_deg.x(), ur.cube_rpy_deg.y(), ur.cube_rpy_deg.z());
  double largest_tilt = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    for (int j = 0; j < kJointCount; ++j)  // two decimals as written
      EXPECT_NEAR(q[i][j] * 100.0, std::round(q[i][j] * 100.0), 1e-6) << "row " << i;
    const Eigen::Isometry3d pose = forward_kinematics(nominal, q[i]);
    EXPECT_LT((pose.translation() - xyz(t, i)).norm(), 1e-9) << "x,y,z are the FK of the written joints";
    const double tilt = std::acos(std::clamp(pose.linear().col(2).dot(center.col(2)), -1.0, 1.0)) / kDeg;
    EXPECT_LE(tilt, 30.0 + 0.05) << "row " << i;  // + the rounding of the joints
    largest_tilt = std::max(largest_tilt, tilt);
    if (i == 0) continue;
    for (int k = 0; k < 3; ++k) {  // in the cube (up to joint rounding)
      EXPECT_GE(pose.translation()[k], ur.cube_min_mm[k] - 0.2);
      EXPECT_LE(pose.translation()[k], ur.cube_min_mm[k] + ur.cube_size_mm + 0.2);
    }
  }
  EXPECT_GT(largest_tilt, 15.0) << "orientations really vary";

  // The same run without rounding, offset and outliers: the robot moved at the same (unrounded)
  // joints, so the truth is unchanged; outliers hit exactly round(0.1 * 40) = 4 targets by 5 mm.
  r = run(common + " --truth-out " + path("true0.json") + " --out " + path("clean.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run(common + " --tool-offset 10,-5,20 --joint-decimals 2 --out " + path("no_outliers.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable clean = CsvTable::read(path("clean.csv")), no_out = CsvTable::read(path("no_outliers.csv"));
  const auto q_clean = joints(clean);
  const auto flag = t.numeric_column("outlier");
  int outliers = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    EXPECT_LE((q[i] - q_clean[i]).cwiseAbs().maxCoeff(), 0.005 + 1e-9) << "row " << i;
    const double moved = (xyz(t, i, "m") - xyz(no_out, i, "m")).norm();
    if (flag[i] == 1.0) {
      ++outliers;
      EXPECT_NEAR(moved, 5.0, 1e-9) << "row " << i;
      EXPECT_NE(t.row(i)[1], "base");
    } else {
      EXPECT_EQ(moved, 0.0) << "row " << i;
      EXPECT_EQ(xyz(t, i, "true_"), xyz(no_out, i, "true_")) << "row " << i;
    }
  }
  EXPECT_EQ(outliers, 4);
  // The true tool is the nominal-side tool moved by the offset, in the tool frame.
  const MdhModel truth = MdhModel::load(path("true.json")), truth0 = MdhModel::load(path("true0.json"));
  const Eigen::Vector3d d = truth0.tool().linear().transpose() * (truth.tool().translation() - truth0.tool().translation());
  EXPECT_LT((d - Eigen::Vector3d(10, -5, 20)).norm(), 1e-9);
  // With the offset the true positions differ from the offset-free run by the turned offset.
  const CsvTable clean_truth = clean;
  double largest_shift = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i)
    largest_shift = std::max(largest_shift, (xyz(t, i, "true_") - xyz(clean_truth, i, "true_")).norm());
  EXPECT_NEAR(largest_shift, std::sqrt(100.0 + 25 + 400), 0.05);  // compliance moves by ~0.005 mm
}

TEST_F(SimulateRealLike, RandomToolOffsetHasTheGivenLength) {
  auto r = run("simulate --seed 3 --sample random:5 --tool-offset random:12 --truth-out " + path("t.json") + " --out " +
               path("a.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run("simulate --seed 3 --sample random:5 --truth-out " + path("t0.json") + " --out " + path("b.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MdhModel a = MdhModel::load(path("t.json")), b = MdhModel::load(path("t0.json"));
  EXPECT_NEAR((a.tool().translation() - b.tool().translation()).norm(), 12.0, 1e-9);
}

TEST_F(SimulateRealLike, Kr16DefaultCubeAndJointBox) {
  auto r = run("simulate --robot kr16 --sample grid --step 250 --out " + path("g.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable g = CsvTable::read(path("g.csv"));
  EXPECT_EQ(g.row_count(), 28u);  // base + 3^3
  const auto qg = joints(g);
  for (std::size_t i = 1; i < qg.size(); ++i)
    EXPECT_LT((forward_position(kr16(), qg[i]) - xyz(g, i)).norm(), 1e-9);
  r = run("simulate --robot kr16 --sample scattered:30 --joint-box -30,30,-100,-60,60,100,-20,20,20,60,-90,90 --out " +
          path("b.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable b = CsvTable::read(path("b.csv"));
  const auto qb = joints(b);
  ASSERT_EQ(qb.size(), 31u);
  const double lo[6] = {-30, -100, 60, -20, 20, -90}, hi[6] = {30, -60, 100, 20, 60, 90};
  for (std::size_t i = 1; i < qb.size(); ++i)
    for (int j = 0; j < kJointCount; ++j) {
      EXPECT_GE(qb[i][j], lo[j]);
      EXPECT_LE(qb[i][j], hi[j]);
    }
}

// --reflectors: every pose read at several points on one flange (issue 34 item 6). Checked against
// FK of the written joints (x,y,z), the plate's rigidity (the true points keep their distances: one
// move, one robot), and the point-to-point difference of the error a kinematic model of one point
// cannot see; a one-point method refuses the mixed file, and fit reads one reflector's rows.
TEST_F(SimulateRealLike, ReflectorsReadEveryPoseAtEachPointOfTheFlange) {
  const std::vector<Eigen::Vector3d> r = {{0, 0, 100}, {150, 0, 100}, {0, 150, 60}};
  auto res = run("simulate --robot kr16 --seed 4 --sample scattered:12 --measure positions --systematic realistic "
                 "--reflectors \"0,0,100;150,0,100;0,150,60\" --truth-columns --robot-out " + path("n.json") +
                 " --out " + path("d.csv"));
  ASSERT_EQ(res.exit_code, 0) << res.err;
  EXPECT_NE(read("d.csv").find("# SIMULATED reflectors"), std::string::npos);
  const CsvTable t = CsvTable::read(path("d.csv"));
  ASSERT_EQ(t.row_count(), 13u * 3u);  // (one base row + 12 targets) x 3 reflectors
  EXPECT_EQ(t.column_index("reflector"), 1u) << "beside point";
  const MdhModel nominal = MdhModel::load(path("n.json"));
  const auto q = joints(t);
  double largest_difference = 0.0;
  for (std::size_t pose = 0; pose < 13; ++pose) {
    const Eigen::Isometry3d flange = forward_kinematics(nominal, q[3 * pose], EndFrame::flange);
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t i = 3 * pose + k;
      EXPECT_EQ(t.cell(i, t.column_index("reflector")), "r" + std::to_string(k + 1));
      EXPECT_EQ(t.cell(i, t.column_index("point")), t.cell(3 * pose, t.column_index("point")));
      EXPECT_EQ(q[i], q[3 * pose]) << "rows of a pose share the joints";
      EXPECT_LT((xyz(t, i) - flange * r[k]).norm(), 1e-9) << "x,y,z: FK of the flange times the offset";
      for (std::size_t m = 0; m < k; ++m)
        EXPECT_NEAR((xyz(t, i, "true_") - xyz(t, 3 * pose + m, "true_")).norm(), (r[k] - r[m]).norm(), 1e-9)
            << "one rigid plate, one move";
      const Eigen::Vector3d error_k = xyz(t, i, "true_") - xyz(t, i), error_1 = xyz(t, 3 * pose, "true_") - xyz(t, 3 * pose);
      largest_difference = std::max(largest_difference, (error_k - error_1).norm());
    }
  }
  // The flange turns by the geometric and joint errors (tenths of a mrad and more): 150 mm away that
  // is tens of micrometres at least.
  EXPECT_GT(largest_difference, 0.02);

  // A method that models one point refuses the mixed file (exit 2, naming the column); the kinematic
  // methods take it (ValidateCli.TwoReflectorsFitOneModelThatTransfersToALocatedThirdPoint).
  res = run("fit --robot " + path("n.json") + " --data " + path("d.csv") + " --method vector-kriging --out " + path("m.json"));
  EXPECT_EQ(res.exit_code, 2) << res.err;
  EXPECT_NE(res.err.find("'reflector'"), std::string::npos) << res.err;
  // One reflector's rows (r2), with a robot whose tool is r2: readable.
  std::string kept;
  {
    std::istringstream in(read("d.csv"));
    for (std::string line; std::getline(in, line);)
      if (line.rfind("#", 0) == 0 || line.rfind("point,", 0) == 0 || line.find(",r2,") != std::string::npos) kept += line + "\n";
  }
  write("r2.csv", kept);
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  tool.translation() = r[1];
  write("r2.json", nominal.with_tool(tool).to_json().dump());
  res = run("fit --robot " + path("r2.json") + " --data " + path("r2.csv") + " --method kinematic --out " + path("m.json"));
  EXPECT_EQ(res.exit_code, 0) << res.err;
}

TEST_F(SimulateRealLike, ReflectorsNeedTwoPointsAndPositionsOnly) {
  for (const char* opt : {"--reflectors 0,0,100 --measure positions", "--reflectors \"0,0,100;1,2\" --measure positions",
                          "--reflectors \"0,0,100;150,0,100\""}) {
    const auto r = run(std::string("simulate --sample random:3 ") + opt + " --out " + path("x.csv"));
    EXPECT_EQ(r.exit_code, 2) << opt << "\n" << r.err;
    EXPECT_NE(r.err.find("--reflectors"), std::string::npos) << opt << "\n" << r.err;
  }
}

TEST_F(SimulateRealLike, BadOptionsAreUsageErrors) {
  const std::pair<const char*, const char*> cases[] = {
      {"--joint-decimals 13", "--joint-decimals"},
      {"--outliers 2:5", "--outliers"},
      {"--outliers 0.1", "--outliers"},
      {"--orientation-spread 120", "--orientation-spread"},
      {"--joint-box 0,1,0,1,0,1,0,1,0,1,0,1", "--joint-box"},
      {"--sample scattered:0", "scattered"},
      {"--tool-offset random:-1", "--tool-offset"},
      {"--robot nosuch", "built-in"},
  };
  for (const auto& [opt, word] : cases) {
    const auto r = run(std::string("simulate ") + opt + " --out " + path("x.csv"));
    EXPECT_EQ(r.exit_code, 2) << opt << "\n" << r.err;
    EXPECT_NE(r.err.find(word), std::string::npos) << opt << "\n" << r.err;
  }
}

TEST_F(SimulateRealLike, RobotsByNameInFkAndTheRobotsCommand) {
  auto r = run("robots");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"er20-c10", "kr16", "ur5e", "FAQ 45257"}) EXPECT_NE(r.out.find(name), std::string::npos) << name;
  r = run("robots --show ur5e --out " + path("u.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MdhModel u = MdhModel::load(path("u.json"));
  write("q.csv", "q1,q2,q3,q4,q5,q6\n10,-70,80,-20,35,60\n");
  r = run("fk --input " + path("q.csv") + " --robot UR5e --out " + path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable p = CsvTable::read(path("p.csv"));
  JointVector q;
  q << 10, -70, 80, -20, 35, 60;
  EXPECT_LT((xyz(p, 0) - forward_position(ur5e(), q)).norm(), 1e-9);
  EXPECT_LT((forward_position(u, q) - forward_position(ur5e(), q)).norm(), 1e-9);
  r = run("fk --input " + path("q.csv") + " --robot list --out " + path("p2.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("kr16"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace errfield::robot
