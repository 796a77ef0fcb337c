#include "errfield/compensation/model/prediction.hpp"

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/robot/kinematics.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

std::string_view status_name(PredictionStatus s) {
  switch (s) {
    case PredictionStatus::ok: return "ok";
    case PredictionStatus::outside_region: return "outside-region";
    case PredictionStatus::not_credible: return "not-credible";
    case PredictionStatus::outside_limits: return "outside-limits";
    case PredictionStatus::orientation_unknown: return "orientation-unknown";
    case PredictionStatus::calibration_extrapolated: return "calibration-extrapolated";
    case PredictionStatus::extrapolated: return "extrapolated";
  }
  return "unknown";
}

PredictionStatus prediction_status(const ErrorPrediction& e) {
  if (!e.inside_region) return PredictionStatus::outside_region;
  if (!e.credible) return PredictionStatus::not_credible;
  if (!e.orientation_supported) return PredictionStatus::orientation_unknown;
  if (!e.calibration_supported) return PredictionStatus::calibration_extrapolated;
  return PredictionStatus::ok;
}

PointPrediction predict_position(const CompensationModel& model, const JointVector& q_deg, bool extrapolate) {
  PointPrediction out;
  if (robot::joint_outside_limits(q_deg, model.nominal_model())) {
    out.status = PredictionStatus::outside_limits;
    return out;
  }
  out.error = model.predict_error(q_deg);
  out.status = prediction_status(out.error);
  if (extrapolate && (out.status == PredictionStatus::outside_region ||
                      out.status == PredictionStatus::calibration_extrapolated)) {
    // What holds beyond the field: the calibrated kinematics and the physical joint functions. No
    // variance is stated: nothing the model measured says how far its calibration and functions
    // extrapolate (the residual variance of the field's samples claimed 0.05-0.4 mm where SIMULATED
    // and real held-out errors were 0.4-0.9 mm: coverage 0-46 %).
    ErrorPrediction e;
    if (out.status == PredictionStatus::outside_region)
      e.position_error_mm = model.joint_function_error_at(q_deg, model.scored_model());
    else
      e.position_error_mm = out.error.position_error_mm;
    e.inside_region = out.status != PredictionStatus::outside_region;
    out.error = e;
    out.status = PredictionStatus::extrapolated;
  }
  if (out.status != PredictionStatus::ok && out.status != PredictionStatus::extrapolated) return out;
  out.position_mm = forward_position(model.scored_model(), q_deg) + out.error.position_error_mm;
  if (model.registration()) out.tracker_mm = model.registration()->robot_from_tracker.inverse() * out.position_mm;
  return out;
}

namespace {

// Every error about a model file's content names the file: the field builders below it speak of
// "vector-kriging field: 0 samples" and know no file name.
template <class F>
auto naming_model_file(const std::string& path, F f) {
  const auto named = [&](const std::string& what) { return what.rfind(path, 0) == 0 ? what : path + ": " + what; };
  try {
    return f();
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    throw InputError(named(e.what()), path);
  } catch (const ArgumentError& e) {
    throw InputError(named(e.what()), path);
  }
}

}  // namespace

LoadedModel load_model(const std::string& path) {
  // A built-in robot's name, unless a file of that name exists (as for --robot elsewhere).
  if (const robot::BuiltinRobot* b = robot::builtin_robot_unless_file(path)) {
    CompensationModel m(CompensationMethod::kinematic, b->model, nullptr);
    return {std::move(m), true, "built-in robot '" + b->model.name() + "'"};
  }
  // The one JSON reader: directories, numbers out of range and duplicate keys are bad input
  // naming the file, never an internal error.
  const nlohmann::json j = read_json_file(path, "model file");
  if (j.is_object() && j.contains("format")) {
    CompensationModel m =
        naming_model_file(path, [&] { return with_json_source(path, [&] { return CompensationModel::from_json(j, path); }); });
    const std::string what = std::string(method_name(m.method())) + " model";
    return {std::move(m), false, what};
  }
  // Anything else is read as a robot JSON, whose reader names what is missing or wrong.
  // The registration is not part of the robot description: read it, then the robot without it.
  std::optional<Registration> reg = find_registration(j, path);
  nlohmann::json robot_json = j;
  robot_json.erase("registration");
  MdhModel robot = with_json_source(path, [&] { return MdhModel::from_json(robot_json, path); });
  const std::string what = "robot JSON '" + robot.name() + "'";
  CompensationModel m = CompensationModel(CompensationMethod::kinematic, std::move(robot), nullptr).with_registration(reg);
  return {std::move(m), true, what};
}

}  // namespace errfield::compensation
