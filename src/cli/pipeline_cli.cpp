#include "cli/pipeline_cli.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <utility>

#include "errfield/csv_table.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::cli {

std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& what) {
  const auto items = split_list(text, what);
  if (items.size() != count)
    throw ArgumentError(what + ": expected " + std::to_string(count) + " comma-separated numbers, got '" + text + "'");
  std::vector<double> v;
  for (const auto& item : items) {
    std::size_t used = 0;
    double x = NAN;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || !std::isfinite(x)) throw ArgumentError(what + ": '" + item + "' is not a finite number");
    v.push_back(x);
  }
  return v;
}

std::optional<Eigen::Isometry3d> parse_tool_option(const std::string& text, const Eigen::Isometry3d& current_tool,
                                                   const std::string& what) {
  if (text.empty()) return std::nullopt;
  const std::size_t count = split_list(text, what).size();
  if (count != 3 && count != 6)
    throw ArgumentError(what + ": expected X,Y,Z or X,Y,Z,RX,RY,RZ (flange frame; mm, deg), got '" + text + "'");
  const std::vector<double> v = parse_numbers(text, count, what);
  // An angle beyond a turn is a typo (radians in the wrong field, a unit slip): reduced modulo 360 it
  // would be an orientation nobody gave.
  for (std::size_t k = 3; k < count; ++k)
    if (std::abs(v[k]) > 360.0)
      throw ArgumentError(what + ": angle " + std::string(1, "xyz"[k - 3]) + " " + format_number(v[k]) +
                          " deg is beyond a turn; expected -360..360 deg (X,Y,Z,RX,RY,RZ: mm, deg)");
  Eigen::Isometry3d tool = current_tool;
  if (count == 6) tool = robot::to_isometry({v[0], v[1], v[2], v[3], v[4], v[5]});
  tool.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  compensation::check_tool_point(tool, what);
  return tool;
}

std::string tool_option_text(const Eigen::Isometry3d& tool) {
  const robot::PoseXyzRpy p = robot::to_xyz_rpy(tool);
  std::string text;
  for (double v : {p.x_mm, p.y_mm, p.z_mm, p.rx_deg, p.ry_deg, p.rz_deg})
    text += (text.empty() ? "" : ",") + format_number(std::round(v * 1e6) / 1e6);
  return text;
}

void add_tool_option(CLI::App* cmd, std::string& into, const std::string& role) {
  cmd->add_option("--tool", into,
                  "X,Y,Z[,RX,RY,RZ]: the working tool for this run (flange frame; mm, deg; three numbers keep the "
                  "tool's orientation), " + role + ", instead of the model's; at most " +
                  format_number(compensation::kMaxToolPointMm) +
                  " mm from the flange. Away from the measured reflector the variance includes the flange's "
                  "unobservable orientation error, and rows too far from it are refused (orientation-unknown; "
                  "docs/robot.md, \"Tool points and orientation\")")
      // Given empty (a shell variable that was not set), it must not silently mean "no --tool".
      ->check(CLI::Validator(
          [](std::string& text) {
            return text.find_first_not_of(" \t") == std::string::npos
                       ? std::string("empty; expected X,Y,Z or X,Y,Z,RX,RY,RZ (flange frame; mm, deg), or leave --tool out")
                       : std::string();
          },
          "X,Y,Z[,RX,RY,RZ]"));
}

void print_working_tool(std::ostream& out, const compensation::CompensationModel& model) {
  if (!model.working_tool()) return;
  const double lever = (model.working_tool()->translation() - model.measured_point_mm()).norm();
  const compensation::OrientationPrior& prior = model.orientation_prior();
  out << "  working tool " << tool_option_text(model.tool_in_robot_frame(*model.working_tool())) << " (--tool, flange frame): "
      << format_number(std::round(lever * 10) / 10) << " mm from the reflector the model was measured with";
  const auto& correction = model.tool_point_correction();
  if (correction && prior.known() &&
      (correction->point_mm() - model.working_tool()->translation()).norm() <= compensation::kSameFlangePointMm)
    out << "; its own " << correction->readings()
        << " readings' residual kriged over the joints (tool_point_correction): rows whose remaining uncertainty "
           "there exceeds "
        << format_number(std::round(compensation::kMaxLeverResidualRatio * prior.residual_rms_mm * 1e4) / 1e4)
        << " mm RMS are refused (orientation-unknown)";
  else if (prior.known())
    out << "; orientation prior " << format_number(std::round(prior.sigma_rad * 1e6) / 1e3)
        << " mrad per axis, refused beyond " << format_number(std::round(prior.max_lever_mm)) << " mm"
        << (lever > prior.max_lever_mm ? " (every row: orientation-unknown)" : "");
  else if (lever > 0.0)
    out << "; the model has no variance to widen for the flange's orientation error";
  out << "\n";
}

void add_step_columns(OutputTable& out, const compensation::StepColumns& step) {
  for (const auto& c : step.columns) {
    if (c.is_words()) {
      out.add_column(c.name, c.words);
      continue;
    }
    std::vector<std::string> cells(c.numbers.size());
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (std::isfinite(c.numbers[i])) cells[i] = format_number(c.numbers[i]);
    out.add_column(c.name, std::move(cells));
  }
}

std::string refusal_tally(const std::vector<std::string>& status) {
  std::vector<std::pair<std::string, std::size_t>> counts;
  for (const auto& s : status) {
    if (s == "ok") continue;
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == s; });
    if (it == counts.end()) counts.emplace_back(s, 1);
    else ++it->second;
  }
  std::string text;
  for (const auto& [word, count] : counts) text += (text.empty() ? "" : ", ") + word + " " + std::to_string(count);
  // The one refusal the user can lift with more data: say which data.
  if (std::any_of(counts.begin(), counts.end(), [](const auto& c) { return c.first == "orientation-unknown"; }))
    text += "; orientation-unknown: the working tool is further from the measured reflector than the flange "
            "orientation the model knows supports - locate it with 'errfield locate-tool' from readings at it, or "
            "fit readings of several points on the flange (docs/robot.md, 'Tool points and orientation')";
  if (std::any_of(counts.begin(), counts.end(),
                  [](const auto& c) { return c.first == "outside-region" || c.first == "calibration-extrapolated"; }))
    text += "; predict and validate answer such poses with --extrapolate (status extrapolated: outside the field's "
            "region the calibration and joint error functions alone, no variance claimed); compensate never "
            "does";
  if (std::any_of(counts.begin(), counts.end(), [](const auto& c) { return c.first == "calibration-extrapolated"; }))
    text += "; calibration-extrapolated: the pose lies beyond what the calibration's poses determine (another tool "
            "orientation or arm posture than they cover) - measure poses like it and fit again (errfield plan "
            "--candidates picks them; docs/robot.md, 'Calibration leverage')";
  return text;
}

const std::vector<std::string>& status_words(const compensation::StepColumns& step) {
  static const std::vector<std::string> none;
  for (const auto& c : step.columns)
    if (c.name == "status") return c.words;
  return none;
}

void add_extrapolate_option(CLI::App* cmd, bool& extrapolate) {
  cmd->add_flag("--extrapolate", extrapolate,
                "answer rows the model refuses as outside-region or calibration-extrapolated (status extrapolated): "
                "outside the field's region with the calibrated kinematics and joint error functions alone, beyond the "
                "calibration's poses with the whole model; no variance or 95 % radius is claimed for them (e.g. a model "
                "of one series used on another after 'errfield register'); compensate never extrapolates");
}

}  // namespace errfield::cli
