#pragma once
// Small helpers shared by the subcommands: reading columns, writing result tables atomically,
// and a progress line on the terminal for long runs.

#include <chrono>
#include <memory>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <utility>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "errfield/atomic_file.hpp"
#include "errfield/thread_count.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {

/// A table to write: column names and, per column, one cell per row. A column is text (an empty
/// string is an empty cell) or numbers (NaN is an empty cell), written as shortest round-trip text
/// when the table is written. Writing it is atomic (AtomicFileWriter).
struct OutputTable {
  /// One column's cells: `text`, or `numbers` when `numeric` (computed results: 100 simulation
  /// draws at 10,000 targets are a million cells, which as strings took ~100 MB and a third of
  /// the run; as numbers they are formatted straight into the file's text).
  struct Column {
    bool numeric = false;
    std::vector<std::string> text;
    std::vector<double> numbers;
    std::size_t size() const { return numeric ? numbers.size() : text.size(); }
  };
  std::vector<std::string> header;
  std::vector<Column> columns;
  /// Input columns that a computed column of the same name replaced (e.g. `ik` run on its own
  /// output): a column twice would make the file unreadable to errfield itself.
  std::vector<std::string> replaced;

  /// Adds a computed column, or replaces the one whose name (without unit) is the same, in its
  /// place. A cell reading "inf" or "nan" is refused (Error naming column and row): errfield never
  /// writes a non-finite number; the caller leaves the cell empty and says why, or fails.
  void add_column(std::string name, std::vector<std::string> cells) {
    for (std::size_t r = 0; r < cells.size(); ++r) check_finite_cell(name, r, cells[r]);
    Column column;
    column.text = std::move(cells);
    put_column(std::move(name), std::move(column));
  }
  static void check_finite_cell(const std::string& column, std::size_t row, const std::string& cell) {
    std::string_view v = cell;
    if (!v.empty() && (v.front() == '-' || v.front() == '+')) v.remove_prefix(1);
    if (v == "inf" || v == "nan" || v == "infinity")
      throw Error("output column '" + column + "', row " + std::to_string(row + 1) + ": the computed value is " + cell +
                  " (beyond the range of a double: inputs too large or too far apart for this computation; "
                  "rescale them, e.g. other units); errfield writes no non-finite number, nothing written");
  }
  /// Adds (or replaces, as add_column) a column of numbers, each written as shortest round-trip
  /// text (format_number's); a NaN is an empty cell (no value: the caller says why), an infinity
  /// is refused as in add_column.
  void add_numbers(std::string name, std::vector<double> values) {
    for (std::size_t r = 0; r < values.size(); ++r)
      if (std::isinf(values[r])) check_finite_cell(name, r, format_number(values[r]));
    Column column;
    column.numeric = true;
    column.numbers = std::move(values);
    put_column(std::move(name), std::move(column));
  }
  /// Numbers as shortest round-trip text; a non-finite one, NaN included, is refused (as in add_column).
  void add_numeric_column(std::string name, const std::vector<double>& values) {
    for (std::size_t r = 0; r < values.size(); ++r)
      if (!std::isfinite(values[r])) check_finite_cell(name, r, format_number(values[r]));
    add_numbers(std::move(name), values);
  }
  void put_column(std::string name, std::vector<std::string> cells) {
    Column column;
    column.text = std::move(cells);
    put_column(std::move(name), std::move(column));
  }
  void put_column(std::string name, Column column) {
    const std::string key = column_key(name);
    for (std::size_t c = 0; c < header.size(); ++c)
      if (column_key(header[c]) == key) {
        replaced.push_back(header[c]);
        header[c] = std::move(name);
        columns[c] = std::move(column);
        return;
      }
    header.push_back(std::move(name));
    columns.push_back(std::move(column));
  }
  /// Copies every column of `input` (used to keep the targets' columns in an output).
  void add_all_columns(const CsvTable& input) {
    for (std::size_t c = 0; c < input.header().size(); ++c) {
      std::vector<std::string> cells(input.row_count());
      for (std::size_t r = 0; r < input.row_count(); ++r) cells[r] = input.cell(r, c);
      put_column(input.header()[c], std::move(cells));  // the input's own text, as it was
    }
  }
  /// Copies every column of `input`, rows `rows` only, in that order (a selection of the input's rows).
  void add_all_columns(const CsvTable& input, const std::vector<std::size_t>& rows) {
    for (std::size_t c = 0; c < input.header().size(); ++c) {
      std::vector<std::string> cells;
      cells.reserve(rows.size());
      for (std::size_t r : rows) cells.emplace_back(input.cell(r, c));
      put_column(input.header()[c], std::move(cells));
    }
  }
  /// The table as CSV text; every text cell goes through csv_cell (a point named "p,1" is quoted,
  /// so errfield reads its own outputs back), every number is written as format_number writes it.
  /// Written straight into one buffer, rows in blocks formatted in parallel (OpenMP; the same
  /// bytes for any thread count).
  std::string to_csv() const;
  /// The same bytes as to_csv(), written to `stream` a batch of rows at a time (bounded memory).
  void write_csv(std::ostream& stream) const;
  /// Writes atomically (through write_csv); names on stderr the input columns that computed ones replaced.
  void write(const std::string& path) const;
};

/// Flushes standard output and throws Error ("cannot write to standard output", exit 1) if what
/// was printed did not get through (`> /dev/full`, a closed pipe). A command that prints its
/// summary before committing its output file calls it between the two, so a failing run leaves
/// the previous file in place (docs/reliability.md, "Atomic outputs").
void require_standard_output();
/// Lets the OpenMP worker threads go (they are started again by the next parallel region), so
/// that they do not spin-wait while the command formats and writes its results.
void release_idle_threads();

// kMaxThreads and check_thread_count (--threads): errfield/thread_count.hpp, shared with the library and Python.

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

/// Progress of a job in stages on stderr. When stderr is a terminal (or ERRFIELD_PROGRESS=1):
/// "label: stage (12.3 s)" as the job enters each stage when `long_job` (known to be long from its
/// size), and, whatever the size, a line for a stage once it has run kProgressAfter (5 s; the
/// environment's ERRFIELD_PROGRESS_AFTER, in seconds, overrides it) and again every 5 s after,
/// from a watcher thread: a 687-pose fit ran 12-24 s silently because only 1,000 rows counted as
/// long. When stderr is a pipe or a file, only the second kind, after kLogProgressAfter (30 s, or
/// ERRFIELD_PROGRESS_AFTER) and every 30 s; ERRFIELD_PROGRESS=0 prints nothing. Copies share one
/// log (it is kept in a std::function); the watcher ends with the last copy.
class StageLog {
 public:
  static constexpr double kProgressAfter = 5.0;
  static constexpr double kLogProgressAfter = 30.0;
  StageLog(std::string label, bool long_job);
  void operator()(const std::string& stage) const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

/// Refuses, before any work, two output options naming one file in any spelling (`--out c.json
/// --report ./c.json`, a symlink): AtomicFileSet::commit would refuse them too, but only after
/// the job ran. `outputs` are (option, path) pairs; empty paths are options not given.
inline void refuse_same_output(std::initializer_list<std::pair<const char*, const std::string*>> outputs) {
  for (auto i = outputs.begin(); i != outputs.end(); ++i)
    for (auto j = outputs.begin(); j != i; ++j)
      if (!i->second->empty() && !j->second->empty() && same_output_file(*i->second, *j->second))
        throw ArgumentError(std::string(i->first) + " " + *i->second + " and " + j->first + " " + *j->second +
                            ": the same output file is given twice");
}

/// Prints `text` (the command's report) to standard output and only then commits `outputs`: when
/// standard output cannot be written (a full disk, `> /dev/full`) the job fails (Error, exit 1)
/// before any file is replaced - all or nothing (`plan --out X > /dev/full` replaced X, then
/// exited 1). The text may say "written to X": if the commit fails after it, the exit status and
/// the error message say so.
inline void commit_after_standard_output(AtomicFileSet& outputs, const std::string& text) {
  std::cout << text;
  require_standard_output();
  outputs.commit();
}

/// CLI11 check for an option read into an unsigned integer (--neighbors, --seed): CLI11 would
/// wrap "-3" to 2^64 - 3. CLI11 puts the option's name in front of the message.
inline const CLI::Validator kUnsignedInteger(
    [](std::string& s) -> std::string {
      const auto first = s.find_first_not_of(" \t");
      if (first != std::string::npos && s[first] == '-') return "'" + s + "' is negative; expected an integer >= 0";
      return {};
    },
    "UINT");

/// Runs `f()` (typically `options.validate()` of a library struct filled from the command line);
/// an ArgumentError naming the library's field (`IkOptions::max_iterations`) is re-thrown naming
/// the command-line option that set it (`--max-iterations`): a user can act only on the option.
/// A ResourceError is renamed the same way (its advice names what to change).
template <class F>
void naming_options(F f, std::initializer_list<std::pair<const char*, const char*>> internal_to_option) {
  bool renamed = false;
  auto rename = [&](std::string message) {
    for (const auto& [internal, option] : internal_to_option)
      for (auto pos = message.find(internal); pos != std::string::npos; pos = message.find(internal, pos)) {
        message.replace(pos, std::char_traits<char>::length(internal), option);
        pos += std::char_traits<char>::length(option);
        renamed = true;
      }
    return message;
  };
  try {
    f();
  } catch (const ArgumentError& e) {
    std::string message = rename(e.what());
    if (!renamed) throw;
    throw ArgumentError(message);
  } catch (const ResourceError& e) {
    std::string message = rename(e.what());
    if (!renamed) throw;
    throw ResourceError(message);
  }
}

}  // namespace errfield::cli
