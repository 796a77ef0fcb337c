#pragma once
/// A CSV file as exported by tracker software and robot controllers, read into memory with every
/// cell kept as text until a column is asked for as numbers. Use it at the edge of a program; the
/// estimators take plain vectors and matrices.
///
/// Accepted: a UTF-8 byte-order mark, CRLF or LF line ends, ',' or ';' as delimiter (detected from
/// the header line), double-quoted cells, blank lines and lines starting with '#' (skipped), and a
/// unit after a column name ("x [mm]" or "x (mm)" is found as "x"). Rejected with an InputError
/// naming file, row and column: a row with a different number of cells than the header, duplicate
/// column names, and — when a column is read as numbers — empty, non-numeric, NaN or infinite cells.
///
/// Bounds (so that a wrong file, `/dev/zero` or an endless pipe cannot hang the reader or eat the
/// memory): at most kMaxColumns columns (InputError), at most kMaxInputBytes bytes per file
/// (ResourceError, exit 3), and a NUL byte stops the reading at the first block that has one.
/// The limits of every reader (CSV, JSON, URDF) are listed in docs/reliability.md, "Input limits".

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "errfield/number_format.hpp"  // format_number, declared where formatting lives

namespace errfield {

class CsvTable {
 public:
  /// More columns than any tracker or controller export has; the header is refused beyond it.
  static constexpr std::size_t kMaxColumns = 10000;
  /// 4 GiB: the table in memory takes several times the file's size.
  static constexpr std::size_t kMaxInputBytes = std::size_t{4} << 30;

  /// Reads and parses `path`. Throws InputError if the file cannot be opened or is malformed,
  /// ResourceError if it holds more than `max_bytes` bytes (read no further than that).
  static CsvTable read(const std::string& path, std::size_t max_bytes = kMaxInputBytes);
  /// Parses text already in memory; `source` names it in error messages.
  static CsvTable parse(std::string_view text, std::string source);

  /// The data rows `keep` (in that order) with the header, source and line numbers kept, so messages
  /// about a subset still name the file's lines. Throws std::out_of_range beyond the table.
  CsvTable rows(const std::vector<std::size_t>& keep) const;

  /// A table computed from this one's rows (e.g. one reading expanded into several): row r holds
  /// `cells[r]` under `header` and keeps the line number of row `from[r]` of this table, so that a
  /// message about it names the line the user wrote. Throws ArgumentError for a row whose cell count
  /// is not the header's, or a header with a duplicate name.
  CsvTable derived(std::vector<std::string> header, const std::vector<std::size_t>& from,
                   const std::vector<std::vector<std::string>>& cells) const;
  const std::string& source() const noexcept { return source_; }
  const std::vector<std::string>& header() const noexcept { return header_; }
  std::size_t row_count() const noexcept { return lines_.size(); }
  /// The text of one cell (data row `row`, column index `column`): trimmed, unquoted. Valid while
  /// the table lives. Throws std::out_of_range beyond the table.
  std::string_view cell(std::size_t row, std::size_t column) const;

  /// Data row i, whose cells are copied out as strings on access (`table.row(i)[c]`); for code
  /// that wants owned text. Reading many cells, prefer cell(), which copies nothing.
  class Row {
   public:
    Row(const CsvTable& table, std::size_t row) noexcept : table_(&table), row_(row) {}
    std::string operator[](std::size_t column) const { return std::string(table_->cell(row_, column)); }
    std::size_t size() const noexcept { return table_->header_.size(); }
    /// Every cell, copied.
    operator std::vector<std::string>() const {
      std::vector<std::string> cells;
      cells.reserve(size());
      for (std::size_t c = 0; c < size(); ++c) cells.emplace_back(table_->cell(row_, c));
      return cells;
    }
    /// Cell for cell the same text (the rows may come from different tables).
    friend bool operator==(const Row& a, const Row& b) {
      if (a.size() != b.size()) return false;
      for (std::size_t c = 0; c < a.size(); ++c)
        if (a.table_->cell(a.row_, c) != b.table_->cell(b.row_, c)) return false;
      return true;
    }

   private:
    const CsvTable* table_;
    std::size_t row_;
  };
  /// Throws std::out_of_range beyond the table.
  Row row(std::size_t i) const {
    if (i >= row_count()) (void)cell(i, 0);  // the same out_of_range message
    return Row(*this, i);
  }
  /// Line number in the file (1-based) of data row i, for messages.
  std::size_t line_of_row(std::size_t i) const { return lines_.at(i); }

  bool has_column(std::string_view name) const noexcept;
  /// Index of a column; throws InputError listing the available columns when it is missing.
  std::size_t column_index(std::string_view name) const;
  /// A column as numbers; throws InputError naming file, line and column for a bad cell.
  std::vector<double> numeric_column(std::string_view name) const;
  /// One cell (data row `row`, column index `column`) as a finite number; throws InputError
  /// naming file, line, column and the cell, as numeric_column does.
  double numeric_cell(std::size_t row, std::size_t column) const;
  /// Several columns as a rows x names.size() matrix (row-major semantics: row i is data row i).
  Eigen::MatrixXd numeric_columns(const std::vector<std::string>& names) const;

 private:
  /// Appends the cells of one data line; returns how many it had.
  std::size_t append_row(std::string_view line, char delimiter, std::size_t line_number);

  std::string source_;
  std::vector<std::string> header_;
  std::vector<std::string> keys_;  // header names without units, for lookup
  // Every data cell's text back to back, row-major, and where each ends: one allocation for the
  // whole table instead of one string per cell (a 20,000-row file was a third of a variogram run).
  std::string cells_;
  std::vector<std::size_t> cell_ends_;
  std::vector<std::size_t> lines_;
};

/// The name under which a header cell is looked up: blanks trimmed, a unit ("x [mm]", "x (mm)")
/// dropped. Two header cells with the same key are the same column (and a duplicate).
std::string column_key(std::string_view name);


/// Splits "a,b,c" into {"a","b","c"}, trimming spaces; empty items are an ArgumentError naming
/// `what` (the option being parsed).
std::vector<std::string> split_list(std::string_view text, std::string_view what);

/// split_list for a list of column names: a name given twice ("x,y,x") is also an ArgumentError
/// naming `what` and the column, since it would silently weigh that column twice.
std::vector<std::string> split_column_list(std::string_view text, std::string_view what);

}  // namespace errfield
