#include "errfield/compensation/model/compensation.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "errfield/compensation/model/error_ball.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/compensation/model/error_fields.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/kinematics.hpp"
#include "robot/json_fields.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

struct MethodName {
  CompensationMethod method;
  std::string_view name;
};

constexpr MethodName kMethods[] = {
    {CompensationMethod::none, "none"},
    {CompensationMethod::kinematic, "kinematic"},
    {CompensationMethod::position_idw, "position-idw"},
    {CompensationMethod::distance_idw, "distance-idw"},
    {CompensationMethod::distance_kriging, "distance-kriging"},
    {CompensationMethod::vector_kriging, "vector-kriging"},
    {CompensationMethod::kinematic_kriging, "kinematic+kriging"},
};

}  // namespace

std::string_view method_name(CompensationMethod method) {
  for (const auto& m : kMethods)
    if (m.method == method) return m.name;
  return "unknown";
}

CompensationMethod method_from_name(std::string_view name) {
  std::string known;
  for (const auto& m : kMethods) {
    if (m.name == name) return m.method;
    known += (known.empty() ? "" : ", ") + std::string(m.name);
  }
  throw ArgumentError("unknown compensation method '" + std::string(name) + "'; expected one of: " + known);
}

std::vector<CompensationMethod> all_methods() {
  std::vector<CompensationMethod> out;
  for (const auto& m : kMethods) out.push_back(m.method);
  return out;
}

namespace {
/// The methods whose command model is a calibrated robot (used through compensated_joints).
bool is_calibrated(CompensationMethod method) {
  return method == CompensationMethod::kinematic || method == CompensationMethod::kinematic_kriging;
}
}  // namespace

Eigen::Vector3d radial_direction(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& base_mm) {
  return (p_mm - base_mm).normalized();
}

double probability_within(double tolerance_mm, double variance_mm2) {
  if (!(variance_mm2 >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  if (variance_mm2 == 0.0) return 1.0;
  return std::erf(tolerance_mm / std::sqrt(2.0 * variance_mm2));
}

CompensationModel::CompensationModel(CompensationMethod method, MdhModel command_model,
                                     std::shared_ptr<const ErrorField> field)
    : method_(method), command_model_(std::move(command_model)), field_(std::move(field)) {
  // Every field carries the errors it was fitted on, so every model (also a file written before the
  // range was stored) judges its predictions against them.
  if (field_) {
    const Eigen::MatrixXd e = compensation::fitted_errors(*field_);
    if (e.rows() > 0) credible_ = CredibleRange::of(e);
  }
}

CompensatedTarget CompensationModel::compensate(const MdhModel& nominal_model, const Eigen::Isometry3d& target,
                                                const JointVector& seed_deg, double tolerance_mm,
                                                const IkOptions& ik) const {
  const IkResult nominal = inverse_kinematics(nominal_model, target, seed_deg, ik);
  if (!nominal.ok()) {
    CompensatedTarget out;
    out.q_nominal_deg = out.q_command_deg = nominal.q_deg;
    out.ik_status = nominal.status;
    out.ik_residual_mm = nominal.position_residual_mm;
    out.command_position_mm = target.translation();
    return out;
  }
  return compensate_joints(nominal_model, nominal.q_deg, tolerance_mm, ik);
}

CompensatedTarget CompensationModel::compensate_joints(const MdhModel& nominal_model, const JointVector& q_nominal_deg,
                                                       double tolerance_mm, const IkOptions& ik) const {
  CompensatedTarget out;
  out.q_nominal_deg = q_nominal_deg;
  out.q_command_deg = q_nominal_deg;
  Eigen::Isometry3d pose = forward_kinematics(nominal_model, q_nominal_deg, ik.frame);
  const Eigen::Vector3d p_nominal = pose.translation();
  // The tool point, not the reflector the data measured (when the model knows both).
  const MdhModel aimed = aimed_model();
  if (field_) {
    // The field lives on the nominal robot the model was fitted with (the caller's, unless the model
    // stored its own; with a working tool the caller's nominal robot carries that tool, not the
    // reflector the field was fitted at).
    out.prediction = has_nominal_model() || working_tool_ ? predict_error_at(q_nominal_deg, aimed)
                                                          : field_->predict(p_nominal, q_nominal_deg);
    if (!has_nominal_model() && !working_tool_ && credible_ && out.prediction.inside_region)
      out.prediction.credible = credible_->contains(out.prediction);
    if (!out.prediction.inside_region || !out.prediction.credible || !out.prediction.orientation_supported) {
      out.command_position_mm = p_nominal;
      return out;
    }
    // Of a new reading (field + nugget): the figure a tracker check of the target will show.
    if (tolerance_mm > 0.0)
      out.p_within_tolerance = out.prediction.axis_variance_mm2.allFinite()
                                   ? probability_within_radius(tolerance_mm, out.prediction.axis_variance_mm2)
                                   : probability_within(tolerance_mm, out.prediction.predictive_variance_mm2());
  }
  out.command_position_mm = p_nominal - out.prediction.position_error_mm;
  const bool calibrated = is_calibrated(method_);
  // The calibration's share of the error: where the calibrated model puts the tool point at the
  // nominal joints (pred_dx..dz leave it out; the joints move by both).
  out.total_error_mm = out.prediction.position_error_mm;
  if (calibrated) out.total_error_mm += forward_kinematics(aimed, q_nominal_deg, ik.frame).translation() - p_nominal;
  if (method_ == CompensationMethod::none) {
    out.move_mm = 0.0;
    return out;
  }
  // Three or more points on the flange (or a probe) determine its orientation: the rotation the
  // fields predict is corrected as the position is, R_cmd = exp(-[w]x) R_n, through the calibrated
  // model's whole pose.
  if (calibrated && field_ && fielded_points().size() >= 3) {
    out.rotation = predict_rotation(q_nominal_deg);
    if (out.rotation && out.rotation->status != "ok") {
      out.prediction.inside_region = out.rotation->status != "outside-region" && out.prediction.inside_region;
      out.prediction.credible = out.rotation->status != "not-credible" && out.prediction.credible;
      out.prediction.orientation_supported =
          out.rotation->status != "orientation-unknown" && out.prediction.orientation_supported;
      out.prediction.calibration_supported =
          out.rotation->status != "calibration-extrapolated" && out.prediction.calibration_supported;
    }
  }
  const bool with_orientation = out.rotation && out.rotation->status == "ok";
  pose.translation() = out.command_position_mm;
  if (with_orientation) {
    const Eigen::Vector3d& w = out.rotation->rotation_rad;
    const Eigen::AngleAxisd calibration(forward_kinematics(aimed, q_nominal_deg, ik.frame).linear() * pose.linear().transpose());
    out.total_rotation_error_rad = calibration.angle() * calibration.axis() + w;
    pose.linear() = Eigen::AngleAxisd(-w.norm(), w.norm() > 0 ? Eigen::Vector3d(w.normalized()) : Eigen::Vector3d::UnitX())
                        .toRotationMatrix() *
                    pose.linear();
  }
  // A calibrated model is otherwise used through compensated_joints (its orientation parameters are
  // weakly determined by one point's positions or by distances, so full-pose IK of it would follow
  // them).
  const IkResult cmd = with_orientation ? compensated_pose_joints(nominal_model, aimed, pose, q_nominal_deg)
                       : calibrated     ? compensated_joints(nominal_model, aimed, pose, q_nominal_deg)
                                        : inverse_kinematics(aimed, pose, q_nominal_deg, ik);
  out.ik_status = cmd.status;
  out.ik_residual_mm = cmd.position_residual_mm;
  if (cmd.ok()) {
    out.q_command_deg = cmd.q_deg;
    out.move_mm = (forward_kinematics(nominal_model, cmd.q_deg, ik.frame).translation() - p_nominal).norm();
  }
  return out;
}

Eigen::Vector3d CompensationModel::total_error(const MdhModel& nominal_model, const JointVector& q_deg) const {
  const Eigen::Vector3d p_nominal = forward_position(nominal_model, q_deg);
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  if (field_) {
    ErrorPrediction p = has_nominal_model() || working_tool_ ? predict_error_at(q_deg, aimed_model())
                                                             : field_->predict(p_nominal, q_deg);
    if (!has_nominal_model() && !working_tool_ && credible_ && p.inside_region) p.credible = credible_->contains(p);
    if (!p.inside_region || !p.credible) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    e = p.position_error_mm;
  }
  if (is_calibrated(method_)) e += forward_position(aimed_model(), q_deg) - p_nominal;
  return e;
}

double CompensationModel::largest_training_correction_mm() const {
  double largest = 0.0;
  // The nominal robot with the point aimed, so that only errors count, not the lever to it.
  const MdhModel nominal = working_tool_ ? nominal_model().with_tool(*working_tool_) : nominal_model();
  for (const JointVector& q : data_joints_) {
    const double e = total_error(nominal, q).norm();
    if (std::isfinite(e)) largest = std::max(largest, e);
  }
  return largest;
}

MdhModel nominal_at_working_tool(const CompensationModel& model, const MdhModel& nominal) {
  return model.working_tool() ? nominal.with_tool(model.tool_in_robot_frame(*model.working_tool())) : nominal;
}

void check_tool_point(const Eigen::Isometry3d& tool, const std::string& what) {
  const Eigen::Vector3d t = tool.translation();
  if (!tool.matrix().allFinite())
    throw ArgumentError(what + ": the tool point is not finite");
  if (t.norm() > kMaxToolPointMm)
    throw ArgumentError(what + ": the tool point (" + format_number(t.x()) + ", " + format_number(t.y()) + ", " +
                        format_number(t.z()) + ") mm is " + format_number(t.norm()) + " mm from the flange; expected at most " +
                        format_number(kMaxToolPointMm) + " mm (millimetres, flange frame)");
}

bool CredibleRange::contains(const ErrorPrediction& p) const {
  if (center_mm.size() == 1) {
    const double d = std::abs(p.distance_error_mm - center_mm[0]);
    return d <= radius_mm;  // false for NaN
  }
  if (center_mm.size() != 3) return true;
  const double d = (p.position_error_mm - Eigen::Vector3d(center_mm[0], center_mm[1], center_mm[2])).norm();
  return d <= radius_mm;
}

CredibleRange CredibleRange::of(const Eigen::MatrixXd& e) {
  CredibleRange r;
  if (e.rows() == 0) return r;
  const Eigen::RowVectorXd mean = e.colwise().mean();
  for (Eigen::Index c = 0; c < e.cols(); ++c) r.center_mm.push_back(mean[c]);
  double spread = 0.0;
  for (Eigen::Index i = 0; i < e.rows(); ++i) spread = std::max(spread, (e.row(i) - mean).norm());
  r.radius_mm = 2.0 * spread + 1e-6;  // + 1 nm: a constant field must still predict its own value
  return r;
}

CompensationModel CompensationModel::with_registration(std::optional<compensation::Registration> r) const {
  CompensationModel m = *this;
  m.registration_ = std::move(r);
  return m;
}
CompensationModel CompensationModel::with_measured_orientation(std::optional<MeasuredOrientation> measured) const {
  CompensationModel m = *this;
  m.measured_orientation_ = measured;
  return m;
}
CompensationModel CompensationModel::with_calibration_leverage(std::optional<CalibrationLeverage> leverage) const {
  CompensationModel m = *this;
  m.calibration_leverage_ = std::move(leverage);
  return m;
}
CompensationModel CompensationModel::with_rotation_calibration(std::optional<RotationCalibration> c) const {
  CompensationModel m = *this;
  m.rotation_calibration_ = c;
  return m;
}
CompensationModel CompensationModel::with_flange_error_covariance(std::optional<FlangeErrorCovariance> c) const {
  CompensationModel m = *this;
  m.flange_error_covariance_ = std::move(c);
  return m;
}
CompensationModel CompensationModel::with_tool_point_correction(std::shared_ptr<const ToolPointCorrection> c) const {
  CompensationModel m = *this;
  m.tool_point_correction_ = std::move(c);
  return m;
}

CompensationModel CompensationModel::with_flange_points(std::vector<LabelledPoint> points) const {
  CompensationModel m = *this;
  m.flange_points_ = std::move(points);
  m.set_function_rows_at_samples();
  return m;
}
CompensationModel CompensationModel::with_excluded_rows(std::vector<std::string> points) const {
  CompensationModel m = *this;
  m.excluded_rows_ = std::move(points);
  return m;
}
CompensationModel CompensationModel::with_notes(std::vector<std::string> notes) const {
  CompensationModel m = *this;
  m.notes_ = std::move(notes);
  return m;
}
CompensationModel CompensationModel::with_nominal_registration(std::optional<compensation::Registration> r) const {
  CompensationModel m = *this;
  m.nominal_registration_ = std::move(r);
  return m;
}
CompensationModel CompensationModel::with_nominal_model(MdhModel nominal) const {
  CompensationModel m = *this;
  m.nominal_model_ = std::move(nominal);
  return m;
}
CompensationModel CompensationModel::with_data_joints(std::vector<JointVector> q_deg) const {
  CompensationModel m = *this;
  m.data_joints_ = std::move(q_deg);
  return m;
}
CompensationModel CompensationModel::with_tool_point(std::optional<Eigen::Vector3d> tool_point,
                                                     std::optional<Eigen::Vector3d> reflector) const {
  CompensationModel m = *this;
  m.tool_point_ = std::move(tool_point);
  m.reflector_ = std::move(reflector);
  return m;
}

CompensationModel CompensationModel::with_joint_error_functions(std::optional<JointErrorFunctions> functions) const {
  CompensationModel m = *this;
  m.joint_functions_ = std::move(functions);
  m.set_function_rows_at_samples();
  return m;
}

void CompensationModel::set_function_rows_at_samples() {
  function_rows_at_samples_.reset();
  set_point_function_rows();
  if (!joint_functions_ || joint_functions_->coefficient_covariance_mrad2.size() == 0 || !field_) return;
  const std::vector<JointVector> q = field_->sample_joints();
  if (q.empty()) return;
  // Row i: sample i's 3 x P design block, column-major (component fastest), so that the weighted
  // sum over the samples is one matrix-vector product over contiguous rows.
  const Eigen::Index p = joint_functions_->parameter_count();
  auto rows = std::make_shared<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      static_cast<Eigen::Index>(q.size()), 3 * p);
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Eigen::MatrixXd block = joint_functions_->design_rows(command_model_, q[i]);
    rows->row(static_cast<Eigen::Index>(i)) = Eigen::Map<const Eigen::RowVectorXd>(block.data(), 3 * p);
  }
  function_rows_at_samples_ = std::move(rows);
}

CompensationModel CompensationModel::with_working_tool(std::optional<Eigen::Isometry3d> tool) const {
  CompensationModel m = *this;
  m.working_tool_ = std::move(tool);
  m.working_tool_located_ = false;
  return m;
}

CompensationModel CompensationModel::with_located_working_tool(const Eigen::Isometry3d& tool) const {
  CompensationModel m = with_working_tool(tool);
  m.working_tool_located_ = true;
  return m;
}

Eigen::Isometry3d CompensationModel::tool_in_model_frame(const Eigen::Isometry3d& tool) const {
  // Where the calibration moved the robot description's tool (the reflector, when the two are one
  // point): the same correction of the flange holds for any point on it.
  if (!has_nominal_model()) return tool;
  const Eigen::Vector3d shift = measured_point_mm() - nominal_model().tool().translation();
  if (!(shift.norm() < kReflectorAtToolMm)) return tool;
  Eigen::Isometry3d t = tool;
  t.translation() += shift;
  return t;
}

Eigen::Isometry3d CompensationModel::tool_in_robot_frame(const Eigen::Isometry3d& tool) const {
  const Eigen::Isometry3d there = tool_in_model_frame(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d t = tool;
  t.translation() -= there.translation();
  return t;
}

namespace {

/// with_located_probe_frame: a description's tool rotation within this of the located probe frame
/// (rad; 5 deg, far beyond a mounting's tolerance and far below a deliberate turn) is the probe's.
constexpr double kProbeFrameAsDrawnRad = 5.0 * M_PI / 180.0;

/// `model` with its tool's rotation the probe frame the model's flange points located, where they are
/// a 6-DoF probe's (probe_readings.hpp: the own point LABEL with LABEL+x and LABEL+y kProbeLeverMm
/// along the probe's own axes): the probe's mounting on the calibrated flange as its readings showed
/// it. The robot description's tool rotation is the mounting as drawn; the difference (the probe's
/// twist on the flange, with joint 6's offset that the calibration cannot tell from it) made
/// predict's orientation miss the probe frame by 149 mdeg RMS and compensate's joints leave 151
/// (issue 47). `model` unchanged for other models.
MdhModel with_located_probe_frame(MdhModel model, const std::vector<CompensationModel::LabelledPoint>& points) {
  if (points.empty()) return model;
  const std::string& own = points.front().label;
  const CompensationModel::LabelledPoint *x = nullptr, *y = nullptr;
  for (const CompensationModel::LabelledPoint& p : points) {
    if (p.label == own + "+x") x = &p;
    if (p.label == own + "+y") y = &p;
  }
  if (!x || !y) return model;
  const Eigen::Vector3d origin = points.front().position_mm;
  const Eigen::Vector3d ex = (x->position_mm - origin).normalized();
  Eigen::Vector3d ey = y->position_mm - origin;
  ey = (ey - ey.dot(ex) * ex).normalized();
  if (!ex.allFinite() || !ey.allFinite()) return model;
  Eigen::Matrix3d located;
  located << ex, ey, ex.cross(ey);
  // Only where the description's tool is the probe's frame as drawn: a tool frame turned against the
  // probe on purpose (a TCP of its own) keeps its rotation on the calibrated flange.
  if (Eigen::AngleAxisd(model.tool().linear().transpose() * located).angle() > kProbeFrameAsDrawnRad) return model;
  Eigen::Isometry3d tool = model.tool();
  tool.linear() = located;
  return model.with_tool(tool);
}

}  // namespace

namespace {

/// True for a working tool no data located: not the model's reflector (within kSameFlangePointMm,
/// where the calibration maps the robot description's tool onto the located point), not the point
/// locate-tool located (it sets the working tool, for calibrated models also the aimed tool point to
/// the same numbers, and from kMinToolPointCorrectionReadings readings a correction there). A
/// `--tool` elsewhere is in the robot description's frame, which the calibrated flange's frame
/// differs from by a constant turn nothing measured, whatever the model measured of the flange's
/// orientation at its own points: a three-nest model scored a point 150 mm away given by --tool at
/// 0.39 mm with a 95 % radius that held none (issue 47). Even a fitted flange point's description
/// coordinates are not its located ones (--reflector scores its readings there).
bool unlocated_working_tool(const CompensationModel& model) {
  if (!model.working_tool() || model.working_tool_located()) return false;
  const Eigen::Vector3d x = model.working_tool()->translation();
  if ((x - model.measured_point_mm()).norm() <= kSameFlangePointMm) return false;
  // A flange point the fit located, at its located coordinates (`--reflector` sets the working tool
  // there); its description's coordinates, a few tenths away, are not located.
  for (const CompensationModel::LabelledPoint& p : model.flange_points())
    if ((p.position_mm - x).norm() <= 1e-9) return false;
  if (model.tool_point_mm() && (x - *model.tool_point_mm()).norm() <= 1e-6 && model.reflector_mm() &&
      (*model.tool_point_mm() - *model.reflector_mm()).norm() > 1e-9)
    return false;
  const auto& correction = model.tool_point_correction();
  return !(correction && (correction->point_mm() - x).norm() <= kSameFlangePointMm);
}

}  // namespace

MdhModel CompensationModel::scored_model() const {
  return working_tool_ ? command_model_.with_tool(*working_tool_) : with_located_probe_frame(command_model_, flange_points_);
}

MdhModel CompensationModel::aimed_model() const {
  if (working_tool_) return command_model_.with_tool(*working_tool_);
  const MdhModel aimed = with_located_probe_frame(command_model_, flange_points_);
  return tool_point_ ? aimed.with_tool_point(*tool_point_) : aimed;
}

CompensationModel CompensationModel::with_credible_range(std::optional<CredibleRange> range) const {
  CompensationModel m = *this;
  m.credible_ = std::move(range);
  return m;
}

namespace {

/// The joint error functions' prediction at the tool point of `at`, with their angle errors as fitted
/// at the reflector (`reflector`'s tool): their design carried to the point
/// (JointErrorFunctions::design_rows_at_point).
JointFunctionPrediction functions_at_point(const JointErrorFunctions& f, const MdhModel& reflector, const MdhModel& at,
                                           const JointVector& q_deg, const Eigen::MatrixXd* taken_back) {
  JointFunctionPrediction out;
  const Eigen::Index count = f.parameter_count();
  if (count == 0) return out;
  Eigen::MatrixXd d = f.design_rows_at_point(reflector, at, q_deg);
  const Eigen::Index polynomial = kJointCount * static_cast<Eigen::Index>(f.degree);
  Eigen::VectorXd beta(count);
  for (Eigen::Index c = 0; c < count; ++c) {
    const int j = c < polynomial ? static_cast<int>(c / f.degree) : f.gravity_terms[static_cast<std::size_t>(c - polynomial)].joint;
    beta[c] = c < polynomial ? f.coefficients_mrad(j, c % f.degree)
                             : f.gravity_terms[static_cast<std::size_t>(c - polynomial)].coefficient_mrad;
  }
  out.position_error_mm = d * beta;
  if (f.coefficient_covariance_mrad2.size() > 0) {
    if (taken_back) d -= *taken_back;
    out.axis_variance_mm2 = (d * f.coefficient_covariance_mrad2 * d.transpose()).diagonal();
  }
  return out;
}

}  // namespace

const OrientationPrior& CompensationModel::orientation_prior() const {
  LazyOrientationPrior::State& s = *orientation_prior_.state;
  std::call_once(s.once, [&] {
    if (!field_) return;
    const std::vector<JointVector> q = field_->sample_joints();
    const Eigen::MatrixXd e = compensation::fitted_errors(*field_);
    if (q.empty() || e.cols() != 3 || e.rows() != static_cast<Eigen::Index>(q.size())) return;
    // The kinematic residual at the reflector (what the field and the functions model together),
    // read as independent angle errors of equal variance s² in the three wrist joints, the joints
    // with the shortest levers to the reflector, so the largest rotation the residual allows:
    // E|r|² = s² sum_k |J_k|² over joints 4..6, J_k the position column of joint k at the reflector.
    // The flange then turns by w = sum_k z_k dq_k, of trace covariance 3 s²: s² per axis. Errors
    // of the long axes (the shoulder, the elbow) turn it by less; a joint whose axis passes through
    // the reflector (J6 for a reflector on the flange's axis) leaves no trace at all, which is what
    // the floor is for (docs/robot.md, "Tool points and orientation").
    double residual_ss = 0.0, lever_ss = 0.0;
    for (std::size_t i = 0; i < q.size(); ++i) {
      Eigen::Vector3d r = e.row(static_cast<Eigen::Index>(i)).transpose();
      if (joint_functions_) r += joint_functions_->position_error_mm(command_model_, q[i]);
      residual_ss += r.squaredNorm();
      lever_ss += geometric_jacobian(command_model_, q[i], EndFrame::tool).block<3, 3>(0, 3).squaredNorm();
    }
    if (!(lever_ss > 0.0) || !std::isfinite(residual_ss)) return;
    OrientationPrior& p = s.value;
    p.samples = q.size();
    p.residual_rms_mm = std::sqrt(residual_ss / static_cast<double>(q.size()));
    p.data_sigma_rad = std::sqrt(residual_ss / lever_ss);
    p.sigma_rad = std::sqrt(p.data_sigma_rad * p.data_sigma_rad + kOrientationPriorFloorRad * kOrientationPriorFloorRad +
                            kUnlocatedOrientationRad * kUnlocatedOrientationRad);
    if (measured_orientation_) {
      // Several points measured it: no guess from one point's residuals; the floor only where a
      // rotation escapes them all (points on one line).
      p.data_sigma_rad = measured_orientation_->sigma_rad;
      p.sigma_rad = !measured_orientation_->add_floor ? p.data_sigma_rad
                                                       : std::hypot(p.data_sigma_rad, kOrientationPriorFloorRad);
      // What they measured is the flange's turn at their own located points; a working tool no data
      // located (`--tool`, in the robot description's frame) also carries the constant turn between
      // that frame and the calibrated one, which nothing measured (unlocated_working_tool).
      if (unlocated_working_tool(*this)) p.sigma_rad = std::hypot(p.sigma_rad, kUnlocatedOrientationRad);
      if (!(p.sigma_rad > 0.0)) {
        p.max_lever_mm = std::numeric_limits<double>::infinity();
        return;
      }
    }
    p.max_lever_mm = kMaxLeverResidualRatio * p.residual_rms_mm / (std::sqrt(2.0) * p.sigma_rad);
  });
  return s.value;
}

ErrorPrediction CompensationModel::predict_error(const JointVector& q_deg) const {
  return predict_error_at(q_deg, scored_model());
}

namespace {

/// What a field's prediction takes back of the joint functions' error near its samples: its weights
/// times the functions' design at its samples (3 x P); empty when the weights do not match the rows.
std::optional<Eigen::MatrixXd> taken_back_by(
    const std::vector<double>& weights,
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>* rows) {
  if (!rows || static_cast<Eigen::Index>(weights.size()) != rows->rows()) return std::nullopt;
  const Eigen::RowVectorXd sum =
      Eigen::Map<const Eigen::RowVectorXd>(weights.data(), static_cast<Eigen::Index>(weights.size())) * *rows;
  return Eigen::MatrixXd(Eigen::Map<const Eigen::MatrixXd>(sum.data(), 3, sum.size() / 3));
}

/// Adds the joint functions' displacement at `point` and their estimation variance (less what the
/// field takes back) to a field's prediction `p`.
void add_functions_at_point(ErrorPrediction& p, const JointErrorFunctions& functions, const MdhModel& reflector,
                            const MdhModel& point, const JointVector& q_deg,
                            const std::optional<Eigen::MatrixXd>& taken_back) {
  const JointFunctionPrediction f =
      functions_at_point(functions, reflector, point, q_deg, taken_back ? &*taken_back : nullptr);
  p.position_error_mm += f.position_error_mm;
  if (std::isfinite(p.variance_mm2)) p.variance_mm2 += f.axis_variance_mm2.sum();
  if (p.axis_variance_mm2.allFinite()) p.axis_variance_mm2 += f.axis_variance_mm2;
}

/// [v]x: the matrix of the cross product v x .
Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Eigen::Vector3d CompensationModel::joint_function_error_at(const JointVector& q_deg, const MdhModel& at) const {
  if (!joint_functions_) return Eigen::Vector3d::Zero();
  if (at.tool().isApprox(command_model_.tool(), 1e-12)) return joint_functions_->predict(command_model_, q_deg).position_error_mm;
  return functions_at_point(*joint_functions_, command_model_, at, q_deg, nullptr).position_error_mm;
}

void CompensationModel::set_point_function_rows() {
  point_function_rows_.assign(flange_points_.size(), nullptr);
  if (!joint_functions_ || joint_functions_->coefficient_covariance_mrad2.size() == 0) return;
  const Eigen::Index p = joint_functions_->parameter_count();
  for (std::size_t k = 0; k < flange_points_.size(); ++k) {
    if (!flange_points_[k].field) continue;
    const std::vector<JointVector> q = flange_points_[k].field->sample_joints();
    if (q.empty()) continue;
    const MdhModel at = command_model_.with_tool_point(flange_points_[k].position_mm);
    auto rows = std::make_shared<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        static_cast<Eigen::Index>(q.size()), 3 * p);
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Eigen::MatrixXd block = joint_functions_->design_rows_at_point(command_model_, at, q[i]);
      rows->row(static_cast<Eigen::Index>(i)) = Eigen::Map<const Eigen::RowVectorXd>(block.data(), 3 * p);
    }
    point_function_rows_[k] = std::move(rows);
  }
}

ErrorPrediction CompensationModel::predict_at_labelled_point(const JointVector& q_deg, const MdhModel& point,
                                                             std::size_t k) const {
  const ErrorField& field = *flange_points_[k].field;
  const auto& rows = point_function_rows_.size() == flange_points_.size() ? point_function_rows_[k] : nullptr;
  std::vector<double> w;
  const Eigen::Vector3d at = forward_position(nominal_model(), q_deg);
  ErrorPrediction p = rows ? field.predict_with_weights(at, q_deg, w) : field.predict(at, q_deg);
  if (p.inside_region && credible_) p.credible = credible_->contains(p);
  if (p.inside_region && joint_functions_) {
    // As at the own point: the point's field takes back part of the functions' error near its samples.
    add_functions_at_point(p, *joint_functions_, command_model_, point, q_deg, taken_back_by(w, rows.get()));
  }
  return p;
}

namespace {

/// How the error at a point on the flange combines the errors at points with a field, through the
/// small rigid motion (t, w) of the flange they imply: the residual at a point p moved by it is
/// t + w x p = [I, -[p]x] (t, w), with p in the robot frame (the flange's rotation at q applied); the
/// fields' predictions at the known points give (t, w) by least squares, which then gives the point's.
struct RigidMotionCombination {
  Eigen::Matrix<double, 3, 6> at_point;  ///< the point's error per rigid motion (t, w)
  Eigen::MatrixXd combination;           ///< 3 x 3k: the point's error per known points' errors
  /// Rigid motions none of the known points observes (points on one line: the rotation about it),
  /// scaled to a unit rotation.
  std::vector<Eigen::Matrix<double, 6, 1>> unobservable;

  RigidMotionCombination(const Eigen::Matrix3d& rotation, const std::vector<Eigen::Vector3d>& known_points_mm,
                         const Eigen::Vector3d& point_mm) {
    const auto k = static_cast<Eigen::Index>(known_points_mm.size());
    Eigen::MatrixXd a(3 * k, 6);
    for (Eigen::Index j = 0; j < k; ++j) {
      a.block<3, 3>(3 * j, 0).setIdentity();
      a.block<3, 3>(3 * j, 3) = -cross_matrix(rotation * known_points_mm[static_cast<std::size_t>(j)]);
    }
    at_point << Eigen::Matrix3d::Identity(), -cross_matrix(rotation * point_mm);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeFullV);
    const Eigen::VectorXd& s = svd.singularValues();
    // Points on one line leave the rotation about it unobservable (one singular value ~0).
    const double cutoff = 1e-9 * s[0];
    Eigen::MatrixXd pseudo_inverse = Eigen::MatrixXd::Zero(6, 3 * k);
    for (Eigen::Index c = 0; c < 6; ++c) {
      if (c < s.size() && s[c] > cutoff) {
        pseudo_inverse += svd.matrixV().col(c) * svd.matrixU().col(c).transpose() / s[c];
      } else {
        const Eigen::Matrix<double, 6, 1> v = svd.matrixV().col(c);
        if (v.tail<3>().norm() > 1e-12) unobservable.push_back(v / v.tail<3>().norm());
      }
    }
    // Of the motions that fit, the one that does not turn about the unobservable axis (the prior's
    // mean, isotropic in the rotation): the least-norm solution would mix translation into it.
    for (const Eigen::Matrix<double, 6, 1>& v : unobservable) {
      Eigen::Matrix<double, 6, 6> keep = Eigen::Matrix<double, 6, 6>::Identity();
      keep.rightCols<3>() -= v * v.tail<3>().transpose();
      pseudo_inverse = keep * pseudo_inverse;
    }
    combination = at_point * pseudo_inverse;
  }
};

}  // namespace

ErrorPrediction CompensationModel::predict_by_rigid_motion(const JointVector& q_deg, const MdhModel& point,
                                                           bool orientation_variance) const {
  // The points with a field (flange frame) and their fields: the own point first.
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  struct Known {
    Eigen::Vector3d point_mm;
    const ErrorField* field;
    const Rows* function_rows;  // the functions' design at the field's samples, or null
  };
  std::vector<Known> known = {{measured_point_mm(), field_.get(), function_rows_at_samples_.get()}};
  for (std::size_t k = 0; k < flange_points_.size(); ++k)
    if (flange_points_[k].field)
      known.push_back({flange_points_[k].position_mm, flange_points_[k].field.get(),
                       k < point_function_rows_.size() ? point_function_rows_[k].get() : nullptr});
  const Eigen::Index k = static_cast<Eigen::Index>(known.size());
  const Eigen::Matrix3d rotation = forward_kinematics(command_model_, q_deg, EndFrame::flange).linear();
  std::vector<Eigen::Vector3d> known_points_mm;
  for (const Known& point_of_field : known) known_points_mm.push_back(point_of_field.point_mm);
  const RigidMotionCombination motion(rotation, known_points_mm, point.tool().translation());
  const Eigen::MatrixXd& combination = motion.combination;
  const Eigen::Matrix<double, 3, 6>& at_point = motion.at_point;
  const std::vector<Eigen::Matrix<double, 6, 1>>& unobservable = motion.unobservable;
  const Eigen::Vector3d at = forward_position(nominal_model(), q_deg);
  ErrorPrediction p;
  p.variance_mm2 = 0.0;
  p.noise_variance_mm2 = 0.0;
  Eigen::Vector3d field_sd = Eigen::Vector3d::Zero();
  bool with_variance = true;
  // What the fields take back of the joint functions' error near their samples, combined as their
  // predictions are (each field's weights times the functions' design at its samples).
  const Eigen::Index parameters = joint_functions_ ? joint_functions_->parameter_count() : 0;
  std::optional<Eigen::MatrixXd> taken_back;
  if (joint_functions_ && joint_functions_->coefficient_covariance_mrad2.size() > 0)
    taken_back = Eigen::MatrixXd::Zero(3, parameters);
  std::vector<double> weights;
  double field_variance_sum = 0.0;  // the fields' own variances, noise excluded, summed over points and axes
  for (Eigen::Index j = 0; j < k; ++j) {
    const Known& known_point = known[static_cast<std::size_t>(j)];
    const ErrorPrediction e = known_point.function_rows ? known_point.field->predict_with_weights(at, q_deg, weights)
                                                        : known_point.field->predict(at, q_deg);
    if (!e.inside_region) return e;
    const Eigen::Matrix3d c = combination.middleCols<3>(3 * j);
    const std::optional<Eigen::MatrixXd> by_this = taken_back ? taken_back_by(weights, known_point.function_rows) : std::nullopt;
    if (by_this) *taken_back += c * *by_this;
    else taken_back.reset();
    p.position_error_mm += c * e.position_error_mm;
    // Each field's own variance per axis (its nugget, when it is measurement noise, taken out: a new
    // reading at the point has the noise of one reading, not a combination of several).
    const double noise = std::isfinite(e.noise_variance_mm2) ? e.noise_variance_mm2 : 0.0;
    const Eigen::Vector3d own = (e.axis_variance_mm2.array() - noise / 3.0).max(0.0).matrix();
    with_variance = with_variance && e.axis_variance_mm2.allFinite();
    // The fields' errors are alike at nearby points: the sum of their standard deviations bounds
    // the combination's.
    field_sd += (c.cwiseAbs2() * own).cwiseSqrt();
    field_variance_sum += own.sum();
    p.noise_variance_mm2 += noise / static_cast<double>(k);
  }
  if (credible_) p.credible = credible_->contains(p);
  if (!with_variance) {
    p.variance_mm2 = p.noise_variance_mm2 = std::numeric_limits<double>::quiet_NaN();
  } else {
    Eigen::Vector3d field_variance = field_sd.cwiseAbs2();
    // How alike the fields' errors are, from their leave-one-out (FlangeErrorCovariance), in place
    // of that bound.
    if (flange_error_covariance_ && flange_error_covariance_->point_count() == static_cast<std::size_t>(k))
      field_variance = flange_error_covariance_->covariance_at(rotation, combination, field_variance_sum).diagonal().cwiseMax(0.0);
    // The rotation about the points' line, which none of them sees: the orientation prior.
    const OrientationPrior& prior = orientation_prior();
    for (const Eigen::Matrix<double, 6, 1>& v : unobservable) {
      const Eigen::Vector3d moved = at_point * v;  // mm per rad about the line
      const double s2 = prior.known() && orientation_variance ? prior.sigma_rad * prior.sigma_rad : 0.0;
      field_variance += s2 * moved.cwiseAbs2();
      p.orientation_variance_mm2 += s2 * moved.squaredNorm();
      // The one-point lever limit is for a rotation about any axis (2 sigma² L²); about one axis it
      // is sigma² |moved|².
      if (prior.known()) p.orientation_supported = p.orientation_supported && moved.norm() <= std::sqrt(2.0) * prior.max_lever_mm;
    }
    p.variance_mm2 = field_variance.sum();
    p.axis_variance_mm2 = field_variance + Eigen::Vector3d::Constant(p.noise_variance_mm2 / 3.0);
  }
  if (joint_functions_) add_functions_at_point(p, *joint_functions_, command_model_, point, q_deg, taken_back);
  return p;
}

std::vector<CompensationModel::FieldedPoint> CompensationModel::fielded_points() const {
  std::vector<FieldedPoint> out;
  if (!field_) return out;
  out.push_back({measured_point_mm(), field_.get()});
  for (const LabelledPoint& p : flange_points_)
    if (p.field) out.push_back({p.position_mm, p.field.get()});
  return out;
}

std::optional<RotationPrediction> CompensationModel::predict_rotation(const JointVector& q_deg) const {
  const std::vector<FieldedPoint> points = fielded_points();
  std::vector<Eigen::Vector3d> at;  // robot frame
  std::vector<MdhModel> models;
  for (const FieldedPoint& p : points) {
    models.push_back(command_model_.with_tool_point(p.position_mm));
    at.push_back(forward_position(models.back(), q_deg));
  }
  const std::optional<FlangeRotationOperator> rotation = FlangeRotationOperator::of(at);
  if (!rotation) return std::nullopt;
  std::vector<Eigen::Vector3d> error, variance;
  RotationPrediction out;
  for (const MdhModel& m : models) {
    const ErrorPrediction e = predict_error_at(q_deg, m);
    if (const PredictionStatus s = prediction_status(e); s != PredictionStatus::ok && out.status == "ok")
      out.status = std::string(status_name(s));
    error.push_back(e.position_error_mm);
    variance.push_back(e.axis_variance_mm2);
  }
  out.rotation_rad = rotation->rotation_rad(error);
  out.covariance_rad2 = rotation->covariance_rad2(variance);
  if (rotation_calibration_)
    out.covariance_rad2 = rotation_calibration_->covariance_at(
        forward_kinematics(command_model_, q_deg, EndFrame::flange).linear(), out.covariance_rad2);
  return out;
}

ErrorPrediction CompensationModel::predict_error_at(const JointVector& q_deg, const MdhModel& point) const {
  return with_calibration_leverage(predict_field_at(q_deg, point), q_deg);
}

ErrorPrediction CompensationModel::with_calibration_leverage(ErrorPrediction p, const JointVector& q_deg) const {
  // Judged at the measured point: how far the pose is from what the calibration's data determine
  // (a lever to another point is the orientation prior's).
  if (calibration_leverage_) {
    p.calibration_leverage_ratio = calibration_leverage_->ratio(command_model_, q_deg);
    p.calibration_supported = p.calibration_leverage_ratio <= kMaxCalibrationLeverageRatio;
  }
  return p;
}

std::vector<ErrorPrediction> CompensationModel::predict_errors_at(std::span<const JointVector> q_deg,
                                                                  std::span<const MdhModel> at) const {
  if (q_deg.size() != at.size())
    throw ArgumentError("predict_errors_at: " + std::to_string(q_deg.size()) + " joint vectors for " +
                        std::to_string(at.size()) + " points");
  std::vector<ErrorPrediction> out(q_deg.size());
  if (!field_) {
    for (std::size_t i = 0; i < q_deg.size(); ++i) out[i] = predict_error_at(q_deg[i], at[i]);
    return out;
  }
  // The rows the model's own field answers (predict_uncorrected_at's first branch not taken) have
  // their field predictions batched; the others go one by one.
  const bool several = std::any_of(flange_points_.begin(), flange_points_.end(), [](const LabelledPoint& lp) { return lp.field != nullptr; });
  std::vector<std::size_t> own;
  std::vector<Eigen::Vector3d> nominal;
  std::vector<JointVector> joints;
  for (std::size_t i = 0; i < q_deg.size(); ++i) {
    if (several && (at[i].tool().translation() - measured_point_mm()).norm() > kSameFlangePointMm) {
      out[i] = predict_error_at(q_deg[i], at[i]);
      continue;
    }
    own.push_back(i);
    nominal.push_back(forward_position(nominal_model(), q_deg[i]));
    joints.push_back(q_deg[i]);
  }
  std::vector<std::vector<double>> weights;
  std::vector<ErrorPrediction> fields = field_->predict_many(nominal, joints, function_rows_at_samples_ ? &weights : nullptr);
  static const std::vector<double> kNoWeights;
  for (std::size_t k = 0; k < own.size(); ++k) {
    const std::size_t i = own[k];
    const ToolPointCorrection* correction = tool_point_correction_at(at[i]);
    ErrorPrediction p = completed_at_own_field(std::move(fields[k]), weights.empty() ? kNoWeights : weights[k], q_deg[i],
                                               at[i], correction == nullptr);
    out[i] = with_calibration_leverage(with_tool_point_correction(std::move(p), q_deg[i], correction), q_deg[i]);
  }
  return out;
}

const ToolPointCorrection* CompensationModel::tool_point_correction_at(const MdhModel& point) const {
  return tool_point_correction_ && (tool_point_correction_->point_mm() - point.tool().translation()).norm() <= kSameFlangePointMm
             ? tool_point_correction_.get()
             : nullptr;
}

ErrorPrediction CompensationModel::predict_field_at(const JointVector& q_deg, const MdhModel& point) const {
  if (!field_) return {};
  const ToolPointCorrection* correction = tool_point_correction_at(point);
  return with_tool_point_correction(predict_uncorrected_at(q_deg, point, correction == nullptr), q_deg, correction);
}

ErrorPrediction CompensationModel::with_tool_point_correction(ErrorPrediction p, const JointVector& q_deg,
                                                              const ToolPointCorrection* correction) const {
  if (!correction || !p.inside_region) return p;
  // What the point's own readings showed beyond the model's prediction there (the flange's turn the
  // model's points do not see), kriged; its variance is what the orientation term guessed.
  const ToolPointCorrectionPrediction c =
      correction->predict(q_deg, forward_kinematics(command_model_, q_deg, EndFrame::flange).linear());
  p.position_error_mm += c.error_mm;
  p.orientation_variance_mm2 = c.axis_variance_mm2.sum();
  // The lever rule with what is left unknown at this pose: the correction's kriging variance in place
  // of the prior's 2 sigma² L² (near the readings the point is supported, far from them as before).
  const OrientationPrior& prior = orientation_prior();
  if (prior.known())
    p.orientation_supported = std::sqrt(p.orientation_variance_mm2) <= kMaxLeverResidualRatio * prior.residual_rms_mm;
  if (std::isfinite(p.variance_mm2)) p.variance_mm2 += p.orientation_variance_mm2;
  if (p.axis_variance_mm2.allFinite()) p.axis_variance_mm2 += c.axis_variance_mm2;
  return p;
}

namespace {

/// `p`, a several-point model's prediction at `point` (a flange point's field, or their rigid motion),
/// with the unlocated turn of the working tool where `point` is an unlocated working tool.
ErrorPrediction with_unlocated_orientation(const CompensationModel& model, ErrorPrediction p, const JointVector& q_deg,
                                           const MdhModel& point, bool orientation_variance) {
  const Eigen::Vector3d x = point.tool().translation();
  if (!orientation_variance || !p.inside_region || !unlocated_working_tool(model) ||
      (model.working_tool()->translation() - x).norm() > 1e-9)
    return p;
  const OrientationPrior& prior = model.orientation_prior();
  if (!prior.known()) return p;
  // The constant turn w0 between the description's flange frame and the calibrated one moves the
  // point by w0 x L, L its lever from the reflector (where the two frames agree): isotropic
  // kUnlocatedOrientationRad per axis, as for a one-point model (predict_uncorrected_at below).
  const Eigen::Vector3d lever_flange = x - model.measured_point_mm();
  const Eigen::Vector3d lever = forward_kinematics(point, q_deg, EndFrame::flange).linear() * lever_flange;
  const double s2 = kUnlocatedOrientationRad * kUnlocatedOrientationRad, l2 = lever.squaredNorm();
  p.orientation_variance_mm2 += 2.0 * s2 * l2;
  if (std::isfinite(p.variance_mm2)) p.variance_mm2 += 2.0 * s2 * l2;
  if (p.axis_variance_mm2.allFinite()) p.axis_variance_mm2 += s2 * (Eigen::Vector3d::Constant(l2) - lever.cwiseAbs2());
  p.orientation_supported = p.orientation_supported && lever_flange.norm() <= prior.max_lever_mm;
  return p;
}

}  // namespace

ErrorPrediction CompensationModel::predict_uncorrected_at(const JointVector& q_deg, const MdhModel& point,
                                                          bool orientation_variance) const {
  const Eigen::Vector3d x = point.tool().translation();
  const bool several = std::any_of(flange_points_.begin(), flange_points_.end(), [](const LabelledPoint& lp) { return lp.field != nullptr; });
  if (several && (x - measured_point_mm()).norm() > kSameFlangePointMm) {
    for (std::size_t k = 0; k < flange_points_.size(); ++k)
      if (flange_points_[k].field && (flange_points_[k].position_mm - x).norm() <= kSameFlangePointMm)
        return with_unlocated_orientation(*this, predict_at_labelled_point(q_deg, point, k), q_deg, point,
                                          orientation_variance);
    return with_unlocated_orientation(*this, predict_by_rigid_motion(q_deg, point, orientation_variance), q_deg, point,
                                      orientation_variance);
  }
  std::vector<double> w;  // the field's weights, when the functions' variance needs them
  const Eigen::Vector3d at = forward_position(nominal_model(), q_deg);
  ErrorPrediction p = function_rows_at_samples_ ? field_->predict_with_weights(at, q_deg, w) : field_->predict(at, q_deg);
  return completed_at_own_field(std::move(p), w, q_deg, point, orientation_variance);
}

ErrorPrediction CompensationModel::completed_at_own_field(ErrorPrediction p, const std::vector<double>& w,
                                                          const JointVector& q_deg, const MdhModel& point,
                                                          bool orientation_variance) const {
  if (p.inside_region && credible_) p.credible = credible_->contains(p);
  // The credible range is the field's (its values are what the functions left); the functions are
  // smooth in each joint and clamped beyond the fitted range, so they add no extrapolation.
  if (p.inside_region && joint_functions_) {
    // The field krigs what the functions left at its samples, so near them it takes back part of
    // the functions' error: the variance is that of (D(q) - sum_i w_i F_i) beta's error, with w the
    // field's weights and F_i the design at sample i (the universal-kriging variance's drift term).
    const std::optional<Eigen::MatrixXd> taken_back = taken_back_by(w, function_rows_at_samples_.get());
    const bool at_reflector = (point.tool().translation() - command_model_.tool().translation()).norm() <= 1e-12;
    const JointFunctionPrediction f =
        at_reflector ? joint_functions_->predict(command_model_, q_deg, taken_back ? &*taken_back : nullptr)
                     : functions_at_point(*joint_functions_, command_model_, point, q_deg, taken_back ? &*taken_back : nullptr);
    p.position_error_mm += f.position_error_mm;
    // Their estimation error is part of the field's error (the `var_field_mm2` column) and of a
    // new reading's.
    const Eigen::Vector3d& v = f.axis_variance_mm2;
    if (std::isfinite(p.variance_mm2)) p.variance_mm2 += v.sum();
    if (p.axis_variance_mm2.allFinite()) p.axis_variance_mm2 += v;
  }
  // Away from the reflector: the flange's orientation residual w, unobservable with one reflector,
  // moves the point by w x L. Its covariance under an isotropic prior sigma² is
  // sigma² (|L|² I - L Lᵀ) (the diagonal is what the error ball uses).
  const Eigen::Vector3d lever_flange = point.tool().translation() - measured_point_mm();
  if (p.inside_region && lever_flange.norm() > 0.0) {
    const OrientationPrior& prior = orientation_prior();
    if (prior.known()) {
      const Eigen::Vector3d lever = forward_kinematics(point, q_deg, EndFrame::flange).linear() * lever_flange;
      const double s2 = orientation_variance ? prior.sigma_rad * prior.sigma_rad : 0.0, l2 = lever.squaredNorm();
      p.orientation_variance_mm2 = 2.0 * s2 * l2;
      if (std::isfinite(p.variance_mm2)) p.variance_mm2 += p.orientation_variance_mm2;
      if (p.axis_variance_mm2.allFinite())
        p.axis_variance_mm2 += s2 * (Eigen::Vector3d::Constant(l2) - lever.cwiseAbs2());
      p.orientation_supported = lever_flange.norm() <= prior.max_lever_mm;
    }
  }
  return p;
}

namespace {

/// A matrix as a model file holds it: rows of numbers.
nlohmann::json rows_of(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

/// The n x n matrix `rows` holds (rows of numbers), or none when it holds anything else.
std::optional<Eigen::MatrixXd> square_matrix_of(const nlohmann::json& rows, Eigen::Index n) {
  if (!rows.is_array() || rows.size() != static_cast<std::size_t>(n)) return std::nullopt;
  Eigen::MatrixXd m(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const nlohmann::json& line = rows[static_cast<std::size_t>(r)];
    if (!line.is_array() || line.size() != static_cast<std::size_t>(n)) return std::nullopt;
    for (Eigen::Index c = 0; c < n; ++c) {
      if (!line[static_cast<std::size_t>(c)].is_number()) return std::nullopt;
      m(r, c) = line[static_cast<std::size_t>(c)].get<double>();
    }
  }
  return m;
}

}  // namespace

nlohmann::json CompensationModel::to_json() const {
  nlohmann::json j;
  j["format"] = "errfield-compensation-model";
  j["version"] = 1;
  j["method"] = std::string(method_name(method_));
  j["command_model"] = command_model_.to_json();
  j["field"] = field_ ? field_->to_json() : nlohmann::json(nullptr);
  if (nominal_model_) j["nominal_model"] = nominal_model_->to_json();
  if (registration_) j["registration"] = compensation::registration_to_json(*registration_);
  if (nominal_registration_) j["nominal_registration"] = compensation::registration_to_json(*nominal_registration_);
  if (credible_) j["credible_range"] = {{"center_mm", credible_->center_mm}, {"radius_mm", credible_->radius_mm}};
  if (!data_joints_.empty()) {
    nlohmann::json q = nlohmann::json::array();
    for (const JointVector& v : data_joints_) q.push_back({v[0], v[1], v[2], v[3], v[4], v[5]});
    j["data_joints_deg"] = q;
  }
  if (tool_point_) j["tool_point_mm"] = {tool_point_->x(), tool_point_->y(), tool_point_->z()};
  if (reflector_) j["reflector_mm"] = {reflector_->x(), reflector_->y(), reflector_->z()};
  if (joint_functions_) j["joint_error_functions"] = joint_functions_->to_json();
  if (working_tool_) j["working_tool"] = robot::detail::pose_json(*working_tool_);
  if (working_tool_ && working_tool_located_) j["working_tool_located"] = true;
  if (!flange_points_.empty()) {
    nlohmann::json points = nlohmann::json::array();
    for (const LabelledPoint& p : flange_points_)
    {
      nlohmann::json e = {{"label", p.label}, {"mm", {p.position_mm.x(), p.position_mm.y(), p.position_mm.z()}}};
      if (p.field) e["field"] = p.field->to_json();
      if (p.nominal_mm) e["nominal_mm"] = {p.nominal_mm->x(), p.nominal_mm->y(), p.nominal_mm->z()};
      points.push_back(std::move(e));
    }
    j["flange_points"] = points;
  }
  if (calibration_leverage_) j["calibration_leverage"] = calibration_leverage_->to_json();
  if (measured_orientation_)
    j["orientation_residual"] = {{"sigma_rad", measured_orientation_->sigma_rad},
                                 {"readings", measured_orientation_->readings},
                                 {"add_floor", measured_orientation_->add_floor}};
  if (flange_error_covariance_) {
    j["flange_error_covariance"] = {{"field_covariance_mm2", rows_of(flange_error_covariance_->field_covariance_mm2)},
                                    {"mean_field_variance_mm2", flange_error_covariance_->mean_field_variance_mm2},
                                    {"poses", flange_error_covariance_->poses}};
  }
  if (tool_point_correction_) j["tool_point_correction"] = tool_point_correction_->to_json();
  if (rotation_calibration_) {
    j["rotation_calibration"] = {{"flange_covariance_rad2", rows_of(rotation_calibration_->flange_covariance_rad2)},
                                 {"mean_independent_trace_rad2", rotation_calibration_->mean_independent_trace_rad2},
                                 {"poses", rotation_calibration_->poses}};
  }
  if (!notes_.empty()) j["notes"] = notes_;
  if (!excluded_rows_.empty()) j["excluded_rows"] = excluded_rows_;
  return j;
}

namespace {
[[noreturn]] void fail_model(const std::string& source, const std::string& what) {
  throw InputError(source + ": " + what, source);
}

/// The field kind each method fits (model_fitting.cpp); "" for the methods without a field.
std::string_view field_kind_of(CompensationMethod method) {
  switch (method) {
    case CompensationMethod::distance_idw: return "distance-idw";
    case CompensationMethod::position_idw: return "position-idw";
    case CompensationMethod::distance_kriging: return "distance-kriging";
    case CompensationMethod::vector_kriging:
    case CompensationMethod::kinematic_kriging: return "vector-kriging";
    default: return "";
  }
}

/// A kriging field's stored sample positions are the nominal robot's FK of its stored joints (the
/// field is evaluated there): a command model of another robot than the samples' gave 126/126
/// rows "ok", 779 mm off. Positions may come from the data's x,y,z columns, which fit checks to
/// kNominalFkToleranceMm, so that is the limit here too.
void check_stored_samples(const CompensationModel& model, const nlohmann::json& field, const std::string& source) {
  if (!field.contains("samples")) return;
  const auto& s = field["samples"];
  const auto& pos = s["position_mm"];
  const auto& joints = s["joints_deg"];
  const MdhModel& robot = model.nominal_model();
  // Readings of several points on the flange fitted with a robot JSON whose tool is elsewhere (the
  // flange itself, as `simulate --reflectors --robot-out` writes it): the samples are the data's
  // x,y,z at the model's own reflector, which the nominal robot carries only at that point.
  const MdhModel at_reflector = robot.with_tool_point(model.measured_point_mm());
  for (std::size_t i = 0; i < pos.size(); ++i) {
    JointVector q;
    Eigen::Vector3d p;
    for (int k = 0; k < 6; ++k) q[k] = joints[i][static_cast<std::size_t>(k)].get<double>();
    for (int k = 0; k < 3; ++k) p[k] = pos[i][static_cast<std::size_t>(k)].get<double>();
    const Eigen::Vector3d fk = forward_position(robot, q);
    const double off = std::min((fk - p).norm(), (forward_position(at_reflector, q) - p).norm());
    if (off <= kNominalFkToleranceMm) continue;
    fail_model(source, "member \"field.samples\"[" + std::to_string(i) + "]: position_mm is " +
                           format_number(std::round(off * 1000) / 1000) + " mm from the FK of its joints_deg by the " +
                           (model.has_nominal_model() ? "\"nominal_model\"" : "\"command_model\"") + " '" +
                           robot.name() + "' (limit " + format_number(kNominalFkToleranceMm) +
                           " mm): the robot in the file is not the one the field was fitted on; refit the model "
                           "with 'errfield fit'");
  }
}

}  // namespace

namespace {

/// check_flange_points: the points lie as far apart as on the nominal robot's flange to within this
/// (mm): their nominal positions are means of many readings, so their distances agree to a few
/// hundredths on SIMULATED data.
constexpr double kFlangePointDistanceToleranceMm = 0.2;

/// A model's flange points as fit locates them: one label each, the own point first at the measured
/// point, no two within kSameFlangePointMm of each other (one point to the predictions), on a line
/// only if the measured orientation says so (add_floor), and their distances as on the nominal
/// robot's flange (LabelledPoint::nominal_mm, where stored), for a rigid plate is the same plate in
/// both frames. A position moved by hand would otherwise be predicted with the fields of where it
/// was (orientation "after" of 72-15,005 mdeg with moves of 0.5-50 mm, issue 47). A move at right
/// angles to every other point is not seen in their distances.
/// `located_tool`: the model's working tool was located from readings of it (working_tool_located),
/// whose orientation residual then replaced the points' own (locate-tool): a plane's, whatever line
/// the flange points lie on.
void check_flange_points(const CompensationModel& model, const std::string& source, bool located_tool) {
  const std::vector<CompensationModel::LabelledPoint>& points = model.flange_points();
  if (points.empty()) return;
  auto where = [](std::size_t k) { return "member \"flange_points\"[" + std::to_string(k) + "]"; };
  auto mm3 = [](const Eigen::Vector3d& v) {
    return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ") mm";
  };
  if ((points.front().position_mm - model.measured_point_mm()).norm() > 1e-6)
    fail_model(source, where(0) + ".mm: the model's own point " + mm3(points.front().position_mm) +
                           " is not its command model's tool " + mm3(model.measured_point_mm()) +
                           " (the own point comes first; the file was edited?)");
  for (std::size_t a = 0; a < points.size(); ++a)
    for (std::size_t b = a + 1; b < points.size(); ++b) {
      if (points[a].label == points[b].label)
        fail_model(source, where(b) + ".label: '" + points[b].label + "' is also " + where(a) + "'s label");
      const double apart = (points[a].position_mm - points[b].position_mm).norm();
      if (apart <= kSameFlangePointMm)
        fail_model(source, where(b) + ".mm: " + mm3(points[b].position_mm) + " is " + format_number(apart) + " mm from " +
                               where(a) + " ('" + points[a].label + "'): points closer than " +
                               format_number(kSameFlangePointMm) + " mm are one point (the file was edited?)");
    }
  for (std::size_t a = 0; a < points.size(); ++a)
    for (std::size_t b = a + 1; b < points.size(); ++b) {
      const double apart = (points[a].position_mm - points[b].position_mm).norm();
      if (points[a].nominal_mm && points[b].nominal_mm) {
        const double nominal_apart = (*points[a].nominal_mm - *points[b].nominal_mm).norm();
        if (std::abs(apart - nominal_apart) > kFlangePointDistanceToleranceMm)
          fail_model(source, where(b) + ".mm: " + format_number(apart) + " mm from " + where(a) + " ('" + points[a].label +
                                 "'), but " + format_number(nominal_apart) + " mm apart on the nominal flange (nominal_mm): "
                                 "more than " + format_number(kFlangePointDistanceToleranceMm) +
                                 " mm differs; a rigid plate is the same in both frames (the file was edited?)");
      }
    }
  // On one line, the rotation about it is unobserved: a model that says otherwise (add_floor false)
  // would predict the flange's orientation from points that cannot give it.
  if (points.size() >= 2 && !located_tool && model.measured_orientation() && !model.measured_orientation()->add_floor) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : points) mean += p.position_mm / static_cast<double>(points.size());
    Eigen::MatrixXd spread(3, static_cast<Eigen::Index>(points.size()));
    for (std::size_t k = 0; k < points.size(); ++k) spread.col(static_cast<Eigen::Index>(k)) = points[k].position_mm - mean;
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(spread).singularValues();
    if (!(points.size() >= 3 && sv.size() >= 2 && sv[1] > 0.05 * sv[0]))
      fail_model(source, "member \"flange_points\": the points lie on one line, but \"orientation_residual\".add_floor "
                         "is false (which says they span a plane; the file was edited?)");
  }
}

CompensationMethod method_of_model(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) fail_model(source, "expected a JSON object (an errfield compensation model)");
  if (j.value("format", std::string()) != "errfield-compensation-model")
    fail_model(source, "member \"format\" must be \"errfield-compensation-model\" (is this a model written by 'errfield fit'?)");
  if (!j.contains("version") || json_integer_in(j["version"], 1, 1) != 1)
    fail_model(source, "member \"version\": expected 1");
  if (!j.contains("method") || !j["method"].is_string()) fail_model(source, "member \"method\": expected a string");
  try {
    return method_from_name(j["method"].get<std::string>());
  } catch (const ArgumentError& e) {
    fail_model(source, std::string("member \"method\": ") + e.what());
  }
}

/// The model's field, refused when the method corrects through none or through another kind.
std::shared_ptr<const ErrorField> field_of_model(const nlohmann::json& j, CompensationMethod method,
                                                 const std::string& source) {
  auto field = error_field_from_json(j.contains("field") ? j["field"] : nlohmann::json(nullptr), source);
  // A method that corrects through a field, without one, would send uncorrected joints as "ok".
  const bool needs_field = method != CompensationMethod::none && method != CompensationMethod::kinematic;
  if (needs_field && !field)
    fail_model(source, "member \"field\" is " + std::string(j.contains("field") ? "null" : "missing") +
                           ", but method \"" + std::string(method_name(method)) +
                           "\" corrects through its field; refit the model with 'errfield fit'");
  if (!needs_field && field)
    fail_model(source, "member \"field\": method \"" + std::string(method_name(method)) +
                           "\" has no error field, yet the model carries one; refit the model with 'errfield fit'");
  // The field's kind is the method's (a kinematic+kriging model carrying a distance-idw field was
  // trusted and compensated along a radius it never fitted).
  const std::string_view kind = field ? std::string_view(j["field"]["kind"].get_ref<const std::string&>()) : "";
  if (field && kind != field_kind_of(method))
    fail_model(source, "member \"field.kind\": \"" + std::string(kind) + "\", but method \"" +
                           std::string(method_name(method)) + "\" fits a \"" + std::string(field_kind_of(method)) +
                           "\" field; the file was edited or mixed from two models: refit it with 'errfield fit'");
  return field;
}

/// Informative members (notes, excluded rows): read back so a model loaded and saved again keeps them.
void read_strings(const nlohmann::json& j, const char* key, const std::string& source, std::vector<std::string>& into) {
  if (!j.contains(key)) return;
  if (!j[key].is_array()) fail_model(source, std::string("member \"") + key + "\": expected an array of strings");
  for (std::size_t i = 0; i < j[key].size(); ++i) {
    if (!j[key][i].is_string())
      fail_model(source, std::string("member \"") + key + "\"[" + std::to_string(i) + "]: expected a string, got " +
                             j[key][i].dump());
    into.push_back(j[key][i].get<std::string>());
  }
}

bool is_flange_coordinate(const nlohmann::json& v) {
  return v.is_number() && std::isfinite(v.get<double>()) && std::abs(v.get<double>()) <= kMaxToolPointMm;
}

/// Member "flange_points": each point's label, position, own field (of the model's field kind
/// `kind`, when the model has a field) and nominal position.
std::vector<CompensationModel::LabelledPoint> flange_points_of_model(const nlohmann::json& f, bool has_field,
                                                                     std::string_view kind, const std::string& source) {
  if (!f.is_array()) fail_model(source, "member \"flange_points\": expected an array of {\"label\", \"mm\": [x, y, z]}");
  std::vector<CompensationModel::LabelledPoint> points;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const nlohmann::json& e = f[k];
    const bool ok = e.is_object() && e.contains("label") && e["label"].is_string() && e.contains("mm") &&
                    e["mm"].is_array() && e["mm"].size() == 3 && std::all_of(e["mm"].begin(), e["mm"].end(), is_flange_coordinate);
    if (!ok)
      fail_model(source, "member \"flange_points\"[" + std::to_string(k) + "]: expected {\"label\": text, \"mm\": [x, y, z] "
                         "within " + format_number(kMaxToolPointMm) + " mm}, got " + e.dump());
    std::shared_ptr<const ErrorField> point_field;
    if (e.contains("field")) {
      // A further point's field is of the own field's kind (kinematic+kriging models only).
      const std::string where = "member \"flange_points\"[" + std::to_string(k) + "].field";
      if (!has_field || !e["field"].is_object() || !e["field"].contains("kind") || !e["field"]["kind"].is_string() ||
          e["field"]["kind"].get<std::string>() != kind)
        fail_model(source, where + ": expected a field of the model's own kind (\"" + std::string(kind) + "\")");
      point_field = error_field_from_json(e["field"], source);
    }
    std::optional<Eigen::Vector3d> nominal_point;
    if (e.contains("nominal_mm")) {
      const nlohmann::json& n = e["nominal_mm"];
      if (!n.is_array() || n.size() != 3 || !std::all_of(n.begin(), n.end(), is_flange_coordinate))
        fail_model(source, "member \"flange_points\"[" + std::to_string(k) + "].nominal_mm: expected [x, y, z] within " +
                               format_number(kMaxToolPointMm) + " mm, got " + n.dump());
      nominal_point = Eigen::Vector3d(n[0].get<double>(), n[1].get<double>(), n[2].get<double>());
    }
    points.push_back({e["label"].get<std::string>(),
                      Eigen::Vector3d(e["mm"][0].get<double>(), e["mm"][1].get<double>(), e["mm"][2].get<double>()),
                      std::move(point_field), nominal_point});
  }
  return points;
}

MeasuredOrientation orientation_residual_of_model(const nlohmann::json& o, const std::string& source) {
  // 0.1 rad (5.7 deg) of residual orientation after calibration is no robot: a hand edit.
  if (!o.is_object() || !o.contains("sigma_rad") || !o["sigma_rad"].is_number() || !o.contains("readings") ||
      !o["readings"].is_number_unsigned() || !o.contains("add_floor") || !o["add_floor"].is_boolean() ||
      !(o["sigma_rad"].get<double>() >= 0.0 && o["sigma_rad"].get<double>() < 0.1))
    fail_model(source, "member \"orientation_residual\": expected {\"sigma_rad\": 0 <= number < 0.1, \"readings\": "
                       "count, \"add_floor\": bool}, got " + o.dump());
  return MeasuredOrientation{o["sigma_rad"].get<double>(), o["readings"].get<std::size_t>(), o["add_floor"].get<bool>()};
}

/// Member "flange_error_covariance" of a model with fields at `k` points.
FlangeErrorCovariance flange_error_covariance_of_model(const nlohmann::json& c, std::size_t k, const std::string& source) {
  const std::string expected = "member \"flange_error_covariance\": expected {\"field_covariance_mm2\": a symmetric "
                               "positive semi-definite " + std::to_string(3 * k) + " x " + std::to_string(3 * k) +
                               " matrix (3 rows per point with a field, " + std::to_string(k) +
                               " here) below 1 mm², \"mean_field_variance_mm2\": a positive number, \"poses\": count}, got ";
  FlangeErrorCovariance f;
  const std::optional<Eigen::MatrixXd> matrix =
      c.is_object() && c.contains("field_covariance_mm2")
          ? square_matrix_of(c["field_covariance_mm2"], static_cast<Eigen::Index>(3 * k))
          : std::nullopt;
  bool valid = k >= 2 && matrix && c.contains("mean_field_variance_mm2") && c["mean_field_variance_mm2"].is_number() &&
               c.contains("poses") && c["poses"].is_number_unsigned();
  if (valid) {
    f.field_covariance_mm2 = *matrix;
    f.mean_field_variance_mm2 = c["mean_field_variance_mm2"].get<double>();
    f.poses = c["poses"].get<std::size_t>();
    const Eigen::MatrixXd& m = f.field_covariance_mm2;
    const double largest = m.cwiseAbs().maxCoeff();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m, Eigen::EigenvaluesOnly);
    valid = m.allFinite() && (m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * largest &&
            eig.eigenvalues().minCoeff() >= -1e-9 * largest && largest < 1.0 &&
            std::isfinite(f.mean_field_variance_mm2) && f.mean_field_variance_mm2 > 0.0;
  }
  if (!valid) fail_model(source, expected + c.dump());
  return f;
}

/// Member "rotation_calibration" of a model with fields at `fielded_points` points.
RotationCalibration rotation_calibration_of_model(const nlohmann::json& c, std::size_t fielded_points,
                                                  const std::string& source) {
  const std::string expected = "member \"rotation_calibration\": expected {\"flange_covariance_rad2\": a symmetric "
                               "positive definite 3 x 3 matrix below 0.01 rad² (5.7 deg sd), "
                               "\"mean_independent_trace_rad2\": a positive number, \"poses\": count}, got ";
  RotationCalibration r;
  const std::optional<Eigen::MatrixXd> matrix =
      c.is_object() && c.contains("flange_covariance_rad2") ? square_matrix_of(c["flange_covariance_rad2"], 3) : std::nullopt;
  bool valid = matrix && c.contains("mean_independent_trace_rad2") && c["mean_independent_trace_rad2"].is_number() &&
               c.contains("poses") && c["poses"].is_number_unsigned();
  if (valid) {
    r.flange_covariance_rad2 = *matrix;
    r.mean_independent_trace_rad2 = c["mean_independent_trace_rad2"].get<double>();
    r.poses = c["poses"].get<std::size_t>();
    const Eigen::Matrix3d& m = r.flange_covariance_rad2;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m, Eigen::EigenvaluesOnly);
    valid = m.allFinite() && (m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * m.cwiseAbs().maxCoeff() &&
            eig.eigenvalues().minCoeff() > 0.0 && eig.eigenvalues().maxCoeff() < 0.01 &&
            std::isfinite(r.mean_independent_trace_rad2) && r.mean_independent_trace_rad2 > 0.0;
  }
  if (!valid) fail_model(source, expected + c.dump());
  if (fielded_points < 3)
    fail_model(source, "member \"rotation_calibration\": the model has fields at fewer than three points on the flange");
  return r;
}

Registration nominal_registration_of_model(const nlohmann::json& r, const std::string& source) {
  try {
    return compensation::registration_from_json(r, source);
  } catch (const InputError& e) {
    // The reader names "registration.<member>"; this is the other one.
    std::string what = e.what();
    if (const auto at = what.find("\"registration"); at != std::string::npos) what.insert(at + 1, "nominal_");
    throw InputError(what, source);
  }
}

/// Member "credible_range": its centre has as many values as the field (of kind `kind`, when the
/// model has one) predicts.
CredibleRange credible_range_of_model(const nlohmann::json& c, bool has_field, std::string_view kind,
                                      const std::string& source) {
  CredibleRange r;
  if (!c.is_object() || !c.contains("center_mm") || !c["center_mm"].is_array() || !c.contains("radius_mm") ||
      !c["radius_mm"].is_number())
    fail_model(source, "member \"credible_range\": expected {\"center_mm\": [1 or 3 numbers], \"radius_mm\": number}");
  for (const auto& v : c["center_mm"]) {
    if (!v.is_number()) fail_model(source, "member \"credible_range.center_mm\": expected numbers");
    r.center_mm.push_back(v.get<double>());
  }
  r.radius_mm = c["radius_mm"].get<double>();
  if ((r.center_mm.size() != 1 && r.center_mm.size() != 3) || !(r.radius_mm >= 0.0))
    fail_model(source, "member \"credible_range\": expected 1 or 3 centre values and a radius >= 0");
  const std::size_t dims = kind.starts_with("distance") ? 1 : 3;
  if (has_field && r.center_mm.size() != dims)
    fail_model(source, "member \"credible_range.center_mm\": " + std::to_string(r.center_mm.size()) +
                           " values, but a \"" + std::string(kind) + "\" field predicts " + std::to_string(dims) +
                           " (a " + (dims == 1 ? "distance error" : "3-D error") + ")");
  for (double value : r.center_mm)
    if (!std::isfinite(value)) fail_model(source, "member \"credible_range.center_mm\": not finite");
  return r;
}

/// A point on the flange (tool_point_mm, reflector_mm): 3 finite numbers, or none when absent.
std::optional<Eigen::Vector3d> flange_point_of_model(const nlohmann::json& j, const char* key, const std::string& source) {
  if (!j.contains(key)) return std::nullopt;
  const auto& v = j[key];
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    fail_model(source, std::string("member \"") + key + "\": expected 3 numbers (mm, flange frame)");
  const Eigen::Vector3d p(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (!p.allFinite()) fail_model(source, std::string("member \"") + key + "\": not finite");
  return p;
}

/// Members "working_tool" and "working_tool_located" (j holds "working_tool").
void read_working_tool(const nlohmann::json& j, const std::string& source, std::optional<Eigen::Isometry3d>& tool,
                       bool& located) {
  const nlohmann::json& t = j["working_tool"];
  // The model file states every member (to_json writes all six): one missing is a hand edit, and a
  // default of 0 would turn the tool without a word (a robot JSON's tool may leave them out).
  if (t.is_object())
    for (const char* key : {"x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"})
      if (!t.contains(key))
        fail_model(source, std::string("member \"working_tool\".") + key +
                               ": missing (a model file states all six of x_mm, y_mm, z_mm, rx_deg, ry_deg, rz_deg)");
  tool = robot::detail::json_pose(t, "working_tool", source);
  if (j.contains("working_tool_located")) {
    if (!j["working_tool_located"].is_boolean()) fail_model(source, "member \"working_tool_located\": expected true or false");
    located = j["working_tool_located"].get<bool>();
  }
  try {
    check_tool_point(*tool, "member \"working_tool\"");
  } catch (const ArgumentError& e) {
    fail_model(source, e.what());
  }
}

/// Member "tool_point_correction": the residual of the located working tool's readings, which
/// applies at that tool only.
std::shared_ptr<const ToolPointCorrection> tool_point_correction_of_model(
    const nlohmann::json& c, const std::optional<Eigen::Isometry3d>& working_tool, const std::string& source) {
  auto correction = std::make_shared<const ToolPointCorrection>(ToolPointCorrection::from_json(c, source));
  // It is the residual of the working tool's readings against this model: at another point it
  // belongs to another model (or the file was edited).
  if (!working_tool || (working_tool->translation() - correction->point_mm()).norm() > kSameFlangePointMm)
    fail_model(source, "member \"tool_point_correction\" is for the point (" + format_number(correction->point_mm().x()) +
                           ", " + format_number(correction->point_mm().y()) + ", " +
                           format_number(correction->point_mm().z()) + ") mm, but the model's working_tool is " +
                           (working_tool ? "elsewhere" : "not set") +
                           ": it holds the residual of the located point's readings and applies there only "
                           "(run locate-tool again rather than editing either)");
  return correction;
}

std::vector<JointVector> data_joints_of_model(const nlohmann::json& q, const std::string& source) {
  if (!q.is_array()) fail_model(source, "member \"data_joints_deg\": expected an array of 6-number arrays");
  std::vector<JointVector> joints;
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!q[i].is_array() || q[i].size() != 6)
      fail_model(source, "member \"data_joints_deg\"[" + std::to_string(i) + "]: expected 6 numbers");
    JointVector v;
    for (int k = 0; k < 6; ++k) {
      if (!q[i][static_cast<std::size_t>(k)].is_number())
        fail_model(source, "member \"data_joints_deg\"[" + std::to_string(i) + "]: expected 6 numbers");
      v[k] = q[i][static_cast<std::size_t>(k)].get<double>();
    }
    joints.push_back(v);
  }
  return joints;
}

}  // namespace

CompensationModel CompensationModel::from_json(const nlohmann::json& j, const std::string& source) {
  const CompensationMethod method = method_of_model(j, source);
  if (!j.contains("command_model")) fail_model(source, "member \"command_model\" is missing");
  MdhModel command = robot::detail::json_nested_model(j, "command_model", source);
  auto field = field_of_model(j, method, source);
  const std::string_view kind = field ? std::string_view(j["field"]["kind"].get_ref<const std::string&>()) : "";
  CompensationModel model(method, std::move(command), std::move(field));
  if (j.contains("nominal_model")) {
    model.nominal_model_ = robot::detail::json_nested_model(j, "nominal_model", source);
    // The command model is the nominal one calibrated: millimetres and tenths of a degree apart.
    // The stored samples are checked against the nominal model below, so a command model of
    // another robot (a UR5e inside a KR16 model) passed and gave 126/126 rows ok, 1,066 mm off.
    if (const auto why = robot::differs_beyond_calibration(*model.nominal_model_, model.command_model_))
      fail_model(source, "member \"command_model\" ('" + model.command_model_.name() + "') is not a calibration of the "
                         "\"nominal_model\" ('" + model.nominal_model_->name() + "'): " + *why +
                         "; the file was edited or mixed from two models: refit it with 'errfield fit'");
  }
  model.registration_ = compensation::find_registration(j, source);
  read_strings(j, "notes", source, model.notes_);
  read_strings(j, "excluded_rows", source, model.excluded_rows_);
  if (j.contains("flange_points"))
    model.flange_points_ = flange_points_of_model(j["flange_points"], model.field_ != nullptr, kind, source);
  if (j.contains("calibration_leverage")) {
    if (!is_calibrated(method))
      fail_model(source, "member \"calibration_leverage\": only calibrated models (kinematic, kinematic+kriging) have one");
    model.calibration_leverage_ = CalibrationLeverage::from_json(j["calibration_leverage"], source);
  }
  if (j.contains("orientation_residual"))
    model.measured_orientation_ = orientation_residual_of_model(j["orientation_residual"], source);
  check_flange_points(model, source,
                      j.contains("working_tool") && j.contains("working_tool_located") && j["working_tool_located"] == true);
  if (j.contains("flange_error_covariance"))
    model.flange_error_covariance_ =
        flange_error_covariance_of_model(j["flange_error_covariance"], model.fielded_points().size(), source);
  if (j.contains("rotation_calibration"))
    model.rotation_calibration_ =
        rotation_calibration_of_model(j["rotation_calibration"], model.fielded_points().size(), source);
  if (j.contains("nominal_registration"))
    model.nominal_registration_ = nominal_registration_of_model(j["nominal_registration"], source);
  if (j.contains("credible_range")) {
    model.credible_ = credible_range_of_model(j["credible_range"], model.field_ != nullptr, kind, source);
  } else if (model.field_) {
    // Without it every prediction, however far beyond the fitted errors, would be "credible"
    // (errfield fit always writes it).
    fail_model(source, "member \"credible_range\" is missing: a model with a field must say which errors it was "
                       "fitted on (errfield fit writes it); refit the model with 'errfield fit'");
  }
  if (model.field_) check_stored_samples(model, j["field"], source);
  // The tool point compensate aims and the reflector measured (flange frame).
  model.tool_point_ = flange_point_of_model(j, "tool_point_mm", source);
  model.reflector_ = flange_point_of_model(j, "reflector_mm", source);
  if (model.tool_point_ && !is_calibrated(method))
    fail_model(source, "member \"tool_point_mm\": only calibrated models (kinematic, kinematic+kriging) aim a tool "
                       "point on their calibrated flange; method \"" + std::string(method_name(method)) + "\" has none");
  if (j.contains("working_tool")) read_working_tool(j, source, model.working_tool_, model.working_tool_located_);
  if (j.contains("tool_point_correction"))
    model.tool_point_correction_ = tool_point_correction_of_model(j["tool_point_correction"], model.working_tool_, source);
  if (j.contains("joint_error_functions")) {
    // Evaluated through the calibrated command model's Jacobian and added to a field's prediction:
    // meaningless for any other method (a hand-edited or mixed file).
    if (method != CompensationMethod::kinematic_kriging)
      fail_model(source, "member \"joint_error_functions\": only kinematic+kriging models carry joint error functions; "
                         "method \"" + std::string(method_name(method)) + "\" has none; refit the model with 'errfield fit'");
    model.joint_functions_ = JointErrorFunctions::from_json(j["joint_error_functions"], source);
    model.set_function_rows_at_samples();
  }
  if (j.contains("data_joints_deg")) model.data_joints_ = data_joints_of_model(j["data_joints_deg"], source);
  return model;
}

}  // namespace errfield::compensation
