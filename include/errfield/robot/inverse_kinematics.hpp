#pragma once
/// Inverse kinematics of an MdhModel: joint angles that put the flange or tool at a target pose.
///
/// Damped least squares with Levenberg–Marquardt damping control on the 6-D pose error
/// (position mm; orientation as a rotation vector scaled by `orientation_weight_mm`), joint
/// limits enforced by projection. It finds the solution nearest the seed's branch, which is what
/// compensation needs (the seed is the nominal solution; a few iterations). Failures are a status
/// with the residual, never a silent wrong answer. Thread-safe, allocation-free.

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/robot/kinematics.hpp"

namespace errfield::robot {

struct IkOptions {
  EndFrame frame = EndFrame::tool;
  double position_tolerance_mm = 1e-7;     ///< Converged when |dp| below this ...
  double orientation_tolerance_rad = 1e-10; ///< ... and |rotation error| below this.
  /// Length (mm) that turns a rotation error (rad) into mm in the least-squares objective.
  double orientation_weight_mm = 500.0;
  int max_iterations = 100;
  double initial_damping = 1e-3;  ///< lambda relative to the mean diagonal of J^T J.
  /// Solve for position only (orientation is free; for 3-D targets).
  bool position_only = false;
  /// Throws ArgumentError naming the field when a value is out of range.
  void validate() const;
};

enum class IkStatus {
  converged,       ///< Residual within tolerance, joints within limits.
  joint_limits,    ///< The best pose within the joint limits misses the target, and the solver
                   ///< without limits, continued from there, reaches it: a joint would have to go
                   ///< beyond its range.
  unreachable,     ///< Stalled away from the target and no joint values reach it from there: outside
                   ///< the reach sphere (sum of the links' lengths, plus the tool's), or out of the
                   ///< workspace or at a singular configuration even without limits.
  max_iterations,  ///< Still improving when the iteration budget ran out.
};

const char* to_string(IkStatus s);

struct IkResult {
  JointVector q_deg;                 ///< Best joints found (always within limits).
  IkStatus status = IkStatus::max_iterations;
  double position_residual_mm = 0;   ///< |p_target - p(q)|.
  double orientation_residual_rad = 0;  ///< Angle of R_target R(q)^T (0 if position_only).
  int iterations = 0;
  bool ok() const { return status == IkStatus::converged; }
};

/// Solves IK for `target` (world frame, mm) from `seed_deg`. Precondition: options.validate() passed
/// and the seed is finite (it is clamped into the limits first).
IkResult inverse_kinematics(const MdhModel& model, const Eigen::Isometry3d& target, const JointVector& seed_deg,
                            const IkOptions& options = {});

/// A seed for targets without one: a few fixed postures tried in turn (used by the CLI and
/// the planner when the user gives none). Returns the first converged result, or the best one.
IkResult inverse_kinematics_multistart(const MdhModel& model, const Eigen::Isometry3d& target,
                                       const IkOptions& options = {});

}  // namespace errfield::robot
