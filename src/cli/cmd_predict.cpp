// `errfield predict`: where the robot goes at given joints, according to a model.
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/compensation/prediction.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {
namespace {

struct PredictArgs {
  std::string model, joints, out;
};

void run_predict(const PredictArgs& a) {
  const compensation::LoadedModel loaded = compensation::load_model(a.model);
  const compensation::CompensationModel& model = loaded.model;
  const CsvTable table = CsvTable::read(a.joints);
  const std::vector<robot::JointVector> q = read_joint_columns(table);
  const std::size_t n = q.size();
  const bool tracker = model.registration().has_value();
  const compensation::StepColumns step = compensation::predict_columns(model, q);
  const std::size_t refused = step.refused;
  bool any_variance = false;
  for (const auto& c : step.columns) any_variance = any_variance || c.name == "var_mm2";
  OutputTable out;
  out.add_all_columns(table);
  add_step_columns(out, step);
  std::cout << "predict: " << n - refused << " of " << n << " rows predicted with " << loaded.description << " from "
            << a.model;
  if (refused) std::cout << "; " << refused << " refused (status column): no position written for them";
  std::cout << "\n  columns px,py,pz (robot frame)" << (tracker ? ", tx,ty,tz (tracker frame, stored registration)" : "")
            << (any_variance ? ", var_mm2" : "") << "\n  written to " << a.out << "\n";
  require_standard_output();  // before the commit: a failing run must not replace a.out
  out.write(a.out);
}

void add_predict_command(CLI::App& app) {
  auto a = std::make_shared<PredictArgs>();
  auto* cmd = app.add_subcommand(
      "predict",
      "Where the tool point goes at given joints, according to a model: px,py,pz (robot frame, mm) = command\n"
      "model FK + the error field's predicted error; tx,ty,tz (tracker frame) when the model holds a\n"
      "registration; var_mm2 (kriging variance of the 3-D error) where the model has one; status ok,\n"
      "outside-region or not-credible (refused rows get no position).\n"
      "Example: errfield predict --model model.json --joints joints.csv --out predicted.csv");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit' or robot JSON from 'errfield calibrate'")->required();
  cmd->add_option("--joints", a->joints, "CSV with columns q1..q6 (deg); other columns are carried through")->required();
  cmd->add_option("--out", a->out, "output CSV (written atomically)")->required();
  cmd->callback([a] { run_predict(*a); });
}

Registration register_predict{"predict", 74, &add_predict_command};

}  // namespace
}  // namespace errfield::cli
