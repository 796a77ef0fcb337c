#pragma once
/// How far a pose lies outside what a kinematic calibration's data determine. A calibration from
/// poses of one tool orientation identifies the wrist's parameters only in the combinations those
/// poses move (or removes them as unidentifiable); at a pose of another orientation their errors
/// return in full (issue 34: the README's 40 tool-down poses gave 2.07 mm at 14 tilted poses where
/// the nominal robot had 1.15, all `ok`).
///
/// Every identification parameter (robot/kinematics.hpp) gets a Gaussian prior: a robot's usual
/// geometric errors (kGeometricErrorSdMm, kGeometricErrorSdRad) for the links and the tool, and a
/// free base (the registration). With J_i the identification Jacobian of the measured point at
/// training pose i, sigma² the calibration's residual variance per component and P the prior's
/// precision, M = (sum_i J_i' w_i J_i / sigma² + P)^-1 is the parameters' posterior covariance and
/// v(q) = trace(J(q) M J(q)') the calibrated prediction's variance at q (mm²). Where the data
/// determine every parameter, v/v_max is the ordinary regression leverage ratio: above 1 the pose
/// lies outside the hull of the training poses in parameter space ("hidden extrapolation": the
/// joints can be inside the data's box and the pose still outside). Where a parameter was not
/// determined, its prior variance returns at poses that move it. A pose whose v exceeds
/// kMaxCalibrationLeverageRatio times the largest training pose's is refused
/// (`calibration-extrapolated`).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// A pose whose calibration leverage is beyond this many times the largest training pose's is
/// refused (docs/robot.md, "Calibration leverage", says which data chose it).
inline constexpr double kMaxCalibrationLeverageRatio = 2.0;
/// The prior sd of a link or tool parameter's error: generous for a mastered industrial arm, whose
/// geometric errors are tenths of a mm and of a mrad.
inline constexpr double kGeometricErrorSdMm = 1.0;
inline constexpr double kGeometricErrorSdRad = 1e-3;
/// The base (the tracker registration) is free: the data always determine it.
inline constexpr double kFreeBaseSdMm = 1e4;
inline constexpr double kFreeBaseSdRad = 10.0;

struct CalibrationLeverage {
  /// Identification parameter indices (robot/kinematics.hpp param::), every one.
  std::vector<int> parameters;
  /// The parameters' posterior covariance M (mm and rad units).
  Eigen::MatrixXd inverse_information;
  /// The largest v of a training pose (mm²).
  double largest_training = 0.0;

  /// From the calibrated model `model` (its tool: the measured point) at training joints `q_deg`,
  /// with `noise_variance_mm2` the calibration's residual variance per component, each reading at
  /// its point on the flange `point_of_reading_mm` (flange frame; empty: the model's tool for all)
  /// with its robust weight `weights` (empty: 1). Empty (nullopt) without a positive variance.
  static std::optional<CalibrationLeverage> of(const robot::MdhModel& model, const std::vector<robot::JointVector>& q_deg,
                                               double noise_variance_mm2,
                                               const std::vector<Eigen::Vector3d>& point_of_reading_mm = {},
                                               const std::vector<double>& weights = {});
  /// v(q) at the model's tool point (mm²).
  double at(const robot::MdhModel& model, const robot::JointVector& q_deg) const;
  /// at() / largest_training.
  double ratio(const robot::MdhModel& model, const robot::JointVector& q_deg) const {
    return at(model, q_deg) / largest_training;
  }

  nlohmann::json to_json() const;
  /// Throws InputError naming `source` and the member for anything but what to_json writes.
  static CalibrationLeverage from_json(const nlohmann::json& j, const std::string& source);
};

}  // namespace errfield::compensation
