// The predictive uncertainty `validate` checks (coverage95: the share of held-out readings within the
// predicted 95 % radius r95_mm; for distance fields the share within 1.96 sigma of the predicted
// distance error) for every method that reports a variance, as a user runs them: simulate, fit
// with defaults, validate on rows the fit never saw (issue 19, item 1). SIMULATED data.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/session_split.hpp"

namespace errfield::compensation {
namespace predictive_coverage_cli_test {

struct Uncertainty {
  double coverage = NAN, mean_nees = NAN, points = 0;
};

class PredictiveCoverage : public errfield::testing::CliTest {
 protected:
  /// Splits `all` into train.csv (base rows and the first n_train targets) and hold.csv (base rows
  /// and the rest): one session, so both share the base point's reading, as a split data set does.
  void split(const std::string& all, std::size_t n_train) {
    const errfield::testing::SessionSplit parts = errfield::testing::split_session(read(all), n_train);
    ASSERT_GT(parts.targets, n_train);
    write("train.csv", parts.train);
    write("hold.csv", parts.hold);
  }

  /// SIMULATED KR 16 data that look real: scattered poses at orientations within 30 deg, joints
  /// recorded to 2 decimals, realistic systematic effects (gravity compliance, errors growing at the
  /// ends of q1's and q5's travel, cyclic joint errors); 200 training and 400 held-out targets.
  void simulate_realistic_kr16() {
    ASSERT_EQ(run("simulate --robot kr16 --seed 5 --sample scattered:600 --systematic realistic "
                  "--orientation-spread 30 --joint-decimals 2 --robot-out r.json --out all.csv")
                  .exit_code,
              0);
    split("all.csv", 200);
  }

  /// fit `options` on `train`, validate on `hold`: the summary's uncertainty, or for a distance
  /// field (no 3-D variance) the share of distance errors within 1.96 sigma and the mean z².
  Uncertainty fit_and_validate(const std::string& options, const std::string& train = "train.csv",
                               const std::string& hold = "hold.csv", std::string* fit_output = nullptr) {
    const errfield::testing::CliResult f = run("fit --robot r.json --data " + train + " " + options + " --out m.json");
    EXPECT_EQ(f.exit_code, 0) << options << "\n" << f.output();
    if (fit_output) *fit_output = f.out;
    const errfield::testing::CliResult v =
        run("validate --model m.json --robot r.json --data " + hold + " --summary-out s.json --out points.csv");
    EXPECT_EQ(v.exit_code, 0) << options << "\n" << v.output();
    Uncertainty u;
    const nlohmann::json s = nlohmann::json::parse(read("s.json"));
    if (s.contains("uncertainty") && s["uncertainty"].is_object()) {
      u.coverage = s["uncertainty"]["coverage95"].get<double>();
      u.mean_nees = s["uncertainty"]["mean_nees"].get<double>();
      u.points = s["uncertainty"]["points"].get<double>();
      return u;
    }
    const CsvTable t = CsvTable::read(path("points.csv"));
    double within = 0, z2 = 0;
    for (std::size_t i = 0; i < t.row_count(); ++i) {
      if (t.row(i)[t.column_index("status")] != "ok") continue;
      const double e = t.numeric_cell(i, t.column_index("after_dl_b0"));
      const double var = t.numeric_cell(i, t.column_index("var_mm2"));
      u.points += 1;
      within += std::abs(e) <= 1.959963984540054 * std::sqrt(var);
      z2 += e * e / var;
    }
    u.coverage = within / u.points;
    u.mean_nees = z2 / u.points;
    return u;
  }

  /// coverage95 within 4 binomial standard errors of 0.95: sqrt(0.95 * 0.05 / n) is the standard
  /// error of a share of n independent readings (0.011 for 400; band 0.906-0.994). Held-out rows
  /// share their training data, so their errors are not quite independent: 4, not 2, errors wide.
  void expect_coverage_holds(const std::string& options) {
    const Uncertainty u = fit_and_validate(options);
    const double se = std::sqrt(0.95 * 0.05 / u.points);
    std::cout << "SIMULATED KR 16, " << (options.empty() ? "defaults" : options) << ": coverage95 " << u.coverage
              << ", mean z^2 " << u.mean_nees << " on " << u.points << " held-out readings\n";
    EXPECT_GE(u.points, 380.0) << options;
    EXPECT_NEAR(u.coverage, 0.95, 4.0 * se) << options;
  }

  void expect_task_space_model_holds_between_grid_nodes(const std::string& method);
};

TEST_F(PredictiveCoverage, DefaultFitHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("");
}

TEST_F(PredictiveCoverage, KinematicKrigingInTaskSpaceHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("--method kinematic+kriging --space task");
}

TEST_F(PredictiveCoverage, VectorKrigingHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("--method vector-kriging");
}

TEST_F(PredictiveCoverage, VectorKrigingInTaskSpaceHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("--method vector-kriging --space task");
}

TEST_F(PredictiveCoverage, DistanceKrigingHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("--method distance-kriging");
}

TEST_F(PredictiveCoverage, DistanceKrigingInTaskSpaceHoldsOnRealisticKr16Data) {
  simulate_realistic_kr16();
  expect_coverage_holds("--method distance-kriging --space task");
}

/// The paper's set-up: 125 mm grid, held out one random point per cell (64, between the nodes).
/// The mean NEES (mean of |e|²/σ² over the axes) of n readings is 3 with standard error sqrt(6 / n)
/// (a χ²₃ has variance 6): 0.31 for 64, band 4 errors wide (1.78-4.22). The task-space model fitted
/// to the empirical variogram, the default until issue 19, fitted no nugget (the first lag is
/// 125 mm) and claimed too small a variance between the nodes for kinematic+kriging (NEES 6.1) and
/// too large for vector-kriging (1.3); the REML model must hold, the old one, on the same field
/// values, must not.
void PredictiveCoverage::expect_task_space_model_holds_between_grid_nodes(const std::string& method) {
  ASSERT_EQ(run("simulate --seed 1 --sample grid --step 125 --robot-out r.json --out grid.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --seed 2 --sample cells --step 125 --out cells.csv").exit_code, 0);
  // The comparison is of two variogram estimators on the same field values: without joint error
  // functions, whose own variance (and their share of the residuals) would blur it; with them
  // (the default) DefaultFitHoldsOnRealisticKr16Data checks the coverage.
  const std::string options =
      "--method " + method + " --space task" + (method == "kinematic+kriging" ? " --joint-functions 0" : "");
  std::string said;
  const Uncertainty u = fit_and_validate(options, "grid.csv", "cells.csv", &said);
  const double band = 4.0 * std::sqrt(6.0 / u.points);
  EXPECT_EQ(u.points, 64.0) << method;
  EXPECT_NEAR(u.mean_nees, 3.0, band) << method << " (REML): mean NEES " << u.mean_nees;
  EXPECT_NEAR(u.coverage, 0.95, 4.0 * std::sqrt(0.95 * 0.05 / u.points)) << method;
  EXPECT_NE(said.find("REML"), std::string::npos) << said;
  // The old choice, on the same field values: the empirical-variogram fit, used as given.
  const nlohmann::json field = nlohmann::json::parse(read("m.json"))["field"];
  FieldSamples samples;
  Eigen::MatrixXd values(static_cast<Eigen::Index>(field["values"].size()), 3);
  for (std::size_t i = 0; i < field["values"].size(); ++i) {
    const auto& p = field["samples"]["position_mm"][i];
    samples.position_mm.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
    samples.joints_deg.push_back(robot::JointVector::Zero());
    for (int c = 0; c < 3; ++c)
      values(static_cast<Eigen::Index>(i), c) = field["values"][i][static_cast<std::size_t>(c)].get<double>();
  }
  const std::string old_model = estimate_field_variogram(samples, values, FieldSpace::task).to_string();
  const Uncertainty before =
      fit_and_validate(options + " --model \"" + old_model + "\" --variance-calibration none", "grid.csv", "cells.csv");
  std::cout << "SIMULATED paper grid, " << method << " in task space: mean NEES " << u.mean_nees << " (REML), "
            << before.mean_nees << " (empirical-variogram fit " << old_model << "); coverage95 " << u.coverage << ", "
            << before.coverage << "\n";
  EXPECT_GT(std::abs(before.mean_nees - 3.0), band) << method << ": the old model's mean NEES " << before.mean_nees;
}

TEST_F(PredictiveCoverage, KinematicKrigingTaskSpaceModelHoldsBetweenTheNodesOfTheGrid) {
  expect_task_space_model_holds_between_grid_nodes("kinematic+kriging");
}

TEST_F(PredictiveCoverage, VectorKrigingTaskSpaceModelHoldsBetweenTheNodesOfTheGrid) {
  expect_task_space_model_holds_between_grid_nodes("vector-kriging");
}

/// The multi-seed study behind docs/robot.md's "Predictive uncertainty" table (not in CI: ~60 fits;
/// scripts/measure_predictive_coverage.py prints the same figures): SIMULATED realistic data of the
/// KR 16 and the ER20, 300 training and 200 held-out poses of one session, seeds 1001-1005, every
/// variance method with its defaults. Pooled over the seeds (~980 readings, binomial standard error
/// 0.007) coverage95 must be within issue 19's 93-97 %.
class PredictiveCoverageStudy : public PredictiveCoverage {};

TEST_F(PredictiveCoverageStudy, EveryVarianceMethodWithinNinetyThreeToNinetySevenPercentPooledOverSeeds) {
  const std::vector<std::string> methods{"",
                                         "--method kinematic+kriging --space task",
                                         "--method vector-kriging",
                                         "--method vector-kriging --space task",
                                         "--method distance-kriging",
                                         "--method distance-kriging --space task"};
  for (const std::string robot : {"kr16", "er20-c10"}) {
    std::vector<double> within(methods.size(), 0.0), points(methods.size(), 0.0);
    for (int seed = 1001; seed <= 1005; ++seed) {
      ASSERT_EQ(run("simulate --robot " + robot + " --seed " + std::to_string(seed) +
                    " --sample scattered:500 --systematic realistic --orientation-spread 30 --joint-decimals 2 "
                    "--robot-out r.json --out all.csv")
                    .exit_code,
                0);
      split("all.csv", 300);
      for (std::size_t m = 0; m < methods.size(); ++m) {
        const Uncertainty u = fit_and_validate(methods[m]);
        within[m] += u.coverage * u.points;
        points[m] += u.points;
      }
    }
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const double coverage = within[m] / points[m];
      std::cout << "SIMULATED " << robot << ", " << (methods[m].empty() ? "defaults" : methods[m]) << ": coverage95 "
                << coverage << " pooled over 5 seeds, " << points[m] << " held-out readings\n";
      EXPECT_GE(coverage, 0.93) << robot << " " << methods[m];
      EXPECT_LE(coverage, 0.97) << robot << " " << methods[m];
    }
  }
}

}  // namespace predictive_coverage_cli_test
}  // namespace errfield::compensation
