#pragma once
/// A simulated robot and laser tracker, so every errfield method runs without hardware.
///
/// The "true" robot differs from its nominal MdhModel by
///  - geometric deviations of the MD-H table, base and tool (whose best-fit rigid part is
///    absorbed into the base frame, as a measured base frame would absorb it),
///  - joint compliance under gravity and payload: each joint yields by torque / stiffness, with
///    link masses as point masses halfway between consecutive frame origins,
///  - a small periodic transmission error per joint, amplitude · sin(harmonic · q + phase),
///  - an end-of-travel error per joint that sets in beyond an onset angle and grows towards the
///    joint limit (cable and hose drag, a counterbalance spring: EndRangeErrorModel),
///  - repeatability noise at every move (isotropic Gaussian on the position),
/// and a laser tracker measures positions in its own frame with noise growing with range
/// (SPEC section 7). Everything is deterministic for a given seed (SimulationRng).
///
/// The default configuration (SimulatorConfig::paper_default) is tuned so the uncompensated
/// distance error in the paper's cube is of the paper's size and kinematic calibration leaves
/// the paper's residual; docs/robot.md ("Simulator") lists the values and why.
/// Everything here is SIMULATED data; outputs say so.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/random.hpp"

namespace errfield::robot {

/// Geometric deviations of the true robot from the nominal one, in the units of the JSON model:
/// per link (alpha_deg, a_mm, theta0_deg, d_mm, beta_deg), base and tool as xyz (mm) + rpy (deg)
/// increments. Either given explicitly or drawn from the sigmas with the seed.
struct GeometricDeviation {
  std::array<std::array<double, 5>, kJointCount> link{};  ///< alpha_deg, a_mm, theta0_deg, d_mm, beta_deg
  PoseXyzRpy tool{};  ///< Added to the nominal tool: xyz (mm) and rpy (deg).
};

/// Joint compliance under gravity (static, per-joint torsional springs).
struct ComplianceModel {
  std::array<double, kJointCount> stiffness_nm_per_rad{};  ///< k_j; 0 = rigid joint.
  /// Point masses (kg) of links 1..6, placed halfway between the origins of frames i and i+1
  /// (link 6: 50 mm beyond the flange along its z axis).
  std::array<double, kJointCount> link_mass_kg{};
  /// Each link's mass moved off that place by this offset (mm, in the link's own frame i): motors
  /// and counterweights sit off the chain, where a gravity model on the frame origins (a fit's
  /// gravity-load terms) cannot put them (`simulate --mass-offset`). Zero by default.
  std::array<std::array<double, 3>, kJointCount> mass_offset_mm{};
  double payload_kg = 0.0;                             ///< At the tool point.
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.80665};   ///< m/s², in the world frame.
};

/// Periodic transmission error per joint: dq_j = amplitude_j · sin(harmonic_j · q_j + phase_j).
struct TransmissionErrorModel {
  std::array<double, kJointCount> amplitude_deg{};
  std::array<double, kJointCount> harmonic{};  ///< Cycles per joint revolution.
  std::array<double, kJointCount> phase_deg{};
};

/// Joint errors that set in near the ends of a joint's travel — a dress pack or hose that drags
/// the axis, a counterbalance spring — and that a kinematic model cannot express:
/// dq_j = sign(q_j) · error_at_limit_deg_j · ((|q_j| − onset_deg_j) / (limit_j − onset_deg_j))²
/// for |q_j| > onset_deg_j, where limit_j is the nominal joint limit on q_j's side (q_max_deg for
/// q_j > 0, −q_min_deg for q_j < 0). Quadratic, so it starts smoothly (zero slope at the onset):
/// real robot behaviour at the workspace extremes, not an outlier. 0 = none.
struct EndRangeErrorModel {
  std::array<double, kJointCount> onset_deg{};
  std::array<double, kJointCount> error_at_limit_deg{};
};

/// Laser tracker: where it is and how noisy. Per-axis noise sigma at range r (m) is
/// `sigma_constant_mm + sigma_per_m_mm · r`.
struct TrackerModel {
  /// Tracker frame ← world frame (the transform registration has to find).
  Eigen::Isometry3d tracker_from_world = Eigen::Isometry3d::Identity();
  double sigma_constant_mm = 0.005;
  double sigma_per_m_mm = 0.0025;
};

struct SimulatorConfig {
  std::uint64_t seed = 1;
  /// The nominal robot (its tool is the point that is commanded and measured).
  MdhModel nominal = MdhModel::er20_c10();
  GeometricDeviation geometry;
  /// Absorb the best-fit rigid motion of the geometric error into the true base frame (computed
  /// over `absorb_joints_lo/hi`-uniform configurations). Leaves only non-rigid geometric error.
  bool absorb_rigid_part = true;
  /// A tool/reflector offset the nominal robot does not know (mm, in the tool frame), added to the
  /// true tool after the rigid part is absorbed, so it stays whole (`simulate --tool-offset`).
  Eigen::Vector3d tool_offset_mm = Eigen::Vector3d::Zero();
  ComplianceModel compliance;
  TransmissionErrorModel transmission;
  EndRangeErrorModel end_range;
  /// Repeatability: per-axis Gaussian sigma of the position at each move (mm). 0.02 mm per axis
  /// puts 99.7% of moves within ±0.06 mm per axis (the ER20-C10's ±0.06 mm).
  double repeatability_sigma_mm = 0.02;
  TrackerModel tracker;

  /// The defaults errfield's reproduction uses: ER20-C10 with the Table 7 ball as its tool,
  /// deviations, compliance and transmission error tuned as documented in docs/robot.md.
  static SimulatorConfig paper_default();
  /// Reads a simulation JSON (docs/robot.md); missing fields keep paper_default() values. The
  /// nominal robot may be given inline as "robot": {robot description}.
  static SimulatorConfig from_json(const nlohmann::json& j, const std::string& source = "simulation JSON");
  static SimulatorConfig load(const std::string& path);
  nlohmann::json to_json() const;
  /// Throws ArgumentError naming the field for negative stiffness/masses/sigmas.
  void validate() const;
};

/// The simulated robot + tracker. Immutable after construction; the random state lives in the
/// SimulationRng the caller passes, so one robot can serve several independent streams.
class SimulatedRobot {
 public:
  explicit SimulatedRobot(const SimulatorConfig& config);

  const SimulatorConfig& config() const noexcept { return config_; }
  /// The nominal model (what the controller believes).
  const MdhModel& nominal() const noexcept { return config_.nominal; }
  /// The true geometry (nominal + deviations, rigid part absorbed).
  const MdhModel& true_geometry() const noexcept { return true_geometry_; }

  /// Joint deflection (deg) at commanded joints: compliance + transmission error + end-range error.
  JointVector joint_deflection_deg(const JointVector& q_cmd_deg) const;
  /// Where the robot really goes (world frame), without repeatability noise.
  Eigen::Isometry3d true_pose(const JointVector& q_cmd_deg, EndFrame frame = EndFrame::tool) const;
  Eigen::Vector3d true_position(const JointVector& q_cmd_deg) const { return true_pose(q_cmd_deg).translation(); }
  /// One move: true position plus fresh repeatability noise (world frame, mm).
  Eigen::Vector3d move(const JointVector& q_cmd_deg, SimulationRng& rng) const;
  /// A tracker reading of a world point: in the tracker frame, with range-dependent noise.
  Eigen::Vector3d measure(const Eigen::Vector3d& world_mm, SimulationRng& rng) const;
  /// A tracker distance between two world points (each end measured with noise).
  double measure_distance(const Eigen::Vector3d& a_world_mm, const Eigen::Vector3d& b_world_mm,
                          SimulationRng& rng) const;

 private:
  SimulatorConfig config_;
  MdhModel true_geometry_;
};

// ---- the paper's set-up ------------------------------------------------------------------------

/// Table 7 tool (flange ← tool tip) and target ball (flange ← ball centre) as transforms, with the
/// three angles read as this library's rx, ry, rz (fixed-axis XYZ, deg).
Eigen::Isometry3d paper_tool();
Eigen::Isometry3d paper_ball();

/// A cube of targets at one constant orientation (all in the world frame).
struct MeasurementCube {
  Eigen::Vector3d min_corner_mm;
  double size_mm = 500.0;
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();  ///< Tool orientation at every target.
  Eigen::Vector3d center() const { return min_corner_mm + Eigen::Vector3d::Constant(size_mm / 2); }
  /// Grid points with `step_mm` spacing (step must divide size), x fastest then y then z.
  std::vector<Eigen::Vector3d> grid(double step_mm) const;
  /// One uniformly random point per grid cell (cells ordered as grid()).
  std::vector<Eigen::Vector3d> random_per_cell(double step_mm, SimulationRng& rng) const;
  Eigen::Isometry3d pose(const Eigen::Vector3d& p) const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = orientation;
    t.translation() = p;
    return t;
  }
};

/// The paper's 500 mm cube, placed where the ER20-C10 reaches it at tool-down orientation
/// (rx = 180°): x ∈ [750, 1250], y ∈ [−250, 250], z ∈ [350, 850] mm in the robot base frame,
/// for the tool point of paper_tool() or paper_ball(). docs/robot.md says why.
MeasurementCube paper_cube();

/// The base point the default simulation measures distances from: the robot position at the
/// cube's corner (750, −250, 350) — a robot position, so its own error enters (`dL = n·(dP − dP0)`).
Eigen::Vector3d paper_base_point_nominal();

/// The IK solution at the cube's centre (from the standard postures): a seed that keeps every
/// point of the cube on one branch. Check `.ok()`.
IkResult cube_seed(const MdhModel& model, const MeasurementCube& cube);

/// Joints reaching `p` at the cube's orientation from `seed_deg` (use cube_seed's joints).
IkResult solve_cube_pose(const MdhModel& model, const MeasurementCube& cube, const Eigen::Vector3d& p,
                         const JointVector& seed_deg);

}  // namespace errfield::robot
