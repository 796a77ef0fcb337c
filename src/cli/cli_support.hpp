#pragma once
// Small helpers shared by the subcommands: reading columns, writing result tables atomically,
// and a progress line on the terminal for long runs.

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/atomic_file.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {

/// A table to write: column names and, per column, one cell per row (an empty string is an
/// empty cell). Writing it is atomic (AtomicFileWriter).
struct OutputTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> columns;

  void add_column(std::string name, std::vector<std::string> cells) {
    header.push_back(std::move(name));
    columns.push_back(std::move(cells));
  }
  void add_numeric_column(std::string name, const std::vector<double>& values) {
    std::vector<std::string> cells;
    cells.reserve(values.size());
    for (double v : values) cells.push_back(format_number(v));
    add_column(std::move(name), std::move(cells));
  }
  /// Copies every column of `input` (used to keep the targets' columns in an output).
  void add_all_columns(const CsvTable& input) {
    for (std::size_t c = 0; c < input.header().size(); ++c) {
      std::vector<std::string> cells(input.row_count());
      for (std::size_t r = 0; r < input.row_count(); ++r) cells[r] = input.row(r)[c];
      add_column(input.header()[c], std::move(cells));
    }
  }
  std::string to_csv() const {
    std::string out;
    for (std::size_t c = 0; c < header.size(); ++c) out += (c ? "," : "") + header[c];
    out += "\n";
    const std::size_t rows = columns.empty() ? 0 : columns.front().size();
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c) out += ",";
        out += columns[c][r];
      }
      out += "\n";
    }
    return out;
  }
  void write(const std::string& path) const { write_file_atomically(path, to_csv()); }
};

/// Prints "label: i/n (p%)" to stderr at most every 0.2 s, only when stderr is a terminal and the
/// job has run for more than a second; finish() clears the line.
class Progress {
 public:
  Progress(std::string label, std::size_t total);
  void update(std::size_t done);
  void finish();

 private:
  std::string label_;
  std::size_t total_;
  bool enabled_;
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

/// Runs `f()` (a library step on the data of `file`); an InputError that names no file (e.g.
/// "calibration: 3 measured positions ...") is re-thrown with "file: " in front and file() set.
template <class F>
auto with_source(const std::string& file, F f) {
  try {
    return f();
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    throw InputError(file + ": " + e.what(), file, e.row(), e.column());
  }
}

/// Prints "label: stage (12.3 s)" lines to stderr as a long job enters each stage, only when
/// stderr is a terminal and `long_job` (logs and tests see nothing).
class StageLog {
 public:
  StageLog(std::string label, bool long_job);
  void operator()(const std::string& stage) const;

 private:
  std::string label_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace errfield::cli
