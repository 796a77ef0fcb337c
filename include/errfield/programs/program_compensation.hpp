#pragma once
/// Compensating the targets of a robot program with a fitted model: the same computation as
/// `errfield compensate` on a CSV of pose targets (compensation/pipeline.hpp compensate_columns:
/// the working tool, orientation where the model predicts it, the credible region, the ceiling on
/// the correction, every status), applied to each literal target with the tool, work object and
/// configuration in force where the program uses it. The compensated target is the pose the
/// controller's nominal kinematics turn into the compensated joints: the nominal FK of those joints
/// with the tool, in the target's own frame. Use it from any format's reader (program_target.hpp).

#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/compensation/model/compensation.hpp"
#include "errfield/programs/program_target.hpp"

namespace errfield::programs {

/// Report statuses (the `status` column of compensate-program's report).
inline constexpr const char* kStatusOk = "ok";              ///< rewritten
inline constexpr const char* kStatusComputed = "computed";  ///< computed at run time: not a literal
inline constexpr const char* kStatusUnchanged = "unchanged";  ///< joint target
inline constexpr const char* kStatusRefused = "refused";    ///< left as written, with the reason

/// One row of the report: one target occurrence.
struct ProgramReportRow {
  std::string file;
  std::size_t line = 0;
  std::string target, status, reason;
  Eigen::Vector3d d_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  ///< new - old, target frame
  robot::JointVector q_deg = robot::JointVector::Constant(std::numeric_limits<double>::quiet_NaN());  ///< compensated joints
  /// Rotation vector of R_new R_old^T (target frame, mdeg); NaN where nothing was rewritten.
  Eigen::Vector3d rotation_mdeg = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

struct ProgramCompensation {
  std::vector<ProgramReportRow> rows;        ///< in the order of the targets given
  std::vector<Replacement> replacements;     ///< byte edits of the program (each declaration once)
  double largest_correction_mm = 0.0;        ///< largest |d_mm| among rewritten rows
  double max_correction_mm = 0.0;            ///< the ceiling applied (compensate's --max-correction)
};

struct ProgramCompensationOptions {
  double tolerance_mm = 0.25;     ///< compensate's --tolerance (only feeds p_inside)
  double max_correction_mm = 0.0; ///< compensate's --max-correction; 0 = the model's default
};

/// Compensates every literal of `targets` (see file comment); computed and joint targets are
/// reported, never touched. `nominal_robot` is the controller's nominal robot (the model's stored
/// nominal robot for kinematic models). Declared targets used several times are rewritten once, and
/// only when every use asks for the same rewrite.
ProgramCompensation compensate_program_targets(const compensation::CompensationModel& model,
                                               const robot::MdhModel& nominal_robot,
                                               const std::vector<ProgramTarget>& targets,
                                               const ProgramCompensationOptions& options = {});

/// Every solution of `target` (robot base frame, mm) on `nominal` for which `wanted` holds,
/// nearest `near_deg` first (or in the order found): IK from a spread of seeds plus each solution's
/// wrist flip and its +-360 deg turns of axes 1, 4 and 6 within the joint limits.
std::vector<robot::JointVector> solutions_on_configuration(
    const robot::MdhModel& nominal, const Eigen::Isometry3d& target,
    const std::function<bool(const robot::JointVector&)>& wanted, const std::optional<robot::JointVector>& near_deg);

}  // namespace errfield::programs
