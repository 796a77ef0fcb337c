#pragma once
// Helpers of the pipeline commands (plan, fit, compensate).

#include <string>
#include <vector>

namespace errfield::cli {

/// "a,b,c" -> exactly `count` numbers; ArgumentError naming `what` and the bad item otherwise.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& what);

}  // namespace errfield::cli
