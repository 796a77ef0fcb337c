#pragma once
/// Scoring a model's prediction of the flange's orientation error on held-out readings of three or
/// more points per pose (reflector nests, or a 6-DoF probe turned into points: probe_readings.hpp),
/// `errfield validate`'s orientation block.
///
/// Per pose, the measured orientation error is the rotation w (flange_rotation.hpp) that the
/// readings' position errors at the points imply, each reading mapped into the robot frame as
/// validate maps positions: "after" against the model (calibrated FK of each point plus its
/// prediction, i.e. w_measured − w_predicted), "before" against the nominal robot in its own
/// registration with the points where that registration puts them on its flange
/// (LabelledPoint::nominal_mm; no "before" in model files without them). The model's covariance of w
/// (CompensationModel::predict_rotation) gives a 95 % radius per pose and NEES = eᵀC⁻¹e (3
/// expected); the summary gives the share of poses within their radius (0.95 expected).
/// Angles are reported in millidegrees (mdeg: 1 mdeg = 17.45 µrad, 0.026 mm at 1.5 m).

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/compensation/validation/validation.hpp"

namespace errfield::compensation {

/// Millidegrees per radian.
inline constexpr double kMdegPerRad = 180000.0 / 3.14159265358979323846;

struct ValidatedRotation {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string point;          ///< the pose's `point` name
  std::string status = "ok";  ///< the model's status at the pose (CompensationModel::predict_rotation)
  std::size_t readings = 0;   ///< points read at the pose that the model located
  Eigen::Vector3d before_mdeg = Eigen::Vector3d::Constant(kNaN);  ///< robot frame
  Eigen::Vector3d after_mdeg = Eigen::Vector3d::Constant(kNaN);
  double r95_mdeg = kNaN, nees = kNaN;
};

struct RotationCheck {
  std::vector<ValidatedRotation> poses;
  std::size_t refused = 0;
  std::optional<ErrorStats> before;  ///< of |w| in mdeg (ErrorStats' "_mm" figures hold mdeg here)
  ErrorStats after;
  std::size_t covered = 0;  ///< ok poses with |after| <= r95
  double coverage95 = std::numeric_limits<double>::quiet_NaN();
  double mean_nees = std::numeric_limits<double>::quiet_NaN();

  /// {"poses","refused","before":{count,mean_mdeg,max_mdeg,rms_mdeg,p95_mdeg}|null,"after":{...},
  /// "coverage95","mean_nees"}
  nlohmann::json summary_json() const;
  std::string summary_text() const;
};

/// The orientation check of `model` on `data` (readings with a `reflector` column, as
/// MeasurementSet::from_table reads them with several points; a label is the point
/// CompensationModel::flange_points() gives it), `nominal` the nominal robot of "before". Empty when
/// the model predicts no rotation (fewer than three fielded points), has no registration, the data
/// have no positions or no pose has readings at three of the model's points off one line.
std::optional<RotationCheck> validate_rotations(const CompensationModel& model, const MeasurementSet& data,
                                                const robot::MdhModel& nominal);

}  // namespace errfield::compensation
