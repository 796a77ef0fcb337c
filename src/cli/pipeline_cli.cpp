#include "cli/pipeline_cli.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

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
  return text;
}

const std::vector<std::string>& status_words(const compensation::StepColumns& step) {
  static const std::vector<std::string> none;
  for (const auto& c : step.columns)
    if (c.name == "status") return c.words;
  return none;
}

}  // namespace errfield::cli
