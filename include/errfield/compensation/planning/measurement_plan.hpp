#pragma once
/// Step 1 of the pipeline: where to measure. A cubic grid at one constant tool orientation (the
/// paper's 500 mm cube at 125 mm), the base point(s), and optionally one random validation sample
/// per cell, each with its nominal IK joints; unreachable points are refused with a list.
/// `recommend_grid_step` picks the step from a variogram with the paper's reasoning (section 3.2,
/// Fig. 5): the error must stay similar across a cell, so the cell diagonal should lie where the
/// variogram is still small.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/mdh_model.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::compensation {

struct PlanOptions {
  Eigen::Vector3d min_corner_mm = Eigen::Vector3d::Zero();
  double size_mm = 500.0;
  double step_mm = 125.0;  ///< must divide size_mm
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();  ///< tool orientation at every point
  std::vector<Eigen::Vector3d> base_points_mm;  ///< robot positions to measure distances from
  bool sample_per_cell = false;                 ///< one uniformly random validation point per cell
  std::uint64_t seed = 1;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

struct PlannedPoint {
  std::string id;    ///< "b0", "g0", "s0", ...
  std::string kind;  ///< "base", "grid" or "sample"
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  robot::JointVector q_deg = robot::JointVector::Zero();
};

/// Every point with its IK joints (seeded at the cube centre, so all on one branch). Throws
/// InputError listing the unreachable points (id, position, IK status) when any is unreachable.
std::vector<PlannedPoint> plan_measurements(const robot::MdhModel& robot, const PlanOptions& options);

struct StepRecommendation {
  double step_mm = 0;
  double cell_diagonal_mm = 0;
  double gamma_at_diagonal_mm2 = 0;
  double gamma_max_mm2 = 0;
  std::string reason;  ///< one paragraph for people
};

/// The largest whole-millimetre step dividing `size_mm` (at least `min_step_mm`) whose cell diagonal step·√3 has
/// gamma <= gamma_max_mm2 under `model` (lags in mm). Default threshold 0.01 mm²: an IDW error of
/// about sqrt(gamma) = 0.1 mm, under half the ±0.25 mm assembly tolerance.
StepRecommendation recommend_grid_step(const VariogramModel& model, double size_mm, double gamma_max_mm2 = 0.01,
                                       double min_step_mm = 10.0);

}  // namespace errfield::compensation
