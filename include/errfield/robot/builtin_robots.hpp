#pragma once
/// Nominal robots errfield knows by name, from published datasheets: the ER20-C10 of the paper,
/// a KUKA KR 16 class arm and Universal Robots' UR5e, UR5 and UR10 (the last two CB3). Choose one
/// wherever a robot is accepted (`--robot kr16`); `errfield robots` lists them. Each carries where its numbers come from and a
/// workspace cube it reaches at a tool-down orientation, so `errfield simulate --robot NAME` has a
/// sensible default region. docs/robot.md ("Built-in robots") documents the joint conventions.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot {

struct BuiltinRobot {
  std::string name;         ///< What `--robot` takes (lower case).
  std::string description;  ///< One line for `errfield robots`.
  std::string source;       ///< Where the numbers come from.
  MdhModel model;           ///< Nominal, no tool, base frame at the robot base.
  /// A cube (min corner, side, mm, robot base frame) reachable at `cube_rpy_deg` with every point on
  /// one IK branch: the default region of `errfield simulate --robot NAME`.
  Eigen::Vector3d cube_min_mm;
  double cube_size_mm;
  Eigen::Vector3d cube_rpy_deg;
};

/// Every built-in robot, the ER20-C10 first.
const std::vector<BuiltinRobot>& builtin_robots();
/// The built-in robot called `name` (case-insensitive; "er20" is accepted for "er20-c10"), or
/// nothing.
const BuiltinRobot* find_builtin_robot(const std::string& name);
/// What a `--robot` argument names: the built-in robot of that name unless a file (not a
/// directory: a folder called "kr16" holding a user's outputs is not a robot) of that name
/// exists, in which case the user's file wins; nothing when it is not a built-in name.
const BuiltinRobot* builtin_robot_unless_file(const std::string& name_or_path);
/// "er20-c10, kr16, ur5e, ur5, ur10" for messages.
std::string builtin_robot_names();

/// KUKA KR 16 class arm (KR 16-2 datasheet dimensions; docs/robot.md for the joint convention).
MdhModel kr16();
/// Universal Robots UR5e: the published standard D-H table converted to modified D-H.
MdhModel ur5e();
/// Universal Robots UR5 (CB3 series): its published standard D-H table, converted as ur5e's.
MdhModel ur5();
/// Universal Robots UR10 (CB3 series): its published standard D-H table, converted as ur5e's.
MdhModel ur10();

}  // namespace errfield::robot
