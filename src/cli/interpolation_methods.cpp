#include "cli/interpolation_methods.hpp"

#include <algorithm>

#include "errfield/error.hpp"

namespace errfield::cli {

std::vector<InterpolationMethod>& interpolation_methods() {
  static std::vector<InterpolationMethod> methods;
  return methods;
}

namespace {
bool offered(const InterpolationMethod& m, bool for_cv) {
  return for_cv ? m.cross_validate != nullptr : m.interpolate != nullptr;
}
}  // namespace

MethodOptionOwnership add_method_options(CLI::App& command, bool for_cv) {
  MethodOptionOwnership ownership;
  for (const auto& m : interpolation_methods()) {
    if (!offered(m, for_cv) || !m.add_options) continue;
    const auto before = command.get_options();
    m.add_options(command);
    std::vector<CLI::Option*> mine;
    for (CLI::Option* o : command.get_options())
      if (std::find(before.begin(), before.end(), o) == before.end()) mine.push_back(o);
    ownership.owned.emplace_back(m.name, std::move(mine));
  }
  return ownership;
}

void MethodOptionOwnership::check(const std::string& chosen, const std::vector<std::string>& accepted_shared,
                                  const std::vector<CLI::Option*>& shared_options) const {
  for (const auto& [method, options] : owned) {
    if (method == chosen) continue;
    for (const CLI::Option* o : options)
      if (o->count() > 0)
        throw ArgumentError(o->get_name() + " applies to --method " + method + ", not --method " + chosen);
  }
  for (const CLI::Option* o : shared_options) {
    if (o->count() == 0) continue;
    if (std::find(accepted_shared.begin(), accepted_shared.end(), o->get_name()) == accepted_shared.end())
      throw ArgumentError(o->get_name() + " does not apply to --method " + chosen);
  }
}

const InterpolationMethod& find_method(const std::string& name, bool for_cv) {
  for (const auto& m : interpolation_methods())
    if (m.name == name && offered(m, for_cv)) return m;
  throw ArgumentError("--method: unknown method '" + name + "'; available: " + method_names(for_cv));
}

std::string method_names(bool for_cv) {
  std::vector<std::string> names;
  for (const auto& m : interpolation_methods())
    if (offered(m, for_cv)) names.push_back(m.name);
  std::sort(names.begin(), names.end());
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : "|") + n;
  return s;
}

OptionNames cli_option_names() {
  OptionNames n;
  n.kind = "--kind";
  n.mean = "--mean";
  n.backend = "--backend";
  n.neighbors = "--neighbors";
  n.radius = "--radius";
  n.neighbour_metric = "--neighbour-metric";
  n.min_neighbours = "--min-neighbours";
  n.octant_max = "--octant-max";
  n.nugget = "--nugget-as";
  n.duplicates = "--duplicates";
  n.power = "--power";
  return n;
}

RowLabels row_labels_of(const CsvTable& table, std::string noun) {
  RowLabels labels;
  labels.source = table.source();
  labels.noun = std::move(noun);
  labels.lines.resize(table.row_count());
  for (std::size_t i = 0; i < table.row_count(); ++i) labels.lines[i] = table.line_of_row(i);
  return labels;
}

std::string unit_of_column(const CsvTable& table, const std::string& name) {
  const std::string& header = table.header()[table.column_index(name)];
  const auto open = header.find_first_of("[(");
  if (open == std::string::npos || open == 0) return {};
  const char close = header[open] == '[' ? ']' : ')';
  const auto end = header.find(close, open + 1);
  if (end == std::string::npos) return {};
  std::string unit = header.substr(open + 1, end - open - 1);
  const auto first = unit.find_first_not_of(' ');
  const auto last = unit.find_last_not_of(' ');
  return first == std::string::npos ? std::string{} : unit.substr(first, last - first + 1);
}

void throw_unsupported_components(std::size_t components) {
  throw ArgumentError("--value: " + std::to_string(components) +
                      " value columns; supported are 1 (a scalar), 2 or 3 (a vector)");
}

}  // namespace errfield::cli
