#pragma once
/// One use of a Cartesian (or joint) target in a robot program, read by a format's reader (RAPID,
/// KRL, URScript) into the same vendor-neutral form: the pose with the tool, the work object/base
/// and the configuration in force where it is used, and how to write a new pose back. Readers
/// produce these; compensate_program_targets (program_compensation.hpp) consumes them.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/programs/program_text.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::programs {

/// What a target occurrence is: a literal pose errfield can rewrite, a pose the controller
/// computes at run time (Offs, RelTool, pose_trans, frame products, assignments), or joints
/// (MoveAbsJ, movej with a joint list, PTP with axis values), which no Cartesian model changes.
enum class TargetKind { literal, computed, joints };

/// The configuration a literal asks for (ABB confdata, KUKA Status/Turn): a test on joints, its
/// text for messages, and whether the controller holds the robot to it at this move.
struct ConfigurationRequest {
  /// True when joints `q_deg` (nominal robot, deg) are on the requested configuration; empty: none
  /// requested (any solution, nearest the previous target's).
  std::function<bool(const robot::JointVector&)> matches;
  std::string text;  ///< as written, e.g. "[0,-1,-1,0]" or "S 'B010' T 'B110010'"
  /// The controller ignores the configuration here (ABB ConfL\Off / ConfJ\Off): the branch nearest
  /// the previous target's is used and the reason says so. `off_by` names the instruction.
  bool ignored = false;
  std::string off_by;
};

struct ProgramTarget {
  std::string file;        ///< file the occurrence is in (as given)
  std::size_t line = 0;    ///< 1-based line of the occurrence (the move that uses it)
  std::string label;       ///< the target's name, or a short form of an inline literal/expression
  TargetKind kind = TargetKind::literal;
  /// computed/joints: what it depends on / why it is unchanged; literal: extra words for the report.
  std::string note;
  /// Set when the target cannot be compensated before any computation (an unknown tool or work
  /// object, a literal not in the expected form): the report's reason, status refused.
  std::string refusal;
  Eigen::Isometry3d pose_in_frame = Eigen::Isometry3d::Identity();  ///< literal: the target (mm)
  std::string tool_name;
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();   ///< flange -> TCP (mm)
  std::string frame_name;
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();  ///< robot base -> program frame (mm)
  ConfigurationRequest configuration;
  /// Occurrences of one declared target share a key (rewritten once); empty for inline literals.
  std::string shared_key;
  /// The replacements that write `new_pose_in_frame` in place of this literal's numbers.
  std::function<std::vector<Replacement>(const Eigen::Isometry3d& new_pose_in_frame)> rewrite;
};

}  // namespace errfield::programs
