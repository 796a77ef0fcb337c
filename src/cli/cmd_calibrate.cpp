// `errfield calibrate`: kinematic calibration from tracker measurements (the columns
// `errfield simulate` writes), identified model as robot JSON plus a report.

#include <algorithm>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "cli/robot_cli.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/input_checks.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/compensation/model/registration.hpp"
#include "errfield/robot/calibration.hpp"
#include "errfield/robot/distance_table.hpp"
#include "errfield/robot/flange_points.hpp"
#include "errfield/robot/input_checks.hpp"

namespace errfield::cli {
namespace {

struct CalibrateArgs {
  std::string robot, data, model = "distance", out, report, robust, robot_out;
  std::vector<std::string> base_points;
  double k0 = 1.5, k1 = 3.0, max_condition = 1e3, max_registration_rms = robot::kRegistrationRmsLimitMm;
  bool no_robust = false;
  std::string tool_reflector;
};

robot::CalibrationOptions calibration_options(const CalibrateArgs& a) {
  robot::CalibrationOptions options;
  if (!a.robust.empty() && a.robust != "none" && a.robust != "igg3")
    throw ArgumentError("--robust: expected 'none' or 'igg3', got '" + a.robust + "'");
  if (a.no_robust && a.robust == "igg3") throw ArgumentError("--no-robust contradicts --robust igg3; give one");
  if (!a.robust.empty()) options.robust.enabled = a.robust == "igg3";
  if (a.no_robust) options.robust.enabled = false;
  options.robust.k0 = a.k0;
  options.robust.k1 = a.k1;
  options.max_condition_number = a.max_condition;
  naming_options([&] { options.validate(); }, {{"CalibrationOptions::max_condition_number", "--max-condition"},
                                               {"CalibrationOptions::robust: need 0 < k0 < k1", "need 0 < --k0 < --k1"}});
  return options;
}

// --base-point X,Y,Z, repeatable: the fixed base points' nominal positions (robot base frame, mm).
std::vector<Eigen::Vector3d> base_points(const CalibrateArgs& a) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& b : a.base_points) {
    const auto v = parse_numbers(b, 3, "--base-point");
    points.emplace_back(v[0], v[1], v[2]);
  }
  return points;
}

// Misuse is an error with a reason (robot/input_checks.hpp); x,y,z of another robot say more
// than its joints beyond this robot's limits, so first.
void check_calibration_data(const CalibrateArgs& a, const CsvTable& table, const std::vector<robot::JointVector>& q,
                            const robot::MdhModel& nominal, bool several_points) {
  using namespace robot;
  // Readings of several points on the flange: x,y,z are each point's nominal position, which only
  // the tool point's rows share with the robot JSON; each label's registration checks the robot.
  if (several_points && a.model != "position")
    throw InputError(a.data + ": readings of several points on the flange (column 'reflector') calibrate with "
                         "--model position",
                     a.data, 0, "reflector");
  if (!several_points) check_nominal_positions(table, nominal, !a.robot.empty());
  for (std::size_t i = 0; i < q.size(); ++i)
    for (int j = 0; j < kJointCount; ++j) {
      const MdhLink& l = nominal.link(j);
      if (q[i][j] >= l.q_min_deg - 1e-6 && q[i][j] <= l.q_max_deg + 1e-6) continue;
      const std::string col = "q" + std::to_string(j + 1);
      throw InputError(a.data + ":" + std::to_string(table.line_of_row(i)) + ": column '" + col + "': " +
                           format_number(q[i][j]) + " deg is outside the joint limits [" + format_number(l.q_min_deg) +
                           ", " + format_number(l.q_max_deg) + "] of robot '" + nominal.name() +
                           "'; check units (degrees) and joint order",
                       a.data, table.line_of_row(i), col);
    }
  warn_if_metres(table, nominal, "calibrate", a.model == "position" ? kMeasuredXyz : kDistances);
  // 0 is accepted only at a base point itself (the paper's P0 as a grid vertex; such pairs are skipped).
  if (a.model == "distance") check_distance_columns(table, &nominal, base_points(a));
}

// What a calibration identified: the model, and for positions the registration stored with it.
struct Identified {
  robot::CalibrationResult result;
  robot::MdhModel model;
  std::optional<compensation::Registration> registration;  // stored with the model (positions only)
  std::vector<bool> other_point_row;                       // several points: rows not of the tool point
};

// Several points on the flange: each label's registration checks the robot, then each label is
// located on the flange (one of them the tool point).
robot::LabelledFlangePoints locate_flange_points(const CalibrateArgs& a, const CsvTable& table,
                                                 const robot::MdhModel& nominal,
                                                 std::vector<robot::PositionMeasurement>& data,
                                                 const robot::CalibrationOptions& options) {
  using namespace robot;
  const std::size_t col = table.column_index("reflector");
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < table.row_count(); ++i) labels.emplace_back(table.cell(i, col));
  for (const std::string& l : std::vector<std::string>(labels)) {  // each label is one rigid point
    std::vector<PositionMeasurement> own;
    for (std::size_t i = 0; i < data.size(); ++i)
      if (labels[i] == l) own.push_back(data[i]);
    (void)check_tracker_registration(nominal, own, a.data + " (reflector '" + l + "')", {!a.robot.empty(), ""},
                                     a.max_registration_rms, options);
  }
  return assign_flange_points(nominal, data, labels, a.tool_reflector, options, a.data);
}

// --model position: registration first (tracker <- robot base and reflector offset), then the full
// model in the tracker frame; the output is expressed back in the registered robot frame.
Identified calibrate_positions_model(const CalibrateArgs& a, const CsvTable& table,
                                     const std::vector<robot::JointVector>& q, const robot::MdhModel& nominal,
                                     const robot::CalibrationOptions& options, bool several_points,
                                     std::ostringstream& text) {
  using namespace robot;
  Identified id{{}, nominal, std::nullopt, std::vector<bool>(q.size(), false)};
  const Eigen::MatrixXd m = table.numeric_columns({"mx", "my", "mz"});
  std::vector<PositionMeasurement> data;
  for (std::size_t i = 0; i < q.size(); ++i) data.push_back({q[i], m.row(static_cast<Eigen::Index>(i)).transpose()});
  {
    Eigen::MatrixXd p(m.rows(), 3);
    for (std::size_t i = 0; i < q.size(); ++i) p.row(static_cast<Eigen::Index>(i)) = forward_position(nominal, q[i]).transpose();
    if (const auto why = tracker_frozen(m, p)) throw InputError(a.data + ": " + *why, a.data, 0, "mx");
  }
  // The check fit, validate, predict and compensate run too (robot/input_checks.hpp).
  std::optional<LabelledFlangePoints> points;
  if (several_points) {
    points = locate_flange_points(a, table, nominal, data, options);
    for (std::size_t i = 0; i < data.size(); ++i) id.other_point_row[i] = data[i].flange_point != 0;
  } else if (!a.tool_reflector.empty()) {
    throw ArgumentError("--tool-reflector: " + a.data + " has no 'reflector' column with several labels");
  }
  const CalibrationResult reg = with_source(a.data, [&] {
    if (points) return register_tracker(nominal, data, points->further_points_mm(), options);
    const auto checked = check_tracker_registration(nominal, data, a.data, {!a.robot.empty(), ""},
                                                    a.max_registration_rms, options);
    return checked ? *checked : register_tracker(nominal, data, options);
  });
  text << "== registration (tracker <- robot base, reflector offset) ==\n" << reg.report();
  const PoseXyzRpy t = to_xyz_rpy(reg.model.base());
  text << "tracker <- robot base: x " << t.x_mm << " y " << t.y_mm << " z " << t.z_mm << " mm, rx " << t.rx_deg
       << " ry " << t.ry_deg << " rz " << t.rz_deg << " deg\n\n";
  std::vector<Eigen::Vector3d> further;
  for (const FlangePointEstimate& p : reg.flange_points) further.push_back(p.position_mm);
  id.result = with_source(a.data, [&] { return calibrate_positions(reg.model, data, further, options); });
  if (points) {
    text << "points on the flange (flange frame, mm): '" << points->labels[0] << "' is the tool point ("
         << id.result.model.tool().translation().transpose() << ")";
    for (std::size_t k = 1; k < points->labels.size(); ++k)
      text << "; '" << points->labels[k] << "' is flange point " << k << " ("
           << id.result.flange_points[k - 1].position_mm.transpose() << ")";
    text << "\n";
  }
  // reg.model.base() is tracker <- robot chain, the nominal base world <- robot chain.
  id.model = id.result.model.with_base(nominal.base() * reg.model.base().inverse() * id.result.model.base());
  // Tracker readings map into the identified model's world frame by nominal.base · reg.base^-1: keep it (and the
  // reflector offset found with it) at full precision, for validate, predict and fk.
  id.registration.emplace();
  id.registration->robot_from_tracker = nominal.base() * reg.model.base().inverse();
  id.registration->reflector_offset_mm = Eigen::Vector3d(reg.model.tool().translation());
  id.registration->points = data.size();
  id.registration->residual_rms_mm = id.result.after.rms_mm;
  return id;
}

Identified calibrate_distances_model(const CalibrateArgs& a, const CsvTable& table,
                                     const std::vector<robot::JointVector>& q, const robot::MdhModel& nominal,
                                     const robot::CalibrationOptions& options, std::ostringstream& text) {
  using namespace robot;
  Identified id{{}, nominal, std::nullopt, std::vector<bool>(q.size(), false)};
  const std::vector<Eigen::Vector3d> fixed = base_points(a);
  const DistanceTable pairs = distance_measurements_from_table(table, q, nominal, fixed);
  text << pairs.note;
  id.result = with_source(a.data, [&] {
    return fixed.empty() ? calibrate_distances(nominal, pairs.data, options)
                         : calibrate_distances(nominal, pairs.data, fixed, options);
  });
  id.model = id.result.model;
  return id;
}

// --robot-out: the nominal robot with the reflector offset the data found as its tool point (the
// nominal tool's orientation kept): what scores `--method none` or fits a field on this reflector
// without the calibrated links, instead of a robot JSON edited by hand.
nlohmann::json nominal_with_reflector(const CalibrateArgs& a, const CsvTable& table,
                                      const std::vector<robot::JointVector>& q, const robot::MdhModel& nominal,
                                      const Identified& id) {
  const Eigen::Vector3d reflector =
      id.registration ? *id.registration->reflector_offset_mm : Eigen::Vector3d(id.model.tool().translation());
  Eigen::Isometry3d tool = nominal.tool();
  tool.translation() = reflector;
  nlohmann::json nominal_json =
      nominal.with_tool(tool).with_name(nominal.name() + " (nominal, reflector offset from " + a.data + ")").to_json();
  if (id.registration) {
    // The registration found with the nominal links (tracker -> robot base, the frame the calibrated
    // model is expressed in too), with the residual the nominal links leave.
    compensation::Registration own = *id.registration;
    double ss = 0.0;
    const Eigen::MatrixXd m = table.numeric_columns({"mx", "my", "mz"});
    const robot::MdhModel with_reflector = nominal.with_tool(tool);
    std::size_t rows = 0;
    for (std::size_t i = 0; i < q.size(); ++i)
      if (!id.other_point_row[i] && ++rows)
        ss += (own.robot_from_tracker * Eigen::Vector3d(m.row(static_cast<Eigen::Index>(i)).transpose()) -
               forward_position(with_reflector, q[i]))
                  .squaredNorm();
    own.residual_rms_mm = std::sqrt(ss / static_cast<double>(rows));
    nominal_json["registration"] = compensation::registration_to_json(own);
  }
  return nominal_json;
}

void run_calibrate(const CalibrateArgs& a) {
  refuse_same_output({{"--out", &a.out}, {"--report", &a.report}, {"--robot-out", &a.robot_out}});
  using namespace robot;
  const MdhModel nominal = load_robot_or_default(a.robot);
  const CalibrationOptions options = calibration_options(a);
  // A 6-DoF probe's rows become three points on the flange (probe_readings.hpp).
  const CsvTable table = compensation::expand_probe_readings(CsvTable::read(a.data));
  const auto q = read_joint_columns(table);
  const bool several_points = compensation::several_reflector_labels(table);
  check_calibration_data(a, table, q, nominal, several_points);
  std::ostringstream text;
  if (a.model == "position" && !a.base_points.empty())
    throw ArgumentError("--base-point: fixed base points are for --model distance, not --model position");
  if (a.model != "position" && a.model != "distance")
    throw ArgumentError("--model: expected 'distance' or 'position', got '" + a.model + "'");
  const Identified id = a.model == "position"
                            ? calibrate_positions_model(a, table, q, nominal, options, several_points, text)
                            : calibrate_distances_model(a, table, q, nominal, options, text);
  const CalibrationResult& result = id.result;
  text << "== kinematic calibration (" << a.model << " model, " << result.before.count << " measurements) ==\n"
       << result.report();
  std::cout << text.str();
  if (!result.converged) std::cerr << "calibrate: warning: " << result.message << "\n";
  // --out and --report all or none: an unwritable --report must not leave a new model next to an
  // old report (or the reverse).
  AtomicFileSet outputs;
  nlohmann::json model_json = id.model.with_name(nominal.name() + " (calibrated, " + a.model + " model)").to_json();
  if (id.registration) model_json["registration"] = compensation::registration_to_json(*id.registration);
  outputs.add(a.out, model_json.dump(2) + "\n");
  if (!a.report.empty()) outputs.add(a.report, text.str());
  if (!a.robot_out.empty()) outputs.add(a.robot_out, nominal_with_reflector(a, table, q, nominal, id).dump(2) + "\n");
  require_standard_output();  // the report went to standard output: all or nothing
  outputs.commit();
  std::cerr << "calibrate: identified model written to " << a.out << "\n";
}

void add_calibrate_command(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Kinematic calibration (Levenberg-Marquardt, optional IGG3 robust weights, automatic removal of\n"
      "unidentifiable parameters) from tracker measurements in the columns 'errfield simulate' writes:\n"
      "q1..q6 (deg) and either mx,my,mz (--model position: tracker frame, mm; registration first) or\n"
      "kind (base|target) + dist_b0,dist_b1,... (--model distance: distances to the base points, mm).\n"
      "Fixed base points (not robot positions, e.g. tracker nests): no base rows, one --base-point X,Y,Z\n"
      "(nominal, robot base frame, mm) per dist_bK column; their coordinates are identified too.\n"
      "Prints the identified parameters and the before/after residuals; writes the identified robot JSON.\n"
      "Example: errfield calibrate --robot robot.json --data grid.csv --model distance --out calibrated.json");
  cmd->add_option("--robot", args->robot,
                  "nominal robot JSON or built-in name (er20-c10, kr16, ur5e, ur5, ur10); default: built-in ER20-C10 (no tool). "
                  "x,y,z columns, if present, must be its FK (within 5 mm)");
  cmd->add_option("--data", args->data, "measurement CSV")->required();
  cmd->add_option("--model", args->model, "distance (default) or position");
  cmd->add_option("--tool-reflector", args->tool_reflector,
                  "--model position with a 'reflector' column (several points on the flange, e.g. simulate "
                  "--reflectors): the label that is the identified model's tool point; the others are located on the "
                  "flange with it and determine its orientation. Default: the label located nearest --robot's tool");
  cmd->add_option("--base-point", args->base_points,
                  "nominal X,Y,Z (mm, robot base frame) of fixed base point bK, repeatable, one per dist_bK column, "
                  "for data without base rows (--model distance); identified with the robot");
  cmd->add_option("--k0", args->k0, "IGG3 k0 (default 1.5)");
  cmd->add_option("--k1", args->k1, "IGG3 k1 (default 3.0)");
  cmd->add_option("--robust", args->robust,
                  "'none' (plain least squares, the default) or 'igg3' (IGG3 reweighting against gross outliers); "
                  "docs/robot.md says which data decided the default");
  cmd->add_flag("--no-robust", args->no_robust, "the same as --robust none");
  cmd->add_option("--max-condition", args->max_condition,
                  "--model position: remove weakly identifiable parameters until the physically scaled Jacobian's "
                  "condition number (mm, and rad x the arm's reach) is below this; --model distance: directions "
                  "weaker than largest/this are regularized toward nominal (docs/robot.md; default 1000)");
  cmd->add_option("--max-registration-rms", args->max_registration_rms,
                  "--model position: refuse (exit 2) when the registration (with reflector offset) leaves a larger RMS "
                  "(mm; default 5): a wrong robot or mixed-up rows");
  cmd->add_option("--report", args->report, "also write the report to this text file (with --out, all or none)");
  cmd->add_option("--out", args->out, "identified robot JSON (written atomically)")->required();
  cmd->add_option("--robot-out", args->robot_out,
                  "also write the NOMINAL robot with the reflector offset found in the data as its tool point (and, "
                  "--model position, its own tracker registration): the robot to score --method none or fit "
                  "vector-kriging with, instead of editing JSON by hand");
  cmd->callback([args] { run_calibrate(*args); });
}

Registration register_calibrate{"calibrate", 63, &add_calibrate_command};

}  // namespace
}  // namespace errfield::cli
