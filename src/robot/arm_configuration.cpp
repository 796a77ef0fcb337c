#include "errfield/robot/arm_configuration.hpp"

#include "errfield/robot/kinematics.hpp"

namespace errfield::robot {

namespace {
int sign_of(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }
char sign_char(int s) { return s > 0 ? '+' : (s < 0 ? '-' : '0'); }
}  // namespace

std::string ArmConfiguration::to_string() const {
  return std::string{'s', sign_char(shoulder), 'e', sign_char(elbow), 'w', sign_char(wrist)};
}

ArmConfiguration arm_configuration(const MdhModel& model, const JointVector& q_deg) {
  KinematicFrames f;
  forward_kinematics_all(model, q_deg, f);
  auto origin = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].translation(); };
  auto z_axis = [&](int i) -> Eigen::Vector3d { return f.frames[static_cast<std::size_t>(i)].linear().col(2); };
  const Eigen::Vector3d wrist_centre = origin(5);
  ArmConfiguration c;
  c.shoulder = sign_of((f.frames[1].inverse() * wrist_centre).x());
  c.elbow = sign_of(z_axis(2).dot((origin(3) - origin(2)).cross(wrist_centre - origin(3))));
  c.wrist = sign_of(z_axis(5).dot(z_axis(4).cross(z_axis(6))));
  return c;
}

}  // namespace errfield::robot
