// Bad-input catalogue for robot data: robot JSON with a missing or wrongly-sized MD-H table,
// joint angles outside the limits, unreachable IK targets versus targets only beyond the joint
// limits, singular calibration (too few or repeated poses), and positions or distances in metres
// where millimetres are expected (a warning, robot/input_checks.hpp). Robot data are SIMULATED.

#include <random>
#include <regex>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace robot_input_test {

using namespace testing::cli_common;

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
  EXPECT_THAT(r.err, AllOf(HasSubstr("warning"), HasSubstr("q.csv:3: q2 = 100"),
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
  // Outside the reach sphere: unreachable, although the best pose within the limits has q2 at
  // its limit (this used to say joint_limits).
  EXPECT_EQ(out.row(0)[status], "unreachable");
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

TEST(RobotBadInput, IkTargetOnlyBeyondTheJointLimitsIsJointLimits) {
  // A robot whose joints may only move +-10 deg from home: a target FK'd at q1 = 40 deg is inside
  // the reach sphere and reachable, but only with q1 beyond its limit.
  ScratchDir dir;
  auto j = er20_json();
  for (auto& l : j["links"]) {
    l["q_min_deg"] = -10.0;
    l["q_max_deg"] = 10.0;
  }
  dir.write("r.json", j.dump());
  const robot::MdhModel narrow = robot::MdhModel::load(dir / "r.json");
  const Eigen::Vector3d beyond = robot::forward_position(narrow, (robot::JointVector() << 40, 5, 5, 0, 5, 0).finished());
  const Eigen::Vector3d within = robot::forward_position(narrow, (robot::JointVector() << 5, 5, -5, 0, 5, 0).finished());
  dir.write("p.csv", "x,y,z\n" + format_number(beyond.x()) + "," + format_number(beyond.y()) + "," +
                         format_number(beyond.z()) + "\n" + format_number(within.x()) + "," +
                         format_number(within.y()) + "," + format_number(within.z()) + "\n2200,0,504\n");
  const auto r =
      run_errfield({"ik", "--input", "p.csv", "--robot", "r.json", "--position-only", "--out", "o.csv"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = CsvTable::parse(dir.read("o.csv"), "o.csv");
  const auto status = out.column_index("status");
  EXPECT_EQ(out.row(0)[status], "joint_limits");
  EXPECT_EQ(out.row(1)[status], "converged");
  // 2.2 m out along x at shoulder height: inside the reach sphere (sum of link lengths ~2.35 m)
  // but ~2.03 m from the shoulder, beyond the arm (782 + 774 mm + wrist 125 mm): unreachable,
  // though the best pose within the limits has joints at their limits.
  EXPECT_EQ(out.row(2)[status], "unreachable");
}

TEST(RobotBadInput, IkStatusLibraryLevel) {
  const auto er20 = robot::MdhModel::er20_c10();
  robot::IkOptions o;
  o.position_only = true;
  const robot::JointVector seed = (robot::JointVector() << 0, -90, 0, 0, -45, 0).finished();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  // Beyond the arm inside the sphere, and outside the sphere.
  for (const double x : {2200.0, 5000.0}) {
    t.translation() << x, 0, 504;
    const auto r = robot::inverse_kinematics(er20, t, seed, o);
    EXPECT_EQ(r.status, robot::IkStatus::unreachable) << x;
    EXPECT_TRUE(er20.within_limits(r.q_deg));
  }
}

// --- singular calibration: too few poses ---------------------------------------------------

// SIMULATED noise-free data: a perturbed ER20-C10 ("true") measured at `n` joint vectors drawn
// within the limits (fixed seed).
struct CalibrationData {
  robot::MdhModel nominal = robot::MdhModel::er20_c10();
  robot::MdhModel truth = robot::MdhModel::er20_c10();
  std::vector<robot::JointVector> q;
  explicit CalibrationData(std::size_t n) {
    auto links = nominal.links();
    links[1].a_mm += 0.4;
    links[2].alpha_deg += 0.02;
    links[3].d_mm -= 0.3;
    truth = nominal.with_links(links);
    std::mt19937 rng(7);
    for (std::size_t i = 0; i < n; ++i) {
      robot::JointVector v;
      for (int j = 0; j < robot::kJointCount; ++j) {
        const double lo = nominal.link(j).q_min_deg, hi = nominal.link(j).q_max_deg;
        v[j] = std::uniform_real_distribution<double>(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))(rng);
      }
      q.push_back(v);
    }
  }
  std::vector<robot::PositionMeasurement> positions(std::size_t n) const {
    std::vector<robot::PositionMeasurement> d;
    for (std::size_t i = 0; i < n; ++i) d.push_back({q[i], robot::forward_position(truth, q[i])});
    return d;
  }
  // Distances from pose 0 (the base point) to poses 1..n.
  std::vector<robot::DistanceMeasurement> distances(std::size_t n) const {
    std::vector<robot::DistanceMeasurement> d;
    for (std::size_t i = 1; i <= n; ++i)
      d.push_back({q[i], q[0], (robot::forward_position(truth, q[i]) - robot::forward_position(truth, q[0])).norm()});
    return d;
  }
};

// The "need at least N" of a too-few-poses message, checking the message names the counts.
std::size_t needed_of(const std::string& message, std::size_t given, const std::string& kind) {
  EXPECT_THAT(message, AllOf(HasSubstr(std::to_string(given) + " measured " + kind), HasSubstr("equation"),
                             HasSubstr("robot 'ER20-C10'"), HasSubstr("need at least")));
  std::smatch m;
  EXPECT_TRUE(std::regex_search(message, m, std::regex("need at least ([0-9]+) measured " + kind))) << message;
  return m.empty() ? 0 : std::stoul(m[1]);
}

TEST(RobotBadInput, CalibrationWithTooFewPosesNamesTheCountNeeded) {
  const CalibrationData data(80);
  robot::CalibrationOptions o;
  o.robust.enabled = false;
  // Distances: 3 measurements. The message names the count needed; one fewer distinct pose than
  // that still fails, that many is accepted (and, noise-free, fits to ~0).
  std::size_t needed = 0;
  try {
    robot::calibrate_distances(data.nominal, data.distances(3), o);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    needed = needed_of(e.what(), 3, "distance");
  }
  ASSERT_GT(needed, 10u);  // an MD-H table has far more than 10 identifiable parameters
  ASSERT_LT(needed, 60u);
  EXPECT_THROW(robot::calibrate_distances(data.nominal, data.distances(needed - 1), o), InputError);
  // Noise-free: a cap of 1e8 makes distance calibration's regularization toward nominal (a noise
  // policy, weight 0.1 · (largest singular value / cap)²) negligible.
  robot::CalibrationOptions exact = o;
  exact.max_condition_number = 1e8;
  const auto ok = robot::calibrate_distances(data.nominal, data.distances(needed), exact);
  EXPECT_LT(ok.after.max_abs_mm, 1e-6);

  // Positions: registration needs 4 (9 parameters, 3 equations each); calibration more.
  try {
    robot::register_tracker(data.nominal, data.positions(3), o);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(needed_of(e.what(), 3, "position"), 4u);
  }
  try {
    robot::calibrate_positions(data.nominal, data.positions(5), o);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    needed = needed_of(e.what(), 5, "position");
  }
  EXPECT_GT(needed, 5u);
  EXPECT_THROW(robot::calibrate_positions(data.nominal, data.positions(needed - 1), o), InputError);
  EXPECT_NO_THROW(robot::calibrate_positions(data.nominal, data.positions(needed), o));
}

TEST(RobotBadInput, CalibrationAtOneRepeatedPoseIsRefused) {
  const CalibrationData data(2);
  // 60 readings of the same pose pair: one equation, however many rows.
  std::vector<robot::DistanceMeasurement> same(60, data.distances(1)[0]);
  try {
    robot::calibrate_distances(data.nominal, same);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("60 measured distance(s) at 1 distinct pose pair(s)"),
                                HasSubstr("1 equation(s)")));
  }
}

// Runs `errfield simulate` (SIMULATED measurements on the paper's cube) into `file`.
void simulate(const ScratchDir& dir, const std::string& file) {
  // robot.json: the nominal robot with the paper's ball, which the commands below take as --robot
  // (its x,y,z are that robot's FK; the built-in ER20-C10 has no tool and is refused).
  const auto r = run_errfield({"simulate", "--sample", "grid", "--step", "125", "--robot-out", "robot.json", "--out", file},
                              dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// The first `rows` data rows (after comments and header) of a CSV file's text.
std::string first_rows(const std::string& text, std::size_t rows) {
  std::string out;
  std::size_t data = 0;
  bool header = false;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    if (!l.empty() && l[0] != '#') {
      if (header && data++ >= rows) break;
      header = true;
    }
    out += l + "\n";
  }
  return out;
}

TEST(RobotBadInput, CalibrateCliWithTooFewPosesFailsNamingFileAndCount) {
  ScratchDir dir;
  simulate(dir, "grid.csv");
  dir.write("few.csv", first_rows(dir.read("grid.csv"), 3));  // base + 2 targets (one at the base)
  for (const std::string model : {"distance", "position"}) {
    const auto r = run_errfield(
        {"calibrate", "--robot", "robot.json", "--data", "few.csv", "--model", model, "--out", "c.json"}, dir.path());
    EXPECT_EQ(r.exit_code, 2) << model;
    EXPECT_THAT(r.err, AllOf(HasSubstr("input error: few.csv: "), HasSubstr("need at least"),
                             HasSubstr("measured " + model), Not(HasSubstr("converged"))))
        << model;
    EXPECT_THAT(r.out, Not(HasSubstr("converged"))) << model;
    EXPECT_FALSE(std::filesystem::exists(dir / "c.json")) << model;
  }
  // The whole grid calibrates.
  const auto r = run_errfield({"calibrate", "--robot", "robot.json", "--data", "grid.csv", "--out", "c.json"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "c.json"));
  // fit --method kinematic calibrates too: the same refusal, naming the file.
  const auto f = run_errfield({"fit", "--robot", "robot.json", "--data", "few.csv", "--method", "kinematic", "--out", "m.json"},
                              dir.path());
  EXPECT_EQ(f.exit_code, 2);
  EXPECT_THAT(f.err, AllOf(HasSubstr("few.csv: calibration: "), HasSubstr("need at least")));
}

TEST(RobotBadInput, CalibrateCliJointsOutsideTheLimitsNameRowColumnAndValue) {
  ScratchDir dir;
  dir.write("q.csv", "point,kind,q1,q2,q3,q4,q5,q6,mx,my,mz\np0,target,0,0,0,0,0,0,1,2,3\n"
                     "p1,target,0,-20,30,0,150,0,1,2,3\n");
  const auto r = run_errfield({"calibrate", "--data", "q.csv", "--model", "position", "--out", "c.json"}, dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("q.csv:3: column 'q5': 150 deg"), HasSubstr("[-135, 135]")));
}

// --- metres where millimetres are expected ----------------------------------------------------

// `text` (a CSV with comments) with the columns `cols` divided by 1000.
std::string to_metres(const std::string& text, const std::vector<std::string>& cols) {
  std::string out;
  std::vector<std::size_t> idx;
  bool header = false;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    if (l.empty() || l[0] == '#') {
      out += l + "\n";
      continue;
    }
    std::vector<std::string> cells;
    std::istringstream cs(l);
    for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
    if (!header) {
      for (const auto& c : cols) idx.push_back(static_cast<std::size_t>(std::find(cells.begin(), cells.end(), c) - cells.begin()));
      header = true;
    } else {
      for (const auto i : idx) cells[i] = format_number(std::stod(cells[i]) / 1000.0);
    }
    for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? "," : "") + cells[i];
    out += "\n";
  }
  return out;
}

TEST(RobotBadInput, MeasurementsInMetresWarnNamingFileAndColumnsAndStillRun) {
  ScratchDir dir;
  simulate(dir, "grid.csv");
  const std::string grid = dir.read("grid.csv");
  dir.write("m.csv", to_metres(grid, {"mx", "my", "mz", "dist_b0"}));
  // Distances in metres are a warning (the run goes on); positions in metres cannot be registered
  // (residual far beyond the limit: input_checks.hpp), so those runs stop with exit 2 after the
  // warning that names the likely cause.
  struct Case {
    std::vector<std::string> args;
    std::string words;
    int exit_code;
  } cases[] = {
      {{"calibrate", "--robot", "robot.json", "--data", "m.csv", "--model", "position", "--out", "c.json"},
       "m.csv columns mx,my,mz", 2},
      {{"calibrate", "--robot", "robot.json", "--data", "m.csv", "--model", "distance", "--out", "c.json"},
       "m.csv column dist_b0", 0},
      {{"fit", "--robot", "robot.json", "--data", "m.csv", "--method", "position-idw", "--out", "f.json"},
       "m.csv columns mx,my,mz", 2},
      {{"fit", "--robot", "robot.json", "--data", "m.csv", "--method", "distance-idw", "--out", "f.json"},
       "m.csv column dist_b0", 0},
  };
  for (const auto& c : cases) {
    const auto r = run_errfield(c.args, dir.path());
    EXPECT_EQ(r.exit_code, c.exit_code) << testing::command_line(c.args) << r.err;
    if (c.exit_code == 2) {
      EXPECT_THAT(r.err, HasSubstr("registration")) << testing::command_line(c.args);
    }
    EXPECT_THAT(r.err, AllOf(HasSubstr("errfield " + c.args[0] + ": warning: " + c.words), HasSubstr("metres"),
                             HasSubstr("millimetres")))
        << testing::command_line(c.args);
  }
  // The same commands on millimetres: no warning.
  for (const auto& c : cases) {
    auto args = c.args;
    std::replace(args.begin(), args.end(), std::string("m.csv"), std::string("grid.csv"));
    const auto r = run_errfield(args, dir.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.err, Not(HasSubstr("metres"))) << testing::command_line(args);
  }
  // compensate: targets as poses in metres.
  ASSERT_EQ(run_errfield({"fit", "--robot", "robot.json", "--data", "grid.csv", "--method", "position-idw", "--out", "f.json"},
                         dir.path())
                .exit_code,
            0);
  dir.write("t.csv", "x,y,z,rx,ry,rz\n1.0,-0.1,0.5,180,0,0\n1.1,0,0.6,180,0,0\n");
  auto r = run_errfield({"compensate", "--model", "f.json", "--targets", "t.csv", "--out", "j.csv"}, dir.path());
  // The warning does not stop the run: the targets go to IK (near the base, none is compensated,
  // so the job fails with exit 1 and their statuses, not with exit 2 at the warning).
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("errfield compensate: warning: t.csv columns x,y,z"), HasSubstr("metres"),
                           HasSubstr("none of the 2 targets"), HasSubstr("t.csv:2: "), HasSubstr("t.csv:3: ")));
  EXPECT_LT(r.err.find("warning: t.csv columns x,y,z"), r.err.find("none of the 2 targets"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "j.csv"));
  dir.write("t.csv", "x,y,z,rx,ry,rz\n1000,-100,500,180,0,0\n1100,0,600,180,0,0\n");
  r = run_errfield({"compensate", "--model", "f.json", "--targets", "t.csv", "--out", "j.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, Not(HasSubstr("metres")));
}

TEST(RobotBadInput, DistancesInMetresCheck) {
  const auto er20 = robot::MdhModel::er20_c10();
  // Distances between robot positions across a workspace, in metres: all below 25 mm.
  const auto w = robot::distances_in_metres({0.0, 0.125, 0.25, 0.866}, er20, "d.csv column dist_b0");
  ASSERT_TRUE(w.has_value());
  EXPECT_THAT(*w, AllOf(HasSubstr("d.csv column dist_b0"), HasSubstr("0.866"), HasSubstr("metres")));
  EXPECT_FALSE(robot::distances_in_metres({0.0, 125, 250, 866}, er20, "d").has_value());
  EXPECT_FALSE(robot::distances_in_metres({}, er20, "d").has_value());
  EXPECT_FALSE(robot::distances_in_metres({0.0, 0.0}, er20, "d").has_value());  // nothing to judge
}

TEST(RobotBadInput, RobotJsonLengthsInMetresWarn) {
  ScratchDir dir;
  auto j = er20_json();
  for (auto& l : j["links"]) {
    l["a_mm"] = l["a_mm"].get<double>() / 1000.0;
    l["d_mm"] = l["d_mm"].get<double>() / 1000.0;
  }
  dir.write("r.json", j.dump());
  dir.write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n");
  auto r = run_errfield({"fk", "--input", "q.csv", "--robot", "r.json", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;  // a warning, not an error
  EXPECT_THAT(r.err, AllOf(HasSubstr("warning: r.json"), HasSubstr("add up to 2.478 mm"), HasSubstr("metres")));
  // The library check, and the real robot in millimetres: no warning.
  EXPECT_TRUE(robot::lengths_in_metres(robot::MdhModel::load(dir / "r.json"), "r.json").has_value());
  EXPECT_FALSE(robot::lengths_in_metres(robot::MdhModel::er20_c10(), "er20").has_value());
  dir.write("r.json", er20_json().dump());
  r = run_errfield({"fk", "--input", "q.csv", "--robot", "r.json", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, Not(HasSubstr("metres")));
}

}  // namespace
}  // namespace errfield
