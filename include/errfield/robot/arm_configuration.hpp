#pragma once
/// The arm configuration of a joint vector: which of the (up to 8) inverse-kinematics solutions of
/// one tool pose it is - shoulder, elbow and wrist flags. Use it to say which solution a set of
/// joints is on, and to check that a solver kept a wanted one (`errfield compensate`'s `config`
/// column and `config-change` status). errfield's own definition, from the link frames of the
/// MD-H model (docs/robot.md, "Arm configuration"), so it applies to any 6R arm the same way:
///
///  - shoulder: the sign of the x coordinate of frame 5's origin (the wrist centre of a spherical
///    wrist) in link frame 1, which turns with joint 1: + when the wrist centre is on the side of
///    axis 1 that x1 points to, − behind it. 0 exactly on the plane through axis 1 normal to x1.
///  - elbow: the sign of z2 · ((o3 − o2) × (w − o3)): the sense in which the forearm (from axis 3
///    to the wrist centre w) turns from the upper arm (axis 2 to axis 3), about axis 2.
///  - wrist: the sign of z5 · (z4 × z6): the sense in which axis 6 is bent away from axis 4, about
///    axis 5; 0 at the wrist singularity (axes 4 and 6 aligned).
/// Two solutions of the same pose on different configurations differ in at least one flag; a flag
/// changes only where its expression passes 0 (a singular configuration of spherical-wrist arms).

#include <string>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot {

struct ArmConfiguration {
  int shoulder = 0, elbow = 0, wrist = 0;  ///< +1, −1, or 0 exactly at the flag's boundary
  /// "s+e+w-" style: one letter and sign per flag ("0" at a boundary).
  std::string to_string() const;
  bool operator==(const ArmConfiguration&) const = default;
};

/// The configuration of joints `q_deg` on `model`. ~3 FK evaluations' cost; no allocation.
ArmConfiguration arm_configuration(const MdhModel& model, const JointVector& q_deg);

}  // namespace errfield::robot
