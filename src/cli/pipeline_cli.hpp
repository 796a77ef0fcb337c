#pragma once
// Helpers of the pipeline commands (plan, fit, compensate).

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>

#include "cli/cli_support.hpp"
#include "errfield/compensation/pipeline.hpp"

namespace errfield::cli {

/// "a,b,c" -> exactly `count` numbers; ArgumentError naming `what` and the bad item otherwise.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& what);

/// `--tool X,Y,Z[,RX,RY,RZ]` (flange frame; mm, deg as robot JSON tools): the working tool of predict,
/// compensate and validate, checked by compensation::check_tool_point; with three numbers the tool
/// keeps `current_tool`'s orientation. Empty text: none. ArgumentError naming the option otherwise.
std::optional<Eigen::Isometry3d> parse_tool_option(const std::string& text, const Eigen::Isometry3d& current_tool,
                                                   const std::string& what = "--tool");
/// The text `--tool` takes for `tool` (six numbers).
std::string tool_option_text(const Eigen::Isometry3d& tool);
/// Adds `--tool` to a command; `role` says what the point is for ("the point predicted").
void add_tool_option(CLI::App* cmd, std::string& into, const std::string& role);
/// Where the model has a working tool: one line with its lever from the reflector, the orientation
/// prior and the lever beyond which rows are refused (orientation-unknown). Nothing otherwise.
void print_working_tool(std::ostream& out, const compensation::CompensationModel& model);

/// Appends a step's columns (compensation/pipeline.hpp) to `out`: numbers in shortest round-trip
/// form, NaN as an empty cell.
void add_step_columns(OutputTable& out, const compensation::StepColumns& step);

/// How many rows have each status other than "ok", in order of first appearance:
/// "outside-region 78, outside-limits 2" (for the message of a job that predicted nothing).
std::string refusal_tally(const std::vector<std::string>& status);

/// The words of a step's "status" column (empty if it has none).
const std::vector<std::string>& status_words(const compensation::StepColumns& step);

/// `--extrapolate` of predict and validate (prediction.hpp, predict_position's extrapolate).
void add_extrapolate_option(CLI::App* cmd, bool& extrapolate);

}  // namespace errfield::cli
