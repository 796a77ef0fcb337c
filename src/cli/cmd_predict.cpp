// `errfield predict`: where the robot goes at given joints, according to a model.
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {
namespace {

struct PredictArgs {
  std::string model, joints, out, tool;
  double max_registration_rms = robot::kRegistrationRmsLimitMm;
  bool joints_are_degrees = false;  // skip the radians check (check_joints_not_radians)
  bool extrapolate = false;
};

void run_predict(const PredictArgs& a) {
  const compensation::LoadedModel loaded = compensation::load_model(a.model);
  const auto tool = parse_tool_option(a.tool, loaded.model.command_model().tool());
  const compensation::CompensationModel model =
      tool ? loaded.model.with_working_tool(loaded.model.tool_in_model_frame(*tool)) : loaded.model;
  const CsvTable table = CsvTable::read(a.joints);
  const std::vector<robot::JointVector> q = read_joint_columns(table);
  const std::size_t n = q.size();
  // Radians read as degrees lie inside any training box and pass every other check.
  if (!a.joints_are_degrees) compensation::check_joints_not_radians(q, model, a.joints, "--joints-are-degrees");
  const bool tracker = model.registration().has_value();
  // Joints files that carry measurements (a held-out set) must be of the model's robot.
  compensation::check_table_fits_robot(table, compensation::nominal_at_working_tool(model, model.nominal_model()),
                                       {true, "the nominal robot of " + a.model + (model.working_tool() ? " at the working tool" : "")},
                                       a.max_registration_rms);
  if (const auto w = robot::joints_outside_limits(q, model.nominal_model(), row_labels_of(table, "row")))
    std::cerr << "errfield predict: warning: " << *w << " (status outside-limits: nothing predicted there)\n";
  const compensation::StepColumns step = compensation::predict_columns(model, q, a.extrapolate);
  const std::size_t refused = step.refused;
  bool any_variance = false, any_radius = false;
  for (const auto& c : step.columns) {
    any_variance = any_variance || c.name == "var_mm2";
    any_radius = any_radius || c.name == "r95_mm";
  }
  // Nothing predicted is a failed job, as in cv: a script must not take an all-refused file for
  // predictions.
  if (n > 0 && refused == n)
    throw Error("predict: none of the " + std::to_string(n) + " rows of " + a.joints + " could be predicted with " +
                loaded.description + " from " + a.model + " (" + refusal_tally(status_words(step)) +
                "); nothing written");
  OutputTable out;
  out.add_all_columns(table);
  add_step_columns(out, step);
  std::cout << "predict: " << n - refused << " of " << n << " rows predicted with " << loaded.description << " from "
            << a.model;
  if (refused) std::cout << "; " << refused << " refused (status column): no position written for them";
  std::cout << "\n  columns px,py,pz (robot frame)" << (tracker ? ", tx,ty,tz (tracker frame, stored registration)" : "")
            << (any_variance ? ", var_mm2 (a new reading: field + nugget), var_field_mm2 (field only)" : "")
            << (any_radius ? ", r95_mm (95 % radius of a new reading around the prediction)" : "") << "\n  written to "
            << a.out << "\n";
  print_working_tool(std::cout, model);
  require_standard_output();  // before the commit: a failing run must not replace a.out
  out.write(a.out);
}

void add_predict_command(CLI::App& app) {
  auto a = std::make_shared<PredictArgs>();
  auto* cmd = app.add_subcommand(
      "predict",
      "Where the tool point goes at given joints, according to a model: px,py,pz (robot frame, mm) = command\n"
      "model FK + the error field's predicted error; tx,ty,tz (tracker frame) when the model holds a\n"
      "registration; where the model has a variance (kriging): var_mm2, the variance of a new tracker reading\n"
      "at those joints (field + nugget, summed over x,y,z), var_field_mm2, the field's part alone, and r95_mm,\n"
      "the radius around the predicted point that holds a new reading with 95 % probability (vector fields);\n"
      "status ok, outside-region or not-credible (refused rows get no position). Joints are degrees: input that\n"
      "looks like radians (all within +-2 pi, spread far less than the model's training joints) is an error (exit 2).\n"
      "Example: errfield predict --model model.json --joints joints.csv --out predicted.csv");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit' or robot JSON from 'errfield calibrate'")->required();
  cmd->add_option("--joints", a->joints, "CSV with columns q1..q6 (deg); other columns are carried through")->required();
  cmd->add_option("--max-registration-rms", a->max_registration_rms,
                  "when --joints has x,y,z or mx,my,mz: refuse (exit 2) data that are not the model's robot's "
                  "(registration RMS above this, mm; docs/robot.md)")
      ->capture_default_str();
  cmd->add_flag("--joints-are-degrees", a->joints_are_degrees,
                "skip the check that refuses joints that look like radians (all within +-2 pi and spread far less "
                "than the model's training joints, exit 2); give it when such small angles are meant");
  add_tool_option(cmd, a->tool, "the point predicted");
  add_extrapolate_option(cmd, a->extrapolate);
  cmd->add_option("--out", a->out, "output CSV (written atomically)")->required();
  cmd->callback([a] { run_predict(*a); });
}

Registration register_predict{"predict", 74, &add_predict_command};

}  // namespace
}  // namespace errfield::cli
