// `errfield validate`: scores a model on measurements it was not fitted on (prediction mode), or
// the validation run on the robot after compensation (--targets).
#include <algorithm>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/compensation/validation/rotation_validation.hpp"
#include "errfield/compensation/validation/validation.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {
namespace {

struct ValidateArgs {
  std::string model, data, robot, out, summary_out, report, tool, reflector, orientation_out;
  std::vector<std::string> base_points;
  bool targets = false, extrapolate = false;
  double max_registration_rms = robot::kRegistrationRmsLimitMm;
  double max_tool_point_shift = compensation::kToolPointShiftLimitMm;
};

/// A file written by `errfield simulate` says so in a leading comment; its report must too.
bool marked_simulated(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && !line.empty() && line[0] == '#')
    if (line.find("SIMULATED") != std::string::npos) return true;
  return false;
}


/// `--orientation-out`: one row per pose with three or more points (rotation_validation.hpp).
std::string rotation_csv(const compensation::RotationCheck& check) {
  OutputTable t;
  std::vector<std::string> point, status;
  std::vector<double> readings, before, after, r95, nees;
  std::vector<std::vector<double>> components(6);
  for (const compensation::ValidatedRotation& v : check.poses) {
    point.push_back(v.point);
    status.push_back(v.status);
    readings.push_back(static_cast<double>(v.readings));
    before.push_back(v.before_mdeg.norm());
    after.push_back(v.after_mdeg.norm());
    for (int c = 0; c < 3; ++c) {
      components[static_cast<std::size_t>(c)].push_back(v.before_mdeg[c]);
      components[static_cast<std::size_t>(3 + c)].push_back(v.after_mdeg[c]);
    }
    r95.push_back(v.r95_mdeg);
    nees.push_back(v.nees);
  }
  t.add_column("point", point);
  t.add_column("status", status);
  t.add_numbers("points_read", readings);
  t.add_numbers("before_mdeg", before);
  t.add_numbers("after_mdeg", after);
  const char* names[] = {"before_wx_mdeg", "before_wy_mdeg", "before_wz_mdeg", "after_wx_mdeg", "after_wy_mdeg", "after_wz_mdeg"};
  for (std::size_t c = 0; c < 6; ++c) t.add_numbers(names[c], components[c]);
  t.add_numbers("r95_mdeg", r95);
  t.add_numbers("nees", nees);
  return t.to_csv();
}

void run_validate(const ValidateArgs& a) {
  using namespace robot;
  using namespace compensation;
  const compensation::LoadedModel loaded = compensation::load_model(a.model);
  const auto tool = parse_tool_option(a.tool, loaded.model.command_model().tool());
  CompensationModel model = tool ? loaded.model.with_working_tool(loaded.model.tool_in_model_frame(*tool)) : loaded.model;
  std::vector<Eigen::Vector3d> fixed;
  for (const auto& b : a.base_points) {
    const auto v = parse_numbers(b, 3, "--base-point");
    fixed.emplace_back(v[0], v[1], v[2]);
  }
  // A 6-DoF probe's rows become three points on the flange (probe_readings.hpp).
  const CsvTable file = compensation::expand_probe_readings(CsvTable::read(a.data));
  // Readings of several points on the flange: one label's rows, scored at its located point.
  const CsvTable table = compensation::rows_of_one_reflector(file, a.reflector, !a.tool.empty(), model, "--");
  compensation::ValidationReport r;
  std::optional<compensation::RotationCheck> rotations;
  if (a.targets) {
    r = with_source(a.data, [&] { return compensation::validate_targets(table, model.registration(), fixed); });
  } else {
    const MdhModel nominal_robot = a.robot.empty() ? model.nominal_model() : load_robot_or_default(a.robot);
    // The readings are of the working tool's point: so is the nominal robot's 'before'.
    const MdhModel nominal = nominal_at_measured_point(model, nominal_robot);
    // Data of another robot, or joints in radians, scored "after" errors of a metre (exit 0). A file's
    // x,y,z columns are the controller's FK at the robot JSON's (working) tool, not at the located
    // reflector: they are checked against that robot.
    check_table_fits_robot(table, compensation::nominal_at_working_tool(model, nominal_robot),
                           {true, a.robot.empty() ? "the nominal robot of " + a.model : "--robot " + a.robot},
                           a.max_registration_rms);
    const MeasurementSet data = compensation::readings_at_measured_point(table, model, nominal_robot, fixed);
    warn_if_metres(table, nominal, "validate");
    // The registration check above fits a free reflector offset, so readings of another reflector
    // pass it; scored against the model's point they gave 150 mm "after" errors with exit 0.
    if (!data.measured_mm.empty())
      check_readings_of_tool_point(model, data.q_deg, data.measured_mm, a.data, a.max_tool_point_shift);
    if (const auto w = joints_outside_limits(read_joint_columns(table), model.nominal_model(), row_labels_of(table, "row")))
      std::cerr << "errfield validate: warning: " << *w << " (status outside-limits: not scored)\n";
    r = with_source(a.data, [&] { return compensation::validate_predictions(model, data, a.extrapolate); });
    // Three or more points per pose and a model with fields at three: the flange's orientation.
    if (file.has_column("reflector") && model.fielded_points().size() >= 3) {
      const MeasurementSet all_points = MeasurementSet::from_table(file, nominal_robot, fixed, true);
      rotations = with_source(a.data, [&] { return compensation::validate_rotations(model, all_points, nominal_robot); });
    }
    if (loaded.is_robot_json && a.robot.empty() && !table.has_column("x"))
      r.notes.push_back("no --robot and no x,y,z columns: 'before' is this robot's own FK; give the nominal robot "
                        "with --robot for an uncompensated baseline");
  }
  // Nothing scored is a failed job, as in cv ("80 points, 80 refused" exited 0).
  if (!r.points.empty() && r.refused == r.points.size()) {
    std::vector<std::string> status;
    for (const auto& p : r.points) status.push_back(p.status);
    throw Error("validate: none of the " + std::to_string(r.points.size()) + " points of " + a.data +
                " could be scored with " + loaded.description + " from " + a.model + " (" + refusal_tally(status) +
                "); nothing written");
  }
  nlohmann::json summary = r.summary_json();
  if (rotations) summary["orientation"] = rotations->summary_json();
  AtomicFileSet outputs;
  if (!a.out.empty()) {
    OutputTable points;
    add_step_columns(points, compensation::validation_point_columns(r));
    outputs.add(a.out, points.to_csv());
  }
  if (!a.orientation_out.empty()) {
    if (!rotations)
      throw InputError(a.data + ": --orientation-out: no orientation to score: it needs readings of three or more "
                       "points per pose (a 'reflector' column, or a probe's mrx,mry,mrz) and a model fitted on them "
                       "with a field at each point",
                       a.data);
    outputs.add(a.orientation_out, rotation_csv(*rotations));
  }
  if (!a.summary_out.empty()) outputs.add(a.summary_out, summary.dump(2) + "\n");
  if (!a.report.empty())
    outputs.add(a.report, compensation::validation_report_html(r, "errfield validate: " + loaded.description + " on " + a.data,
                                                                marked_simulated(a.data)));
  std::cout << "validate: " << loaded.description << " from " << a.model << " on " << a.data << "\n" << r.summary_text();
  if (rotations) std::cout << rotations->summary_text();
  print_working_tool(std::cout, model);
  for (const auto& f : {a.out, a.summary_out, a.report, a.orientation_out})
    if (!f.empty()) std::cout << "  written " << f << "\n";
  require_standard_output();  // before the commit: a run that fails leaves the previous files
  outputs.commit();
}

void add_validate_command(CLI::App& app) {
  auto a = std::make_shared<ValidateArgs>();
  auto* cmd = app.add_subcommand(
      "validate",
      "Score a model on measurements it was not fitted on. Default (prediction mode): at each row's joints\n"
      "q1..q6 the model predicts where the tool point is (command model FK + error field); the tracker reading\n"
      "mx,my,mz is mapped with the model's stored registration (never re-registered on these rows) and\n"
      "distances dist_bK are compared frame-free. 'before' is the nominal robot with its own registration\n"
      "(as fit --method none stores it), 'after' the model; the summary says which registration each uses.\n"
      "Kriging models: coverage95 (share of points within the predicted 95 % radius r95) and the mean of\n"
      "|e|^2/sigma^2 (3 expected) check the predictive variance (field + nugget).\n"
      "--targets: the validation run after compensation; rows carry the intended target (nx,ny,nz or x,y,z)\n"
      "and optionally run=before|after; error = measured - target.\n"
      "Writes per-point errors (--out), summary JSON (--summary-out) and an HTML report (--report).\n"
      "Example: errfield validate --model model.json --data holdout.csv --out points.csv --summary-out summary.json");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit' or robot JSON from 'errfield calibrate'")->required();
  cmd->add_option("--data", a->data, "held-out measurement CSV (or the validation run with --targets)")->required();
  cmd->add_option("--robot", a->robot, "nominal robot JSON for the 'before' baseline (default: the model's nominal robot)");
  cmd->add_option("--base-point", a->base_points, "X,Y,Z of fixed base point bK when the data have no base rows");
  cmd->add_option("--max-registration-rms", a->max_registration_rms,
                  "refuse (exit 2) data whose tracker readings mx,my,mz register to the robot with a larger RMS (mm): "
                  "data of another robot, joints in radians, metres (docs/robot.md)")
      ->capture_default_str();
  cmd->add_option("--max-tool-point-shift", a->max_tool_point_shift,
                  "refuse (exit 2) readings of another point than the model's tool point: when a free reflector "
                  "offset fitted to them lies more than this (mm) from the model's and the model's registration "
                  "leaves them more than this RMS off (docs/robot.md)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  add_tool_option(cmd, a->tool, "the point the held-out readings measured");
  cmd->add_option("--reflector", a->reflector,
                  "data with a 'reflector' column (several points on the flange): score this label's rows, at the "
                  "point the model located for it (fit on several points stores each label's point); default: the "
                  "model's own point");
  cmd->add_flag("--targets", a->targets, "validation-run mode: error = measured - intended target");
  add_extrapolate_option(cmd, a->extrapolate);
  cmd->add_option("--out", a->out, "per-point CSV: point,status,before_mm,after_mm, the error components and, for "
                  "kriging models, var_mm2, var_field_mm2, r95_mm, nees");
  cmd->add_option("--summary-out", a->summary_out, "summary JSON (points, refused, position/distance before/after, "
                  "the registrations used, uncertainty: coverage95, mean_nees)");
  cmd->add_option("--report", a->report, "HTML report with histograms and per-point errors before/after");
  cmd->add_option("--orientation-out", a->orientation_out,
                  "per-pose CSV of the flange's orientation error, for data with three or more points per pose (a "
                  "'reflector' column, or a probe's mrx,mry,mrz) and a model fitted on them: point,status,points_read,"
                  "before_mdeg,after_mdeg, the components before_w*/after_w* (robot frame, mdeg), r95_mdeg, nees");
  cmd->callback([a] { run_validate(*a); });
}

Registration register_validate{"validate", 73, &add_validate_command};

}  // namespace
}  // namespace errfield::cli
