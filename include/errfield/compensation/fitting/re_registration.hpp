#pragma once
/// Another day, the tracker moved: a model fitted on one set of tracker readings, registered anew to
/// readings taken after the tracker (or the robot) stood elsewhere. Everything the model learned about
/// the robot — calibration, joint error functions, field — is kept; only the rigid tracker ↔ robot
/// registration (registration.hpp) and the nominal robot's own registration ("before") are replaced.
/// Use it with a few readings (10-30) spread over the work volume, or a separate registration set.
///
/// The readings are mapped onto the model's prediction of its own point at their joints (the command
/// model's FK plus the field inside its region, plus the joint error functions outside it, where the
/// field is not defined), the frame the model's errors live in, as `fit` registers its training rows.
/// Readings that do not fit one rigid motion (a bumped reflector, a wrong row, the tracker moved
/// during the series) are left out: the registration of the triple of readings that leaves the
/// smallest median residual (least median of squares: a least-squares start is pulled towards a
/// group of bad readings until none stands out) gives the robust sd, readings beyond `outlier_sigmas`
/// of it are left out and the rest refitted by least squares (twice). More than `max_excluded_share`
/// left out refuses the whole set: they are not of one rigid motion (another robot, a tracker bumped
/// mid-series, joints of another file).

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/model/registration.hpp"

namespace errfield::compensation {

struct ReRegistrationOptions {
  /// sqrt of chi-square with 3 degrees of freedom at 0.999: a 3-D residual of Gaussian readings is
  /// beyond it once in a thousand.
  double outlier_sigmas = 4.03;
  /// Robust sd per axis is never taken below this (mm): a tracker's noise; readings that agree to a
  /// micrometre would otherwise flag a 20 µm one.
  double min_sigma_mm = 0.01;
  double max_excluded_share = 0.2;
  std::size_t min_readings = 4;
};

struct ReRegistration {
  Registration registration;          ///< robot ← tracker onto the model's predictions
  Registration nominal_registration;  ///< robot ← tracker onto the nominal robot's FK ("before")
  std::vector<double> residual_mm;    ///< every reading's 3-D residual after `registration`
  std::vector<std::size_t> excluded;  ///< readings left out (indices), largest residual first
  std::size_t without_field = 0;      ///< readings outside the field's region (calibration + functions)
  double robust_sigma_mm = 0.0;       ///< per-axis robust sd of the kept residuals
};

/// Registers `tracker_mm[i]` (readings at joints `q_deg[i]`, tracker frame) onto `model`'s prediction.
/// `nominal` is the nominal robot at the point read (nominal_at_working_tool). Throws InputError
/// (naming `source`) for fewer than min_readings readings, readings whose spread spans no plane
/// (a rigid motion is then not determined), or more than max_excluded_share left out.
ReRegistration reregister(const CompensationModel& model, const robot::MdhModel& nominal,
                          const std::vector<robot::JointVector>& q_deg, const std::vector<Eigen::Vector3d>& tracker_mm,
                          const std::string& source, const ReRegistrationOptions& options = {});

}  // namespace errfield::compensation
