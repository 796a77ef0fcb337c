#include "errfield/compensation/planning/pose_selection.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "errfield/compensation/model/kriging_fields.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/sampling_design.hpp"

namespace errfield::compensation {

void PoseSelectionOptions::validate() const {
  if (count == 0) throw ArgumentError("PoseSelectionOptions::count: expected at least 1 pose to choose");
  if (target_rms_mm && !(*target_rms_mm > 0.0 && std::isfinite(*target_rms_mm)))
    throw ArgumentError("PoseSelectionOptions::target_rms_mm: " + format_number(*target_rms_mm) +
                        "; expected a finite RMS > 0 (mm)");
  if (max_references == 0) throw ArgumentError("PoseSelectionOptions::max_references: expected at least 1");
  if (!(spacing_floor >= 0.0 && spacing_floor < 1.0))
    throw ArgumentError("PoseSelectionOptions::spacing_floor: " + format_number(spacing_floor) +
                        "; expected a fraction in [0, 1)");
}

namespace {

Eigen::MatrixXd joint_rows(const std::vector<robot::JointVector>& q) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(q.size()), robot::kJointCount);
  for (std::size_t i = 0; i < q.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = q[i].transpose();
  return x;
}

Eigen::MatrixXd position_rows(const std::vector<robot::JointVector>& q, const robot::MdhModel& model) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(q.size()), 3);
  for (std::size_t i = 0; i < q.size(); ++i)
    x.row(static_cast<Eigen::Index>(i)) = robot::forward_position(model, q[i]).transpose();
  return x;
}

}  // namespace

namespace {

bool joints_less(const robot::JointVector& a, const robot::JointVector& b) {
  return std::lexicographical_compare(a.data(), a.data() + robot::kJointCount, b.data(), b.data() + robot::kJointCount);
}

PoseSelection select_distinct_poses(const std::vector<robot::JointVector>& candidates,
                                    const std::vector<robot::JointVector>& measured, const CompensationModel* model,
                                    const PoseSelectionOptions& options);

}  // namespace

PoseSelection select_poses(const std::vector<robot::JointVector>& candidates,
                           const std::vector<robot::JointVector>& measured, const CompensationModel* model,
                           const PoseSelectionOptions& options) {
  options.validate();
  // Repeats of an earlier candidate or of a measured pose are left out before the choice (sorted
  // once: pools run to 10,000 poses).
  std::vector<std::size_t> order(candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return joints_less(candidates[a], candidates[b]); });
  std::vector<robot::JointVector> done = measured;
  std::sort(done.begin(), done.end(), joints_less);
  std::vector<char> left_out(candidates.size(), 0);
  std::vector<std::size_t> repeated, already_measured;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    if (k > 0 && candidates[order[k - 1]] == candidates[i]) {
      repeated.push_back(i);
      left_out[i] = 1;
    } else if (std::binary_search(done.begin(), done.end(), candidates[i], joints_less)) {
      already_measured.push_back(i);
      left_out[i] = 1;
    }
  }
  // The first of equal candidates is the one kept (stable sort), and a kept repeat's later copies
  // still count as repeats, not as measured.
  std::vector<robot::JointVector> open;
  std::vector<std::size_t> row_of_open;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (!left_out[i]) open.push_back(candidates[i]), row_of_open.push_back(i);
  if (open.size() < options.count)
    throw ArgumentError("PoseSelectionOptions::count: " + std::to_string(options.count) + " poses asked, but " +
                        std::to_string(open.size()) + " of the " + std::to_string(candidates.size()) +
                        " candidates are distinct poses not measured yet (" + std::to_string(repeated.size()) +
                        " repeat an earlier candidate, " + std::to_string(already_measured.size()) +
                        " a measured pose)");
  PoseSelection out = select_distinct_poses(open, measured, model, options);
  for (std::size_t& c : out.chosen) c = row_of_open[c];
  std::sort(repeated.begin(), repeated.end());
  std::sort(already_measured.begin(), already_measured.end());
  out.repeated = std::move(repeated);
  out.already_measured = std::move(already_measured);
  return out;
}

namespace {

PoseSelection maximin_selection(const std::vector<robot::JointVector>& candidates,
                                const std::vector<robot::JointVector>& measured, const PoseSelectionOptions& options) {
  PoseSelection out;
  MaximinOptions mo;
  mo.count = options.count;
  out.chosen = select_maximin(joint_rows(candidates), joint_rows(measured), mo);
  out.design = "maximin in joint space (each joint scaled by its spread over the pool), away from the " +
               std::to_string(measured.size()) + " poses measured so far: no model yet";
  return out;
}

std::vector<robot::JointVector> joints_of(const nlohmann::json& rows) {
  std::vector<robot::JointVector> out;
  for (const auto& q : rows) {
    robot::JointVector v;
    for (int k = 0; k < robot::kJointCount; ++k) v[k] = q.at(static_cast<std::size_t>(k)).get<double>();
    out.push_back(v);
  }
  return out;
}

/// What planning reads of a model's vector-kriging field: its variogram, its space, its samples
/// (where and what) and the poses it is conditioned on.
struct FieldForPlanning {
  nlohmann::json json;
  VariogramModel variogram;
  bool joint = false;
  const robot::MdhModel* where = nullptr;  ///< the robot that maps joints to task-space locations
  /// Conditioned on the field's own training poses and on the measured ones it has not seen yet.
  std::vector<robot::JointVector> known;
  Eigen::MatrixXd sample_locations, sample_values;

  Eigen::MatrixXd locations(const std::vector<robot::JointVector>& poses) const {
    return joint ? joint_rows(poses) : position_rows(poses, *where);
  }
};

FieldForPlanning field_for_planning(const CompensationModel& model, const std::vector<robot::JointVector>& measured) {
  FieldForPlanning f;
  f.json = model.field()->to_json();
  const nlohmann::json& field = f.json;
  const std::string kind = field.value("kind", std::string());
  if (kind != "vector-kriging")
    throw ArgumentError(std::string("planning with a model needs a vector-kriging field (kinematic+kriging or "
                                    "vector-kriging); this ") +
                        std::string(method_name(model.method())) + " model's field is " + (kind.empty() ? "unnamed" : kind));
  f.variogram = VariogramModel::parse(field.at("model").get<std::string>());
  f.joint = field.value("space", std::string("task")) == "joint";
  f.known = measured;
  for (const robot::JointVector& v : joints_of(field.at("samples").at("joints_deg"))) {
    bool seen = false;
    for (const auto& m : measured) seen = seen || (m - v).cwiseAbs().maxCoeff() < 1e-9;
    if (!seen) f.known.push_back(v);
  }
  f.where = model.has_nominal_model() ? &model.nominal_model() : &model.command_model();
  const auto& fv = field.at("values");
  f.sample_values.resize(static_cast<Eigen::Index>(fv.size()), 3);
  for (std::size_t i = 0; i < fv.size(); ++i)
    for (int k = 0; k < 3; ++k) f.sample_values(static_cast<Eigen::Index>(i), k) = fv.at(i).at(static_cast<std::size_t>(k)).get<double>();
  f.sample_locations = f.locations(joints_of(field.at("samples").at("joints_deg")));
  return f;
}

/// The prediction's level and its local shape, from the field's leave-one-out scores, as the
/// variance scale of each pool pose and each measured pose (`pool`, `done`: their locations).
/// fit calibrates the variance so that 95 % of its leave-one-out errors fall in the 95 % region (the
/// larger of the mean z² and the tail's factor), which suits r95, not a mean: a mean squared error
/// needs the mean z². Where fit took the tail, the variance is scaled back by mean / factor (fit's
/// own mean, which counts the joint error functions' leave-one-out inflation); the local scale
/// gives the shape only (its mean over the samples is 1). Before, the local scale multiplied the
/// calibrated variance by plan's own z² (no inflation): on SIMULATED KR 16 and UR5e draws the
/// prediction came out 4-16 % below the held-out RMS at 120-240 poses (docs/robot.md).
void set_variance_scales(const FieldForPlanning& f, const Eigen::MatrixXd& pool, const Eigen::MatrixXd& done,
                         const PoseSelectionOptions& options, VarianceReductionOptions& vo, PoseSelection& out) {
  const std::vector<double> z2 = leave_one_out_squared_z(f.sample_locations, f.sample_values, f.variogram);
  double z2_mean = 1.0, level = 1.0;
  if (!z2.empty()) {
    double sum = 0.0, sum2 = 0.0;
    for (double z : z2) sum += z, sum2 += z * z;
    const double n = static_cast<double>(z2.size());
    z2_mean = sum / n;
    const double sd = std::sqrt(std::max(sum2 / n - z2_mean * z2_mean, 0.0) * n / std::max(n - 1.0, 1.0));
    // The mean z² of N scores, standard error sd / sqrt(N), relative to the mean: that of the
    // predicted mean squared error (the RMS's is half of it).
    if (z2_mean > 0.0) out.predicted_mse_relative_se = sd / z2_mean / std::sqrt(n);
    out.leave_one_out_scores = z2.size();
    level = z2_mean;
  }
  if (const auto c = f.json.find("variance_calibration"); c != f.json.end() && c->contains("factor") &&
                                                            c->contains("mean_squared_z_before")) {
    const double factor = c->at("factor").get<double>(), mean = c->at("mean_squared_z_before").get<double>();
    if (factor > 0.0 && mean > 0.0 && std::isfinite(factor) && std::isfinite(mean)) level = mean / factor;
  }
  const std::vector<double> ones_pool(static_cast<std::size_t>(pool.rows()), 1.0), ones_done(static_cast<std::size_t>(done.rows()), 1.0);
  vo.variance_scale = ones_pool;
  if (done.rows() > 0) vo.measured_scale = ones_done;
  if (options.local_scale && !z2.empty() && z2_mean > 0.0) {
    // Where the model's own leave-one-out errors were larger than its variance said (e.g. the
    // workspace edges of a robot whose errors grow there), weight the choice and the prediction.
    vo.variance_scale = local_error_scale(f.sample_locations, z2, f.variogram, pool);
    if (done.rows() > 0) vo.measured_scale = local_error_scale(f.sample_locations, z2, f.variogram, done);
    for (double& v : vo.variance_scale) v /= z2_mean;
    for (double& v : vo.measured_scale) v /= z2_mean;
  }
  for (double& v : vo.variance_scale) v *= level;
  for (double& v : vo.measured_scale) v *= level;
}

/// The joint error functions (kinematic+kriging fitted with them): their estimation variance is
/// part of every prediction, and a pose informs them by its lever on each joint at each angle,
/// wherever the field is; the choice weighs both. Measured: without this term, adaptive
/// selection lost to maximin at every count once the functions were in the model (docs/robot.md).
/// The field's kriging takes back the functions' error where measured poses are near, so the
/// design at the measured poses is given too.
void set_joint_function_term(const CompensationModel& model, const std::vector<robot::JointVector>& candidates,
                             const std::vector<robot::JointVector>& known, VarianceReductionOptions& vo) {
  const auto& f = model.joint_error_functions();
  if (!f || f->coefficient_covariance_mrad2.size() == 0 || candidates.empty()) return;
  vo.linear_term.components = 3;
  vo.linear_term.covariance = f->coefficient_covariance_mrad2;
  auto design_at = [&](const std::vector<robot::JointVector>& poses) {
    Eigen::MatrixXd rows(3 * static_cast<Eigen::Index>(poses.size()), f->coefficient_covariance_mrad2.cols());
    for (std::size_t i = 0; i < poses.size(); ++i)
      rows.middleRows(3 * static_cast<Eigen::Index>(i), 3) = f->design_rows(model.command_model(), poses[i]);
    return rows;
  };
  vo.linear_term.candidate_rows = design_at(candidates);
  vo.linear_term.measured_rows = design_at(known);
}

/// The plan's predicted RMS after each chosen pose (with its range), and the counts that reach
/// the target.
void report_predicted_rms(const VarianceReductionPlan& plan, double lower, double upper,
                          const PoseSelectionOptions& options, PoseSelection& out) {
  // The field's variogram is that of one component; a reading's 3-D error sums three.
  for (double mse : plan.predicted_mse) {
    out.predicted_rms_mm.push_back(std::sqrt(3.0 * mse));
    out.predicted_rms_low_mm.push_back(std::sqrt(3.0 * mse * lower));
    out.predicted_rms_high_mm.push_back(std::sqrt(3.0 * mse * upper));
  }
  if (!options.target_rms_mm) return;
  auto first_reaching = [&](const std::vector<double>& rms) -> std::optional<std::size_t> {
    for (std::size_t k = 0; k < rms.size(); ++k)
      if (rms[k] <= *options.target_rms_mm) return k;
    return std::nullopt;
  };
  out.poses_for_target = first_reaching(out.predicted_rms_mm);
  out.poses_for_target_low = first_reaching(out.predicted_rms_low_mm);
  out.poses_for_target_high = first_reaching(out.predicted_rms_high_mm);
}

PoseSelection select_distinct_poses(const std::vector<robot::JointVector>& candidates,
                                    const std::vector<robot::JointVector>& measured, const CompensationModel* model,
                                    const PoseSelectionOptions& options) {
  if (!model || !model->field()) {
    if (model)
      throw ArgumentError("a " + std::string(method_name(model->method())) +
                          " model has no error field to plan for; plan without --model (maximin) or fit "
                          "kinematic+kriging first");
    return maximin_selection(candidates, measured, options);
  }
  PoseSelection out;
  const FieldForPlanning f = field_for_planning(*model, measured);
  out.conditioned_on = f.known.size();
  const Eigen::MatrixXd pool = f.locations(candidates);
  const Eigen::MatrixXd done = f.locations(f.known);
  VarianceReductionOptions vo;
  // The predicted RMS is over the whole pool: the candidates and the poses measured already (in
  // plan's use the pool rows of --data), as the poses asked for later will be spread.
  vo.measured_in_prediction = true;
  set_variance_scales(f, pool, done, options, vo, out);
  if (options.extend_region) {
    // The model refuses a pose outside the box of its samples (widened by its margin): a pool pose
    // beyond the box of what is measured would stay refused after the next fit. Each axis' and
    // side's farthest such pose comes first (at most 2 per axis), whatever its variance reduction;
    // measured on SIMULATED KR 16 with a 687-pose pool, variance reduction alone left 5 of 295
    // held-out poses refused after 240 poses where maximin left none (docs/robot.md).
    const double margin = f.joint ? f.json.value("region_margin_deg", 0.0) + kRegionToleranceDeg
                                  : f.json.value("region_margin_mm", 0.0) + kRegionToleranceMm;
    vo.first_picks = box_extending_picks(pool, done, margin, options.count);
  }
  set_joint_function_term(*model, candidates, f.known, vo);
  vo.spacing_floor = options.spacing_floor;
  vo.count = options.count;
  vo.lookahead = options.target_rms_mm ? options.max_lookahead : 0;
  // The look-ahead only serves "how many more poses": it ends where the prediction reaches the
  // target (an unreachable target still costs all of it: 17.6 s at 10,000 candidates, 500 measured).
  // It goes on until the prediction's upper bound reaches the target, so the advice can say a range.
  const double upper = 1.0 + kPredictionRangeZ * out.predicted_mse_relative_se;
  const double lower = std::max(1.0 - kPredictionRangeZ * out.predicted_mse_relative_se, 0.0);
  if (options.target_rms_mm)
    vo.lookahead_done = [target = *options.target_rms_mm, upper](double mse) { return std::sqrt(3.0 * mse * upper) <= target; };
  vo.max_references = options.max_references;
  const VarianceReductionPlan plan = select_by_variance_reduction(pool, done, f.variogram, vo);
  out.chosen = plan.chosen;
  report_predicted_rms(plan, lower, upper, options, out);
  out.region_extending = vo.first_picks.size();
  out.design = (vo.first_picks.empty() ? std::string()
                                       : std::to_string(vo.first_picks.size()) +
                                             " poses that extend the fitted region to the pool's extent, then ") +
               std::string("integrated variance reduction under the model's field (") + (f.joint ? "joint" : "task") +
               " space)" + (vo.linear_term.covariance.size() > 0 ? " and its joint error functions" : "") +
               (vo.spacing_floor > 0.0 ? " among the poses at least " + format_number(vo.spacing_floor) +
                                             " of the farthest one's distance from everything measured or chosen"
                                       : std::string()) +
               ", conditioned on " + std::to_string(f.known.size()) +
               " measured poses; predicted RMS over " + std::to_string(plan.references) + " pool poses";
  return out;
}

}  // namespace

}  // namespace errfield::compensation
