// `errfield locate-tool`: a model's working tool point located from a few readings of it (issue 34).
#include <cmath>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/pipeline_cli.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/compensation/tools/tool_location.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"

namespace errfield::cli {
namespace {

struct LocateToolArgs {
  std::string model, data, out;
  compensation::ToolLocationOptions options;
  bool joints_are_degrees = false;  // skip the radians check (check_joints_not_radians)
};

std::string rounded(double v, double scale = 1e4) { return format_number(std::round(v * scale) / scale); }

void run_locate_tool(const LocateToolArgs& a) {
  using namespace compensation;
  refuse_same_output({{"--model", &a.model}, {"--out", &a.out}});
  naming_options([&] { a.options.validate(); }, {{"ToolLocationOptions: distinct_orientation_deg", "--distinct-orientation"},
                                                 {"ToolLocationOptions: min_orientations", "--min-orientations"},
                                                 {"ToolLocationOptions: not_rigid_factor", "--not-rigid-factor"}});
  const nlohmann::json j = read_json_file(a.model, "model file");
  const CompensationModel model = with_json_source(a.model, [&] { return CompensationModel::from_json(j, a.model); });
  const CsvTable table = CsvTable::read(a.data);
  const MeasurementSet readings = with_source(a.data, [&] { return MeasurementSet::from_table(table, model.nominal_model()); });
  // Radians read as degrees turn the flange by a few degrees only: without this check they were
  // refused as too few distinct orientations ("measure at more"), which sends a user the wrong way.
  if (!a.joints_are_degrees) check_joints_not_radians(readings.q_deg, model, a.data, "--joints-are-degrees");
  const ToolLocation t = with_source(a.data, [&] { return locate_tool(model, readings, a.options); });
  Eigen::Isometry3d tool = model.command_model().tool();
  tool.translation() = t.tool_mm;
  CompensationModel located = with_located_tool(model, t);
  std::vector<std::string> notes = located.notes();
  notes.push_back("locate-tool: working tool located from " + std::to_string(t.readings) + " readings of " + a.data +
                  " at (" + rounded(t.tool_mm.x()) + ", " + rounded(t.tool_mm.y()) + ", " + rounded(t.tool_mm.z()) +
                  ") mm (flange frame), residual RMS " + rounded(t.residual_rms_mm) + " mm");
  located = located.with_notes(std::move(notes));
  AtomicFileSet outputs;
  outputs.add(a.out, located.to_json().dump(1) + "\n");
  // The report first, the model after it (commit_after_standard_output): a standard output that
  // cannot be written (> /dev/full) replaced --out, then exited 1 (issue 47, the class of item 10).
  std::ostringstream text;
  const OrientationPrior& prior = located.orientation_prior();
  text << "locate-tool: " << t.readings << " readings of " << a.data << " in " << t.orientations
            << " distinct flange orientations";
  if (t.left_out) text << " (" << t.left_out << " left out: outside the model's region)";
  if (t.gross)
    text << " (" << t.gross << " gross reading(s) left out of the location and the correction: over "
         << format_number(ToolPointCorrection::kOutlierLimit) << " robust sd left out one at a time)";
  text << "\n  tool point " << rounded(t.tool_mm.x()) << "," << rounded(t.tool_mm.y()) << "," << rounded(t.tool_mm.z())
            << " mm (the calibrated model's flange frame; --tool " << tool_option_text(located.tool_in_robot_frame(tool))
            << " in the robot description's), standard deviation " << rounded(t.sd_mm.x()) << ", " << rounded(t.sd_mm.y()) << ", "
            << rounded(t.sd_mm.z()) << " mm per axis (least squares, readings taken as independent)\n"
            << "  fit residual RMS " << rounded(t.residual_rms_mm) << " mm (" << t.expected_basis << " explains "
            << rounded(t.expected_rms_mm) << " mm)\n"
            << "  " << rounded(t.lever_mm, 10) << " mm from the reflector the model was measured with"
            << (t.field_used ? "; the flange position corrected by the model's field and joint functions"
                             : "; the model's calibrated kinematics alone (no field)");
  if (prior.known() && !t.correction)
    text << "; orientation " << (located.measured_orientation() ? "residual measured at its readings " : "prior ")
              << rounded(prior.sigma_rad * 1e3, 1e3) << " mrad, rows refused beyond "
              << rounded(prior.max_lever_mm, 1) << " mm" << (t.lever_mm > prior.max_lever_mm ? " (this point: every row)" : "");
  if (const auto& c = t.correction) {
    text << "\n  the readings' residual at the point kriged over the joints (the flange's turn the model's points do "
                 "not see): RMS "
              << rounded(t.uncorrected_rms_mm) << " mm at the readings, " << rounded(t.correction_leave_one_out_rms_mm)
              << " mm left out one at a time with the correction"
              << (c->excluded_readings() ? " (" + std::to_string(c->excluded_readings()) + " gross reading(s) left out: over " +
                                               format_number(ToolPointCorrection::kOutlierLimit) + " robust sd)"
                                         : std::string())
              << "; standard deviation per flange axis "
              << rounded(std::sqrt(c->sill_mm2().x())) << ", " << rounded(std::sqrt(c->sill_mm2().y())) << ", "
              << rounded(std::sqrt(c->sill_mm2().z())) << " mm, noise " << rounded(std::sqrt(c->noise_mm2()))
              << " mm; correlation over the joints " << c->correlation().to_string() << ", variance x " << rounded(c->variance_factor(), 100) << " (leave-one-out)";
    if (prior.known())
      text << "; rows whose remaining uncertainty there exceeds "
                << rounded(compensation::kMaxLeverResidualRatio * prior.residual_rms_mm) << " mm RMS are refused";
  } else if (t.field_used && t.readings < compensation::kMinToolPointCorrectionReadings) {
    text << "\n  " << t.readings << " readings: fewer than the " << compensation::kMinToolPointCorrectionReadings
              << " a correction at the point is kriged from (the orientation term stands for it)";
  }
  text << "\n  model with this working tool written to " << a.out
       << " (predict, validate and compensate use it; --tool overrides it)\n";
  commit_after_standard_output(outputs, text.str());
}

void add_locate_tool_command(CLI::App& app) {
  auto a = std::make_shared<LocateToolArgs>();
  auto* cmd = app.add_subcommand(
      "locate-tool",
      "Locate a point rigidly attached to the flange (a second reflector nest, a tool tip) from a few tracker\n"
      "readings of it, through the model's calibrated kinematics, registration, field and joint functions\n"
      "(least squares, linear in the point); writes the model with that working tool, everything else kept,\n"
      "so predict, validate and compensate work at the new point. Reports the point (flange frame, mm), its\n"
      "standard deviation per axis and the fit residual RMS; refuses readings in fewer than 3 distinct flange\n"
      "orientations and readings that are not one rigid point (docs/robot.md, \"Tool points and orientation\").\n"
      "Example: errfield locate-tool --model model.json --data tool_readings.csv --out model_tool.json"
      "  # not-run: needs tracker readings of a point mounted on the flange, at several orientations");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit' (with a registration)")->required();
  cmd->add_option("--data", a->data, "readings of the point: point,q1..q6,mx,my,mz (tracker frame, mm; docs/data-formats.md)")
      ->required();
  cmd->add_option("--min-orientations", a->options.min_orientations,
                  "at least this many distinct flange orientations among the readings")
      ->capture_default_str();
  cmd->add_option("--distinct-orientation", a->options.distinct_orientation_deg,
                  "DEG: flange orientations closer than this count as one")
      ->capture_default_str();
  cmd->add_option("--not-rigid-factor", a->options.not_rigid_factor,
                  "refuse readings whose residual RMS exceeds this many times what the model's own errors explain")
      ->capture_default_str();
  cmd->add_option("--out", a->out, "model JSON with the located working tool (written atomically)")->required();
  cmd->add_flag("--joints-are-degrees", a->joints_are_degrees,
                "skip the check that refuses readings whose joints look like radians (all within +-2 pi and spread far "
                "less than the model's training joints)");
  cmd->callback([a] { run_locate_tool(*a); });
}

Registration register_locate_tool{"locate-tool", 75, &add_locate_tool_command};

}  // namespace
}  // namespace errfield::cli
