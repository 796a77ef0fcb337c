#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "errfield/error.hpp"

namespace errfield {
namespace {

std::string_view trim_view(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

std::string trim(std::string_view s) { return std::string(trim_view(s)); }

// "x [mm]" and "x (mm)" are looked up as "x": tracker exports put units in headers.
// Surrounding blanks never count (a quoted header cell may keep them), so a name is found however
// the file spaced it. A name that is all unit ("[mm]") is kept whole.
std::string strip_unit(std::string_view name) {
  const std::string trimmed = trim(name);
  const auto pos = trimmed.find_first_of("[(");
  if (pos == std::string::npos || pos == 0) return trimmed;
  return trim(std::string_view(trimmed).substr(0, pos));
}

std::vector<std::string> split_line(std::string_view line, char delimiter, const std::string& source,
                                    std::size_t line_number) {
  std::vector<std::string> cells;
  if (line.find('"') == std::string_view::npos) {
    // No quotes (the common case): the cells are the trimmed pieces between delimiters, cut
    // whole rather than char by char (reading was a fifth of a 20,000-row variogram's time).
    cells.reserve(static_cast<std::size_t>(std::count(line.begin(), line.end(), delimiter)) + 1);
    std::size_t start = 0;
    while (true) {
      const std::size_t d = line.find(delimiter, start);
      cells.push_back(trim(line.substr(start, d == std::string_view::npos ? std::string_view::npos : d - start)));
      if (d == std::string_view::npos) return cells;
      start = d + 1;
    }
  }
  std::string cell;
  bool quoted = false;
  bool was_quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < line.size() && line[i + 1] == '"') {
          cell += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
      was_quoted = true;
    } else if (c == delimiter) {
      cells.push_back(was_quoted ? cell : trim(cell));
      cell.clear();
      was_quoted = false;
    } else {
      cell += c;
    }
  }
  if (quoted)
    throw InputError(source + ":" + std::to_string(line_number) + ": unterminated quoted cell",
                     source, line_number);
  cells.push_back(was_quoted ? cell : trim(cell));
  return cells;
}

}  // namespace

CsvTable CsvTable::read(const std::string& path, std::size_t max_bytes) {
  // Reading a directory "succeeds" with no bytes; say what it is rather than "file is empty".
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a CSV file", path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file for reading", path);
  // Block by block, so that a binary file (/dev/zero) stops at its first NUL and an endless one
  // (a pipe, /dev/urandom) at the byte limit, never after filling the memory.
  std::string text;
  {
    // One allocation for a regular file (growing by doubling copied and re-touched every byte).
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && size <= max_bytes) text.reserve(static_cast<std::size_t>(size));
  }
  std::vector<char> block(std::size_t{1} << 20);
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got == 0) break;
    if (std::memchr(block.data(), '\0', got) != nullptr)
      throw InputError(path + ": contains a NUL byte; expected a text CSV file", path);
    if (text.size() + got > max_bytes)
      throw ResourceError(path + ": the file holds more than " + std::to_string(max_bytes) +
                              " bytes, the most a CSV input may have; split it or thin it out");
    text.append(block.data(), got);
  }
  if (in.bad()) throw InputError(path + ": read error", path);
  return parse(text, path);
}

CsvTable CsvTable::parse(std::string_view text, std::string source) {
  CsvTable table;
  table.source_ = std::move(source);
  const std::string& src = table.source_;
  if (text.size() >= 3 && static_cast<unsigned char>(text[0]) == 0xEF &&
      static_cast<unsigned char>(text[1]) == 0xBB && static_cast<unsigned char>(text[2]) == 0xBF)
    text.remove_prefix(3);
  if (text.find('\0') != std::string_view::npos)
    throw InputError(src + ": contains a NUL byte; expected a text CSV file", src);

  {
    const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
    table.lines_.reserve(lines);
    table.cells_.reserve(text.size());
  }
  char delimiter = ',';
  bool have_header = false;
  std::size_t line_number = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    auto end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    ++line_number;
    {
      std::string_view first_line = line;
      if (!first_line.empty() && first_line.back() == '\r') first_line.remove_suffix(1);
      const auto first = first_line.find_first_not_of(" \t");  // blank or comment line: skipped
      if (first == std::string_view::npos || first_line[first] == '#') {
        pos = end + 1;
        if (end == text.size()) break;
        continue;
      }
    }
    std::size_t continued_lines = 0;
    // A quoted cell may hold line breaks (RFC 4180; csv_cell writes them so): while the quotes
    // are unbalanced, the row goes on on the next line.
    if (line.find('"') != std::string_view::npos)
      while (std::count(line.begin(), line.end(), '"') % 2 == 1 && end < text.size()) {
        end = text.find('\n', end + 1);
        if (end == std::string_view::npos) end = text.size();
        line = text.substr(pos, end - pos);
        ++continued_lines;
      }
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!have_header) {
      if (line.find(',') == std::string_view::npos && line.find(';') != std::string_view::npos)
        delimiter = ';';
      table.header_ = split_line(line, delimiter, src, line_number);
      if (table.header_.size() > kMaxColumns)
        throw InputError(src + ":" + std::to_string(line_number) + ": the header has " +
                             std::to_string(table.header_.size()) + " columns; a CSV input may have at most " +
                             std::to_string(kMaxColumns) + " (is this the right file?)",
                         src, line_number);
      for (std::size_t c = 0; c < table.header_.size(); ++c) {
        if (table.header_[c].empty())
          throw InputError(src + ":" + std::to_string(line_number) + ": column " +
                               std::to_string(c + 1) + " of the header has no name",
                           src, line_number);
        table.keys_.push_back(strip_unit(table.header_[c]));
      }
      // A hash of the names seen: the pairwise comparison was quadratic (10^5 columns: 6.6 s).
      std::unordered_map<std::string_view, std::size_t> first_column;
      first_column.reserve(table.keys_.size());
      for (std::size_t b = 0; b < table.keys_.size(); ++b) {
        const auto [it, fresh] = first_column.emplace(table.keys_[b], b);
        if (!fresh)
          throw InputError(src + ":" + std::to_string(line_number) + ": column '" + table.keys_[b] +
                               "' appears twice in the header (columns " + std::to_string(it->second + 1) +
                               " and " + std::to_string(b + 1) + ")",
                           src, line_number, table.keys_[b]);
      }
      have_header = true;
    } else {
      const std::size_t cells = table.append_row(line, delimiter, line_number);
      if (cells != table.header_.size())
        throw InputError(src + ":" + std::to_string(line_number) + ": row has " +
                             std::to_string(cells) + " cells; the header has " +
                             std::to_string(table.header_.size()),
                         src, line_number);
      table.lines_.push_back(line_number);
    }
    line_number += continued_lines;
    if (end == text.size()) break;
  }
  if (!have_header) throw InputError(src + ": file is empty; expected a header line", src);
  return table;
}

std::size_t CsvTable::append_row(std::string_view line, char delimiter, std::size_t line_number) {
  const std::size_t before = cell_ends_.size();
  if (line.find('"') == std::string_view::npos) {
    // No quotes (the common case): the trimmed pieces between delimiters, appended in place.
    std::size_t start = 0;
    while (true) {
      const std::size_t d = line.find(delimiter, start);
      cells_ += trim_view(line.substr(start, d == std::string_view::npos ? std::string_view::npos : d - start));
      cell_ends_.push_back(cells_.size());
      if (d == std::string_view::npos) break;
      start = d + 1;
    }
  } else {
    for (const std::string& cell : split_line(line, delimiter, source_, line_number)) {
      cells_ += cell;
      cell_ends_.push_back(cells_.size());
    }
  }
  return cell_ends_.size() - before;
}

CsvTable CsvTable::rows(const std::vector<std::size_t>& keep) const {
  CsvTable out;
  out.source_ = source_;
  out.header_ = header_;
  out.keys_ = keys_;
  for (std::size_t r : keep) {
    for (std::size_t c = 0; c < header_.size(); ++c) {
      out.cells_ += cell(r, c);
      out.cell_ends_.push_back(out.cells_.size());
    }
    out.lines_.push_back(lines_.at(r));
  }
  return out;
}

CsvTable CsvTable::derived(std::vector<std::string> header, const std::vector<std::size_t>& from,
                           const std::vector<std::vector<std::string>>& cells) const {
  if (from.size() != cells.size()) throw ArgumentError("CsvTable::derived: one source row per row of cells");
  CsvTable out;
  out.source_ = source_;
  out.header_ = std::move(header);
  for (const std::string& name : out.header_) {
    std::string key = strip_unit(name);
    if (std::find(out.keys_.begin(), out.keys_.end(), key) != out.keys_.end())
      throw ArgumentError("CsvTable::derived: column '" + key + "' twice");
    out.keys_.push_back(std::move(key));
  }
  for (std::size_t r = 0; r < cells.size(); ++r) {
    if (cells[r].size() != out.header_.size())
      throw ArgumentError("CsvTable::derived: row " + std::to_string(r) + " has " + std::to_string(cells[r].size()) +
                          " cells for " + std::to_string(out.header_.size()) + " columns");
    for (const std::string& c : cells[r]) {
      out.cells_ += c;
      out.cell_ends_.push_back(out.cells_.size());
    }
    out.lines_.push_back(lines_.at(from[r]));
  }
  return out;
}

std::string_view CsvTable::cell(std::size_t row, std::size_t column) const {
  if (row >= lines_.size() || column >= header_.size())
    throw std::out_of_range("CsvTable::cell(" + std::to_string(row) + ", " + std::to_string(column) +
                            ") of a " + std::to_string(lines_.size()) + " x " + std::to_string(header_.size()) +
                            " table");
  const std::size_t k = row * header_.size() + column;
  const std::size_t begin = k == 0 ? 0 : cell_ends_[k - 1];
  return std::string_view(cells_).substr(begin, cell_ends_[k] - begin);
}

std::string column_key(std::string_view name) { return strip_unit(name); }

bool CsvTable::has_column(std::string_view name) const noexcept {
  const std::string key = strip_unit(trim(name));
  return std::find(keys_.begin(), keys_.end(), key) != keys_.end();
}

std::size_t CsvTable::column_index(std::string_view name) const {
  const std::string key = strip_unit(trim(name));
  const auto it = std::find(keys_.begin(), keys_.end(), key);
  if (it == keys_.end()) {
    std::string available;
    for (const auto& h : header_) available += (available.empty() ? "" : ",") + h;
    throw InputError(source_ + ": no column '" + std::string(name) + "'; the header has: " +
                         available,
                     source_, 1, std::string(name));
  }
  return static_cast<std::size_t>(it - keys_.begin());
}

std::vector<double> CsvTable::numeric_column(std::string_view name) const {
  const std::size_t c = column_index(name);
  std::vector<double> out(row_count());
  for (std::size_t r = 0; r < out.size(); ++r) out[r] = numeric_cell(r, c);
  return out;
}

double CsvTable::numeric_cell(std::size_t r, std::size_t c) const {
  const std::string_view text = cell(r, c);
  const auto quoted = [&] { return "'" + std::string(text) + "'"; };
  const auto fail = [&](const std::string& what) {
    throw InputError(source_ + ":" + std::to_string(lines_[r]) + ": column '" + header_[c] + "'" + what, source_,
                     lines_[r], header_[c]);
  };
  if (text.empty()) fail(" is empty; expected a number");
  double v = 0.0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (*first == '+') ++first;
  const auto res = std::from_chars(first, last, v);
  if (res.ec == std::errc::result_out_of_range && res.ptr == last) {
    // Overflow is an error (below); underflow reads as the nearest double (0 or subnormal).
    v = std::strtod(std::string(first, last).c_str(), nullptr);
    if (std::isinf(v)) fail(": " + quoted() + " is not a finite number (beyond the range of a double)");
  } else if (res.ec != std::errc() || res.ptr != last) {
    fail(": " + quoted() + " is not a number");
  }
  if (!std::isfinite(v)) fail(": " + quoted() + " is not a finite number");
  return v;
}

Eigen::MatrixXd CsvTable::numeric_columns(const std::vector<std::string>& names) const {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(row_count()), static_cast<Eigen::Index>(names.size()));
  for (std::size_t j = 0; j < names.size(); ++j) {
    const auto col = numeric_column(names[j]);
    for (std::size_t i = 0; i < col.size(); ++i)
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = col[i];
  }
  return m;
}

std::string csv_cell(std::string_view cell) {
  const bool needs_quotes =
      cell.find_first_of(",;\"\r\n") != std::string_view::npos ||
      (!cell.empty() && (cell.front() == ' ' || cell.front() == '\t' || cell.back() == ' ' || cell.back() == '\t' ||
                         cell.front() == '#'));
  if (!needs_quotes) return std::string(cell);
  std::string out;
  out.reserve(cell.size() + 2);
  out += '"';
  for (const char c : cell) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

void append_csv_line(std::string& out, const std::vector<std::string>& cells) {
  if (cells.size() == 1 && cells.front().empty()) {
    out += "\"\"\n";
    return;
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (c) out += ',';
    out += csv_cell(cells[c]);
  }
  out += '\n';
}

std::vector<std::string> split_list(std::string_view text, std::string_view what) {
  std::vector<std::string> items;
  std::size_t pos = 0;
  while (true) {
    const auto end = text.find(',', pos);
    std::string item = trim(text.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos));
    if (item.empty())
      throw ArgumentError(std::string(what) + ": empty item in '" + std::string(text) +
                          "'; expected a comma-separated list such as x,y,z");
    items.push_back(std::move(item));
    if (end == std::string_view::npos) break;
    pos = end + 1;
  }
  return items;
}

std::vector<std::string> split_column_list(std::string_view text, std::string_view what) {
  std::vector<std::string> names = split_list(text, what);
  for (std::size_t i = 0; i < names.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (names[i] == names[j])
        throw ArgumentError(std::string(what) + ": column '" + names[i] + "' is named twice in '" + std::string(text) +
                            "' (items " + std::to_string(j + 1) + " and " + std::to_string(i + 1) + ")");
  return names;
}

}  // namespace errfield
