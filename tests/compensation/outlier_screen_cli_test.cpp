// fit's gross-outlier screen keeps real behaviour (issue 19, item 2): a row is dropped when its
// reading disagrees with what its neighbours in the field predict, not for being far from the
// kinematic model. On SIMULATED KR 16 data with systematic effects that grow at the ends of q1's
// and q5's travel (simulate --systematic realistic) and two injected 3 mm tracker outliers: the
// outliers are dropped, and the edge rows whose residual after calibration is beyond the limit
// (what the screen used to drop) are kept. Small and fast: a CI guard; the study with held-out
// scores is DefaultMethodStudy.GrossOutliers* in default_method_cli_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield::compensation {
namespace outlier_screen_cli_test {

class OutlierScreen : public errfield::testing::CliTest {};

TEST_F(OutlierScreen, KeepsSmoothEdgeBehaviourAndDropsReadingsTheirNeighboursContradict) {
  ASSERT_EQ(run("simulate --robot kr16 --seed 21 --sample scattered:150 "
                "--joint-box -150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --systematic realistic "
                "--outliers 0.014:3 --truth-columns --measure positions --robot-out r.json --out d.csv")
                .exit_code,
            0);
  const CsvTable data = CsvTable::read(path("d.csv"));
  std::set<std::string> injected;
  for (std::size_t i = 0; i < data.row_count(); ++i)
    if (data.row(i)[data.column_index("outlier")] == "1") injected.insert(data.row(i)[data.column_index("point")]);
  ASSERT_EQ(injected.size(), 2u);

  // Independently: each row's residual after a kinematic calibration alone (validate's after_mm of
  // a kinematic model on its own training rows), and the rows beyond 5 robust sigma of it — what a
  // screen on the calibration residual drops.
  ASSERT_EQ(run("fit --robot r.json --data d.csv --method kinematic --outlier-limit 0 --out kin.json").exit_code, 0);
  ASSERT_EQ(run("validate --model kin.json --data d.csv --out kin_points.csv").exit_code, 0);
  const CsvTable kin = CsvTable::read(path("kin_points.csv"));
  std::vector<double> residual;
  for (std::size_t i = 0; i < kin.row_count(); ++i)
    if (kin.row(i)[kin.column_index("point")][0] == 'p')
      residual.push_back(kin.numeric_cell(i, kin.column_index("after_mm")));
  std::vector<double> sorted = residual;
  std::sort(sorted.begin(), sorted.end());
  const double limit_mm = 5.0 * std::sqrt(3.0) * sorted[sorted.size() / 2] / 1.5382;
  std::set<std::string> far_but_real;  // beyond the limit of the calibration residual, not injected
  for (std::size_t i = 0; i < kin.row_count(); ++i) {
    const std::string id = kin.row(i)[kin.column_index("point")];
    if (id[0] == 'p' && !injected.count(id) && kin.numeric_cell(i, kin.column_index("after_mm")) > limit_mm)
      far_but_real.insert(id);
  }
  ASSERT_GE(far_but_real.size(), 3u) << "the set must have real edge behaviour beyond the old limit";
  for (const std::string& id : far_but_real) {  // they are at the ends of q1's or q5's travel
    std::size_t row = 0;
    while (data.row(row)[data.column_index("point")] != id) ++row;
    const double q1 = std::abs(data.numeric_cell(row, data.column_index("q1")));
    const double q5 = std::abs(data.numeric_cell(row, data.column_index("q5")));
    EXPECT_TRUE(q1 > 110 || q5 > 95) << id << " q1 " << q1 << " q5 " << q5;
  }

  // Default fit with the model REML chooses on this set, rounded and given so the test runs in well
  // under a second (the choice itself takes ~10 s here; the studies run it): it drops exactly the
  // injected outliers.
  const auto f = run("fit --robot r.json --data d.csv --model "
                     "\"exp(sill=1.2,range=353000)+nug(0.00076)@ard(0.0023,0.012,0.0097,0.135,0.03,1)\" --out m.json");
  ASSERT_EQ(f.exit_code, 0) << f.output();
  const nlohmann::json model = nlohmann::json::parse(read("m.json"));
  std::set<std::string> excluded;
  if (model.contains("excluded_rows"))
    for (const auto& id : model["excluded_rows"]) excluded.insert(id.get<std::string>());
  EXPECT_EQ(excluded, injected) << f.err;
  for (const std::string& id : far_but_real) EXPECT_FALSE(excluded.count(id)) << id << " is real behaviour";
  EXPECT_NE(f.err.find("from what its neighbours in the field predict"), std::string::npos) << f.err;
}

// `--method kinematic` and `--space task` screen by leave-one-out against the predictive sigma, or
// not at all (issue 35, item 4): they used the residual after calibration (kinematic) or fell back
// to it (task space), and on real data dropped the same 11 real edge rows as the old default. On
// the set above, and on the same set without outliers, where no row may be dropped.
std::set<std::string> excluded_rows_of(const std::string& model_json) {
  const nlohmann::json model = nlohmann::json::parse(model_json);
  std::set<std::string> excluded;
  if (model.contains("excluded_rows"))
    for (const auto& id : model["excluded_rows"]) excluded.insert(id.get<std::string>());
  return excluded;
}

TEST_F(OutlierScreen, KinematicMethodAndTaskSpaceUseTheLeaveOneOutScreen) {
  const std::string sim = "simulate --robot kr16 --seed 21 --sample scattered:150 "
                          "--joint-box -150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --systematic realistic "
                          "--truth-columns --measure positions --robot-out r.json ";
  ASSERT_EQ(run(sim + "--outliers 0.014:3 --out d.csv").exit_code, 0);
  ASSERT_EQ(run(sim + "--out clean.csv").exit_code, 0);
  const CsvTable data = CsvTable::read(path("d.csv"));
  std::set<std::string> injected;
  for (std::size_t i = 0; i < data.row_count(); ++i)
    if (data.row(i)[data.column_index("outlier")] == "1") injected.insert(data.row(i)[data.column_index("point")]);
  ASSERT_EQ(injected.size(), 2u);
  // Without --model, kinematic screens nothing (no field to judge by): the real edge rows stay.
  const auto plain = run("fit --robot r.json --data d.csv --method kinematic --out plain.json");
  ASSERT_EQ(plain.exit_code, 0) << plain.output();
  EXPECT_TRUE(excluded_rows_of(read("plain.json")).empty()) << plain.err;
  EXPECT_NE(plain.out.find("gross-outlier screen: none"), std::string::npos) << plain.out;
  // With the joint-space variogram of the test above, a field judges the rows.
  const std::string model = " --model \"exp(sill=1.2,range=353000)+nug(0.00076)@ard(0.0023,0.012,0.0097,0.135,0.03,1)\"";
  const auto k = run("fit --robot r.json --data d.csv --method kinematic" + model + " --out k.json");
  ASSERT_EQ(k.exit_code, 0) << k.output();
  EXPECT_EQ(excluded_rows_of(read("k.json")), injected) << k.err;
  EXPECT_NE(k.err.find("judged by a joint-space kinematic+kriging field"), std::string::npos) << k.err;
  const auto kc = run("fit --robot r.json --data clean.csv --method kinematic" + model + " --out kc.json");
  ASSERT_EQ(kc.exit_code, 0) << kc.output();
  EXPECT_TRUE(excluded_rows_of(read("kc.json")).empty()) << kc.err;
  // Independently: the kinematic model fitted without the injected rows is the one written (the
  // same calibration as --outlier-limit 0 on the data without them).
  rewrite("d.csv", "d_clean_rows.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string&) { return true; },
          [&](std::size_t i) { return data.row(i)[data.column_index("outlier")] != "1"; });
  ASSERT_EQ(run("fit --robot r.json --data d_clean_rows.csv --method kinematic --outlier-limit 0 --out ko.json").exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(read("k.json"))["command_model"], nlohmann::json::parse(read("ko.json"))["command_model"]);

  // Task space, its own field's leave-one-out, on a 60-row part of the set that holds both
  // outliers, so that it stays fast. (This part passed before too: on real data the task-space
  // leave-one-out was unavailable - repeated locations merged - and the screen fell back to the
  // calibration residual, which it no longer does.)
  auto first60 = [](std::size_t i) { return i >= 60 && i < 120; };
  auto none = [](const CsvTable&, std::size_t, std::vector<std::string>&) {};
  auto all = [](const std::string&) { return true; };
  rewrite("d.csv", "d60.csv", none, all, first60);
  rewrite("clean.csv", "clean60.csv", none, all, first60);
  std::set<std::string> injected60;
  for (std::size_t i = 60; i < 120; ++i)
    if (data.row(i)[data.column_index("outlier")] == "1") injected60.insert(data.row(i)[data.column_index("point")]);
  ASSERT_EQ(injected60, injected);
  const auto t = run("fit --robot r.json --data d60.csv --method kinematic+kriging --space task --joint-functions 0 "
                     "--out t.json");
  ASSERT_EQ(t.exit_code, 0) << t.output();
  EXPECT_EQ(excluded_rows_of(read("t.json")), injected60) << t.err;
  const auto tc = run("fit --robot r.json --data clean60.csv --method kinematic+kriging --space task --joint-functions 0 "
                      "--out tc.json");
  ASSERT_EQ(tc.exit_code, 0) << tc.output();
  EXPECT_TRUE(excluded_rows_of(read("tc.json")).empty()) << tc.err;
}

// Readings of several points on the flange (issue 34): each row is judged by its own point's field,
// so a gross outlier in one nest's reading is left out and the other nests' readings of that pose
// are kept. SIMULATED KR 16 read at three nests with 1 % of the rows 3 mm off: exactly those rows
// are excluded, and the model is the one fitted without them by hand with the screen off (its
// scores on the same poses' clean readings equal); the same poses without outliers lose no row.
TEST_F(OutlierScreen, SeveralPointsOnTheFlangeEachRowJudgedByItsOwnPointsField) {
  const std::string simulate =
      "simulate --robot kr16 --seed 21 --sample scattered:150 --orientation-spread 30 --systematic realistic "
      "--reflectors \"0,0,100;150,0,100;0,150,100\" --truth-columns --measure positions --robot-out r.json ";
  ASSERT_EQ(run(simulate + "--outliers 0.01:3 --out d.csv").exit_code, 0);
  ASSERT_EQ(run(simulate + "--out clean.csv").exit_code, 0);
  nlohmann::json robot = nlohmann::json::parse(read("r.json"));
  robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 100.0}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  write("r100.json", robot.dump());
  const CsvTable data = CsvTable::read(path("d.csv"));
  std::set<std::string> injected;
  std::vector<std::size_t> injected_rows;
  for (std::size_t i = 0; i < data.row_count(); ++i)
    if (data.row(i)[data.column_index("outlier")] == "1") {
      injected.insert(data.row(i)[data.column_index("point")] + " (" + data.row(i)[data.column_index("reflector")] + ")");
      injected_rows.push_back(i);
    }
  ASSERT_GE(injected.size(), 3u);
  const auto f = run("fit --robot r100.json --data d.csv --out m.json");
  ASSERT_EQ(f.exit_code, 0) << f.output();
  EXPECT_EQ(excluded_rows_of(read("m.json")), injected) << f.err;
  EXPECT_NE(f.err.find("from what its neighbours in its own point's field predict"), std::string::npos) << f.err;
  // By hand: the rows removed, the screen off.
  rewrite("d.csv", "by_hand.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string&) { return true; },
          [&](std::size_t i) { return !std::binary_search(injected_rows.begin(), injected_rows.end(), i); });
  ASSERT_EQ(run("fit --robot r100.json --data by_hand.csv --outlier-limit 0 --out hand.json").exit_code, 0);
  for (const std::string model : {"m", "hand"})
    ASSERT_EQ(run("validate --model " + model + ".json --data clean.csv --reflector r2 --summary-out " + model + "_s.json").exit_code, 0);
  const nlohmann::json screened = nlohmann::json::parse(read("m_s.json")), hand = nlohmann::json::parse(read("hand_s.json"));
  EXPECT_NEAR(screened["position"]["after"]["rms_mm"].get<double>(), hand["position"]["after"]["rms_mm"].get<double>(), 1e-9);
  EXPECT_NEAR(screened["uncertainty"]["coverage95"].get<double>(), hand["uncertainty"]["coverage95"].get<double>(), 1e-12);
  const auto c = run("fit --robot r100.json --data clean.csv --out c.json");
  ASSERT_EQ(c.exit_code, 0) << c.output();
  EXPECT_TRUE(excluded_rows_of(read("c.json")).empty()) << c.err;
}

}  // namespace outlier_screen_cli_test
}  // namespace errfield::compensation
