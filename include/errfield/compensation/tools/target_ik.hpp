#pragma once
/// Inverse kinematics of pose targets on the branch of a model's data. A 6R arm reaches most poses
/// in several configurations (shoulder, elbow, wrist flip); an error model fitted on one branch says
/// nothing about another (joint-space models even less), and a multistart solver picks whichever
/// posture converges first. So a pose target is solved from the nearest sample of the model's data
/// (by position plus 500 mm per rad of orientation, the IK's own weighting) or from a given seed,
/// by continuation along the straight pose path from that sample to the target; the sign of the
/// Jacobian's determinant is watched along the path. A sign change means the path crossed a
/// singular configuration onto another branch: that is reported (branch_changed), never passed off
/// as a solution on the data's branch.

#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/robot/inverse_kinematics.hpp"

namespace errfield::compensation {

struct BranchIkResult {
  robot::IkResult ik;
  bool branch_changed = false;
  /// The sample the path started from (index into the reference joints); empty for a given seed or
  /// when there was no reference (then multistart was used and branch_changed says nothing).
  std::optional<std::size_t> start_sample;
  bool had_reference = true;
  bool ok() const { return ik.ok() && !branch_changed; }
};

/// Solves `target` (world frame, tool point) on `model`. `seed_deg` takes precedence over
/// `reference_deg` (the model's training joints); with neither, multistart IK.
BranchIkResult solve_on_branch(const robot::MdhModel& model, const Eigen::Isometry3d& target,
                               const std::vector<robot::JointVector>& reference_deg,
                               const std::optional<robot::JointVector>& seed_deg = std::nullopt,
                               const robot::IkOptions& options = {});

}  // namespace errfield::compensation
