// Step 3 of the compensation pipeline: a compensation model from measurements. The measurements
// here come from the SIMULATED robot and tracker (what `errfield simulate` writes); with a real
// robot, read your CSV with CsvTable::read and MeasurementSet::from_table instead.
#include <cstdio>

#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/robot/simulator.hpp"

int main() {
  using namespace errfield;
  using namespace errfield::robot;
  using namespace errfield::compensation;
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MdhModel& robot = sim.nominal();
  const MeasurementCube cube = paper_cube();
  const JointVector seed = cube_seed(robot, cube).q_deg;
  SimulationRng rng(42);

  // "Measure": the base point once, then the 125 grid points; distances are tracker readings.
  MeasurementSet data;
  data.source = "simulated grid";
  const JointVector q_base = solve_cube_pose(robot, cube, cube.min_corner_mm, seed).q_deg;
  const Eigen::Vector3d base_reading = sim.measure(sim.move(q_base, rng), rng);
  data.base_nominal_mm = {cube.min_corner_mm};
  data.distance_mm.resize(1);
  for (const Eigen::Vector3d& p : cube.grid(125.0)) {
    const JointVector q = solve_cube_pose(robot, cube, p, seed).q_deg;
    const Eigen::Vector3d reading = sim.measure(sim.move(q, rng), rng);
    std::string id = "g";
    id += std::to_string(data.id.size());
    data.id.push_back(id);
    data.q_deg.push_back(q);
    data.nominal_mm.push_back(p);
    data.measured_mm.push_back(reading);
    data.distance_mm[0].push_back((reading - base_reading).norm());
  }

  for (CompensationMethod method : {CompensationMethod::distance_idw, CompensationMethod::distance_kriging,
                                    CompensationMethod::vector_kriging}) {
    FitOptions options;
    options.method = method;
    const FitResult fit = fit_compensation_model(robot, data, options);
    std::printf("%s: %s\n", std::string(method_name(method)).c_str(), fit.model.field()->describe().c_str());
    if (fit.cross_validation)
      std::printf("  leave-one-out: mean |e| %.3f mm, RMS %.3f mm, max %.3f mm\n", fit.cross_validation->mean_abs_mm,
                  fit.cross_validation->rms_mm, fit.cross_validation->max_abs_mm);
    // fit.model.to_json() is what `errfield fit --out model.json` writes.
  }
  return 0;
}
