// No silent wrong command (issue 18): every way a user can hand errfield the wrong robot, units or
// model is caught before a joint is written. Each test failed on the code before the issue (exit 0,
// rows "ok", or a fit that failed on routine data). All robot data here are SIMULATED, and not the
// default set-up: a KR16 (and a UR5e for "another robot"), scattered joints, a tool offset the
// robot JSON lacks, joints rounded as a controller records them.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/robot/pose.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace wrong_command_cli_test {

// KR16 joints (deg) inside its limits (A1 +-185, A2 [-155, 35], A3 [-130, 154], A5 +-130).
constexpr const char* kJointBox = "-30,30,-80,-40,10,50,-40,40,40,80,-40,40";
// The same arm further round (q1 60..120 deg): outside the region of a field fitted in kJointBox.
constexpr const char* kOtherBox = "60,120,-80,-40,10,50,-40,40,40,80,-40,40";

class WrongCommand : public testing::CliTest {
 protected:
  static bool keep_all(const std::string&) { return true; }
  /// `errfield simulate` of the KR16 (SIMULATED), scattered in a joint box, with a reflector 20 mm
  /// off the robot JSON's tool and joints to 3 decimals; writes `out` (and r.json).
  void simulate_kr16(const std::string& out, int n, const std::string& box = kJointBox, const std::string& extra = "") {
    const auto r = run("simulate --robot kr16 --seed 7 --sample scattered:" + std::to_string(n) + " --joint-box " + box +
                       " --tool-offset random:20 --joint-decimals 3 --measure positions --robot-out " + path("r.json") +
                       " --out " + path(out) + " " + extra);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static bool not_xyz(const std::string& c) { return c != "x" && c != "y" && c != "z"; }
  void expect_refused(const testing::CliResult& r, int code, const std::vector<std::string>& words) {
    EXPECT_EQ(r.exit_code, code) << r.out << r.err;
    for (const auto& w : words) EXPECT_NE(r.err.find(w), std::string::npos) << "missing '" << w << "' in:\n" << r.err;
  }
  std::vector<std::string> column(const std::string& file, const std::string& name) {
    const CsvTable t = CsvTable::read(path(file));
    std::vector<std::string> v;
    for (std::size_t i = 0; i < t.row_count(); ++i) v.emplace_back(t.cell(i, t.column_index(name)));
    return v;
  }
  nlohmann::json read_json(const std::string& file) { return nlohmann::json::parse(read(file)); }
  void write_json(const std::string& file, const nlohmann::json& j) { write(file, j.dump(1)); }
};

// ---- item 6: nothing predicted is a failure -------------------------------------------------

TEST_F(WrongCommand, PredictAndValidateWithEveryRowRefusedFail) {
  simulate_kr16("train.csv", 40);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") +
                " --method kinematic+kriging --model \"gau(sill=0.05,range=60)+nug(0.001)\" --out " + path("m.json"))
                .exit_code,
            0);
  // Held-out poses of the same arm further round: all outside the field's region.
  simulate_kr16("far.csv", 12, kOtherBox);
  const auto p = run("predict --model " + path("m.json") + " --joints " + path("far.csv") + " --out " + path("p.csv"));
  // predict reads every row, the base row too (13); validate scores the 12 targets.
  expect_refused(p, 1, {"none of the 13 rows", "outside-region 13", "nothing written"});
  EXPECT_FALSE(std::filesystem::exists(path("p.csv")));
  const auto v = run("validate --model " + path("m.json") + " --data " + path("far.csv") + " --out " + path("v.csv"));
  expect_refused(v, 1, {"none of the 12 points", "outside-region 12", "nothing written"});
  EXPECT_FALSE(std::filesystem::exists(path("v.csv")));
  // One row inside is enough for a result.
  simulate_kr16("near.csv", 5);
  EXPECT_EQ(run("predict --model " + path("m.json") + " --joints " + path("near.csv") + " --out " + path("p.csv")).exit_code, 0);
}

// ---- item 4: joints beyond the limits are a status ------------------------------------------

TEST_F(WrongCommand, JointsBeyondTheLimitsAreNeverOk) {
  simulate_kr16("train.csv", 30);
  // A calibrated robot (no field): before, predict and compensate answered anywhere.
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  write("q.csv", "q1,q2,q3,q4,q5,q6\n10,-60,30,0,60,0\n400,-60,30,0,60,0\n1e300,-60,30,0,60,0\n10,-60,30,0,60,-351\n");
  const auto p = run("predict --model " + path("k.json") + " --joints " + path("q.csv") + " --out " + path("p.csv"));
  EXPECT_EQ(p.exit_code, 0) << p.err;
  EXPECT_EQ(column("p.csv", "status"),
            (std::vector<std::string>{"ok", "outside-limits", "outside-limits", "outside-limits"}));
  // The warning names the row, the joint, its value and the limits (KR16 A1: +-185 deg).
  for (const char* w : {"q.csv:3", "q1 = 400", "[-185, 185]", "3 rows"})
    EXPECT_NE(p.err.find(w), std::string::npos) << w << " in " << p.err;

  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("q.csv") + " --out " + path("c.csv"));
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(column("c.csv", "status"),
            (std::vector<std::string>{"ok", "outside-limits", "outside-limits", "outside-limits"}));
  EXPECT_EQ(column("c.csv", "cq1")[1], "");  // no joints sent

  // validate: q1 + 360 deg is the same pose for the FK (so the data still fit the robot) but a
  // joint value the KR16 cannot take. Row 0 is the base row; validate lists the 12 targets.
  simulate_kr16("hold.csv", 12);
  rewrite("hold.csv", "wrapped.csv", [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
    if (i == 4) row[t.column_index("q1")] = format_number(t.numeric_cell(i, t.column_index("q1")) + 360.0);
  });
  ASSERT_EQ(CsvTable::read(path("wrapped.csv")).row(0)[1], "base");
  const auto v = run("validate --model " + path("k.json") + " --data " + path("wrapped.csv") + " --out " + path("v.csv"));
  EXPECT_EQ(v.exit_code, 0) << v.err;
  const auto status = column("v.csv", "status");
  ASSERT_EQ(status.size(), 12u);
  EXPECT_EQ(status[3], "outside-limits");
  EXPECT_EQ(std::count(status.begin(), status.end(), "ok"), 11);
  EXPECT_NE(v.err.find("wrapped.csv:" + std::to_string(CsvTable::read(path("wrapped.csv")).line_of_row(4))),
            std::string::npos)
      << v.err;
}

// ---- item 1: the data must fit the robot -----------------------------------------------------

TEST_F(WrongCommand, FitWithoutRobotOnAnotherRobotsData) {
  // Real tracker files have no nominal x,y,z: only the registration can tell.
  simulate_kr16("d.csv", 40);
  rewrite("d.csv", "nox.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {}, not_xyz);
  expect_refused(run("fit --data " + path("nox.csv") + " --out " + path("m.json")), 2,
                 {"nox.csv", "registration", "beyond the limit 5 mm", "built-in kr16", "no --robot"});
  EXPECT_FALSE(std::filesystem::exists(path("m.json")));
  // With the right robot the default fit works; a limit raised on purpose lets the wrong one through.
  EXPECT_EQ(run("fit --robot kr16 --method kinematic --data " + path("nox.csv") + " --out " + path("m.json")).exit_code, 0);
  EXPECT_EQ(run("fit --method kinematic --max-registration-rms 100000 --data " + path("nox.csv") + " --out " +
                path("m2.json")).exit_code,
            0);
}

TEST_F(WrongCommand, JointsInRadiansAndReadingsInMetres) {
  simulate_kr16("d.csv", 40);
  rewrite(
      "d.csv", "rad.csv",
      [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
        for (const char* q : {"q1", "q2", "q3", "q4", "q5", "q6"})
          row[t.column_index(q)] = format_number(t.numeric_cell(i, t.column_index(q)) * std::numbers::pi / 180.0);
      },
      not_xyz);
  expect_refused(run("fit --robot " + path("r.json") + " --data " + path("rad.csv") + " --out " + path("m.json")), 2,
                 {"rad.csv", "radians"});
  rewrite(
      "d.csv", "metres.csv",
      [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
        for (const char* c : {"mx", "my", "mz"})
          row[t.column_index(c)] = format_number(t.numeric_cell(i, t.column_index(c)) / 1000.0);
      },
      not_xyz);
  expect_refused(run("fit --robot " + path("r.json") + " --method kinematic --data " + path("metres.csv") + " --out " +
                     path("m.json")),
                 2, {"metres.csv", "metres"});
}

TEST_F(WrongCommand, ValidateOnAnotherRobotOrRadiansIsRefused) {
  simulate_kr16("train.csv", 30);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  // Held-out data of a UR5e: before, "after" errors of a metre and exit 0.
  ASSERT_EQ(run("simulate --robot ur5e --sample scattered:20 --orientation-spread 20 --measure positions --out " +
                path("ur.csv")).exit_code,
            0);
  rewrite("ur.csv", "ur_nox.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {}, not_xyz);
  expect_refused(run("validate --model " + path("k.json") + " --data " + path("ur_nox.csv")), 2,
                 {"ur_nox.csv", "registration", "built-in ur5e"});
  // The KR16's own held-out data in radians.
  simulate_kr16("hold.csv", 20);
  rewrite(
      "hold.csv", "rad.csv",
      [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
        for (const char* q : {"q1", "q2", "q3", "q4", "q5", "q6"})
          row[t.column_index(q)] = format_number(t.numeric_cell(i, t.column_index(q)) * std::numbers::pi / 180.0);
      },
      not_xyz);
  expect_refused(run("validate --model " + path("k.json") + " --data " + path("rad.csv")), 2, {"rad.csv", "radians"});
  // predict on a joints file that carries readings runs the same check.
  expect_refused(run("predict --model " + path("k.json") + " --joints " + path("ur_nox.csv") + " --out " + path("p.csv")),
                 2, {"ur_nox.csv", "built-in ur5e"});
  // The right data pass.
  EXPECT_EQ(run("validate --model " + path("k.json") + " --data " + path("hold.csv")).exit_code, 0);
}

// ---- item 5: a model file is checked as a whole ----------------------------------------------

TEST_F(WrongCommand, EditedModelFilesAreRefusedNamingTheMember) {
  simulate_kr16("train.csv", 30);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") +
                " --method kinematic+kriging --model \"gau(sill=0.05,range=60)+nug(0.001)\" --out " + path("kk.json"))
                .exit_code,
            0);
  ASSERT_EQ(run("simulate --robot kr16 --sample grid --step 250 --measure distances --out " + path("grid.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot kr16 --data " + path("grid.csv") + " --method distance-idw --out " + path("idw.json")).exit_code,
            0);
  simulate_kr16("q.csv", 5);
  const nlohmann::json good = read_json("kk.json");
  auto refused = [&](const std::string& name, const nlohmann::json& j, const std::vector<std::string>& words) {
    write_json(name, j);
    expect_refused(run("predict --model " + path(name) + " --joints " + path("q.csv") + " --out " + path("p.csv")), 2,
                   words);
  };
  {
    nlohmann::json j = good;
    j["field"] = read_json("idw.json")["field"];
    refused("kind.json", j, {"kind.json", "field.kind", "distance-idw", "kinematic+kriging"});
  }
  {
    // The stored samples are of the KR16, the nominal robot now a UR5e.
    ASSERT_EQ(run("simulate --robot ur5e --sample random:5 --robot-out " + path("ur.json") + " --out " + path("u.csv"))
                  .exit_code,
              0);
    nlohmann::json j = good;
    j["nominal_model"] = read_json("ur.json");
    // The command model (the KR16 calibration) is no calibration of a UR5e: refused at that member
    // before the samples are looked at.
    refused("robot.json", j, {"robot.json", "command_model", "nominal_model"});
  }
  for (int order : {9, -1}) {
    nlohmann::json j = good;
    j["field"]["drift_order"] = order;
    refused("drift.json", j, {"drift.json", "field.drift_order", std::to_string(order)});
  }
  {
    nlohmann::json j = good;
    j.erase("credible_range");
    refused("credible.json", j, {"credible.json", "credible_range", "missing"});
  }
  {
    nlohmann::json j = good;
    j["credible_range"]["center_mm"] = {0.1};
    refused("dims.json", j, {"dims.json", "credible_range.center_mm"});
  }
  {
    nlohmann::json j = good;
    for (const char* m : {"position_mm", "joints_deg"}) j["field"]["samples"][m] = nlohmann::json::array();
    j["field"]["values"] = nlohmann::json::array();
    refused("count.json", j, {"count.json", "field", "samples"});
  }
  // The file as fit wrote it is fine.
  EXPECT_EQ(run("predict --model " + path("kk.json") + " --joints " + path("q.csv") + " --out " + path("p.csv")).exit_code, 0);
}

// ---- item 7: re-measured poses ----------------------------------------------------------------

TEST_F(WrongCommand, RemeasuredPosesFitByDefault) {
  simulate_kr16("d.csv", 40);
  // Pose 12 measured again: same joints, a reading 0.05 mm away.
  const CsvTable t = CsvTable::read(path("d.csv"));
  std::string text = read("d.csv");
  std::vector<std::string> again = t.row(12);
  again[t.column_index("point")] += "b";
  const std::size_t mx = t.column_index("mx");
  again[mx] = format_number(t.numeric_cell(12, mx) + 0.05);
  std::string line;
  for (const auto& c : again) line += (line.empty() ? "" : ",") + c;
  write("twice.csv", text + line + "\n");
  const auto r = run("fit --robot " + path("r.json") + " --data " + path("twice.csv") + " --out " + path("m.json"));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(r.err.find("singular"), std::string::npos) << r.err;

  // REML and ML directly, on a scalar with one duplicated location.
  std::string s = "q1,q2,q3,q4,q5,q6,e\n";
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    for (const char* q : {"q1", "q2", "q3", "q4", "q5", "q6"}) s += std::string(t.cell(i, t.column_index(q))) + ",";
    s += format_number(std::sin(0.05 * t.numeric_cell(i, t.column_index("q1"))) + 0.01 * static_cast<double>(i % 3)) + "\n";
  }
  for (const char* q : {"q1", "q2", "q3", "q4", "q5", "q6"}) s += std::string(t.cell(3, t.column_index(q))) + ",";
  s += "0.5\n";
  write("dup.csv", s);
  for (const char* method : {"reml", "ml"}) {
    const auto f = run(std::string("fit-variogram --method ") + method + " --input " + path("dup.csv") +
                       " --coords q1,q2,q3,q4,q5,q6 --value e --model exp");
    EXPECT_EQ(f.exit_code, 0) << method << ": " << f.err;
  }
}

// ---- item 9: the paper's layout ---------------------------------------------------------------

TEST_F(WrongCommand, BasePointThatIsGridVertexZero) {
  // A KR16 grid (27 vertices) with the base point at the cube corner, vertex 0 (simulate writes
  // the base row and the vertex-0 target row, both at that pose).
  ASSERT_EQ(run("simulate --robot kr16 --sample grid --step 250 --measure distances --out " + path("grid.csv")).exit_code,
            0);
  const CsvTable t = CsvTable::read(path("grid.csv"));
  const std::size_t kind = t.column_index("kind");
  auto joints = [&](std::size_t i) {
    std::string q;
    for (const char* c : {"q1", "q2", "q3", "q4", "q5", "q6"}) q += std::string(t.cell(i, t.column_index(c))) + ",";
    return q;
  };
  std::size_t base = t.row_count(), vertex0 = t.row_count();
  for (std::size_t i = 0; i < t.row_count(); ++i)
    if (t.cell(i, kind) == "base") base = i;
  ASSERT_LT(base, t.row_count());
  for (std::size_t i = 0; i < t.row_count() && vertex0 == t.row_count(); ++i)
    if (i != base && joints(i) == joints(base)) vertex0 = i;
  ASSERT_LT(vertex0, t.row_count()) << "the simulated grid has no vertex at its base point";

  // Measured once, as the base row (the vertex-0 target row dropped): the base completes the grid.
  rewrite("grid.csv", "once.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {}, keep_all,
          [&](std::size_t i) { return i != vertex0; });
  const auto a = run("fit --robot kr16 --data " + path("once.csv") + " --method distance-idw --out " + path("a.json"));
  EXPECT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.out.find("grid vertex"), std::string::npos) << a.out;
  // Measured once, as the vertex-0 target with its distance to itself: exactly 0.
  const std::size_t dist = t.column_index("dist_b0");
  auto with_dist = [&](const std::string& value, std::size_t row) {
    rewrite("grid.csv", "zero.csv", [&](const CsvTable&, std::size_t i, std::vector<std::string>& cells) {
      if (i == row) cells[dist] = value;
    });
  };
  with_dist("0", vertex0);
  const auto b = run("fit --robot kr16 --data " + path("zero.csv") + " --method distance-idw --out " + path("b.json"));
  EXPECT_EQ(b.exit_code, 0) << b.err;
  // Calibration from the distances skips that pair (no direction) instead of refusing the file.
  const auto cal = run("calibrate --robot kr16 --data " + path("zero.csv") + " --out " + path("cal.json"));
  EXPECT_EQ(cal.exit_code, 0) << cal.err;
  // Both models compensate the grid's targets (the one at the base point itself has no direction:
  // refused, never ok).
  for (const char* m : {"a.json", "b.json"}) {
    const auto c = run(std::string("compensate --model ") + path(m) + " --targets " + path("grid.csv") + " --out " +
                       path("c.csv"));
    EXPECT_EQ(c.exit_code, 0) << m << ": " << c.err;
    const auto status = column("c.csv", "status");
    EXPECT_EQ(std::count(status.begin(), status.end(), "ok"), static_cast<long>(t.row_count()) - 2) << m;
  }
  // Still refused: a negative distance there, and 0 on a row that is not the base point.
  with_dist("-0.5", vertex0);
  expect_refused(run("fit --robot kr16 --data " + path("zero.csv") + " --method distance-idw --out " + path("c.json")), 2,
                 {"zero.csv", "dist_b0"});
  with_dist("0", vertex0 + 1);
  expect_refused(run("fit --robot kr16 --data " + path("zero.csv") + " --method distance-idw --out " + path("c.json")), 2,
                 {"zero.csv", "dist_b0", "expected a distance > 0"});
}

// ---- item 3: the total correction, and a ceiling on it --------------------------------------

/// Joints in columns `prefix`1..6 of row `i` (empty cells: NaN).
robot::JointVector joints_of(const CsvTable& t, std::size_t i, const std::string& prefix) {
  robot::JointVector q;
  for (int k = 0; k < 6; ++k) {
    const std::string cell(t.cell(i, t.column_index(prefix + std::to_string(k + 1))));
    q[k] = cell.empty() ? std::nan("") : std::stod(cell);
  }
  return q;
}
double cell_of(const CsvTable& t, std::size_t i, const std::string& column) {
  const std::string cell(t.cell(i, t.column_index(column)));
  return cell.empty() ? std::nan("") : std::stod(cell);
}

TEST_F(WrongCommand, CompensateWritesTheTotalCorrectionAndRefusesMovesBeyondTheCeiling) {
  // A calibrated KR16 (SIMULATED, scattered joints, reflector 2.7 mm off the JSON's tool: the same
  // point as far as the tool goes): pred_dx..dz are empty of the calibration, total_* and move_mm
  // are not. Checked against the FK of the model file's own calibrated and nominal robots.
  ASSERT_EQ(run("simulate --robot kr16 --seed 11 --sample scattered:60 --joint-box " + std::string(kJointBox) +
                " --tool-offset 1,-2,1.5 --joint-decimals 3 --measure positions --robot-out " + path("r.json") +
                " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  ASSERT_EQ(run("simulate --robot kr16 --seed 12 --sample scattered:25 --joint-box " + std::string(kJointBox) +
                " --measure positions --out " + path("held.csv")).exit_code,
            0);
  rewrite("held.csv", "q.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& c) { return c.size() == 2 && c[0] == 'q'; });
  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("q.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const nlohmann::json model = read_json("k.json");
  const robot::MdhModel calibrated = robot::MdhModel::from_json(model["command_model"]);
  const robot::MdhModel nominal = robot::MdhModel::load(path("r.json"));
  // The default ceiling: 3 x the largest calibration correction at the training joints, >= 1 mm.
  double largest = 0.0;
  for (const auto& q : model["data_joints_deg"]) {
    robot::JointVector v;
    for (int k = 0; k < 6; ++k) v[k] = q[static_cast<std::size_t>(k)].get<double>();
    largest = std::max(largest, (robot::forward_position(calibrated, v) - robot::forward_position(nominal, v)).norm());
  }
  ASSERT_GT(largest, 0.3);  // the simulated robot's errors are worth correcting
  const double ceiling = std::max(3.0 * largest, 1.0);
  EXPECT_NE(c.out.find("ceiling " + format_number(std::round(ceiling * 1000.0) / 1000.0) + " mm"), std::string::npos) << c.out;
  const CsvTable out = CsvTable::read(path("c.csv"));
  std::vector<double> moves;
  for (std::size_t i = 0; i < out.row_count(); ++i) {
    ASSERT_EQ(out.row(i)[out.column_index("status")], "ok") << "row " << i;
    const robot::JointVector nq = joints_of(out, i, "nq"), cq = joints_of(out, i, "cq");
    const Eigen::Vector3d total = robot::forward_position(calibrated, nq) - robot::forward_position(nominal, nq);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(cell_of(out, i, std::string("total_d") + "xyz"[k]), total[k], 1e-6) << "row " << i;
      EXPECT_NEAR(cell_of(out, i, std::string("pred_d") + "xyz"[k]), 0.0, 1e-12);  // the field's part: none
    }
    EXPECT_NEAR(cell_of(out, i, "total_mm"), total.norm(), 1e-6);
    const double move = (robot::forward_position(nominal, cq) - robot::forward_position(nominal, nq)).norm();
    EXPECT_NEAR(cell_of(out, i, "move_mm"), move, 1e-6) << "row " << i;
    // The joints move the tool by the correction (to first order in its size).
    EXPECT_NEAR(move, total.norm(), 0.02 * total.norm() + 1e-3) << "row " << i;
    EXPECT_LE(move, ceiling);
    moves.push_back(move);
  }

  // A ceiling below some moves: exactly those rows are refused, with no joints.
  std::vector<double> sorted = moves;
  std::sort(sorted.begin(), sorted.end());
  const double limit = sorted[sorted.size() / 2];
  const auto low = run("compensate --model " + path("k.json") + " --targets " + path("q.csv") + " --max-correction " +
                       format_number(limit) + " --out " + path("low.csv"));
  ASSERT_EQ(low.exit_code, 0) << low.err;
  EXPECT_NE(low.err.find("correction-too-large"), std::string::npos) << low.err;
  const CsvTable capped = CsvTable::read(path("low.csv"));
  std::size_t refused = 0;
  for (std::size_t i = 0; i < capped.row_count(); ++i) {
    const bool over = moves[i] > limit;
    refused += over;
    EXPECT_EQ(capped.row(i)[capped.column_index("status")], over ? "correction-too-large" : "ok") << "row " << i;
    EXPECT_EQ(capped.row(i)[capped.column_index("cq1")].empty(), over) << "row " << i;
  }
  EXPECT_GT(refused, 5u);

  // The wrong tool at compensate time (30 mm along the flange z): every target would move the tool
  // point ~30 mm; before, all rows came back ok. Now every one is refused.
  nlohmann::json wrong = read_json("r.json");
  wrong["tool"]["z_mm"] = wrong["tool"].value("z_mm", 0.0) + 30.0;
  write_json("wrong.json", wrong);
  const std::string wrong_run = "compensate --robot " + path("wrong.json") + " --model " + path("k.json") + " --targets " +
                                path("q.csv");
  const auto w = run(wrong_run + " --out " + path("w.csv"));
  // None is ok (rows the calibrated model cannot reach with that tool are refused by IK): a failed
  // job, nothing written, the refusals counted by status.
  EXPECT_EQ(w.exit_code, 1) << w.err;
  EXPECT_FALSE(std::filesystem::exists(path("w.csv")));
  std::smatch too_large;
  ASSERT_TRUE(std::regex_search(w.err, too_large, std::regex("correction-too-large ([0-9]+)"))) << w.err;
  EXPECT_GT(std::stoi(too_large[1].str()), 20) << w.err;
  // What those rows would do: with the ceiling out of the way, every row the IK solves moves the tool
  // point by ~30 mm, beyond the default ceiling (checked above) by far.
  ASSERT_LT(ceiling, 20.0);
  const auto raised = run(wrong_run + " --max-correction 1000 --out " + path("w.csv"));
  ASSERT_EQ(raised.exit_code, 0) << raised.err;
  const auto status = column("w.csv", "status"), move = column("w.csv", "move_mm");
  EXPECT_EQ(std::count(status.begin(), status.end(), "ok"), std::stoi(too_large[1].str()));
  for (std::size_t i = 0; i < status.size(); ++i)
    if (!move[i].empty()) {
      EXPECT_GT(std::stod(move[i]), 20.0) << "row " << i;
      EXPECT_EQ(status[i], "ok") << "row " << i;
    }
  // A negative ceiling is an argument error.
  EXPECT_EQ(run("compensate --model " + path("k.json") + " --targets " + path("q.csv") +
                " --max-correction -1 --out " + path("x.csv")).exit_code,
            2);
}

// ---- item 2: the tool point and the reflector are two points --------------------------------

TEST_F(WrongCommand, ReflectorFarFromTheToolIsRefusedOrAimsTheToolPoint) {
  // A KR16 (SIMULATED, scattered joints) measured at a reflector 150 mm from its tool point (a second
  // nest), the robot JSON carrying the tool point. Before: fit said nothing and compensate aimed the
  // reflector at the tool point's targets (rows ok, joints moving the tool ~150 mm).
  ASSERT_EQ(run("simulate --robot kr16 --seed 21 --sample scattered:60 --joint-box " + std::string(kJointBox) +
                " --tool-offset 0,150,0 --joint-decimals 3 --measure positions --robot-out " + path("r.json") +
                " --out " + path("train.csv")).exit_code,
            0);
  const std::string fit = "fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                          path("k.json");
  expect_refused(run(fit), 2, {"train.csv", "reflector", "mm from the robot JSON's tool point", "--reflector-far-ok"});
  EXPECT_FALSE(std::filesystem::exists(path("k.json")));
  const auto f = run(fit + " --reflector-far-ok");
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.err.find("every 0.01 deg of flange orientation error"), std::string::npos) << f.err;

  // The model stores both points: the reflector as identified (the command model's tool, what
  // predict and validate score) and the tool point compensate aims (the robot JSON's tool).
  const nlohmann::json model = read_json("k.json");
  const robot::MdhModel calibrated = robot::MdhModel::from_json(model["command_model"]);
  const robot::MdhModel nominal = robot::MdhModel::load(path("r.json"));
  ASSERT_EQ(model["reflector_mm"].size(), 3u);
  ASSERT_EQ(model["tool_point_mm"].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(model["reflector_mm"][static_cast<std::size_t>(k)].get<double>(), calibrated.tool().translation()[k]);
    EXPECT_DOUBLE_EQ(model["tool_point_mm"][static_cast<std::size_t>(k)].get<double>(), nominal.tool().translation()[k]);
  }
  EXPECT_NEAR((calibrated.tool().translation() - nominal.tool().translation()).norm(), 150.0, 2.0);

  ASSERT_EQ(run("simulate --robot kr16 --seed 22 --sample scattered:20 --joint-box " + std::string(kJointBox) +
                " --measure positions --out " + path("held.csv")).exit_code,
            0);
  rewrite("held.csv", "q.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& c) { return c.size() == 2 && c[0] == 'q'; });
  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("q.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  // Independent: the calibrated flange carrying the robot JSON's tool lands on each target; the
  // calibrated reflector does not (it stays ~150 mm away); the joints move the tool by millimetres.
  Eigen::Isometry3d tool = calibrated.tool();
  tool.translation() = nominal.tool().translation();
  const robot::MdhModel calibrated_tool = calibrated.with_tool(tool);
  const CsvTable out = CsvTable::read(path("c.csv"));
  for (std::size_t i = 0; i < out.row_count(); ++i) {
    ASSERT_EQ(out.row(i)[out.column_index("status")], "ok") << "row " << i;
    const robot::JointVector nq = joints_of(out, i, "nq"), cq = joints_of(out, i, "cq");
    const Eigen::Vector3d target = robot::forward_position(nominal, nq);
    EXPECT_LT((robot::forward_position(calibrated_tool, cq) - target).norm(), 1e-3) << "row " << i;
    EXPECT_GT((robot::forward_position(calibrated, cq) - target).norm(), 100.0) << "row " << i;
    EXPECT_LT(cell_of(out, i, "move_mm"), 10.0) << "row " << i;
  }
  // A tool-less robot JSON for data measured at a tool 150 mm out is the same mistake.
  nlohmann::json bare = read_json("r.json");
  bare.erase("tool");
  write_json("bare.json", bare);
  ASSERT_EQ(run("simulate --robot kr16 --seed 23 --sample scattered:40 --joint-box " + std::string(kJointBox) +
                " --tool-offset 0,0,150 --measure positions --out " + path("tooled.csv")).exit_code,
            0);
  expect_refused(run("fit --robot " + path("bare.json") + " --data " + path("tooled.csv") +
                     " --method kinematic+kriging --out " + path("b.json")),
                 2, {"tooled.csv", "reflector", "--reflector-far-ok"});
}

// ---- item 8: the arm configuration is explicit ------------------------------------------------

TEST_F(WrongCommand, PoseTargetsKeepTheirSeedsArmConfiguration) {
  // A calibrated KR16 (SIMULATED) with wrists bent both ways (q5 in +-100 deg); pose targets are
  // the FK of taught joints, each given twice: seeded with the taught joints, and with the other
  // wrist solution of the same pose (q4 + 180, -q5, q6 + 180). Before: no seed per row and no
  // configuration in the output (on 60 held-out poses of this set-up without seeds, 7 came back ok
  // on the other wrist solution than the taught one: the nearest training sample's).
  const std::string box = "-40,40,-80,-30,0,60,-90,90,-100,100,-90,90";
  ASSERT_EQ(run("simulate --robot kr16 --seed 31 --sample scattered:60 --joint-box " + box +
                " --measure positions --robot-out " + path("r.json") + " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  const robot::MdhModel nominal = robot::MdhModel::load(path("r.json"));
  // Taught joints well away from the wrist singularity (|q5| >= 20 deg), deterministic.
  std::vector<robot::JointVector> taught;
  for (int i = 0; i < 12; ++i) {
    robot::JointVector q;
    q << -30.0 + 5.0 * i, -60.0 + 2.0 * (i % 5), 20.0 + 3.0 * (i % 4), -70.0 + 13.0 * i, (i % 2 ? 1 : -1) * (25.0 + 5.0 * i),
        -60.0 + 11.0 * i;
    taught.push_back(q);
  }
  std::string text = "x,y,z,rx,ry,rz,sq1,sq2,sq3,sq4,sq5,sq6\n";
  auto row = [&](const robot::JointVector& pose_q, const robot::JointVector& seed) {
    const robot::PoseXyzRpy p = robot::to_xyz_rpy(robot::forward_kinematics(nominal, pose_q));
    std::string l;
    for (double v : {p.x_mm, p.y_mm, p.z_mm, p.rx_deg, p.ry_deg, p.rz_deg}) l += format_number(v) + ",";
    for (int k = 0; k < 6; ++k) l += format_number(seed[k]) + (k < 5 ? "," : "\n");
    text += l;
  };
  std::vector<robot::JointVector> seeds;
  for (const auto& q : taught) {
    robot::JointVector flipped = q;
    flipped[3] += q[3] > 0 ? -180.0 : 180.0;
    flipped[4] = -q[4];
    flipped[5] += q[5] > 0 ? -180.0 : 180.0;
    row(q, q);
    row(q, flipped);  // the same pose
    seeds.push_back(q);
    seeds.push_back(flipped);
  }
  write("poses.csv", text);
  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("poses.csv") + " --out " +
                     path("c.csv"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const CsvTable out = CsvTable::read(path("c.csv"));
  ASSERT_EQ(out.row_count(), seeds.size());
  std::size_t ok = 0;
  for (std::size_t i = 0; i < out.row_count(); ++i) {
    const std::string status = out.row(i)[out.column_index("status")];
    if (status != "ok") continue;
    ++ok;
    const robot::JointVector cq = joints_of(out, i, "cq");
    // Independent of errfield's flags: the solution is the seed's (a flipped wrist would put q5's
    // sign the other way and q4, q6 ~180 deg off), and it is a solution of the row's pose.
    EXPECT_EQ(cq[4] > 0, seeds[i][4] > 0) << "row " << i << ": q5 " << cq[4] << " vs seed " << seeds[i][4];
    for (int k : {0, 3, 5}) EXPECT_LT(std::abs(cq[k] - seeds[i][k]), 20.0) << "row " << i << " q" << k + 1;
    // The configuration column says so: the two rows of one pose differ in the wrist flag only.
    const std::string config = out.row(i)[out.column_index("config")];
    ASSERT_EQ(config.size(), 6u) << config;
    EXPECT_EQ(config, out.row(i)[out.column_index("nconfig")]);
  }
  EXPECT_GE(ok, 20u);
  // Joint targets near the wrist singularity (q5 = +-0.2 deg): a compensation that crosses q5 = 0
  // by a fraction of a degree keeps the configuration (the flag is undetermined there).
  std::string near = "q1,q2,q3,q4,q5,q6\n";
  for (std::size_t i = 0; i < 6; ++i) {
    robot::JointVector q = taught[i];
    q[4] = i % 2 ? 0.2 : -0.2;
    for (int k = 0; k < 6; ++k) near += format_number(q[k]) + (k < 5 ? "," : "\n");
  }
  // And one taught pose away from the singularity, compensated, so that the file is written (a job
  // that compensates nothing writes none).
  for (int k = 0; k < 6; ++k) near += format_number(taught[6][k]) + (k < 5 ? "," : "\n");
  write("near.csv", near);
  const auto nr = run("compensate --model " + path("k.json") + " --targets " + path("near.csv") + " --out " + path("n.csv"));
  ASSERT_EQ(nr.exit_code, 0) << nr.err;
  const auto near_status = column("n.csv", "status"), near_config = column("n.csv", "nconfig");
  ASSERT_EQ(near_status.size(), 7u);
  EXPECT_EQ(near_status[6], "ok");
  for (const auto& st : near_status) EXPECT_NE(st, "config-change");
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(near_config[i].substr(4), "w0") << near_config[i];
  for (std::size_t i = 0; i + 1 < out.row_count(); i += 2) {
    const std::string a = out.row(i)[out.column_index("nconfig")], b = out.row(i + 1)[out.column_index("nconfig")];
    if (a.empty() || b.empty()) continue;
    EXPECT_EQ(a.substr(0, 4), b.substr(0, 4)) << "rows " << i << ", " << i + 1;
    EXPECT_NE(a[5], b[5]) << "rows " << i << ", " << i + 1 << ": " << a << " " << b;
  }
}

// ---- issue 35: data that do not fit the model, configuration never silent -------------------

// UR5e joints (deg), scattered: not the built-in ER20-C10 set-up, wrists bent both ways.
constexpr const char* kUrBox = "-90,90,-120,-40,40,120,-120,-40,40,120,-90,90";

TEST_F(WrongCommand, JointsInRadiansAreRefusedAgainstTheTrainingJoints) {
  // A calibrated UR5e (SIMULATED). Held-out joints written in radians lie within +-2 pi "deg",
  // inside the training box: before, predict and compensate gave every row ok.
  ASSERT_EQ(run("simulate --robot ur5e --seed 41 --sample scattered:40 --joint-box " + std::string(kUrBox) +
                " --measure positions --robot-out " + path("r.json") + " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  ASSERT_EQ(run("simulate --robot ur5e --seed 42 --sample scattered:12 --joint-box " + std::string(kUrBox) +
                " --measure positions --out " + path("held.csv")).exit_code,
            0);
  auto q_only = [](const std::string& c) { return c.size() == 2 && c[0] == 'q'; };
  rewrite("held.csv", "deg.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {}, q_only);
  rewrite("held.csv", "rad.csv", [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
    for (int k = 1; k <= 6; ++k) {
      const std::size_t c = t.column_index("q" + std::to_string(k));
      row[c] = format_number(t.numeric_cell(i, c) * std::numbers::pi / 180.0);
    }
  }, q_only);
  const auto pr = run("predict --model " + path("k.json") + " --joints " + path("rad.csv") + " --out " + path("p.csv"));
  expect_refused(pr, 2, {"rad.csv", "radians", "--joints-are-degrees"});
  EXPECT_FALSE(std::filesystem::exists(path("p.csv")));
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("rad.csv") + " --out " + path("c.csv")),
                 2, {"rad.csv", "radians", "--joints-are-degrees"});
  // The same joints in degrees go through. The override, and a model file without training joints
  // (older files), pass the radians check; the 13 rows (12 poses and the base point), all within
  // 2.6 "deg" of zero, then lie far beyond the poses the calibration determined: every row
  // calibration-extrapolated (exit 1, not the radians refusal's 2).
  EXPECT_EQ(run("predict --model " + path("k.json") + " --joints " + path("deg.csv") + " --out " + path("p.csv")).exit_code, 0);
  EXPECT_EQ(run("compensate --model " + path("k.json") + " --targets " + path("deg.csv") + " --out " + path("c.csv")).exit_code, 0);
  expect_refused(run("predict --model " + path("k.json") + " --joints " + path("rad.csv") + " --joints-are-degrees --out " +
                     path("p2.csv")),
                 1, {"calibration-extrapolated 13"});
  nlohmann::json old = read_json("k.json");
  ASSERT_TRUE(old.contains("data_joints_deg"));
  old.erase("data_joints_deg");
  write_json("old.json", old);
  expect_refused(run("predict --model " + path("old.json") + " --joints " + path("rad.csv") + " --out " + path("p3.csv")), 1,
                 {"calibration-extrapolated 13"});
}

TEST_F(WrongCommand, ValidateRefusesReadingsOfAnotherPointNamingTheDistance) {
  // One SIMULATED KR16 measured at the same scattered joints with two reflectors 150 mm apart
  // (same seed: same robot, same joints). A model of reflector A scored on B's readings exited 0
  // with 150 mm "after" errors: the registration check fits a free reflector offset.
  const std::string box = "-50,50,-90,-30,10,70,-90,90,-100,-20,-120,120";
  for (const char* which : {"a", "b"})
    ASSERT_EQ(run("simulate --robot kr16 --seed 51 --sample scattered:70 --joint-box " + box + " --tool-offset " +
                  (which[0] == 'a' ? "10,0,40" : "160,0,40") + " --measure positions --robot-out " + path("r.json") +
                  " --out " + path(std::string(which) + ".csv")).exit_code,
              0);
  const CsvTable a = CsvTable::read(path("a.csv")), b = CsvTable::read(path("b.csv"));
  ASSERT_EQ(a.row_count(), b.row_count());
  for (std::size_t i = 0; i < a.row_count(); ++i) ASSERT_EQ(a.cell(i, a.column_index("q5")), b.cell(i, b.column_index("q5")));
  auto keep = [](const std::string&) { return true; };
  auto none = [](const CsvTable&, std::size_t, std::vector<std::string>&) {};
  rewrite("a.csv", "train.csv", none, keep, [](std::size_t i) { return i < 50; });
  rewrite("a.csv", "held_a.csv", none, keep, [](std::size_t i) { return i >= 50; });
  rewrite("b.csv", "held_b.csv", none, keep, [](std::size_t i) { return i >= 50; });
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  const auto same = run("validate --model " + path("k.json") + " --data " + path("held_a.csv"));
  EXPECT_EQ(same.exit_code, 0) << same.err;
  const auto other = run("validate --model " + path("k.json") + " --data " + path("held_b.csv") + " --out " + path("v.csv"));
  expect_refused(other, 2, {"held_b.csv", "another point", "mm from the point the model was fitted for"});
  EXPECT_FALSE(std::filesystem::exists(path("v.csv")));
  // The distance named is the reflectors' 150 mm (to the calibration's absorption of a few mm).
  const std::size_t at = other.err.find(" mm from the point");
  ASSERT_NE(at, std::string::npos);
  const std::size_t start = other.err.rfind(' ', at - 1) + 1;
  EXPECT_NEAR(std::stod(other.err.substr(start, at - start)), 150.0, 3.0) << other.err;
}

TEST_F(WrongCommand, CompensateSaysWhereEachConfigurationCameFromAndPinsOne) {
  // A calibrated KR16 (SIMULATED) with wrists bent both ways; pose targets from taught joints, half
  // of them with the taught joints as seeds. Before: no column said where a row's configuration
  // came from, and there was no way to ask for one.
  const std::string box = "-40,40,-80,-30,0,60,-90,90,-100,100,-90,90";
  ASSERT_EQ(run("simulate --robot kr16 --seed 31 --sample scattered:60 --joint-box " + box +
                " --measure positions --robot-out " + path("r.json") + " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  const robot::MdhModel nominal = robot::MdhModel::load(path("r.json"));
  std::string seeded = "x,y,z,rx,ry,rz,sq1,sq2,sq3,sq4,sq5,sq6\n", bare = "x,y,z,rx,ry,rz\n", joints = "q1,q2,q3,q4,q5,q6\n";
  const int n = 8;
  for (int i = 0; i < n; ++i) {
    robot::JointVector q;
    q << -30.0 + 7.0 * i, -60.0 + 2.0 * (i % 5), 20.0 + 3.0 * (i % 4), -60.0 + 15.0 * i,
        (i % 2 ? 1 : -1) * (30.0 + 5.0 * i), -50.0 + 12.0 * i;
    const robot::PoseXyzRpy p = robot::to_xyz_rpy(robot::forward_kinematics(nominal, q));
    std::string pose;
    for (double v : {p.x_mm, p.y_mm, p.z_mm, p.rx_deg, p.ry_deg, p.rz_deg}) pose += format_number(v) + ",";
    std::string seed, qs;
    for (int k = 0; k < 6; ++k) {
      seed += (i < n / 2 ? format_number(q[k]) : std::string()) + (k < 5 ? "," : "\n");
      qs += format_number(q[k]) + (k < 5 ? "," : "\n");
    }
    seeded += pose + seed;
    bare += pose.substr(0, pose.size() - 1) + "\n";
    joints += qs;
  }
  write("seeded.csv", seeded);
  write("bare.csv", bare);
  write("joints.csv", joints);
  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("seeded.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto source = column("c.csv", "config_source");
  ASSERT_EQ(source.size(), static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) EXPECT_EQ(source[static_cast<std::size_t>(i)], i < n / 2 ? "seed" : "nearest-training") << i;
  EXPECT_NE(c.out.find("4 seed, 4 nearest-training"), std::string::npos) << c.out;
  ASSERT_EQ(run("compensate --model " + path("k.json") + " --targets " + path("joints.csv") + " --out " + path("j.csv")).exit_code, 0);
  for (const auto& w : column("j.csv", "config_source")) EXPECT_EQ(w, "given");

  // --config: every ok row on the pinned configuration, whichever wrist the pose was taught with.
  // Independent of errfield's flags: the wrist solutions of one pose differ in q5's sign, so all ok
  // rows of one pin share q5's sign, and the two pins' signs differ.
  std::string shoulder_elbow;
  for (const auto& cfg : column("j.csv", "nconfig"))
    if (cfg.size() == 6 && shoulder_elbow.empty()) shoulder_elbow = cfg.substr(0, 4);
  ASSERT_EQ(shoulder_elbow.size(), 4u);
  int sign_of_pin[2] = {0, 0};
  for (int w = 0; w < 2; ++w) {
    const std::string pin = shoulder_elbow + (w ? "w-" : "w+");
    const auto r = run("compensate --model " + path("k.json") + " --targets " + path("bare.csv") + " --config " + pin +
                       " --out " + path("pin.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(std::to_string(n) + " config-option"), std::string::npos) << r.out;
    const CsvTable out = CsvTable::read(path("pin.csv"));
    int ok = 0;
    for (std::size_t i = 0; i < out.row_count(); ++i) {
      if (out.cell(i, out.column_index("status")) != "ok") continue;
      ++ok;
      EXPECT_EQ(out.cell(i, out.column_index("config")), pin) << i;
      const int sign = cell_of(out, i, "cq5") > 0 ? 1 : -1;
      if (sign_of_pin[w] == 0) sign_of_pin[w] = sign;
      EXPECT_EQ(sign, sign_of_pin[w]) << pin << " row " << i;
    }
    EXPECT_GE(ok, n / 2) << pin << "\n" << r.out << r.err;
  }
  EXPECT_EQ(sign_of_pin[0], -sign_of_pin[1]);
  // A pinned configuration the given joints are not on is refused, row by row.
  const auto jp = run("compensate --model " + path("k.json") + " --targets " + path("joints.csv") + " --config " +
                      shoulder_elbow + "w+ --out " + path("jp.csv"));
  ASSERT_EQ(jp.exit_code, 0) << jp.err;
  const auto jstatus = column("jp.csv", "status");
  const auto jconfig = column("jp.csv", "nconfig");
  for (std::size_t i = 0; i < jstatus.size(); ++i)
    if (jconfig[i].size() == 6 && jconfig[i].substr(4) == "w-") EXPECT_EQ(jstatus[i], "config-change") << i;
    else EXPECT_NE(jstatus[i], "config-change") << i;

  // Seeds the robot cannot take and bad --config text: exit 2 naming the row, column or option.
  rewrite("seeded.csv", "bad_seed.csv", [](const CsvTable& t, std::size_t i, std::vector<std::string>& row) {
    if (i == 2) row[t.column_index("sq5")] = "400";
  });
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("bad_seed.csv") + " --out " + path("x.csv")),
                 2, {"bad_seed.csv:" + std::to_string(CsvTable::read(path("bad_seed.csv")).line_of_row(2)), "sq5", "400",
                     "limits"});
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("bare.csv") +
                     " --seed 0,-60,20,0,1e6,0 --out " + path("x.csv")),
                 2, {"--seed", "joint 5"});
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("bare.csv") + " --config s+e+w0 --out " +
                     path("x.csv")),
                 2, {"--config", "s+e+w0"});
  EXPECT_FALSE(std::filesystem::exists(path("x.csv")));
}

TEST_F(WrongCommand, CompensateRefusesJointSwingsAtASingularWrist) {
  // A calibrated UR5e (SIMULATED). At q5 = +-1e-7 (axes 4 and 6 aligned) a few-mm correction with
  // the orientation kept turned q4 and q6 by 47-81 deg, status ok. The same joints at q5 = 30 and
  // -45 deg are ordinary rows.
  ASSERT_EQ(run("simulate --robot ur5e --seed 41 --sample scattered:40 --joint-box " + std::string(kUrBox) +
                " --measure positions --robot-out " + path("r.json") + " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  const double base[3][6] = {{10, -70, 90, -60, 0, -40}, {40, -100, 70, -80, 0, 60}, {-20, -90, 80, -70, 0, 30}};
  std::string text = "q1,q2,q3,q4,q5,q6\n";
  std::vector<double> q5s;
  for (const auto& b : base)
    for (double q5 : {1e-7, -1e-7, 30.0, -45.0}) {
      for (int k = 0; k < 6; ++k) text += format_number(k == 4 ? q5 : b[k]) + (k < 5 ? "," : "\n");
      q5s.push_back(q5);
    }
  write("sing.csv", text);
  const auto c = run("compensate --model " + path("k.json") + " --targets " + path("sing.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const CsvTable out = CsvTable::read(path("c.csv"));
  int singular = 0, ordinary_ok = 0;
  for (std::size_t i = 0; i < out.row_count(); ++i) {
    const std::string status(out.cell(i, out.column_index("status")));
    if (std::abs(q5s[i]) < 1e-3) {
      EXPECT_NE(status, "ok") << "row " << i << " at the wrist singularity";
      singular += status == "wrist-singular";
      continue;
    }
    // Away from it: ok, and the joints turn by about move / reach (here < 1 deg for < 5 mm),
    // computed from the written joints, far below the bound.
    EXPECT_EQ(status, "ok") << "row " << i;
    if (status != "ok") continue;
    ++ordinary_ok;
    const double swing = (joints_of(out, i, "cq") - joints_of(out, i, "nq")).cwiseAbs().maxCoeff();
    EXPECT_LT(swing, 0.5 * std::max(2.0, 2.865 * cell_of(out, i, "move_mm"))) << "row " << i;
  }
  EXPECT_GE(singular, 2) << c.err;  // some rows at q5 = 0 do not converge at all (ik-max_iterations)
  EXPECT_EQ(ordinary_ok, 6);
  EXPECT_NE(c.err.find("singular configuration"), std::string::npos) << c.err;
}

// ---- issue 35 item 6: the frame of targets ----------------------------------------------------

// Targets were read in the robot base frame with no way to give a part measured with the tracker.
// `--frame tracker` maps them with the registration the model stores (checked here against that
// matrix read from the model file and applied in the test), and says so in a column and a line.
TEST_F(WrongCommand, TrackerFrameTargetsAreMappedWithTheModelsRegistration) {
  // A calibrated KR16 (SIMULATED, scattered joints); held-out poses measured by the tracker.
  ASSERT_EQ(run("simulate --robot kr16 --seed 11 --sample scattered:60 --joint-box " + std::string(kJointBox) +
                " --measure positions --robot-out " + path("r.json") + " --out " + path("train.csv")).exit_code,
            0);
  ASSERT_EQ(run("fit --robot " + path("r.json") + " --data " + path("train.csv") + " --method kinematic --out " +
                path("k.json")).exit_code,
            0);
  ASSERT_EQ(run("simulate --robot kr16 --seed 12 --sample scattered:6 --joint-box " + std::string(kJointBox) +
                " --measure positions --out " + path("held.csv")).exit_code,
            0);
  // robot ← tracker, from the model file's 3 x 4 [R | t].
  const nlohmann::json reg = read_json("k.json")["registration"]["robot_from_tracker"];
  Eigen::Isometry3d robot_from_tracker = Eigen::Isometry3d::Identity();
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 4; ++c) robot_from_tracker.matrix()(r, c) = reg[r][c].get<double>();
  const robot::MdhModel nominal = robot::MdhModel::load(path("r.json"));
  // Targets: where the tracker saw the tool point (mx,my,mz), with the orientation the nominal robot
  // has at those joints; the same poses once in the tracker frame and once mapped here.
  const CsvTable held = CsvTable::read(path("held.csv"));
  std::vector<robot::JointVector> measured_at;
  std::vector<Eigen::Vector3d> in_robot;
  std::string tracker_text = "x,y,z,rx,ry,rz,sq1,sq2,sq3,sq4,sq5,sq6\n", robot_text = tracker_text;
  for (std::size_t i = 0; i < held.row_count(); ++i) {
    if (held.cell(i, held.column_index("kind")) != "target") continue;
    const robot::JointVector q = joints_of(held, i, "q");
    const Eigen::Vector3d m(cell_of(held, i, "mx"), cell_of(held, i, "my"), cell_of(held, i, "mz"));
    const Eigen::Matrix3d r_robot = robot::forward_kinematics(nominal, q).rotation();
    const Eigen::Vector3d rpy_tracker = robot::rpy_deg_from_rotation(robot_from_tracker.linear().transpose() * r_robot);
    const Eigen::Vector3d rpy_robot = robot::rpy_deg_from_rotation(r_robot);
    const Eigen::Vector3d p = robot_from_tracker * m;
    std::string seeds;
    for (int k = 0; k < 6; ++k) seeds += "," + format_number(q[k]);
    tracker_text += format_number(m.x()) + "," + format_number(m.y()) + "," + format_number(m.z());
    for (int k = 0; k < 3; ++k) tracker_text += "," + format_number(rpy_tracker[k]);
    robot_text += format_number(p.x()) + "," + format_number(p.y()) + "," + format_number(p.z());
    for (int k = 0; k < 3; ++k) robot_text += "," + format_number(rpy_robot[k]);
    tracker_text += seeds + "\n";
    robot_text += seeds + "\n";
    measured_at.push_back(q);
    in_robot.push_back(p);
  }
  ASSERT_EQ(measured_at.size(), 6u);
  write("tracker.csv", tracker_text);
  write("robot.csv", robot_text);
  const auto t = run("compensate --model " + path("k.json") + " --targets " + path("tracker.csv") + " --frame tracker --out " +
                     path("ct.csv"));
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_NE(t.out.find("in the tracker frame (--frame tracker), mapped into the robot base frame"), std::string::npos) << t.out;
  const auto r = run("compensate --model " + path("k.json") + " --targets " + path("robot.csv") + " --out " + path("cr.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("targets x,y,z,rx,ry,rz in the robot base frame"), std::string::npos) << r.out;
  const CsvTable ct = CsvTable::read(path("ct.csv")), cr = CsvTable::read(path("cr.csv"));
  for (std::size_t i = 0; i < measured_at.size(); ++i) {
    ASSERT_EQ(ct.cell(i, ct.column_index("status")), "ok") << "row " << i;
    ASSERT_EQ(cr.cell(i, cr.column_index("status")), "ok") << "row " << i;
    EXPECT_EQ(ct.cell(i, ct.column_index("frame")), "tracker");
    EXPECT_EQ(cr.cell(i, cr.column_index("frame")), "robot");
    // The target in the robot frame (nx..nz: the nominal FK of the solved joints) is R m + t, and
    // every result equals the run on the poses mapped here (to rounding of the mapping).
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(cell_of(ct, i, std::string("n") + "xyz"[k]), in_robot[i][k], 1e-6) << "row " << i;
    for (const std::string prefix : {"nq", "cq"}) {
      const robot::JointVector a = joints_of(ct, i, prefix), b = joints_of(cr, i, prefix);
      EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9) << "row " << i << " " << prefix;
    }
    for (const std::string c : {"cmd_x", "cmd_y", "cmd_z", "total_dx", "total_dy", "total_dz", "move_mm"})
      EXPECT_NEAR(cell_of(ct, i, c), cell_of(cr, i, c), 1e-9) << "row " << i << " " << c;
    // End to end: the joints that put the tool point on the tracker's reading are, to the model's
    // accuracy (its registration residual RMS), the joints it was read at, while the uncompensated
    // joints of that point are millimetres away.
    const robot::JointVector cq = joints_of(ct, i, "cq");
    const double off = (robot::forward_position(nominal, cq) - robot::forward_position(nominal, measured_at[i])).norm();
    EXPECT_LT(off, 3.0 * read_json("k.json")["registration"]["residual_rms_mm"].get<double>()) << "row " << i;
    EXPECT_GT(cell_of(ct, i, "move_mm"), 5.0 * off) << "row " << i;
  }

  // What is refused (exit 2, naming the option or the column): a frame errfield does not know;
  // joint targets, which have no frame; a model without a registration; a file whose frame column
  // says another frame than --frame (compensate's own output run again without it).
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("tracker.csv") + " --frame world --out " +
                     path("x.csv")),
                 2, {"--frame", "'world'", "robot", "tracker"});
  write("q.csv", "q1,q2,q3,q4,q5,q6\n0,-60,30,0,60,0\n");
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("q.csv") + " --frame tracker --out " +
                     path("x.csv")),
                 2, {"--frame tracker", "q.csv", "joint targets"});
  nlohmann::json unregistered = read_json("k.json");
  unregistered.erase("registration");
  write_json("noreg.json", unregistered);
  expect_refused(run("compensate --model " + path("noreg.json") + " --targets " + path("tracker.csv") +
                     " --frame tracker --out " + path("x.csv")),
                 2, {"--frame tracker", "noreg.json", "no tracker registration"});
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("ct.csv") + " --out " + path("x.csv")), 2,
                 {"ct.csv:2", "column frame is 'tracker'", "--frame tracker"});
  EXPECT_FALSE(std::filesystem::exists(path("x.csv")));
  const auto again = run("compensate --model " + path("k.json") + " --targets " + path("ct.csv") + " --frame tracker --out " +
                         path("ct2.csv"));
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(column("ct2.csv", "cq1"), column("ct.csv", "cq1"));
  // A column of the user's own named frame (here a video frame number) is not taken for a frame
  // and not silently overwritten: refused, naming the cell and what to rename (issue 35).
  std::string numbered;
  {
    std::istringstream lines(read("robot.csv"));
    std::string line;
    for (int k = 0; std::getline(lines, line); ++k) numbered += line + "," + (k == 0 ? "frame" : std::to_string(100 + k)) + "\n";
  }
  write("numbered.csv", numbered);
  expect_refused(run("compensate --model " + path("k.json") + " --targets " + path("numbered.csv") + " --out " + path("x.csv")),
                 2, {"numbered.csv:2", "column frame holds '101'", "rename that column"});
  EXPECT_FALSE(std::filesystem::exists(path("x.csv")));
}

}  // namespace wrong_command_cli_test
}  // namespace errfield
