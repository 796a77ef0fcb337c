#pragma once
/// Compensation of robot targets from a fitted error model: the last step of the pipeline
/// (plan → measure → fit → compensate), SPEC section 6. Use `CompensationModel::compensate` to
/// turn a nominal target into the joints to send: it predicts the robot's error at the target,
/// moves the commanded point against it (`P_cmd = P_n − dP`, eq. 23 for the paper's method),
/// keeps the orientation and solves inverse kinematics seeded at the nominal solution.
///
/// A model has two parts, either of which may be trivial:
///  - the **command model**: the MdhModel IK runs on (the nominal model, or the one identified by
///    kinematic calibration);
///  - an **error field**: the predicted remaining position error dP (robot frame, mm) at a nominal
///    target, from interpolation of measured errors (grid IDW of distance or position errors,
///    kriging of distance errors or error vectors, in task or joint space).
/// The methods of `errfield fit` are combinations of the two (see CompensationMethod).
///
/// Frames and units: positions in the robot's world frame (the MdhModel's base frame), mm; joints
/// in degrees; the target point is the model's tool point.
/// Thread safety: models are immutable after construction; compensate() may run concurrently.

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// The methods of `errfield fit` / Table 6, named as on the command line.
enum class CompensationMethod {
  none,              ///< "none": nominal IK, no correction
  kinematic,         ///< "kinematic": IK on the calibrated model (distance model, IGG3)
  position_idw,      ///< "position-idw": 8-vertex IDW of registered 3-D position errors
  distance_idw,      ///< "distance-idw": the paper's method (8-vertex IDW of distance errors, eqs. 19–23)
  distance_kriging,  ///< "distance-kriging": kriging of distance errors, projected as eq. 23
  vector_kriging,    ///< "vector-kriging": kriging of 3-D error vectors (from positions or ≥3 base points)
  kinematic_kriging, ///< "kinematic+kriging": calibrated model, then kriging of its residual errors
};

/// Command-line name of a method ("distance-idw", ...).
std::string_view method_name(CompensationMethod method);
/// Inverse of method_name; throws ArgumentError listing the known names.
CompensationMethod method_from_name(std::string_view name);
/// Every method, in Table 6 order.
std::vector<CompensationMethod> all_methods();

/// What an error field predicts at one nominal target.
struct ErrorPrediction {
  /// Predicted position error dP = P' − P of the robot at the target (robot frame, mm); the
  /// correction applied is −dP. For distance methods this is dL · m (eq. 23), radial only.
  Eigen::Vector3d position_error_mm = Eigen::Vector3d::Zero();
  /// Predicted distance error to the base point (mm), for distance-based fields; NaN otherwise.
  double distance_error_mm = std::numeric_limits<double>::quiet_NaN();
  /// Prediction variance (mm²) of the predicted quantity (distance error, or the sum over the three
  /// components for vector fields); NaN when the method has none (IDW).
  double variance_mm2 = std::numeric_limits<double>::quiet_NaN();
  /// False when the target lies outside the modelled region (then nothing is extrapolated:
  /// position_error_mm is zero and compensate() refuses the target).
  bool inside_region = true;
};

/// The spatial part of a compensation model. Implementations: distance_idw_field, ...
class ErrorField {
 public:
  virtual ~ErrorField() = default;
  /// Prediction at a nominal target position `p_mm` reached with nominal joints `q_deg`.
  virtual ErrorPrediction predict(const Eigen::Vector3d& p_mm, const robot::JointVector& q_deg) const = 0;
  /// JSON description (see docs/data-formats.md, "model JSON").
  virtual nlohmann::json to_json() const = 0;
  /// One line for people ("distance IDW on x [..] ... base point (..)").
  virtual std::string describe() const = 0;
};

/// The result of compensating one target.
struct CompensatedTarget {
  robot::JointVector q_nominal_deg = robot::JointVector::Zero();  ///< nominal IK solution of the target
  ErrorPrediction prediction;                        ///< the field's prediction (zero if no field)
  Eigen::Vector3d command_position_mm = Eigen::Vector3d::Zero();  ///< P_cmd = P_n − dP
  robot::JointVector q_command_deg = robot::JointVector::Zero();   ///< joints to send (IK of the command model)
  robot::IkStatus ik_status = robot::IkStatus::converged;          ///< of the command IK (nominal IK if that failed)
  double ik_residual_mm = 0.0;
  /// Probability that the remaining error along the predicted quantity lies within ±tolerance,
  /// assuming a Gaussian prediction error with the kriging variance; NaN without a variance.
  double p_within_tolerance = std::numeric_limits<double>::quiet_NaN();
  /// True when the target is inside the modelled region and both IK solves converged.
  bool ok() const { return prediction.inside_region && ik_status == robot::IkStatus::converged; }
};

class CompensationModel {
 public:
  /// `command_model` is what IK runs on; `field` may be null (none, kinematic).
  CompensationModel(CompensationMethod method, robot::MdhModel command_model, std::shared_ptr<const ErrorField> field);

  CompensationMethod method() const noexcept { return method_; }
  const robot::MdhModel& command_model() const noexcept { return command_model_; }
  const ErrorField* field() const noexcept { return field_.get(); }

  /// Compensates a target pose (robot frame, tool point). `nominal_model` gives the nominal joints
  /// (IK seeded at `seed_deg`); the field is evaluated there; the command is solved on
  /// command_model() seeded at the nominal joints. `tolerance_mm` > 0 feeds p_within_tolerance.
  /// Never throws for numerical outcomes: a failed IK or a target outside the region shows in the
  /// result (ok() false; then q_command_deg = q_nominal_deg).
  CompensatedTarget compensate(const robot::MdhModel& nominal_model, const Eigen::Isometry3d& target,
                               const robot::JointVector& seed_deg, double tolerance_mm = 0.25,
                               const robot::IkOptions& ik = {}) const;

  /// Same, from nominal joints already known (the target is their nominal FK).
  CompensatedTarget compensate_joints(const robot::MdhModel& nominal_model, const robot::JointVector& q_nominal_deg,
                                      double tolerance_mm = 0.25, const robot::IkOptions& ik = {}) const;

  /// JSON form: {"format":"errfield-compensation-model","version":1,"method":...,
  /// "command_model":{robot JSON},"field":{...}|null}.
  nlohmann::json to_json() const;
  /// Reads the JSON form; throws InputError naming `source` and the field.
  static CompensationModel from_json(const nlohmann::json& j, const std::string& source);

 private:
  CompensationMethod method_;
  robot::MdhModel command_model_;
  std::shared_ptr<const ErrorField> field_;
};

/// Unit direction m = (p − base)/|p − base| of eq. 22. Precondition: p != base.
Eigen::Vector3d radial_direction(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& base_mm);

/// P(|e| <= tol) for e ~ N(0, variance) (both in mm / mm²); NaN for a NaN or negative variance.
double probability_within(double tolerance_mm, double variance_mm2);

}  // namespace errfield::compensation
