// `errfield fit` with no --method (auto) as a new user runs it: simulate → fit with defaults →
// validate on held-out rows, on data unlike the built-in set-up (the UR5e, scattered poses with
// varying orientation, joints recorded to 2 decimals, an unknown reflector offset). The default
// must be within 10 % (held-out 3-D RMS; issue 10) of the best of the alternatives a user could
// hand-pick, and its automatically chosen joint-space model within 5 % (issue 11) — the tighter
// bound is asserted, scored on the held-out points every model accepted (a model that refuses the
// hard points must not look better for it). SIMULATED data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/session_split.hpp"

namespace errfield::compensation {
namespace default_method_cli_test {

class DefaultMethodStudy : public errfield::testing::CliTest {
 protected:
  /// Splits `all` into `train` (base rows and the first n_train targets) and `hold` (base rows and
  /// the rest), keeping the SIMULATED comment lines in both.
  void split(const std::string& all, std::size_t n_train, const std::string& train, const std::string& hold) {
    const errfield::testing::SessionSplit parts = errfield::testing::split_session(read(all), n_train);
    ASSERT_GT(parts.targets, n_train);
    write(train, parts.train);
    write(hold, parts.hold);
  }

  /// Simulates with `simulate` (+ truth columns, positions), splits at `n_train` targets and checks
  /// fit's default outlier screen against the oracle (the same fit without the true outliers).
  void expect_screen_as_an_oracle(const std::string& simulate, std::size_t n_train);

  /// Fits with `options`, validates on hold.csv; returns after_mm per point that was accepted.
  std::map<std::string, double> held_out_errors(const std::string& options, std::string* fit_output = nullptr) {
    const errfield::testing::CliResult f = run("fit --robot r.json --data train.csv " + options + " --out m.json");
    EXPECT_EQ(f.exit_code, 0) << options << "\n" << f.output();
    if (fit_output) *fit_output = f.out;
    const errfield::testing::CliResult v = run("validate --model m.json --data hold.csv --out points.csv");
    EXPECT_EQ(v.exit_code, 0) << options << "\n" << v.output();
    std::map<std::string, double> e;
    const CsvTable t = CsvTable::read(path("points.csv"));
    for (std::size_t i = 0; i < t.row_count(); ++i)
      if (t.row(i)[t.column_index("status")] == "ok")
        e[t.row(i)[t.column_index("point")]] = t.numeric_cell(i, t.column_index("after_mm"));
    return e;
  }
};

double rms_over(const std::map<std::string, double>& e, const std::set<std::string>& points) {
  double ss = 0;
  for (const auto& p : points) ss += e.at(p) * e.at(p);
  return std::sqrt(ss / static_cast<double>(points.size()));
}

TEST_F(DefaultMethodStudy, PositionsDefaultIsWithinFivePercentOfTheBestHandPickedMethod) {
  ASSERT_EQ(run("simulate --robot ur5e --seed 11 --sample scattered:330 --orientation-spread 30 --joint-decimals 2 "
                "--tool-offset random:20 --measure positions --robot-out r.json --out all.csv")
                .exit_code,
            0);
  split("all.csv", 220, "train.csv", "hold.csv");
  std::string said;
  const auto by_default = held_out_errors("", &said);
  EXPECT_NE(said.find("method auto: kinematic+kriging"), std::string::npos) << said;
  const std::map<std::string, std::string> alternatives{
      {"kinematic", "--method kinematic"},
      {"kinematic+kriging, task space", "--method kinematic+kriging --space task"},
      {"kinematic+kriging, joint space, universal1", "--method kinematic+kriging --space joint --kind universal1"},
      {"kinematic+kriging, joint space, hand-set Matern", "--method kinematic+kriging --space joint --model "
                                                         "\"mat(sill=0.01,range=40,nu=1.5)+nug(0.0005)\""},
  };
  std::map<std::string, std::map<std::string, double>> alt;
  for (const auto& [name, options] : alternatives) alt[name] = held_out_errors(options);

  std::set<std::string> common;
  for (const auto& [p, e] : by_default) {
    bool everywhere = true;
    for (const auto& [name, errors] : alt) everywhere = everywhere && errors.count(p);
    if (everywhere) common.insert(p);
  }
  // The joint-space region refuses a few targets beyond the samples' joints; most are scored.
  ASSERT_GE(common.size(), 100u);
  const double mine = rms_over(by_default, common);
  double best = INFINITY;
  std::string best_name;
  for (const auto& [name, errors] : alt)
    if (const double r = rms_over(errors, common); r < best) best = r, best_name = name;
  std::cout << "held-out 3-D RMS on " << common.size() << " points: default " << mine << " mm; best hand-picked ("
            << best_name << ") " << best << " mm\n";
  EXPECT_LE(mine, 1.05 * best) << "default " << mine << " mm, best hand-picked (" << best_name << ") " << best
                               << " mm on " << common.size() << " held-out points";
  // and the default is an actual compensation: well below the kinematic calibration alone
  EXPECT_LT(mine, 0.8 * rms_over(alt.at("kinematic"), common));
}

/// Points whose `outlier` truth column is 1 (simulate --truth-columns).
std::set<std::string> true_outliers(const std::string& file) {
  const CsvTable t = CsvTable::read(file);
  std::set<std::string> s;
  for (std::size_t i = 0; i < t.row_count(); ++i)
    if (t.row(i)[t.column_index("outlier")] == "1") s.insert(t.row(i)[t.column_index("point")]);
  return s;
}

// Gross tracker outliers among 0.1-0.3 mm errors: kriged as if they were the field they spread into
// their neighbourhood. The default must find exactly the simulated ones and score, on the clean
// held-out points, as well as the same method fitted on data with the outliers removed by hand (the
// oracle: RMS within 5 %, max within 10 %, no held-out point refused that the oracle predicts), and
// far better than keeping them.
void DefaultMethodStudy::expect_screen_as_an_oracle(const std::string& simulate, std::size_t n_train) {
  ASSERT_EQ(run(simulate + " --truth-columns --measure positions --robot-out r.json --out all.csv").exit_code, 0);
  split("all.csv", n_train, "train.csv", "hold.csv");
  const std::set<std::string> train_bad = true_outliers(path("train.csv")), hold_bad = true_outliers(path("hold.csv"));
  ASSERT_GE(train_bad.size(), 4u);
  // the oracle's training file: the same rows without the simulated outliers
  {
    std::istringstream in(read("train.csv"));
    std::string line, text;
    while (std::getline(in, line)) {
      const std::string id = line.substr(0, line.find(','));
      if (!train_bad.count(id)) text += line + "\n";
    }
    write("oracle.csv", text);
  }
  std::string said;
  const auto by_default = held_out_errors("", &said);
  const auto kept_all = held_out_errors("--outlier-limit 0");
  const errfield::testing::CliResult f = run("fit --robot r.json --data train.csv --out m.json");
  const std::size_t at = f.err.find("gross outliers");
  ASSERT_NE(at, std::string::npos) << f.output();
  const std::string listed = f.err.substr(at, f.err.find('\n', at) - at);
  for (const auto& id : train_bad) EXPECT_NE(listed.find(" " + id), std::string::npos) << id << " not in: " << listed;
  EXPECT_NE(f.err.find(std::to_string(train_bad.size()) + " row(s) excluded"), std::string::npos) << f.err;
  EXPECT_EQ(listed.find("more)"), std::string::npos) << "the list is cut short: " << listed;
  // The model file lists them all, by point name, and carries fit's notes (docs/robot.md).
  const nlohmann::json model = nlohmann::json::parse(read("m.json"));
  ASSERT_TRUE(model.contains("excluded_rows")) << "no excluded_rows in m.json";
  std::set<std::string> in_file;
  for (const auto& id : model["excluded_rows"]) in_file.insert(id.get<std::string>());
  EXPECT_EQ(in_file, train_bad);
  ASSERT_TRUE(model.contains("notes") && model["notes"].is_array());
  bool noted = false;
  for (const auto& n : model["notes"]) noted = noted || n.get<std::string>().find("gross outliers") != std::string::npos;
  EXPECT_TRUE(noted) << model["notes"].dump();

  const errfield::testing::CliResult o = run("fit --robot r.json --data oracle.csv --out oracle.json");
  ASSERT_EQ(o.exit_code, 0) << o.output();
  ASSERT_EQ(run("validate --model oracle.json --data hold.csv --out oracle_points.csv").exit_code, 0);
  std::map<std::string, double> oracle;
  const CsvTable op = CsvTable::read(path("oracle_points.csv"));
  for (std::size_t i = 0; i < op.row_count(); ++i)
    if (op.row(i)[op.column_index("status")] == "ok")
      oracle[op.row(i)[op.column_index("point")]] = op.numeric_cell(i, op.column_index("after_mm"));

  std::set<std::string> clean;
  std::size_t held_out = 0;
  for (const auto& [p, e] : oracle) held_out += hold_bad.count(p) ? 0 : 1;
  for (const auto& [p, e] : by_default)
    if (!hold_bad.count(p) && kept_all.count(p) && oracle.count(p)) clean.insert(p);
  ASSERT_GE(clean.size(), 90u);
  EXPECT_EQ(clean.size(), held_out) << "the default refused held-out points the oracle predicted";
  const double mine = rms_over(by_default, clean), oracle_rms = rms_over(oracle, clean),
               naive = rms_over(kept_all, clean);
  double mine_max = 0, oracle_max = 0;
  for (const auto& p : clean) {
    mine_max = std::max(mine_max, by_default.at(p));
    oracle_max = std::max(oracle_max, oracle.at(p));
  }
  std::cout << "clean held-out 3-D RMS on " << clean.size() << " points: default " << mine << " mm (max " << mine_max
            << "), oracle " << oracle_rms << " mm (max " << oracle_max << "), outliers kept " << naive << " mm\n";
  EXPECT_LE(mine, 1.05 * oracle_rms);
  EXPECT_LE(mine_max, 1.1 * oracle_max);
  EXPECT_LT(mine, 0.8 * naive);
}

TEST_F(DefaultMethodStudy, GrossOutliersAreExcludedAsAnOracleWould) {
  expect_screen_as_an_oracle("simulate --robot ur5e --seed 13 --sample scattered:330 --orientation-spread 30 "
                             "--joint-decimals 2 --tool-offset random:20 --outliers 0.04:3",
                             220);
}

// The same with systematic effects that grow at the ends of q1's and q5's travel (issue 19): the
// screen on the calibration residual dropped 17 rows here (5 outliers and 12 real rows at
// |q1| > 110 deg), refused 2 held-out points there and doubled the held-out maximum.
TEST_F(DefaultMethodStudy, GrossOutliersAmongRealisticSystematicEffectsAreExcludedAsAnOracleWould) {
  expect_screen_as_an_oracle("simulate --robot kr16 --seed 3 --sample scattered:400 --joint-box "
                             "-150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --systematic realistic "
                             "--outliers 0.02:3",
                             280);
}

TEST_F(DefaultMethodStudy, DistancesOnlyDefaultIsTheKinematicCalibration) {
  ASSERT_EQ(run("simulate --robot ur5e --seed 12 --sample scattered:200 --orientation-spread 30 --joint-decimals 2 "
                "--tool-offset random:20 --measure distances --robot-out r.json --out all.csv")
                .exit_code,
            0);
  split("all.csv", 140, "train.csv", "hold.csv");
  const errfield::testing::CliResult f = run("fit --robot r.json --data train.csv --out m.json");
  ASSERT_EQ(f.exit_code, 0) << f.output();
  EXPECT_NE(f.out.find("method auto: kinematic ("), std::string::npos) << f.out;
  ASSERT_EQ(run("validate --model m.json --data hold.csv --summary-out s.json").exit_code, 0);
  const double mine = nlohmann::json::parse(read("s.json"))["distance"]["after"]["rms_mm"].get<double>();
  for (const std::string other : {"--method distance-kriging --space task", "--method distance-kriging --space joint"}) {
    SCOPED_TRACE(other);
    ASSERT_EQ(run("fit --robot r.json --data train.csv " + other + " --out o.json").exit_code, 0);
    ASSERT_EQ(run("validate --model o.json --data hold.csv --summary-out o.json.s").exit_code, 0);
    EXPECT_LE(mine, 1.10 * nlohmann::json::parse(read("o.json.s"))["distance"]["after"]["rms_mm"].get<double>());
  }
  // data with neither positions nor distances: an error naming what is missing, no model
  write("bare.csv", "point,kind,q1,q2,q3,q4,q5,q6\np0,target,0,-90,90,0,45,0\n");
  const errfield::testing::CliResult bare = run("fit --robot r.json --data bare.csv --out b.json");
  EXPECT_EQ(bare.exit_code, 2) << bare.output();
  EXPECT_NE(bare.err.find("neither tracker positions"), std::string::npos) << bare.err;
}

}  // namespace
}  // namespace errfield::compensation
