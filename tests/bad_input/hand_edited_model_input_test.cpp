// Hand-edited models and several-point files that gave numbers instead of a refusal (issue 47 items 3
// and 5): each is refused with exit 2, naming the member, line or option to fix, and nothing written.
// Data: SIMULATED readings of three nests on a UR5e flange (support/three_nest_data.hpp).

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/three_nest_data.hpp"

namespace errfield {
namespace hand_edited_model_input_test {

using ::testing::HasSubstr;
using testing::CliResult;
namespace fs = std::filesystem;
namespace nest = testing::three_nest;

// A model fitted to the three nests (several points on the flange), and a one-nest model moved to
// r2 by locate-tool from 30 readings (so with a tool_point_correction), made once for the suite.
class HandEditedModel : public ::testing::Test {
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
    dir_ = fs::temp_directory_path() / ("errfield_HandEditedModel_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    nest::simulate(dir_);
    nest::write_robot_with_tool(dir_, "ur5e_r1.json", 0, 0, 60);
    nest::write_subset(dir_, "train.csv", {"r1", "r2", "r3"}, true);
    nest::write_subset(dir_, "train_r1.csv", {"r1"}, true);
    nest::write_subset(dir_, "locate_r2.csv", {"r2"}, true, 30);
    nest::write_subset(dir_, "test_r1.csv", {"r1"}, false);
    for (const std::string line : {"fit --robot ur5e_r1.json --data train.csv --out m3.json",
                                   "fit --robot ur5e_r1.json --data train_r1.csv --out m1.json",
                                   "locate-tool --model m1.json --data locate_r2.csv --out m1_r2.json"}) {
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
  /// `model` edited by `edit`, validated on r1's held-out rows: exit 2 naming `words`, no summary.
  static void expect_refused(const std::string& model, const std::function<void(nlohmann::json&)>& edit,
                             const std::vector<std::string>& words, const std::string& options = "") {
    nlohmann::json m = json(model);
    edit(m);
    write("edited.json", m.dump());
    fs::remove(dir_ / "s.json");
    const CliResult r = run("validate --model edited.json --data test_r1.csv --summary-out s.json " + options);
    EXPECT_EQ(r.exit_code, 2) << r.output();
    for (const std::string& w : words) EXPECT_THAT(r.output(), HasSubstr(w));
    EXPECT_FALSE(fs::exists(dir_ / "s.json"));
  }
  static fs::path dir_;
};
fs::path HandEditedModel::dir_;

// Item 3: a (point, reflector) row given twice made fit drop rotation_calibration and
// flange_error_covariance without a word; labels that differ by a space were two points.
TEST_F(HandEditedModel, RepeatedRowAndLabelSpeltWithSpacesAreRefusedByLine) {
  std::string text = testing::ScratchDir::slurp(dir_ / "train.csv");
  const std::size_t second = text.find('\n') + 1, third = text.find('\n', second) + 1;
  write("repeated.csv", text + text.substr(second, third - second));  // the first data row again, at the end
  const CsvTable t = CsvTable::read((dir_ / "repeated.csv").string());
  const CliResult repeated = run("fit --robot ur5e_r1.json --data repeated.csv --out r.json");
  EXPECT_EQ(repeated.exit_code, 2) << repeated.output();
  EXPECT_THAT(repeated.output(), HasSubstr("repeated.csv:" + std::to_string(t.row_count() + 1)));
  EXPECT_THAT(repeated.output(), HasSubstr("first at line 2"));
  EXPECT_FALSE(fs::exists(dir_ / "r.json"));

  const std::size_t at = text.find(",r2,");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 4, ",r 2,");
  write("spaced.csv", text);
  const CliResult spaced = run("fit --robot ur5e_r1.json --data spaced.csv --out r.json");
  EXPECT_EQ(spaced.exit_code, 2) << spaced.output();
  // The base row (line 3) is the first to carry a label.
  EXPECT_THAT(spaced.output(), HasSubstr("'r2' differs from 'r 2' (line 3)"));
  EXPECT_THAT(spaced.output(), HasSubstr("only by spaces"));
  EXPECT_FALSE(fs::exists(dir_ / "r.json"));
}

// Item 5: flange points moved, made one, or put on a line.
TEST_F(HandEditedModel, FlangePointsMovedCoincidentOrOnALineAreRefused) {
  ASSERT_EQ(run("validate --model m3.json --data test_r1.csv --summary-out s.json").exit_code, 0);
  ASSERT_GE(json("m3.json")["flange_points"].size(), 3u);
  for (double move : {0.5, 5.0, 50.0})
    expect_refused("m3.json", [&](nlohmann::json& m) { m["flange_points"][1]["mm"][0] = m["flange_points"][1]["mm"][0].get<double>() + move; },
                   {"flange_points", "nominal flange"});
  expect_refused("m3.json", [](nlohmann::json& m) { m["flange_points"][0]["mm"][1] = 3.0; }, {"flange_points\"[0]", "own point"});
  expect_refused("m3.json",
                 [](nlohmann::json& m) {
                   m["flange_points"][2]["mm"] = m["flange_points"][1]["mm"];
                   m["flange_points"][2]["mm"][0] = m["flange_points"][1]["mm"][0].get<double>() + 0.3;
                   m["flange_points"][2]["nominal_mm"] = m["flange_points"][1]["nominal_mm"];
                 },
                 {"flange_points\"[2]", "one point"});
  // r3 moved onto the line through r1 and r2 (its nominal position too, so the distances agree).
  expect_refused("m3.json",
                 [](nlohmann::json& m) {
                   for (const char* key : {"mm", "nominal_mm"})
                     for (int k = 0; k < 3; ++k)
                       m["flange_points"][2][key][k] = 2.0 * m["flange_points"][1][key][k].get<double>() -
                                                       m["flange_points"][0][key][k].get<double>();
                 },
                 {"flange_points", "one line"});
}

// Item 5: a tool_point_correction's noise, sill or range beyond what its residuals allow, a missing
// rx_deg in the working tool, and --tool values that were reduced or ignored.
TEST_F(HandEditedModel, ToolPointCorrectionWorkingToolAndToolOptionOutOfRangeAreRefused) {
  ASSERT_TRUE(json("m1_r2.json").contains("tool_point_correction"));
  ASSERT_EQ(run("validate --model m1_r2.json --data test_r1.csv --tool 0,0,60 --summary-out s.json").exit_code, 0);
  expect_refused("m1_r2.json", [](nlohmann::json& m) { m["tool_point_correction"]["noise_mm2"] = 1e300; }, {"noise_mm2"},
                 "--tool 0,0,60");
  expect_refused("m1_r2.json", [](nlohmann::json& m) { m["tool_point_correction"]["sill_mm2"][1] = 1e300; }, {"sill_mm2"},
                 "--tool 0,0,60");
  expect_refused("m1_r2.json",
                 [](nlohmann::json& m) { m["tool_point_correction"]["correlation"] = "gau(sill=1,range=1e300)"; },
                 {"tool_point_correction", "correlation"}, "--tool 0,0,60");
  expect_refused("m1_r2.json",
                 [](nlohmann::json& m) {
                   nlohmann::json& c = m["tool_point_correction"];
                   c["sill_mm2"][0] = 0.0;
                   for (nlohmann::json& r : c["residual_flange_mm"]) r[0] = 10.0;
                 },
                 {"sill_mm2 0"}, "--tool 0,0,60");
  expect_refused("m1_r2.json", [](nlohmann::json& m) { m["working_tool"].erase("rx_deg"); }, {"working_tool", "rx_deg"});
  for (const std::string tool : {"0,0,60,1e300,0,0", "0,0,60,0,-400,0", "''"}) {
    fs::remove(dir_ / "s.json");
    const CliResult r = run("validate --model m1.json --data test_r1.csv --summary-out s.json --tool " + tool);
    EXPECT_EQ(r.exit_code, 2) << tool << "\n" << r.output();
    EXPECT_THAT(r.output(), HasSubstr("--tool")) << tool;
    EXPECT_FALSE(fs::exists(dir_ / "s.json")) << tool;
  }
}

}  // namespace hand_edited_model_input_test
}  // namespace errfield
