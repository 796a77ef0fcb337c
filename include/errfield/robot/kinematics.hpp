#pragma once
/// Forward kinematics, the geometric Jacobian and the identification Jacobian of an MdhModel.
///
/// Use forward_kinematics for one pose (flange or tool), forward_kinematics_all when you need
/// every link frame, geometric_jacobian for IK and velocity work, and identification_jacobian for
/// calibration. All functions are pure, allocation-free and thread-safe; joint angles come in
/// degrees (the interface unit), Jacobian columns are derivatives per radian (angles) or per mm
/// (lengths). Poses are in the model's world frame: `base · T_0^6 [· tool]`, mm.
/// The mathematics is in docs/robot.md ("Kinematics").

#include <array>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot {

/// Which frame a pose or Jacobian refers to.
enum class EndFrame { flange, tool };

/// Parses "flange" or "tool"; throws ArgumentError naming `what` otherwise.
EndFrame parse_end_frame(const std::string& text, const std::string& what = "--frame");

/// World poses of every frame for one joint vector: frames[0] is the robot base frame 0
/// (= model.base()), frames[i] the frame of link i (i = 1..6, frames[6] the flange), and
/// frames[7] the tool frame.
struct KinematicFrames {
  std::array<Eigen::Isometry3d, kJointCount + 2> frames;
  const Eigen::Isometry3d& flange() const { return frames[kJointCount]; }
  const Eigen::Isometry3d& tool() const { return frames[kJointCount + 1]; }
};

/// World pose (mm) of the flange or tool for joints `q_deg`. ~100 ns; no allocation.
Eigen::Isometry3d forward_kinematics(const MdhModel& model, const JointVector& q_deg,
                                     EndFrame frame = EndFrame::tool);

/// World position (mm) of the tool point (or flange origin) only.
Eigen::Vector3d forward_position(const MdhModel& model, const JointVector& q_deg, EndFrame frame = EndFrame::tool);

/// Every frame's world pose, see KinematicFrames.
void forward_kinematics_all(const MdhModel& model, const JointVector& q_deg, KinematicFrames& out);

/// Geometric Jacobian (6 x 6) of the chosen frame, in the world frame, reference point at that
/// frame's origin: rows 0–2 linear velocity (mm/rad), rows 3–5 angular velocity (rad/rad);
/// column j is joint j+1.
Eigen::Matrix<double, 6, kJointCount> geometric_jacobian(const MdhModel& model, const JointVector& q_deg,
                                                         EndFrame frame = EndFrame::tool);
/// Same, from frames already computed by forward_kinematics_all.
Eigen::Matrix<double, 6, kJointCount> geometric_jacobian(const KinematicFrames& frames, EndFrame frame);

// ---- Identification parameters -----------------------------------------------------------------

/// Layout of the identification parameter vector (kinematic calibration). All perturbations are
/// small increments, angles in rad, lengths in mm:
///   index 5*i + k, i = 0..5 (link i+1), k = 0 alpha_{i}, 1 a_{i}, 2 theta0_{i+1}, 3 d_{i+1},
///   4 beta_{i+1} (Hayati; rotation about the y axis after Dx(a));
///   30..32 base translation (world frame, mm), 33..35 base rotation (small rotation vector about
///   the world axes through the base origin, rad);
///   36..38 tool translation (in the flange frame, mm).
namespace param {
inline constexpr int kPerLink = 5;
inline constexpr int kAlpha = 0, kA = 1, kTheta0 = 2, kD = 3, kBeta = 4;
inline constexpr int kBaseTranslation = kPerLink * kJointCount;  // 30
inline constexpr int kBaseRotation = kBaseTranslation + 3;        // 33
inline constexpr int kToolTranslation = kBaseRotation + 3;        // 36
inline constexpr int kCount = kToolTranslation + 3;                // 39
constexpr int link_index(int link0, int k) { return kPerLink * link0 + k; }
}  // namespace param

using ParameterVector = Eigen::Matrix<double, param::kCount, 1>;
using IdentificationJacobian = Eigen::Matrix<double, 3, param::kCount>;

/// Name of parameter `index` ("link2.alpha", "link3.beta", "base.x", "base.rx", "tool.z", ...).
std::string parameter_name(int index);
/// Unit of parameter `index` as stored in the increment vector: "rad" or "mm".
const char* parameter_unit(int index);
/// True for angular parameters (rad in the increment vector, deg in the model).
bool parameter_is_angle(int index);

/// Derivative (3 x 39) of the world tool position with respect to every identification parameter
/// at `q_deg`; column units mm/rad or mm/mm. Exact (analytic), checked against finite differences
/// of apply_parameter_increment in the tests.
IdentificationJacobian identification_jacobian(const MdhModel& model, const JointVector& q_deg);

/// The model with a parameter increment applied (the inverse of linearization: FK of the result
/// equals FK + J·delta to first order). Angles in delta are rad, lengths mm.
MdhModel apply_parameter_increment(const MdhModel& model, const ParameterVector& delta);

}  // namespace errfield::robot
