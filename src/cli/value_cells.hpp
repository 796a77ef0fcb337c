#pragma once
// Value columns of a CSV that may have gaps: heterotopic samples, where a variable is measured at
// fewer locations than another (cokriging, the variograms of several columns).

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/csv_table.hpp"

namespace errfield::cli {

/// CsvTable::numeric_columns for data with gaps: an empty cell reads as NaN, "not measured"; a
/// non-numeric, NaN or infinite cell is still an InputError naming file, line and column. For
/// commands that can use missing values only; the others keep refusing empty cells through
/// numeric_columns.
inline Eigen::MatrixXd numeric_columns_with_gaps(const CsvTable& table, const std::vector<std::string>& names) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(table.row_count()), static_cast<Eigen::Index>(names.size()));
  for (std::size_t j = 0; j < names.size(); ++j) {
    const std::size_t c = table.column_index(names[j]);
    for (std::size_t i = 0; i < table.row_count(); ++i)
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          table.cell(i, c).empty() ? std::numeric_limits<double>::quiet_NaN() : table.numeric_cell(i, c);
  }
  return m;
}

}  // namespace errfield::cli
