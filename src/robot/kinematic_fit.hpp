#pragma once
// Internal: the kinematic-calibration step of `fit --method kinematic|kinematic+kriging`
// (model_fitting.hpp): from tracker positions (registration with the reflector offset, then the
// model) or from distances to base points, whichever FitOptions::calibration_data asks for.

#include <optional>
#include <string>
#include <vector>

#include "errfield/robot/model_fitting.hpp"

namespace errfield::robot::detail {

struct KinematicFit {
  MdhModel model;  ///< identified, in the nominal robot's world frame
  std::optional<Registration> registration;  ///< robot ← tracker, from position calibration
  std::vector<std::string> notes, warnings;
};

KinematicFit fit_kinematic(const MdhModel& robot, const MeasurementSet& data, const FitOptions& options);

}  // namespace errfield::robot::detail
