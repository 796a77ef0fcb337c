// `errfield plan --candidates` (issue 21): the next poses to measure from a pool, with and without a
// fitted model, on SIMULATED data of a KR16 (scattered joints, not the built-in grid set-up).

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace plan_candidates_cli_test {

constexpr const char* kBox = "-60,60,-100,-40,20,110,-90,90,30,100,-90,90";

class PlanCandidates : public testing::CliTest {
 protected:
  /// A SIMULATED pool of `n` KR16 poses (already "measured": mx,my,mz), a first batch of it in
  /// first.csv (rows 1..k), and held-out poses of the same robot in hold.csv.
  void make_pool(int n) {
    const auto r = run("simulate --robot kr16 --seed 5 --sample scattered:" + std::to_string(n) + " --joint-box " + kBox +
                       " --measure positions --joint-decimals 3 --robot-out r.json --out all.csv");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  void take_rows(const std::string& in, const std::string& out, std::size_t from, std::size_t to) {
    rewrite(in, out, [](const CsvTable&, std::size_t, std::vector<std::string>&) {}, [](const std::string&) { return true; },
            [from, to](std::size_t i) { return i >= from && i < to; });
  }
  std::vector<std::string> points(const std::string& file) {
    const CsvTable t = CsvTable::read(path(file));
    std::vector<std::string> p;
    for (std::size_t i = 0; i < t.row_count(); ++i) p.push_back(t.row(i)[t.column_index("point")]);
    return p;
  }
};

TEST_F(PlanCandidates, WithoutAModelChoosesSpreadPosesNeverMeasuredKeepingEveryColumn) {
  make_pool(160);
  take_rows("all.csv", "pool.csv", 1, 161);  // the targets (row 0 is the base point)
  take_rows("all.csv", "measured.csv", 1, 21);
  const auto r = run("plan --robot r.json --candidates pool.csv --count 30 --data measured.csv --out next.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("maximin"), std::string::npos) << r.out;
  const CsvTable pool = CsvTable::read(path("pool.csv")), next = CsvTable::read(path("next.csv"));
  ASSERT_EQ(next.row_count(), 30u);
  EXPECT_EQ(next.header(), pool.header());  // all the pool's columns, as they were
  const auto measured = points("measured.csv");
  const std::set<std::string> done(measured.begin(), measured.end());
  std::set<std::string> chosen;
  for (const auto& p : points("next.csv")) {
    EXPECT_FALSE(done.count(p)) << p << " was measured already";
    EXPECT_TRUE(chosen.insert(p).second) << p << " chosen twice";
  }
  // Each chosen row is the pool's row of that point, cell for cell.
  for (std::size_t i = 0; i < next.row_count(); ++i) {
    bool found = false;
    for (std::size_t j = 0; j < pool.row_count() && !found; ++j) found = pool.row(j) == next.row(i);
    EXPECT_TRUE(found) << "row " << i;
  }
  // Spread: the smallest distance between two chosen poses, each joint in units of its standard
  // deviation over the candidates not yet measured (what the design scales by), is larger than in
  // a random batch of the same size (the pool's order is random: scattered sampling).
  std::vector<std::vector<double>> open;
  for (std::size_t i = 0; i < pool.row_count(); ++i)
    if (!done.count(pool.row(i)[pool.column_index("point")])) {
      std::vector<double> v;
      for (int k = 1; k <= 6; ++k) v.push_back(pool.numeric_cell(i, pool.column_index("q" + std::to_string(k))));
      open.push_back(v);
    }
  std::vector<double> sd(6);
  for (int k = 0; k < 6; ++k) {
    double m = 0.0, ss = 0.0;
    for (const auto& v : open) m += v[k] / static_cast<double>(open.size());
    for (const auto& v : open) ss += (v[k] - m) * (v[k] - m);
    sd[static_cast<std::size_t>(k)] = std::sqrt(ss / static_cast<double>(open.size() - 1));
  }
  auto min_distance = [&](const CsvTable& t) {
    double best = 1e300;
    for (std::size_t i = 0; i < t.row_count(); ++i)
      for (std::size_t j = i + 1; j < t.row_count(); ++j) {
        double d = 0.0;
        for (int k = 1; k <= 6; ++k) {
          const std::size_t c = t.column_index("q" + std::to_string(k));
          const double x = (t.numeric_cell(i, c) - t.numeric_cell(j, c)) / sd[static_cast<std::size_t>(k - 1)];
          d += x * x;
        }
        best = std::min(best, std::sqrt(d));
      }
    return best;
  };
  take_rows("pool.csv", "random30.csv", 20, 50);  // 30 rows not measured, in the pool's random order
  EXPECT_GT(min_distance(next), 1.5 * min_distance(CsvTable::read(path("random30.csv"))));
  // Deterministic.
  ASSERT_EQ(run("plan --robot r.json --candidates pool.csv --count 30 --data measured.csv --out again.csv").exit_code, 0);
  EXPECT_EQ(read("again.csv"), read("next.csv"));
}

TEST_F(PlanCandidates, WithAModelPredictsTheRmsAndAnswersATarget) {
  make_pool(200);
  take_rows("all.csv", "pool.csv", 1, 201);
  take_rows("all.csv", "measured.csv", 1, 81);
  ASSERT_EQ(run("fit --robot r.json --data measured.csv --out m.json").exit_code, 0);
  const auto r = run("plan --candidates pool.csv --count 20 --model m.json --data measured.csv --target-rms 1000 "
                     "--summary-out s.json --out next.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("variance reduction"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("at least 0.7 of the farthest"), std::string::npos) << r.out;  // the default spacing floor
  for (const std::string bad : {"1", "-0.2", "nan"}) {
    const auto f = run("plan --candidates pool.csv --count 5 --model m.json --data measured.csv --spacing-floor " + bad +
                       " --out bad_floor.csv");
    EXPECT_EQ(f.exit_code, 2) << bad << "\n" << f.err;
    EXPECT_NE(f.err.find("--spacing-floor"), std::string::npos) << bad << "\n" << f.err;
    EXPECT_FALSE(std::filesystem::exists(path("bad_floor.csv"))) << bad;
  }
  const auto s = nlohmann::json::parse(read("s.json"));
  const double now = s["predicted_rms_mm"]["now"].get<double>(), after = s["predicted_rms_mm"]["after"].get<double>();
  EXPECT_GT(now, 0.0);
  EXPECT_LT(after, now);  // 20 more readings never leave the prediction where it was
  EXPECT_EQ(s["poses_for_target"].get<int>(), 0);  // 1 m is reached already
  const auto measured = points("measured.csv");
  for (const auto& p : points("next.csv")) EXPECT_EQ(std::count(measured.begin(), measured.end(), p), 0) << p;
  // The fitted model refuses poses beyond the box of its samples' joints widened by its margin:
  // after a batch no pool pose may lie beyond the box of the measured and chosen poses so widened.
  // Returns whether some pool pose lay beyond it before the batch.
  auto check_region_covered = [&](const std::string& model, const std::string& data, const std::string& chosen,
                                  const std::string& out) {
    const auto field = nlohmann::json::parse(read(model))["field"];
    EXPECT_EQ(field["space"], "joint");
    const double margin = field["region_margin_deg"].get<double>();
    const CsvTable pool = CsvTable::read(path("pool.csv")), done = CsvTable::read(path(data)),
                   next = CsvTable::read(path(chosen));
    bool was_outside = false;
    for (int k = 1; k <= 6; ++k) {
      const std::string q = "q" + std::to_string(k);
      const auto a = done.numeric_column(q), b = next.numeric_column(q), all = pool.numeric_column(q);
      const double lo0 = *std::min_element(a.begin(), a.end()) - margin;
      const double hi0 = *std::max_element(a.begin(), a.end()) + margin;
      const double lo = std::min(lo0, *std::min_element(b.begin(), b.end()) - margin);
      const double hi = std::max(hi0, *std::max_element(b.begin(), b.end()) + margin);
      for (double v : all) {
        was_outside = was_outside || v < lo0 || v > hi0;
        EXPECT_GE(v, lo) << q << " after " << chosen;
        EXPECT_LE(v, hi) << q << " after " << chosen;
      }
    }
    EXPECT_EQ(was_outside, out.find("extend the fitted region") != std::string::npos) << out;
    return was_outside;
  };
  check_region_covered("m.json", "measured.csv", "next.csv", r.out);
  // From 25 measured poses much of the pool lies beyond their box: the batch starts by extending it.
  take_rows("all.csv", "measured25.csv", 1, 26);
  ASSERT_EQ(run("fit --robot r.json --data measured25.csv --out m25.json").exit_code, 0);
  const auto r25 = run("plan --candidates pool.csv --count 20 --model m25.json --data measured25.csv --out next25.csv");
  ASSERT_EQ(r25.exit_code, 0) << r25.err;
  EXPECT_TRUE(check_region_covered("m25.json", "measured25.csv", "next25.csv", r25.out));
  // A target below the nugget is never reached: said, not a number made up.
  const auto t = run("plan --candidates pool.csv --count 20 --model m.json --data measured.csv --target-rms 1e-6 "
                     "--summary-out t.json --out next2.csv");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_NE(t.out.find("not reached"), std::string::npos) << t.out;
  EXPECT_TRUE(nlohmann::json::parse(read("t.json"))["poses_for_target"].is_null());
}

TEST_F(PlanCandidates, TheStoppingRuleSaysItsUncertaintyAndAdvisesARange) {
  // Issue 35: the prediction's level is the mean of the model's leave-one-out z² (fit's mean, not
  // the 95 % tail factor its calibration may take), its 90 % range the standard error of that mean,
  // and --target-rms advice a range of poses, withheld while the range covers the target.
  make_pool(200);
  take_rows("all.csv", "pool.csv", 1, 201);
  take_rows("all.csv", "measured.csv", 1, 81);
  // vector-kriging: the prediction is the field's alone (no joint error functions' term), so the
  // level scales it exactly.
  ASSERT_EQ(run("fit --robot r.json --data measured.csv --method vector-kriging --out m.json").exit_code, 0);
  const auto r = run("plan --candidates pool.csv --count 20 --model m.json --data measured.csv --summary-out s.json --out n.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("90 % range"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("80 leave-one-out scores"), std::string::npos) << r.out;
  const auto s = nlohmann::json::parse(read("s.json"))["predicted_rms_mm"];
  const double now = s["now"].get<double>(), se = s["mse_relative_se"].get<double>();
  EXPECT_EQ(s["leave_one_out_scores"].get<int>(), 80);
  ASSERT_GT(se, 0.0);
  EXPECT_LT(se, 1.0);
  // The ends are the mean square times 1 -/+ 1.645 standard errors.
  EXPECT_NEAR(s["now_range"][0].get<double>(), now * std::sqrt(1.0 - 1.645 * se), 1e-12);
  EXPECT_NEAR(s["now_range"][1].get<double>(), now * std::sqrt(1.0 + 1.645 * se), 1e-12);
  // A calibration that took the tail (factor twice the mean z²) leaves the predicted mean square at
  // half of what the calibrated variance says: the stopping rule predicts a mean, not a 95 % radius.
  {
    auto m = nlohmann::json::parse(read("m.json"));
    auto& c = m["field"]["variance_calibration"];
    ASSERT_TRUE(c.contains("factor")) << c.dump();
    c["mean_squared_z_before"] = 0.5 * c["factor"].get<double>();
    write("half.json", m.dump());
    ASSERT_EQ(run("plan --candidates pool.csv --count 20 --model half.json --data measured.csv --summary-out h.json "
                  "--out h.csv").exit_code, 0);
    const double half = nlohmann::json::parse(read("h.json"))["predicted_rms_mm"]["now"].get<double>();
    const double full = now * std::sqrt(c["factor"].get<double>() / nlohmann::json::parse(read("m.json"))["field"]
                                              ["variance_calibration"]["mean_squared_z_before"].get<double>());
    EXPECT_NEAR(half * half, 0.5 * full * full, 1e-9 * full * full);
    EXPECT_EQ(read("h.csv"), read("n.csv"));  // a common factor changes no pick
  }
  // A target inside the range now: no count (it would be the estimate's noise), and the summary's
  // range starts at 0.
  const double inside = now * std::sqrt(1.0 - 0.5 * 1.645 * se);
  auto exact = [](double v) {
    std::ostringstream o;
    o << std::setprecision(17) << v;
    return o.str();
  };
  const auto w = run("plan --candidates pool.csv --count 20 --model m.json --data measured.csv --target-rms " +
                     exact(inside) + " --summary-out w.json --out w.csv");
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_NE(w.out.find("within the prediction's 90 % range now"), std::string::npos) << w.out;
  EXPECT_EQ(nlohmann::json::parse(read("w.json"))["poses_for_target_range"][0].get<int>(), 0);
  // A target the prediction reaches after 15 poses (below the low end now): a count and its range
  // around it, low <= central <= high.
  const double after15 = s["by_pose"][15].get<double>();
  ASSERT_LT(after15, s["now_range"][0].get<double>()) << "the draw no longer shows a fall beyond the range";
  const auto t = run("plan --candidates pool.csv --count 20 --model m.json --data measured.csv --target-rms " +
                     exact(after15 * (1.0 + 1e-12)) + " --summary-out t.json --out t.csv");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const auto ts = nlohmann::json::parse(read("t.json"));
  EXPECT_EQ(ts["poses_for_target"].get<int>(), 15) << t.out;
  const auto& range = ts["poses_for_target_range"];
  EXPECT_LE(range[0].get<int>(), 15);
  if (!range[1].is_null()) EXPECT_GE(range[1].get<int>(), 15);
  EXPECT_NE(t.out.find("about 15 more poses chosen this way (90 % range "), std::string::npos) << t.out;
}

TEST_F(PlanCandidates, MisuseIsRefusedNamingTheOption) {
  make_pool(40);
  take_rows("all.csv", "pool.csv", 1, 41);
  const std::vector<std::pair<std::string, std::string>> cases{
      {"plan --robot r.json --candidates pool.csv --out n.csv", "--count"},
      {"plan --robot r.json --candidates pool.csv --count 5 --target-rms 0.1 --out n.csv", "--target-rms needs --model"},
      {"plan --robot r.json --candidates pool.csv --count 5 --cube 0,0,0,100 --out n.csv", "--cube"},
      {"plan --robot r.json --candidates pool.csv --count 50 --out n.csv", "--count 50"},
      {"plan --robot r.json --count 5 --out n.csv", "--candidates"},
      {"plan --robot r.json --candidates bad.csv --count 5 --out n.csv", "300"},
  };
  rewrite("pool.csv", "bad.csv", [](const CsvTable& t, std::size_t i, std::vector<std::string>& cells) {
    if (i == 2) cells[t.column_index("q2")] = "300";  // beyond A2's [-155, 35]
  });
  for (const auto& [line, word] : cases) {
    const auto r = run(line);
    EXPECT_EQ(r.exit_code, 2) << line << "\n" << r.err;
    EXPECT_NE(r.err.find(word), std::string::npos) << line << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(path("n.csv"))) << line;
  }
  // A kinematic model has no field to plan for.
  take_rows("all.csv", "measured.csv", 1, 31);
  ASSERT_EQ(run("fit --robot r.json --data measured.csv --method kinematic --out k.json").exit_code, 0);
  const auto k = run("plan --candidates pool.csv --count 5 --model k.json --data measured.csv --out n.csv");
  EXPECT_EQ(k.exit_code, 2) << k.err;
  EXPECT_NE(k.err.find("no error field"), std::string::npos) << k.err;
}

// Issue 35: poses measured already (data without a point column) or repeated in the pool were
// chosen again, and --count -1 wrapped to 2^64 - 1. Joints match exactly as read.
TEST_F(PlanCandidates, MeasuredAndRepeatedPosesAreNeverChosenAgain) {
  make_pool(40);
  take_rows("all.csv", "pool.csv", 1, 41);
  // The first 20 pool poses measured, written without their point labels.
  rewrite("all.csv", "measured.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& c) { return c != "point"; }, [](std::size_t i) { return i >= 1 && i < 21; });
  const auto r = run("plan --robot r.json --candidates pool.csv --count 15 --data measured.csv --out next.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("20 pool row(s) have the joints of a pose in measured.csv"), std::string::npos) << r.err;
  const auto all = points("pool.csv");
  const std::set<std::string> measured(all.begin(), all.begin() + 20);
  for (const auto& p : points("next.csv")) EXPECT_FALSE(measured.count(p)) << p << " was measured already";
  // 20 poses are left: 25 cannot be chosen without repeating measured ones (before: 5 were).
  const auto over = run("plan --robot r.json --candidates pool.csv --count 25 --data measured.csv --out over.csv");
  EXPECT_EQ(over.exit_code, 2) << over.err;
  EXPECT_NE(over.err.find("--count: 25 poses asked, but 20 of the 40 candidates"), std::string::npos) << over.err;
  EXPECT_FALSE(std::filesystem::exists(path("over.csv")));
  // A pool whose row 3 comes four more times (other labels): never chosen twice.
  std::string text = read("pool.csv");
  const CsvTable pool = CsvTable::read(path("pool.csv"));
  for (int copy = 0; copy < 4; ++copy) {
    std::vector<std::string> row = pool.row(2);
    row[pool.column_index("point")] = "copy" + std::to_string(copy);
    std::string line;
    for (const auto& c : row) line += (line.empty() ? "" : ",") + c;
    text += line + "\n";
  }
  write("repeats.csv", text);
  const auto d = run("plan --robot r.json --candidates repeats.csv --count 44 --out d.csv");
  EXPECT_EQ(d.exit_code, 2) << d.err;
  EXPECT_NE(d.err.find("4 repeat an earlier candidate"), std::string::npos) << d.err;
  const auto e = run("plan --robot r.json --candidates repeats.csv --count 40 --out e.csv");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.err.find("4 pool row(s) repeat the joints of an earlier row and were left out (repeats.csv:42"),
            std::string::npos)
      << e.err;
  const auto chosen = points("e.csv");
  EXPECT_EQ(std::set<std::string>(chosen.begin(), chosen.end()).size(), 40u);
  for (const auto& p : chosen) EXPECT_NE(p.rfind("copy", 0), 0u) << p;
  // Negative counts are refused, not wrapped.
  const auto neg = run("plan --robot r.json --candidates pool.csv --count -1 --out neg.csv");
  EXPECT_EQ(neg.exit_code, 2) << neg.err;
  EXPECT_NE(neg.err.find("--count"), std::string::npos) << neg.err;
  EXPECT_NE(neg.err.find("negative"), std::string::npos) << neg.err;
}

// Issue 35: hand-edited models crashed plan (a coefficient covariance x1e18, a gravity scale of
// 1e-300: heap corruption) or planned in silence for another robot (its pool, --robot, a swapped
// command model); `plan --out X > /dev/full` replaced X, then exited 1.
TEST_F(PlanCandidates, HandEditedModelsAnotherRobotAndAFullStandardOutputAreRefused) {
  make_pool(40);
  take_rows("all.csv", "pool.csv", 1, 41);
  take_rows("all.csv", "measured.csv", 1, 31);
  ASSERT_EQ(run("fit --robot r.json --data measured.csv --out m.json").exit_code, 0);
  const nlohmann::json m = nlohmann::json::parse(read("m.json"));
  ASSERT_TRUE(m["joint_error_functions"].contains("gravity_terms"));
  auto refused = [&](const std::string& line, const std::string& word) {
    const auto r = run(line);
    EXPECT_EQ(r.signal, 0) << line;
    EXPECT_EQ(r.exit_code, 2) << line << "\n" << r.err;
    EXPECT_NE(r.err.find(word), std::string::npos) << line << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(path("n.csv"))) << line;
  };
  nlohmann::json scaled = m;
  for (auto& row : scaled["joint_error_functions"]["coefficient_covariance_mrad2"])
    for (auto& v : row) v = v.get<double>() * 1e18;
  write("scaled.json", scaled.dump());
  refused("plan --candidates pool.csv --count 5 --model scaled.json --data measured.csv --out n.csv",
          "scaled.json: member \"joint_error_functions.coefficient_covariance_mrad2\"");
  nlohmann::json tiny = m;
  tiny["joint_error_functions"]["gravity_terms"][0]["scale_m"] = 1e-300;
  write("tiny.json", tiny.dump());
  refused("plan --candidates pool.csv --count 5 --model tiny.json --data measured.csv --out n.csv",
          "gravity_terms\"[0].scale_m");
  // A UR5e's command model inside this KR16 model.
  nlohmann::json swapped = m;
  swapped["command_model"] = robot::find_builtin_robot("ur5e")->model.to_json();
  write("swapped.json", swapped.dump());
  refused("plan --candidates pool.csv --count 5 --model swapped.json --data measured.csv --out n.csv",
          "member \"command_model\" ('UR5e') is not a calibration of the \"nominal_model\"");
  refused("plan --robot ur5e --candidates pool.csv --count 5 --model m.json --data measured.csv --out n.csv",
          "--robot ur5e is not the robot of --model m.json");
  // Another robot's poses (measured, within both robots' joint limits) as the pool.
  ASSERT_EQ(run("simulate --robot ur5e --seed 6 --sample scattered:12 --joint-box " + std::string(kBox) +
                " --measure positions --out ur.csv")
                .exit_code,
            0);
  take_rows("ur.csv", "ur_pool.csv", 1, 13);
  refused("plan --robot r.json --candidates ur_pool.csv --count 5 --out n.csv", "ur_pool.csv");
  refused("plan --candidates ur_pool.csv --count 5 --model m.json --data measured.csv --out n.csv", "ur_pool.csv");
  // All or nothing with a standard output that cannot be written.
  write("n.csv", "previous\n");
  const auto full = errfield::testing::run_errfield_to_full_stdout(
      {"plan", "--robot", path("r.json"), "--candidates", path("pool.csv"), "--count", "5", "--out", path("n.csv")}, dir());
  ASSERT_EQ(full.signal, 0);
  EXPECT_EQ(full.exit_code, 1) << full.err;
  EXPECT_NE(full.err.find("cannot write to standard output"), std::string::npos) << full.err;
  EXPECT_EQ(read("n.csv"), "previous\n") << "a run that failed replaced its output";
}

TEST_F(PlanCandidates, PredictedRmsHoldsOnHeldOutPoses) {
  // The stopping rule's number is a claim: the 3-D RMS that `plan` predicts for the model's own
  // poses (a new reading anywhere in the pool) against the RMS `validate` measures on held-out poses
  // of the same pool. SIMULATED KR16 with the realistic systematic effects (growing at the
  // workspace edges), varying orientation and joints to 3 decimals; 160 poses fitted, 200 held out.
  // Issue 35's bar: within 10 % (this draw: 0.117 predicted, 0.109 held out; 1.08).
  const auto sim = run("simulate --robot kr16 --seed 8 --sample scattered:360 --joint-box "
                       "-150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --systematic realistic "
                       "--orientation-spread 30 --joint-decimals 3 --measure positions --robot-out r.json --out all.csv");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  take_rows("all.csv", "train.csv", 1, 161);
  take_rows("all.csv", "hold.csv", 161, 361);
  take_rows("all.csv", "pool.csv", 1, 361);
  ASSERT_EQ(run("fit --robot r.json --data train.csv --out m.json").exit_code, 0);
  const auto v = run("validate --model m.json --data hold.csv --summary-out v.json");
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const auto p = run("plan --candidates pool.csv --count 1 --model m.json --data train.csv --summary-out p.json --out n.csv");
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const double achieved = nlohmann::json::parse(read("v.json"))["position"]["after"]["rms_mm"].get<double>();
  const double predicted = nlohmann::json::parse(read("p.json"))["predicted_rms_mm"]["now"].get<double>();
  EXPECT_NEAR(predicted / achieved, 1.0, 0.1) << "predicted " << predicted << " mm, held-out " << achieved << " mm";
}

// A campaign read at three nests on one plate (SIMULATED KR16, `simulate --reflectors`), as a first
// batch of 40 poses: the pool with its three rows per pose was refused by plan as "not the FK of the
// robot" (each label's x,y,z is its own nest's nominal position); fit on those 40 poses wrote models
// its own loader refused, with the robot JSON's tool at the nest r1 ("flange_points"[1]: 0.26 mm
// from the nominal distance, limit 0.2) and with the tool at the flange, as `--robot-out` writes it
// ("field.samples"[0]: 120 mm from the FK). Another robot is still refused, naming the nest.
TEST_F(PlanCandidates, AFirstBatchReadAtSeveralNestsPlansFitsAndLoads) {
  ASSERT_EQ(run("simulate --robot kr16 --seed 5 --sample scattered:40 --joint-box "
                "-150,150,-130,-30,70,150,-90,90,-110,110,-180,180 --orientation-spread 30 --measure positions "
                "--reflectors \"0,0,120;60,0,110;0,60,110\" --robot-out kr16.json --out nests.csv")
                .exit_code,
            0);
  nlohmann::json robot = nlohmann::json::parse(read("kr16.json"));
  ASSERT_NEAR(robot["tool"]["z_mm"].get<double>(), 0.0, 1e-12);  // the flange: the case that failed
  robot["tool"] = {{"x_mm", 0.0}, {"y_mm", 0.0}, {"z_mm", 120.0}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  write("kr16_r1.json", robot.dump());

  const auto plan = run("plan --robot kr16.json --candidates nests.csv --count 5 --out next.csv");
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  EXPECT_EQ(points("next.csv").size(), 5u);  // a pose's three rows count once
  ASSERT_EQ(run("robots --show ur10 --out ur10.json").exit_code, 0);
  const auto other = run("plan --robot ur10.json --candidates nests.csv --count 5 --out other.csv");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("(reflector r1)"), std::string::npos) << other.err;

  ASSERT_EQ(run("fit --robot kr16_r1.json --data nests.csv --out at_r1.json").exit_code, 0);
  const auto v = run("validate --model at_r1.json --data nests.csv --reflector r2");
  EXPECT_EQ(v.exit_code, 0) << v.err;
  const nlohmann::json m = nlohmann::json::parse(read("at_r1.json"));
  ASSERT_EQ(m["flange_points"].size(), 3u);
  // The nominal positions are the calibrated ones moved rigidly: every distance agrees.
  auto point = [&](std::size_t k, const char* member) {
    const auto& a = m["flange_points"][k][member];
    return std::array<double, 3>{a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
  };
  auto apart = [](std::array<double, 3> a, std::array<double, 3> b) {
    return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
  };
  for (std::size_t a = 0; a < 3; ++a)
    for (std::size_t b = a + 1; b < 3; ++b)
      EXPECT_NEAR(apart(point(a, "mm"), point(b, "mm")), apart(point(a, "nominal_mm"), point(b, "nominal_mm")), 1e-9);

  ASSERT_EQ(run("fit --robot kr16.json --data nests.csv --out at_flange.json").exit_code, 0);
  const auto p = run("predict --model at_flange.json --joints nests.csv --out p.csv");
  EXPECT_EQ(p.exit_code, 0) << p.err;
}

}  // namespace plan_candidates_cli_test
}  // namespace errfield
