#include "errfield/reproduction/paper_reproduction.hpp"

#include <gtest/gtest.h>

#include "errfield/reproduction/orientation_experiment.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <unistd.h>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "support/chromium_render.hpp"
#include "support/cli_harness.hpp"

namespace errfield::reproduction {
using namespace errfield::robot;
namespace paper_reproduction_test {

namespace fs = std::filesystem;

TEST(ErrorStats, AbsoluteValuesWithSampleStd) {
  const ErrorStats s = error_stats({-1.0, 2.0, -3.0, 0.0});
  EXPECT_DOUBLE_EQ(s.max_mm, 3.0);
  EXPECT_DOUBLE_EQ(s.mean_mm, 1.5);
  EXPECT_NEAR(s.std_mm, std::sqrt((0.25 + 0.25 + 2.25 + 2.25) / 3.0), 1e-15);  // |e| = 1,2,3,0
}

TEST(Spread, QuantilesLikeRType7) {
  // R: quantile(c(4,1,3,2,5), c(.25,.5,.75)) = 2, 3, 4
  const Spread s = spread_of({4, 1, 3, 2, 5});
  EXPECT_DOUBLE_EQ(s.median, 3);
  EXPECT_DOUBLE_EQ(s.q25, 2);
  EXPECT_DOUBLE_EQ(s.q75, 4);
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 5);
  // R: quantile(c(1,2,3,4), .25) = 1.75
  EXPECT_DOUBLE_EQ(spread_of({1, 2, 3, 4}).q25, 1.75);
}

TEST(ReproductionOptions, RejectsBadValues) {
  ReproductionOptions o;
  o.runs = 0;
  EXPECT_THROW(o.validate(), ArgumentError);
  o = {};
  o.grid_steps_mm = {30};  // does not divide 500
  EXPECT_THROW(o.validate(), ArgumentError);
}

ReproductionOptions small_options(int threads) {
  ReproductionOptions o;
  o.seed = 7;
  o.runs = 2;
  o.threads = threads;
  o.grid_steps_mm = {50, 125, 250};
  o.heldout_points = 100;
  o.orientation_training_poses = 150;
  o.orientation_validation_poses = 80;
  return o;
}

const OrientationExperimentRow& orientation_row(const OrientationExperiment& e, const std::string& orientation,
                                                const std::string& space) {
  for (const auto& r : e.rows)
    if (r.orientation == orientation && r.space == space) return r;
  throw std::runtime_error("orientation experiment: row missing: " + orientation + " " + space);
}

// Same seed, same numbers, on any thread count.
TEST(Reproduction, DeterministicAndThreadInvariant) {
  const ReproductionResult a = reproduce_paper(small_options(1));
  const ReproductionResult b = reproduce_paper(small_options(2));
  ASSERT_EQ(a.table6.rows.size(), b.table6.rows.size());
  for (std::size_t i = 0; i < a.table6.rows.size(); ++i) {
    EXPECT_EQ(a.table6.rows[i].method, b.table6.rows[i].method);
    EXPECT_EQ(a.table6.rows[i].mean_mm.median, b.table6.rows[i].mean_mm.median) << a.table6.rows[i].method;
    EXPECT_EQ(a.table6.rows[i].max_mm.max, b.table6.rows[i].max_mm.max);
  }
  ASSERT_EQ(a.grid_steps.size(), 3u);
  for (std::size_t i = 0; i < a.grid_steps.size(); ++i)
    EXPECT_EQ(a.grid_steps[i].rms_error_mm, b.grid_steps[i].rms_error_mm);
  for (std::size_t i = 0; i < a.joint_variogram.rows.size(); ++i)
    EXPECT_EQ(a.joint_variogram.rows[i].gamma_mm2, b.joint_variogram.rows[i].gamma_mm2);
  ASSERT_EQ(a.beyond_orientation.rows.size(), 6u);
  for (std::size_t i = 0; i < a.beyond_orientation.rows.size(); ++i) {
    EXPECT_EQ(a.beyond_orientation.rows[i].mean_mm, b.beyond_orientation.rows[i].mean_mm);
    EXPECT_EQ(a.beyond_orientation.rows[i].max_mm, b.beyond_orientation.rows[i].max_mm);
  }
  ReproductionOptions other = small_options(1);
  other.seed = 8;
  EXPECT_NE(reproduce_paper(other).table6.rows[0].mean_mm.median, a.table6.rows[0].mean_mm.median);
}

// Sanity that does not copy our own output: compensation must beat doing nothing on the paper's
// metric; finer grids must predict better than the coarsest; the variograms rise with lag like
// the paper's. The paper's full ordering is reported (printed), not asserted: the simulation may
// legitimately disagree, see docs/reproduction.md.
TEST(Reproduction, ResultsAreSane) {
  const ReproductionResult r = reproduce_paper(small_options(0));
  auto row = [&](const std::string& method, const std::string& metric) -> const Table6Row& {
    for (const auto& x : r.table6.rows)
      if (x.method == method && x.metric == metric) return x;
    throw std::runtime_error("row missing: " + method + " " + metric);
  };
  const double none = row("none", "distance").mean_mm.median;
  for (const std::string m : {"distance-idw", "position-idw"}) {
    EXPECT_LT(row(m, "distance").mean_mm.median, 0.5 * none) << m;
    EXPECT_EQ(row(m, "distance").failed_targets, 0u) << m;
  }
  // Kinematic calibration identifies the robot: it must reduce the error on both metrics, the 3-D
  // one included (before its frame was aligned over configurations and noise-level parameters were
  // kept out, it left the 3-D error above `none`'s).
  EXPECT_LT(row("kinematic", "distance").mean_mm.median, 0.5 * none);
  EXPECT_LT(row("kinematic", "position").mean_mm.median, 0.7 * row("none", "position").mean_mm.median);
  // The simulator's default error is of the paper's size on the paper's metric (Table 6 none:
  // 0.514 mm mean; SPEC section 7), not half of it.
  EXPECT_GT(none, 0.8 * 0.514);
  EXPECT_LT(none, 1.25 * 0.514);
  // the paper's method cannot remove the tangential error: position error stays well above its
  // distance error
  EXPECT_GT(row("distance-idw", "position").mean_mm.median, 2.0 * row("distance-idw", "distance").mean_mm.median);
  EXPECT_LT(r.grid_steps.front().rms_error_mm, r.grid_steps.back().rms_error_mm);
  for (const auto* v : {&r.joint_variogram, &r.task_variogram}) {
    ASSERT_EQ(v->rows.size(), 11u);
    EXPECT_LT(v->rows.front().gamma_mm2, v->rows.back().gamma_mm2);
    EXPECT_FALSE(v->fitted.components().empty());
  }
  // Beyond the paper: at constant orientation a position fixes the joints, so kriging in either
  // space must remove most of the error and the two spaces must agree (SPEC section 3); with the
  // orientation varying, the uncompensated error is larger (the wrist's errors add up differently).
  const auto& e = r.beyond_orientation;
  const double none_constant = orientation_row(e, "constant", "-").mean_mm;
  const double task_constant = orientation_row(e, "constant", "task").mean_mm;
  const double joint_constant = orientation_row(e, "constant", "joint").mean_mm;
  EXPECT_LT(task_constant, 0.3 * none_constant);
  EXPECT_LT(joint_constant, 0.3 * none_constant);
  // The joint-space field must not lose to the task-space one (its default model, chosen by REML
  // with one range per joint, may beat it: docs/kriging.md "Automatic model choice").
  EXPECT_LT(joint_constant, 1.5 * task_constant);
  EXPECT_GT(orientation_row(e, "varying", "-").mean_mm, none_constant);
  EXPECT_GT(e.orientation_effect_mean_mm, 0.0);
  std::cout << "[ orientation ] mean residual (mm): varying none/task/joint = "
            << orientation_row(e, "varying", "-").mean_mm << "/" << orientation_row(e, "varying", "task").mean_mm << "/"
            << orientation_row(e, "varying", "joint").mean_mm << ", constant = " << none_constant << "/"
            << task_constant << "/" << joint_constant << "\n";
  std::ostringstream order;
  for (const auto& x : r.table6.rows)
    if (x.metric == "distance") order << x.method << "=" << x.mean_mm.median << " ";
  std::cout << "[ ordering ] distance metric, median mean error (mm): " << order.str() << "\n";
}

TEST(OrientationExperiment, RejectsBadOptions) {
  const SimulatorConfig cfg = SimulatorConfig::paper_default();
  OrientationExperimentOptions o;
  o.training_poses = 7;
  EXPECT_THROW(run_orientation_experiment(cfg, o), ArgumentError);
  o = {};
  o.orientation_spread_deg = 0.0;
  EXPECT_THROW(run_orientation_experiment(cfg, o), ArgumentError);
  o = {};
  o.region_margin_mm = -1.0;
  EXPECT_THROW(run_orientation_experiment(cfg, o), ArgumentError);
  ReproductionOptions r;
  r.orientation_validation_poses = 0;
  EXPECT_THROW(r.validate(), ArgumentError);
}

// Independent ground truth: a robot whose only error is an offset d of its tool point, in the tool
// frame. Its position error is R_tool(q) d: a function of the tool orientation alone. At constant
// orientation it is one constant vector, which the registration absorbs exactly (a translation),
// so every method leaves only the tracker noise. With the orientation varying, the error at a
// position depends on the orientation the position is reached at: a task-space field cannot
// predict it (its samples near a target carry unrelated orientations), while it is a smooth
// function of the joints, which a joint-space field interpolates.
TEST(OrientationExperiment, ToolOffsetErrorIsSeenInJointSpaceOnly) {
  SimulatorConfig cfg = SimulatorConfig::paper_default();
  cfg.geometry = {};
  cfg.geometry.tool = {0.6, -0.5, 0.4, 0.0, 0.0, 0.0};  // |d| = 0.88 mm
  cfg.absorb_rigid_part = false;
  cfg.compliance.stiffness_nm_per_rad.fill(0.0);      // rigid joints
  cfg.transmission.amplitude_deg.fill(0.0);
  cfg.repeatability_sigma_mm = 0.0;
  cfg.tracker.sigma_constant_mm = 0.002;  // a little noise: the fields' variograms need some nugget
  cfg.tracker.sigma_per_m_mm = 0.0;
  OrientationExperimentOptions o;
  o.seed = 11;
  o.training_poses = 150;
  o.validation_poses = 80;
  const OrientationExperiment e = run_orientation_experiment(cfg, o);
  ASSERT_EQ(e.rows.size(), 6u);
  // Constant orientation: nothing left but noise (a few tracker sigmas), with or without a field.
  for (const char* space : {"-", "task", "joint"}) {
    EXPECT_LT(orientation_row(e, "constant", space).max_mm, 0.02) << space;
    // A joint-space field answers inside the box of its training joints (issue 10 item 6), and a few
    // random validation poses reach the cube with a joint just outside that box: refused, not
    // extrapolated. Task space judges by positions, all inside the cube.
    if (std::string(space) == "joint")
      EXPECT_LT(orientation_row(e, "constant", space).refused, o.validation_poses / 10) << space;
    else
      EXPECT_EQ(orientation_row(e, "constant", space).refused, 0u) << space;
  }
  // Varying orientation: ±30° turns d by up to ~0.5 rad, a few tenths of a mm.
  const double none = orientation_row(e, "varying", "-").mean_mm;
  EXPECT_GT(none, 0.1);
  EXPECT_GT(orientation_row(e, "varying", "task").mean_mm, 0.7 * none);
  EXPECT_LT(orientation_row(e, "varying", "joint").mean_mm, 0.25 * none);
  // The orientation effect at one position is exactly |(R_drawn − R_down) d| <= 2 |d| sin(angle/2),
  // where R_drawn R_down^T = Rz(c) Ry(b) Rx(a) turns by at most |a| + |b| + |c| <= 90°.
  const double d = std::sqrt(0.6 * 0.6 + 0.5 * 0.5 + 0.4 * 0.4);
  EXPECT_GT(e.orientation_effect_mean_mm, 0.05);
  EXPECT_LE(e.orientation_effect_max_mm, 2.0 * d * std::sin(0.5 * 3.0 * 30.0 * M_PI / 180.0) + 1e-6);
  std::cout << "[ tool offset ] varying mean (mm): none " << none << ", task "
            << orientation_row(e, "varying", "task").mean_mm << ", joint "
            << orientation_row(e, "varying", "joint").mean_mm << "\n";
}

// stdout and stderr of `errfield <args>`; `status` gets the exit code.
std::string run_cli(const std::string& args, int* status) {
  const auto r = errfield::testing::run_errfield_line(args);
  *status = r.exit_code;
  return r.output();
}

// The README's main command with --runs 1: the CSV contract of table6.csv, every table's CSV, and
// a report that a browser draws. (Its speed, < 10 s, is a benchmark: BM_ReproduceOneRun.)
TEST(ReproduceCli, OneRunWritesEveryTableAndARenderableReport) {
  const fs::path dir = fs::temp_directory_path() / ("errfield_reproduce_" + std::to_string(::getpid()));
  int status = 0;
  const std::string out = run_cli("reproduce --runs 1 --seed 3 --out " + dir.string(), &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("SIMULATED"), std::string::npos);
  EXPECT_NE(out.find("Table 6"), std::string::npos);
  for (const char* f : {"table3.csv", "table4.csv", "fig5.csv", "table6.csv", "table6_spread.csv",
                        "table6_points.csv", "table8.csv", "beyond_orientation.csv", "report.html"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_NE(out.find("Beyond the paper (SIMULATED)"), std::string::npos);
  {
    const CsvTable b = CsvTable::read((dir / "beyond_orientation.csv").string());
    std::ifstream bin(dir / "beyond_orientation.csv");
    std::string bheader;
    std::getline(bin, bheader);
    EXPECT_EQ(bheader,
              "orientation,orientation_spread_deg,method,space,training_poses,validation_poses,max_mm,mean_mm,std_mm,"
              "refused_targets");
    ASSERT_EQ(b.row_count(), 6u);
    std::set<std::pair<std::string, std::string>> cases;
    const auto bmax = b.numeric_column("max_mm"), bmean = b.numeric_column("mean_mm");
    for (std::size_t i = 0; i < b.row_count(); ++i) {
      cases.insert({b.row(i)[0], b.row(i)[3]});
      EXPECT_GE(bmax[i], bmean[i]);
      EXPECT_GT(bmean[i], 0.0);
    }
    for (const char* orientation : {"varying", "constant"})
      for (const char* space : {"-", "task", "joint"}) EXPECT_TRUE(cases.count({orientation, space})) << orientation << space;
  }
  {
    std::ifstream h(dir / "report.html");
    const std::string html(std::istreambuf_iterator<char>(h), {});
    EXPECT_NE(html.find("Beyond the paper: compensation with varying tool orientation (SIMULATED)"), std::string::npos);
  }

  std::ifstream in(dir / "table6.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "method,metric,max_mm,mean_mm,std_mm");
  const CsvTable t = CsvTable::read((dir / "table6.csv").string());
  std::set<std::pair<std::string, std::string>> seen;
  const std::set<std::string> known{"none", "kinematic", "position-idw", "distance-idw", "distance-kriging",
                                    "vector-kriging", "kinematic+kriging"};
  const auto mx = t.numeric_column("max_mm"), mean = t.numeric_column("mean_mm"), sd = t.numeric_column("std_mm");
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    const std::string method = t.row(i)[0], metric = t.row(i)[1];
    EXPECT_TRUE(known.count(method)) << method;
    EXPECT_TRUE(metric == "distance" || metric == "position") << metric;
    EXPECT_TRUE(seen.insert({method, metric}).second) << "duplicate row " << method << "," << metric;
    EXPECT_GE(mx[i], mean[i]);
    EXPECT_GE(sd[i], 0.0);
  }
  for (const char* m : {"none", "position-idw", "distance-idw"})
    for (const char* metric : {"distance", "position"}) EXPECT_TRUE(seen.count({m, metric})) << m << " " << metric;

  // Same seed, same CSV.
  const fs::path dir2 = dir.string() + "_again";
  ASSERT_EQ((run_cli("reproduce --runs 1 --seed 3 --out " + dir2.string(), &status), status), 0);
  auto slurp = [](const fs::path& p) {
    std::ifstream f(p);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  for (const char* f : {"table3.csv", "table4.csv", "fig5.csv", "table6.csv", "table8.csv", "beyond_orientation.csv"})
    EXPECT_EQ(slurp(dir / f), slurp(dir2 / f)) << f;

  if (const std::string why = test::chromium_unavailable_reason(); !why.empty()) {
    std::cout << "[ skipped ] report render check: " << why << "\n";
  } else {
    // The top of the page: banner, then the two variogram plots with the simulated points (blue)
    // and the paper's curve (grey).
    auto r = test::render_in_chromium(dir / "report.html", {"#1f77b4", "#7f7f7f", "#fff3cd"}, 1000, 2400);
    EXPECT_GE(test::count_occurrences(r.dom, "<svg "), 5u);  // variograms x2, Fig. 5, Fig. 9 x2 (+ Fig. 11)
    EXPECT_GE(test::count_occurrences(r.dom, "<polyline"), 5u);
    EXPECT_GT(r.distinct_colors, 50);
    EXPECT_GT(r.pixels["#1f77b4"], 300);
    EXPECT_GT(r.pixels["#7f7f7f"], 1000);
    EXPECT_GT(r.pixels["#fff3cd"], 5000);
  }
  fs::remove_all(dir);
  fs::remove_all(dir2);
}

TEST(ReproduceCli, BadOptionsExitNonZero) {
  int status = 0;
  const std::string out = run_cli("reproduce --runs 0 --out /tmp/errfield_never", &status);
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("runs"), std::string::npos) << out;
}

}  // namespace
}  // namespace errfield::reproduction
