#include "errfield/robot/arm_configuration.hpp"

#include <cmath>
#include <numbers>

#include "errfield/robot/kinematics.hpp"

namespace errfield::robot {

namespace {
// The sign of `sine`, 0 within the band (and for NaN).
int configuration_sign(double sine) {
  const double band = std::sin(kConfigurationBandDeg * std::numbers::pi / 180.0);
  return sine > band ? 1 : (sine < -band ? -1 : 0);
}
char configuration_sign_char(int s) { return s > 0 ? '+' : (s < 0 ? '-' : '0'); }
}  // namespace

std::string ArmConfiguration::to_string() const {
  return std::string{'s', configuration_sign_char(shoulder), 'e', configuration_sign_char(elbow), 'w', configuration_sign_char(wrist)};
}

std::optional<ArmConfiguration> parse_arm_configuration(std::string_view text) {
  if (text.size() != 6 || text[0] != 's' || text[2] != 'e' || text[4] != 'w') return std::nullopt;
  int sign[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const char c = text[static_cast<std::size_t>(2 * k + 1)];
    if (c != '+' && c != '-') return std::nullopt;
    sign[k] = c == '+' ? 1 : -1;
  }
  return ArmConfiguration{sign[0], sign[1], sign[2]};
}

ArmConfiguration arm_configuration(const MdhModel& model, const JointVector& q_deg) {
  KinematicFrames f;
  forward_kinematics_all(model, q_deg, f);
  auto origin = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].translation(); };
  auto z_axis = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].linear().col(2); };
  const Eigen::Vector3d wrist_centre = origin(5);
  ArmConfiguration c;
  const Eigen::Vector3d in_frame1 = f.frames[1].inverse() * wrist_centre;
  c.shoulder = configuration_sign(in_frame1.x() / in_frame1.norm());
  // The elbow bends the forearm up to frame 4's origin: the wrist centre of a spherical wrist, and for
  // an offset wrist (UR) the end of the planar two-link arm its analytic IK solves, whose elbow choice
  // is then the sign of q3. Both arms projected on the plane of the elbow's motion (normal to axis 2).
  const Eigen::Vector3d z2 = z_axis(2);
  auto in_plane = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d { return v - v.dot(z2) * z2; };
  const Eigen::Vector3d upper = in_plane(origin(3) - origin(2)), fore = in_plane(origin(4) - origin(3));
  c.elbow = configuration_sign(z2.dot(upper.cross(fore)) / (upper.norm() * fore.norm()));
  c.wrist = configuration_sign(z_axis(5).dot(z_axis(4).cross(z_axis(6))));
  return c;
}

}  // namespace errfield::robot
