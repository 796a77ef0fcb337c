#pragma once
/// Writing CSV cells so that CsvTable (csv_table.hpp) reads them back exactly: every CSV writer of
/// errfield (the CLI's OutputTable, the reproduction's tables) goes through these two functions, so
/// a point named "p,1" or a note with a quote never makes a file errfield itself refuses.

#include <string>
#include <string_view>
#include <vector>

namespace errfield {

/// One cell as it must be written to a CSV file so that CsvTable reads back exactly `cell`:
/// quoted (RFC 4180: inside double quotes, a quote doubled) when it holds a comma, semicolon,
/// quote, CR or LF, starts or ends with a blank (the reader trims unquoted cells) or starts with
/// '#' (a line starting with '#' is a comment); else unchanged.
std::string csv_cell(std::string_view cell);

/// Appends `cells` as one CSV line ending in '\n', each through csv_cell. A line of one empty cell
/// is written `""` (a blank line would be skipped by the reader).
void append_csv_line(std::string& out, const std::vector<std::string>& cells);

}  // namespace errfield
