// Step 1 of the compensation pipeline: where to measure. A 500 mm cube at a constant tool-down
// orientation, a grid step recommended from a variogram (the paper's reasoning), every grid point
// with its IK joints, and one base point. Run it, then measure the printed joints.
#include <cstdio>

#include "errfield/compensation/planning/measurement_plan.hpp"
#include "errfield/robot/pose.hpp"
#include "errfield/robot/simulator.hpp"

int main() {
  using namespace errfield;
  using namespace errfield::robot;
  using namespace errfield::compensation;
  // The robot: the ER20-C10 carrying the Table 7 target ball (use MdhModel::load for your own).
  const MdhModel robot = MdhModel::er20_c10().with_tool(paper_ball());

  // A variogram of the distance error over task-space lags (mm), e.g. fitted to a first coarse
  // measurement with `errfield variogram` + `errfield fit-variogram`.
  const VariogramModel model = VariogramModel::parse("gau(sill=1.6,range=970)+nug(0.005)");
  const StepRecommendation step = recommend_grid_step(model, /*cube side mm*/ 500.0, /*gamma max mm²*/ 0.03);
  std::printf("%s\n", step.reason.c_str());

  PlanOptions plan;
  plan.min_corner_mm = {750, -250, 350};
  plan.size_mm = 500;
  plan.step_mm = step.step_mm;
  plan.orientation = rotation_from_rpy_deg(180, 0, 0);  // tool down
  plan.base_points_mm = {{750, -250, 350}};             // a robot position: the cube's corner
  const std::vector<PlannedPoint> points = plan_measurements(robot, plan);  // throws if unreachable
  std::printf("%zu points to measure; the first three:\n", points.size());
  for (std::size_t i = 0; i < 3 && i < points.size(); ++i) {
    const auto& p = points[i];
    std::printf("  %-4s %-5s (%7.1f, %7.1f, %7.1f) mm  q = [%.3f %.3f %.3f %.3f %.3f %.3f] deg\n", p.id.c_str(),
                p.kind.c_str(), p.position_mm.x(), p.position_mm.y(), p.position_mm.z(), p.q_deg[0], p.q_deg[1],
                p.q_deg[2], p.q_deg[3], p.q_deg[4], p.q_deg[5]);
  }
  return 0;
}
