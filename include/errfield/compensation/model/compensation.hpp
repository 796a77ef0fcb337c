#pragma once
/// Compensation of robot targets from a fitted error model: the last step of the pipeline
/// (plan → measure → fit → compensate), SPEC section 6. Use `CompensationModel::compensate` to
/// turn a nominal target into the joints to send: it predicts the robot's error at the target,
/// moves the commanded point against it (`P_cmd = P_n − dP`, eq. 23 for the paper's method),
/// keeps the orientation and solves inverse kinematics seeded at the nominal solution.
///
/// A model has two parts, either of which may be trivial:
///  - the **command model**: the robot::MdhModel IK runs on (the nominal model, or the one identified by
///    kinematic calibration);
///  - an **error field**: the predicted remaining position error dP (robot frame, mm) at a nominal
///    target, from interpolation of measured errors (grid IDW of distance or position errors,
///    kriging of distance errors or error vectors, in task or joint space).
/// The methods of `errfield fit` are combinations of the two (see CompensationMethod).
///
/// Frames and units: positions in the robot's world frame (the robot::MdhModel's base frame), mm; joints
/// in degrees; the target point is the model's tool point.
/// Thread safety: models are immutable after construction; compensate() may run concurrently.

#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "errfield/compensation/model/calibration_leverage.hpp"
#include "errfield/compensation/model/flange_error_covariance.hpp"
#include "errfield/compensation/model/flange_rotation.hpp"
#include "errfield/compensation/model/joint_error_functions.hpp"
#include "errfield/compensation/model/registration.hpp"
#include "errfield/compensation/model/tool_point_correction.hpp"
#include "errfield/robot/inverse_kinematics.hpp"
#include "errfield/robot/mdh_model.hpp"

namespace errfield::compensation {

/// The methods of `errfield fit` / Table 6, named as on the command line.
enum class CompensationMethod {
  none,              ///< "none": nominal IK, no correction
  kinematic,         ///< "kinematic": IK on the calibrated model (distance model, IGG3)
  position_idw,      ///< "position-idw": 8-vertex IDW of registered 3-D position errors
  distance_idw,      ///< "distance-idw": the paper's method (8-vertex IDW of distance errors, eqs. 19–23)
  distance_kriging,  ///< "distance-kriging": kriging of distance errors, projected as eq. 23
  vector_kriging,    ///< "vector-kriging": kriging of 3-D error vectors (from positions or ≥3 base points)
  kinematic_kriging, ///< "kinematic+kriging": calibrated model, then kriging of its residual errors
};

/// Command-line name of a method ("distance-idw", ...).
std::string_view method_name(CompensationMethod method);
/// Inverse of method_name; throws ArgumentError listing the known names.
CompensationMethod method_from_name(std::string_view name);
/// Every method, in Table 6 order.
std::vector<CompensationMethod> all_methods();

/// What an error field predicts at one nominal target.
struct ErrorPrediction {
  /// Predicted position error dP = P' − P of the robot at the target (robot frame, mm); the
  /// correction applied is −dP. For distance methods this is dL · m (eq. 23), radial only.
  Eigen::Vector3d position_error_mm = Eigen::Vector3d::Zero();
  /// Predicted distance error to the base point (mm), for distance-based fields; NaN otherwise.
  double distance_error_mm = std::numeric_limits<double>::quiet_NaN();
  /// Field variance (mm²): the kriging variance of the predicted error itself (distance error, or
  /// the sum over the three components for vector fields), without measurement noise; NaN when the
  /// method has none (IDW). The `var_field_mm2` column.
  double variance_mm2 = std::numeric_limits<double>::quiet_NaN();
  /// Variance (mm²) that one new reading adds to the same quantity: the fitted nugget when the field
  /// treats it as measurement error (tracker noise and repeatability; for vector fields the sum of
  /// the three components' nuggets), 0 when the nugget is micro-scale variation (then it is part of
  /// variance_mm2); NaN without a variance.
  double noise_variance_mm2 = std::numeric_limits<double>::quiet_NaN();
  /// Vector fields: the predictive variance of a new reading per robot-frame axis x, y, z (mm²),
  /// field plus nugget; what r95_mm and p_inside are computed from (error_ball.hpp). NaN otherwise.
  Eigen::Vector3d axis_variance_mm2 = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// Variance of a new reading of the predicted quantity (mm²): variance_mm2 + noise_variance_mm2.
  /// The `var_mm2` column of predict, compensate and validate.
  double predictive_variance_mm2() const { return variance_mm2 + noise_variance_mm2; }
  /// False when the target lies outside the modelled region (then nothing is extrapolated:
  /// position_error_mm is zero and compensate() refuses the target).
  bool inside_region = true;
  /// False when the prediction lies far beyond the range of errors the model was fitted on
  /// (CredibleRange): compensate() and predict refuse it (status not-credible).
  bool credible = true;
  /// False when the point predicted is so far from the reflector the model was measured with that
  /// the flange's orientation error, which one reflector cannot observe, would dominate
  /// (OrientationPrior::max_lever_mm): compensate() and predict refuse it (status orientation-unknown).
  bool orientation_supported = true;
  /// The part of variance_mm2 (and of axis_variance_mm2's sum) that is the unobservable orientation
  /// residual of the flange times the lever from the reflector (OrientationPrior); 0 at the reflector.
  double orientation_variance_mm2 = 0.0;
  /// False when the pose lies beyond what the kinematic calibration's data determine
  /// (calibration_leverage.hpp: its leverage over kMaxCalibrationLeverageRatio times the largest
  /// training pose's): predict, validate and compensate refuse it (status calibration-extrapolated).
  bool calibration_supported = true;
  /// The pose's calibration leverage over the largest training pose's; NaN for models without one.
  double calibration_leverage_ratio = std::numeric_limits<double>::quiet_NaN();
};

/// What one reflector's data say about the orientation error of the flange, which they cannot observe:
/// a prior on the flange's orientation residual (a small rotation w, isotropic, sigma_rad per axis),
/// so that a point at lever L (mm) from the reflector gets the covariance
/// sigma² (|L|² I − L Lᵀ) (w × L) added to its predicted error, and a lever beyond which the model
/// refuses instead (docs/robot.md, "Tool points and orientation", says how both are chosen).
struct OrientationPrior {
  /// Per-axis standard deviation of the orientation residual (rad); NaN when the model has no
  /// residuals to scale it from (no vector field): then nothing is added and nothing refused.
  double sigma_rad = std::numeric_limits<double>::quiet_NaN();
  /// The part of sigma_rad from the model's residuals (wrist angle errors of equal size that would
  /// leave the residual RMS at the reflector); sigma_rad adds the floor kOrientationPriorFloorRad.
  double data_sigma_rad = std::numeric_limits<double>::quiet_NaN();
  /// Rows whose working point is further than this from the reflector (mm) are refused
  /// (orientation-unknown): the lever at which the orientation term's RMS, sqrt(2) sigma L, is
  /// kMaxLeverResidualRatio x residual_rms_mm, the error the model corrects at the reflector;
  /// infinite without a prior.
  double max_lever_mm = std::numeric_limits<double>::infinity();
  /// RMS of the kinematic residuals at the reflector the prior is scaled from (mm), and how many.
  double residual_rms_mm = std::numeric_limits<double>::quiet_NaN();
  std::size_t samples = 0;
  bool known() const { return std::isfinite(sigma_rad); }
};

/// The flange's orientation residual as measured by a model fitted to several points on the flange
/// (FitOptions::tool_reflector): the other points' training readings against the model's prediction
/// at each (its own point's field and functions carried to them) leave what the orientation
/// residual w moves them by, w x L, plus their noise; so do the readings locate-tool located a point
/// from. Per-axis sd of w (rad), from how many readings, and whether the floor
/// kOrientationPriorFloorRad is added (the points measured lie on one line: a rotation about it
/// escapes them).
struct MeasuredOrientation {
  double sigma_rad = 0.0;
  std::size_t readings = 0;
  bool add_floor = true;
};

/// The floor of OrientationPrior::sigma_rad (rad): orientation errors of the flange that leave no
/// position error at the reflector at all (a rotation about the axis through it, the mounting of a
/// tool) are not seen in the residuals; 0.1 mrad is a tool flange's typical angular tolerance
/// (docs/robot.md, "Tool points and orientation").
inline constexpr double kOrientationPriorFloorRad = 1e-4;
/// Per-axis sd (rad) of the flange's constant orientation error a one-point model cannot identify
/// (rotations about axes through its reflector, which the calibration leaves at nominal), added to
/// OrientationPrior::sigma_rad unless the orientation was measured (several points, or locate-tool's
/// readings at the point, which absorb the constant part). 2 mrad: a reflector-1 model's kinematic
/// part missed real readings 150 mm away by 0.39 mm (issue 34: 1.8 mrad per axis as w x L), and the
/// constant part on SIMULATED KR 16 data was 0.37 and 0.51 mm at 150 mm (1.7 and 2.4 mrad;
/// docs/robot.md, "Tool points and orientation").
inline constexpr double kUnlocatedOrientationRad = 2e-3;
/// OrientationPrior::max_lever_mm: the lever at which the orientation term's RMS is this many times
/// the RMS of the residual the model corrects at the reflector (docs/robot.md).
inline constexpr double kMaxLeverResidualRatio = 2.0;
/// A point on the flange closer than this (mm) to a labelled point with a field of its own takes
/// that field (LabelledPoint::field): a located tool's position scatters by ~0.05 mm around the
/// point it is, and the rigid combination would trade the point's own field for its neighbours'.
inline constexpr double kSameFlangePointMm = 1.0;
/// Reflector and tool point closer than this (mm, flange frame) are one point as far as the data
/// can tell: the tool point compensate aims is the reflector as identified, which corrects the tool's
/// own error (a robot JSON tool a few mm off, a ball's centre). Further apart they are two points:
/// compensate aims the robot JSON's tool on the calibrated flange, and fit warns what that costs.
inline constexpr double kReflectorAtToolMm = 10.0;
/// `--tool`: a tool point further than this from the flange origin (mm) is refused as a typo (metres
/// for mm, a wrong column): no robot tool is 2 m long.
inline constexpr double kMaxToolPointMm = 2000.0;

/// The range of errors a model's data showed, against which a prediction is judged credible:
/// |prediction − center| <= radius_mm, with center the mean of the fitted errors (the distance error
/// for distance fields, the 3-D error vector otherwise) and radius_mm = 2 × the largest distance of a
/// fitted error from that mean (+ 1 nm, so that a constant field still predicts its own value).
/// A predictor that forms convex combinations of the data stays within 1 ×; kriging's negative
/// weights overshoot a little; 2 × leaves room for that and nothing more.
struct CredibleRange {
  std::vector<double> center_mm;  ///< 1 value (distance fields) or 3 (vector fields)
  double radius_mm = 0.0;
  /// True if `prediction` is within the range (a NaN prediction is not).
  bool contains(const ErrorPrediction& prediction) const;
  /// From fitted errors: one row per sample, 1 or 3 columns.
  static CredibleRange of(const Eigen::MatrixXd& errors_mm);
};

/// The spatial part of a compensation model. Implementations: distance_idw_field, ...
class ErrorField {
 public:
  virtual ~ErrorField() = default;
  /// Prediction at a nominal target position `p_mm` reached with nominal joints `q_deg`.
  virtual ErrorPrediction predict(const Eigen::Vector3d& p_mm, const robot::JointVector& q_deg) const = 0;
  /// JSON description (see docs/data-formats.md, "model JSON").
  virtual nlohmann::json to_json() const = 0;
  /// One line for people ("distance IDW on x [..] ... base point (..)").
  virtual std::string describe() const = 0;
  /// predict(), and the weight each sample has in that prediction, in the order of sample_joints(),
  /// for fields whose prediction is a weighted sum of their samples' values (kriging); `weights` is
  /// left empty by the others and where the field does not predict.
  virtual ErrorPrediction predict_with_weights(const Eigen::Vector3d& p_mm, const robot::JointVector& q_deg,
                                               std::vector<double>& weights) const {
    weights.clear();
    return predict(p_mm, q_deg);
  }
  /// predict() (with `weights`: predict_with_weights()) at each (p_mm[i], q_deg[i]); kriging fields
  /// solve a batch of locations in one pass over their factor, much faster than one call per location.
  virtual std::vector<ErrorPrediction> predict_many(std::span<const Eigen::Vector3d> p_mm,
                                                    std::span<const robot::JointVector> q_deg,
                                                    std::vector<std::vector<double>>* weights) const {
    std::vector<ErrorPrediction> out;
    out.reserve(p_mm.size());
    if (weights) weights->assign(p_mm.size(), {});
    for (std::size_t i = 0; i < p_mm.size(); ++i)
      out.push_back(weights ? predict_with_weights(p_mm[i], q_deg[i], (*weights)[i]) : predict(p_mm[i], q_deg[i]));
    return out;
  }
  /// The joints of the samples predict_with_weights() weighs; empty for fields without weights.
  virtual std::vector<robot::JointVector> sample_joints() const { return {}; }
};

/// The result of compensating one target.
struct CompensatedTarget {
  robot::JointVector q_nominal_deg = robot::JointVector::Zero();  ///< nominal IK solution of the target
  ErrorPrediction prediction;                        ///< the field's prediction (zero if no field)
  Eigen::Vector3d command_position_mm = Eigen::Vector3d::Zero();  ///< P_cmd = P_n − dP
  robot::JointVector q_command_deg = robot::JointVector::Zero();   ///< joints to send (IK of the command model)
  robot::IkStatus ik_status = robot::IkStatus::converged;          ///< of the command IK (nominal IK if that failed)
  double ik_residual_mm = 0.0;
  /// Probability that a new reading's error lies within the tolerance, under the predictive
  /// distribution (field variance plus nugget): for vector fields P(|e| <= tol) of the 3-D error
  /// (error_ball.hpp), for distance fields P(|e| <= tol) of the distance error; NaN without a variance.
  double p_within_tolerance = std::numeric_limits<double>::quiet_NaN();
  /// The robot's whole predicted position error of the tool point at the nominal joints (robot frame,
  /// mm): calibration (the calibrated tool point's FK minus the nominal FK) plus the field. The
  /// correction is its negative. For methods without calibration it equals prediction.position_error_mm.
  /// NaN where nothing was predicted (outside the region, not credible, nominal IK failed).
  Eigen::Vector3d total_error_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// How far the compensated joints move the tool point from where the nominal joints put it, by the
  /// nominal model's FK: |FK(q_command) − FK(q_nominal)| (mm). What the robot will actually do
  /// differently; NaN when the command IK failed.
  double move_mm = std::numeric_limits<double>::quiet_NaN();
  /// Models that predict the flange's orientation (predict_rotation: three or more points on the
  /// flange, a 6-DoF probe): the field's predicted rotation at the nominal joints, and the whole
  /// orientation error (robot frame, rad: the calibrated tool frame against the nominal one, plus the
  /// field's). The joints then correct the orientation too (the whole pose: compensated_pose_joints).
  std::optional<RotationPrediction> rotation;
  Eigen::Vector3d total_rotation_error_rad = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// True when the target is inside the modelled region, the prediction is credible, the tool point
  /// is within the lever the model's orientation supports and both IK solves converged.
  bool ok() const {
    return prediction.inside_region && prediction.credible && prediction.orientation_supported &&
           prediction.calibration_supported &&
           ik_status == robot::IkStatus::converged;
  }
};

class CompensationModel {
 public:
  /// `command_model` is what IK runs on; `field` may be null (none, kinematic).
  CompensationModel(CompensationMethod method, robot::MdhModel command_model, std::shared_ptr<const ErrorField> field);

  CompensationMethod method() const noexcept { return method_; }
  const robot::MdhModel& command_model() const noexcept { return command_model_; }
  const ErrorField* field() const noexcept { return field_.get(); }

  /// The tracker ↔ robot registration of the training data (fit stores it when the data have
  /// tracker positions): validate and predict map tracker readings with it.
  const std::optional<compensation::Registration>& registration() const noexcept { return registration_; }
  /// The registration of the same training readings onto the nominal robot's FK (what `fit --method
  /// none` stores): validate's "before" maps held-out readings with it, so the uncompensated robot
  /// is scored in its own best frame, not in the calibrated model's. Empty in files written before
  /// it was stored, and for data without tracker positions.
  const std::optional<compensation::Registration>& nominal_registration() const noexcept { return nominal_registration_; }
  /// The nominal robot the model was fitted with (where it differs from command_model: the kinematic
  /// methods); the field is evaluated at this robot's FK of the joints.
  const robot::MdhModel& nominal_model() const noexcept { return nominal_model_ ? *nominal_model_ : command_model_; }
  bool has_nominal_model() const noexcept { return nominal_model_.has_value(); }
  /// Joints of the training rows: the branch pose targets are solved on (compensate).
  const std::vector<robot::JointVector>& data_joints() const noexcept { return data_joints_; }
  /// Range of the fitted errors (set from the field's own values at construction); empty when the
  /// model has no field.
  const std::optional<CredibleRange>& credible_range() const noexcept { return credible_; }

  /// The point names of the training rows `fit` excluded as gross outliers (FitOptions::outlier_limit),
  /// in row order; written to the model file in full ("excluded_rows").
  const std::vector<std::string>& excluded_rows() const noexcept { return excluded_rows_; }
  /// What fit used and why, one sentence each (the notes fit prints), written as "notes".
  const std::vector<std::string>& notes() const noexcept { return notes_; }
  CompensationModel with_excluded_rows(std::vector<std::string> points) const;
  /// Models fitted to several points on the flange: the orientation residual they measured, which
  /// orientation_prior() then uses instead of reading it off the residuals at one point
  /// ("orientation_residual" in the model file).
  CompensationModel with_measured_orientation(std::optional<MeasuredOrientation> m) const;
  /// Models fitted to several points on the flange: each label's located position (calibrated flange
  /// frame, mm), the model's own first ("flange_points" in the model file); validate scores a label's
  /// readings at its point.
  struct LabelledPoint {
    std::string label;
    Eigen::Vector3d position_mm;
    /// The kriged residual of this point's own readings (after the calibration and the joint error
    /// functions at the point), with the own point's variogram; null for the own point (field())
    /// and in files written before session 20. With two or more points holding a field, a point
    /// between them is predicted from the flange's rigid motion their fields imply
    /// (predict_error_at).
    std::shared_ptr<const ErrorField> field;
    /// The point on the nominal robot's flange (mm): where the nominal registration
    /// (nominal_registration()) puts its training readings, on average, in the nominal FK's flange
    /// frame. validate's "before" orientation takes the points there, so the uncompensated robot is
    /// scored with its own best mounting of them, as its positions are in its own registration.
    /// Empty in files written before session 21.
    std::optional<Eigen::Vector3d> nominal_mm;
  };
  CompensationModel with_flange_points(std::vector<LabelledPoint> points) const;
  const std::vector<LabelledPoint>& flange_points() const noexcept { return flange_points_; }
  const std::optional<MeasuredOrientation>& measured_orientation() const noexcept { return measured_orientation_; }
  CompensationModel with_notes(std::vector<std::string> notes) const;
  /// Models with fields at three or more points on the flange that do not lie on one line (the own
  /// point and LabelledPoint::field): the flange's orientation error they imply at joints `q_deg`
  /// (flange_rotation.hpp), each point predicted as predict_error_at predicts it; empty for other
  /// models. Its covariance is the points' predictive variances combined as independent, times
  /// rotation_calibration()'s scale (1 without one).
  std::optional<RotationPrediction> predict_rotation(const robot::JointVector& q_deg) const;
  /// The points predict_rotation combines (flange frame, mm: the own point first) and their fields.
  struct FieldedPoint {
    Eigen::Vector3d position_mm;
    const ErrorField* field;
  };
  std::vector<FieldedPoint> fielded_points() const;
  /// How the independent combination of predict_rotation was scaled to the fields' leave-one-out
  /// ("rotation_calibration" in the model file; fit sets it).
  CompensationModel with_rotation_calibration(std::optional<RotationCalibration> c) const;
  const std::optional<RotationCalibration>& rotation_calibration() const noexcept { return rotation_calibration_; }
  /// How alike the fields' errors are at their points, for a point predicted from their
  /// combination ("flange_error_covariance" in the model file; fit sets it for two or more fielded
  /// points). Without one the combination's variance is the sum of their standard deviations.
  CompensationModel with_flange_error_covariance(std::optional<FlangeErrorCovariance> c) const;
  const std::optional<FlangeErrorCovariance>& flange_error_covariance() const noexcept { return flange_error_covariance_; }
  /// The kriged residual of a located point's own readings (tool_point_correction.hpp; `locate-tool`
  /// sets it, "tool_point_correction" in the model file): added where a point within
  /// kSameFlangePointMm of its point is predicted, its kriging variance in place of the orientation
  /// term there.
  CompensationModel with_tool_point_correction(std::shared_ptr<const ToolPointCorrection> c) const;
  const std::shared_ptr<const ToolPointCorrection>& tool_point_correction() const noexcept { return tool_point_correction_; }
  /// Calibrated models fitted from positions: the calibration's leverage, which refuses poses
  /// outside what its data determine ("calibration_leverage" in the model file; empty in older files).
  CompensationModel with_calibration_leverage(std::optional<CalibrationLeverage> leverage) const;
  const std::optional<CalibrationLeverage>& calibration_leverage() const noexcept { return calibration_leverage_; }
  CompensationModel with_registration(std::optional<compensation::Registration> r) const;
  CompensationModel with_nominal_registration(std::optional<compensation::Registration> r) const;
  CompensationModel with_nominal_model(robot::MdhModel nominal) const;
  CompensationModel with_data_joints(std::vector<robot::JointVector> q_deg) const;
  CompensationModel with_credible_range(std::optional<CredibleRange> range) const;
  /// Calibrated models fitted from positions: the point compensate aims (flange frame, mm: the robot
  /// JSON's tool, or the reflector when the two are one point, model_fitting.hpp kReflectorAtToolMm)
  /// and the reflector the data measured (the command model's tool: what predict and validate
  /// score). Empty in other models and older files: then the command model's tool is aimed.
  const std::optional<Eigen::Vector3d>& tool_point_mm() const noexcept { return tool_point_; }
  const std::optional<Eigen::Vector3d>& reflector_mm() const noexcept { return reflector_; }
  CompensationModel with_tool_point(std::optional<Eigen::Vector3d> tool_point_mm,
                                    std::optional<Eigen::Vector3d> reflector_mm) const;
  /// kinematic+kriging fitted with per-joint angle-error functions (fit --joint-functions): they are
  /// evaluated through the command model's Jacobian and added to the field's prediction.
  const std::optional<JointErrorFunctions>& joint_error_functions() const noexcept { return joint_functions_; }
  CompensationModel with_joint_error_functions(std::optional<JointErrorFunctions> functions) const;
  /// The working tool (flange frame: translation mm, rotation) predict, validate and compensate use
  /// instead of the measured reflector: set by `--tool` for one run, or stored by `errfield
  /// locate-tool` ("working_tool"). Empty: predict and validate score the reflector, compensate aims
  /// tool_point_mm(). Its lever from the reflector brings in the orientation term (OrientationPrior).
  const std::optional<Eigen::Isometry3d>& working_tool() const noexcept { return working_tool_; }
  /// Sets the working tool as given (`--tool`, `--reflector`): not located by readings of it.
  CompensationModel with_working_tool(std::optional<Eigen::Isometry3d> tool) const;
  /// Sets the working tool `errfield locate-tool` located from readings of it ("working_tool_located"
  /// in the file): its lever's orientation was measured there, whatever else the model keeps.
  CompensationModel with_located_working_tool(const Eigen::Isometry3d& tool) const;
  bool working_tool_located() const noexcept { return working_tool_located_; }
  /// A tool given in the robot description's flange frame (`--tool`), in the calibrated model's: moved
  /// by the calibration's correction of the reflector (measured_point_mm() − the nominal robot's tool)
  /// when the two are one point (closer than kReflectorAtToolMm), since the flange it corrects carries
  /// every point; unchanged otherwise and for models without a stored nominal robot.
  Eigen::Isometry3d tool_in_model_frame(const Eigen::Isometry3d& tool_in_robot_description) const;
  /// The inverse of tool_in_model_frame (for printing a located tool as `--tool` takes it).
  Eigen::Isometry3d tool_in_robot_frame(const Eigen::Isometry3d& tool_in_model) const;
  /// The reflector the data measured (flange frame, mm): the command model's tool.
  Eigen::Vector3d measured_point_mm() const { return command_model_.tool().translation(); }
  /// The model compensate aims with: the command model, with its tool set to working_tool() or else
  /// its tool translation set to tool_point_mm() where the model has one.
  robot::MdhModel aimed_model() const;
  /// The model predict and validate score: the command model with working_tool() where set, else
  /// the command model (the reflector).
  robot::MdhModel scored_model() const;
  /// The prior on the flange's orientation residual (computed once from the field's samples).
  const OrientationPrior& orientation_prior() const;

  /// The field's prediction at joints `q_deg` (evaluated at nominal_model()'s FK), with the credible
  /// range applied (to the field's part), plus the joint error functions where the model has them;
  /// zero prediction, inside the region, when the model has no field.
  ErrorPrediction predict_error(const robot::JointVector& q_deg) const;
  /// Same, for the point `at` (a command model whose tool is that point, e.g. aimed_model()): the joint
  /// error functions act through its Jacobian and the orientation term uses its lever from
  /// measured_point_mm(). predict_error(q) is predict_error_at(q, scored_model()).
  /// With fields at several points on the flange (LabelledPoint::field): at a point within
  /// kSameFlangePointMm of one of them, that point's field; elsewhere the flange's small rigid motion
  /// (a translation and a rotation) fitted by least squares to the fields' predictions at their points,
  /// carried to the point, with the fields' variances combined as if fully correlated (an upper
  /// bound) and, where the points lie on one line, the prior on the rotation about it.
  ErrorPrediction predict_error_at(const robot::JointVector& q_deg, const robot::MdhModel& at) const;
  /// predict_error_at(q_deg[i], at[i]) for every i, the field's kriging solves at the model's own
  /// point batched: one pass over the field's factor per batch of rows instead of one per row (a
  /// fit's check of 3,882 probe readings against a 1,941-sample field: 18 s one by one).
  std::vector<ErrorPrediction> predict_errors_at(std::span<const robot::JointVector> q_deg,
                                                 std::span<const robot::MdhModel> at) const;
  /// The joint error functions' position error at the point `at` (a command model whose tool is that
  /// point), zero without functions: what fit takes from a further point's readings before kriging them.
  Eigen::Vector3d joint_function_error_at(const robot::JointVector& q_deg, const robot::MdhModel& at) const;

  /// The robot's whole predicted error of the tool point at nominal joints `q_deg` (CompensatedTarget::
  /// total_error_mm: calibration + field), with `nominal_model` giving the nominal tool point; NaN
  /// outside the field's region or beyond its credible range.
  Eigen::Vector3d total_error(const robot::MdhModel& nominal_model, const robot::JointVector& q_deg) const;
  /// The largest |total_error| over the training joints (data_joints()), with the robot the model was
  /// fitted with (nominal_model()), not a caller's: a wrong --robot must not raise its own ceiling.
  /// 0 without training joints. What `compensate --max-correction` scales its default from.
  double largest_training_correction_mm() const;

  /// Compensates a target pose (robot frame, tool point). `nominal_model` gives the nominal joints
  /// (IK seeded at `seed_deg`); the field is evaluated there; the command is solved on
  /// command_model() seeded at the nominal joints. `tolerance_mm` > 0 feeds p_within_tolerance.
  /// Never throws for numerical outcomes: a failed IK or a target outside the region shows in the
  /// result (ok() false; then q_command_deg = q_nominal_deg).
  CompensatedTarget compensate(const robot::MdhModel& nominal_model, const Eigen::Isometry3d& target,
                               const robot::JointVector& seed_deg, double tolerance_mm = 0.25,
                               const robot::IkOptions& ik = {}) const;

  /// Same, from nominal joints already known (the target is their nominal FK).
  CompensatedTarget compensate_joints(const robot::MdhModel& nominal_model, const robot::JointVector& q_nominal_deg,
                                      double tolerance_mm = 0.25, const robot::IkOptions& ik = {}) const;

  /// JSON form: {"format":"errfield-compensation-model","version":1,"method":...,
  /// "command_model":{robot JSON},"field":{...}|null} plus, when present, "nominal_model",
  /// "registration" (registration.hpp), "nominal_registration" (same form), "data_joints_deg" [N][6] and "credible_range"
  /// {"center_mm": [1 or 3], "radius_mm"}, and what fit noted: "notes" and "excluded_rows" (arrays
  /// of strings; informative, ignored by every step that reads the model).
  nlohmann::json to_json() const;
  /// Reads the JSON form; throws InputError naming `source` and the field.
  static CompensationModel from_json(const nlohmann::json& j, const std::string& source);

 private:
  CompensationMethod method_;
  robot::MdhModel command_model_;
  std::shared_ptr<const ErrorField> field_;
  std::optional<compensation::Registration> registration_;
  std::optional<compensation::Registration> nominal_registration_;
  std::optional<robot::MdhModel> nominal_model_;
  std::vector<robot::JointVector> data_joints_;
  std::optional<CredibleRange> credible_;
  std::optional<Eigen::Vector3d> tool_point_, reflector_;
  std::optional<JointErrorFunctions> joint_functions_;
  std::optional<Eigen::Isometry3d> working_tool_;
  bool working_tool_located_ = false;
  std::optional<MeasuredOrientation> measured_orientation_;
  std::vector<LabelledPoint> flange_points_;
  std::optional<CalibrationLeverage> calibration_leverage_;
  std::optional<RotationCalibration> rotation_calibration_;
  std::optional<FlangeErrorCovariance> flange_error_covariance_;
  std::shared_ptr<const ToolPointCorrection> tool_point_correction_;
  /// orientation_prior(), computed on first use; a copy (every with_*) starts afresh, since what it
  /// is computed from may change.
  struct LazyOrientationPrior {
    struct State {
      std::once_flag once;
      OrientationPrior value;
    };
    std::shared_ptr<State> state = std::make_shared<State>();
    LazyOrientationPrior() = default;
    LazyOrientationPrior(const LazyOrientationPrior&) : state(std::make_shared<State>()) {}
    LazyOrientationPrior& operator=(const LazyOrientationPrior&) {
      state = std::make_shared<State>();
      return *this;
    }
  };
  LazyOrientationPrior orientation_prior_;
  /// The functions' design at the field's samples (row i: sample i's 3 x P block, column-major):
  /// what the field's prediction takes back from their error near its samples (predict_error);
  /// empty without.
  std::shared_ptr<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> function_rows_at_samples_;
  /// The same for each flange point's own field (LabelledPoint::field), the design carried to that
  /// point; null where the point has no field. Parallel to flange_points_.
  std::vector<std::shared_ptr<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>>
      point_function_rows_;
  /// predict_error_at without the calibration's leverage.
  ErrorPrediction predict_field_at(const robot::JointVector& q_deg, const robot::MdhModel& at) const;
  /// predict_field_at without the tool point correction; `orientation_variance` false leaves the
  /// orientation term's variance out (the correction's measured variance takes its place).
  ErrorPrediction predict_uncorrected_at(const robot::JointVector& q_deg, const robot::MdhModel& at,
                                         bool orientation_variance) const;
  /// predict_uncorrected_at's own-field branch after the field's prediction `p` (with its weights
  /// `w`, or none): the credible range, the joint functions, the orientation term.
  ErrorPrediction completed_at_own_field(ErrorPrediction p, const std::vector<double>& w, const robot::JointVector& q_deg,
                                         const robot::MdhModel& at, bool orientation_variance) const;
  /// The tool point correction that applies at `at`'s tool point, or null.
  const ToolPointCorrection* tool_point_correction_at(const robot::MdhModel& at) const;
  /// `p` with `correction` (null: none) added: predict_field_at after predict_uncorrected_at.
  ErrorPrediction with_tool_point_correction(ErrorPrediction p, const robot::JointVector& q_deg,
                                             const ToolPointCorrection* correction) const;
  /// `p` with the calibration's leverage at `q_deg` judged: predict_error_at after predict_field_at.
  ErrorPrediction with_calibration_leverage(ErrorPrediction p, const robot::JointVector& q_deg) const;
  /// predict_error_at away from every point with a field, when several points hold one.
  ErrorPrediction predict_by_rigid_motion(const robot::JointVector& q_deg, const robot::MdhModel& at,
                                          bool orientation_variance) const;
  /// predict_error_at at a further point with a field of its own.
  ErrorPrediction predict_at_labelled_point(const robot::JointVector& q_deg, const robot::MdhModel& at,
                                            std::size_t point) const;
  /// point_function_rows_ from flange_points_ and joint_functions_.
  void set_point_function_rows();
  std::vector<std::string> excluded_rows_, notes_;
  void set_function_rows_at_samples();
};

/// The nominal robot `nominal` with the model's working tool in the robot description's frame (what
/// the readings' or targets' nominal positions are of); `nominal` itself without a working tool.
robot::MdhModel nominal_at_working_tool(const CompensationModel& model, const robot::MdhModel& nominal);

/// A working tool (flange frame) as `--tool` and a model's "working_tool" must be: finite, and its
/// point at most kMaxToolPointMm from the flange origin; ArgumentError starting with `what` otherwise.
void check_tool_point(const Eigen::Isometry3d& tool, const std::string& what);

/// Unit direction m = (p − base)/|p − base| of eq. 22. Precondition: p != base.
Eigen::Vector3d radial_direction(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& base_mm);

/// P(|e| <= tol) for a scalar e ~ N(0, variance) (both in mm / mm²); NaN for a NaN or negative
/// variance. One-dimensional: for a 3-D error use probability_within_radius (error_ball.hpp).
double probability_within(double tolerance_mm, double variance_mm2);

}  // namespace errfield::compensation
