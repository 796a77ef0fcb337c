// Which default for the calibration's robust weights: plain least squares or IGG3? Measured on
// held-out accuracy (SIMULATED data), with and without gross outliers, for the two ways errfield
// calibrates (docs/robot.md, "Robust weights"):
//  - position: 150 scattered poses with varying orientation of the default simulated robot
//    (ER20-C10 with compliance, transmission error, repeatability and tracker noise), joints
//    recorded to 3 decimals; `fit --method kinematic` (registration with the reflector offset,
//    then the model); held-out 3-D RMS at 100 new poses, in the fitted robot frame.
//  - distance: the paper's cube, distances from the corner node to the other 124 grid points;
//    held-out mean |error| of the distance from the base pose the identified model predicts at 64
//    random targets (one per cell), against the true distance.
// Outliers: 5 % of the measurements get a gross error of 0.5–2 mm (a wrong target, a beam break).
//
//   build/examples/example_robot_robust_choice [runs=10]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "errfield/robot/calibration.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/robot/simulator.hpp"

using namespace errfield::robot;
using namespace errfield::compensation;

namespace {

JointVector rounded3(const JointVector& q) {
  JointVector r;
  for (int j = 0; j < kJointCount; ++j) r[j] = std::round(q[j] * 1e3) / 1e3;
  return r;
}

std::vector<JointVector> scattered(std::size_t n, SimulationRng& rng) {
  std::vector<JointVector> q(n);
  for (auto& v : q)
    v << rng.uniform(-70, 70), rng.uniform(-140, -60), rng.uniform(-50, 40), rng.uniform(-120, 120),
        rng.uniform(-110, -20), rng.uniform(-150, 150);
  return q;
}

double gross(SimulationRng& rng) { return (rng.uniform01() < 0.5 ? -1 : 1) * rng.uniform(0.5, 2.0); }

// Held-out 3-D RMS (mm) of position calibration with the given robust setting.
double position_run(const SimulatedRobot& sim, int run, bool outliers, bool robust) {
  SimulationRng rng(1000 + static_cast<std::uint64_t>(run));
  MeasurementSet data;
  data.source = "simulated";
  for (const auto& q : scattered(150, rng)) {
    Eigen::Vector3d m = sim.measure(sim.move(q, rng), rng);
    if (outliers && rng.uniform01() < 0.05) {
      const Eigen::Vector3d dir(rng.normal(0, 1), rng.normal(0, 1), rng.normal(0, 1));
      m += std::abs(gross(rng)) * dir.normalized();
    }
    data.id.push_back("p");
    data.q_deg.push_back(rounded3(q));
    data.nominal_mm.push_back(forward_position(sim.nominal(), rounded3(q)));
    data.measured_mm.push_back(m);
  }
  FitOptions o;
  o.method = CompensationMethod::kinematic;
  o.calibration.robust.enabled = robust;
  const FitResult fit = fit_compensation_model(sim.nominal(), data, o);
  const Eigen::Isometry3d& robot_from_tracker = fit.registration->robot_from_tracker;
  double ss = 0;
  const auto heldout = scattered(100, rng);
  for (const auto& q : heldout) {
    const Eigen::Vector3d truth = robot_from_tracker * (sim.config().tracker.tracker_from_world * sim.true_position(q));
    ss += (forward_position(fit.model.command_model(), rounded3(q)) - truth).squaredNorm();
  }
  return std::sqrt(ss / static_cast<double>(heldout.size()));
}

// Held-out mean |distance error| (mm) of distance calibration in the paper's cube.
double distance_run(const SimulatedRobot& sim, int run, bool outliers, bool robust) {
  SimulationRng rng(2000 + static_cast<std::uint64_t>(run));
  const MeasurementCube cube = paper_cube();
  const JointVector seed = cube_seed(sim.nominal(), cube).q_deg;
  const Eigen::Vector3d b = paper_base_point_nominal();
  const JointVector qb = solve_cube_pose(sim.nominal(), cube, b, seed).q_deg;
  const Eigen::Vector3d base_actual = sim.move(qb, rng);
  const Eigen::Vector3d base_measured = sim.measure(base_actual, rng);
  std::vector<DistanceMeasurement> data;
  for (const auto& p : cube.grid(125)) {
    if ((p - b).norm() < 1) continue;
    const JointVector q = solve_cube_pose(sim.nominal(), cube, p, seed).q_deg;
    double d = (sim.measure(sim.move(q, rng), rng) - base_measured).norm();
    if (outliers && rng.uniform01() < 0.05) d += gross(rng);
    data.push_back({qb, q, d});
  }
  CalibrationOptions o;
  o.robust.enabled = robust;
  const CalibrationResult cal = calibrate_distances(sim.nominal(), data, o);
  // Frame-free: distances leave the identified model's frame free, so score the distances it
  // predicts from the base pose to held-out poses against the true ones.
  double sum = 0;
  const auto targets = cube.random_per_cell(125, rng);
  for (const auto& p : targets) {
    const JointVector q = solve_cube_pose(sim.nominal(), cube, p, seed).q_deg;
    const double predicted = (forward_position(cal.model, q) - forward_position(cal.model, qb)).norm();
    sum += std::abs(predicted - (sim.true_position(q) - sim.true_position(qb)).norm());
  }
  return sum / static_cast<double>(targets.size());
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::atoi(argv[1]) : 10;
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  std::printf("SIMULATED data, %d runs each; held-out error (mm), mean over runs [worst run]\n", runs);
  std::printf("%-9s %-9s %22s %22s %s\n", "data", "outliers", "robust none", "robust igg3", "igg3 better in");
  for (const bool positions : {true, false})
    for (const bool outliers : {false, true}) {
      double sum[2] = {0, 0}, worst[2] = {0, 0};
      int igg3_better = 0;
      for (int run = 0; run < runs; ++run) {
        double e[2];
        for (int robust = 0; robust < 2; ++robust) {
          e[robust] = positions ? position_run(sim, run, outliers, robust == 1) : distance_run(sim, run, outliers, robust == 1);
          sum[robust] += e[robust];
          worst[robust] = std::max(worst[robust], e[robust]);
        }
        igg3_better += e[1] < e[0];
      }
      std::printf("%-9s %-9s %12.4f [%6.4f] %12.4f [%6.4f] %d of %d runs\n", positions ? "position" : "distance",
                  outliers ? "5%" : "none", sum[0] / runs, worst[0], sum[1] / runs, worst[1], igg3_better, runs);
    }
  return 0;
}
