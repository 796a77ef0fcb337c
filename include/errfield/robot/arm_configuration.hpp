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
///  - elbow: the sign of z2 · ((o3 − o2) × (o4 − o3)), both vectors projected on the plane normal to
///    z2: the sense in which the forearm (from axis 3 to frame 4's origin o4 - the wrist centre of a
///    spherical wrist) turns from the upper arm (axis 2 to axis 3), about axis 2. For an offset wrist
///    (UR) o4 ends the planar two-link arm that its analytic IK solves, so the flag is UR's elbow
///    choice, the sign of q3.
///  - wrist: the sign of z5 · (z4 × z6): the sense in which axis 6 is bent away from axis 4, about
///    axis 5; 0 at the wrist singularity (axes 4 and 6 aligned).
/// Each expression is taken as the sine of an angle (normalized by the lengths involved; the
/// shoulder's by the wrist centre's distance from frame 1's origin); within kConfigurationBandDeg of
/// its boundary a flag is 0, undetermined: joints that cross a boundary by a fraction of a degree
/// (a compensation near the wrist singularity) have not changed configuration.
/// Two solutions of the same pose on different configurations differ in at least one flag.

#include <optional>
#include <string>
#include <string_view>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot {

/// Half-width (deg) of the band around each flag's boundary where the flag is 0 (undetermined).
inline constexpr double kConfigurationBandDeg = 1.0;

struct ArmConfiguration {
  int shoulder = 0, elbow = 0, wrist = 0;  ///< +1, −1, or 0 within the band around the boundary
  /// "s+e+w-" style: one letter and sign per flag ("0" when undetermined).
  std::string to_string() const;
  bool operator==(const ArmConfiguration&) const = default;
  /// False when some flag is +1 in one and −1 in the other (an undetermined flag matches either):
  /// the two are different solutions, not the same one near a boundary.
  bool compatible_with(const ArmConfiguration& other) const {
    return shoulder * other.shoulder >= 0 && elbow * other.elbow >= 0 && wrist * other.wrist >= 0;
  }
};

/// The configuration a user names, in ArmConfiguration::to_string()'s format with every flag given
/// ("s+e-w+"; `compensate --config`); nothing for any other text (a "0" flag included: a
/// configuration to keep is one side of each boundary).
std::optional<ArmConfiguration> parse_arm_configuration(std::string_view text);

/// The configuration of joints `q_deg` on `model`. ~3 FK evaluations' cost; no allocation.
ArmConfiguration arm_configuration(const MdhModel& model, const JointVector& q_deg);

}  // namespace errfield::robot
