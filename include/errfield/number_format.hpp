#pragma once
/// @file
/// The one home of number formatting: every number errfield writes to a file, a message or a note
/// goes through one of these two functions, so that files read back exactly and people read the
/// same spelling everywhere. Solvers return numbers; only their callers format them.

#include <string>

namespace errfield {

/// Shortest text that reads back to exactly `value` (std::to_chars): what CSV and JSON files hold.
/// "nan" and "inf" never occur in our outputs; callers write an empty cell for a missing value.
std::string format_number(double value);

/// `value` with at most `digits` significant digits (printf's %g: 5 gives "0.012346", "1.2346e+05"),
/// for notes and log lines a person reads; the numbers that matter are written exactly elsewhere.
std::string format_significant(double value, int digits);

}  // namespace errfield
