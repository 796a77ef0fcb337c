#pragma once
/// Reading the targets of a Universal Robots URScript program (.script) for compensation: every
/// pose a move uses, with the TCP in force there, and the byte spans of its numbers so they can be
/// rewritten in place.
///
/// What is read: movel, movej, movep and movec (its via and end poses) with a pose literal
/// `p[x,y,z,rx,ry,rz]` (metres; a rotation vector, axis times angle in rad) or a variable assigned
/// one exactly once (`global Waypoint_1_p=p[...]`); a joint list (`[q1,...,q6]`, rad, or a variable
/// holding one) is a joint target, reported unchanged; anything else (pose_trans, pose_add,
/// get_inverse_kin, interpreter variables assigned more than once, ...) is computed. The TCP in
/// force is the last `set_tcp(p[...])` before the move in the file's text (a set_tcp of anything
/// but a literal makes it unknown); before any set_tcp it is the installation's active TCP, unknown
/// to the program: such moves are refused unless it is given (`--tool tcp=...`). URScript has no
/// configuration: the joint solution nearest the previous target's is used, or, when the program
/// stores a joint list beside the pose (`Waypoint_1_q` beside `Waypoint_1_p`, Polyscope's naming),
/// the solution within kUrStoredJointsDeg of it on every joint (whole turns apart count as one).
/// Numbers are rewritten in metres and radians, spelled with as many decimals as the literal had (at
/// least 6: 1 um, 1 urad), in its style (".417" keeps no leading 0).

#include <array>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/programs/program_target.hpp"
#include "errfield/programs/program_text.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::programs {

/// A solution within this of a pose's stored joint list (every joint, deg) is the one the stored
/// joints ask for.
inline constexpr double kUrStoredJointsDeg = 20.0;

struct UrscriptReadOptions {
  /// The TCP in force before any set_tcp, under the name "tcp" (flange -> TCP, mm); absent: unknown.
  std::map<std::string, Eigen::Isometry3d> tools;
};

/// The target occurrences of the moves in `program` in the order they appear (replacements name
/// file 0). Throws InputError naming file and line for text that is not URScript as expected (an
/// unterminated string or bracket).
std::vector<ProgramTarget> read_urscript_targets(const ProgramFile& program, const UrscriptReadOptions& options = {});

/// A URScript pose p[x,y,z,rx,ry,rz] (m, rad rotation vector) as a pose in mm, and back.
Eigen::Isometry3d urscript_pose(const std::array<double, 6>& p);
std::array<double, 6> urscript_pose_of(const Eigen::Isometry3d& pose_mm);

}  // namespace errfield::programs
