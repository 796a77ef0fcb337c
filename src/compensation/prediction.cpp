#include "errfield/compensation/prediction.hpp"

#include <fstream>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

std::string_view status_name(PredictionStatus s) {
  switch (s) {
    case PredictionStatus::ok: return "ok";
    case PredictionStatus::outside_region: return "outside-region";
    case PredictionStatus::not_credible: return "not-credible";
  }
  return "unknown";
}

PointPrediction predict_position(const CompensationModel& model, const JointVector& q_deg) {
  PointPrediction out;
  out.error = model.predict_error(q_deg);
  if (!out.error.inside_region) {
    out.status = PredictionStatus::outside_region;
    return out;
  }
  if (!out.error.credible) {
    out.status = PredictionStatus::not_credible;
    return out;
  }
  out.position_mm = forward_position(model.command_model(), q_deg) + out.error.position_error_mm;
  if (model.registration()) out.tracker_mm = model.registration()->robot_from_tracker.inverse() * out.position_mm;
  return out;
}

LoadedModel load_model(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open model file '" + path + "'", path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path + ": not valid JSON: " + e.what(), path);
  }
  if (j.is_object() && j.contains("format")) {
    CompensationModel m = CompensationModel::from_json(j, path);
    const std::string what = std::string(method_name(m.method())) + " model";
    return {std::move(m), false, what};
  }
  // Anything else is read as a robot JSON, whose reader names what is missing or wrong.
  // The registration is not part of the robot description: read it, then the robot without it.
  std::optional<Registration> reg = find_registration(j, path);
  nlohmann::json robot_json = j;
  robot_json.erase("registration");
  MdhModel robot = MdhModel::from_json(robot_json, path);
  const std::string what = "robot JSON '" + robot.name() + "'";
  CompensationModel m = CompensationModel(CompensationMethod::kinematic, std::move(robot), nullptr).with_registration(reg);
  return {std::move(m), true, what};
}

}  // namespace errfield::compensation
