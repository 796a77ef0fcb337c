// Issue 47 item 12: what locate-tool, validate and the probe reader say about input a user can fix.
// The options of locate-tool were refused naming the library's struct (`ToolLocationOptions:
// min_orientations`); readings with joints in radians were refused as "too few orientations", which
// sends a user to measure more; a probe angle of 1e300 deg was taken (its sine is rounding noise)
// and failed later without a line; readings of the second located point of a two-point model,
// labelled with its name, were scored at the model's own point and refused, with no hint of
// --reflector. SIMULATED UR5e data from `errfield simulate` (short lever nests, not the KR 16
// three-nest plate of validate_cli_test.cpp).
#include <cmath>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield::compensation {
namespace locate_tool_messages_cli_test {

using ::testing::HasSubstr;
using ::testing::Not;

class LocateToolMessages : public errfield::testing::CliTest {
 protected:
  nlohmann::json json(const std::string& name) const { return nlohmann::json::parse(read(name)); }

  // Two nests 70 mm apart on a UR5e's flange: a model fitted on both (r1 its own point, r2 located
  // by fit), the train rows of r2 for locate-tool and the held-out rows of r2 alone.
  void make_two_point_model() {
    ASSERT_EQ(run("simulate --robot ur5e --seed 21 --sample scattered:120 --orientation-spread 30 --measure positions "
                  "--reflectors \"0,0,40;70,0,30\" --robot-out ur.json --out refl.csv")
                  .exit_code,
              0);
    nlohmann::json robot = json("ur.json");
    robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 40.0}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
    write("ur_r1.json", robot.dump());
    const CsvTable all = CsvTable::read(path("refl.csv"));
    const std::size_t point = all.column_index("point"), reflector = all.column_index("reflector"),
                      kind = all.column_index("kind");
    std::set<std::string> train;  // the first 90 poses; the other 30 are held out
    for (std::size_t i = 0; i < all.row_count() && train.size() < 90; ++i)
      if (all.cell(i, kind) == "target") train.emplace(all.cell(i, point));
    auto subset = [&](const std::string& out, const std::set<std::string>& labels, bool training) {
      rewrite("refl.csv", out, [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
              [](const std::string&) { return true; },
              [&](std::size_t i) {
                return all.cell(i, kind) == "target" && labels.count(std::string(all.cell(i, reflector))) &&
                       train.count(std::string(all.cell(i, point))) == (training ? 1u : 0u);
              });
    };
    subset("train.csv", {"r1", "r2"}, true);
    subset("train_r2.csv", {"r2"}, true);
    subset("test_r2.csv", {"r2"}, false);
    const auto fit = run("fit --robot ur_r1.json --data train.csv --out m.json");
    ASSERT_EQ(fit.exit_code, 0) << fit.output();
    ASSERT_EQ(json("m.json")["flange_points"].size(), 2u) << "a model that located r2";
  }
};

TEST_F(LocateToolMessages, OptionsAreNamedAsOnTheCommandLineAndRadiansAreCalledSo) {
  ASSERT_NO_FATAL_FAILURE(make_two_point_model());
  for (const std::string bad : {"--min-orientations 0", "--distinct-orientation 0", "--distinct-orientation 200",
                                 "--not-rigid-factor 0", "--not-rigid-factor -1"}) {
    const auto r = run("locate-tool --model m.json --data train_r2.csv --out l.json " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.output();
    EXPECT_THAT(r.err, HasSubstr(bad.substr(0, bad.find(' ')))) << bad;
    EXPECT_THAT(r.err, Not(HasSubstr("ToolLocationOptions"))) << bad;
  }
  // The same readings with the joints in radians: named as such, not "measure more orientations".
  rewrite("train_r2.csv", "radians.csv", [](const CsvTable& t, std::size_t, std::vector<std::string>& cells) {
    for (int k = 1; k <= 6; ++k) {
      const std::size_t c = t.column_index("q" + std::to_string(k));
      cells[c] = format_number(std::stod(cells[c]) * M_PI / 180.0);
    }
  });
  const auto radians = run("locate-tool --model m.json --data radians.csv --out l.json");
  EXPECT_EQ(radians.exit_code, 2) << radians.output();
  EXPECT_THAT(radians.err, HasSubstr("radians"));
  EXPECT_THAT(radians.err, HasSubstr("--joints-are-degrees"));
  EXPECT_FALSE(std::filesystem::exists(path("l.json")));
  // The readings themselves (degrees) locate r2; a standard output that cannot be written leaves
  // --out as it was (the report is written first), as every command with several outputs does.
  const auto full = errfield::testing::run_errfield_to_full_stdout(
      {"locate-tool", "--model", "m.json", "--data", "train_r2.csv", "--out", "l.json"}, dir());
  EXPECT_EQ(full.exit_code, 1) << full.err;
  EXPECT_FALSE(std::filesystem::exists(path("l.json")));
  const auto ok = run("locate-tool --model m.json --data train_r2.csv --out l.json");
  EXPECT_EQ(ok.exit_code, 0) << ok.output();
}

// A file whose every row is of r2, a point the model located, is scored there without --reflector,
// as with it (before: scored at r1 and refused as readings of another point).
TEST_F(LocateToolMessages, ReadingsAllOfOneLocatedPointAreScoredAtIt) {
  ASSERT_NO_FATAL_FAILURE(make_two_point_model());
  const auto named = run("validate --model m.json --data test_r2.csv --reflector r2 --summary-out named.json");
  ASSERT_EQ(named.exit_code, 0) << named.output();
  const auto unnamed = run("validate --model m.json --data test_r2.csv --summary-out unnamed.json");
  ASSERT_EQ(unnamed.exit_code, 0) << unnamed.output();
  EXPECT_EQ(json("named.json")["position"]["after"], json("unnamed.json")["position"]["after"]);
  EXPECT_EQ(json("unnamed.json")["points"].get<int>(), 30);
  // With --tool the user says where the point is: the label does not move it (that point is r1's
  // here, so the readings of r2 are refused as of another point).
  const auto tool = run("validate --model m.json --data test_r2.csv --tool 0,0,40");
  EXPECT_NE(tool.exit_code, 0) << tool.output();
}

TEST_F(LocateToolMessages, AProbeAngleBeyondTwoTurnsNamesItsLine) {
  write("probe.csv",
        "point,q1,q2,q3,q4,q5,q6,mx,my,mz,mrx,mry,mrz\n"
        "1,10,-80,90,0,90,0,-400,-100,300,180,0,10\n"
        "2,12,-82,88,5,92,3,-410,-110,310,1e300,0,20\n");
  const auto r = run("fit --robot ur5e --data probe.csv --method kinematic --out p.json");
  EXPECT_EQ(r.exit_code, 2) << r.output();
  EXPECT_THAT(r.err, HasSubstr("probe.csv:3"));
  EXPECT_THAT(r.err, HasSubstr("mrx"));
  EXPECT_FALSE(std::filesystem::exists(path("p.json")));
}

}  // namespace locate_tool_messages_cli_test
}  // namespace errfield::compensation
