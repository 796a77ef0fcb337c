#pragma once
// Helpers of the pipeline commands (plan, fit, compensate).

#include <string>
#include <vector>

#include "cli/cli_support.hpp"
#include "errfield/compensation/pipeline.hpp"

namespace errfield::cli {

/// "a,b,c" -> exactly `count` numbers; ArgumentError naming `what` and the bad item otherwise.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& what);

/// Appends a step's columns (compensation/pipeline.hpp) to `out`: numbers in shortest round-trip
/// form, NaN as an empty cell.
void add_step_columns(OutputTable& out, const compensation::StepColumns& step);

/// How many rows have each status other than "ok", in order of first appearance:
/// "outside-region 78, outside-limits 2" (for the message of a job that predicted nothing).
std::string refusal_tally(const std::vector<std::string>& status);

/// The words of a step's "status" column (empty if it has none).
const std::vector<std::string>& status_words(const compensation::StepColumns& step);

}  // namespace errfield::cli
