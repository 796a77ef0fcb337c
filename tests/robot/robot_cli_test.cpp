// End-to-end tests of the robot subcommands through the real `errfield` executable.

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/arm_configuration.hpp"
#include "errfield/robot/kinematics.hpp"
#include "support/cli_harness.hpp"

namespace errfield::robot {
namespace robot_cli_test {

namespace fs = std::filesystem;

class RobotCli : public errfield::testing::CliTest {};

TEST_F(RobotCli, FkThenIkRoundTripsWithUserRobotJson) {
  // A user robot: the ER20 table with a tool and a base, saved as JSON.
  const MdhModel m = MdhModel::er20_c10().with_tool(to_isometry({0.018, -0.012, 77.025, 0.011, -0.015, 0.008}))
                         .with_base(to_isometry({10, 20, 30, 0, 0, 5}));
  m.save(path("robot.json"));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::string csv = "label,q1,q2,q3,q4,q5,q6\n";
  std::vector<JointVector> qs;
  for (int i = 0; i < 20; ++i) {
    JointVector q;
    q << 30 * u(rng), -100 + 20 * u(rng), -20 + 20 * u(rng), 40 * u(rng), -60 + 20 * u(rng), 90 * u(rng);
    qs.push_back(q);
    csv.append("p").append(std::to_string(i));
    for (int k = 0; k < 6; ++k) csv.append(",").append(format_number(q[k]));
    csv += "\n";
  }
  write("joints.csv", csv);
  auto r = run("fk --input " + path("joints.csv") + " --robot " + path("robot.json") + " --out " + path("poses.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable poses = CsvTable::read(path("poses.csv"));
  ASSERT_EQ(poses.row_count(), 20u);
  EXPECT_EQ(poses.row(3)[0], "p3");  // input columns kept
  const auto x = poses.numeric_column("x"), r23 = poses.numeric_column("r23");
  for (std::size_t i = 0; i < qs.size(); ++i) {
    const Eigen::Isometry3d t = forward_kinematics(m, qs[i], EndFrame::tool);
    EXPECT_DOUBLE_EQ(x[i], t.translation().x());
    EXPECT_DOUBLE_EQ(r23[i], t.linear()(1, 2));
  }
  // IK of those poses without seeds (each row seeds the next) must return joints whose FK is the pose.
  std::string targets = "x,y,z,r11,r12,r13,r21,r22,r23,r31,r32,r33\n";
  for (std::size_t i = 0; i < poses.row_count(); ++i) {
    for (int c = 7; c < 19; ++c) targets.append(c > 7 ? "," : "").append(poses.row(i)[static_cast<std::size_t>(c)]);
    targets += "\n";
  }
  write("targets.csv", targets);
  r = run("ik --input " + path("targets.csv") + " --robot " + path("robot.json") + " --out " + path("ik.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable ik = CsvTable::read(path("ik.csv"));
  const auto q = [&] {
    std::vector<JointVector> out(ik.row_count());
    const Eigen::MatrixXd m2 = ik.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
    for (Eigen::Index i = 0; i < m2.rows(); ++i) out[static_cast<std::size_t>(i)] = m2.row(i).transpose();
    return out;
  }();
  const auto status_col = ik.column_index("status");
  for (std::size_t i = 0; i < ik.row_count(); ++i) {
    EXPECT_EQ(ik.row(i)[status_col], "converged") << "row " << i;
    const Eigen::Isometry3d t = forward_kinematics(m, q[i], EndFrame::tool);
    const Eigen::Isometry3d want = forward_kinematics(m, qs[i], EndFrame::tool);
    EXPECT_LT((t.translation() - want.translation()).norm(), 1e-6);
    EXPECT_LT((t.linear() - want.linear()).cwiseAbs().maxCoeff(), 1e-9);
    // Where the solution's configuration came from (issue 35): without seeds the first row from the
    // multistart, then the previous row's solution unless that failed; config is the solution's own.
    EXPECT_EQ(ik.cell(i, ik.column_index("config")), arm_configuration(m, q[i]).to_string()) << "row " << i;
    const std::string_view source = ik.cell(i, ik.column_index("config_source"));
    EXPECT_TRUE(i == 0 ? source == "multistart" : source == "previous-row" || source == "multistart") << i << " " << source;
  }
  EXPECT_NE(r.err.find("arm configuration from (column config_source): previous-row"), std::string::npos) << r.err;
  // With seeds every row says so; ik run on its own output replaces its computed columns.
  r = run("ik --input " + path("ik.csv") + " --robot " + path("robot.json") + " --out " + path("ik2.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable again = CsvTable::read(path("ik2.csv"));
  EXPECT_EQ(again.header().size(), ik.header().size());
  for (std::size_t i = 0; i < again.row_count(); ++i)
    EXPECT_EQ(again.cell(i, again.column_index("config_source")), "seed") << "row " << i;
  EXPECT_NE(r.err.find("arm configuration from (column config_source): seed 20"), std::string::npos) << r.err;
}

// Issue 19: fk wrote only a rotation matrix while every pose input takes rx,ry,rz. Its rx,ry,rz
// must compose, as R = Rz(rz) Ry(ry) Rx(rx) written out here, to its own r11..r33, and ik must take
// fk's x,y,z,rx,ry,rz alone (no matrix) back to joints whose FK is that pose.
TEST_F(RobotCli, FkWritesRxRyRzThatIkTakesBack) {
  const MdhModel m = MdhModel::er20_c10().with_tool(to_isometry({5, -3, 120, 0, 30, 0}));
  m.save(path("robot.json"));
  std::string csv = "q1,q2,q3,q4,q5,q6\n";
  const std::vector<std::array<double, 6>> qs{
      {10, -95, -15, 20, -60, 30}, {-35, -80, -30, -50, -40, 120}, {60, -110, 5, 90, -85, -150}, {0, -90, 0, 0, -89.5, 0}};
  for (const auto& q : qs) {
    for (int k = 0; k < 6; ++k) csv.append(k ? "," : "").append(format_number(q[static_cast<std::size_t>(k)]));
    csv += "\n";
  }
  write("joints.csv", csv);
  auto r = run("fk --input " + path("joints.csv") + " --robot " + path("robot.json") + " --out " + path("poses.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable poses = CsvTable::read(path("poses.csv"));
  const double d = std::acos(-1.0) / 180.0;
  std::string targets = "x,y,z,rx,ry,rz\n";
  for (std::size_t i = 0; i < poses.row_count(); ++i) {
    const double a = poses.numeric_column("rx")[i] * d, b = poses.numeric_column("ry")[i] * d,
                 c = poses.numeric_column("rz")[i] * d;
    EXPECT_LE(std::abs(poses.numeric_column("ry")[i]), 90.0);
    // Rz(c) Ry(b) Rx(a), row by row
    const double want[9] = {std::cos(c) * std::cos(b), std::cos(c) * std::sin(b) * std::sin(a) - std::sin(c) * std::cos(a),
                            std::cos(c) * std::sin(b) * std::cos(a) + std::sin(c) * std::sin(a),
                            std::sin(c) * std::cos(b), std::sin(c) * std::sin(b) * std::sin(a) + std::cos(c) * std::cos(a),
                            std::sin(c) * std::sin(b) * std::cos(a) - std::cos(c) * std::sin(a),
                            -std::sin(b), std::cos(b) * std::sin(a), std::cos(b) * std::cos(a)};
    const char* names[9] = {"r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33"};
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(poses.numeric_column(names[k])[i], want[k], 1e-12) << names[k] << " row " << i;
    for (const char* col : {"x", "y", "z", "rx", "ry", "rz"})
      targets.append(col[0] == 'x' ? "" : ",").append(format_number(poses.numeric_column(col)[i]));
    targets += "\n";
  }
  write("targets.csv", targets);
  r = run("ik --input " + path("targets.csv") + " --robot " + path("robot.json") + " --out " + path("ik.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable ik = CsvTable::read(path("ik.csv"));
  const Eigen::MatrixXd q = ik.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
  for (std::size_t i = 0; i < qs.size(); ++i) {
    EXPECT_EQ(ik.row(i)[ik.column_index("status")], "converged") << "row " << i;
    const JointVector got = q.row(static_cast<Eigen::Index>(i)).transpose();
    const JointVector given(qs[i].data());
    const Eigen::Isometry3d t = forward_kinematics(m, got, EndFrame::tool);
    const Eigen::Isometry3d want_pose = forward_kinematics(m, given, EndFrame::tool);
    EXPECT_LT((t.translation() - want_pose.translation()).norm(), 1e-6) << "row " << i;
    EXPECT_LT((t.linear() - want_pose.linear()).cwiseAbs().maxCoeff(), 1e-9) << "row " << i;
  }
}

TEST_F(RobotCli, IkAcceptsEulerAnglesAndReportsUnreachable) {
  write("t.csv", "x,y,z,rx,ry,rz\n1000,0,600,180,0,0\n6000,0,600,180,0,0\n");
  const auto r = run("ik --input " + path("t.csv") + " --out " + path("o.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 of 2 targets solved"), std::string::npos) << r.err;
  const CsvTable o = CsvTable::read(path("o.csv"));
  EXPECT_EQ(o.row(0)[o.column_index("status")], "converged");
  EXPECT_NE(o.row(1)[o.column_index("status")], "converged");
  EXPECT_GT(o.numeric_column("residual_mm")[1], 1000.0);
  const JointVector q = o.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"}).row(0).transpose();
  const Eigen::Isometry3d t = forward_kinematics(MdhModel::er20_c10(), q);
  EXPECT_LT((t.translation() - Eigen::Vector3d(1000, 0, 600)).norm(), 1e-6);
  EXPECT_LT((t.linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);  // tool down
}

TEST_F(RobotCli, BadInputNamesFileRowAndColumn) {
  write("j.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n0,abc,0,0,0,0\n");
  auto r = run("fk --input " + path("j.csv") + " --out " + path("o.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("j.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("q2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("abc"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("o.csv")));
  write("bad.json", "{\"links\": 3}");
  r = run("fk --input " + path("j.csv") + " --robot " + path("bad.json") + " --out " + path("o.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("links"), std::string::npos) << r.err;
  r = run("fk --input " + path("j.csv") + " --frame elbow --out " + path("o.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("elbow"), std::string::npos) << r.err;
}

TEST_F(RobotCli, SimulateRobotOutWritesTheNominalRobotOfTheConfig) {
  const auto r = run("simulate --sample grid --step 250 --out " + path("g.csv") + " --config-out " + path("sim.json") +
                     " --robot-out " + path("nominal.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto sim = nlohmann::json::parse(std::ifstream(path("sim.json")));
  const MdhModel from_config = MdhModel::from_json(sim["robot"]);
  const MdhModel written = MdhModel::load(path("nominal.json"));
  EXPECT_EQ(written.to_json(), from_config.to_json());
  // The measured point is the Table 7 ball, so the tool is not the identity.
  EXPECT_NE(written.to_json(), MdhModel::er20_c10().to_json());
}

TEST_F(RobotCli, SimulateThenCalibrateBothModels) {
  auto r = run("simulate --sample grid --step 125 --out " + path("grid.csv") + " --truth-out " + path("truth.json") +
               " --config-out " + path("sim.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  {
    std::ifstream in(path("grid.csv"));
    std::string first;
    std::getline(in, first);
    EXPECT_NE(first.find("SIMULATED"), std::string::npos) << first;  // the file says what it is
  }
  const CsvTable grid = CsvTable::read(path("grid.csv"));
  EXPECT_EQ(grid.row_count(), 126u);  // 1 base point + 125 grid points
  for (const char* c : {"point", "kind", "q1", "q6", "x", "y", "z", "mx", "my", "mz", "dist_b0"})
    EXPECT_TRUE(grid.has_column(c)) << c;
  EXPECT_EQ(grid.row(0)[grid.column_index("kind")], "base");
  EXPECT_NO_THROW(MdhModel::load(path("truth.json")));
  // The nominal robot of the simulation (ER20-C10 with the Table 7 ball as tool).
  const auto sim = nlohmann::json::parse(std::ifstream(path("sim.json")));
  MdhModel::from_json(sim["robot"]).save(path("robot.json"));
  for (const std::string model : {"distance", "position"}) {
    r = run("calibrate --robot " + path("robot.json") + " --data " + path("grid.csv") + " --model " + model + " --out " +
            path("cal_" + model + ".json") + " --report " + path("report.txt"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(path("report.txt"));
    std::stringstream report;
    report << in.rdbuf();
    // Before/after residuals are printed; calibration removes most of the (simulated) error.
    const std::string text = report.str();
    // The last before/after pair is the calibration (the position model reports registration first).
    const auto before = text.rfind("residuals before: rms "), after = text.rfind("residuals after:  rms ");
    ASSERT_NE(before, std::string::npos) << text;
    ASSERT_NE(after, std::string::npos) << text;
    const double rms_before = std::stod(text.substr(before + 22)), rms_after = std::stod(text.substr(after + 22));
    EXPECT_LT(rms_after, rms_before / 2.5) << model << "\n" << text;
    EXPECT_NE(text.find("removed candidates"), std::string::npos);
    const MdhModel calibrated = MdhModel::load(path("cal_" + model + ".json"));
    EXPECT_NE(calibrated.name().find("calibrated"), std::string::npos);
  }
}

// Fixed base points end to end: simulate distances to two points in the cell (not robot
// positions), calibrate from nominals off by about 1 mm; the report lists the identified points.
TEST_F(RobotCli, SimulateAndCalibrateWithFixedBasePoints) {
  auto r = run("simulate --seed 3 --fixed-base 1500,650,150 --fixed-base 600,-700,250 --measure distances --robot-out " +
               path("robot.json") + " --out " + path("fixed.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable data = CsvTable::read(path("fixed.csv"));
  EXPECT_EQ(data.row_count(), 125u);  // no base rows
  EXPECT_TRUE(data.has_column("dist_b1"));
  EXPECT_FALSE(data.has_column("dist_b2"));
  for (std::size_t i = 0; i < data.row_count(); ++i) EXPECT_EQ(data.row(i)[data.column_index("kind")], "target");
  // A distance is to the fixed point itself: |nominal position − point| within a few mm.
  const auto x = data.numeric_column("x"), y = data.numeric_column("y"), z = data.numeric_column("z");
  const auto d0 = data.numeric_column("dist_b0");
  for (std::size_t i = 0; i < data.row_count(); ++i)
    EXPECT_NEAR(d0[i], std::hypot(x[i] - 1500, y[i] - 650, z[i] - 150), 5.0);
  r = run("calibrate --robot " + path("robot.json") + " --data " + path("fixed.csv") +
          " --base-point 1500.8,649.5,151.1 --base-point 598.8,-699.6,250.6 --out " + path("cal.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fixed base point 0 (robot frame, mm)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fixed base point 1 (robot frame, mm)"), std::string::npos) << r.out;
  const auto before = r.out.rfind("residuals before: rms "), after = r.out.rfind("residuals after:  rms ");
  ASSERT_NE(after, std::string::npos) << r.out;
  EXPECT_LT(std::stod(r.out.substr(after + 22)), std::stod(r.out.substr(before + 22)) / 2.5) << r.out;
  EXPECT_NO_THROW(MdhModel::load(path("cal.json")));

  // The same data through `fit --method kinematic` (the pipeline's calibration step).
  r = run("fit --robot " + path("robot.json") + " --data " + path("fixed.csv") + " --method kinematic" +
          " --base-point 1500.8,649.5,151.1 --base-point 598.8,-699.6,250.6 --out " + path("fit.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fixed base point b1 identified at"), std::string::npos) << r.out;
  const auto rms = r.out.find("residual RMS ");
  ASSERT_NE(rms, std::string::npos) << r.out;
  const double rms_before = std::stod(r.out.substr(rms + 13));
  const double rms_after = std::stod(r.out.substr(r.out.find("-> ", rms) + 3));
  EXPECT_LT(rms_after, rms_before / 2.5) << r.out;

  // One --base-point for two dist_bK columns: a usage error naming the option, nothing written.
  r = run("calibrate --robot " + path("robot.json") + " --data " + path("fixed.csv") +
          " --base-point 1500,650,150 --out " + path("bad.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--base-point"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 distance column"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("bad.json")));
  r = run("calibrate --robot " + path("robot.json") + " --data " + path("fixed.csv") +
          " --base-point 1500,650 --base-point 600,-700,250 --out " + path("bad.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--base-point"), std::string::npos) << r.err;
  r = run("simulate --base 750,-250,350 --fixed-base 1500,650,150 --out " + path("bad.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--fixed-base"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("bad.csv")));
}

TEST_F(RobotCli, SimulateBadOptionsAreNamed) {
  for (const std::string& args : {std::string("--cube 1,2,3,x"), std::string("--sample random:abc"),
                                  std::string("--step 120"), std::string("--measure angles"),
                                  std::string("--base 5000,0,0")}) {
    const auto r = run("simulate " + args + " --out " + path("o.csv"));
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_FALSE(fs::exists(path("o.csv"))) << args;
  }
  const auto r = run("simulate --base 5000,0,0 --out " + path("o.csv"));
  EXPECT_NE(r.err.find("not reachable"), std::string::npos) << r.err;
}

TEST_F(RobotCli, CalibrateRejectsDataWithoutBasePoints) {
  write("m.csv", "q1,q2,q3,q4,q5,q6,dist_b0\n0,-90,0,0,-60,0,100\n");
  auto r = run("calibrate --data " + path("m.csv") + " --out " + path("o.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("kind"), std::string::npos) << r.err;
  r = run("calibrate --data " + path("m.csv") + " --model joint --out " + path("o.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(fs::exists(path("o.json")));
}

// calibrate --robot-out: the nominal robot with the reflector offset the data found (issue 19: users
// edited JSON by hand to score --method none). SIMULATED KR16, scattered joints, a reflector
// (12, -8, 30) mm off the nominal tool, which the written robot must carry as its tool point.
TEST_F(RobotCli, CalibrateRobotOutIsTheNominalRobotWithTheFoundReflector) {
  auto r = run("simulate --robot kr16 --seed 3 --sample scattered:80 --joint-box -30,30,-80,-40,10,50,-40,40,40,80,-40,40"
               " --tool-offset 12,-8,30 --measure positions --robot-out " + path("r.json") + " --out " + path("d.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run("calibrate --robot " + path("r.json") + " --data " + path("d.csv") + " --model position --out " +
          path("cal.json") + " --robot-out " + path("nominal.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const MdhModel nominal = MdhModel::load(path("r.json")), written = MdhModel::load(path("nominal.json"));
  for (int i = 0; i < kJointCount; ++i) {  // the nominal links, untouched
    EXPECT_EQ(written.link(i).a_mm, nominal.link(i).a_mm) << i;
    EXPECT_EQ(written.link(i).d_mm, nominal.link(i).d_mm) << i;
    EXPECT_EQ(written.link(i).theta0_deg, nominal.link(i).theta0_deg) << i;
    EXPECT_EQ(written.link(i).alpha_deg, nominal.link(i).alpha_deg) << i;
  }
  const auto j = nlohmann::json::parse(read("nominal.json"));
  const auto c = nlohmann::json::parse(read("cal.json"));
  ASSERT_TRUE(j.contains("registration"));
  // The tool point is exactly the reflector offset the registration found (stored with cal.json) ...
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(written.tool().translation()[k], c["registration"]["reflector_offset_mm"][k].get<double>()) << k;
  // ... which is the simulated reflector, not the nominal tool point: the nominal links' own errors
  // shift a registration by a few mm, the offset is 36 mm.
  const Eigen::Vector3d truth(12.0, -8.0, 30.0);
  EXPECT_LT((written.tool().translation() - truth).norm(), 0.25 * truth.norm()) << written.tool().translation().transpose();
  // It carries its own registration, whose residual is that of the nominal links (larger than the
  // calibrated model's).
  EXPECT_GT(j["registration"]["residual_rms_mm"].get<double>(), c["registration"]["residual_rms_mm"].get<double>());
  // Scoring the nominal robot with it works without an edit of the robot: validate reads it as a
  // model (the data's x,y,z, the FK with the robot JSON's tool, are dropped: errfield computes them).
  rewrite("d.csv", "d_noxyz.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& c) { return c != "x" && c != "y" && c != "z"; });
  r = run("validate --model " + path("nominal.json") + " --data " + path("d_noxyz.csv") + " --summary-out " +
          path("s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Its "after" is the nominal links' error: larger than the calibrated model's on the same rows.
  r = run("validate --model " + path("cal.json") + " --data " + path("d_noxyz.csv") + " --summary-out " +
          path("sc.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto nominal_summary = nlohmann::json::parse(read("s.json")), cal_summary = nlohmann::json::parse(read("sc.json"));
  EXPECT_GT(nominal_summary["position"]["after"]["rms_mm"].get<double>(),
            1.5 * cal_summary["position"]["after"]["rms_mm"].get<double>());
}

}  // namespace
}  // namespace errfield::robot
