// Silent wrong numbers at tool points (issue 47 items 1, 4 and 6): a --tool point a several-point
// model never located, locate-tool's readings given twice, with a gross one or from 3 readings, and
// validate's "before" with a robot JSON whose tool is 0. Each case was scored `ok` with a 95 % radius
// that held a fraction of the held-out readings, or a baseline 60 mm off; now it is refused or its
// radius holds. Data: SIMULATED readings of three nests on a UR5e flange (support/three_nest_data.hpp).

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/robot/pose.hpp"
#include "support/cli_harness.hpp"
#include "support/three_nest_data.hpp"

namespace errfield {
namespace tool_point_results_test {

using ::testing::HasSubstr;
using testing::CliResult;
namespace fs = std::filesystem;
namespace nest = testing::three_nest;

class ToolPointResults : public ::testing::Test {
 protected:
  // The suite's data, made once per process in the first test's SetUp, not in SetUpTestSuite: a
  // failed assertion there marks every test skipped, which ctest and CI count as passed.
  void SetUp() override {
    static bool prepared = false, prepared_ok = false;
    if (!prepared) {
      prepared = true;
      prepare();
      prepared_ok = !HasFatalFailure();
    }
    ASSERT_TRUE(prepared_ok) << "the suite's data could not be made (the first test's output says why)";
  }
  static void prepare() {
    dir_ = fs::temp_directory_path() / ("errfield_ToolPointResults_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    nest::simulate(dir_);
    nest::write_robot_with_tool(dir_, "ur5e_r1.json", 0, 0, 60);
    nest::write_robot_with_tool(dir_, "ur5e_flange.json", 0, 0, 0);
    nest::write_subset(dir_, "train.csv", {"r1", "r2", "r3"}, true);
    nest::write_subset(dir_, "train_r1.csv", {"r1"}, true);
    nest::write_subset(dir_, "test_r1.csv", {"r1"}, false);
    nest::write_subset(dir_, "test_r2.csv", {"r2"}, false);
    nest::write_subset(dir_, "locate_r2.csv", {"r2"}, true, 30);
    nest::write_subset(dir_, "train_r13.csv", {"r1", "r3"}, true);
    nest::write_subset(dir_, "train_r1_q.csv", {"r1"}, true, 0, "nests.csv", false);
    nest::write_subset(dir_, "test_r1_q.csv", {"r1"}, false, 0, "nests.csv", false);
    for (const std::string line : {"fit --robot ur5e_r1.json --data train.csv --out m3.json",
                                   "fit --robot ur5e_r1.json --data train_r1.csv --out m1.json",
                                   "fit --robot ur5e_r1.json --data train_r13.csv --out m13.json"}) {
      const CliResult r = run(line);
      ASSERT_EQ(r.exit_code, 0) << line << "\n" << r.output();
    }
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static CliResult run(const std::string& line) { return testing::run_errfield_line(line, dir_); }
  static nlohmann::json json(const std::string& name) { return nlohmann::json::parse(testing::ScratchDir::slurp(dir_ / name)); }
  static void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name, std::ios::binary) << text; }
  static std::string read(const std::string& name) { return testing::ScratchDir::slurp(dir_ / name); }
  static fs::path dir_;
};
fs::path ToolPointResults::dir_;

// Item 1: r2 given by --tool in the robot description's frame is not where the model located r2
// (they differ by the calibrated flange's constant turn times the 110 mm lever), and nothing the
// model measured covers that turn. Before: every row `ok`, orientation prior "0 mrad ... refused
// beyond inf mm", a radius that held few of the readings. Now the rows it cannot vouch for are
// refused (orientation-unknown, pointing at locate-tool), and whatever it scores is covered.
TEST_F(ToolPointResults, ToolOptionOnASeveralPointModelCarriesTheUnlocatedTurn) {
  const CliResult own = run("validate --model m3.json --data test_r2.csv --reflector r2 --summary-out s_r2.json");
  ASSERT_EQ(own.exit_code, 0) << own.output();
  EXPECT_GE(json("s_r2.json")["uncertainty"]["coverage95"].get<double>(), 0.85);
  const CliResult by_tool = run("validate --model m3.json --data test_r2.csv --tool 110,0,60 --summary-out s_tool.json");
  EXPECT_THAT(by_tool.output(), ::testing::Not(HasSubstr("orientation prior 0 mrad")));
  EXPECT_THAT(by_tool.output(), ::testing::Not(HasSubstr("refused beyond inf mm")));
  if (by_tool.exit_code == 0) {
    const nlohmann::json s = json("s_tool.json");
    if (s["points"].get<int>() > s["refused"].get<int>()) {
      EXPECT_GE(s["uncertainty"]["coverage95"].get<double>(), 0.85) << by_tool.output();
    }
  } else {
    EXPECT_EQ(by_tool.exit_code, 1) << by_tool.output();
    EXPECT_THAT(by_tool.output(), HasSubstr("orientation-unknown"));
    EXPECT_THAT(by_tool.output(), HasSubstr("locate-tool"));
  }
  EXPECT_TRUE(by_tool.exit_code == 1 || fs::exists(dir_ / "s_tool.json")) << by_tool.output();
}

// Item 4: readings given twice, and a gross reading, in locate-tool.
TEST_F(ToolPointResults, LocateToolRefusesRepeatedReadingsAndLeavesAGrossOneOutOfTheLocation) {
  const std::string readings = read("locate_r2.csv");
  write("twice.csv", readings + readings.substr(readings.find('\n') + 1));
  const CliResult twice = run("locate-tool --model m1.json --data twice.csv --out t.json");
  EXPECT_EQ(twice.exit_code, 2) << twice.output();
  // Refused as the file is read: each (point, reflector) pair is one reading (the same rows under
  // other point names reach locate-tool's own check, "repeats the joints": ToolPoints tests).
  EXPECT_THAT(twice.output(), HasSubstr("is read again"));
  EXPECT_FALSE(fs::exists(dir_ / "t.json"));

  const CliResult clean = run("locate-tool --model m1.json --data locate_r2.csv --out clean.json");
  ASSERT_EQ(clean.exit_code, 0) << clean.output();
  // One reading 3 mm off along the tracker's x (a bumped nest).
  const CsvTable t = CsvTable::read((dir_ / "locate_r2.csv").string());
  const std::size_t mx = t.column_index("mx");
  std::string text;
  for (const std::string& h : t.header()) text += (text.empty() ? "" : ",") + h;
  text += "\n";
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    for (std::size_t c = 0; c < t.header().size(); ++c)
      text += (c ? "," : "") + (i == 7 && c == mx ? std::to_string(t.numeric_cell(i, c) + 3.0) : std::string(t.cell(i, c)));
    text += "\n";
  }
  write("gross.csv", text);
  const CliResult gross = run("locate-tool --model m1.json --data gross.csv --out gross.json");
  ASSERT_EQ(gross.exit_code, 0) << gross.output();
  EXPECT_THAT(gross.output(), HasSubstr("1 gross reading(s) left out of the location"));
  auto point = [&](const std::string& name) {
    const nlohmann::json w = json(name)["working_tool"];
    return std::array<double, 3>{w["x_mm"].get<double>(), w["y_mm"].get<double>(), w["z_mm"].get<double>()};
  };
  const auto a = point("clean.json"), b = point("gross.json");
  // 3 mm over 30 readings moved the least-squares point by ~0.1 mm; left out, the other 29 put it
  // where the 30 clean ones do, to their own scatter (sd ~0.01 mm).
  EXPECT_LT(std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]), 0.03);
}

// Item 4: readings of r2 on another unit of the same robot model in the same cell: its geometric
// deviations 1.3 x this one's. Before: located (residual 0.66 mm at the readings against 0.32 mm
// "explained", the orientation term inflating the latter), 0.149 mm held out with 87 % coverage.
TEST_F(ToolPointResults, LocateToolRefusesReadingsOfAnotherUnit) {
  ASSERT_EQ(run("simulate --robot ur5e --seed 7 --sample scattered:5 --measure positions --config-out cfg.json --out c.csv")
                .exit_code,
            0);
  nlohmann::json config = json("cfg.json");
  for (nlohmann::json& link : config["geometry"]["links"])
    for (auto it = link.begin(); it != link.end(); ++it) *it = 1.3 * it->get<double>();
  write("cfg_other.json", config.dump());
  nest::simulate(dir_, 8, "other_unit.csv", "--config cfg_other.json");
  nest::write_subset(dir_, "other_r2.csv", {"r2"}, true, 30, "other_unit.csv");
  const CliResult r = run("locate-tool --model m1.json --data other_r2.csv --out other.json");
  EXPECT_EQ(r.exit_code, 2) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("another unit"));
  EXPECT_FALSE(fs::exists(dir_ / "other.json"));
}

// Item 4: located from 3 readings (the allowed minimum), the 95 % radius at the point holds held-out
// readings (72 % in the case). Here a model of r1 and r3 moved to r2: its radius there takes
// the point's own location error (sd ~0.09 mm per axis from 3 readings) and the orientation residual
// at its 6-degree-of-freedom upper bound. 39 held-out readings: 0.85 is 95 % less 2.9 binomial sd.
TEST_F(ToolPointResults, LocatedFromThreeReadingsTheRadiusHolds) {
  nest::write_subset(dir_, "three.csv", {"r2"}, true, 4);  // one of the four is outside the field's region
  const CliResult located = run("locate-tool --model m13.json --data three.csv --out three.json");
  ASSERT_EQ(located.exit_code, 0) << located.output();
  EXPECT_THAT(located.output(), HasSubstr("3 readings"));
  const CliResult v = run("validate --model three.json --data test_r2.csv --summary-out s3.json");
  if (v.exit_code == 0) {
    EXPECT_GE(json("s3.json")["uncertainty"]["coverage95"].get<double>(), 0.85) << v.output();
  } else {  // or every row refused: the orientation it measured does not support the lever
    EXPECT_EQ(v.exit_code, 1) << v.output();
    EXPECT_THAT(v.output(), HasSubstr("orientation-unknown"));
  }
}

// Item 6: a robot JSON with tool 0 (the reflector found by the calibration): "before" was the
// nominal flange centre against readings 60 mm away; now the nominal robot at the located
// reflector, within a few mm as the uncompensated robot is.
TEST_F(ToolPointResults, BeforeWithAZeroToolRobotIsAtTheLocatedReflector) {
  // As real data: no x,y,z columns (the nominal positions are the FK of the robot given).
  const CliResult fit = run("fit --robot ur5e_flange.json --data train_r1_q.csv --reflector-far-ok --out m0.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.output();
  const CliResult v = run("validate --model m0.json --data test_r1_q.csv --summary-out s0.json");
  ASSERT_EQ(v.exit_code, 0) << v.output();
  const CliResult ref = run("validate --model m1.json --data test_r1_q.csv --summary-out s1.json");
  ASSERT_EQ(ref.exit_code, 0) << ref.output();
  const double before0 = json("s0.json")["position"]["before"]["rms_mm"].get<double>();
  const double before1 = json("s1.json")["position"]["before"]["rms_mm"].get<double>();
  // The robot JSON at r1 gives the baseline (1.12 mm); at the flange centre it read 22.8 mm.
  EXPECT_LT(before0, 1.5 * before1 + 0.5) << before0 << " mm vs " << before1 << " mm with the tool at r1";
}

// Item 2: a 6-DoF probe model's predicted tool orientation (predict's prx,pry,prz) against the
// probe's held-out readings, with the robot JSON's tool the probe's frame as drawn. The calibrated
// flange differs from the true one by a constant turn (joint 6's offset and the probe's twist on the
// flange cannot be told apart), which the located probe points absorb: the description's mounting on
// the calibrated flange missed by ~150 mdeg, none within r95_w_mdeg (~35). Now the located mounting:
// the miss is what the predicted rotation leaves, within its radius.
TEST(ProbeToolFrame, PredictedOrientationIsTheLocatedProbeFrameWithinItsRadius) {
  testing::ScratchDir dir;
  auto run = [&](const std::string& line) { return testing::run_errfield_line(line, dir.path()); };
  ASSERT_EQ(run("simulate --robot ur5e --seed 9 --sample scattered:230 --orientation-spread 30 --measure positions "
                "--probe 0,0,80,180,0,0 --robot-out u.json --out probe.csv")
                .exit_code,
            0);
  nlohmann::json robot = nlohmann::json::parse(dir.read("u.json"));
  robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 80.0}, {"rx_deg", 180.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  dir.write("u_probe.json", robot.dump());
  const CsvTable all = CsvTable::read(dir / "probe.csv");
  std::string header, train_rows, test_rows;
  for (const std::string& h : all.header()) header += (header.empty() ? "" : ",") + h;
  for (std::size_t i = 0; i < all.row_count(); ++i) {
    std::string line;
    for (std::size_t c = 0; c < all.header().size(); ++c) line += (c ? "," : "") + std::string(all.cell(i, c));
    (i < 170 ? train_rows : test_rows) += line + "\n";  // 170 training poses, the rest held out
  }
  dir.write("train.csv", header + "\n" + train_rows);
  dir.write("test.csv", header + "\n" + test_rows);
  const CliResult fit = run("fit --robot u_probe.json --data train.csv --out m.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.output();
  const CliResult p = run("predict --model m.json --joints test.csv --out predicted.csv");
  ASSERT_EQ(p.exit_code, 0) << p.output();
  const nlohmann::json model = nlohmann::json::parse(dir.read("m.json"));
  Eigen::Matrix3d registration;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) registration(r, c) = model["registration"]["robot_from_tracker"][r][c].get<double>();
  const CsvTable test = CsvTable::read(dir / "test.csv"), predicted = CsvTable::read(dir / "predicted.csv");
  ASSERT_EQ(test.row_count(), predicted.row_count());
  std::size_t scored = 0, within = 0;
  double ss = 0.0;
  for (std::size_t i = 0; i < predicted.row_count(); ++i) {
    if (predicted.cell(i, predicted.column_index("status")) != "ok") continue;
    auto rotation = [](const CsvTable& t, std::size_t row, const char* x, const char* y, const char* z) {
      return robot::rotation_from_rpy_deg(t.numeric_cell(row, t.column_index(x)), t.numeric_cell(row, t.column_index(y)),
                                          t.numeric_cell(row, t.column_index(z)));
    };
    const Eigen::Matrix3d read = registration * rotation(test, i, "mrx", "mry", "mrz");
    const Eigen::Matrix3d at = rotation(predicted, i, "prx", "pry", "prz");
    const double miss_mdeg = Eigen::AngleAxisd(read * at.transpose()).angle() * 180000.0 / M_PI;
    ss += miss_mdeg * miss_mdeg;
    within += miss_mdeg <= predicted.numeric_cell(i, predicted.column_index("r95_w_mdeg"));
    ++scored;
  }
  ASSERT_GE(scored, 40u);
  const double rms = std::sqrt(ss / static_cast<double>(scored)), coverage = static_cast<double>(within) / static_cast<double>(scored);
  std::printf("probe frame: predicted within %.1f mdeg RMS of the readings, %.3f within r95_w over %zu poses\n", rms,
              coverage, scored);
  EXPECT_GE(coverage, 0.85);
  EXPECT_LT(rms, 60.0);
}

// CompensationModel::predict_errors_at batches the field's kriging solves of many rows; it must be
// predict_error_at row by row on every path: the own point (joint functions, their weights), a
// further nest with a field of its own, a point between (the flange's rigid motion), a point far off,
// at training poses and held-out ones.
TEST_F(ToolPointResults, BatchedPredictionsEqualThePredictionsOneByOne) {
  for (const std::string name : {"m1.json", "m3.json"}) {
    const compensation::CompensationModel model = compensation::CompensationModel::from_json(json(name), name);
    std::vector<robot::JointVector> poses;
    for (const std::string file : {"train_r1.csv", "test_r1.csv"}) {
      const CsvTable t = CsvTable::read((dir_ / file).string());
      for (std::size_t i = 0; i < t.row_count(); ++i) {
        robot::JointVector q;
        for (int k = 0; k < 6; ++k) q[k] = t.numeric_cell(i, t.column_index("q" + std::to_string(k + 1)));
        poses.push_back(q);
      }
    }
    poses.push_back(robot::JointVector::Constant(170.0));  // far outside the fitted region
    std::vector<robot::JointVector> q;
    std::vector<robot::MdhModel> at;
    const std::array<Eigen::Vector3d, 4> points = {model.measured_point_mm(), Eigen::Vector3d(110, 0, 60),
                                                   Eigen::Vector3d(40, 30, 70), Eigen::Vector3d(0, 0, 400)};
    for (std::size_t i = 0; i < poses.size(); ++i) {
      q.push_back(poses[i]);
      at.push_back(model.command_model().with_tool_point(points[i % points.size()]));
    }
    const std::vector<compensation::ErrorPrediction> batched = model.predict_errors_at(q, at);
    ASSERT_EQ(batched.size(), q.size());
    std::size_t inside = 0;
    for (std::size_t i = 0; i < q.size(); ++i) {
      const compensation::ErrorPrediction one = model.predict_error_at(q[i], at[i]);
      const compensation::ErrorPrediction& b = batched[i];
      ASSERT_EQ(b.inside_region, one.inside_region) << name << " row " << i;
      EXPECT_EQ(b.credible, one.credible) << name << " row " << i;
      EXPECT_EQ(b.orientation_supported, one.orientation_supported) << name << " row " << i;
      EXPECT_EQ(b.calibration_supported, one.calibration_supported) << name << " row " << i;
      if (!one.inside_region) continue;
      ++inside;
      // The same sums in another order (a batch's tiled solve): equal to rounding.
      EXPECT_LT((b.position_error_mm - one.position_error_mm).norm(), 1e-9) << name << " row " << i;
      EXPECT_NEAR(b.variance_mm2, one.variance_mm2, 1e-9 * one.variance_mm2) << name << " row " << i;
      EXPECT_NEAR(b.orientation_variance_mm2, one.orientation_variance_mm2, 1e-9 * one.variance_mm2) << name << " row " << i;
      EXPECT_LT((b.axis_variance_mm2 - one.axis_variance_mm2).norm(), 1e-9 * one.variance_mm2) << name << " row " << i;
    }
    EXPECT_GE(inside, poses.size() / 2) << name;
  }
}

}  // namespace tool_point_results_test
}  // namespace errfield
