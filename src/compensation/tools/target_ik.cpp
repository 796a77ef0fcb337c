#include "errfield/compensation/tools/target_ik.hpp"

#include <cmath>
#include <limits>

#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

double pose_distance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double weight_mm) {
  return (a.translation() - b.translation()).norm() +
         weight_mm * rotation_log(a.linear().transpose() * b.linear()).norm();
}

int det_sign(const MdhModel& m, const JointVector& q, EndFrame frame) {
  const double d = geometric_jacobian(m, q, frame).determinant();
  return d > 0.0 ? 1 : (d < 0.0 ? -1 : 0);
}

}  // namespace

BranchIkResult solve_on_branch(const MdhModel& model, const Eigen::Isometry3d& target,
                               const std::vector<JointVector>& reference, const std::optional<JointVector>& seed,
                               const IkOptions& options) {
  BranchIkResult out;
  JointVector start;
  if (seed) {
    start = *seed;
  } else if (!reference.empty()) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < reference.size(); ++i) {
      const double d = pose_distance(forward_kinematics(model, reference[i], options.frame), target,
                                     options.orientation_weight_mm);
      if (d < best) {
        best = d;
        out.start_sample = i;
        start = reference[i];
      }
    }
  } else {
    out.had_reference = false;
    out.ik = inverse_kinematics_multistart(model, target, options);
    return out;
  }
  const Eigen::Isometry3d from = forward_kinematics(model, start, options.frame);
  const Eigen::Vector3d dp = target.translation() - from.translation();
  const Eigen::Vector3d w = rotation_log(from.linear().transpose() * target.linear());
  // Steps of at most 20 mm and 2 deg: small enough that each solve stays in the basin of the
  // previous solution, so a branch can only be left through a singular configuration.
  const int steps = std::clamp(static_cast<int>(std::ceil(std::max(dp.norm() / 20.0, w.norm() / (2.0 * M_PI / 180.0)))),
                               1, 200);
  int sign0 = det_sign(model, start, options.frame);  // 0 only exactly at a singularity: take the first step's
  JointVector q = start;
  for (int s = 1; s <= steps; ++s) {
    const double t = static_cast<double>(s) / steps;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = from.linear() * rotation_exp(t * w);
    pose.translation() = from.translation() + t * dp;
    if (s == steps) pose = target;
    out.ik = inverse_kinematics(model, pose, q, options);
    if (!out.ik.ok() && s < steps) continue;  // an intermediate pose may be unreachable; keep going
    q = out.ik.q_deg;
    const int sign = det_sign(model, q, options.frame);
    if (sign0 == 0) sign0 = sign;
    if (sign != sign0) out.branch_changed = true;
  }
  return out;
}

}  // namespace errfield::compensation
