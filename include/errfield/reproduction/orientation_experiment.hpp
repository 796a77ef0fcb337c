#pragma once
/// A "beyond the paper" experiment (SPEC section 8, item 5): compensation by vector kriging when
/// the tool orientation VARIES from target to target, with the field's locations in task space
/// (nominal positions, mm) or in joint space (nominal joints, deg, the lag of eq. 16).
///
/// The paper compensates at one constant orientation, where a position fixes the joints and the
/// two spaces carry the same information. With the orientation free, one position is reached by
/// many joint configurations whose errors differ; a task-space field cannot tell them apart, a
/// joint-space field can (but has to interpolate in 6-D instead of 3-D). Use
/// `run_orientation_experiment` to measure which effect wins on a (simulated) robot; `errfield
/// reproduce` runs it once on the paper's simulated ER20-C10 and writes beyond_orientation.csv.
///
/// Protocol, per orientation case ("varying": RX, RY, RZ of every target drawn uniformly within
/// ±spread of the tool-down orientation (180°, 0°, 0°); "constant": all at tool-down), on the same
/// target positions (uniform in the cube): measure the training poses once each (one move, one
/// tracker reading), register tracker → robot on them, krige the registered 3-D position errors
/// (vector kriging, variogram estimated from the samples, nugget as measurement error) in task and
/// in joint space, then command independent validation poses (drawn the same way) nominally and
/// through each field, and take |P' − P| in the registered frame with fresh repeatability noise.
/// Everything is SIMULATED; deterministic for a given seed (single-threaded).

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/simulator.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::reproduction {

struct OrientationExperimentOptions {
  std::uint64_t seed = 1;         ///< seeds the poses, the measurement and the evaluation noise
  int training_poses = 300;       ///< measured poses the fields are fitted on (>= 8)
  int validation_poses = 200;     ///< independent poses the compensation is evaluated on (>= 1)
  double orientation_spread_deg = 30.0;  ///< RX, RY, RZ drawn within ± this of tool-down, in (0, 90]
  /// Region margin of the fields (mm): their region is the box of the training positions widened
  /// by this, so that it covers the cube the validation poses come from.
  double region_margin_mm = 10.0;
  /// The joint-space fields' margin (deg per joint): their region is the box of the training
  /// joints, and the joints of poses inside the cube reach a few degrees beyond the box of the
  /// grid's joints (the wrist's joints are not monotonic in the position).
  double region_margin_deg = 5.0;
  /// Orientation draws tried per position before the experiment gives up on the robot (IK must
  /// converge within the joint limits, seeded at the cube seed's branch).
  int max_orientation_draws = 100;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

/// One method under one orientation case.
struct OrientationExperimentRow {
  std::string orientation;  ///< "varying" or "constant"
  std::string method;       ///< "none" or "vector-kriging"
  std::string space;        ///< "task", "joint", or "-" for none
  VariogramModel model;     ///< the field's variogram model, estimated from the samples (empty for none)
  double max_mm = 0, mean_mm = 0, std_mm = 0;  ///< of the residual 3-D position error |P' − P|
  std::size_t refused = 0;  ///< validation targets the field refused or IK failed on (commanded nominally)
};

struct OrientationExperiment {
  OrientationExperimentOptions options;
  std::vector<OrientationExperimentRow> rows;  ///< varying: none, task, joint; then constant: the same
  /// Orientation draws rejected because IK failed (varying case, training + validation).
  std::size_t rejected_orientation_draws = 0;
  /// max / mean / std over the varying-orientation validation poses of |dP(q) − dP(q_down)|: how
  /// far the true (noise-free) error moves when the same position is reached at its drawn
  /// orientation instead of tool-down. This is what a task-space field cannot see.
  double orientation_effect_max_mm = 0, orientation_effect_mean_mm = 0, orientation_effect_std_mm = 0;
  /// Spread of the wrist and arm joints over the varying-orientation training poses (max − min, deg).
  Eigen::Matrix<double, 6, 1> joint_span_deg = Eigen::Matrix<double, 6, 1>::Zero();
};

/// Runs the experiment on the robot `config` simulates, in the paper's cube (paper_cube()).
/// Throws ArgumentError for bad options, Error when a position admits no reachable orientation
/// within max_orientation_draws or a field cannot be fitted.
OrientationExperiment run_orientation_experiment(const robot::SimulatorConfig& config,
                                                 const OrientationExperimentOptions& options);

}  // namespace errfield::reproduction
