#pragma once
/// Where the robot goes: a compensation model's prediction of the actual tool position at given
/// commanded joints — the command model's FK plus the error field's predicted error dP at those
/// joints (evaluated at the nominal robot's FK, where the field was fitted). `errfield predict`
/// writes it per row; `errfield validate` compares it with held-out measurements.
///
/// A prediction the model cannot vouch for is refused with a status, never given as a number:
/// joints outside the robot's limits, outside the modelled region, or not credible (beyond the range
/// of errors the model was fitted on, CredibleRange in compensation.hpp).
/// Frames: robot frame (the model's world frame), mm; the tracker frame through the model's stored
/// registration (registration.hpp).

#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"

namespace errfield::compensation {

/// outside_limits: a joint beyond the nominal robot's limits (robot/input_checks.hpp) - radians, a
/// wrong joint order or a typo; the robot cannot be there, whatever the field says.
/// orientation_unknown: the point predicted (a working tool, `--tool`) is further from the reflector the
/// model was measured with than the model's orientation prior supports (OrientationPrior::max_lever_mm).
/// calibration_extrapolated: the pose lies beyond what the kinematic calibration's data determine
/// (calibration_leverage.hpp), though its joints may be inside the data's box.
/// extrapolated: only with predict_position's `extrapolate` (predict and validate --extrapolate, never
/// compensate): a pose outside the field's region or beyond the calibration's leverage, answered with
/// what holds there (PointPrediction::position_mm says how) and a variance that says so.
enum class PredictionStatus { ok, outside_region, not_credible, outside_limits, orientation_unknown, calibration_extrapolated, extrapolated };
/// "ok", "outside-region", "not-credible", "outside-limits", "orientation-unknown",
/// "calibration-extrapolated", "extrapolated" (the status column of predict, validate, compensate).
std::string_view status_name(PredictionStatus s);

/// What a field's prediction says of itself, in this order: outside-region, not-credible,
/// orientation-unknown, calibration-extrapolated, else ok (the joint limits are the caller's).
PredictionStatus prediction_status(const ErrorPrediction& e);

struct PointPrediction {
  PredictionStatus status = PredictionStatus::ok;
  /// Predicted actual tool position, robot frame (mm); NaN unless ok.
  Eigen::Vector3d position_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// The same in the tracker frame, when the model holds a registration; NaN unless ok.
  std::optional<Eigen::Vector3d> tracker_mm;
  /// The field's part (zero without a field).
  ErrorPrediction error;
  bool ok() const { return status == PredictionStatus::ok; }
};

/// Prediction at commanded joints `q_deg`, of the model's scored point (scored_model(): the working
/// tool where the model has one, else the reflector).
/// `extrapolate`: a pose the model refuses as outside-region or calibration-extrapolated is answered
/// instead, with status extrapolated: beyond the calibration's leverage with the whole model (the
/// field is still inside its region); outside the field's region with the parts that hold everywhere,
/// the calibrated kinematics and the joint error functions. No variance is stated for them (NaN):
/// nothing the model measured says how far its calibration extrapolates. Never for compensate.
PointPrediction predict_position(const CompensationModel& model, const robot::JointVector& q_deg, bool extrapolate = false);

/// A model file as validate, predict and fk read it: a compensation model (errfield fit) or a robot
/// JSON (errfield calibrate, or any robot description: its FK is the prediction, its
/// "registration" member, if any, the registration).
struct LoadedModel {
  CompensationModel model;
  bool is_robot_json = false;
  /// "vector-kriging model" or "robot JSON 'ER20-C10 (calibrated, position model)'".
  std::string description;
};
/// Throws InputError naming the file and the member for anything malformed.
LoadedModel load_model(const std::string& path);

}  // namespace errfield::compensation
