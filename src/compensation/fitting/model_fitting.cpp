#include "errfield/compensation/fitting/model_fitting.hpp"

#include "errfield/robot/input_checks.hpp"

#include <array>
#include <cctype>
#include <algorithm>
#include <map>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <optional>

#include "errfield/cross_validation.hpp"
#include "errfield/error.hpp"
#include "errfield/grid_idw.hpp"
#include "errfield/kriging.hpp"
#include "errfield/metrics.hpp"
#include "errfield/regular_grid.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/distance_error.hpp"
#include "errfield/compensation/model/error_fields.hpp"
#include "errfield/compensation/fitting/held_out_shift.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/scattered_idw.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "compensation/fitting/kinematic_fit.hpp"
#include "errfield/robot/flange_points.hpp"
#include "robot/rigid_fit.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

void refuse_several_reflectors(const CsvTable& t) {
  // Rows of several points on the flange: one model of one point cannot take them together (each
  // reflector has its own error at a pose), so refuse them unless the file holds one label.
  if (!t.has_column("reflector")) return;
  const std::size_t col = t.column_index("reflector");
  for (std::size_t r = 1; r < t.row_count(); ++r)
    if (t.row(r)[col] != t.row(0)[col])
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column 'reflector': '" + t.row(r)[col] +
                           "' after '" + t.row(0)[col] +
                           "': the file holds readings of several reflectors, and a model is fitted to one point at a "
                           "time; keep one reflector's rows (and give a robot JSON whose tool is that reflector)",
                       t.source(), t.line_of_row(r), "reflector");
}

std::vector<std::string> MeasurementSet::reflector_labels() const {
  std::vector<std::string> out;
  for (const std::string& r : reflector)
    if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
  return out;
}

void refuse_several_points_for(const MeasurementSet& d, CompensationMethod method) {
  if (d.reflector_labels().size() <= 1 || method == CompensationMethod::kinematic ||
      method == CompensationMethod::kinematic_kriging)
    return;
  throw InputError(d.source + ": readings of " + std::to_string(d.reflector_labels().size()) +
                       " points on the flange (column 'reflector'): --method " + std::string(method_name(method)) +
                       " models one point; kinematic and kinematic+kriging take several (or keep one reflector's rows)",
                   d.source, 0, "reflector");
}

bool several_reflector_labels(const CsvTable& t) {
  if (!t.has_column("reflector")) return false;
  const std::size_t col = t.column_index("reflector");
  for (std::size_t r = 1; r < t.row_count(); ++r)
    if (t.row(r)[col] != t.row(0)[col]) return true;
  return false;
}

namespace {

/// `label` without its whitespace: what a person reads as the label.
std::string label_spelling(std::string_view label) {
  std::string out;
  for (char c : label)
    if (!std::isspace(static_cast<unsigned char>(c))) out.push_back(c);
  return out;
}

/// Refuses row `r`'s reflector label when an earlier row spelt the same label with other spaces
/// (`seen`: spelling -> first label and its row), naming both lines.
void refuse_label_spelt_differently(const CsvTable& t, std::size_t r, std::size_t col,
                                    std::map<std::string, std::pair<std::string, std::size_t>>& seen) {
  const std::string& label = t.row(r)[col];
  const auto [it, fresh] = seen.emplace(label_spelling(label), std::make_pair(label, r));
  if (fresh || it->second.first == label) return;
  throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column 'reflector': '" + label +
                       "' differs from '" + it->second.first + "' (line " + std::to_string(t.line_of_row(it->second.second)) +
                       ") only by spaces: two labels are two points on the flange; spell one reflector's label one way",
                   t.source(), t.line_of_row(r), "reflector");
}

}  // namespace

namespace {

/// Implausible measurements (distances in metres or far from the nominal ones, a tracker that
/// never moved) are refused here, before any method turns them into corrections.
void refuse_implausible_measurements(const CsvTable& t, const MeasurementSet& m, const MdhModel& robot) {
  const bool has_kind = t.has_column("kind");
  const std::size_t kind_col = has_kind ? t.column_index("kind") : 0;
  std::vector<std::size_t> target_rows;
  for (std::size_t r = 0; r < t.row_count(); ++r)
    if (!has_kind || t.row(r)[kind_col] != "base") target_rows.push_back(r);
  for (std::size_t k = 0; k < m.distance_mm.size(); ++k) {
    const bool metres = distances_in_metres(m.distance_mm[k], robot, {}).has_value();  // warned, not refused
    for (std::size_t i = 0; i < m.q_deg.size(); ++i) {
      const double nominal = (m.nominal_mm[i] - m.base_nominal_mm[k]).norm();
      if (nominal < 1.0) continue;  // the point at its base: no distance to speak of
      if (const auto why = implausible_distance(m.distance_mm[k][i], nominal, robot, !metres)) {
        const std::size_t line = t.line_of_row(target_rows[i]);
        const std::string col = "dist_b" + std::to_string(k);
        throw InputError(t.source() + ":" + std::to_string(line) + ": column '" + col + "': " + *why, t.source(), line,
                         col);
      }
    }
  }
  if (!m.measured_mm.empty()) {
    Eigen::MatrixXd measured(static_cast<Eigen::Index>(m.q_deg.size()), 3), nominal(measured.rows(), 3);
    for (std::size_t i = 0; i < m.q_deg.size(); ++i) {
      measured.row(static_cast<Eigen::Index>(i)) = m.measured_mm[i].transpose();
      nominal.row(static_cast<Eigen::Index>(i)) = m.nominal_mm[i].transpose();
    }
    if (const auto why = tracker_frozen(measured, nominal)) throw InputError(t.source() + ": " + *why, t.source(), 0, "mx");
  }
}

}  // namespace

MeasurementSet MeasurementSet::from_table(const CsvTable& t, const MdhModel& robot,
                                          const std::vector<Eigen::Vector3d>& fixed_bases, bool several_points) {
  MeasurementSet m;
  m.source = t.source();
  const Eigen::MatrixXd q = t.numeric_columns({"q1", "q2", "q3", "q4", "q5", "q6"});
  const bool has_xyz = t.has_column("x") && t.has_column("y") && t.has_column("z");
  const Eigen::MatrixXd xyz = has_xyz ? t.numeric_columns({"x", "y", "z"}) : Eigen::MatrixXd();
  const bool has_m = t.has_column("mx") && t.has_column("my") && t.has_column("mz");
  const Eigen::MatrixXd mxyz = has_m ? t.numeric_columns({"mx", "my", "mz"}) : Eigen::MatrixXd();
  std::vector<std::vector<double>> dist;
  for (std::size_t k = 0; t.has_column("dist_b" + std::to_string(k)); ++k)
    dist.push_back(t.numeric_column("dist_b" + std::to_string(k)));
  const bool has_kind = t.has_column("kind");
  const std::size_t kind_col = has_kind ? t.column_index("kind") : 0;
  if (!several_points) refuse_several_reflectors(t);
  const bool has_point = t.has_column("point");
  const std::size_t point_col = has_point ? t.column_index("point") : 0;
  const bool has_reflector = t.has_column("reflector");
  const std::size_t reflector_col = has_reflector ? t.column_index("reflector") : 0;
  // Rows of one pose read at several points must share the joints: the pose is one robot state.
  std::map<std::string, std::size_t> first_row_of_point;
  // A (point, reflector) pair names one reading: a repeated pair is a row given twice (its joints
  // and reading count twice, and the fields' leave-one-out per pose, which the rotation's and the
  // points' covariance come from, cannot take it). Labels that differ only by spaces are one
  // reflector to a person and two to the file.
  std::map<std::pair<std::string, std::string>, std::size_t> row_of_reading;
  std::map<std::string, std::pair<std::string, std::size_t>> label_by_spelling;
  m.distance_mm.assign(dist.size(), {});
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    const JointVector qr = q.row(static_cast<Eigen::Index>(r)).transpose();
    const Eigen::Vector3d p = has_xyz ? Eigen::Vector3d(xyz.row(static_cast<Eigen::Index>(r)).transpose())
                                      : forward_position(robot, qr);
    const std::string kind = has_kind ? t.row(r)[kind_col] : "target";
    // A base reading given twice counts twice in the base point's distance as a target's would.
    if (kind == "base" && has_reflector) refuse_label_spelt_differently(t, r, reflector_col, label_by_spelling);
    if (kind == "base" && has_point && has_reflector) {
      const std::string label(t.row(r)[reflector_col]), point(t.row(r)[point_col]);
      const auto [seen, fresh] = row_of_reading.emplace(std::make_pair(point, label), r);
      if (!fresh)
        throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": base point '" + point + "' at reflector '" +
                             label + "' is read again (first at line " + std::to_string(t.line_of_row(seen->second)) +
                             "): each (point, reflector) pair is one reading; remove the repeated row",
                         t.source(), t.line_of_row(r), "point");
    }
    if (kind == "base") {
      m.base_nominal_mm.push_back(p);
      m.base_q_deg.push_back(qr);
      continue;
    }
    if (kind != "target")
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column 'kind': '" + kind +
                           "'; expected base or target",
                       t.source(), t.line_of_row(r), "kind");
    m.id.push_back(has_point ? t.row(r)[point_col] : "row" + std::to_string(t.line_of_row(r)));
    if (has_reflector) {
      m.reflector.push_back(t.row(r)[reflector_col]);
      refuse_label_spelt_differently(t, r, reflector_col, label_by_spelling);
      if (has_point) {
        const auto [seen, fresh] = row_of_reading.emplace(std::make_pair(m.id.back(), m.reflector.back()), r);
        if (!fresh)
          throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": point '" + m.id.back() +
                               "' at reflector '" + m.reflector.back() + "' is read again (first at line " +
                               std::to_string(t.line_of_row(seen->second)) +
                               "): each (point, reflector) pair is one reading; remove the repeated row, or give a "
                               "repeated measurement of the pose its own point name",
                           t.source(), t.line_of_row(r), "point");
        const auto [it, first] = first_row_of_point.emplace(m.id.back(), r);
        if (!first && q.row(static_cast<Eigen::Index>(it->second)) != q.row(static_cast<Eigen::Index>(r)))
          throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": point '" + m.id.back() +
                               "' (reflector '" + m.reflector.back() + "') has other joints than its row at line " +
                               std::to_string(t.line_of_row(it->second)) +
                               ": the readings of one pose at several points must share q1..q6",
                           t.source(), t.line_of_row(r), "q1");
      }
    }
    m.q_deg.push_back(qr);
    m.nominal_mm.push_back(p);
    if (has_m) m.measured_mm.push_back(mxyz.row(static_cast<Eigen::Index>(r)).transpose());
    for (std::size_t k = 0; k < dist.size(); ++k) m.distance_mm[k].push_back(dist[k][r]);
  }
  if (m.base_nominal_mm.empty()) m.base_nominal_mm = fixed_bases;
  if (!dist.empty() && m.base_nominal_mm.size() < dist.size())
    throw InputError(t.source() + ": " + std::to_string(dist.size()) + " distance columns (dist_b0..) but " +
                         std::to_string(m.base_nominal_mm.size()) +
                         " base points; add rows with kind=base or give the base points (--base-point X,Y,Z)",
                     t.source());
  if (m.q_deg.empty()) throw InputError(t.source() + ": no target rows", t.source());
  refuse_implausible_measurements(t, m, robot);
  return m;
}

std::vector<double> MeasurementSet::distance_errors(std::size_t k) const {
  if (k >= distance_mm.size())
    throw InputError(source + ": no column dist_b" + std::to_string(k) +
                         " (distances to a base point are needed by the distance methods)",
                     source, 0, "dist_b" + std::to_string(k));
  std::vector<double> out(q_deg.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = distance_mm[k][i] - (nominal_mm[i] - base_nominal_mm[k]).norm();
  return out;
}

MethodChoice choose_method(const MeasurementSet& d) {
  if (!d.measured_mm.empty())
    return {CompensationMethod::kinematic_kriging, FieldSpace::joint,
            "the data have tracker positions (mx,my,mz): kinematic calibration, then kriging of the 3-D residuals in "
            "joint space (the most accurate on held-out points in docs/robot.md)"};
  if (!d.distance_mm.empty())
    return {CompensationMethod::kinematic, FieldSpace::joint,
            "the data have distances only (dist_bK): kinematic calibration from the distances (robust to scattered "
            "poses and varying orientation; docs/robot.md)"};
  throw InputError(d.source + ": neither tracker positions (mx,my,mz) nor distances (dist_b0, ...): nothing to fit "
                   "a compensation model to",
                   d.source);
}

VarianceCalibrationChoice variance_calibration_from_name(std::string_view name) {
  if (name == "auto") return VarianceCalibrationChoice::automatic;
  if (name == "loo") return VarianceCalibrationChoice::leave_one_out;
  if (name == "none") return VarianceCalibrationChoice::none;
  throw ArgumentError("--variance-calibration: '" + std::string(name) + "'; expected auto, loo or none");
}

int FitOptions::joint_function_degree_for(std::size_t poses) const {
  if (joint_function_degree != kJointFunctionDegreeByPoses) return joint_function_degree;
  return poses >= kJointFunctionManyPoses ? kJointFunctionDegreeManyPoses : kJointFunctionDegreeFewPoses;
}

void FitOptions::validate() const {
  if (!(idw_power >= 0.0) || !std::isfinite(idw_power))
    throw ArgumentError("fit: idw power " + std::to_string(idw_power) + "; expected a finite value >= 0");
  if (region_margin && (!(*region_margin >= 0.0) || !std::isfinite(*region_margin)))
    throw ArgumentError("fit: region margin " + std::to_string(*region_margin) + "; expected a finite value >= 0");
  if (!(outlier_limit >= 0.0) || !std::isfinite(outlier_limit))
    throw ArgumentError("fit: outlier limit " + std::to_string(outlier_limit) + "; expected a finite value >= 0 (0 = off)");
  if ((joint_function_degree < 0 && joint_function_degree != kJointFunctionDegreeByPoses) || joint_function_degree > 20)
    throw ArgumentError("fit: joint function degree " + std::to_string(joint_function_degree) +
                        "; expected 0 (none) to 20, or " + std::to_string(kJointFunctionDegreeByPoses) +
                        " (by the number of poses)");
  joint_function_prior.validate();
  if (!(gls_guard_ratio >= 0.0) || !std::isfinite(gls_guard_ratio))
    throw ArgumentError("fit: GLS guard ratio " + format_number(gls_guard_ratio) + "; expected a finite value >= 0 (0 = off)");
  calibration.validate();
}

namespace {

CrossValidationReport report(const CrossValidationSummary& s, std::string how) {
  CrossValidationReport c;
  c.method = std::move(how);
  c.samples = s.predicted;
  c.mean_abs_mm = s.mean_abs_error;
  c.rms_mm = s.rms_error;
  c.max_abs_mm = s.max_abs_error;
  c.mean_squared_z = s.mean_squared_z;
  return c;
}

/// The kriging field's own leave-one-out (closed form from its factorization; KrigingFieldFit).
CrossValidationReport kriging_report(const KrigingFieldFit& fit, FieldSpace space, const FitOptions& o) {
  std::string how = "leave-one-out, " +
                    (o.kind == KrigingKind::Universal ? "universal kriging (drift order " + std::to_string(o.drift_order) + ")"
                                                      : std::string("ordinary kriging")) +
                    " in " + std::string(field_space_name(space)) + " space";
  if (fit.merged_duplicates > 0)
    how += "; " + std::to_string(fit.merged_duplicates) +
           " repeated measurements averaged into their location, so one location is left out at a time";
  return report(fit.leave_one_out, std::move(how));
}

/// The kriging system's conditioning, as a note, and as a warning when it costs precision: a model
/// without nugget (Gaussian above all) on dense samples makes K nearly singular, and predictions
/// and the leave-one-out summary are then dominated by rounding.
void note_factorization(FitResult& out, const KrigingFieldFit& fit, const VariogramModel& model) {
  const KrigingReport& f = fit.factorization;
  if (out.cross_validation) {
    out.cross_validation->variogram = model;
    out.cross_validation->factorization = f;
  }
  std::string note = "kriging system: " + std::to_string(f.samples_used) + " samples";
  if (std::isfinite(f.condition_number)) note += ", condition number " + format_number(f.condition_number);
  if (f.jitter > 0.0) note += ", jitter " + format_number(f.jitter) + " added to the diagonal";
  out.notes.push_back(std::move(note));
  if (f.status == KrigingStatus::IllConditioned || f.jitter > 0.0)
    out.warnings.push_back("the kriging system is ill-conditioned: " +
                           (f.message.empty() ? "jitter " + format_number(f.jitter) + " was needed" : f.message) +
                           ". Predictions and the leave-one-out summary lose precision; give the variogram model " +
                           (model.nugget() > 0.0 ? "a larger nugget" : "a nugget") + " (model " + model.to_string() +
                           "), e.g. --model \"...+nug(" + format_number(1e-3 * model.sill()) + ")\"");
}

template <class V>
CrossValidationReport idw_cv(const std::vector<Eigen::Vector3d>& p, const std::vector<V>& values, double power) {
  ScatteredIdwEstimator<Eigen::Vector3d, V> est;
  est.options.power = power;
  est.options.neighbors = 8;
  est.options.threads = 1;
  return report(cross_validate<Eigen::Vector3d, V>(est, std::span<const Eigen::Vector3d>(p), std::span<const V>(values))
                    .summary,
                "leave-one-out with 8-nearest-neighbour IDW (grid IDW needs every node, so its own LOO is "
                "not defined)");
}

/// `model_estimated`: the variogram was chosen by fit (not given by the user), which is when
/// VarianceCalibrationChoice::automatic calibrates the variance.
KrigingFieldOptions field_options(const FitOptions& o, bool model_estimated) {
  KrigingFieldOptions ko;
  ko.calibrate_variance = o.variance_calibration == VarianceCalibrationChoice::leave_one_out ||
                          (o.variance_calibration == VarianceCalibrationChoice::automatic && model_estimated);
  ko.on_stage = o.on_stage;
  ko.space = o.space;
  ko.kind = o.kind;
  ko.drift_order = o.drift_order;
  ko.family = o.model_family;
  (o.space == FieldSpace::task ? ko.region_margin_mm : ko.region_margin_deg) +=
      o.region_margin.value_or(o.space == FieldSpace::joint ? 5.0 : 0.0);
  return ko;
}

/// The given model, or the one choose_field_model picks (its reason in `reason`).
VariogramModel chosen_model(const FitOptions& o, const FieldSamples& samples, const Eigen::MatrixXd& values,
                            const KrigingFieldOptions& ko, std::string& reason) {
  if (o.model) return *o.model;
  return choose_field_model(samples, values, ko, reason);
}

/// The grid detector's refusal said as what the IDW methods need: "the x values are not evenly
/// spaced ... would need 719866 planes" on scattered poses read as a tolerance problem, not as a
/// method that needs the paper's grid. The file (or row) prefix stays in front.
[[noreturn]] void throw_grid_needed(const InputError& e, CompensationMethod method, std::size_t poses) {
  std::string found = e.what(), prefix;
  if (!e.file().empty() && found.rfind(e.file(), 0) == 0)
    if (const auto colon = found.find(": ", e.file().size()); colon != std::string::npos) {
      prefix = found.substr(0, colon + 2);
      found = found.substr(colon + 2);
    }
  throw InputError(prefix + std::string(method_name(method)) +
                       " needs the paper's regular grid of poses (one pose per node of an evenly spaced x,y,z grid, "
                       "as 'errfield plan' writes); the " +
                       std::to_string(poses) + " poses given are not one: " + found +
                       ". For scattered poses use --method auto, vector-kriging or distance-kriging",
                   e.file(), e.row(), e.column());
}

RegularGrid3 detect_grid(const MeasurementSet& d, std::vector<std::size_t>& sample_of_node) {
  Eigen::MatrixXd pts(static_cast<Eigen::Index>(d.nominal_mm.size()), 3);
  for (std::size_t i = 0; i < d.nominal_mm.size(); ++i) pts.row(static_cast<Eigen::Index>(i)) = d.nominal_mm[i].transpose();
  RowLabels labels;
  labels.source = d.source;
  GridDetection g = detect_regular_grid(pts, labels);
  sample_of_node = std::move(g.sample_of_node);
  return g.grid;
}

}  // namespace

namespace {

/// The variance calibration of a kriging field, as a note (fit prints it; the model JSON has the
/// figures in field.variance_calibration).
void note_variance_calibration(FitResult& out, const KrigingFieldFit& fit) {
  if (!fit.variance_calibration) return;
  const VarianceCalibration& c = *fit.variance_calibration;
  out.notes.push_back("predictive variance calibrated by leave-one-out on the " + std::to_string(c.samples) +
                      " samples: every sill and the nugget x " + format_number(c.factor) +
                      " = max(mean z^2 per component " + format_number(c.mean_squared_z_before) +
                      (c.capped_samples == 0 ? std::string()
                                             : " (" + std::to_string(c.capped_samples) +
                                                   " sample(s) beyond 1 in 1000 under the tail's scale entered at that cap)") +
                      ", 95 % quantile of z^2 / chi2(0.95) " + format_number(c.tail_factor) +
                      "), so the variance is too small neither on average nor in the tail; the predicted errors "
                      "are unchanged (model before " + c.model_before + "; --variance-calibration none keeps it)");
}

MeasurementSet without_rows(const MeasurementSet& d, const std::vector<std::size_t>& rows);

/// The orientation residual a model fitted at one of several points leaves (MeasuredOrientation):
/// at the other points' rows, the miss of the model's prediction there (its own point's field and
/// functions carried to the point) beyond the variance it states without the orientation term is
/// w x L, of expected square 2 sigma² |L|² for an isotropic w: sigma² = (Σ|miss|² − Σ var) / Σ 2|L|².
MeasuredOrientation measured_orientation(const CompensationModel& model, const MeasurementSet& d,
                                         const detail::KinematicFit& kin, const Registration& reg,
                                         const std::vector<std::size_t>& rows) {
  const Eigen::Vector3d own = kin.model.tool().translation();
  double miss_ss = 0.0, explained = 0.0, lever_ss = 0.0;
  MeasuredOrientation out;
  std::vector<MdhModel> at_row;
  std::vector<JointVector> q_row;
  for (std::size_t i : rows) {
    at_row.push_back(model.command_model().with_tool_point(kin.flange_point_of_row_mm[i]));
    q_row.push_back(d.q_deg[i]);
  }
  const std::vector<ErrorPrediction> predicted = model.predict_errors_at(q_row, at_row);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::size_t i = rows[k];
    const MdhModel& at = at_row[k];
    const ErrorPrediction& e = predicted[k];
    if (!e.inside_region || !std::isfinite(e.variance_mm2)) continue;
    const Eigen::Vector3d miss =
        reg.robot_from_tracker * d.measured_mm[i] - (forward_position(at, d.q_deg[i]) + e.position_error_mm);
    const double stated = e.predictive_variance_mm2() - (std::isfinite(e.orientation_variance_mm2) ? e.orientation_variance_mm2 : 0.0);
    const Eigen::Vector3d lever =
        forward_kinematics(at, d.q_deg[i], EndFrame::flange).linear() * (kin.flange_point_of_row_mm[i] - own);
    miss_ss += miss.squaredNorm();
    explained += stated;
    lever_ss += 2.0 * lever.squaredNorm();
    ++out.readings;
  }
  out.sigma_rad = lever_ss > 0.0 ? std::sqrt(std::max(0.0, miss_ss - explained) / lever_ss) : 0.0;
  // The points span a plane when the second singular value of their spread is not negligible.
  std::vector<Eigen::Vector3d> points = {own};
  for (std::size_t i : rows) {
    bool seen = false;
    for (const Eigen::Vector3d& p : points) seen = seen || (p - kin.flange_point_of_row_mm[i]).norm() < 1e-9;
    if (!seen) points.push_back(kin.flange_point_of_row_mm[i]);
  }
  Eigen::MatrixXd spread(3, static_cast<Eigen::Index>(points.size()));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p / static_cast<double>(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) spread.col(static_cast<Eigen::Index>(k)) = points[k] - mean;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(spread).singularValues();
  out.add_floor = !(points.size() >= 3 && sv.size() >= 2 && sv[1] > 0.05 * sv[0]);
  return out;
}

/// The model's flange points, each further one (not the own point) with a field kriged on its own
/// readings (`rows` of `d`): what the calibration, the registration and the joint error functions
/// at that point leave, with `options` (the own field's variogram). A point with fewer than
/// kMinimumPointFieldReadings readings keeps none.
std::vector<CompensationModel::LabelledPoint> fields_of_further_points(const CompensationModel& model,
                                                                       const MeasurementSet& d,
                                                                       const detail::KinematicFit& kin,
                                                                       const Registration& reg,
                                                                       const std::vector<std::size_t>& rows,
                                                                       const KrigingFieldOptions& options,
                                                                       const std::function<HeldOutShift(const MdhModel&)>& shift_at) {
  constexpr std::size_t kMinimumPointFieldReadings = 20;
  std::vector<CompensationModel::LabelledPoint> points = model.flange_points();
  for (CompensationModel::LabelledPoint& point : points) {
    FieldSamples samples;
    std::vector<Eigen::Vector3d> residual;
    for (std::size_t i : rows) {
      if (d.reflector[i] != point.label) continue;
      const MdhModel at = model.command_model().with_tool_point(kin.flange_point_of_row_mm[i]);
      residual.push_back(reg.robot_from_tracker * d.measured_mm[i] - forward_position(at, d.q_deg[i]) -
                         model.joint_function_error_at(d.q_deg[i], at));
      samples.position_mm.push_back(d.nominal_mm[i]);
      samples.joints_deg.push_back(d.q_deg[i]);
    }
    if (residual.size() < kMinimumPointFieldReadings) continue;
    KrigingFieldOptions at_point = options;
    if (shift_at) at_point.held_out_shift = shift_at(model.command_model().with_tool_point(point.position_mm));
    point.field = fit_vector_kriging_field(samples, std::move(residual), at_point).field;
  }
  return points;
}

/// The fields' leave-one-out at every training pose that each of them holds as a sample of its own:
/// per pose the residuals in the flange frame (where the points' geometry is fixed), stacked in
/// fielded_points()'s order, and each field's stated variance (per component). Empty when a field
/// has no per-sample leave-one-out (repeated poses merge into one location).
struct HeldOutAtPoints {
  std::vector<Eigen::VectorXd> flange_residual_mm;  // 3K per pose
  std::vector<Eigen::VectorXd> variance_mm2;        // K per pose
};

std::optional<HeldOutAtPoints> held_out_at_fielded_points(const CompensationModel& model) {
  const std::vector<CompensationModel::FieldedPoint> points = model.fielded_points();
  using Key = std::array<double, kJointCount>;
  auto key_of = [](const JointVector& q) {
    Key k;
    for (int j = 0; j < kJointCount; ++j) k[static_cast<std::size_t>(j)] = q[j];
    return k;
  };
  std::vector<std::map<Key, SampleHoldOut>> held_out(points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    const std::vector<SampleHoldOut> loo = leave_one_out_by_sample(*points[p].field);
    const std::vector<JointVector> joints = points[p].field->sample_joints();
    if (loo.size() != joints.size()) return std::nullopt;
    for (std::size_t i = 0; i < loo.size(); ++i) held_out[p].emplace(key_of(joints[i]), loo[i]);
  }
  const auto k = static_cast<Eigen::Index>(points.size());
  HeldOutAtPoints out;
  for (const auto& [key, first] : held_out[0]) {
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q[j] = key[static_cast<std::size_t>(j)];
    const Eigen::Matrix3d flange = forward_kinematics(model.command_model(), q, EndFrame::flange).linear();
    Eigen::VectorXd residual(3 * k), variance(k);
    bool every = true;
    for (Eigen::Index p = 0; p < k && every; ++p) {
      const auto found = held_out[static_cast<std::size_t>(p)].find(key);
      every = found != held_out[static_cast<std::size_t>(p)].end();
      if (!every) break;
      residual.segment<3>(3 * p) = flange.transpose() * found->second.residual_mm;
      variance[p] = found->second.variance_mm2;
    }
    if (!every) continue;
    out.flange_residual_mm.push_back(std::move(residual));
    out.variance_mm2.push_back(std::move(variance));
  }
  return out;
}

/// predict_rotation's covariance (RotationCalibration): at every training pose that each field holds,
/// the rotation the fields' leave-one-out residuals imply, in the flange frame. Empty when fewer than
/// 30 poses qualify or the points do not determine a rotation.
std::optional<RotationCalibration> rotation_calibration_of(const CompensationModel& model,
                                                           const HeldOutAtPoints& held_out) {
  const std::vector<CompensationModel::FieldedPoint> points = model.fielded_points();
  if (points.size() < 3) return std::nullopt;
  std::vector<Eigen::Vector3d> flange_points;
  for (const CompensationModel::FieldedPoint& p : points) flange_points.push_back(p.position_mm);
  // The least-squares rotation is the same in any frame the points and errors are given in.
  const std::optional<FlangeRotationOperator> rotation = FlangeRotationOperator::of(flange_points);
  if (!rotation) return std::nullopt;
  RotationCalibration out;
  double independent_trace = 0.0;
  for (std::size_t i = 0; i < held_out.flange_residual_mm.size(); ++i) {
    const Eigen::Vector3d w = rotation->from_errors * held_out.flange_residual_mm[i];
    out.flange_covariance_rad2 += w * w.transpose();
    std::vector<Eigen::Vector3d> variance;
    for (Eigen::Index p = 0; p < held_out.variance_mm2[i].size(); ++p)
      variance.push_back(Eigen::Vector3d::Constant(held_out.variance_mm2[i][p]));
    independent_trace += rotation->covariance_rad2(variance).trace();
    ++out.poses;
  }
  // Fewer poses than this leave a 3 x 3 covariance too uncertain to claim a 95 % region from.
  constexpr std::size_t kMinimumPoses = 30;
  if (out.poses < kMinimumPoses) return std::nullopt;
  out.flange_covariance_rad2 /= static_cast<double>(out.poses);
  out.mean_independent_trace_rad2 = independent_trace / static_cast<double>(out.poses);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(out.flange_covariance_rad2, Eigen::EigenvaluesOnly);
  if (!(eig.eigenvalues().minCoeff() > 0.0) || !(out.mean_independent_trace_rad2 > 0.0)) return std::nullopt;
  return out;
}

/// The covariance of the fields' errors at their points (FlangeErrorCovariance), for the points
/// predicted from their combination; each field's noise is its nugget when the nugget stands for
/// measurement error (what its predictions state as noise_variance_mm2).
std::optional<FlangeErrorCovariance> flange_error_covariance_of(const CompensationModel& model,
                                                                const HeldOutAtPoints& held_out) {
  const std::vector<CompensationModel::FieldedPoint> points = model.fielded_points();
  if (points.size() < 2 || held_out.flange_residual_mm.empty()) return std::nullopt;
  const JointVector q = points.front().field->sample_joints().front();
  Eigen::VectorXd noise_per_axis(static_cast<Eigen::Index>(points.size()));
  for (std::size_t p = 0; p < points.size(); ++p) {
    const ErrorPrediction e = points[p].field->predict(forward_position(model.nominal_model(), q), q);
    noise_per_axis[static_cast<Eigen::Index>(p)] = std::isfinite(e.noise_variance_mm2) ? e.noise_variance_mm2 / 3.0 : 0.0;
  }
  std::vector<double> field_variance;
  for (const Eigen::VectorXd& v : held_out.variance_mm2)
    field_variance.push_back((3.0 * (v - noise_per_axis)).cwiseMax(0.0).sum());
  return FlangeErrorCovariance::of(held_out.flange_residual_mm, field_variance, noise_per_axis);
}

/// Each labelled point's position on the nominal robot's flange (LabelledPoint::nominal_mm): the
/// mean of its training readings mapped by the nominal registration into the nominal FK's flange
/// frame, then the calibrated points (LabelledPoint::position_mm) moved rigidly onto those means
/// (least squares, no scaling), so that the plate is the same rigid plate in both frames as the
/// model file's check requires. The means alone each carry the robot's error at their own lever:
/// from 40 SIMULATED poses of a three-nest KR 16 their distances differed from the calibrated
/// points' by 0.26 mm and fit wrote a model its own loader refused.
FitResult with_nominal_flange_points(FitResult fit, const MdhModel& nominal, const MeasurementSet& d) {
  const std::optional<Registration>& frame = fit.model.nominal_registration();
  if (!frame || fit.model.flange_points().empty() || d.reflector.empty()) return fit;
  std::vector<CompensationModel::LabelledPoint> points = fit.model.flange_points();
  std::vector<std::size_t> with_mean;
  for (std::size_t k = 0; k < points.size(); ++k) {
    CompensationModel::LabelledPoint& p = points[k];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < d.reflector.size(); ++i) {
      if (d.reflector[i] != p.label) continue;
      sum += forward_kinematics(nominal, d.q_deg[i], EndFrame::flange).inverse() * (frame->robot_from_tracker * d.measured_mm[i]);
      ++n;
    }
    if (n > 0) p.nominal_mm = sum / static_cast<double>(n), with_mean.push_back(k);
  }
  if (with_mean.size() >= 2) {
    Eigen::Matrix3Xd calibrated(3, static_cast<Eigen::Index>(with_mean.size())), means(3, calibrated.cols());
    for (std::size_t c = 0; c < with_mean.size(); ++c) {
      calibrated.col(static_cast<Eigen::Index>(c)) = points[with_mean[c]].position_mm;
      means.col(static_cast<Eigen::Index>(c)) = *points[with_mean[c]].nominal_mm;
    }
    const Eigen::Matrix4d t = Eigen::umeyama(calibrated, means, false);
    for (std::size_t k : with_mean)
      points[k].nominal_mm = t.topLeftCorner<3, 3>() * points[k].position_mm + t.topRightCorner<3, 1>();
  }
  fit.model = fit.model.with_flange_points(std::move(points));
  return fit;
}

void require_base_point(const MeasurementSet& d, const FitOptions& o) {
  if (o.base >= d.base_nominal_mm.size())
    throw InputError(d.source + ": base point " + std::to_string(o.base) + " requested but the data have " +
                         std::to_string(d.base_nominal_mm.size()),
                     d.source);
}

/// Each point's measured error after the tracker -> robot registration fitted on all points (kept
/// in `out` with its note): the rigid part of the robot's error goes into the registration.
std::vector<Eigen::Vector3d> registered_errors(const MeasurementSet& d, FitResult& out) {
  if (d.measured_mm.empty())
    throw InputError(d.source + ": the method needs measured positions (columns mx,my,mz, tracker frame)", d.source, 0,
                     "mx");
  const Registration reg = fit_registration(d.measured_mm, d.nominal_mm);
  std::vector<Eigen::Vector3d> dp(d.nominal_mm.size());
  for (std::size_t i = 0; i < dp.size(); ++i) dp[i] = reg.robot_from_tracker * d.measured_mm[i] - d.nominal_mm[i];
  out.registration = reg;
  out.notes.push_back("registration tracker -> robot fitted on " + std::to_string(dp.size()) +
                      " points, residual RMS " + std::to_string(reg.residual_rms_mm) +
                      " mm (it absorbs the rigid part of the robot's error)");
  return dp;
}

/// The notes every kriged field ends with: its variogram, its factorization, why the model was
/// chosen and how its variance was calibrated.
void note_kriged_field(FitResult& out, const KrigingFieldFit& fit, FieldSpace space, const std::string& model_reason) {
  out.notes.push_back("variogram per component: " + describe_field_model(fit.model, space));
  note_factorization(out, fit, fit.model);
  if (!model_reason.empty()) out.notes.push_back("model chosen by " + model_reason);
  note_variance_calibration(out, fit);
}

FitResult fit_distance_idw(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  const CompensationMethod method = CompensationMethod::distance_idw;
  require_base_point(d, o);
  GridIdwOptions idw;
  idw.power = o.idw_power;
  const std::vector<double> dl = d.distance_errors(o.base);
  std::vector<std::size_t> order;
  // The paper's layout: the base point P0 is grid vertex 0, measured once as the base row. Its
  // distance to itself is exactly 0, its distance error 0: it completes the grid (when the
  // targets alone do not form one and the base row is a robot position).
  std::vector<double> node_values = dl;
  std::optional<RegularGrid3> found;
  bool base_as_vertex = false;
  try {
    found = detect_grid(d, order);
  } catch (const InputError& e) {
    if (o.base >= d.base_q_deg.size()) throw_grid_needed(e, method, d.nominal_mm.size());
    MeasurementSet with_base = d;
    with_base.nominal_mm.push_back(d.base_nominal_mm[o.base]);
    try {
      found = detect_grid(with_base, order);
    } catch (const InputError&) {
    }
    if (!found) throw_grid_needed(e, method, d.nominal_mm.size());  // the targets' own grid error
    node_values.push_back(0.0);
    base_as_vertex = true;
  }
  const RegularGrid3 grid = *found;
  std::vector<double> node(order.size());
  for (std::size_t n = 0; n < order.size(); ++n) node[n] = node_values[order[n]];
  FitResult out{CompensationModel(method, robot, make_distance_idw_field(grid, node, d.base_nominal_mm[o.base], idw)),
                std::nullopt, idw_cv(d.nominal_mm, dl, o.idw_power), {}, {}};
  if (base_as_vertex)
    out.notes.push_back("base point b" + std::to_string(o.base) +
                        " is a grid vertex (the paper's layout): its distance error there is 0");
  out.notes.push_back("base point b" + std::to_string(o.base) + " at (" + std::to_string(d.base_nominal_mm[o.base].x()) +
                      ", " + std::to_string(d.base_nominal_mm[o.base].y()) + ", " +
                      std::to_string(d.base_nominal_mm[o.base].z()) + ") mm");
  return out;
}

FitResult fit_position_idw(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  const CompensationMethod method = CompensationMethod::position_idw;
  GridIdwOptions idw;
  idw.power = o.idw_power;
  FitResult out{CompensationModel(method, robot, nullptr), std::nullopt, std::nullopt, {}, {}};
  const auto dp = registered_errors(d, out);
  std::vector<std::size_t> order;
  const RegularGrid3 grid = [&] {
    try {
      return detect_grid(d, order);
    } catch (const InputError& e) {
      throw_grid_needed(e, method, d.nominal_mm.size());
    }
  }();
  std::vector<Eigen::Vector3d> node(order.size());
  for (std::size_t n = 0; n < order.size(); ++n) node[n] = dp[order[n]];
  out.model = CompensationModel(method, robot, make_position_idw_field(grid, node, idw));
  out.cross_validation = idw_cv(d.nominal_mm, dp, o.idw_power);
  return out;
}

FitResult fit_distance_kriging(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o, bool model_estimated) {
  const CompensationMethod method = CompensationMethod::distance_kriging;
  require_base_point(d, o);
  std::string model_reason;
  const FieldSamples samples{d.nominal_mm, d.q_deg};
  const std::vector<double> dl = d.distance_errors(o.base);
  KrigingFieldOptions ko = field_options(o, model_estimated);
  const Eigen::MatrixXd flat = Eigen::Map<const Eigen::VectorXd>(dl.data(), static_cast<Eigen::Index>(dl.size()));
  if (!o.model && o.on_stage) o.on_stage("estimating the variogram");
  ko.model = chosen_model(o, samples, flat, ko, model_reason);
  const KrigingFieldFit fit = fit_distance_kriging_field(samples, dl, d.base_nominal_mm[o.base], ko);
  FitResult out{CompensationModel(method, robot, fit.field), std::nullopt, kriging_report(fit, o.space, o), {}, {}};
  note_factorization(out, fit, fit.model);
  if (!model_reason.empty()) out.notes.push_back("model chosen by " + model_reason);
  out.notes.push_back("variogram model " + fit.model.to_string() + "; base point b" + std::to_string(o.base));
  out.notes.push_back("variogram: " + describe_field_model(fit.model, o.space));
  note_variance_calibration(out, fit);
  return out;
}

/// The full error vector at every point from its distances to >= 3 fixed base points: no
/// registration needed.
std::vector<Eigen::Vector3d> errors_from_base_distances(const MeasurementSet& d, FitResult& out) {
  std::vector<Eigen::Vector3d> dp;
  std::vector<std::vector<double>> dl;
  for (std::size_t k = 0; k < d.distance_mm.size(); ++k) dl.push_back(d.distance_errors(k));
  double worst = 0.0;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    std::vector<double> di;
    for (const auto& col : dl) di.push_back(col[i]);
    const PositionErrorRecovery rec = recover_position_error(d.base_nominal_mm, di, d.nominal_mm[i]);
    if (!rec.ok) throw InputError(d.source + ": point " + d.id[i] + ": " + rec.message, d.source);
    worst = std::max(worst, rec.condition_number);
    dp.push_back(rec.position_error_mm);
  }
  out.notes.push_back("error vectors recovered from distances to " + std::to_string(dl.size()) +
                      " base points (worst condition number " + std::to_string(worst) + ")");
  return dp;
}

Eigen::MatrixXd rows_of_vectors(const std::vector<Eigen::Vector3d>& v) {
  Eigen::MatrixXd flat(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) flat.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return flat;
}

FitResult fit_vector_kriging(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o, bool model_estimated) {
  const CompensationMethod method = CompensationMethod::vector_kriging;
  std::string model_reason;
  const FieldSamples samples{d.nominal_mm, d.q_deg};
  FitResult out{CompensationModel(method, robot, nullptr), std::nullopt, std::nullopt, {}, {}};
  // Robot-position bases carry the robot's own error into every distance; recovering error
  // vectors from them as if they were exact biases every vector, so those data use positions
  // (the CLI refuses them without positions: input_checks.hpp).
  const std::vector<Eigen::Vector3d> dp = d.distance_mm.size() >= 3 && d.base_q_deg.empty()
                                              ? errors_from_base_distances(d, out)
                                              : registered_errors(d, out);
  KrigingFieldOptions ko = field_options(o, model_estimated);
  const Eigen::MatrixXd flat = rows_of_vectors(dp);
  if (!o.model && o.on_stage) o.on_stage("estimating the variogram");
  ko.model = chosen_model(o, samples, flat, ko, model_reason);
  const KrigingFieldFit fit = fit_vector_kriging_field(samples, dp, ko);
  out.model = CompensationModel(method, robot, fit.field);
  out.cross_validation = kriging_report(fit, o.space, o);
  out.notes.push_back("variogram model " + fit.model.to_string() + " (shared by the 3 components)");
  note_kriged_field(out, fit, o.space, model_reason);
  return out;
}

/// The rows that are not the model's own point (data of several points on the flange); empty when
/// every row is.
std::vector<std::size_t> rows_of_other_points(const detail::KinematicFit& kin, std::size_t rows) {
  std::vector<std::size_t> other_points;
  for (std::size_t i = 0, next = 0; !kin.own_point_rows.empty() && i < rows; ++i) {
    if (next < kin.own_point_rows.size() && kin.own_point_rows[next] == i) ++next;
    else other_points.push_back(i);
  }
  return other_points;
}

/// What the calibrated model leaves at the own point's readings, in the robot frame, and the
/// registration it is measured through.
struct CalibrationResidual {
  Registration registration;
  std::vector<Eigen::Vector3d> residual_mm;
};

CalibrationResidual calibration_residual(const detail::KinematicFit& kin, const MeasurementSet& dd) {
  if (dd.measured_mm.empty())
    throw InputError(dd.source + ": kinematic+kriging needs measured positions (mx,my,mz) for the residuals",
                     dd.source, 0, "mx");
  std::vector<Eigen::Vector3d> identified(dd.q_deg.size());
  for (std::size_t i = 0; i < identified.size(); ++i) identified[i] = forward_position(kin.model, dd.q_deg[i]);
  // Position calibration found the registration with the model; distance calibration has none.
  const Registration reg = kin.registration ? *kin.registration : fit_registration(dd.measured_mm, identified);
  std::vector<Eigen::Vector3d> residual(identified.size());
  for (std::size_t i = 0; i < residual.size(); ++i) residual[i] = reg.robot_from_tracker * dd.measured_mm[i] - identified[i];
  return {reg, std::move(residual)};
}

/// The joint error functions by ordinary (ridge) least squares on the calibration's residual, with
/// their notes.
JointErrorFunctionFit ordinary_joint_functions(const detail::KinematicFit& kin, const MeasurementSet& dd,
                                               const std::vector<Eigen::Vector3d>& residual, const FitOptions& o,
                                               FitResult& out) {
  const int degree = o.joint_function_degree_for(dd.q_deg.size());
  JointErrorFunctionFit jf = fit_joint_error_functions(kin.model, dd.q_deg, residual, degree, o.gravity_load,
                                                       o.joint_function_prior);
  if (!jf.undetermined_gravity_terms.empty()) {
    std::string which;
    for (const std::string& t : jf.undetermined_gravity_terms) which += (which.empty() ? "" : ", ") + t;
    out.notes.push_back(std::to_string(jf.undetermined_gravity_terms.size()) + " gravity-load term(s) left out (" +
                        which +
                        "): over these poses their lever barely varies, so the data cannot tell them from the "
                        "joint offsets the calibration identified");
  }
  const std::string gravity =
      o.gravity_load ? " and " + std::to_string(jf.functions.gravity_terms.size()) +
                           " gravity-load terms (largest deflection over the poses " +
                           format_number(std::round(jf.largest_gravity_deflection_mrad * 1e3) / 1e3) + " mrad)"
                     : std::string();
  const std::string by_poses =
      o.joint_function_degree == kJointFunctionDegreeByPoses
          ? " (" + std::to_string(kJointFunctionDegreeManyPoses) + " from " + std::to_string(kJointFunctionManyPoses) +
                " poses, else " + std::to_string(kJointFunctionDegreeFewPoses) + ")"
          : std::string();
  out.notes.push_back("joint error functions (Legendre degree " + std::to_string(degree) + by_poses +
                      " per joint" + gravity + ", ridge by generalized cross-validation: " +
                      format_number(std::round(jf.effective_parameters * 10) / 10) +
                      " effective parameters): residual RMS " + format_number(std::round(jf.rms_before_mm * 1e4) / 1e4) +
                      " -> " + format_number(std::round(jf.rms_after_mm * 1e4) / 1e4) +
                      " mm, largest joint angle error " +
                      format_number(std::round(jf.functions.largest_angle_error_mrad() * 1e3) / 1e3) +
                      " mrad; the field's variance calibration counts their leave-one-out inflation x" +
                      format_number(std::round(jf.leave_one_out_inflation * 1e3) / 1e3));
  return jf;
}

/// The joint functions again, by generalized least squares under the first field's covariance (the
/// residuals are correlated), then the field on what they leave, with the same variogram; or the
/// ordinary fit kept, when the GLS refit is not possible or the guard refuses it. `fit` holds the
/// first field on entry and the final field on return.
void refit_joint_functions(JointErrorFunctionFit& jf, const MeasurementSet& dd,
                           const std::vector<Eigen::Vector3d>& calibration_residual, const FieldSamples& own_samples,
                           const KrigingFieldOptions& ko, const FitOptions& o, KrigingFieldFit& fit, FitResult& out) {
  const double ordinary_rms = jf.rms_after_mm;
  const VariogramModel field_model = fit.model;
  fit = KrigingFieldFit{};  // the first field's N x N factorization is not needed any more
  const JointErrorFunctionFit ordinary = jf;
  const bool refitted =
      refit_by_generalized_least_squares(jf, dd.q_deg, calibration_residual, field_model, o.joint_function_prior);
  // A GLS fit that leaves the field far more than the ordinary one moved the functions into
  // what the correlated field absorbs at these poses: the two then cancel at the measured point
  // and nowhere else (real data: 0.89 mm left where the ordinary fit left 0.17 mm, issue 34).
  const bool moved_far = refitted && o.gls_guard_ratio > 0.0 && jf.rms_after_mm > o.gls_guard_ratio * ordinary_rms;
  if (moved_far) {
    out.notes.push_back("joint error functions: the refit by generalized least squares would leave an RMS of " +
                        format_number(std::round(jf.rms_after_mm * 1e4) / 1e4) + " mm to the field, over " +
                        format_number(o.gls_guard_ratio) + " x the " + format_number(std::round(ordinary_rms * 1e4) / 1e4) +
                        " mm the ordinary fit left (it moved the functions into what the field absorbs at "
                        "these poses), so they keep the ordinary fit");
    jf = ordinary;
    fit = fit_vector_kriging_field(own_samples, jf.remaining_mm, ko);
    set_coefficient_covariance(jf, dd.q_deg, fit.model);
  } else if (refitted) {
    fit = fit_vector_kriging_field(own_samples, jf.remaining_mm, ko);
    out.notes.push_back("joint error functions refitted by generalized least squares under the field's "
                        "covariance (" + format_number(std::round(jf.effective_parameters * 10) / 10) +
                        " effective parameters): they leave an RMS of " +
                        format_number(std::round(jf.rms_after_mm * 1e4) / 1e4) + " mm to the field (the ordinary fit left " +
                        format_number(std::round(ordinary_rms * 1e4) / 1e4) +
                        " mm, chasing clusters of correlated residuals)");
  } else {  // jf is as the ordinary fit left it
    fit = fit_vector_kriging_field(own_samples, jf.remaining_mm, ko);
    set_coefficient_covariance(jf, dd.q_deg, fit.model);
    if (jf.ridge_inverse.size() > 0)
      out.notes.push_back("joint error functions: the field's covariance at the poses is not positive definite "
                          "(repeated poses without a nugget), so they keep the ordinary fit");
  }
}

/// The final functions' size over the training poses, in the notes, and a warning when it is beyond
/// what a joint plausibly errs or when their polynomial and gravity-load parts cancel.
void note_joint_function_size(FitResult& out, const JointErrorFunctions& f, const MdhModel& model,
                              const std::vector<JointVector>& poses) {
  const JointErrorFunctions::Size size = f.size_over(model, poses);
  if (size.largest_joint < 0) return;
  const auto mrad = [](double v) { return format_number(std::round(v * 100.0) / 100.0); };
  const std::string cancelling =
      size.cancelling_joint < 0
          ? std::string()
          : "; at joint " + std::to_string(size.cancelling_joint + 1) + " a polynomial part of " +
                mrad(size.cancelling_polynomial_mrad) + " mrad against a gravity-load part of " +
                mrad(size.cancelling_gravity_mrad) + " mrad";
  out.notes.push_back("joint error functions as written: largest joint angle error over the " +
                      std::to_string(poses.size()) + " training poses " + mrad(size.largest_mrad) + " mrad (joint " +
                      std::to_string(size.largest_joint + 1) + ", gravity-load terms included)" + cancelling);
  if (std::optional<std::string> why = implausible_joint_functions(size)) out.warnings.push_back(std::move(*why));
}

/// Data of several points on the flange: the covariances the model states at a point between or
/// beyond the measured ones, from the fields' leave-one-out at the training poses.
void add_point_covariances(FitResult& out) {
  const std::optional<HeldOutAtPoints> held_out = held_out_at_fielded_points(out.model);
  if (!held_out)
    out.notes.push_back("warning: no flange_error_covariance and no rotation_calibration: a field holds no "
                        "leave-one-out per training pose (poses repeated at one point merge into one "
                        "location), so a point between the measured ones takes the sum of the fields' "
                        "standard deviations and the orientation's covariance their independent combination");
  if (const std::optional<FlangeErrorCovariance> c = held_out ? flange_error_covariance_of(out.model, *held_out) : std::nullopt) {
    out.model = out.model.with_flange_error_covariance(c);
    out.notes.push_back("a point between or beyond the measured ones takes the covariance of the fields' "
                        "leave-one-out errors at their points at " + std::to_string(c->poses) +
                        " training poses (how alike their errors are), larger where the fields' own variance is");
  }
  if (const std::optional<RotationCalibration> c = held_out ? rotation_calibration_of(out.model, *held_out) : std::nullopt) {
    out.model = out.model.with_rotation_calibration(c);
    out.notes.push_back("the flange's orientation error is predicted from the fields at " +
                        std::to_string(out.model.fielded_points().size()) +
                        " points; its covariance is that of the rotation their leave-one-out residuals "
                        "imply at " + std::to_string(c->poses) + " training poses (" +
                        format_number(std::round(std::sqrt(c->flange_covariance_rad2.trace() / 3.0) * 1e7) / 1e4) +
                        " mrad per axis, 1 sd), larger where the fields' own variance is");
  }
}

/// Data of several points on the flange: the orientation residual the other points measure, then
/// each further point's own field, so that every measured point is predicted from its own readings
/// and any other from the flange's rigid motion they imply (predict_error_at).
void add_further_points(FitResult& out, const MeasurementSet& d, const detail::KinematicFit& kin,
                        const Registration& reg, const std::vector<std::size_t>& other_points,
                        const KrigingFieldOptions& ko, const VariogramModel& field_model,
                        const std::function<HeldOutShift(const MdhModel&)>& shift_at) {
  const MeasuredOrientation m = measured_orientation(out.model, d, kin, reg, other_points);
  out.model = out.model.with_measured_orientation(m);
  // sigma is what the misses leave beyond the variance the model states there; none left is not
  // "0 mrad" of orientation error (the real UR10 probe fit printed that), but an orientation
  // error the stated variance already covers.
  const std::string sigma_text =
      m.sigma_rad > 0.0 ? format_number(std::round(m.sigma_rad * 1e7) / 1e4) + " mrad per axis (1 sd)"
                        : "none beyond the variance the model states there (their misses are within it)";
  out.notes.push_back("orientation residual of the flange measured at the other points' " + std::to_string(m.readings) +
                      " readings: " + sigma_text +
                      (!m.add_floor ? std::string()
                                     : " plus the 0.1 mrad floor (the points lie on a line: a rotation about it "
                                       "escapes them)") +
                      "; the variance at any other point on the flange counts it");
  KrigingFieldOptions point_options = ko;
  point_options.model = field_model;
  point_options.on_stage = nullptr;
  const std::vector<CompensationModel::LabelledPoint> fielded =
      fields_of_further_points(out.model, d, kin, reg, other_points, point_options, shift_at);
  std::string labels;
  for (const CompensationModel::LabelledPoint& lp : fielded)
    if (lp.field) labels += (labels.empty() ? "'" : ", '") + lp.label + "'";
  if (labels.empty()) return;
  out.model = out.model.with_flange_points(fielded);
  out.notes.push_back("the residuals at " + labels + " kriged on their own readings with the same variogram; "
                      "a point between the measured ones is predicted from the flange's rigid motion "
                      "their fields imply");
  add_point_covariances(out);
}

/// Kinematic calibration, then (kinematic+kriging) joint error functions and a field on what the
/// calibration leaves at the model's own point, then the further points on the flange.
FitResult fit_kinematic_model(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o, bool model_estimated) {
  const CompensationMethod method = o.method;
  const detail::KinematicFit kin = detail::fit_kinematic(robot, d, o);
  std::vector<CompensationModel::LabelledPoint> located;
  for (const auto& [label, p] : kin.located_points) located.push_back({label, p, nullptr});
  FitResult out{CompensationModel(CompensationMethod::kinematic, kin.model, nullptr)
                    .with_tool_point(kin.tool_point_mm, kin.reflector_mm)
                    .with_flange_points(located)
                    .with_calibration_leverage(kin.leverage),
                kin.registration, std::nullopt, kin.notes, kin.warnings};
  if (method == CompensationMethod::kinematic) return out;
  // Readings of several points on the flange: the functions and the field take the model's own point.
  const std::vector<std::size_t> other_points = rows_of_other_points(kin, d.q_deg.size());
  const MeasurementSet own_point = other_points.empty() ? MeasurementSet{} : without_rows(d, other_points);
  const MeasurementSet& dd = other_points.empty() ? d : own_point;
  const FieldSamples own_samples{dd.nominal_mm, dd.q_deg};
  const CalibrationResidual calibration = calibration_residual(kin, dd);
  if (!kin.registration) out.registration = calibration.registration;
  std::vector<Eigen::Vector3d> residual = calibration.residual_mm;
  std::optional<JointErrorFunctionFit> jf;
  if (o.joint_function_degree_for(dd.q_deg.size()) > 0) {
    jf = ordinary_joint_functions(kin, dd, residual, o, out);
    residual = jf->remaining_mm;
  }
  KrigingFieldOptions ko = field_options(o, model_estimated);
  ko.value_variance_inflation = jf ? jf->leave_one_out_inflation : 1.0;
  // The ordinary fit's leave-one-out, per sample of every field the functions are carried to
  // (the GLS refit keeps it, as it keeps the inflation).
  std::function<HeldOutShift(const MdhModel&)> shift_at;
  if (jf) {
    auto ordinary_fit = std::make_shared<const JointErrorFunctionFit>(*jf);
    shift_at = [ordinary_fit, poses = dd.q_deg, reflector = kin.model](const MdhModel& at) {
      return joint_function_held_out_shift(ordinary_fit, poses, reflector, at);
    };
    ko.held_out_shift = shift_at(kin.model);
  }
  std::string model_reason;
  if (!o.model && o.on_stage) o.on_stage("estimating the variogram");
  ko.model = chosen_model(o, own_samples, rows_of_vectors(residual), ko, model_reason);
  KrigingFieldFit fit = fit_vector_kriging_field(own_samples, residual, ko);
  std::optional<JointErrorFunctions> functions;
  if (jf) {
    refit_joint_functions(*jf, dd, calibration.residual_mm, own_samples, ko, o, fit, out);
    note_joint_function_size(out, jf->functions, kin.model, dd.q_deg);
    functions = std::move(jf->functions);
  }
  out.model = CompensationModel(method, kin.model, fit.field)
                  .with_tool_point(kin.tool_point_mm, kin.reflector_mm)
                  .with_joint_error_functions(std::move(functions))
                  .with_flange_points(located)
                  .with_calibration_leverage(kin.leverage);
  if (!other_points.empty())
    add_further_points(out, d, kin, calibration.registration, other_points, ko, fit.model, shift_at);
  out.cross_validation = kriging_report(fit, o.space, o);
  out.notes.push_back("residuals after calibration kriged with " + fit.model.to_string());
  note_kriged_field(out, fit, o.space, model_reason);
  return out;
}

FitResult fit_unchecked(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o, bool model_estimated) {
  switch (o.method) {
    case CompensationMethod::none:
      return {CompensationModel(o.method, robot, nullptr), std::nullopt, std::nullopt, {"no correction"}, {}};
    case CompensationMethod::distance_idw: return fit_distance_idw(robot, d, o);
    case CompensationMethod::position_idw: return fit_position_idw(robot, d, o);
    case CompensationMethod::distance_kriging: return fit_distance_kriging(robot, d, o, model_estimated);
    case CompensationMethod::vector_kriging: return fit_vector_kriging(robot, d, o, model_estimated);
    case CompensationMethod::kinematic:
    case CompensationMethod::kinematic_kriging: return fit_kinematic_model(robot, d, o, model_estimated);
  }
  throw ArgumentError("fit: unknown method");
}

FitResult fit_checked(const MdhModel& robot, const MeasurementSet& d, const FitOptions& o) {
  const bool estimated = !o.model;
  FitResult out = fit_unchecked(robot, d, o, estimated);
  // Judge the model before anyone writes it; an estimated variogram may be refitted with a nugget.
  return check_fitted_model(std::move(out), o, [&](const VariogramModel& m) {
    FitOptions again = o;
    again.model = m;
    return fit_unchecked(robot, d, again, estimated);
  });
}

/// Rows whose u = (|r| / σ) / (median |r| / σ over the rows / 1.5382) / √3 is above `limit`: the
/// robust scale of IGG3 for 3-D residuals, applied to residuals standardized by their own σ.
std::vector<std::size_t> beyond_robust_limit(const std::vector<double>& standardized, double limit) {
  std::vector<double> sorted = standardized;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double sigma0 = sorted[sorted.size() / 2] / 1.5382;  // median of a 3-D Gaussian residual's norm
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < standardized.size(); ++i)
    if (standardized[i] > limit * std::sqrt(3.0) * sigma0) rows.push_back(i);
  return rows;
}

/// The fit whose field judges gross outliers by leave-one-out against the predictive σ. For
/// kinematic+kriging, `fit` itself, in either space (a field without per-row leave-one-out, e.g.
/// repeated locations merged in task space, screens nothing). For kinematic (no field of its own),
/// the same options fitted as joint-space kinematic+kriging on the same rows, only to judge them,
/// when --model gives that field's variogram; estimating one would multiply the fit's time by 10-30
/// (measured on 60 and 150 rows), so without --model nothing is screened, and `why_none` says so.
/// Judging by the calibration residual alone (kinematic, and task space's fallback) dropped the
/// same 11 real edge rows on all three reflectors of a real arm and doubled the held-out maximum
/// (issue 35).
std::optional<FitResult> screening_fit(const FitResult& fit, const MdhModel& robot, const MeasurementSet& d,
                                       const FitOptions& o, std::string& why_none) {
  if (o.method == CompensationMethod::kinematic_kriging) return fit;
  if (!o.model) {
    why_none = "gross-outlier screen: none for --method kinematic without --model (rows are judged by a joint-space "
               "kinematic+kriging field; give its variogram with --model to screen them)";
    return std::nullopt;
  }
  FitOptions screen = o;
  screen.method = CompensationMethod::kinematic_kriging;
  screen.space = FieldSpace::joint;
  screen.outlier_limit = 0.0;
  try {
    return fit_checked(robot, d, screen);
  } catch (const Error& e) {
    why_none = std::string("gross-outlier screen: none (the joint-space field that judges the rows could not be "
                           "fitted: ") + e.what() + ")";
    return std::nullopt;
  }
}

/// Rows of `d` (all of them, also those a previous round excluded: `excluded`, sorted) that are
/// gross outliers (FitOptions::outlier_limit), judged by `fit`'s field (screening_fit): a row is
/// judged by how far its reading is from what its neighbours in the field's space predict, in units
/// of the predictive σ (nugget included): the leave-one-out residual for the rows the field holds,
/// the field's prediction for excluded rows. A row at the edge of the data, or
/// in a corner where the robot departs smoothly from its kinematic model, has a large σ or
/// neighbours that agree with it, so it is kept; a reading off among consistent neighbours is not.
/// The residual after calibration alone took real behaviour at the workspace extremes for outliers
/// (issue 19: 11 real rows at |q1| > 110 deg dropped, held-out maximum 3-4x worse), so it is never
/// used: without a per-row leave-one-out nothing is flagged.
std::vector<std::size_t> gross_outliers(const FitResult& fit, const MeasurementSet& d,
                                        const std::vector<std::size_t>& excluded, double limit) {
  const std::size_t n = d.q_deg.size();
  const ErrorField* field = fit.model.field();
  if (!field || !fit.registration) return {};
  const std::vector<SampleHoldOut> loo = leave_one_out_by_sample(*field);
  if (loo.size() + excluded.size() != n) return {};
  std::vector<double> standardized(n);
  std::size_t next_excluded = 0, next_kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (next_excluded < excluded.size() && excluded[next_excluded] == i) {
      ++next_excluded;
      // Not in the field: its held-out prediction is the field's own.
      const Eigen::Vector3d p = forward_position(fit.model.nominal_model(), d.q_deg[i]);
      const ErrorPrediction e = field->predict(p, d.q_deg[i]);
      const double variance = e.predictive_variance_mm2() / 3.0;  // per component
      const Eigen::Vector3d residual = fit.registration->robot_from_tracker * d.measured_mm[i] -
                                       forward_position(fit.model.command_model(), d.q_deg[i]) - e.position_error_mm;
      // Outside the field's region nothing is predicted there: no evidence against the row.
      standardized[i] = e.inside_region && variance > 0 ? residual.norm() / std::sqrt(variance) : 0.0;
      continue;
    }
    const SampleHoldOut& h = loo[next_kept++];
    standardized[i] = h.variance_mm2 > 0 ? h.residual_mm.norm() / std::sqrt(h.variance_mm2) : 0.0;
  }
  return beyond_robust_limit(standardized, limit);
}

MeasurementSet without_rows(const MeasurementSet& d, const std::vector<std::size_t>& rows) {
  MeasurementSet out = d;
  out.id.clear();
  out.q_deg.clear();
  out.nominal_mm.clear();
  out.reflector.clear();
  out.measured_mm.clear();
  for (auto& col : out.distance_mm) col.clear();
  std::size_t next = 0;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    if (next < rows.size() && rows[next] == i) {
      ++next;
      continue;
    }
    out.id.push_back(d.id[i]);
    out.q_deg.push_back(d.q_deg[i]);
    out.nominal_mm.push_back(d.nominal_mm[i]);
    if (!d.reflector.empty()) out.reflector.push_back(d.reflector[i]);
    if (!d.measured_mm.empty()) out.measured_mm.push_back(d.measured_mm[i]);
    for (std::size_t k = 0; k < d.distance_mm.size(); ++k) out.distance_mm[k].push_back(d.distance_mm[k][i]);
  }
  return out;
}

/// The points of `rows`, the first `limit` of them (0: all).
std::string point_list(const MeasurementSet& d, const std::vector<std::size_t>& rows, std::size_t limit = 0) {
  std::string s;
  const std::size_t shown = limit == 0 ? rows.size() : std::min(limit, rows.size());
  for (std::size_t k = 0; k < shown; ++k) s += (k ? ", " : "") + d.id[rows[k]];
  if (rows.size() > shown) s += ", ... (" + std::to_string(rows.size() - shown) + " more)";
  return s;
}

/// Rows of `d` (all of them, also those a previous round excluded: `excluded`, sorted; `fit` was
/// fitted without them) of readings of several points on the flange that are gross outliers, judged
/// as gross_outliers judges one point's: each row by its own point's field (the own point's, or the
/// field fitted at that label's readings) in units of the predictive σ, against the robust scale
/// of all judged rows: a kept row by its leave-one-out, an excluded one by the model's prediction
/// at its point. A label without a field of its own (fewer than 20 readings) is not judged.
std::vector<std::size_t> gross_outliers_at_points(const FitResult& fit, const MeasurementSet& d,
                                                  const std::vector<std::size_t>& excluded,
                                                  const std::string& own_label, double limit) {
  const CompensationModel& model = fit.model;
  if (!fit.registration) return {};
  struct Judged {
    const ErrorField* field;
    Eigen::Vector3d point_mm;  // flange frame
  };
  std::map<std::string, Judged> by_label;
  if (model.field()) by_label.emplace(own_label, Judged{model.field(), model.measured_point_mm()});
  for (const CompensationModel::LabelledPoint& p : model.flange_points())
    if (p.field) by_label.emplace(p.label, Judged{p.field.get(), p.position_mm});
  std::vector<std::size_t> judged_rows;
  std::vector<double> standardized;
  for (const auto& [label, judged] : by_label) {
    std::vector<std::size_t> kept_rows;
    for (std::size_t i = 0; i < d.reflector.size(); ++i)
      if (d.reflector[i] == label && !std::binary_search(excluded.begin(), excluded.end(), i)) kept_rows.push_back(i);
    const std::vector<SampleHoldOut> loo = leave_one_out_by_sample(*judged.field);
    if (loo.size() != kept_rows.size()) continue;  // merged repeated poses: no per-row leave-one-out
    for (std::size_t k = 0; k < kept_rows.size(); ++k) {
      judged_rows.push_back(kept_rows[k]);
      standardized.push_back(loo[k].variance_mm2 > 0 ? loo[k].residual_mm.norm() / std::sqrt(loo[k].variance_mm2) : 0.0);
    }
    const MdhModel at = model.command_model().with_tool_point(judged.point_mm);
    for (std::size_t i : excluded) {
      if (d.reflector[i] != label) continue;
      const ErrorPrediction e = model.predict_error_at(d.q_deg[i], at);
      const double variance = e.predictive_variance_mm2() / 3.0;  // per component
      const Eigen::Vector3d residual = fit.registration->robot_from_tracker * d.measured_mm[i] -
                                       forward_position(at, d.q_deg[i]) - e.position_error_mm;
      judged_rows.push_back(i);
      // Outside the field's region nothing is predicted there: no evidence against the row.
      standardized.push_back(e.inside_region && variance > 0 ? residual.norm() / std::sqrt(variance) : 0.0);
    }
  }
  std::vector<std::size_t> out;
  for (std::size_t k : beyond_robust_limit(standardized, limit)) out.push_back(judged_rows[k]);
  std::sort(out.begin(), out.end());
  return out;
}

/// Rows a round of the gross-outlier screen judges beyond the limit, given the fit without
/// `excluded`; none when nothing can judge them (the judge notes why in the fit).
using OutlierJudge = std::function<std::optional<std::vector<std::size_t>>(FitResult& fit,
                                                                           const std::vector<std::size_t>& excluded)>;

/// Up to three rounds of the gross-outlier screen over `d`: each round the rows `judge` names are
/// left out and the model fitted again (`out`, `kept`), until a round names the same rows (a row
/// near an outlier can look like one while the outlier is in the field, and comes back once it is
/// not). More than a fifth of the rows is no few gross outliers: all are kept and `out` warns.
/// Returns the rows left out (sorted).
std::vector<std::size_t> screen_gross_outliers(FitResult& out, MeasurementSet& kept, const MdhModel& robot,
                                               const MeasurementSet& d, const FitOptions& o, const OutlierJudge& judge,
                                               const std::string& likely_causes) {
  std::vector<std::size_t> excluded;
  for (int round = 0; round < 3; ++round) {
    const std::optional<std::vector<std::size_t>> rows = judge(out, excluded);
    if (!rows || *rows == excluded) break;
    if (rows->size() * 5 > d.q_deg.size()) {
      out.warnings.push_back(std::to_string(rows->size()) + " of " + std::to_string(d.q_deg.size()) +
                             " rows are beyond " + format_number(o.outlier_limit) + " robust sigma (" +
                             point_list(d, *rows, 10) +
                             "): too many to be a few gross outliers, so all were kept; check the data (" +
                             likely_causes + ")");
      break;
    }
    excluded = *rows;
    kept = without_rows(d, excluded);
    out = fit_checked(robot, kept, o);
  }
  return excluded;
}

/// Readings of several points on the flange: the model's own label resolved first (so the stored
/// artifacts — data joints, the nominal robot's registration — are that point's), then one round of
/// the gross-outlier screen over every fielded point's rows (gross_outliers_at_points).
FitResult fit_several_points(const MdhModel& robot, const MeasurementSet& d, const FitOptions& options) {
  refuse_several_points_for(d, options.method);
  if (d.measured_mm.empty())
    throw InputError(d.source + ": readings of several points on the flange (column 'reflector') need the measured "
                         "positions mx,my,mz",
                     d.source, 0, "mx");
  FitOptions o = options;
  if (o.tool_reflector.empty()) {
    std::vector<PositionMeasurement> pm;
    for (std::size_t i = 0; i < d.q_deg.size(); ++i) pm.push_back({d.q_deg[i], d.measured_mm.at(i), 0});
    o.tool_reflector = assign_flange_points(robot, pm, d.reflector, "", o.calibration, d.source).labels.front();
  }
  FitResult out = fit_checked(robot, d, o);
  // Gross outliers pull the one calibration of every point and are kriged as their point's field.
  // One round: the rows the first fit's fields judge beyond the limit are left out, and the model
  // fitted again.
  MeasurementSet kept = d;
  std::vector<std::size_t> excluded;
  // Up to three rounds, as for one point: a reading near a gross outlier can look like one while
  // the outlier is in its field, and comes back once it is not.
  if (o.outlier_limit > 0 && o.method == CompensationMethod::kinematic_kriging) {
    excluded = screen_gross_outliers(
        out, kept, robot, d, o,
        [&](FitResult& fit, const std::vector<std::size_t>& left_out) {
          return std::optional(gross_outliers_at_points(fit, d, left_out, o.tool_reflector, o.outlier_limit));
        },
        "a wrong robot or tool, a moved tracker, a reflector moved in its nest");
    if (!excluded.empty()) {
      std::string rows;
      for (std::size_t k = 0; k < excluded.size(); ++k)
        rows += (k ? ", " : "") + d.id[excluded[k]] + " (" + d.reflector[excluded[k]] + ")";
      const std::string what = std::to_string(excluded.size()) +
                               " row(s) excluded as gross outliers (a reading beyond " + format_number(o.outlier_limit) +
                               " robust sigma from what its neighbours in its own point's field predict, leave-one-out "
                               "in units of the predictive sigma; --outlier-limit): " + rows;
      out.notes.insert(out.notes.begin(), what);
      out.warnings.push_back(what + "; look at their measurements");
    }
  }
  std::vector<std::size_t> others;
  for (std::size_t i = 0; i < kept.reflector.size(); ++i)
    if (kept.reflector[i] != o.tool_reflector) others.push_back(i);
  out = attach_artifacts(std::move(out), robot, without_rows(kept, others));
  if (!excluded.empty()) {
    std::vector<std::string> names;
    for (std::size_t row : excluded) names.push_back(d.id[row] + " (" + d.reflector[row] + ")");
    out.model = out.model.with_excluded_rows(std::move(names));
  }
  return with_nominal_flange_points(std::move(out), robot, kept);
}

}  // namespace

FitResult fit_compensation_model(const robot::MdhModel& robot, const MeasurementSet& d, const FitOptions& options) {
  options.validate();
  if (options.choose_method) {
    const MethodChoice c = choose_method(d);
    FitOptions o = options;
    o.choose_method = false;
    o.method = c.method;
    FitResult out = fit_compensation_model(robot, d, o);
    out.notes.insert(out.notes.begin(), "method auto: " + std::string(method_name(c.method)) + " (" + c.reason + ")");
    return out;
  }
  if (d.reflector_labels().size() > 1) return fit_several_points(robot, d, options);
  const FitOptions& o = options;
  FitResult out = fit_checked(robot, d, o);
  const bool screened = o.outlier_limit > 0 && !d.measured_mm.empty() && out.registration &&
                        (o.method == CompensationMethod::kinematic || o.method == CompensationMethod::kinematic_kriging);
  if (!screened) return attach_artifacts(std::move(out), robot, d);
  // Gross outliers pull the calibration and, worse, are kriged as if they were the field: 3 %
  // of 5 mm tracker errors made the joint-space default 2.3x worse on clean held-out points.
  MeasurementSet kept = d;
  const bool screened_by_own_field = o.method == CompensationMethod::kinematic_kriging;
  const std::vector<std::size_t> excluded = screen_gross_outliers(
      out, kept, robot, d, o,
      [&](FitResult& fit, const std::vector<std::size_t>& left_out) -> std::optional<std::vector<std::size_t>> {
        std::string why_none;
        const std::optional<FitResult> screen = screening_fit(fit, robot, kept, o, why_none);
        if (!screen) {
          fit.notes.push_back(why_none);
          return std::nullopt;
        }
        return gross_outliers(*screen, d, left_out, o.outlier_limit);
      },
      "a wrong robot or tool, a moved tracker");
  if (excluded.empty()) return attach_artifacts(std::move(out), robot, d);
  const std::string how = "reading beyond " + format_number(o.outlier_limit) +
                          " robust sigma from what its neighbours in the field predict (leave-one-out, in units of "
                          "the predictive sigma, nugget included" +
                          (screened_by_own_field ? std::string(")")
                                                 : std::string("; judged by a joint-space kinematic+kriging field "
                                                               "fitted to the same rows)"));
  const std::string what = std::to_string(excluded.size()) + " row(s) excluded as gross outliers (" + how +
                           "; --outlier-limit): " + point_list(d, excluded);
  out.notes.insert(out.notes.begin(), what);
  out.warnings.push_back(what + "; look at their measurements");
  std::vector<std::string> points;
  for (std::size_t row : excluded) points.push_back(d.id[row]);
  out = attach_artifacts(std::move(out), robot, kept);
  out.model = out.model.with_excluded_rows(std::move(points));
  return out;
}

}  // namespace errfield::compensation
