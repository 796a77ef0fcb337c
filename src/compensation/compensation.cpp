#include "errfield/compensation/compensation.hpp"

#include <cmath>

#include "errfield/error.hpp"
#include "errfield/compensation/error_fields.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/kinematics.hpp"

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
    : method_(method), command_model_(std::move(command_model)), field_(std::move(field)) {}

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
  if (field_) {
    out.prediction = field_->predict(p_nominal, q_nominal_deg);
    if (!out.prediction.inside_region) {
      out.command_position_mm = p_nominal;
      return out;
    }
    if (tolerance_mm > 0.0) out.p_within_tolerance = probability_within(tolerance_mm, out.prediction.variance_mm2);
  }
  out.command_position_mm = p_nominal - out.prediction.position_error_mm;
  if (method_ == CompensationMethod::none) return out;
  pose.translation() = out.command_position_mm;
  // A calibrated model is used through compensated_joints (its orientation parameters are weakly
  // determined by position/distance data, so full-pose IK of it would follow them).
  const bool calibrated =
      method_ == CompensationMethod::kinematic || method_ == CompensationMethod::kinematic_kriging;
  const IkResult cmd = calibrated ? compensated_joints(nominal_model, command_model_, pose, q_nominal_deg)
                                  : inverse_kinematics(command_model_, pose, q_nominal_deg, ik);
  out.ik_status = cmd.status;
  out.ik_residual_mm = cmd.position_residual_mm;
  if (cmd.ok()) out.q_command_deg = cmd.q_deg;
  return out;
}

nlohmann::json CompensationModel::to_json() const {
  nlohmann::json j;
  j["format"] = "errfield-compensation-model";
  j["version"] = 1;
  j["method"] = std::string(method_name(method_));
  j["command_model"] = command_model_.to_json();
  j["field"] = field_ ? field_->to_json() : nlohmann::json(nullptr);
  return j;
}

namespace {
[[noreturn]] void fail_model(const std::string& source, const std::string& what) {
  throw InputError(source + ": " + what, source);
}
}  // namespace

CompensationModel CompensationModel::from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) fail_model(source, "expected a JSON object (an errfield compensation model)");
  if (j.value("format", std::string()) != "errfield-compensation-model")
    fail_model(source, "member \"format\" must be \"errfield-compensation-model\" (is this a model written by 'errfield fit'?)");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"].get<int>() != 1)
    fail_model(source, "member \"version\": expected 1");
  if (!j.contains("method") || !j["method"].is_string()) fail_model(source, "member \"method\": expected a string");
  CompensationMethod method;
  try {
    method = method_from_name(j["method"].get<std::string>());
  } catch (const ArgumentError& e) {
    fail_model(source, std::string("member \"method\": ") + e.what());
  }
  if (!j.contains("command_model")) fail_model(source, "member \"command_model\" is missing");
  MdhModel command = MdhModel::from_json(j["command_model"], source + " (command_model)");
  auto field = error_field_from_json(j.contains("field") ? j["field"] : nlohmann::json(nullptr), source);
  return CompensationModel(method, std::move(command), std::move(field));
}

}  // namespace errfield::compensation
