#pragma once
/// A table of results for people: column headers with units, right-aligned numbers, one string
/// per cell. Use it to print a summary on the terminal (`to_text`) and to put the same table into
/// an HTML report (HtmlReport::add_table), so the console and the report never disagree.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace errfield::report {

/// How the cells of a column line up.
enum class Align { Left, Right };

/// One column: a header, an optional unit printed under it as "[mm]", and an alignment.
struct TextColumn {
  TextColumn() = default;
  TextColumn(std::string header_, std::string unit_ = {}, Align align_ = Align::Right)
      : header(std::move(header_)), unit(std::move(unit_)), align(align_) {}

  std::string header;
  std::string unit;           ///< empty: no unit line entry for this column
  Align align = Align::Right;
};

class TextTable {
 public:
  TextTable() = default;
  explicit TextTable(std::vector<TextColumn> columns) : columns_(std::move(columns)) {}

  /// Appends a row; throws ArgumentError if it has a different number of cells than columns.
  void add_row(std::vector<std::string> cells);
  /// Appends a horizontal rule before the next row (e.g. between measured and paper rows).
  void add_separator();

  const std::vector<TextColumn>& columns() const noexcept { return columns_; }
  std::size_t row_count() const noexcept { return rows_.size(); }
  const std::vector<std::string>& row(std::size_t i) const { return rows_.at(i); }
  /// Whether a rule was requested before row i.
  bool separator_before(std::size_t i) const;

  /// Monospace rendering: header line, unit line (when any column has a unit), a rule, the rows;
  /// every column padded to its widest cell (width counted in UTF-8 code points). Ends with '\n'.
  std::string to_text(std::string_view indent = "  ") const;

 private:
  std::vector<TextColumn> columns_;
  std::vector<std::vector<std::string>> rows_;
  std::vector<std::size_t> separators_;  // row indices preceded by a rule
};

/// `value` with exactly `decimals` digits after the point ("0.104"); "-" for NaN (a missing value).
std::string fixed(double value, int decimals);

/// Number of code points in a UTF-8 string (its width on a terminal for the text we print).
std::size_t display_width(std::string_view text);

}  // namespace errfield::report
