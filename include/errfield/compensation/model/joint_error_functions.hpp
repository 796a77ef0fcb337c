#pragma once
/// Per-joint angle-error functions: the part of a robot's remaining error that depends on one
/// joint's angle only — errors that grow toward the end of a joint's travel (a dress pack's drag, a
/// hose, a counterbalance spring), a gear's transmission error, a joint's gain error. A kinematic
/// model cannot express them (its joint offset is a constant) and a kriging field in joint space
/// learns them only where it has samples nearby in all six joints; as functions of one angle each,
/// every measured pose informs them.
///
/// Use it between the kinematic calibration and the field (`fit --joint-functions`, kinematic+
/// kriging): fit_joint_error_functions on the calibration's residuals, subtract, krige the rest;
/// CompensationModel adds the functions back to every prediction.
///
/// Model: joint j's angle error dq_j(q_j) = sum_k c_jk P_k(u_j), k = 1..degree, with P_k the Legendre
/// polynomial of degree k and u_j = 2 (q_j - lo_j) / (hi_j - lo_j) - 1 the joint scaled over the
/// fitted joints' range (clamped to [-1, 1] beyond it: constant continuation, never a polynomial's
/// growth; the field refuses poses far outside anyway). No constant term: that is the calibration's
/// joint offset. The position error it causes at the tool point is sum_j J_j(q) dq_j, with J_j the
/// linear part of the calibrated model's geometric Jacobian column j (mm/rad) at q.
///
/// Gravity-load terms (optional, `fit --gravity-load`): a joint also yields under the weight of the
/// arm beyond it — a torsional compliance loaded by gravity, which depends on several joints at
/// once, so no function of one angle expresses it. For a point mass m at p, joint j's load is
/// m g · (z_j × (p − o_j)) (z_j, o_j its axis and origin), so its deflection is a sum, over the
/// points that carry the arm's masses, of a coefficient times the lever ĝ · (z_j × (p − o_j)),
/// ĝ = −z of the robot's world frame (a floor-mounted robot's description has z up). The points
/// are the downstream frame origins and the tool point (GravityLoadTerm); each lever is divided by
/// its RMS over the fitted poses, so its coefficient (mrad) is on the polynomials' scale and shares
/// their ridge. A mass between two frame origins is a combination of their two terms.
///
/// Fit: ridge least squares on the coefficients (mrad), the ridge chosen by generalized
/// cross-validation, so that data without such errors leave the functions near zero, plus a
/// physical prior (JointFunctionPrior): a coefficient may have a prior standard deviation of a
/// physically plausible size (by default the gravity terms: 2 mrad), so a combination the measured
/// point barely sees (it turns the flange about that point) cannot grow to hundreds of mrad and move
/// every other point on the flange; where the prior decides, its variance is in the coefficients' covariance. Once the
/// field's variogram is known, `fit` refits them by generalized least squares under its covariance
/// (refit_by_generalized_least_squares).
/// Units: joints deg, coefficients mrad, positions mm, robot frame.

#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield {
class VariogramModel;
}

namespace errfield::compensation {

/// What the functions add at one pose (robot frame): their position error (mm) and the variance per
/// axis (mm²) of their estimation error (zero without a coefficient covariance).
struct JointFunctionPrediction {
  Eigen::Vector3d position_error_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_variance_mm2 = Eigen::Vector3d::Zero();
};

/// The credible range of what a model file may hold (JointErrorFunctions::from_json refuses beyond
/// it, naming the member): a joint error function (its largest value over the fitted range) or a
/// gravity coefficient up to a radian (about 57°; real joint errors are a few mrad), a coefficient
/// variance up to 1e12 mrad² (the ridge leaves a barely-seen coefficient a large variance: about
/// 1e5 mrad² on a 40-pose fit; this bound only refuses what no fit writes), and a gravity term's
/// lever scale (`scale_m`, fit writes the lever's RMS over its poses) from 0.1 mm to 1 km. A
/// hand-edited 1e5 mrad moved the tool 297 mm with status ok; a scale of 1e-300 or a covariance of
/// 1e300 overflowed plan's updates.
inline constexpr double kMaxCredibleAngleErrorMrad = 1000.0;
inline constexpr double kMaxCoefficientVarianceMrad2 = 1e12;
inline constexpr double kMinGravityScaleM = 1e-4;
inline constexpr double kMaxGravityScaleM = 1e3;

/// One gravity-load term: joint `joint`'s deflection proportional to the gravity lever about its
/// axis of the origin of KinematicFrames::frames[frame] (7: the tool point).
struct GravityLoadTerm {
  int joint = 0;             ///< 0-based: the axis is frames[joint + 1]
  int frame = 7;             ///< joint + 2 .. 7: the loaded point
  double scale_m = 1.0;      ///< RMS of the lever over the fitted poses (m); the design uses lever / scale
  double coefficient_mrad = 0.0;
};

/// Gravity lever (m) about joint `joint`'s axis of frames[frame]'s origin: ĝ · (z × (p − o)).
double gravity_lever_m(const robot::KinematicFrames& frames, int joint, int frame);

struct JointErrorFunctions {
  int degree = 0;                    ///< highest Legendre degree (coefficients per joint)
  std::array<double, 6> lo_deg{};    ///< each joint's range over the fitted poses
  std::array<double, 6> hi_deg{};    ///< (lo == hi: no function; the joint did not move, or barely moved the point)
  Eigen::MatrixXd coefficients_mrad; ///< 6 x degree: row j, column k-1 = c_jk
  std::vector<GravityLoadTerm> gravity_terms;  ///< empty: none
  /// Covariance of the coefficients (mrad², parameter_count() square: the polynomials' joint-major
  /// as the design's columns, then the gravity terms in their order),
  /// under the field's covariance of the residuals they were fitted to (refit_by_generalized_least_
  /// squares, or set_coefficient_covariance for the ordinary fit); empty: no variance is added.
  Eigen::MatrixXd coefficient_covariance_mrad2;

  /// Coefficients in all: 6·degree polynomial ones, then one per gravity term.
  Eigen::Index parameter_count() const { return 6 * static_cast<Eigen::Index>(degree) + static_cast<Eigen::Index>(gravity_terms.size()); }
  /// Angle error of each joint at joints `q_deg` (mrad): the polynomials, plus the gravity terms
  /// (which need the robot's frames) when `model` is given.
  Eigen::Matrix<double, 6, 1> angle_error_mrad(const robot::JointVector& q_deg, const robot::MdhModel* model = nullptr) const;
  /// Both of the below from one Jacobian of `model` at q (what a prediction needs). With
  /// `taken_back` (3 x parameter_count(): the rows a field's prediction at q takes back, the
  /// field's weights times the design at its samples), the variance is that of (D - taken_back)
  /// times the coefficients' error: what is left of it after the field's correction.
  JointFunctionPrediction predict(const robot::MdhModel& model, const robot::JointVector& q_deg,
                                  const Eigen::MatrixXd* taken_back = nullptr) const;
  /// The position error they cause at `model`'s tool point (robot frame, mm).
  Eigen::Vector3d position_error_mm(const robot::MdhModel& model, const robot::JointVector& q_deg) const;
  /// The variance (mm², per robot-frame axis) their estimation error adds to a prediction at q:
  /// the diagonal of D cov D', D the 3 x parameter_count() design row block at q. Zero without a covariance.
  Eigen::Vector3d axis_variance_mm2(const robot::MdhModel& model, const robot::JointVector& q_deg) const;
  /// The 3 x parameter_count() block of the design at q: position error (mm) per coefficient (mrad).
  Eigen::MatrixXd design_rows(const robot::KinematicFrames& frames, const robot::JointVector& q_deg) const;
  Eigen::MatrixXd design_rows(const robot::MdhModel& model, const robot::JointVector& q_deg) const;
  /// The design (3 x parameter_count(), mm per mrad) carried from the reflector the functions were
  /// fitted at (`reflector`'s tool point) to the tool point of `at`: each column is a scalar times
  /// one joint's position column at the reflector, so it becomes the same scalar times that joint's
  /// column at the point (a gravity term's load point stays where the fit put it). A column that
  /// vanishes at the reflector (the joint's axis through it) was not fitted and is zero.
  Eigen::MatrixXd design_rows_at_point(const robot::MdhModel& reflector, const robot::MdhModel& at,
                                       const robot::JointVector& q_deg) const;
  /// The largest |dq_j| of the polynomials over each joint's range (mrad), sampled: for people.
  double largest_angle_error_mrad() const;
  /// How large they are over `poses` (angle errors in mrad, gravity terms through `model`'s frames).
  struct Size {
    double largest_mrad = 0.0;  ///< the largest |dq_j| (polynomials + gravity terms)
    int largest_joint = -1;     ///< 0-based joint of it; -1: no pose
    /// The largest cancelling pair: at one pose and joint, a polynomial part and a gravity part of
    /// opposite signs; `cancelling_mrad` is the smaller of the two magnitudes (0: none cancel).
    double cancelling_mrad = 0.0;
    double cancelling_polynomial_mrad = 0.0, cancelling_gravity_mrad = 0.0;
    int cancelling_joint = -1;
  };
  Size size_over(const robot::MdhModel& model, const std::vector<robot::JointVector>& poses_deg) const;

  /// {"degree": K, "lo_deg": [6], "hi_deg": [6], "coefficients_mrad": [[K] x 6],
  ///  "gravity_terms": [{"joint": 1..6, "frame": joint+1..7, "scale_m", "coefficient_mrad"}] (optional),
  ///  "coefficient_covariance_mrad2": [[P] x P] (optional, P = parameter_count())}
  nlohmann::json to_json() const;
  /// Throws InputError naming `source` and the member.
  static JointErrorFunctions from_json(const nlohmann::json& j, const std::string& source);
};

/// The physical prior of the fit: coefficients (mrad) drawn from N(0, sd^2), the penalty
/// noise variance / sd^2 on each (the maximum a posteriori fit). Why these sizes: docs/robot.md
/// "Transfer to another point".
struct JointFunctionPrior {
  /// Per Legendre coefficient; infinite by default (no prior beyond the GCV ridge): on SIMULATED KR 16
  /// data read at three reflectors (60 training poses, seeds 3-6) and at another tool point (60 and 210
  /// poses, seeds 1-3) 3-30 mrad changed no held-out RMS by more than 0.1 %, at the measured point or
  /// 150 mm away (docs/robot.md, "Transfer to another point"); `fit --joint-function-prior` sets one.
  double polynomial_sd_mrad = std::numeric_limits<double>::infinity();
  /// Per gravity term (its RMS deflection over the poses): joints 2-3 of a 20 kg arm yield ~0.7 mrad
  /// at full reach at the realistic preset's 1 mrad/kN·m (the paper's default 0.3-0.4 mrad/kN·m). On
  /// the same data it stopped a runaway term (seed 3: 0.74 -> 0.58 mm 150 mm away, 0.065 -> 0.056 mm
  /// at the measured point), any size from 0.5 to 5 mrad alike, and changed nothing elsewhere.
  double gravity_sd_mrad = 2.0;
  /// A gravity term whose column is within this fraction of the joint-offset columns (its lever
  /// barely varies over the poses: the calibration's joint offset already holds it) is left out.
  double min_identifiable_fraction = 0.1;
  /// Throws ArgumentError for a value <= 0 (sd) or outside [0, 1) (fraction).
  void validate() const;
};

struct JointErrorFunctionFit {
  JointErrorFunctions functions;
  std::vector<Eigen::Vector3d> remaining_mm;  ///< residual - fitted position error, per pose
  double effective_parameters = 0.0;          ///< trace of the ridge hat matrix
  double ridge = 0.0;                         ///< the penalty GCV chose (relative to the largest s^2)
  double rms_before_mm = 0.0, rms_after_mm = 0.0;  ///< 3-D RMS of the residuals and of what remains
  /// sum |leave-one-pose-out residual|^2 / sum |in-sample residual|^2 of the regression (>= 1): how
  /// much the remaining residuals understate a new pose's (KrigingFieldOptions::value_variance_inflation).
  double leave_one_out_inflation = 1.0;
  /// Per pose, how the coefficients move when that pose is left out of the ridge fit (mrad):
  /// beta_-i - beta = -R D_i' (I - H_ii)^-1 r_i (R the ridge inverse, D_i the pose's design rows,
  /// H_ii = D_i R D_i', r_i its residual); exact for the ridge at its chosen penalty. With the
  /// field's leave-one-out weights it gives the leave-one-out of functions and field together
  /// (KrigingFieldOptions::held_out_shift). Empty without a ridge fit.
  std::vector<Eigen::VectorXd> held_out_coefficient_change_mrad;
  double largest_gravity_deflection_mrad = 0.0;  ///< largest |gravity terms' dq_j| over the poses
  Eigen::MatrixXd design;         ///< 3N x parameter_count() (mm per mrad), rows 3i..3i+2 for pose i
  /// (design' design + ridge)^-1, or of the whitened design after refit_by_generalized_least_squares;
  /// empty when no function was fitted
  Eigen::MatrixXd ridge_inverse;
  bool generalized = false;  ///< refitted by generalized least squares (refit_by_generalized_least_squares)
  /// The prior's share of the coefficients' covariance: diag(noise variance x prior penalty), the
  /// middle term R diag(.) R adds (mm^4/mrad^2 for the ordinary fit, whitened units after the GLS
  /// refit); empty without a prior. In a direction the data do not determine the covariance is then
  /// the prior's sd^2, not the (tiny) spread of a shrunken estimate.
  Eigen::VectorXd prior_middle_diagonal;
  /// Gravity terms left out because the data cannot tell them from the joint offsets
  /// (JointFunctionPrior::min_identifiable_fraction), as "joint J frame F".
  std::vector<std::string> undetermined_gravity_terms;
};

/// Sets fit.functions.coefficient_covariance_mrad2 = R F' S F R (R = fit.ridge_inverse, F the
/// design, S the covariance of the residuals: per component, `field_model`'s covariance between the
/// poses' joints with its nugget on the diagonal, centred, P K P with P = I - 11'/n, because the
/// field's ordinary kriging takes a constant per component). The residuals are spatially correlated, so the
/// coefficients vary far more than independent errors would say; the field's variance at a new
/// pose does not contain that, and without it the 95 % region held 90 % of held-out readings
/// (SIMULATED KR 16, docs/robot.md "Joint error functions"). The field corrects part of the
/// functions' error near its samples; CompensationModel::predict_error subtracts what it takes
/// back (predict's `taken_back`).
void set_coefficient_covariance(JointErrorFunctionFit& fit, const std::vector<robot::JointVector>& q_deg,
                                const VariogramModel& field_model);

/// Refits the functions by generalized least squares under `field_model`'s covariance of the
/// residuals (per component, the poses' joints in its metric, its nugget on the diagonal; each
/// component's constant profiled out, as ordinary kriging takes it): whitened by the Cholesky factor
/// of that covariance, the ridge is chosen by GCV as in the first fit. `residual_mm` are the same
/// residuals the first fit saw. Updates the coefficients, remaining_mm, the ridge and sets
/// coefficient_covariance_mrad2 = R F~'F~ R (R the whitened ridge inverse: the GLS estimate's
/// covariance when the field's is right). The leave-one-out inflation stays the first fit's.
/// Returns false, leaving `fit` unchanged, when there is no function to refit or the covariance is
/// not positive definite at the poses. Why: the residuals are spatially correlated, and an ordinary
/// fit lets the functions chase clusters of correlated residuals; on SIMULATED KR 16 the refit took
/// 3-11 % off the held-out RMS at 120-687 poses (docs/robot.md, "Joint error functions").
/// O(N^3) time, N^2 memory (as the field's dense kriging).
bool refit_by_generalized_least_squares(JointErrorFunctionFit& fit, const std::vector<robot::JointVector>& q_deg,
                                        const std::vector<Eigen::Vector3d>& residual_mm, const VariogramModel& field_model,
                                        const JointFunctionPrior& prior = {});

/// Fits the functions to `residual_mm[i]` (robot frame, the calibrated model's residual at joints
/// `q_deg[i]`). Throws ArgumentError for degree < 1 or mismatched sizes; fewer poses than
/// parameters are allowed (the ridge keeps the fit determined). With `gravity_load`, the gravity-load
/// terms of every joint that moves the point, for each downstream frame origin and the tool point
/// whose lever is not negligible (RMS under 2 % of the largest term's: a vertical axis carries
/// none) nor a copy of an earlier point's (coincident frame origins).
JointErrorFunctionFit fit_joint_error_functions(const robot::MdhModel& model, const std::vector<robot::JointVector>& q_deg,
                                                const std::vector<Eigen::Vector3d>& residual_mm, int degree,
                                                bool gravity_load = false, const JointFunctionPrior& prior = {});

}  // namespace errfield::compensation
