#pragma once
/// ABB's robot configuration data (RAPID `confdata`, the third part of a robtarget) from joints.
/// Use it to find which inverse-kinematics solution a robtarget asks for and to check that a
/// compensated target stays on it.
///
/// As ABB's technical reference manual (RAPID data types, confdata) defines it for six-axis arms:
/// cf1, cf4 and cf6 are the quadrants of axes 1, 4 and 6, the integer part of angle/90 deg rounded
/// down (0 for 0..90 deg, -1 for -90..0 deg, 2 for 180..270 deg); cfx is a number 0..7:
///   cfx = 4 * [wrist centre behind axis 1] + 2 * [wrist centre behind the lower arm] + [axis 5 < 0].
/// "Behind axis 1": the wrist centre lies on the far side of the plane through axis 1 normal to the
/// arm's forward direction (link frame 1's x axis as the robot description orients it at q = 0).
/// "Behind the lower arm": on the other side of the line through axes 2 and 3 (the lower arm) than
/// at the home posture. Both are measured from the robot description's link frames, the wrist
/// centre being frame 5's origin (axes 4, 5 and 6 meet there on ABB's spherical wrists), and
/// "in front" is the side the wrist centre is on at the home posture (q = 0, axis 5 bent), where
/// every ABB arm has it in front of both.

#include <string>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::programs {

struct AbbConfdata {
  int cf1 = 0, cf4 = 0, cf6 = 0, cfx = 0;
  bool operator==(const AbbConfdata&) const = default;
  std::string to_string() const;  ///< "[cf1,cf4,cf6,cfx]"
};

/// The confdata of joints `q_deg` (deg) on `model`.
AbbConfdata abb_confdata(const robot::MdhModel& model, const robot::JointVector& q_deg);

}  // namespace errfield::programs
