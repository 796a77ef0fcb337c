#pragma once
/// Import of a robot's nominal kinematics from a URDF file into an MdhModel (`errfield import-urdf`).
///
/// Three steps, usable separately:
///  1. read_urdf_chain / parse_urdf_chain: parse the URDF (urdfdom, Debian liburdfdom-dev) and take
///     the joints on the path base link -> tip link, in mm. Refuses, naming the joint or link, what a
///     6R MD-H model cannot hold: prismatic, continuous, planar or floating joints and mimic joints on
///     the path, a moving joint branching off a link between base and tip, an axis that is not a unit
///     vector, and any number of revolute joints other than six. Also refuses what is no model at
///     all: a file over kMaxUrdfBytes or nested deeper than kMaxUrdfDepth (before parsing), a
///     <!DOCTYPE>, a link that is the child of two joints (not a tree), joint limits beyond
///     kMaxUrdfJointLimit_rad, origin angles beyond kMaxUrdfOriginAngle_rad or not finite, and
///     origin values outside the rule of kMinUrdfNonzeroOrigin.
///  2. mdh_from_urdf_chain: the equivalent modified D-H table (common normals between consecutive
///     joint axes), with what is left over in the model's base and tool transforms. Joint angles map
///     1:1: q_i of the model is the URDF joint position of the i-th revolute joint, in degrees.
///  3. verify_urdf_import: FK of the model against urdf_chain_pose (the URDF chain evaluated as
///     its own product of origin and joint-rotation transforms) at random joint vectors.
///
/// The conversion rules (which frame gets which offset, the Hayati beta for nearly parallel axes)
/// are in docs/robot.md ("Importing a URDF").

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "errfield/robot/mdh_model.hpp"

namespace errfield::robot {

/// One joint on the URDF path from the base link to the tip link, in URDF terms but in mm and deg.
struct UrdfJoint {
  std::string name;
  std::string parent_link, child_link;
  bool revolute = false;  ///< false: a fixed joint (only its origin counts)
  /// Parent link frame <- joint frame (the URDF `<origin xyz rpy>`), translation in mm.
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  /// Unit rotation axis in the joint frame (revolute joints).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double lower_deg = -180.0, upper_deg = 180.0;  ///< joint limits (revolute joints)
};

/// The joints on the path base link -> tip link, base side first.
struct UrdfChain {
  std::string robot_name;  ///< the URDF's <robot name>
  std::string base_link, tip_link;
  std::string source;  ///< file name (or "URDF") for messages
  std::vector<UrdfJoint> joints;
  /// The revolute joints in chain order (joint i of the MD-H model is revolute()[i - 1]).
  std::vector<const UrdfJoint*> revolute() const;
};

/// Input limits of the URDF reader (docs/reliability.md, "Input limits"). A real arm's URDF is a
/// few hundred kB at most and nests elements ~5 deep; the parser (TinyXML via urdfdom) recurses once
/// per level and slows down quadratically with depth, so both are checked before it runs.
inline constexpr std::size_t kMaxUrdfBytes = std::size_t{16} << 20;  ///< 16 MiB per file
inline constexpr int kMaxUrdfDepth = 64;                                ///< element nesting levels
/// Largest |joint limit| accepted, in radians (about 16 turns): beyond it a limit is a stand-in for
/// "unlimited" or a unit mistake, and the sampled verification and planning would be meaningless.
inline constexpr double kMaxUrdfJointLimit_rad = 100.0;
/// Largest |angle| accepted in an <origin rpy="..."> (radians), read from the text before urdfdom
/// turns it into a quaternion (which hides the value: 1e20 rad was accepted as some rotation). The
/// same ~16 turns as the joint limits: a URDF writer produces at most one turn (xacro's ${pi}); a
/// larger value is a unit mistake or garbage, and from ~1e16 rad on the double cannot even hold the
/// angle's remainder modulo 2 pi, so the rotation read would be arbitrary.
inline constexpr double kMaxUrdfOriginAngle_rad = 100.0;
/// An origin coordinate (metres or radians) is 0 or at least this in magnitude, and at most
/// kMaxUrdfOriginOffset_m for xyz. Below 1e-30 a value is neither an exact zero nor physics nor the
/// rounding residue of a printed angle (~1e-17): a corrupted or generated-by-mistake number.
inline constexpr double kMinUrdfNonzeroOrigin = 1e-30;
inline constexpr double kMaxUrdfOriginOffset_m = 1000.0;

/// True when this build can parse URDF files (urdfdom found at configure time).
bool urdf_support_available() noexcept;

/// Parses URDF text and extracts the chain base_link -> tip_link. Throws InputError naming `source`
/// and the joint or link (see the file comment); when urdfdom rejects the file its own messages are
/// in the exception. Without URDF support in the build throws Error saying so.
UrdfChain parse_urdf_chain(const std::string& urdf_xml, const std::string& base_link, const std::string& tip_link,
                           const std::string& source = "URDF");
/// Same, reading the file at `path`.
UrdfChain read_urdf_chain(const std::filesystem::path& path, const std::string& base_link,
                          const std::string& tip_link);

/// Pose of the tip link in the base link frame (mm) for the revolute joint positions `q_deg`
/// (chain order): the product over the path of origin · rotation(axis, q). Independent of MdhModel.
Eigen::Isometry3d urdf_chain_pose(const UrdfChain& chain, const JointVector& q_deg);

/// The MD-H model whose FK equals urdf_chain_pose(chain, q) · tool for every q: world frame = the
/// base link frame, flange = frame 6, model tool = flange <- tip link · `tool`. Limits from the URDF.
/// Named after the URDF robot. Throws ArgumentError unless the chain has six revolute joints.
MdhModel mdh_from_urdf_chain(const UrdfChain& chain, const Eigen::Isometry3d& tool = Eigen::Isometry3d::Identity());

struct UrdfVerification {
  int samples = 0;
  double max_position_mm = 0.0;   ///< largest |p_model - p_urdf| of the tool point
  double max_rotation_rad = 0.0;  ///< largest rotation angle of R_model^T R_urdf
  /// Accepted when max_position_mm <= 1e-9 mm and max_rotation_rad <= 1e-12 rad (1e-9 mm at 1 m).
  bool passed = false;
};

inline constexpr double kUrdfPositionTolerance_mm = 1e-9;
inline constexpr double kUrdfRotationTolerance_rad = 1e-12;

/// Compares forward_kinematics(model, q, tool frame) with urdf_chain_pose(chain, q) · tool at the
/// zero vector and `samples - 1` joint vectors drawn uniformly within the URDF limits.
UrdfVerification verify_urdf_import(const MdhModel& model, const UrdfChain& chain,
                                    const Eigen::Isometry3d& tool = Eigen::Isometry3d::Identity(),
                                    int samples = 1000, std::uint64_t seed = 1);

}  // namespace errfield::robot
