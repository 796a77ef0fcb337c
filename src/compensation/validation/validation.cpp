#include "errfield/compensation/validation/validation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "errfield/compensation/model/error_ball.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/model/registration.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

ErrorStats ErrorStats::of(const std::vector<double>& errors) {
  std::vector<double> a;
  for (double e : errors)
    if (std::isfinite(e)) a.push_back(std::abs(e));
  ErrorStats s;
  s.count = a.size();
  if (a.empty()) return s;
  std::sort(a.begin(), a.end());
  double sum = 0.0, ss = 0.0;
  for (double v : a) {
    sum += v;
    ss += v * v;
  }
  const double n = static_cast<double>(a.size());
  s.mean_mm = sum / n;
  s.rms_mm = std::sqrt(ss / n);
  s.max_mm = a.back();
  const double rank = 0.95 * (n - 1.0);
  const std::size_t lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, a.size() - 1);
  s.p95_mm = a[lo] + (rank - static_cast<double>(lo)) * (a[hi] - a[lo]);
  return s;
}

namespace {

nlohmann::json stats_json(const ErrorStats& s) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"count", s.count}, {"mean_mm", num(s.mean_mm)}, {"max_mm", num(s.max_mm)}, {"rms_mm", num(s.rms_mm)},
          {"p95_mm", num(s.p95_mm)}};
}

nlohmann::json block_json(const BeforeAfter& b) {
  return {{"before", b.before ? stats_json(*b.before) : nlohmann::json(nullptr)}, {"after", stats_json(b.after)}};
}

std::string fmt(double v) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream s;
  s.precision(4);
  s << std::fixed << v;
  return s.str();
}

std::string stats_line(const std::string& label, const ErrorStats& s) {
  return "    " + label + ": mean " + fmt(s.mean_mm) + "  rms " + fmt(s.rms_mm) + "  p95 " + fmt(s.p95_mm) + "  max " +
         fmt(s.max_mm) + " mm (" + std::to_string(s.count) + " points)\n";
}

/// Stats of the points that were not refused; before and after over the same points.
void summarize(ValidationReport& r, bool has_before_positions, bool has_before_distances) {
  std::vector<double> pb, pa, db, da;
  bool positions = false;
  for (const ValidatedPoint& p : r.points) {
    if (!p.ok()) continue;
    if (std::isfinite(p.after_mm.x())) {
      positions = true;
      pa.push_back(p.after_mm.norm());
      pb.push_back(p.before_mm.norm());
    }
    for (std::size_t k = 0; k < p.distance_after_mm.size(); ++k) {
      da.push_back(p.distance_after_mm[k]);
      db.push_back(k < p.distance_before_mm.size() ? p.distance_before_mm[k] : NAN);
    }
  }
  // no block when positions were not scored (the notes say why)
  if (positions)
    r.position = BeforeAfter{has_before_positions ? std::optional(ErrorStats::of(pb)) : std::nullopt, ErrorStats::of(pa)};
  if (r.distance_columns > 0)
    r.distance = BeforeAfter{has_before_distances ? std::optional(ErrorStats::of(db)) : std::nullopt, ErrorStats::of(da)};
}

}  // namespace

nlohmann::json ValidationReport::summary_json() const {
  nlohmann::json j = {{"mode", mode}, {"points", points.size()}, {"refused", refused}};
  if (extrapolated > 0) j["extrapolated"] = extrapolated;
  j["position"] = position ? block_json(*position) : nlohmann::json(nullptr);
  if (position) {
    if (!before_registration.empty()) j["position"]["before_registration"] = before_registration;
    if (!after_registration.empty()) j["position"]["after_registration"] = after_registration;
  }
  if (distance) j["distance"] = block_json(*distance);
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j["uncertainty"] = uncertainty ? nlohmann::json{{"points", uncertainty->points},
                                                  {"coverage95", num(uncertainty->coverage95)},
                                                  {"mean_nees", num(uncertainty->mean_nees)}}
                                 : nlohmann::json(nullptr);
  j["notes"] = notes;
  return j;
}

std::string ValidationReport::summary_text() const {
  std::string s = "  " + std::to_string(points.size()) + " points, " + std::to_string(refused) + " refused (" + mode +
                  " mode)\n";
  auto block = [&](const std::string& name, const std::optional<BeforeAfter>& b, const std::string& before_frame,
                   const std::string& after_frame) {
    if (!b) return;
    s += "  " + name + " error:\n";
    if (b->before) s += stats_line("before", *b->before);
    if (b->before && !before_frame.empty()) s += "      (" + before_frame + ")\n";
    s += stats_line("after ", b->after);
    if (!after_frame.empty()) s += "      (" + after_frame + ")\n";
  };
  block("3-D position", position, before_registration, after_registration);
  block("distance", distance, "", "");
  if (uncertainty)
    s += "  predictive uncertainty (field + nugget) on " + std::to_string(uncertainty->points) +
         " points: " + fmt(100.0 * uncertainty->coverage95) + " % within the 95 % radius r95 (95 expected), mean " +
         "|e|^2/sigma^2 " + fmt(uncertainty->mean_nees) + " (3 expected)\n";
  for (const auto& n : notes) s += "  note: " + n + "\n";
  return s;
}

namespace {

/// The registration "before" is scored in: the nominal robot in its own best frame (docs/robot.md,
/// step 5 "Validate"), never the calibrated model's, which put a 0.66 mm robot at 1.23 mm on real
/// data. None when the rows cannot give one; `r` says which was used.
std::optional<Registration> before_registration_of(const CompensationModel& model, const MeasurementSet& d,
                                                   ValidationReport& r) {
  std::optional<Registration> before_registration;
  const bool kinematic =
      model.method() == CompensationMethod::kinematic || model.method() == CompensationMethod::kinematic_kriging;
  r.after_registration = "the model's stored registration, fitted on " + std::to_string(model.registration()->points) +
                         " training points";
  if (model.nominal_registration()) {
    before_registration = model.nominal_registration();
    r.before_registration = "the nominal robot's own registration, fitted on " +
                            std::to_string(model.nominal_registration()->points) + " training points";
  } else if (!kinematic) {
    before_registration = model.registration();  // fitted on the nominal robot's positions
    r.before_registration = "the model's stored registration (its robot is the nominal one), fitted on " +
                            std::to_string(model.registration()->points) + " training points";
  } else if (d.measured_mm.size() >= 3) {
    before_registration = fit_registration(d.measured_mm, d.nominal_mm);
    r.before_registration = "the nominal robot registered on these " + std::to_string(d.measured_mm.size()) +
                            " held-out rows (the model file stores no nominal registration; refit to get one)";
  }
  return before_registration;
}

/// Each base point's predicted position, and whether it is the distance field's own base (whose
/// distances the field predicts directly).
struct BasePredictions {
  std::vector<std::optional<Eigen::Vector3d>> position_mm;
  std::vector<bool> own_base;
};

BasePredictions base_predictions(const CompensationModel& model, const MeasurementSet& d, ValidationReport& r) {
  BasePredictions out;
  out.position_mm.resize(d.distance_mm.size());
  std::optional<Eigen::Vector3d> field_base;  // a distance field predicts the error of its own base's distances
  if (model.field()) {
    const nlohmann::json fj = model.field()->to_json();
    if (fj.contains("base_point_mm"))
      field_base = Eigen::Vector3d(fj["base_point_mm"][0].get<double>(), fj["base_point_mm"][1].get<double>(),
                                   fj["base_point_mm"][2].get<double>());
  }
  out.own_base.assign(d.distance_mm.size(), false);
  for (std::size_t k = 0; k < d.distance_mm.size(); ++k) {
    out.own_base[k] = field_base && (d.base_nominal_mm[k] - *field_base).norm() < 1e-6;
    if (k < d.base_q_deg.size()) {
      const PointPrediction b = predict_position(model, d.base_q_deg[k]);
      if (b.ok()) out.position_mm[k] = b.position_mm;
      else if (!out.own_base[k])
        r.notes.push_back("distances to b" + std::to_string(k) + " not scored after: the base point's own prediction is " +
                          std::string(status_name(b.status)));
    } else {
      out.position_mm[k] = d.base_nominal_mm[k];  // a fixed point in the cell: its nominal position
    }
  }
  return out;
}

/// How often the stated 95 % radius held the held-out error, and the mean normalized squared error.
std::optional<UncertaintyCheck> uncertainty_check(const std::vector<ValidatedPoint>& points) {
  UncertaintyCheck u;
  double within = 0.0, nees = 0.0;
  for (const ValidatedPoint& p : points) {
    if (!p.ok() || !std::isfinite(p.nees)) continue;
    ++u.points;
    within += p.after_mm.norm() <= p.r95_mm ? 1.0 : 0.0;
    nees += p.nees;
  }
  if (u.points == 0) return std::nullopt;
  u.coverage95 = within / static_cast<double>(u.points);
  u.mean_nees = nees / static_cast<double>(u.points);
  return u;
}

}  // namespace

ValidationReport validate_predictions(const CompensationModel& model, const MeasurementSet& d, bool extrapolate) {
  ValidationReport r;
  r.mode = "prediction";
  const bool positions = !d.measured_mm.empty() && model.registration().has_value();
  if (!d.measured_mm.empty() && !positions)
    r.notes.push_back("positions not scored: the model holds no tracker registration (fit or calibrate it from data "
                      "with mx,my,mz); held-out rows are never registered on themselves");
  std::optional<Registration> before_registration;
  if (positions) before_registration = before_registration_of(model, d, r);
  // Distances: frame-free, measured − predicted distance to each base point.
  r.distance_columns = d.distance_mm.size();
  const BasePredictions bases = base_predictions(model, d, r);
  const std::vector<std::optional<Eigen::Vector3d>>& base_pred = bases.position_mm;
  const std::vector<bool>& own_base = bases.own_base;
  for (std::size_t i = 0; i < d.q_deg.size(); ++i) {
    ValidatedPoint p;
    p.point = d.id[i];
    p.q_deg = d.q_deg[i];
    const PointPrediction pr = predict_position(model, d.q_deg[i], extrapolate);
    if (pr.status == PredictionStatus::extrapolated) {
      p.status = std::string(status_name(pr.status));
      ++r.extrapolated;
    } else if (!pr.ok()) {
      p.status = std::string(status_name(pr.status));
      ++r.refused;
      r.points.push_back(std::move(p));
      continue;
    }
    if (positions) {
      const Eigen::Vector3d m = model.registration()->robot_from_tracker * d.measured_mm[i];
      if (before_registration) p.before_mm = before_registration->robot_from_tracker * d.measured_mm[i] - d.nominal_mm[i];
      p.after_mm = m - pr.position_mm;
    }
    p.var_mm2 = pr.error.predictive_variance_mm2();
    p.var_field_mm2 = pr.error.variance_mm2;
    const Eigen::Vector3d& axis = pr.error.axis_variance_mm2;
    if (positions && axis.allFinite() && (axis.array() > 0.0).all()) {
      p.r95_mm = radius_with_probability(0.95, axis);
      p.nees = (p.after_mm.array().square() / axis.array()).sum();
    }
    for (std::size_t k = 0; k < d.distance_mm.size(); ++k) {
      const double measured = d.distance_mm[k][i];
      p.distance_before_mm.push_back(measured - (d.nominal_mm[i] - d.base_nominal_mm[k]).norm());
      double predicted = NAN;
      if (own_base[k] && std::isfinite(pr.error.distance_error_mm))
        predicted = (d.nominal_mm[i] - d.base_nominal_mm[k]).norm() + pr.error.distance_error_mm;
      else if (base_pred[k])
        predicted = (pr.position_mm - *base_pred[k]).norm();
      p.distance_after_mm.push_back(measured - predicted);
    }
    r.points.push_back(std::move(p));
  }
  if (r.extrapolated > 0)
    r.notes.push_back(std::to_string(r.extrapolated) + " of " + std::to_string(r.points.size()) +
                      " points lie beyond the model's region and were answered with --extrapolate (status extrapolated: "
                      "outside the field's region the calibration and joint error functions alone; "
                      "no variance is claimed for them); compensate refuses them");
  summarize(r, before_registration.has_value() || !positions, true);
  if (const std::optional<UncertaintyCheck> u = uncertainty_check(r.points)) r.uncertainty = u;
  return r;
}

namespace {

Eigen::Vector3d row_vector(const CsvTable& t, std::size_t row, const std::vector<std::size_t>& cols) {
  Eigen::Vector3d v;
  for (int c = 0; c < 3; ++c) {
    const std::string& cell = t.row(row)[cols[static_cast<std::size_t>(c)]];
    v[c] = cell.empty() ? NAN : t.numeric_cell(row, cols[static_cast<std::size_t>(c)]);
  }
  return v;
}

std::vector<std::size_t> columns_of(const CsvTable& t, const std::string& a, const std::string& b, const std::string& c) {
  if (!t.has_column(a) || !t.has_column(b) || !t.has_column(c)) return {};
  return {t.column_index(a), t.column_index(b), t.column_index(c)};
}

}  // namespace

ValidationReport validate_targets(const CsvTable& t, const std::optional<Registration>& registration,
                                  const std::vector<Eigen::Vector3d>& fixed_bases) {
  ValidationReport r;
  r.mode = "targets";
  std::vector<std::size_t> target = columns_of(t, "nx", "ny", "nz");
  if (target.empty()) target = columns_of(t, "x", "y", "z");
  if (target.empty())
    throw InputError(t.source() + ": --targets needs the intended target of each row: columns nx,ny,nz (written by "
                         "compensate) or x,y,z (robot frame, mm)",
                     t.source(), 0, "nx");
  const std::vector<std::size_t> measured = columns_of(t, "mx", "my", "mz");
  const bool positions = !measured.empty() && registration.has_value();
  if (!measured.empty() && !registration)
    r.notes.push_back("positions not scored: the model holds no tracker registration");
  std::size_t dist_cols = 0;
  while (t.has_column("dist_b" + std::to_string(dist_cols))) ++dist_cols;
  if (measured.empty() && dist_cols == 0)
    throw InputError(t.source() + ": nothing measured: expected mx,my,mz (tracker frame) or dist_b0, dist_b1, ...",
                     t.source(), 0, "mx");
  const auto col = [&](const std::string& name) -> std::optional<std::size_t> {
    return t.has_column(name) ? std::optional(t.column_index(name)) : std::nullopt;
  };
  const auto kind = col("kind"), run = col("run"), status = col("status"), point = col("point");
  // Base points: the target positions of base rows, else the given fixed points.
  std::vector<Eigen::Vector3d> bases;
  for (std::size_t i = 0; i < t.row_count(); ++i)
    if (kind && t.row(i)[*kind] == "base") bases.push_back(row_vector(t, i, target));
  if (bases.empty()) bases = fixed_bases;
  if (bases.size() < dist_cols)
    throw InputError(t.source() + ": " + std::to_string(dist_cols) + " distance columns but " +
                         std::to_string(bases.size()) + " base points (rows with kind=base, or --base-point X,Y,Z)",
                     t.source());
  r.distance_columns = dist_cols;
  // The joints of each point, for the report's per-joint view: the nominal joints compensate wrote, else q1..q6.
  std::vector<std::size_t> joints;
  for (const char* prefix : {"nq", "q"}) {
    if (!joints.empty()) break;
    for (int k = 1; k <= 6; ++k)
      if (t.has_column(prefix + std::to_string(k))) joints.push_back(t.column_index(prefix + std::to_string(k)));
    if (joints.size() != 6) joints.clear();
  }
  std::map<std::string, std::size_t> index;  // point name -> entry in r.points
  bool any_before = false;
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    const std::string line = t.source() + ":" + std::to_string(t.line_of_row(i));
    if (kind && t.row(i)[*kind] == "base") continue;
    if (kind && t.row(i)[*kind] != "target")
      throw InputError(line + ": column 'kind': '" + t.row(i)[*kind] + "'; expected base or target", t.source(),
                       t.line_of_row(i), "kind");
    const std::string name = point ? t.row(i)[*point] : "row" + std::to_string(t.line_of_row(i));
    const std::string which = run ? t.row(i)[*run] : "after";
    if (which != "before" && which != "after")
      throw InputError(line + ": column 'run': '" + which + "'; expected before or after", t.source(), t.line_of_row(i),
                       "run");
    auto [it, fresh] = index.emplace(name, r.points.size());
    if (fresh) {
      r.points.emplace_back();
      r.points.back().point = name;
      r.points.back().distance_before_mm.assign(dist_cols, NAN);
      r.points.back().distance_after_mm.assign(dist_cols, NAN);
    }
    ValidatedPoint& p = r.points[it->second];
    const bool before = which == "before";
    if (!joints.empty() && !before)
      for (int k = 0; k < 6; ++k) {
        const std::string& cell = t.row(i)[joints[static_cast<std::size_t>(k)]];
        p.q_deg[k] = cell.empty() ? NAN : t.numeric_cell(i, joints[static_cast<std::size_t>(k)]);
      }
    any_before = any_before || before;
    if (!before && status && t.row(i)[*status] != "ok") {
      p.status = "refused";  // compensate sent nothing for it
      continue;
    }
    const Eigen::Vector3d goal = row_vector(t, i, target);
    bool measured_any = false;
    if (positions) {
      const Eigen::Vector3d m = row_vector(t, i, measured);
      if (m.allFinite()) {
        (before ? p.before_mm : p.after_mm) = registration->robot_from_tracker * m - goal;
        measured_any = true;
      }
    }
    for (std::size_t k = 0; k < dist_cols; ++k) {
      const std::size_t c = t.column_index("dist_b" + std::to_string(k));
      if (t.row(i)[c].empty()) continue;
      (before ? p.distance_before_mm : p.distance_after_mm)[k] = t.numeric_cell(i, c) - (goal - bases[k]).norm();
      measured_any = true;
    }
    if (!before && !measured_any && p.status == "ok") p.status = "no-measurement";
  }
  for (const ValidatedPoint& p : r.points) r.refused += p.ok() ? 0 : 1;
  if (!any_before)
    r.notes.push_back("no rows with run=before: only the errors after compensation are scored");
  summarize(r, any_before, any_before);
  return r;
}

}  // namespace errfield::compensation
