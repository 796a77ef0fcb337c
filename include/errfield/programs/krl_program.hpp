#pragma once
/// Reading the targets of a KUKA KRL program (a .src and the .dat beside it) for compensation:
/// every Cartesian target a motion uses, with the tool, base and Status/Turn in force there, and the
/// byte spans of its numbers so they can be rewritten in place.
///
/// What is read: PTP, LIN, CIRC and the spline motions SPTP, SLIN, SCIRC, SPL with a point name
/// (E6POS, POS or FRAME declared in the .src, the .dat or an include such as $config.dat; arrays
/// `P[3]` element by element) or an inline aggregate `{X 10,Y 20,...}`; the tool and base in force
/// from `$TOOL=TOOL_DATA[n]` / `$BASE=BASE_DATA[n]` (or $NULLFRAME), `BAS(#TOOL,n)`/`BAS(#BASE,n)`,
/// `FDAT_ACT=FP1` (the FDAT's TOOL_NO/BASE_NO) and the inline-form fold line's `Tool[n] Base[n]`,
/// whichever comes last; TOOL_DATA[n]/BASE_DATA[n] from their `{X,Y,Z,A,B,C}` aggregates in any
/// file read, or given by name (`--tool TOOL_DATA[1]=...`). Index 0 and $NULLFRAME are the flange
/// and $WORLD (taken as the robot base: $ROBROOT at $WORLD). Axis targets (E6AXIS/AXIS, `{A1 ..}`)
/// are reported unchanged; relative motions (PTP_REL, ...), frame products (`:`), function calls,
/// partial aggregates and points assigned in the .src at run time are reported computed.
///
/// Angles: KUKA's A, B, C (deg) are R = Rz(A) Ry(B) Rx(C), errfield's (rz, ry, rx) (robot/pose.hpp).
/// Status/Turn (decimal or 'B0101' binary) pick the joint solution of PTP motions (CP motions, LIN
/// and CIRC and the splines, ignore them on the controller, so the solution nearest the previous
/// target's is used there). Checked: Turn bit i set = axis i+1 < 0 deg, and Status bit 0 = the
/// wrist centre behind axis 1 (its x in the A1 coordinate system negative, KUKA's "overhead area"),
/// both as KUKA's expert programming manual defines them. Status bits 1 and 2 (the elbow, the wrist)
/// are not checked: their definition differs between KUKA documents and arm types; the elbow is
/// held by the branch the solution starts on. The joint angles are the robot description's: they
/// mean KUKA's only where the description counts the axes as the controller does.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "errfield/programs/program_target.hpp"
#include "errfield/programs/program_text.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::programs {

struct KrlReadOptions {
  /// Tools and bases given by name, e.g. "TOOL_DATA[1]", "BASE_DATA[2]" (case-insensitive): these
  /// win over declarations (flange -> TCP, robot base -> base frame; mm).
  std::map<std::string, Eigen::Isometry3d> tools, bases;
};

/// The target occurrences of the motions in `src` in the order they appear. `dat` (may be empty:
/// path "") is the .dat beside the .src; points declared in `src` or `dat` are rewritten (the
/// replacements name file 0 for `src`, 1 for `dat`), points declared in `includes` are refused.
/// `robot` is the controller's nominal robot (for Status/Turn). Throws InputError naming file and
/// line for text that is not KRL as expected (an unterminated string or aggregate).
std::vector<ProgramTarget> read_krl_targets(const ProgramFile& src, const ProgramFile& dat, const std::vector<ProgramFile>& includes,
                                            const robot::MdhModel& robot, const KrlReadOptions& options = {});

/// KUKA's A, B, C (deg) of a rotation, and back: R = Rz(A) Ry(B) Rx(C).
Eigen::Matrix3d kuka_abc_rotation(double a_deg, double b_deg, double c_deg);
Eigen::Vector3d kuka_abc_of(const Eigen::Matrix3d& r);  ///< (A, B, C) deg, B in [-90, 90]

/// A KRL Status or Turn value as written: a decimal ("6") or a bit literal ('B110', 'H1A'); -1 if
/// it is neither.
int krl_bits(const std::string& text);

/// True when joints `q_deg` have the Turn `turn` (bit i set: axis i+1 < 0 deg).
bool krl_turn_matches(int turn, const robot::JointVector& q_deg);

}  // namespace errfield::programs
