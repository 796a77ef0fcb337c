// Step 4 of the compensation pipeline: the joints to send. A model read from JSON (as written by
// `errfield fit`) compensates targets; the SIMULATED robot then shows the error before and after.
#include <cstdio>

#include "errfield/grid_idw.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/model/error_fields.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/simulator.hpp"

int main() {
  using namespace errfield;
  using namespace errfield::robot;
  using namespace errfield::compensation;
  const SimulatedRobot sim(SimulatorConfig::paper_default());
  const MdhModel& robot = sim.nominal();
  const MeasurementCube cube = paper_cube();
  const JointVector seed = cube_seed(robot, cube).q_deg;

  // The paper's model from noise-free distance errors to the cube's corner (a robot position), to
  // keep the example short; pipeline_fit.cpp shows fitting from measurements.
  const RegularGrid3 grid(cube.min_corner_mm, Eigen::Vector3d::Constant(125), {5, 5, 5});
  const JointVector q_base = solve_cube_pose(robot, cube, cube.min_corner_mm, seed).q_deg;
  const Eigen::Vector3d base_true = sim.true_position(q_base);
  std::vector<double> dl;
  for (std::size_t n = 0; n < grid.node_count(); ++n) {
    const Eigen::Vector3d p = grid.node_position(n);
    const JointVector q = solve_cube_pose(robot, cube, p, seed).q_deg;
    dl.push_back((sim.true_position(q) - base_true).norm() - (p - cube.min_corner_mm).norm());
  }
  const CompensationModel written(CompensationMethod::distance_idw, robot,
                                  make_distance_idw_field(grid, dl, cube.min_corner_mm));
  const CompensationModel model = CompensationModel::from_json(written.to_json(), "model.json");

  for (const Eigen::Vector3d& target : {Eigen::Vector3d(912, -40, 505), Eigen::Vector3d(1180, 210, 800),
                                        Eigen::Vector3d(1400, 0, 600)}) {
    const CompensatedTarget c = model.compensate(robot, cube.pose(target), seed);
    if (!c.ok()) {
      std::printf("target (%g, %g, %g): refused (outside the modelled cube or IK failed)\n", target.x(), target.y(),
                  target.z());
      continue;
    }
    auto distance_error = [&](const JointVector& q) {
      return (sim.true_position(q) - base_true).norm() - (target - cube.min_corner_mm).norm();
    };
    std::printf("target (%g, %g, %g): predicted dL %.3f mm; distance error %.3f mm -> %.3f mm\n", target.x(),
                target.y(), target.z(), c.prediction.distance_error_mm, distance_error(c.q_nominal_deg),
                distance_error(c.q_command_deg));
  }
  return 0;
}
