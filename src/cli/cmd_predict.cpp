// `errfield predict`: where the robot goes at given joints, according to a model.
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
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
  std::vector<std::vector<std::string>> cols(7, std::vector<std::string>(n));
  std::vector<std::string> status(n);
  bool any_variance = false;
  std::size_t refused = 0;
  auto cell = [](double v) { return std::isfinite(v) ? format_number(v) : std::string(); };
  for (std::size_t i = 0; i < n; ++i) {
    const compensation::PointPrediction p = compensation::predict_position(model, q[i]);
    status[i] = std::string(compensation::status_name(p.status));
    if (!p.ok()) {
      ++refused;  // no position for a prediction the model cannot vouch for
      continue;
    }
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(k)][i] = cell(p.position_mm[k]);
    if (p.tracker_mm)
      for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(3 + k)][i] = cell((*p.tracker_mm)[k]);
    cols[6][i] = cell(p.error.variance_mm2);
    any_variance = any_variance || std::isfinite(p.error.variance_mm2);
  }
  OutputTable out;
  out.add_all_columns(table);
  const char* names[] = {"px", "py", "pz", "tx", "ty", "tz", "var_mm2"};
  for (std::size_t c = 0; c < 7; ++c) {
    if (c >= 3 && c < 6 && !tracker) continue;
    if (c == 6 && !any_variance) continue;
    out.add_column(names[c], cols[c]);
  }
  out.add_column("status", status);
  out.write(a.out);
  std::cout << "predict: " << n - refused << " of " << n << " rows predicted with " << loaded.description << " from "
            << a.model;
  if (refused) std::cout << "; " << refused << " refused (status column): no position written for them";
  std::cout << "\n  columns px,py,pz (robot frame)" << (tracker ? ", tx,ty,tz (tracker frame, stored registration)" : "")
            << (any_variance ? ", var_mm2" : "") << "\n  written to " << a.out << "\n";
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

Registration reg{"predict", 74, &add_predict_command};

}  // namespace
}  // namespace errfield::cli
