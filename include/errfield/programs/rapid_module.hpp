#pragma once
/// Reading the targets of an ABB RAPID module (.mod, .prg, .sys) for compensation: every robtarget
/// a move instruction uses, with the tool, work object and configuration in force there, and the
/// byte spans of its numbers so they can be rewritten in place.
///
/// What is read: robtarget literals inline in MoveL/MoveJ/MoveC (and their DO/Sync/AO/GO forms,
/// TriggL/J/C), robtargets declared CONST/PERS/VAR (one level of arrays, `p{2}`), tooldata and
/// wobjdata declared in the module or in `includes` (or given by name), ConfL/ConfJ \On/\Off in
/// the order they appear, MoveAbsJ/MoveExtJ (joint targets: unchanged), and targets computed at run
/// time (Offs, RelTool, CRobT, any function call, or a robtarget assigned in a routine). A
/// robtarget's quaternion is [q1,q2,q3,q4] with q1 the scalar part; its confdata is checked with
/// abb_confdata.hpp; 9E9 external axes and everything else in it are kept as written. The work
/// object's frame is uframe o oframe; tool0 and wobj0 are the flange and the base frame.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/programs/program_target.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::programs {

struct RapidReadOptions {
  /// Tools and work objects given by name (`--tool NAME=...`, `--wobj NAME=...`): these win over
  /// declarations (flange -> TCP, base -> work object; mm).
  std::map<std::string, Eigen::Isometry3d> tools, wobjs;
};

/// The target occurrences of `program` in the order they appear. Tool, work object and robtarget
/// declarations are looked up in `program` first, then in `includes` (which are never rewritten:
/// a robtarget declared there is reported refused). `robot` is the controller's nominal robot
/// (for confdata). Throws InputError naming file and line for text that is not RAPID as expected
/// (an unterminated string or aggregate).
std::vector<ProgramTarget> read_rapid_targets(const ProgramFile& program, const std::vector<ProgramFile>& includes,
                                              const robot::MdhModel& robot, const RapidReadOptions& options = {});

}  // namespace errfield::programs
