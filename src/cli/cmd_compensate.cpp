// `errfield compensate`: joints to send for a list of targets, from a fitted model (step 4).
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "errfield/compensation/tools/target_ik.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/json_file.hpp"
#include "errfield/robot/kinematics.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::cli {
namespace {

struct CompensateArgs {
  std::string robot, model, targets, out, seed, config, tool;
  std::string frame = "robot";  // of pose targets: robot (the model's robot base frame) or tracker
  double tolerance = 0.25, max_registration_rms = robot::kRegistrationRmsLimitMm;
  double max_correction = 0.0;  // 0: compensation::default_max_correction_mm
  bool strict = false;
  bool joints_are_degrees = false;  // skip the radians check (check_joints_not_radians)
};

// Pose targets that carry a `frame` column (a previous compensate's output) must be in the frame
// --frame says: tracker coordinates read as robot coordinates are off by the whole registration.
// An empty cell claims nothing.
void check_frame_column(const CsvTable& t, const std::string& frame) {
  if (!t.has_column("frame")) return;
  const std::size_t c = t.column_index("frame");
  for (std::size_t i = 0; i < t.row_count(); ++i) {
    const std::string_view cell = t.cell(i, c);
    // A column of the user's own under that name (a video frame, a fixture) would be overwritten by
    // the frame compensate writes there: named, not taken for a frame.
    if (!cell.empty() && cell != "robot" && cell != "tracker")
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(i)) + ": column frame holds '" + std::string(cell) +
                           "', which is not a frame (robot or tracker); compensate writes the targets' frame in column "
                           "frame, so rename that column of the targets (or leave its cells empty)",
                       t.source(), t.line_of_row(i), "frame");
    if (!cell.empty() && cell != frame)
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(i)) + ": column frame is '" + std::string(t.cell(i, c)) +
                           "' but --frame is " + frame + "; give --frame " + std::string(t.cell(i, c)) +
                           " for targets in that frame",
                       t.source(), t.line_of_row(i), "frame");
  }
}

// One line of the summary: in which frame the targets were read and the robot-frame columns are.
std::string frame_line(const compensation::CompensationModel& model, const CompensateArgs& a, bool joints) {
  const bool calibrated = model.method() == compensation::CompensationMethod::kinematic ||
                          model.method() == compensation::CompensationMethod::kinematic_kriging;
  std::string line = joints ? std::string("joint targets; ")
                     : a.frame == "tracker"
                         ? "targets x,y,z,rx,ry,rz in the tracker frame (--frame tracker), mapped into the robot base frame "
                           "with the registration stored in " + a.model + " (" + std::to_string(model.registration()->points) +
                               " points, residual RMS " + format_number(std::round(model.registration()->residual_rms_mm * 1000.0) / 1000.0) +
                               " mm: column nx,ny,nz is each target there); "
                         : std::string("targets x,y,z,rx,ry,rz in the robot base frame (the nominal model's") +
                               (model.registration() ? ", placed by the model's tracker registration; --frame tracker for "
                                                       "tracker coordinates"
                                                     : "") +
                               "); ";
  line += "nx..nz, pred_d*, cmd_x..z and total_d* in the robot base frame";
  if (calibrated)
    line += " (total_* is against the nominal robot's FK: it includes any offset of the calibrated robot's base from the "
            "nominal one)";
  return line;
}

// --seed and --config: where IK starts and which arm configuration it keeps.
compensation::CompensationTargets target_options(const CompensateArgs& a) {
  using namespace robot;
  using namespace compensation;
  CompensationTargets targets;
  if (!a.seed.empty()) {
    const auto v = parse_numbers(a.seed, 6, "--seed");
    targets.seed_deg = JointVector(v.data());
  }
  if (!a.config.empty()) {
    targets.config = parse_arm_configuration(a.config);
    if (!targets.config)
      throw ArgumentError("--config: '" + a.config +
                          "'; expected s, e and w each followed by + or -, e.g. s+e+w- (docs/robot.md, \"Arm configuration\")");
  }
  return targets;
}

// The targets as nominal joints (q1..q6) or poses (x,y,z,rx,ry,rz), checked against the robot.
void read_targets(const CompensateArgs& a, const CsvTable& t, bool joints, const compensation::CompensationModel& model,
                  const robot::MdhModel& nominal, compensation::CompensationTargets& targets) {
  using namespace robot;
  using namespace compensation;
  if (joints) {
    // Targets that carry measurements must be of this robot (the check of fit and validate).
    check_table_fits_robot(t, nominal,
                           {true, a.robot.empty() ? "the command model of " + a.model : "--robot " + a.robot},
                           a.max_registration_rms);
    targets.joints_deg = read_joint_columns(t);
    if (!a.joints_are_degrees) check_joints_not_radians(targets.joints_deg, model, a.targets, "--joints-are-degrees");
    if (const auto w = joints_outside_limits(targets.joints_deg, nominal, row_labels_of(t, "row")))
      std::cerr << "errfield compensate: warning: " << *w << " (status outside-limits: no joints written)\n";
  } else {
    targets.poses = t.numeric_columns({"x", "y", "z", "rx", "ry", "rz"});
    // Per-row seeds (e.g. the taught joints): solved from, and kept on, their arm configuration.
    targets.seed_rows_deg = seed_rows_of(t);
    warn_if_metres(t, nominal, "compensate", kNominalXyz);
    check_frame_column(t, a.frame);
  }
}

// The first refused rows, as file:line: status, for the messages that fail the job.
std::string refused_rows(const CompensateArgs& a, const CsvTable& t, const std::vector<std::string>& status,
                         std::size_t refused) {
  std::string rows;
  std::size_t named = 0;
  for (std::size_t i = 0; i < t.row_count() && named < 5; ++i) {
    if (status[i] == "ok") continue;
    rows += (named++ ? "; " : "") + a.targets + ":" + std::to_string(t.line_of_row(i)) + ": " + status[i];
  }
  return rows + (refused > named ? "; ..." : "");
}

void print_compensate_summary(const CompensateArgs& a, const compensation::CompensationModel& model,
                              const compensation::StepColumns& step, std::size_t n, bool joints) {
  using namespace compensation;
  const std::size_t refused = step.refused;
  std::cout << "compensate: " << n - refused << " of " << n << " targets compensated with " << method_name(model.method())
            << (refused ? "; " + std::to_string(refused) + " refused (status column): no joints written for them" : "")
            << "\n  written to " << a.out << "\n";
  std::cout << "  " << frame_line(model, a, joints) << "\n";
  std::cout << "  arm configuration from (column config_source):";
  for (std::size_t k = 0; k < step.config_sources.size(); ++k)
    std::cout << (k ? "," : "") << " " << step.config_sources[k].second << " " << step.config_sources[k].first;
  std::cout << "\n";
  // Two numbers: what the joints did (the largest move_mm written) and the ceiling that was
  // allowed (the ceiling alone read as the largest move).
  std::cout << "  tool point moved by " << format_number(std::round(step.largest_move_mm * 1000.0) / 1000.0)
            << " mm at most (column move_mm); ceiling " << format_number(std::round(step.max_correction_mm * 1000.0) / 1000.0)
            << " mm ("
            << (a.max_correction > 0.0 ? std::string("--max-correction")
                                       : "default: " + format_number(kMaxCorrectionFactor) +
                                             " x the largest correction at the model's training poses, at least " +
                                             format_number(kMaxCorrectionFloorMm) + " mm")
            << ")\n";
  print_working_tool(std::cout, model);
}

void warn_refusals(const compensation::StepColumns& step) {
  if (step.too_large)
    std::cerr << "errfield compensate: warning: " << step.too_large << " target(s) would move the tool point by more "
              << "than " << format_number(step.max_correction_mm)
              << " mm (status correction-too-large, no joints written): far beyond the corrections the model "
                 "predicts on its own data; check the robot, tool and model (or raise --max-correction)\n";
  if (step.singular)
    std::cerr << "errfield compensate: warning: " << step.singular << " target(s) near a singular configuration "
              << "(status wrist-singular, elbow-singular, shoulder-singular or near-singular, no joints written): "
                 "their compensated joints turn by far more than the correction warrants\n";
  if (step.no_prediction)
    std::cerr << "errfield compensate: warning: " << step.no_prediction
              << " target(s) got no finite prediction from the model's field (status no-prediction); no joints "
                 "written for them\n";
}

void run_compensate(const CompensateArgs& a) {
  using namespace robot;
  using namespace compensation;
  // p_inside is P(|error| <= tolerance): 0, a negative or a NaN tolerance makes it meaningless.
  if (!(std::isfinite(a.tolerance) && a.tolerance > 0.0))
    throw ArgumentError("--tolerance: " + format_number(a.tolerance) + "; expected a finite tolerance > 0 (mm)");
  const TargetFrame frame = parse_target_frame(a.frame, "--frame");
  const nlohmann::json j = read_json_file(a.model, "model file");
  const CompensationModel stored = with_json_source(a.model, [&] { return CompensationModel::from_json(j, a.model); });
  const auto tool = parse_tool_option(a.tool, stored.aimed_model().tool());
  const CompensationModel model = tool ? stored.with_working_tool(stored.tool_in_model_frame(*tool)) : stored;
  const bool kinematic = model.method() == CompensationMethod::kinematic ||
                         model.method() == CompensationMethod::kinematic_kriging;
  if (kinematic && a.robot.empty() && !model.has_nominal_model())
    throw ArgumentError("--robot: a kinematic model's command model is the calibrated robot; give the nominal robot JSON");
  const MdhModel nominal_robot = a.robot.empty() ? model.nominal_model() : load_robot_or_default(a.robot);
  // Targets are poses (or the FK) of the working tool.
  const MdhModel nominal = nominal_at_working_tool(model, nominal_robot);
  CompensationTargets targets = target_options(a);
  const CsvTable t = CsvTable::read(a.targets);
  const bool joints = has_joint_columns(t);
  bool pose = true;
  for (const char* c : {"x", "y", "z", "rx", "ry", "rz"}) pose = pose && t.has_column(c);
  if (!joints && !pose)
    throw InputError(a.targets + ": targets need columns q1..q6 (nominal joints, deg) or x,y,z,rx,ry,rz (mm, deg)",
                     a.targets);
  const std::size_t n = t.row_count();
  read_targets(a, t, joints, model, nominal, targets);
  bring_targets_to_robot_frame(targets, model, frame, "--frame", a.targets, a.model);
  check_seed_joints(targets, nominal, &t);
  if (!(std::isfinite(a.max_correction) && a.max_correction >= 0.0))
    throw ArgumentError("--max-correction: " + format_number(a.max_correction) +
                        "; expected a ceiling > 0 (mm), or 0 for the default");
  const StepColumns step = compensate_columns(model, nominal, targets, a.tolerance, a.max_correction);
  const std::size_t refused = step.refused;
  const std::vector<std::string>& status = step.columns.back().words;
  // Nothing compensated is a failed job, as in predict, validate and cv (exit 1, nothing written,
  // a previous output kept): a script that checks the exit status must not send a file of refusals
  // to the robot. The message carries what the statuses would have said: the tally of the reasons
  // and the first rows.
  if (n > 0 && refused == n)
    throw Error("compensate: none of the " + std::to_string(n) + " targets of " + a.targets + " could be compensated with " +
                std::string(method_name(model.method())) + " from " + a.model + " (" + refusal_tally(status) + "; first rows: " +
                refused_rows(a, t, status, refused) + "); " + a.out + " not written");
  OutputTable out;
  out.add_all_columns(t);
  add_step_columns(out, step);
  // The frame of the row's own x,y,z,rx,ry,rz (written as given): a later run on this file, or a
  // reader of it, need not guess (check_frame_column).
  if (!joints) out.add_column("frame", std::vector<std::string>(n, a.frame));
  // `--strict`: any refusal fails the job. Checked before writing: a job that fails leaves any
  // previous output as it was.
  if (a.strict && refused)
    throw Error("--strict: " + std::to_string(refused) + " of " + std::to_string(n) + " target(s) refused (" +
                refused_rows(a, t, status, refused) + "); " + a.out + " not written");
  print_compensate_summary(a, model, step, n, joints);
  warn_refusals(step);
  require_standard_output();  // before the write: a run that fails leaves the previous file
  out.write(a.out);
}

void add_compensate_command(CLI::App& app) {
  auto a = std::make_shared<CompensateArgs>();
  auto* cmd = app.add_subcommand(
      "compensate",
      "Joints to send for each target from a fitted model: predicted error (pred_dx..dz, pred_dl for distance\n"
      "models), where the model has a variance: var_mm2 (a new reading at the target: field + nugget),\n"
      "var_field_mm2 (field only), r95_mm (95 % radius, vector fields) and p_inside, the probability that the\n"
      "3-D error (distance error for distance models) is within --tolerance; the corrected command cmd_x..z and\n"
      "the compensated joints cq1..cq6 (IK, orientation kept), the whole predicted error of the tool point\n"
      "(total_dx..dz, total_mm: calibration + field) and how far the joints move it (move_mm). Targets: q1..q6 (nominal joints, deg) or x,y,z,rx,ry,rz (mm, deg). Targets outside the modelled\n"
      "region are refused (status outside-region, no joints), never extrapolated; so are predictions far beyond\n"
      "the model's range of errors (not-credible) and pose targets whose IK left the data's branch\n"
      "(branch-change: solved from the nearest training sample, or --seed, along the pose path). Pose targets\n"
      "may carry seed joints sq1..sq6 per row (e.g. the taught joints); a solution on another arm configuration\n"
      "than the seed's (or the training sample's, or given joints', or --config's) is refused (config-change);\n"
      "columns nconfig, config (s+e+w- style, docs/robot.md) and config_source: where the configuration a row is\n"
      "held to came from (seed, given, nearest-training, config-option, none), counted in the summary. Rows whose\n"
      "joints swing far more than the correction warrants (a singular wrist, elbow or shoulder) are refused\n"
      "(wrist-singular, ...). Joint targets that look like radians (all within +-2 pi, spread far less than the\n"
      "model's training joints) are an error (exit 2; --joints-are-degrees if they are degrees).\n"
      "Frames: pose targets are in the robot base frame of the model's nominal robot (mm, deg) - the frame\n"
      "its stored tracker registration maps readings into - or, with --frame tracker, in the tracker frame\n"
      "(e.g. a part measured with the tracker), mapped with that registration; column frame says which.\n"
      "nx..nz (the target), pred_d*, cmd_x..z and total_d* are always in the robot base frame; total_* is\n"
      "against the nominal robot's FK, so for calibrated models it includes any offset of the calibrated\n"
      "robot's base from the nominal one (docs/robot.md).\n"
      "Prints the largest move of the tool point and the ceiling (--max-correction). If every target is\n"
      "refused, nothing is written and the exit status is 1 (as predict's): the error counts the refusals by\n"
      "status and names the first rows; with --strict, so it is if any target is refused.\n"
      "Example: errfield compensate --model model.json --targets targets.csv --out joints.csv");
  cmd->add_option("--robot", a->robot,
                  "nominal robot JSON or built-in name (er20-c10, kr16, ur5e, ur5, ur10; default: the model's command "
                  "model)");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit'")->required();
  cmd->add_option("--targets", a->targets, "targets CSV")->required();
  cmd->add_option("--tolerance", a->tolerance, "tolerance for p_inside: radius of the 3-D error (mm; distance models: |distance error|)")->capture_default_str();
  cmd->add_option("--seed", a->seed,
                  "Q1,...,Q6 (deg): solve pose targets from these joints (default: the model's nearest training "
                  "sample), on their branch");
  cmd->add_option("--config", a->config,
                  "s+e+w- style (docs/robot.md, \"Arm configuration\"): hold every row to this arm configuration; pose "
                  "targets are solved from the nearest training sample on it (or their seed, which must be on it); "
                  "rows that end on another are refused (config-change)");
  cmd->add_flag("--joints-are-degrees", a->joints_are_degrees,
                "joint targets: skip the check that refuses joints that look like radians (all within +-2 pi and "
                "spread far less than the model's training joints); give it when such small angles are meant");
  cmd->add_option("--max-registration-rms", a->max_registration_rms,
                  "joint targets with x,y,z or mx,my,mz: refuse (exit 2) data that are not this robot's "
                  "(registration RMS above this, mm; docs/robot.md)")
      ->capture_default_str();
  cmd->add_option("--max-correction", a->max_correction,
                  "MM: refuse targets whose compensated joints move the tool point by more than this (status "
                  "correction-too-large; column move_mm). Default (0): 3 x the largest total correction the model "
                  "predicts at its own training poses, at least 1 mm (docs/robot.md)")
      ->capture_default_str();
  add_tool_option(cmd, a->tool, "the point compensated (targets are its poses)");
  cmd->add_option("--frame", a->frame,
                  "robot or tracker: the frame of pose targets x,y,z,rx,ry,rz. robot (default): the nominal robot's "
                  "base frame; tracker: the frame of the tracker readings the model was fitted on (mapped with the "
                  "model's stored registration; a model fitted without mx,my,mz has none, exit 2)")
      ->capture_default_str();
  cmd->add_flag("--strict", a->strict,
                "if any target is refused (not only all of them, the default): write nothing, name the refused rows "
                "and exit with status 1");
  cmd->add_option("--out", a->out, "output CSV (written atomically)")->required();
  cmd->callback([a] { run_compensate(*a); });
}

Registration register_compensate{"compensate", 72, &add_compensate_command};

}  // namespace
}  // namespace errfield::cli
