#pragma once
/// Kinematic calibration: identify errors of the MD-H table (and base/tool) from laser-tracker
/// measurements. Use `register_tracker` first when you have positions (it finds the
/// tracker ← robot transform and the reflector offset, 9 parameters), then `calibrate_positions`
/// or, frame-free, `calibrate_distances` (the paper's baseline: distances between robot
/// positions, e.g. to a base point; or distances to fixed points in the cell, whose coordinates
/// are identified with the robot).
///
/// Method (docs/robot.md "Calibration"): Levenberg–Marquardt on the identification Jacobian;
/// identifiability judged on PHYSICALLY scaled columns (lengths in mm, angles in rad times the
/// arm's reach, so every column says how many mm of measurement one mm of parameter moves):
/// parameters with no effect or that are combinations of others are removed automatically, with
/// the reason; from positions, so are those that make the kept set worse conditioned than
/// `max_condition_number`; from distances the rest are all kept and regularized toward nominal
/// (Tikhonov, weight set by `max_condition_number`), and only parameters the data hardly
/// determine at all are removed — so rounding noise in the joints never makes a parameter
/// identifiable; standard errors of the rest;
/// optional IGG3 robust reweighting (SPEC note) against gross outliers. Where consecutive axes are
/// parallel (|alpha_{i-1}| < 1e-6 deg) the Hayati beta of that link is a candidate, as plain MD-H
/// is singular there.
/// Pure functions; the result carries the identified model and a report.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::robot {

/// A tracker reading of the model's tool point at commanded joints, in the measurement frame
/// (the frame the model's base maps into).
struct PositionMeasurement {
  JointVector q_deg;
  Eigen::Vector3d measured_mm;
  /// Which point on the flange was read: 0 is the model's tool point; k >= 1 is flange point k of
  /// the list given to the multi-point overloads (a second or third reflector nest on the same
  /// plate), whose flange-frame position is identified with the robot.
  int flange_point = 0;
};

/// A measured distance from the tool point at `q_a_deg` to a base point: either the tool point at
/// `q_b_deg` (a robot position, `fixed_base` < 0) or fixed point number `fixed_base` of the list
/// passed to calibrate_distances (a point in the cell not carried by the robot, e.g. a nest the
/// tracker measured; `q_b_deg` is then ignored). Frame-free.
struct DistanceMeasurement {
  JointVector q_a_deg;
  JointVector q_b_deg = JointVector::Zero();
  double distance_mm = 0.0;
  int fixed_base = -1;  ///< Index into the fixed base points, or -1 for a robot-position base.
};

/// IGG3 robust weights (Yang): u = |v| / sigma0 with sigma0 = 1.4826 · MAD (distances) or
/// median(|r|) / 1.5382 (3-D position residuals, the Maxwell median); weight 1 for u <= k0,
/// (k0/u)·((k1 − u)/(k1 − k0))² for k0 < u <= k1, 0 beyond.
/// Off by default, chosen by held-out accuracy: on data without gross outliers it gained nothing
/// on simulated data and made real tracker data worse (the largest residuals there are errors the
/// kinematic model cannot represent, not outliers, and down-weighting them biases the fit); with
/// 5 % gross outliers it helps. docs/robot.md ("Robust weights") has the numbers and commands.
struct RobustOptions {
  bool enabled = false;
  double k0 = 1.5;
  double k1 = 3.0;
  int max_rounds = 20;  ///< Reweighting rounds (each a full LM solve).
};

struct CalibrationOptions {
  /// Candidate parameters (indices of the `param` layout). Empty: the default set for the model
  /// (see default_candidates).
  std::vector<int> candidates;
  /// In physical units (mm, rad × reach): a candidate whose column is smaller than this fraction
  /// of the largest column has no effect; one whose column, projected off the columns kept before
  /// it, retains less than this fraction of its norm is redundant.
  double redundancy_tolerance = 1e-6;
  /// Then, while the condition number of the physically scaled Jacobian of the kept parameters
  /// exceeds this, the parameter dominating its weakest direction is removed ("weakly
  /// identifiable"). CalibrationResult::condition_number reports the final value (<= this).
  /// 1e3 removes columns that only joints rounded to 3 or more decimals move (1e-4 of the
  /// largest or less) and, at one constant orientation (the paper's cube), the weak directions
  /// along which parameters would trade off by tens of mm while fitting the data equally well
  /// (at 1e4 the cube's calibration moved link lengths by up to 200 mm). Over well-spread poses
  /// a wrist offset (e.g. link5.theta0, short lever) can sit just above 1e3 and is then removed;
  /// raise the cap for such data.
  /// Distances: no parameter is removed for conditioning alone; every structurally identifiable one
  /// is kept and the fit is regularized toward nominal with the Tikhonov weight
  /// 0.1 · (largest singular value / this)² (CalibrationResult::regularization); parameters of
  /// which less than half is determined under that weight are removed as weakly identifiable.
  /// Removing parameters one by one made the rest absorb what they carried (a KR 16 at one
  /// orientation: tens of mm, held-out 3-D error 1.14x an independent least-squares calibration;
  /// docs/robot.md "Distances: regularized toward nominal"). Both are judged at the initial model,
  /// so the data get the last word: the weakly identifiable parameters are put back, and the weight
  /// divided by 10 (up to 3 times), when an F test on the residual sum of squares says the data ask
  /// for it (F > 10; an arm off by 0.3 deg / 3 mm from nominal).
  double max_condition_number = 1e3;
  /// LM iterations per round. Along a weakly determined direction whose cost is not quadratic LM
  /// converges linearly: a few hundred cheap iterations.
  int max_iterations = 1000;
  double cost_tolerance = 1e-14;  ///< Stop when the relative cost decrease is below this.
  RobustOptions robust;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

/// Identification candidates for a model. Order matters (earlier candidates are kept when a later
/// one is redundant with them): base (if `with_base`), tool translation, then per link alpha, a,
/// theta0, d, and beta where alpha_{i-1} is within 1e-6 deg of 0 or +-180 (parallel or anti-parallel
/// axes).
std::vector<int> default_candidates(const MdhModel& model, bool with_base);

struct ParameterEstimate {
  int index = 0;
  std::string name;
  std::string unit;          ///< "deg" or "mm" (report units).
  double nominal = 0.0;      ///< Value in the initial model (deg / mm; base/tool increments start at 0).
  double increment = 0.0;    ///< Identified change (deg / mm).
  double standard_error = 0.0;  ///< 1-sigma, same unit.
};

struct RemovedParameter {
  int index = 0;
  std::string name;
  std::string reason;  ///< "no effect on the measured quantity" or "redundant with ..."
};

/// A fixed base point identified together with the robot (robot base frame, mm). Coordinates the
/// identifiability analysis removed keep their nominal value, standard error 0, identified false
/// (the reason is in CalibrationResult::removed as "base point K x|y|z").
struct BasePointEstimate {
  Eigen::Vector3d nominal_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d standard_error_mm = Eigen::Vector3d::Zero();  ///< 1-sigma per coordinate.
  bool identified[3] = {false, false, false};
};

/// A further point on the flange (a second reflector nest) identified with the robot: its position in
/// the flange frame (mm). The same fields as a fixed base point: `nominal_mm` is where the fit started.
using FlangePointEstimate = BasePointEstimate;

/// Candidate index of coordinate c (0 x, 1 y, 2 z) of flange point k >= 1 (multi-point position
/// calibration): far above the model's parameters and any fixed base point's.
inline constexpr int kFlangePointCandidateBase = param::kCount + (1 << 20);
inline constexpr int flange_point_candidate(int k, int c) { return kFlangePointCandidateBase + 3 * (k - 1) + c; }

struct ResidualSummary {
  double rms_mm = 0, mean_abs_mm = 0, max_abs_mm = 0;
  std::size_t count = 0;
};

struct CalibrationResult {
  MdhModel model = MdhModel::er20_c10();  ///< The identified model.
  std::vector<ParameterEstimate> parameters;  ///< Identified (kept) parameters.
  std::vector<RemovedParameter> removed;      ///< Candidates removed, with the reason.
  /// Fixed base points (calibrate_distances with fixed points), identified with the robot.
  std::vector<BasePointEstimate> base_points;
  /// Multi-point position calibration: flange points 1.. (index k - 1), identified with the robot
  /// (flange frame, mm). Point 0 is the model's tool point, in `model.tool()`.
  std::vector<FlangePointEstimate> flange_points;
  /// Condition number of the physically scaled identification Jacobian of the identified (kept)
  /// parameters at the initial model, where they were selected. Positions: at most
  /// CalibrationOptions::max_condition_number. Distances: may exceed it, the weak directions being
  /// regularized toward nominal instead (`regularization`).
  double condition_number = 0.0;
  /// Distances: the Tikhonov weight mu (mm² per physical mm², i.e. per mm of length or per
  /// rad × reach of angle) of the penalty mu · Σ increment² toward the initial model,
  /// 0.1 · (largest singular value of the physically scaled Jacobian / max_condition_number)²,
  /// divided by 10 for each relaxation the data asked for (max_condition_number). 0 for positions.
  double regularization = 0.0;
  /// The length (mm) that scales angular parameters for identifiability: Σ(|a| + |d|) + |tool|.
  double reach_mm = 0.0;
  ResidualSummary before, after;  ///< Per measurement: distance residual or 3-D residual norm.
  std::vector<double> weights;    ///< Final IGG3 weight per measurement (1 without robust weights).
  std::size_t rejected = 0;       ///< Measurements with weight 0.
  int iterations = 0;             ///< LM iterations over all rounds.
  int rounds = 0;
  /// Largest change of an IGG3 weight in the last reweighting round (0 without robust weights).
  double weight_change = 0.0;
  /// LM converged in the last round and, with robust weights, the weights settled (changed by
  /// less than 1e-3) within RobustOptions::max_rounds.
  bool converged = false;
  std::string message;
  /// Multi-line human-readable report (parameters, removed ones and why, residuals).
  std::string report() const;
};

/// Tracker registration: base (tracker ← robot base, 6) and tool translation (reflector offset in
/// the flange, 3) of `model` fitted to positions, MD-H table fixed. Starts from a closed-form rigid
/// fit (Horn/Kabsch) of the nominal positions, so any initial base is fine.
CalibrationResult register_tracker(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                   const CalibrationOptions& options = {});

/// Identification from positions in the measurement frame: MD-H + base + tool. The model's base
/// should already map into the measurement frame (register_tracker does that).
CalibrationResult calibrate_positions(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const CalibrationOptions& options = {});

/// Several points on the flange read at the same poses (reflector nests on one plate): measurements
/// with flange_point = k >= 1 are readings of flange point k, which starts at
/// `flange_points_start_mm[k - 1]` (flange frame, mm) and is identified with the rest. One base, one
/// MD-H table, one tool point (point 0) and the further points: the points together see the flange's
/// orientation, which one point cannot. Registration: base 6, tool translation 3 and 3 per further
/// point; the closed-form start uses the readings of point 0 (at least 3). Throws ArgumentError for a
/// measurement naming a point outside the list, InputError for too few readings of point 0.
CalibrationResult register_tracker(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                   const std::vector<Eigen::Vector3d>& flange_points_start_mm,
                                   const CalibrationOptions& options = {});
/// Identification from positions of several flange points (see the register_tracker overload): the
/// default candidates (or options.candidates) plus every further point's coordinates.
CalibrationResult calibrate_positions(const MdhModel& model, const std::vector<PositionMeasurement>& data,
                                      const std::vector<Eigen::Vector3d>& flange_points_start_mm,
                                      const CalibrationOptions& options = {});
/// Identification from distances (pairs of robot positions): MD-H + tool; the base is
/// unobservable from distances and never a candidate. The identified model is re-aligned
/// (a rigid motion of its base) to the initial model's positions at the distinct measured configurations,
/// each counted once.
CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const CalibrationOptions& options = {});

/// Identification from distances to fixed base points (and, optionally, also between robot
/// positions): `fixed_bases_nominal_mm[k]` is the nominal position of fixed point k in the robot
/// base frame (mm); measurements with `fixed_base = k` are |P(q) − B_k| (SPEC eq. 11, dL = n·dP
/// for a fixed B). The coordinates of every B_k are identified with the robot (candidates first,
/// 3 per point; Jacobian columns −nᵀ). Distances are invariant under a common rigid motion of the
/// robot and the points, so the robot parameters that place the robot in the world (on the
/// ER20: link1.alpha, link1.a, link1.theta0, link1.d) are removed as redundant with the point
/// coordinates and keep their nominal values: they define the frame the points are reported in.
/// No re-alignment afterwards (the points pin the frame). Throws InputError for a measurement
/// naming a fixed point outside the list or a non-finite nominal point.
CalibrationResult calibrate_distances(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                      const std::vector<Eigen::Vector3d>& fixed_bases_nominal_mm,
                                      const CalibrationOptions& options = {});

/// Jacobian (rows: measurements, columns: `candidates`) of the predicted distances |Pa − Pb| with
/// respect to model parameters (indices < param::kCount; mm/rad or mm/mm, as
/// identification_jacobian) and fixed base point coordinates (index param::kCount + 3k + c for
/// coordinate c of point k; column −nᵀ, n the unit vector from B_k to the tool point).
Eigen::MatrixXd distance_identification_jacobian(const MdhModel& model, const std::vector<DistanceMeasurement>& data,
                                                const std::vector<Eigen::Vector3d>& fixed_bases_mm,
                                                const std::vector<int>& candidates);

/// Joints for commanding `target` (world frame) on the real robot using an identified model:
/// the target position is corrected by the identified model's predicted error and the pose solved
/// with the nominal model, iterated until the identified model's tool is at the target position
/// (`position_residual_mm` of the result is that remaining gap). Use this rather than IK of the
/// identified model itself: position or distance data leave orientation parameters weakly
/// determined, and full-pose IK of the identified model would follow them.
IkResult compensated_joints(const MdhModel& nominal, const MdhModel& identified, const Eigen::Isometry3d& target,
                            const JointVector& seed_deg, int iterations = 6);

/// compensated_joints for the whole pose: the identified model's tool frame is brought to `target`'s
/// position and orientation (each gap, in position and as a small rotation, taken off the nominal
/// command and solved again). For models whose flange orientation the data determine (three or more
/// points on the flange, a 6-DoF probe); `orientation_residual_rad` of the result holds the angle
/// left (rad), and a gap over 1e-4 mm or 1e-7 rad is max_iterations.
IkResult compensated_pose_joints(const MdhModel& nominal, const MdhModel& identified, const Eigen::Isometry3d& target,
                                 const JointVector& seed_deg, int iterations = 8);

/// IGG3 weight of a standardized residual u >= 0.
double igg3_weight(double u, double k0, double k1);

}  // namespace errfield::robot
