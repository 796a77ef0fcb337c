// fit / predict / compensate / validate on tables, shared by the CLI (src/cli/cmd_*.cpp) and the
// Python module: the checks and the output columns live here once.

#include "errfield/compensation/pipeline.hpp"

#include "errfield/number_format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "errfield/compensation/model/error_ball.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/model/registration.hpp"
#include "errfield/compensation/validation/rotation_validation.hpp"
#include "errfield/compensation/tools/target_ik.hpp"
#include "errfield/error.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "errfield/robot/arm_configuration.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::compensation {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

OutputColumn numbers(std::string name, std::vector<double> v) { return {std::move(name), std::move(v), {}}; }
OutputColumn words(std::string name, std::vector<std::string> v) { return {std::move(name), {}, std::move(v), true}; }

/// "ok", or the status of a compensation whose joints swing far more than its move warrants
/// (kSingularSwingDegPerMm), named after the flag of the nominal configuration that is at its
/// boundary: a singular configuration lets a small move of the tool point turn joints by tens of
/// degrees (pipeline.hpp).
std::string singular_swing(const robot::MdhModel& nominal, const robot::JointVector& q_nominal_deg,
                           const robot::JointVector& q_command_deg, double move_mm) {
  const double swing_deg = (q_command_deg - q_nominal_deg).cwiseAbs().maxCoeff();
  if (swing_deg <= std::max(kSingularSwingFloorDeg, kSingularSwingDegPerMm * move_mm)) return "ok";
  const robot::ArmConfiguration c = robot::arm_configuration(nominal, q_nominal_deg);
  return c.wrist == 0 ? "wrist-singular" : c.elbow == 0 ? "elbow-singular" : c.shoulder == 0 ? "shoulder-singular"
                                                                                           : "near-singular";
}

}  // namespace

FitOptions fit_options_from_text(const FitOptionText& a) {
  FitOptions o;
  // Every kriging method was more accurate on held-out points in joint space than in task space
  // (docs/robot.md, "Which method"): the error of a serial arm follows its joints.
  o.choose_method = a.method == "auto";
  if (!o.choose_method) o.method = method_from_name(a.method);
  o.space = a.space == "auto" ? FieldSpace::joint : field_space_from_name(a.space);
  o.idw_power = a.power;
  o.base = a.base;
  o.region_margin = a.region_margin;
  if (!a.model.empty() && a.model != "auto") {
    // A bare family (--model mat) is estimated; anything else is a model given in full.
    if (auto family = parse_field_model_family(a.model)) o.model_family = *family;
    else o.model = load_variogram_model(a.model);
  }
  if (!a.calibration.empty()) o.calibration_data = calibration_data_from_name(a.calibration);
  if (!a.robust.empty()) {
    if (a.robust != "none" && a.robust != "igg3")
      throw ArgumentError("--robust: expected 'none' or 'igg3', got '" + a.robust + "'");
    o.calibration.robust.enabled = a.robust == "igg3";
  }
  o.calibration.max_condition_number = a.max_condition;
  o.outlier_limit = a.outlier_limit;
  if (!a.variance_calibration.empty()) o.variance_calibration = variance_calibration_from_name(a.variance_calibration);
  o.calibration.validate();
  if (a.kind == "universal1" || a.kind == "universal2") {
    o.kind = KrigingKind::Universal;
    o.drift_order = a.kind == "universal1" ? 1 : 2;
  } else if (a.kind != "ordinary") {
    throw ArgumentError("--kind: '" + a.kind + "'; expected ordinary, universal1 or universal2");
  }
  return o;
}

void check_table_fits_robot(const CsvTable& table, const robot::MdhModel& robot, const robot::RobotOrigin& origin,
                            double max_registration_rms_mm) {
  const std::vector<std::string> q_cols{"q1", "q2", "q3", "q4", "q5", "q6"};
  for (const auto& c : q_cols)
    if (!table.has_column(c)) return;
  // Readings of several points on the flange (column 'reflector', as fit takes them): x,y,z are
  // each point's nominal position, which only the tool point's rows share with the robot JSON, so
  // each label's readings are registered alone, with their own reflector offset (a pool of such
  // rows was refused by plan as "not the FK of the robot").
  const bool several_points = several_reflector_labels(table);
  if (!several_points) robot::check_nominal_positions(table, robot, origin.given);
  if (!table.has_column("mx") || !table.has_column("my") || !table.has_column("mz")) return;
  const std::size_t mcol[3] = {table.column_index("mx"), table.column_index("my"), table.column_index("mz")};
  std::map<std::string, std::vector<robot::PositionMeasurement>> by_label;
  for (std::size_t i = 0; i < table.row_count(); ++i) {
    const auto& row = table.row(i);
    if (row[mcol[0]].empty() || row[mcol[1]].empty() || row[mcol[2]].empty()) continue;
    robot::PositionMeasurement m;
    for (int k = 0; k < robot::kJointCount; ++k)
      m.q_deg[k] = table.numeric_cell(i, table.column_index(q_cols[static_cast<std::size_t>(k)]));
    for (int k = 0; k < 3; ++k) m.measured_mm[k] = table.numeric_cell(i, mcol[k]);
    by_label[several_points ? std::string(row[table.column_index("reflector")]) : std::string()].push_back(m);
  }
  for (const auto& [label, data] : by_label)
    (void)robot::check_tracker_registration(
        robot, data, several_points ? table.source() + " (reflector " + label + ")" : table.source(), origin,
        max_registration_rms_mm);
}

TableFit fit_table(const robot::MdhModel& robot, const CsvTable& table, const FitTableOptions& options) {
  // Misuse is an error with a reason (robot/input_checks.hpp), before any fitting.
  robot::check_distance_columns(table, &robot, options.fixed_bases);
  const robot::RobotOrigin origin{options.robot_given, ""};
  // Readings of several points on the flange: x,y,z are each point's nominal position, which only
  // the tool point's rows share with the robot JSON; each label's registration checks the robot.
  const bool several_points = several_reflector_labels(table);
  if (!several_points) robot::check_nominal_positions(table, robot, origin.given);
  const MeasurementSet data = MeasurementSet::from_table(table, robot, options.fixed_bases, true);
  if (options.on_measurements_read) options.on_measurements_read();
  FitOptions o = options.fit;
  // --method auto: the method the data support best (after the input checks, before the
  // method-specific ones below).
  std::optional<std::string> chosen;
  if (o.choose_method) {
    const MethodChoice c = choose_method(data);
    o.choose_method = false;
    o.method = c.method;
    chosen = "method auto: " + std::string(method_name(c.method)) + " (" + c.reason + ")";
  }
  refuse_several_points_for(data, o.method);
  // The tracker readings must be this robot's positions (the check of calibrate, validate, predict
  // and compensate), where the method uses them: a distance method ignores mx,my,mz.
  const bool uses_readings =
      o.method == CompensationMethod::position_idw || o.method == CompensationMethod::vector_kriging ||
      o.method == CompensationMethod::kinematic_kriging ||
      (o.method == CompensationMethod::kinematic && o.calibration_data != CalibrationData::distance);
  if (uses_readings && !data.measured_mm.empty()) {
    // Each point on the flange on its own (one label's readings are one rigid point's).
    const std::vector<std::string> labels = several_points ? data.reflector_labels() : std::vector<std::string>{""};
    for (const std::string& label : labels) {
      std::vector<robot::PositionMeasurement> readings;
      for (std::size_t i = 0; i < data.q_deg.size(); ++i)
        if (!several_points || data.reflector[i] == label) readings.push_back({data.q_deg[i], data.measured_mm[i]});
      (void)robot::check_tracker_registration(robot, readings,
                                              several_points ? table.source() + " (reflector '" + label + "')"
                                                             : table.source(),
                                              origin, options.max_registration_rms_mm);
    }
  }
  const bool from_distances = o.method == CompensationMethod::vector_kriging && data.distance_mm.size() >= 3;
  if (from_distances)
    robot::check_error_vectors_from_distances(!data.base_q_deg.empty(), !data.measured_mm.empty(), table.source());
  if ((o.method == CompensationMethod::position_idw || o.method == CompensationMethod::vector_kriging) &&
      !data.measured_mm.empty() && data.measured_mm.size() >= 3 && (!from_distances || !data.base_q_deg.empty())) {
    // The registration these methods fit, checked before the (possibly long) fit.
    const auto reg = fit_registration(data.measured_mm, data.nominal_mm);
    robot::check_registration_residual(reg.residual_rms_mm, data.measured_mm.size(), table.source(),
                                       "registration tracker -> robot", options.max_registration_rms_mm);
  }
  TableFit fit{fit_compensation_model(robot, data, o), data.q_deg.size()};
  if (chosen) fit.result.notes.insert(fit.result.notes.begin(), *chosen);
  // The file says what fit noted (docs/robot.md): the rows it excluded, the method and why.
  fit.result.model = fit.result.model.with_notes(fit.result.notes);
  const FitResult& r = fit.result;
  if (r.registration)
    robot::check_registration_residual(r.registration->residual_rms_mm, data.measured_mm.size(), table.source(),
                                       "registration tracker -> robot", options.max_registration_rms_mm);
  return fit;
}

StepColumns predict_columns(const CompensationModel& model, std::span<const robot::JointVector> q, bool extrapolate) {
  const std::size_t n = q.size();
  const bool tracker = model.registration().has_value();
  std::vector<std::vector<double>> cols(9, std::vector<double>(n, kNaN));  // see `names` below
  // Models that predict the flange's orientation: the scored tool frame's orientation (robot frame,
  // fixed-axis XYZ, deg) and the 95 % radius of its rotation error (mdeg).
  const bool orientation = model.fielded_points().size() >= 3 && model.rotation_calibration().has_value();
  std::vector<std::vector<double>> rotation_cols(orientation ? 4 : 0, std::vector<double>(n, kNaN));
  std::vector<std::string> status(n);
  bool any_variance = false, any_radius = false;
  StepColumns out;
  for (std::size_t i = 0; i < n; ++i) {
    const PointPrediction p = predict_position(model, q[i], extrapolate);
    status[i] = std::string(status_name(p.status));
    if (!p.ok() && p.status != PredictionStatus::extrapolated) {
      ++out.refused;  // no position for a prediction the model cannot vouch for
      continue;
    }
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(k)][i] = p.position_mm[k];
    if (p.tracker_mm)
      for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(3 + k)][i] = (*p.tracker_mm)[k];
    cols[6][i] = p.error.predictive_variance_mm2();
    cols[7][i] = p.error.variance_mm2;
    cols[8][i] = radius_with_probability(0.95, p.error.axis_variance_mm2);
    any_variance = any_variance || std::isfinite(p.error.variance_mm2);
    any_radius = any_radius || std::isfinite(cols[8][i]);
    if (orientation) {
      const std::optional<RotationPrediction> w = model.predict_rotation(q[i]);
      if (!w || w->status != "ok") continue;
      const Eigen::Matrix3d tool = robot::forward_kinematics(model.scored_model(), q[i]).linear();
      const Eigen::Vector3d& v = w->rotation_rad;
      const Eigen::Vector3d rpy = robot::rpy_deg_from_rotation(
          Eigen::AngleAxisd(v.norm(), v.norm() > 0 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX()).toRotationMatrix() * tool);
      for (int k = 0; k < 3; ++k) rotation_cols[static_cast<std::size_t>(k)][i] = rpy[k];
      rotation_cols[3][i] = kMdegPerRad * w->radius95_rad();
    }
  }
  const char* names[] = {"px", "py", "pz", "tx", "ty", "tz", "var_mm2", "var_field_mm2", "r95_mm"};
  for (std::size_t c = 0; c < 9; ++c) {
    if (c >= 3 && c < 6 && !tracker) continue;
    if ((c == 6 || c == 7) && !any_variance) continue;
    if (c == 8 && !any_radius) continue;
    out.columns.push_back(numbers(names[c], std::move(cols[c])));
  }
  const char* rotation_names[] = {"prx", "pry", "prz", "r95_w_mdeg"};
  for (std::size_t c = 0; c < rotation_cols.size(); ++c) out.columns.push_back(numbers(rotation_names[c], std::move(rotation_cols[c])));
  out.columns.push_back(words("status", std::move(status)));
  return out;
}

double default_max_correction_mm(const CompensationModel& model) {
  return std::max(kMaxCorrectionFactor * model.largest_training_correction_mm(), kMaxCorrectionFloorMm);
}

std::vector<robot::JointVector> seed_rows_of(const CsvTable& table) {
  std::vector<robot::JointVector> seeds;
  if (!table.has_column("sq1")) return seeds;
  std::vector<std::size_t> col;
  for (const char* c : {"sq1", "sq2", "sq3", "sq4", "sq5", "sq6"}) col.push_back(table.column_index(c));
  for (std::size_t i = 0; i < table.row_count(); ++i) {
    robot::JointVector q = robot::JointVector::Constant(std::numeric_limits<double>::quiet_NaN());  // no seed
    bool empty = true;
    for (std::size_t k = 0; k < col.size(); ++k) empty = empty && table.row(i)[col[k]].empty();
    if (!empty)  // numeric_cell names row and column of an empty or non-numeric cell
      for (std::size_t k = 0; k < col.size(); ++k) q[static_cast<Eigen::Index>(k)] = table.numeric_cell(i, col[k]);
    seeds.push_back(q);
  }
  return seeds;
}

namespace {

/// Each target's nominal joints and what the compensation must keep: whether they were found, why
/// not, the arm configuration the row must stay on and where that configuration came from.
struct NominalTargets {
  std::vector<robot::JointVector> q_deg;
  std::vector<bool> ok;
  std::vector<std::string> status;
  // The arm configuration each row must keep: its seed's, or the training sample's its pose path
  // started from, or that of the given nominal joints. A solver may land on another solution of the
  // same pose (the wrist flipped: q4, q6 180 deg away, q5 negated) without crossing a singularity
  // on its path; a robot sent those joints would flip its wrist between moves.
  std::vector<std::optional<robot::ArmConfiguration>> wanted;
  std::vector<std::string> config_source;

  explicit NominalTargets(std::size_t n) : q_deg(n), ok(n, true), status(n), wanted(n), config_source(n) {}
};

NominalTargets given_joint_targets(const robot::MdhModel& nominal, const CompensationTargets& targets) {
  const std::size_t n = targets.joints_deg.size();
  NominalTargets out(n);
  out.q_deg = targets.joints_deg;
  for (std::size_t i = 0; i < n; ++i) {
    if (out.q_deg[i].allFinite()) out.wanted[i] = robot::arm_configuration(nominal, out.q_deg[i]);
    out.config_source[i] = kConfigSourceGiven;
    if (targets.config) {
      // Given joints on another configuration than the pinned one are refused below.
      if (out.wanted[i] && !out.wanted[i]->compatible_with(*targets.config)) out.status[i] = "config-change";
      out.wanted[i] = targets.config;
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (out.status[i] == "config-change") out.ok[i] = false;
  return out;
}

/// Pose targets solved on the branch of their seed, of the pinned configuration's training poses,
/// or of the nearest training pose (`reference`: the model's training joints; older model files
/// have none: multistart).
NominalTargets solved_pose_targets(const robot::MdhModel& nominal, const CompensationTargets& targets,
                                   const std::vector<robot::JointVector>& reference) {
  using namespace robot;
  const std::size_t n = static_cast<std::size_t>(targets.poses.rows());
  NominalTargets out(n);
  // --config: pose paths start from the training samples on that configuration only.
  std::vector<JointVector> pinned_reference;
  if (targets.config) {
    for (const JointVector& q : reference)
      if (arm_configuration(nominal, q).compatible_with(*targets.config)) pinned_reference.push_back(q);
  }
  const std::vector<JointVector>& start_from = targets.config ? pinned_reference : reference;
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = targets.poses.row(static_cast<Eigen::Index>(i));
    std::optional<JointVector> seed = targets.seed_deg;
    if (!targets.seed_rows_deg.empty() && targets.seed_rows_deg[i].allFinite()) seed = targets.seed_rows_deg[i];
    if (targets.config && !seed && start_from.empty())
      throw ArgumentError("--config " + targets.config->to_string() + ": none of the model's " +
                          std::to_string(reference.size()) +
                          " training poses is on this configuration, so pose targets have no start on it; give "
                          "seed joints on it per row (columns sq1..sq6) or --seed");
    const BranchIkResult ik = solve_on_branch(nominal, to_isometry({r[0], r[1], r[2], r[3], r[4], r[5]}), start_from, seed);
    out.q_deg[i] = ik.ik.q_deg;
    out.ok[i] = ik.ok();
    out.status[i] = ik.branch_changed ? "branch-change" : ik.ik.ok() ? "" : to_string(ik.ik.status);
    out.config_source[i] = targets.config ? kConfigSourcePinned : seed ? kConfigSourceSeed
                           : ik.start_sample ? kConfigSourceNearestTraining : kConfigSourceNone;
    if (targets.config) out.wanted[i] = targets.config;
    else if (seed) out.wanted[i] = arm_configuration(nominal, *seed);
    else if (ik.start_sample) out.wanted[i] = arm_configuration(nominal, start_from[*ik.start_sample]);
    if (out.ok[i] && out.wanted[i] && !arm_configuration(nominal, out.q_deg[i]).compatible_with(*out.wanted[i])) {
      out.ok[i] = false;
      out.status[i] = "config-change";
    }
  }
  return out;
}

/// The compensation step's columns, one value per target (NaN or empty where a row is refused).
struct CompensationColumns {
  std::vector<std::vector<double>> numbers;    // kCompensationColumnNames' order
  std::vector<std::vector<double>> rotation;   // kRotationColumnNames' order; none without orientation
  std::vector<std::string> config, status;

  CompensationColumns(std::size_t n, bool orientation)
      : numbers(31, std::vector<double>(n, kNaN)),
        rotation(orientation ? 7 : 0, std::vector<double>(n, kNaN)),
        config(n),
        status(n) {}
};

constexpr const char* kCompensationColumnNames[] = {
    "nq1", "nq2", "nq3", "nq4", "nq5", "nq6", "nx", "ny", "nz", "pred_dx", "pred_dy", "pred_dz",
    "pred_dl", "var_mm2", "p_inside", "cmd_x", "cmd_y", "cmd_z", "cq1", "cq2", "cq3", "cq4",
    "cq5", "cq6", "var_field_mm2", "r95_mm", "total_dx", "total_dy", "total_dz", "total_mm",
    "move_mm"};
constexpr const char* kRotationColumnNames[] = {"pred_wx_mdeg", "pred_wy_mdeg", "pred_wz_mdeg", "r95_w_mdeg",
                                                "total_wx_mdeg", "total_wy_mdeg", "total_wz_mdeg"};

/// The prediction and the compensation of row i, whether or not it is then sent.
void put_compensation(CompensationColumns& out, std::size_t i, const robot::JointVector& q,
                      const Eigen::Vector3d& nominal_mm, const CompensatedTarget& c) {
  std::vector<std::vector<double>>& cols = out.numbers;
  for (int k = 0; k < 6; ++k) cols[static_cast<std::size_t>(k)][i] = q[k];
  for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(6 + k)][i] = nominal_mm[k];
  for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(9 + k)][i] = c.prediction.position_error_mm[k];
  cols[12][i] = c.prediction.distance_error_mm;
  cols[13][i] = c.prediction.predictive_variance_mm2();
  cols[14][i] = c.p_within_tolerance;
  cols[24][i] = c.prediction.variance_mm2;
  cols[25][i] = radius_with_probability(0.95, c.prediction.axis_variance_mm2);
  for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(15 + k)][i] = c.command_position_mm[k];
  for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(26 + k)][i] = c.total_error_mm[k];
  cols[29][i] = c.total_error_mm.norm();
  cols[30][i] = c.move_mm;
  if (!out.rotation.empty() && c.rotation) {
    for (int k = 0; k < 3; ++k) out.rotation[static_cast<std::size_t>(k)][i] = kMdegPerRad * c.rotation->rotation_rad[k];
    out.rotation[3][i] = kMdegPerRad * c.rotation->radius95_rad();
    for (int k = 0; k < 3; ++k) out.rotation[static_cast<std::size_t>(4 + k)][i] = kMdegPerRad * c.total_rotation_error_rad[k];
  }
}

/// Why the compensated joints of a predicted target are not sent, or "ok".
std::string compensation_status(const CompensationModel& model, const robot::MdhModel& nominal,
                                const robot::JointVector& q, const CompensatedTarget& c, double ceiling,
                                const std::optional<robot::ArmConfiguration>& wanted) {
  using namespace robot;
  return !c.prediction.inside_region ? "outside-region"
         : !c.prediction.credible ? "not-credible"
         : !c.prediction.orientation_supported ? std::string(status_name(PredictionStatus::orientation_unknown))
         : !c.prediction.calibration_supported ? std::string(status_name(PredictionStatus::calibration_extrapolated))
         : c.ik_status != IkStatus::converged ? std::string("ik-") + to_string(c.ik_status)
         : robot::joint_outside_limits(c.q_command_deg, model.command_model()) ? std::string(status_name(PredictionStatus::outside_limits))
         // A move far beyond what the model ever predicted on its own data is a wrong robot,
         // tool or model, not a correction (NaN: no move known, never ok either).
         : !(c.move_mm <= ceiling) ? "correction-too-large"
         : wanted && !arm_configuration(nominal, c.q_command_deg).compatible_with(*wanted) ? "config-change"
         : singular_swing(nominal, q, c.q_command_deg, c.move_mm);
}

/// Compensates every target the nominal stage found, counting the refusals in `out`.
CompensationColumns compensate_targets(const CompensationModel& model, const robot::MdhModel& nominal,
                                       const NominalTargets& targets, double tolerance_mm, double ceiling,
                                       StepColumns& out) {
  const std::size_t n = targets.q_deg.size();
  // Models that predict the flange's orientation: its predicted rotation, 95 % radius and the whole
  // orientation error (mdeg, robot frame).
  const bool orientation = model.fielded_points().size() >= 3 && model.rotation_calibration().has_value();
  CompensationColumns cols(n, orientation);
  std::vector<std::string>& status = cols.status;
  for (std::size_t i = 0; i < n; ++i) {
    const robot::JointVector& q = targets.q_deg[i];
    if (!targets.ok[i]) {
      const std::string& why = targets.status[i];
      status[i] = why == "branch-change" || why == "config-change" ? why : "unreachable";
      ++out.refused;
      continue;
    }
    if (robot::joint_outside_limits(q, nominal)) {
      status[i] = std::string(status_name(PredictionStatus::outside_limits));  // a target the robot cannot take is not compensated
      ++out.refused;
      continue;
    }
    const CompensatedTarget c = model.compensate_joints(nominal, q, tolerance_mm);
    put_compensation(cols, i, q, robot::forward_position(nominal, q), c);
    if (c.prediction.inside_region && !(c.prediction.position_error_mm.allFinite() && c.command_position_mm.allFinite())) {
      // The field gave no number here (e.g. an overflow): never an IK failure's name, never ok.
      status[i] = "no-prediction";
      ++out.no_prediction;
      ++out.refused;
      continue;
    }
    status[i] = compensation_status(model, nominal, q, c, ceiling, targets.wanted[i]);
    out.too_large += status[i] == "correction-too-large";
    out.singular += status[i].ends_with("singular");
    if (status[i] != "ok") {
      ++out.refused;
      continue;  // compensated joints stay empty: nothing is sent for a refused target
    }
    for (int k = 0; k < 6; ++k) cols.numbers[static_cast<std::size_t>(18 + k)][i] = c.q_command_deg[k];
    cols.config[i] = robot::arm_configuration(nominal, c.q_command_deg).to_string();
    out.largest_move_mm = std::max(out.largest_move_mm, c.move_mm);
  }
  return cols;
}

}  // namespace

StepColumns compensate_columns(const CompensationModel& model, const robot::MdhModel& nominal,
                               const CompensationTargets& targets, double tolerance_mm, double max_correction_mm) {
  using namespace robot;
  // p_inside is P(|error| <= tolerance): 0, a negative or a NaN tolerance makes it meaningless.
  if (!(std::isfinite(tolerance_mm) && tolerance_mm > 0.0))
    throw ArgumentError("tolerance: " + format_number(tolerance_mm) + "; expected a finite tolerance > 0 (mm)");
  if (!(std::isfinite(max_correction_mm) && max_correction_mm >= 0.0))
    throw ArgumentError("max-correction: " + format_number(max_correction_mm) +
                        "; expected a finite ceiling > 0 (mm), or 0 for the default");
  const double ceiling = max_correction_mm > 0.0 ? max_correction_mm : default_max_correction_mm(model);
  const bool joints = !targets.joints_deg.empty() || targets.poses.rows() == 0;
  if (!joints && targets.poses.cols() != 6)
    throw ArgumentError("poses: " + std::to_string(targets.poses.cols()) + " columns; expected x,y,z,rx,ry,rz");
  const std::size_t n = joints ? targets.joints_deg.size() : static_cast<std::size_t>(targets.poses.rows());
  if (!targets.seed_rows_deg.empty() && (joints || targets.seed_rows_deg.size() != n))
    throw ArgumentError("seed rows: " + std::to_string(targets.seed_rows_deg.size()) + " for " + std::to_string(n) +
                        (joints ? " joint targets; only pose targets take seeds" : " pose targets"));
  // The branch pose targets are solved on: the model's training joints (older model files have
  // none: multistart).
  NominalTargets nominal_targets =
      joints ? given_joint_targets(nominal, targets) : solved_pose_targets(nominal, targets, model.data_joints());
  std::vector<std::string> nconfig(n);
  for (std::size_t i = 0; i < n; ++i)
    if ((nominal_targets.ok[i] || nominal_targets.status[i] == "config-change") && nominal_targets.q_deg[i].allFinite())
      nconfig[i] = arm_configuration(nominal, nominal_targets.q_deg[i]).to_string();
  StepColumns out;
  out.max_correction_mm = ceiling;
  CompensationColumns cols = compensate_targets(model, nominal, nominal_targets, tolerance_mm, ceiling, out);
  for (std::size_t c = 0; c < cols.numbers.size(); ++c)
    out.columns.push_back(numbers(kCompensationColumnNames[c], std::move(cols.numbers[c])));
  for (std::size_t c = 0; c < cols.rotation.size(); ++c)
    out.columns.push_back(numbers(kRotationColumnNames[c], std::move(cols.rotation[c])));
  out.columns.push_back(words("nconfig", std::move(nconfig)));
  out.columns.push_back(words("config", std::move(cols.config)));
  for (const std::string& w : nominal_targets.config_source) {
    auto it = std::find_if(out.config_sources.begin(), out.config_sources.end(), [&](const auto& e) { return e.first == w; });
    if (it == out.config_sources.end()) out.config_sources.emplace_back(w, 1);
    else ++it->second;
  }
  out.columns.push_back(words("config_source", std::move(nominal_targets.config_source)));
  out.columns.push_back(words("status", std::move(cols.status)));
  return out;
}

/// The rows of one reflector label of a file with several (`--reflector`, default the model's own
/// point), and the model moved to that label's point when the model located it (fit on several
/// points); the file itself when it has one label or none (`--reflector` must then match it).
CsvTable rows_of_one_reflector(const CsvTable& file, const std::string& asked, bool tool_given, CompensationModel& model,
                               const std::string& option_prefix) {
  const std::string reflector_option = option_prefix + "reflector", tool_option = option_prefix + "tool";
  if (!file.has_column("reflector")) {
    if (!asked.empty())
      throw InputError(file.source() + ": " + reflector_option + " " + asked + " but the file has no 'reflector' column", file.source(),
                       0, "reflector");
    return file;
  }
  const std::vector<CompensationModel::LabelledPoint>& points = model.flange_points();
  if (asked.empty() && !several_reflector_labels(file)) {
    // One label: the readings of one point, scored at the model's point (or --tool); the check that
    // they are of that point follows. But a label that is a further point the model located (r2 of an
    // r1+r2 model) says which point was read: scored there, as --reflector r2 would (they were
    // refused as not of the model's point, with no hint of the option).
    const std::string only = file.row_count() > 0 ? std::string(file.cell(0, file.column_index("reflector"))) : std::string();
    const bool further = !tool_given && points.size() > 1 &&
                         std::any_of(points.begin() + 1, points.end(), [&](const auto& p) { return p.label == only; });
    if (!further) return file;
    return rows_of_one_reflector(file, only, tool_given, model, option_prefix);
  }
  const std::string label = !asked.empty() ? asked : !points.empty() ? points.front().label : std::string(file.cell(0, file.column_index("reflector")));
  std::vector<std::size_t> keep;
  const std::size_t col = file.column_index("reflector");
  for (std::size_t i = 0; i < file.row_count(); ++i)
    if (file.cell(i, col) == label) keep.push_back(i);
  if (keep.empty())
    throw InputError(file.source() + ": no rows of reflector '" + label + "'" +
                         (asked.empty() ? " (the model's own point; give " + reflector_option + " LABEL)" : std::string()),
                     file.source(), 0, "reflector");
  if (keep.size() == file.row_count() && points.empty()) return file;  // one label, a one-point model
  if (points.empty())
    throw InputError(file.source() + ": readings of several points on the flange; the model was fitted at one point, "
                         "so only its own readings can be scored (keep them, or give " + reflector_option + " LABEL with " + tool_option +
                         " at that point)",
                     file.source(), 0, "reflector");
  const auto at = std::find_if(points.begin(), points.end(), [&](const auto& p) { return p.label == label; });
  if (at == points.end()) {
    std::string known;
    for (const auto& p : points) known += (known.empty() ? "'" : ", '") + p.label + "'";
    throw InputError(file.source() + ": reflector '" + label + "' is not a point the model located (it knows " + known +
                         "); locate it with 'errfield locate-tool' from readings of it, then validate that model",
                     file.source(), 0, "reflector");
  }
  if (at != points.begin()) {
    if (tool_given)
      throw ArgumentError(tool_option + " and " + reflector_option + " " + label + ": the model located '" + label + "'; give one of them");
    Eigen::Isometry3d point = model.command_model().tool();
    point.translation() = at->position_mm;
    model = model.with_working_tool(point);
  }
  return file.rows(keep);
}

TargetFrame parse_target_frame(const std::string& word, const std::string& option) {
  if (word == "robot") return TargetFrame::robot;
  if (word == "tracker") return TargetFrame::tracker;
  throw ArgumentError(option + ": '" + word + "'; expected robot (targets in the robot base frame, the default) or tracker "
                      "(targets in the frame of the tracker readings the model was fitted on)");
}

void bring_targets_to_robot_frame(CompensationTargets& targets, const CompensationModel& model, TargetFrame frame,
                                  const std::string& option, const std::string& targets_name, const std::string& model_name) {
  if (frame == TargetFrame::robot) return;
  if (!targets.joints_deg.empty())
    throw ArgumentError(option + " tracker: " + targets_name + " holds joint targets (q1..q6), which have no frame; " +
                        option + " is for pose targets x,y,z,rx,ry,rz");
  // A part measured with the tracker: the registration fit stored maps it into the frame the model's
  // robots live in (the frame the training readings were fitted in).
  if (!model.registration())
    throw ArgumentError(option + " tracker: " + model_name + " holds no tracker registration (it was fitted without "
                        "tracker positions mx,my,mz); give the targets in the robot base frame");
  if (targets.poses.rows() > 0) targets.poses = poses_in_robot_frame(*model.registration(), targets.poses);
}

void check_seed_joints(const CompensationTargets& targets, const robot::MdhModel& nominal, const CsvTable* table) {
  const robot::JointVector lo = nominal.q_min_deg(), hi = nominal.q_max_deg();
  auto limits = [&](int k) {
    return "joint " + std::to_string(k + 1) + "'s limits [" + format_number(lo[k]) + ", " + format_number(hi[k]) +
           "] deg of robot '" + nominal.name() + "'";
  };
  if (targets.seed_deg) {
    if (const auto k = robot::joint_outside_limits(*targets.seed_deg, nominal))
      throw ArgumentError("--seed: joint " + std::to_string(*k + 1) + " = " + format_number((*targets.seed_deg)[*k]) +
                          " deg is outside " + limits(*k) + "; a seed must be joints the robot can take (degrees)");
    if (targets.config && !robot::arm_configuration(nominal, *targets.seed_deg).compatible_with(*targets.config))
      throw ArgumentError("--seed is on configuration " + robot::arm_configuration(nominal, *targets.seed_deg).to_string() +
                          ", not on --config " + targets.config->to_string());
  }
  for (std::size_t i = 0; i < targets.seed_rows_deg.size(); ++i) {
    const robot::JointVector& q = targets.seed_rows_deg[i];
    if (q.array().isNaN().all()) continue;  // no seed for this row
    const std::string source = table ? table->source() : std::string("targets");
    const std::string where = table ? source + ":" + std::to_string(table->line_of_row(i)) : "seed row " + std::to_string(i + 1);
    if (const auto k = robot::joint_outside_limits(q, nominal))
      throw InputError(where + ": seed column sq" + std::to_string(*k + 1) + " = " + format_number(q[*k]) +
                           " deg is outside " + limits(*k) +
                           "; seeds are joints the robot can take, in degrees (the taught joints)",
                       source);
    if (targets.config && !robot::arm_configuration(nominal, q).compatible_with(*targets.config))
      throw InputError(where + ": seed joints sq1..sq6 are on configuration " +
                           robot::arm_configuration(nominal, q).to_string() + ", not on --config " +
                           targets.config->to_string(),
                       source);
  }
}

void check_joints_not_radians(std::span<const robot::JointVector> q, const CompensationModel& model,
                              const std::string& source, const std::string& override_option) {
  const std::vector<robot::JointVector>& train = model.data_joints();
  if (q.empty() || train.size() < 2) return;
  double largest = 0.0;
  for (const robot::JointVector& row : q) {
    if (!row.allFinite()) return;  // rows the other checks name
    largest = std::max(largest, row.cwiseAbs().maxCoeff());
  }
  // Within one turn either way: the radians of any joint range up to +-360 deg (UR).
  if (largest > 2.0 * std::numbers::pi + 1e-6) return;
  auto spread = [](auto rows, int k) {
    double mean = 0.0, sq = 0.0;
    for (const robot::JointVector& r : rows) mean += r[k];
    mean /= static_cast<double>(rows.size());
    for (const robot::JointVector& r : rows) sq += (r[k] - mean) * (r[k] - mean);
    return std::sqrt(sq / static_cast<double>(rows.size()));
  };
  int spread_joints = 0;
  std::string evidence;
  for (int k = 0; k < robot::kJointCount; ++k) {
    const double t = spread(train, k);
    if (t < kRadiansSuspectTrainingSpreadDeg) continue;
    const double in = spread(q, k);
    if (in >= 0.1 * t) return;  // this joint moves as much as in training: degrees
    ++spread_joints;
    evidence += (evidence.empty() ? "" : ", ") + ("q" + std::to_string(k + 1)) + " " + format_number(std::round(in * 100) / 100) +
                " here vs " + format_number(std::round(t * 10) / 10) + " in training";
  }
  if (spread_joints < kRadiansSuspectJoints) return;
  throw InputError(source + ": the joints look like radians: all " + std::to_string(q.size()) +
                       " rows lie within +-2 pi (largest |q| " + format_number(std::round(largest * 1000) / 1000) +
                       ") and spread far less than the model's " + std::to_string(train.size()) +
                       " training joints (standard deviation, deg: " + evidence +
                       "). errfield reads joints q1..q6 in degrees: convert (x 180/pi), or give " + override_option +
                       " if these really are degrees",
                   source);
}

void check_readings_of_tool_point(const CompensationModel& model, std::span<const robot::JointVector> q,
                                  std::span<const Eigen::Vector3d> measured, const std::string& source,
                                  double limit_mm) {
  if (!model.registration() || measured.size() < 6 || q.size() != measured.size()) return;
  // The point validate scores: the working tool where `--tool` or locate-tool set one, else the
  // reflector the model was fitted on.
  const robot::MdhModel command = model.scored_model();
  double sq = 0.0;
  std::vector<robot::PositionMeasurement> data;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const Eigen::Vector3d r = model.registration()->robot_from_tracker * measured[i] - robot::forward_position(command, q[i]);
    sq += r.squaredNorm();
    data.push_back({q[i], measured[i]});
  }
  const double rms = std::sqrt(sq / static_cast<double>(q.size()));
  if (!(rms > limit_mm)) return;
  const robot::CalibrationResult reg = robot::register_tracker(command, data);
  const Eigen::Vector3d found = reg.model.tool().translation(), fitted = command.tool().translation();
  const double shift = (found - fitted).norm();
  if (!(shift > limit_mm)) {
    // The model's point, far in the stored frame yet close in a frame fitted to the readings: the
    // tracker (or the robot) moved since the model was fitted (issue 45: another day, another place).
    if (reg.after.rms_mm < 0.2 * rms)
      throw InputError(source + ": the model's registration leaves these readings " + format_significant(rms, 4) +
                           " mm RMS from the model's point, and a registration fitted to them " +
                           format_significant(reg.after.rms_mm, 4) +
                           " mm: the tracker (or the robot) has moved since the model was fitted. Register the model "
                           "to readings of today first: errfield register --model MODEL --data READINGS --out MODEL_TODAY",
                       source);
    return;
  }
  auto xyz = [](const Eigen::Vector3d& v) {
    return "(" + format_number(std::round(v.x() * 10) / 10) + ", " + format_number(std::round(v.y() * 10) / 10) +
           ", " + format_number(std::round(v.z() * 10) / 10) + ")";
  };
  throw InputError(source + ": these readings are of another point than the model's tool point: registered with a "
                       "free reflector offset they put the reflector at " + xyz(found) + " mm in the flange frame, " +
                       format_number(std::round(shift * 10) / 10) +
                       (model.working_tool() ? " mm from the model's working tool point " : " mm from the point the model was fitted for ") +
                       xyz(fitted) + " (limit " + format_number(limit_mm) +
                       " mm), and the model's registration leaves them " + format_number(std::round(rms * 10) / 10) +
                       " mm RMS from it. Validate a model with readings of the reflector or tool it was fitted on "
                       "(or fit a model for this one)",
                   source);
}

StepColumns validation_point_columns(const ValidationReport& r) {
  const std::size_t n = r.points.size();
  std::vector<std::string> point(n), status(n);
  std::vector<double> before(n), after(n);
  std::vector<std::vector<double>> comp(6, std::vector<double>(n));
  const bool positions = r.position.has_value();
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = r.points[i];
    point[i] = p.point;
    status[i] = p.status;
    // before_mm/after_mm: the 3-D error where positions were scored, else |distance error| to b0.
    before[i] = positions ? p.before_mm.norm() : (p.distance_before_mm.empty() ? kNaN : std::abs(p.distance_before_mm[0]));
    after[i] = positions ? p.after_mm.norm() : (p.distance_after_mm.empty() ? kNaN : std::abs(p.distance_after_mm[0]));
    for (int c = 0; c < 3; ++c) {
      comp[static_cast<std::size_t>(c)][i] = p.before_mm[c];
      comp[static_cast<std::size_t>(3 + c)][i] = p.after_mm[c];
    }
  }
  StepColumns out;
  out.columns.push_back(words("point", std::move(point)));
  out.columns.push_back(words("status", std::move(status)));
  out.columns.push_back(numbers("before_mm", std::move(before)));
  out.columns.push_back(numbers("after_mm", std::move(after)));
  const char* names[] = {"before_dx", "before_dy", "before_dz", "after_dx", "after_dy", "after_dz"};
  for (std::size_t c = 0; c < 6; ++c) out.columns.push_back(numbers(names[c], std::move(comp[c])));
  for (std::size_t k = 0; k < r.distance_columns; ++k) {
    std::vector<double> db(n, kNaN), da(n, kNaN);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = r.points[i];
      if (k < p.distance_before_mm.size()) db[i] = p.distance_before_mm[k];
      if (k < p.distance_after_mm.size()) da[i] = p.distance_after_mm[k];
    }
    out.columns.push_back(numbers("before_dl_b" + std::to_string(k), std::move(db)));
    out.columns.push_back(numbers("after_dl_b" + std::to_string(k), std::move(da)));
  }
  // The predictive uncertainty where the model has one (kriging fields).
  std::vector<std::vector<double>> unc(4, std::vector<double>(n, kNaN));
  bool any_variance = false, any_nees = false;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = r.points[i];
    unc[0][i] = p.var_mm2;
    unc[1][i] = p.var_field_mm2;
    unc[2][i] = p.r95_mm;
    unc[3][i] = p.nees;
    any_variance = any_variance || std::isfinite(p.var_mm2);
    any_nees = any_nees || std::isfinite(p.nees);
  }
  const char* unc_names[] = {"var_mm2", "var_field_mm2", "r95_mm", "nees"};
  for (std::size_t c = 0; c < 4; ++c)
    if (c < 2 ? any_variance : any_nees) out.columns.push_back(numbers(unc_names[c], std::move(unc[c])));
  for (const auto& p : r.points) out.refused += p.status != "ok";
  return out;
}

}  // namespace errfield::compensation
