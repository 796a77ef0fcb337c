#pragma once
// Internal: the kinematic-calibration step of `fit --method kinematic|kinematic+kriging`
// (model_fitting.hpp): from tracker positions (registration with the reflector offset, then the
// model) or from distances to base points, whichever FitOptions::calibration_data asks for.

#include <optional>
#include <string>
#include <vector>

#include "errfield/compensation/fitting/model_fitting.hpp"

namespace errfield::compensation::detail {

struct KinematicFit {
  robot::MdhModel model;  ///< identified, in the nominal robot's world frame
  std::optional<Registration> registration;  ///< robot ← tracker, from position calibration
  std::vector<std::string> notes, warnings;
  /// From positions: the identified reflector and the tool point compensate aims (flange frame, mm).
  std::optional<Eigen::Vector3d> reflector_mm, tool_point_mm;
  /// Data of several points on the flange: the rows of the model's own point (the reflector), which
  /// the joint functions and the field take; empty: every row.
  std::vector<std::size_t> own_point_rows;
  /// Data of several points: each row's point on the calibrated flange (flange frame, mm).
  std::vector<Eigen::Vector3d> flange_point_of_row_mm;
  /// Data of several points: each label's located position (flange frame, mm), the own point first.
  std::vector<std::pair<std::string, Eigen::Vector3d>> located_points;
  /// From positions: the leverage of the calibration (calibration_leverage.hpp).
  std::optional<CalibrationLeverage> leverage;
};

KinematicFit fit_kinematic(const robot::MdhModel& robot, const MeasurementSet& data, const FitOptions& options);

}  // namespace errfield::compensation::detail
