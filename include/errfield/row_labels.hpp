#pragma once
/// Names of the rows of a data set, for error messages: "S.csv:7" (file:line, like a compiler and
/// like CsvTable's cell errors) when the data came from a file, "sample 5" (0-based index) when it
/// was passed in memory. A message about one row starts with its label: "S.csv:7: ...". Estimators that can reject a
/// particular sample or target (a duplicate grid node, a target outside the grid) take one of
/// these so that their message points at the row the user has to fix.

#include <cstddef>
#include <string>
#include <vector>

namespace errfield {

struct RowLabels {
  std::string source;              ///< file name; empty for data passed in memory
  std::vector<std::size_t> lines;  ///< 1-based line in `source` of each row; empty if unknown
  std::string noun = "sample";     ///< what a row is called when no file is known ("target", ...)

  /// 1-based file line of row i, or 0 when unknown.
  std::size_t line(std::size_t i) const { return i < lines.size() ? lines[i] : 0; }

  /// True when row i has a file and line, i.e. its label is "S.csv:7".
  bool in_file(std::size_t i) const { return !source.empty() && i < lines.size(); }

  /// "S.csv:7" or "sample 5".
  std::string operator()(std::size_t i) const {
    if (in_file(i)) return source + ":" + std::to_string(lines[i]);
    return noun + " " + std::to_string(i);
  }
};

}  // namespace errfield
