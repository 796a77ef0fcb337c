#pragma once
/// The tracker ↔ robot registration as an artifact: the rigid transform that maps a laser
/// tracker's readings (tracker frame) into the robot frame a model predicts in. `errfield fit` and
/// `errfield calibrate` fit it on their training rows and store it (at full precision) in the JSON
/// they write; `validate`, `predict` and `fk` read it back, so held-out measurements are compared
/// in the frame the model was fitted in and are never re-registered on themselves.
///
/// JSON form (member "registration" of a compensation model or a calibrated robot JSON):
///   {"robot_from_tracker": [[r11,r12,r13,tx],[r21,r22,r23,ty],[r31,r32,r33,tz]],
///    "residual_rms_mm": 0.31, "points": 125, "reflector_offset_mm": [x,y,z] (optional)}
/// The 3 x 4 matrix is [R | t] of p_robot = R p_tracker + t (mm); numbers are written in the shortest
/// form that reads back to the same double.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

namespace errfield::compensation {

/// Rigid registration robot ← tracker (least squares over point pairs, Horn's closed form) and how
/// well it fitted. The residual RMS absorbs the rigid part of the robot's error.
struct Registration {
  Eigen::Isometry3d robot_from_tracker = Eigen::Isometry3d::Identity();
  double residual_rms_mm = 0.0;
  std::size_t points = 0;  ///< point pairs it was fitted on (0: unknown)
  /// Reflector (tool point) offset in the flange found with the registration, mm; when known.
  std::optional<Eigen::Vector3d> reflector_offset_mm;
};

/// Fits the registration that maps `tracker_mm[i]` onto `robot_mm[i]`. Throws InputError for fewer
/// than 3 pairs or mismatched sizes.
Registration fit_registration(const std::vector<Eigen::Vector3d>& tracker_mm, const std::vector<Eigen::Vector3d>& robot_mm);

nlohmann::json registration_to_json(const Registration& r);
/// Reads the JSON form; throws InputError naming `source` and the member (a non-rigid matrix, a
/// missing or non-finite entry).
Registration registration_from_json(const nlohmann::json& j, const std::string& source);
/// The "registration" member of a model or robot JSON object, if it has one.
std::optional<Registration> find_registration(const nlohmann::json& document, const std::string& source);

/// Poses given in the tracker frame (a part or fixture measured with the tracker) in the robot frame
/// the registration maps into (the frame `compensate` takes targets in): each row x,y,z (mm),
/// rx,ry,rz (deg, robot/pose.hpp's convention) of the N x 6 `tracker_poses` is mapped as a whole,
/// robot_from_tracker · pose, so the orientation turns with the frame. Rows with a non-finite entry
/// come back non-finite. Throws InputError unless `tracker_poses` has 6 columns.
Eigen::MatrixXd poses_in_robot_frame(const Registration& r, const Eigen::MatrixXd& tracker_poses);

}  // namespace errfield::compensation
