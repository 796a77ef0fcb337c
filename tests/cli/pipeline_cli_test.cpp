// The user pipeline end to end on SIMULATED data: plan -> simulate (the "measurement") -> fit ->
// compensate, then the simulated robot executes the compensated joints and the errors must drop.
// Also on a robot JSON other than the built-in one, and with bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "errfield/csv_table.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/robot/simulator.hpp"
#include "support/cli_harness.hpp"

namespace errfield::robot {
using namespace errfield::compensation;
namespace pipeline_cli_test {

namespace fs = std::filesystem;
using errfield::testing::CliResult;

CliResult run(const std::string& line) { return errfield::testing::run_errfield_line(line); }

class PipelineCli : public errfield::testing::CliTest {};


/// "q3" without GCC 12's false -Wrestrict on "q" + std::to_string(k).
std::string column(const std::string& prefix, int k) {
  std::string s = prefix;
  s += std::to_string(k);
  return s;
}

/// Distance errors to the base (robot position b0) and registered-frame position errors of the
/// targets when the simulated robot runs `joints` (columns q1..q6 or cq1..cq6).
struct Outcome {
  double mean_distance = 0, mean_position = 0;
  std::size_t ok = 0;
};

Outcome execute(const SimulatedRobot& sim, const MdhModel& nominal, const CsvTable& t, const std::string& prefix,
                const Registration& reg, const JointVector& q_base, const Eigen::Vector3d& base_nominal) {
  Outcome o;
  const Eigen::Vector3d base_true = sim.true_position(q_base);
  const Eigen::Isometry3d registered_from_world = reg.robot_from_tracker * sim.config().tracker.tracker_from_world;
  const std::size_t kind = t.column_index("kind"), status = t.has_column("status") ? t.column_index("status") : 0;
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    if (t.row(r)[kind] != "target") continue;
    if (t.has_column("status") && t.row(r)[status] != "ok") continue;
    JointVector q, qn;
    for (int k = 0; k < 6; ++k) {
      q[k] = std::stod(t.row(r)[t.column_index(column(prefix, k + 1))]);
      qn[k] = std::stod(t.row(r)[t.column_index(column("q", k + 1))]);
    }
    const Eigen::Vector3d target = forward_position(nominal, qn);
    const Eigen::Vector3d actual = sim.true_position(q);
    o.mean_distance += std::abs((actual - base_true).norm() - (target - base_nominal).norm());
    o.mean_position += (registered_from_world * actual - target).norm();
    ++o.ok;
  }
  o.mean_distance /= static_cast<double>(o.ok);
  o.mean_position /= static_cast<double>(o.ok);
  return o;
}

/// One method through fit and compensate; the simulated robot then runs the compensated joints.
void pipeline_reduces_errors(const std::string& robot_json, const MdhModel& nominal, const std::string& d,
                             const std::string& method) {
  // measure: the 125-point grid and 64 validation targets (one per cell), SIMULATED
  ASSERT_EQ(run("simulate --robot " + robot_json + " --sample grid --step 125 --out " + d + "/grid.csv").exit_code, 0);
  ASSERT_EQ(run("simulate --robot " + robot_json + " --sample cells --step 125 --seed 9 --out " + d + "/cells.csv").exit_code, 0);
  SimulatorConfig cfg = SimulatorConfig::paper_default();
  cfg.nominal = nominal;
  const SimulatedRobot sim(cfg);
  const CsvTable grid = CsvTable::read(d + "/grid.csv");
  const MeasurementSet m = MeasurementSet::from_table(grid, nominal);
  const Registration reg = fit_registration(m.measured_mm, m.nominal_mm);
  const CsvTable cells = CsvTable::read(d + "/cells.csv");
  JointVector q_base;
  for (int k = 0; k < 6; ++k) q_base[k] = std::stod(cells.row(0)[cells.column_index(column("q", k + 1))]);
  ASSERT_EQ(cells.row(0)[cells.column_index("kind")], "base");
  const Eigen::Vector3d base_nominal = m.base_nominal_mm[0];
  const Outcome none = execute(sim, nominal, cells, "q", reg, q_base, base_nominal);
  ASSERT_EQ(none.ok, 64u);
  {
    SCOPED_TRACE(method);
    const CliResult fit = run("fit --robot " + robot_json + " --data " + d + "/grid.csv --method " + method + " --out " + d +
                        "/" + method + ".json");
    ASSERT_EQ(fit.exit_code, 0) << fit.output();
    EXPECT_NE(fit.output().find(method == "kinematic" ? "calibration on" : "cross-validation"), std::string::npos) << fit.output();
    const CliResult comp = run("compensate --robot " + robot_json + " --model " + d + "/" + method + ".json --targets " + d +
                         "/cells.csv --out " + d + "/joints.csv");
    ASSERT_EQ(comp.exit_code, 0) << comp.output();
    const CsvTable joints = CsvTable::read(d + "/joints.csv");
    const Outcome after = execute(sim, nominal, joints, "cq", reg, q_base, base_nominal);
    EXPECT_EQ(after.ok, 64u) << "every validation target is inside the grid";
    std::cout << "[ pipeline ] " << method << ": mean |distance error| " << none.mean_distance << " -> "
              << after.mean_distance << " mm, mean position error (registered frame) " << none.mean_position
              << " -> " << after.mean_position << " mm\n";
    if (method == "kinematic" || method == "kinematic+kriging") {
      // grid.csv has tracker positions, so fit calibrates from them (registration first): the
      // model lives in the registered frame and the full 3-D error drops
      EXPECT_LT(after.mean_position, 0.6 * none.mean_position);
    } else if (method.rfind("distance", 0) == 0) {
      EXPECT_LT(after.mean_distance, 0.5 * none.mean_distance);  // the radial error drops
    } else {
      EXPECT_LT(after.mean_position, 0.6 * none.mean_position);  // the full 3-D error drops
    }
  }
}

// One test per method (each a few seconds; as one loop they took 30 s and held up the -j2 suite).
class PipelineMethod : public errfield::testing::CliTest, public ::testing::WithParamInterface<std::string> {};

TEST_P(PipelineMethod, SimulateFitCompensateReducesTheErrorOnTheBuiltInRobot) {
  const MdhModel nominal = SimulatorConfig::paper_default().nominal;
  nominal.save(path("robot.json"));
  pipeline_reduces_errors(path("robot.json"), nominal, dir().string(), GetParam());
}

TEST_P(PipelineMethod, WorksOnAnotherRobotJson) {
  auto links = SimulatorConfig::paper_default().nominal.links();
  links[1].a_mm += 20.0;   // a longer shoulder offset
  links[3].d_mm -= 15.0;   // a shorter forearm
  links[2].a_mm -= 10.0;
  const MdhModel other = SimulatorConfig::paper_default().nominal.with_links(links).with_name("another 6R arm");
  other.save(path("other.json"));
  pipeline_reduces_errors(path("other.json"), other, dir().string(), GetParam());
}

INSTANTIATE_TEST_SUITE_P(PipelineCli, PipelineMethod,
                         ::testing::Values("distance-idw", "position-idw", "distance-kriging", "vector-kriging",
                                           "kinematic", "kinematic+kriging"),
                         [](const auto& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-' || c == '+') c = '_';
                           return name;
                         });

TEST_F(PipelineCli, PlanOnAnotherRobotJsonGivesItsJoints) {
  auto links = SimulatorConfig::paper_default().nominal.links();
  links[1].a_mm += 20.0;
  links[3].d_mm -= 15.0;
  links[2].a_mm -= 10.0;
  const MdhModel other = SimulatorConfig::paper_default().nominal.with_links(links).with_name("another 6R arm");
  other.save(path("other.json"));
  // the grid must be reachable and its joints must be the other robot's
  const CliResult plan = run("plan --robot " + path("other.json") + " --cube 750,-250,350,500 --step 125 --out " +
                       path("plan.csv") + " --samples-out " + path("samples.csv"));
  ASSERT_EQ(plan.exit_code, 0) << plan.output();
  const CsvTable p = CsvTable::read(path("plan.csv"));
  ASSERT_EQ(p.row_count(), 125u);
  for (std::size_t r = 0; r < p.row_count(); r += 31) {
    JointVector q;
    for (int k = 0; k < 6; ++k) q[k] = std::stod(p.row(r)[p.column_index(column("q", k + 1))]);
    const Eigen::Vector3d xyz(std::stod(p.row(r)[p.column_index("x")]), std::stod(p.row(r)[p.column_index("y")]),
                              std::stod(p.row(r)[p.column_index("z")]));
    EXPECT_LT((forward_position(other, q) - xyz).norm(), 1e-6);
  }
}

TEST_F(PipelineCli, BadInputGetsClearErrors) {
  auto expect_error = [](const CliResult& c, const std::string& needle) {
    EXPECT_NE(c.exit_code, 0) << c.output();
    EXPECT_NE(c.output().find(needle), std::string::npos) << c.output();
  };
  expect_error(run("fit --data " + path("missing.csv") + " --out " + path("m.json")), "missing.csv");
  ASSERT_EQ(run("simulate --sample cells --robot-out " + path("r.json") + " --out " + path("cells.csv")).exit_code, 0);
  ASSERT_EQ(run("simulate --sample grid --measure distances --out " + path("dist.csv")).exit_code, 0);
  const std::string robot = " --robot " + path("r.json");
  expect_error(run("fit" + robot + " --data " + path("cells.csv") + " --method distance-idw --out " + path("m.json")),
               "cells.csv");
  expect_error(run("fit" + robot + " --data " + path("dist.csv") + " --method position-idw --out " + path("m.json")), "mx");
  expect_error(run("fit" + robot + " --data " + path("dist.csv") + " --method magic --out " + path("m.json")),
               "distance-idw");
  expect_error(run("fit" + robot + " --data " + path("dist.csv") + " --method kinematic+kriging --out " + path("m.json")),
               "mx");
  EXPECT_FALSE(fs::exists(path("m.json"))) << "no model file after a failed fit";
  {
    std::ofstream(path("bad.json")) << "{\"format\":\"errfield-compensation-model\",\"version\":1,\"method\":\"none\"}";
  }
  expect_error(run("compensate --model " + path("bad.json") + " --targets " + path("cells.csv") + " --out " + path("j.csv")),
               "command_model");
  expect_error(run("plan --cube 750,-250,350,500 --step 30 --out " + path("p.csv")), "divide");
  expect_error(run("plan --cube 750,-250,350 --out " + path("p.csv")), "--cube");
  // A cube 7.5 m away (found by fuzzing: it used to take minutes): refused at once, naming the first
  // points, after checking only as many as it reports.
  const CliResult far = run("plan --cube 7500,-250,350,250 --step 25 --out " + path("p.csv"));
  expect_error(far, "10 of the first 10 of 1331 points are unreachable");
  EXPECT_NE(far.err.find("g0 (7500.0, -250.0, 350.0) mm: unreachable"), std::string::npos) << far.err;
  EXPECT_FALSE(fs::exists(path("p.csv")));
}

}  // namespace
}  // namespace errfield::robot
