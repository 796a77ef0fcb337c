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

ArmConfiguration arm_configuration(const MdhModel& model, const JointVector& q_deg) {
  KinematicFrames f;
  forward_kinematics_all(model, q_deg, f);
  auto origin = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].translation(); };
  auto z_axis = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].linear().col(2); };
  const Eigen::Vector3d wrist_centre = origin(5);
  ArmConfiguration c;
  const Eigen::Vector3d in_frame1 = f.frames[1].inverse() * wrist_centre;
  c.shoulder = configuration_sign(in_frame1.x() / in_frame1.norm());
  const Eigen::Vector3d upper = origin(3) - origin(2), fore = wrist_centre - origin(3);
  c.elbow = configuration_sign(z_axis(2).dot(upper.cross(fore)) / (upper.norm() * fore.norm()));
  c.wrist = configuration_sign(z_axis(5).dot(z_axis(4).cross(z_axis(6))));
  return c;
}

}  // namespace errfield::robot
