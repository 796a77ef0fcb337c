#pragma once
/// A 6-joint serial robot described by the modified (Craig) Denavit–Hartenberg convention, with
/// joint limits, a base transform and a tool transform. Use it for everything kinematic: forward
/// and inverse kinematics (kinematics.hpp, inverse_kinematics.hpp), calibration (calibration.hpp)
/// and the simulator (simulator.hpp). The model is immutable after construction and cheap to copy;
/// it precomputes the sines and cosines of its constant angles so FK never calls trig on them.
///
/// Link i (i = 1..6) transform, SPEC eq. 1 extended by Hayati's beta:
///
///     T_{i-1}^{i} = Rx(alpha_{i-1}) · Dx(a_{i-1}) · Ry(beta_i) · Rz(q_i + theta0_i) · Dz(d_i)
///
/// beta_i is 0 in every nominal model, which makes this exactly eq. 1. Calibration uses it where
/// consecutive axes are parallel (alpha_{i-1} = 0), where plain MD-H is singular.
/// The world pose of the tool is `base · T_0^1 ··· T_5^6 · tool` (eqs. 2–3).
///
/// Units at this interface: mm and degrees. The JSON robot description is documented in
/// docs/robot.md.

#include <array>
#include <filesystem>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "errfield/robot/pose.hpp"

namespace errfield::robot {

/// Number of joints every MdhModel has (6R arms).
inline constexpr int kJointCount = 6;

/// Joint angles, degrees, joint 1 first.
using JointVector = Eigen::Matrix<double, kJointCount, 1>;

/// One row of the MD-H table plus the joint's limits. Angles in degrees, lengths in mm.
struct MdhLink {
  double alpha_deg = 0.0;   ///< alpha_{i-1}: twist about x_{i-1}.
  double a_mm = 0.0;        ///< a_{i-1}: length along x_{i-1}.
  double theta0_deg = 0.0;  ///< theta0_i: joint-angle offset about z_i.
  double d_mm = 0.0;        ///< d_i: offset along z_i.
  double beta_deg = 0.0;    ///< Hayati beta_i: rotation about y after Dx(a); 0 nominal.
  double q_min_deg = -180.0;  ///< Lower joint limit.
  double q_max_deg = 180.0;   ///< Upper joint limit.
};

/// Constants of one link precomputed for fast FK (internal use by kinematics; stable layout).
struct MdhLinkConstants {
  Eigen::Matrix3d r_const;  ///< Rx(alpha) · Ry(beta).
  double a_mm;              ///< Translation along x_{i-1}.
  double d_mm;              ///< Translation along z_i.
  double cos_theta0, sin_theta0;
};

class MdhModel {
 public:
  /// Validates and builds a model. Throws ArgumentError naming the link and field when a value is
  /// not finite or a joint's q_min_deg >= q_max_deg, or when base/tool are not rigid transforms.
  MdhModel(std::string name, const std::array<MdhLink, kJointCount>& links,
           const Eigen::Isometry3d& base = Eigen::Isometry3d::Identity(),
           const Eigen::Isometry3d& tool = Eigen::Isometry3d::Identity());

  /// The Efort ER20-C10 of SPEC Table 1 with no tool and the base frame at the robot base.
  /// Joint limits are plausible values for this class of arm, not the manufacturer's datasheet
  /// (docs/robot.md lists them): J1 ±170, J2 [-150, 90], J3 [-80, 180], J4 ±180, J5 ±135, J6 ±360.
  static MdhModel er20_c10();

  /// Reads a JSON robot description (docs/robot.md). `source` names it in error messages.
  /// Throws InputError naming the field ("links[2].a_mm: expected a number, got \"x\"").
  static MdhModel from_json(const nlohmann::json& j, const std::string& source = "robot JSON");
  /// Reads a JSON robot description file; errors name the file.
  static MdhModel load(const std::filesystem::path& path);
  /// The JSON robot description of this model (shortest round-trip numbers; base and tool go
  /// through their xyz-rpy form, so load(save(m)) reproduces them to ~1e-15).
  nlohmann::json to_json() const;
  /// Writes to_json() atomically.
  void save(const std::filesystem::path& path) const;

  const std::string& name() const noexcept { return name_; }
  const std::array<MdhLink, kJointCount>& links() const noexcept { return links_; }
  /// Link i, 0-based (link(0) holds alpha_0, a_0, theta0_1, d_1).
  const MdhLink& link(int i) const { return links_.at(static_cast<std::size_t>(i)); }
  /// World (or measurement) frame ← robot base frame 0, mm.
  const Eigen::Isometry3d& base() const noexcept { return base_; }
  /// Flange frame 6 ← tool frame, mm.
  const Eigen::Isometry3d& tool() const noexcept { return tool_; }
  const MdhLinkConstants& constants(int i) const noexcept { return constants_[static_cast<std::size_t>(i)]; }

  JointVector q_min_deg() const;
  JointVector q_max_deg() const;
  /// True if every joint is within its limits (inclusive, with `slack_deg`).
  bool within_limits(const JointVector& q_deg, double slack_deg = 0.0) const;

  MdhModel with_base(const Eigen::Isometry3d& base) const;
  MdhModel with_tool(const Eigen::Isometry3d& tool) const;
  /// The same robot with its tool point at `point_mm` (flange frame, mm), the tool's rotation kept:
  /// a point on the flange (a reflector, a probe, a located tool) as the model's end point.
  MdhModel with_tool_point(const Eigen::Vector3d& point_mm) const;
  MdhModel with_links(const std::array<MdhLink, kJointCount>& links) const;
  MdhModel with_name(std::string name) const;

 private:
  std::string name_;
  std::array<MdhLink, kJointCount> links_;
  Eigen::Isometry3d base_;
  Eigen::Isometry3d tool_;
  std::array<MdhLinkConstants, kJointCount> constants_;
};

}  // namespace errfield::robot
