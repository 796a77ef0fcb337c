#include "errfield/compensation/validation/rotation_validation.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "errfield/compensation/model/flange_rotation.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

nlohmann::json mdeg_stats_json(const ErrorStats& s) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"count", s.count}, {"mean_mdeg", num(s.mean_mm)}, {"max_mdeg", num(s.max_mm)}, {"rms_mdeg", num(s.rms_mm)},
          {"p95_mdeg", num(s.p95_mm)}};
}

std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

std::string mdeg_line(const std::string& label, const ErrorStats& s) {
  return "    " + label + ": mean " + fixed(s.mean_mm, 2) + "  rms " + fixed(s.rms_mm, 2) + "  p95 " +
         fixed(s.p95_mm, 2) + "  max " + fixed(s.max_mm, 2) + " mdeg (" + std::to_string(s.count) + " poses)\n";
}

}  // namespace

nlohmann::json RotationCheck::summary_json() const {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"poses", poses.size()},
          {"refused", refused},
          {"before", before ? mdeg_stats_json(*before) : nlohmann::json(nullptr)},
          {"after", mdeg_stats_json(after)},
          {"coverage95", num(coverage95)},
          {"mean_nees", num(mean_nees)}};
}

std::string RotationCheck::summary_text() const {
  std::string s = "  flange orientation error (" + std::to_string(poses.size()) + " poses with three or more points, " +
                  std::to_string(refused) + " refused):\n";
  if (before) s += mdeg_line("before", *before);
  s += mdeg_line("after ", after);
  s += "    predictive uncertainty: " + fixed(100.0 * coverage95, 1) +
       " % within the 95 % radius (95 expected), mean |e|^2/sigma^2 " + fixed(mean_nees, 3) + " (3 expected)\n";
  return s;
}

std::optional<RotationCheck> validate_rotations(const CompensationModel& model, const MeasurementSet& data,
                                                const MdhModel& nominal) {
  if (model.fielded_points().size() < 3 || !model.registration() || data.measured_mm.empty() || data.reflector.empty())
    return std::nullopt;
  // Each label's point on the flange, as the model located it.
  std::map<std::string, Eigen::Vector3d> located;
  std::map<std::string, std::optional<Eigen::Vector3d>> on_nominal;  // "before" needs every point's
  for (const CompensationModel::LabelledPoint& p : model.flange_points()) {
    located.emplace(p.label, p.position_mm);
    on_nominal.emplace(p.label, p.nominal_mm);
  }
  // The rows of each pose, in the order the poses first appear.
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::size_t>> rows_of;
  for (std::size_t i = 0; i < data.id.size(); ++i) {
    if (!located.count(data.reflector[i])) continue;
    auto [at, fresh] = rows_of.try_emplace(data.id[i]);
    if (fresh) order.push_back(data.id[i]);
    at->second.push_back(i);
  }
  const Registration& after_frame = *model.registration();
  const std::optional<Registration>& before_frame = model.nominal_registration();
  RotationCheck out;
  std::vector<double> before, after;
  double nees_sum = 0.0;
  std::size_t nees_count = 0;
  for (const std::string& pose : order) {
    const std::vector<std::size_t>& rows = rows_of[pose];
    const JointVector& q = data.q_deg[rows.front()];
    std::vector<Eigen::Vector3d> calibrated, uncompensated, after_error, before_error;
    bool with_before = before_frame.has_value();
    for (std::size_t i : rows) {
      const Eigen::Vector3d& p = located.at(data.reflector[i]);
      calibrated.push_back(forward_position(model.command_model().with_tool_point(p), q));
      after_error.push_back(after_frame.robot_from_tracker * data.measured_mm[i] - calibrated.back());
      const std::optional<Eigen::Vector3d>& p_nominal = on_nominal.at(data.reflector[i]);
      with_before = with_before && p_nominal.has_value();
      if (!with_before) continue;
      uncompensated.push_back(forward_position(nominal.with_tool_point(*p_nominal), q));
      before_error.push_back(before_frame->robot_from_tracker * data.measured_mm[i] - uncompensated.back());
    }
    const std::optional<FlangeRotationOperator> measured = FlangeRotationOperator::of(calibrated);
    if (!measured) continue;
    const std::optional<RotationPrediction> predicted = model.predict_rotation(q);
    if (!predicted) return std::nullopt;
    ValidatedRotation v;
    v.point = pose;
    v.readings = rows.size();
    v.status = predicted->status;
    if (v.status != "ok") {
      ++out.refused;
      out.poses.push_back(v);
      continue;
    }
    const Eigen::Vector3d e = measured->rotation_rad(after_error) - predicted->rotation_rad;
    v.after_mdeg = kMdegPerRad * e;
    if (with_before) {
      const std::optional<FlangeRotationOperator> nominal_points = FlangeRotationOperator::of(uncompensated);
      if (nominal_points) v.before_mdeg = kMdegPerRad * nominal_points->rotation_rad(before_error);
    }
    v.r95_mdeg = kMdegPerRad * predicted->radius95_rad();
    v.nees = predicted->nees(e);
    after.push_back(v.after_mdeg.norm());
    before.push_back(v.before_mdeg.norm());
    if (std::isfinite(v.r95_mdeg) && v.after_mdeg.norm() <= v.r95_mdeg) ++out.covered;
    if (std::isfinite(v.nees)) {
      nees_sum += v.nees;
      ++nees_count;
    }
    out.poses.push_back(v);
  }
  if (out.poses.empty()) return std::nullopt;
  out.after = ErrorStats::of(after);
  if (std::any_of(before.begin(), before.end(), [](double b) { return std::isfinite(b); })) out.before = ErrorStats::of(before);
  if (!after.empty()) out.coverage95 = static_cast<double>(out.covered) / static_cast<double>(after.size());
  if (nees_count) out.mean_nees = nees_sum / static_cast<double>(nees_count);
  return out;
}

}  // namespace errfield::compensation
