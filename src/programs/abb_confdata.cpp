#include "errfield/programs/abb_confdata.hpp"

#include <cmath>

#include "errfield/robot/kinematics.hpp"

namespace errfield::programs {
namespace {

int quadrant(double angle_deg) { return static_cast<int>(std::floor(angle_deg / 90.0)); }

// The two signed quantities cfx's first two bits compare with the home posture: the wrist centre's
// x in link frame 1, and its side of the lower arm's line about axis 2.
struct WristSides {
  double ahead_of_axis1 = 0.0, ahead_of_lower_arm = 0.0;
};

WristSides wrist_sides(const robot::MdhModel& model, const robot::JointVector& q_deg) {
  robot::KinematicFrames f;
  robot::forward_kinematics_all(model, q_deg, f);
  const Eigen::Vector3d wrist = f.frames[5].translation();
  const Eigen::Vector3d o2 = f.frames[2].translation(), o3 = f.frames[3].translation();
  const Eigen::Vector3d z2 = f.frames[2].linear().col(2);
  WristSides s;
  s.ahead_of_axis1 = (f.frames[1].inverse() * wrist).x();
  s.ahead_of_lower_arm = z2.dot((o3 - o2).cross(wrist - o2));
  return s;
}

}  // namespace

std::string AbbConfdata::to_string() const {
  return "[" + std::to_string(cf1) + "," + std::to_string(cf4) + "," + std::to_string(cf6) + "," + std::to_string(cfx) + "]";
}

AbbConfdata abb_confdata(const robot::MdhModel& model, const robot::JointVector& q_deg) {
  // Home with axis 5 bent (q5 = 0 puts axes 4 and 6 in line, which moves nothing used here but keeps
  // the reference away from any degenerate layout).
  robot::JointVector home = robot::JointVector::Zero();
  home[4] = 30.0;
  const WristSides ref = wrist_sides(model, home), now = wrist_sides(model, q_deg);
  AbbConfdata c;
  c.cf1 = quadrant(q_deg[0]);
  c.cf4 = quadrant(q_deg[3]);
  c.cf6 = quadrant(q_deg[5]);
  const bool behind_axis1 = now.ahead_of_axis1 * ref.ahead_of_axis1 < 0.0;
  const bool behind_lower_arm = now.ahead_of_lower_arm * ref.ahead_of_lower_arm < 0.0;
  c.cfx = 4 * behind_axis1 + 2 * behind_lower_arm + (q_deg[4] < 0.0);
  return c;
}

}  // namespace errfield::programs
