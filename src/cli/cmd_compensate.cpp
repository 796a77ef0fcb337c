// `errfield compensate`: joints to send for a list of targets, from a fitted model (step 4).
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/error.hpp"
#include "errfield/compensation/compensation.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::cli {
namespace {

struct CompensateArgs {
  std::string robot, model, targets, out;
  double tolerance = 0.25;
  bool strict = false;
};

void run_compensate(const CompensateArgs& a) {
  using namespace robot;
  using namespace compensation;
  // p_inside is P(|error| <= tolerance): 0, a negative or a NaN tolerance makes it meaningless.
  if (!(std::isfinite(a.tolerance) && a.tolerance > 0.0))
    throw ArgumentError("--tolerance: " + format_number(a.tolerance) + "; expected a finite tolerance > 0 (mm)");
  const nlohmann::json j = read_json_file(a.model, "model file");
  const CompensationModel model = with_json_source(a.model, [&] { return CompensationModel::from_json(j, a.model); });
  const bool kinematic = model.method() == CompensationMethod::kinematic ||
                         model.method() == CompensationMethod::kinematic_kriging;
  if (kinematic && a.robot.empty())
    throw ArgumentError("--robot: a kinematic model's command model is the calibrated robot; give the nominal robot JSON");
  const MdhModel nominal = a.robot.empty() ? model.command_model() : load_robot_or_default(a.robot);

  const CsvTable t = CsvTable::read(a.targets);
  const bool joints = has_joint_columns(t);
  const std::vector<std::string> pose_cols{"x", "y", "z", "rx", "ry", "rz"};
  bool pose = true;
  for (const auto& c : pose_cols) pose = pose && t.has_column(c);
  if (!joints && !pose)
    throw InputError(a.targets + ": targets need columns q1..q6 (nominal joints, deg) or x,y,z,rx,ry,rz (mm, deg)",
                     a.targets);
  const std::size_t n = t.row_count();
  std::vector<JointVector> qn(n);
  std::vector<bool> ik_ok(n, true);
  if (joints) {
    qn = read_joint_columns(t);
  } else {
    const Eigen::MatrixXd p = t.numeric_columns(pose_cols);
    warn_if_metres(t, nominal, "compensate", kNominalXyz);
    for (std::size_t i = 0; i < n; ++i) {
      const auto r = p.row(static_cast<Eigen::Index>(i));
      const IkResult ik = inverse_kinematics_multistart(nominal, to_isometry({r[0], r[1], r[2], r[3], r[4], r[5]}));
      qn[i] = ik.q_deg;
      ik_ok[i] = ik.ok();
    }
  }
  OutputTable out;
  out.add_all_columns(t);
  std::vector<std::vector<double>> cols(24, std::vector<double>(n, NAN));  // see `names` below
  std::vector<std::string> status(n);
  std::size_t refused = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!ik_ok[i]) {
      status[i] = "unreachable";
      ++refused;
      continue;
    }
    const CompensatedTarget c = model.compensate_joints(nominal, qn[i], a.tolerance);
    const Eigen::Vector3d p = forward_position(nominal, qn[i]);
    for (int k = 0; k < 6; ++k) cols[static_cast<std::size_t>(k)][i] = qn[i][k];
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(6 + k)][i] = p[k];
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(9 + k)][i] = c.prediction.position_error_mm[k];
    cols[12][i] = c.prediction.distance_error_mm;
    cols[13][i] = c.prediction.variance_mm2;
    cols[14][i] = c.p_within_tolerance;
    for (int k = 0; k < 3; ++k) cols[static_cast<std::size_t>(15 + k)][i] = c.command_position_mm[k];
    status[i] = !c.prediction.inside_region ? "outside-region"
                : c.ik_status != IkStatus::converged ? std::string("ik-") + to_string(c.ik_status)
                                                     : "ok";
    if (!c.ok()) {
      ++refused;
      continue;  // compensated joints stay empty: nothing is sent for a refused target
    }
    for (int k = 0; k < 6; ++k) cols[static_cast<std::size_t>(18 + k)][i] = c.q_command_deg[k];
  }
  auto cells = [&](std::size_t c) {
    std::vector<std::string> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = std::isfinite(cols[c][i]) ? format_number(cols[c][i]) : "";
    return v;
  };
  const char* names[] = {"nq1", "nq2", "nq3", "nq4", "nq5", "nq6", "nx", "ny", "nz", "pred_dx", "pred_dy", "pred_dz",
                         "pred_dl", "var_mm2", "p_inside", "cmd_x", "cmd_y", "cmd_z", "cq1", "cq2", "cq3", "cq4",
                         "cq5", "cq6"};
  for (std::size_t c = 0; c < 24; ++c) out.add_column(names[c], cells(c));
  out.add_column("status", status);
  if (a.strict && refused) {
    // Checked before writing: a job that fails leaves any previous output as it was.
    std::string rows;
    std::size_t named = 0;
    for (std::size_t i = 0; i < n && named < 5; ++i) {
      if (status[i] == "ok") continue;
      rows += (named++ ? "; " : "") + a.targets + ":" + std::to_string(t.line_of_row(i)) + ": " + status[i];
    }
    throw Error("--strict: " + std::to_string(refused) + " of " + std::to_string(n) + " target(s) refused (" + rows +
                (refused > named ? "; ..." : "") + "); " + a.out + " not written");
  }
  out.write(a.out);
  std::cout << "compensate: " << n - refused << " of " << n << " targets compensated with " << method_name(model.method())
            << (refused ? "; " + std::to_string(refused) + " refused (status column): no joints written for them" : "")
            << "\n  written to " << a.out << "\n";
}

void add_compensate_command(CLI::App& app) {
  auto a = std::make_shared<CompensateArgs>();
  auto* cmd = app.add_subcommand(
      "compensate",
      "Joints to send for each target from a fitted model: predicted error (pred_dx..dz, pred_dl for distance\n"
      "models), kriging variance var_mm2 and the probability p_inside of being within ±tolerance where the\n"
      "model has a variance, the corrected command cmd_x..z and the compensated joints cq1..cq6 (IK, orientation\n"
      "kept). Targets: q1..q6 (nominal joints, deg) or x,y,z,rx,ry,rz (mm, deg). Targets outside the modelled\n"
      "region are refused (status outside-region, no joints), never extrapolated.\n"
      "Example: errfield compensate --model model.json --targets targets.csv --out joints.csv");
  cmd->add_option("--robot", a->robot, "nominal robot JSON (default: the model's command model)");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit'")->required();
  cmd->add_option("--targets", a->targets, "targets CSV")->required();
  cmd->add_option("--tolerance", a->tolerance, "tolerance for p_inside (± mm)")->capture_default_str();
  cmd->add_flag("--strict", a->strict,
                "if any target is refused: write nothing, name the refused rows and exit with status 1");
  cmd->add_option("--out", a->out, "output CSV (written atomically)")->required();
  cmd->callback([a] { run_compensate(*a); });
}

Registration reg{"compensate", 72, &add_compensate_command};

}  // namespace
}  // namespace errfield::cli
