#include "cli/cli_support.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <condition_variable>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <string_view>
#include <thread>

namespace errfield::cli {

void require_standard_output() {
  std::cout.flush();
  if (std::cout && std::fflush(stdout) == 0 && !std::ferror(stdout)) return;
  const int err = errno;
  throw Error("cannot write to standard output" + (err ? std::string(": ") + std::strerror(err) : std::string()) +
              "; no output file written");
}

void release_idle_threads() {
  // The computation is done when a command writes its results; an idle OpenMP worker would
  // otherwise spin-wait (libgomp's default) through the formatting, the write and the exit,
  // on a CPU that may share a core with this thread. Measured: `errfield variogram` of 20,000
  // points (cutoff 100 in a 500 cube, 2 threads) 27.7 -> 24.5 ms wall, 34 -> 27 ms CPU (2026-11-26,
  // docs/benchmarks.md). A later parallel region starts a new team (tens of microseconds).
  omp_pause_resource_all(omp_pause_soft);
}

namespace {

// A double's shortest round-trip text is at most 24 characters ("-2.2250738585072014e-308").
constexpr std::size_t kNumberChars = 32;

bool is_number_text(const std::string& cell) { return cell.find_first_not_of("0123456789.-+eE") == std::string::npos; }

// Appends rows [begin, end) of `table` to `out` as CSV lines: one resize to a bound of their
// length, the cells written in place, then the string cut to what was written.
void append_csv_rows(const OutputTable& table, std::size_t begin, std::size_t end, std::string& out) {
  std::size_t bound = 0;
  for (const OutputTable::Column& column : table.columns) {
    if (column.numeric) {
      bound += (end - begin) * (kNumberChars + 1);
    } else {
      for (std::size_t r = begin; r < end; ++r) bound += 2 * column.text[r].size() + 3;  // quoted, quotes doubled
    }
  }
  bound += (end - begin) * 3;  // newlines, a lone empty cell's ""
  const std::size_t start = out.size();
  out.resize(start + bound);
  char* p = out.data() + start;
  const bool one_column = table.columns.size() == 1;
  for (std::size_t r = begin; r < end; ++r) {
    if (one_column) {
      const OutputTable::Column& only = table.columns.front();
      if (only.numeric ? std::isnan(only.numbers[r]) : only.text[r].empty()) {
        p = std::copy_n("\"\"\n", 3, p);  // a lone empty cell: as append_csv_line writes it
        continue;
      }
    }
    for (std::size_t c = 0; c < table.columns.size(); ++c) {
      if (c) *p++ = ',';
      const OutputTable::Column& column = table.columns[c];
      if (column.numeric) {
        const double v = column.numbers[r];
        if (!std::isnan(v)) p = std::to_chars(p, p + kNumberChars, v).ptr;  // format_number's text
        continue;
      }
      const std::string& cell = column.text[r];
      // A number's text (digits, sign, point, exponent) never needs quotes: no copy through csv_cell.
      if (is_number_text(cell)) {
        p = std::copy(cell.begin(), cell.end(), p);
      } else {
        const std::string quoted = csv_cell(cell);
        p = std::copy(quoted.begin(), quoted.end(), p);
      }
    }
    *p++ = '\n';
  }
  out.resize(static_cast<std::size_t>(p - out.data()));
}

}  // namespace

namespace {

void check_column_sizes(const OutputTable& table, std::size_t rows) {
  for (std::size_t c = 1; c < table.columns.size(); ++c)
    if (table.columns[c].size() != rows)
      throw Error("output column '" + table.header[c] + "' has " + std::to_string(table.columns[c].size()) +
                  " cells, column '" + table.header[0] + "' " + std::to_string(rows) + " (internal error)");
}

std::size_t row_count(const OutputTable& table) { return table.columns.empty() ? 0 : table.columns.front().size(); }

// Blocks of rows formatted in parallel: 100 simulation draws at 10,000 targets are a million
// numbers, whose shortest round-trip text is most of the writing's time.
constexpr std::size_t kRowsPerBlock = 512;

bool formatted_in_parallel(const OutputTable& table, std::size_t rows) {
  return rows > kRowsPerBlock && rows * table.columns.size() >= 100000;
}

}  // namespace

std::string OutputTable::to_csv() const {
  std::string out;
  append_csv_line(out, header);
  const std::size_t rows = row_count(*this);
  check_column_sizes(*this, rows);
  if (!formatted_in_parallel(*this, rows)) {
    append_csv_rows(*this, 0, rows, out);
    return out;
  }
  const std::size_t blocks = (rows + kRowsPerBlock - 1) / kRowsPerBlock;
  std::vector<std::string> parts(blocks);
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t b = 0; b < static_cast<std::ptrdiff_t>(blocks); ++b) {
    const std::size_t begin = static_cast<std::size_t>(b) * kRowsPerBlock;
    append_csv_rows(*this, begin, std::min(rows, begin + kRowsPerBlock), parts[static_cast<std::size_t>(b)]);
  }
  std::size_t bytes = out.size();
  for (const std::string& part : parts) bytes += part.size();
  out.reserve(bytes);
  for (const std::string& part : parts) out += part;
  return out;
}

void OutputTable::write_csv(std::ostream& stream) const {
  std::string head;
  append_csv_line(head, header);
  const std::size_t rows = row_count(*this);
  check_column_sizes(*this, rows);
  if (!formatted_in_parallel(*this, rows)) {
    append_csv_rows(*this, 0, rows, head);
    stream.write(head.data(), static_cast<std::streamsize>(head.size()));
    return;
  }
  stream.write(head.data(), static_cast<std::streamsize>(head.size()));
  // A batch of blocks at a time, formatted in parallel into buffers that every batch reuses, then
  // written in order: the same bytes as to_csv(), but the text in memory is one batch (~8 MB for
  // 100 draws) instead of the whole file twice (parts + joined, 40 MB at 10,000 x 100 draws).
  // Fresh memory is not free: every new page is a fault the kernel clears (20,800 faults were a
  // third of `interpolate --simulations 100`'s CPU time on this machine, 2026-11-29).
  constexpr std::size_t kBlocksPerBatch = 8;
  std::vector<std::string> parts(kBlocksPerBatch);
  for (std::size_t first = 0; first < rows; first += kBlocksPerBatch * kRowsPerBlock) {
    const std::size_t count = std::min(kBlocksPerBatch, (rows - first + kRowsPerBlock - 1) / kRowsPerBlock);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::ptrdiff_t b = 0; b < static_cast<std::ptrdiff_t>(count); ++b) {
      const std::size_t begin = first + static_cast<std::size_t>(b) * kRowsPerBlock;
      std::string& part = parts[static_cast<std::size_t>(b)];
      part.clear();
      append_csv_rows(*this, begin, std::min(rows, begin + kRowsPerBlock), part);
    }
    for (std::size_t b = 0; b < count; ++b) stream.write(parts[b].data(), static_cast<std::streamsize>(parts[b].size()));
  }
}

void OutputTable::write(const std::string& path) const {
  AtomicFileWriter writer(path);
  write_csv(writer.stream());
  release_idle_threads();
  writer.commit();
  if (!replaced.empty()) {
    std::string names;
    for (const auto& r : replaced) names += (names.empty() ? "'" : ", '") + r + "'";
    std::fprintf(stderr, "errfield: note: %s: the input's column(s) %s replaced by the computed ones\n", path.c_str(),
                 names.c_str());
  }
}

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void Progress::update(std::size_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  const double pct = total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 0.0;
  std::fprintf(stderr, "\r%s: %zu/%zu (%.0f%%)   ", label_.c_str(), done, total_, pct);
  std::fflush(stderr);
  printed_ = true;
}

void Progress::finish() {
  if (printed_) std::fprintf(stderr, "\r%*s\r", static_cast<int>(label_.size() + 40), "");
  printed_ = false;
}

namespace {

// Off (ERRFIELD_PROGRESS=0), a terminal (or ERRFIELD_PROGRESS=1 standing in for one), or a log: a
// pipe or file, which gets the "still running" lines only, and less often.
enum class ProgressMode { off, terminal, log };

ProgressMode progress_mode() {
  const char* forced = std::getenv("ERRFIELD_PROGRESS");
  if (forced && *forced) return std::string_view(forced) != "0" ? ProgressMode::terminal : ProgressMode::off;
  return ::isatty(STDERR_FILENO) != 0 ? ProgressMode::terminal : ProgressMode::log;
}

double progress_after_seconds(double fallback) {
  const char* text = std::getenv("ERRFIELD_PROGRESS_AFTER");
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  return end != text && *end == '\0' && v >= 0.0 && v <= 3600.0 ? v : fallback;
}

}  // namespace

struct StageLog::State {
  using Clock = std::chrono::steady_clock;
  std::string label;
  bool every_stage = false;  // long_job: a line at each stage's start
  double after_s = kProgressAfter;
  double every_s = kProgressAfter;  // between two lines of one stage
  Clock::time_point start = Clock::now();
  std::mutex mutex;
  std::condition_variable wake;
  std::string stage;               // the stage running ("" before the first)
  Clock::time_point stage_start;   // when it began
  Clock::time_point next_line;     // when the watcher says it again
  bool stop = false;
  std::thread watcher;

  void print(const std::string& what, Clock::time_point now) const {
    std::fprintf(stderr, "%s: %s (%.1f s)\n", label.c_str(), what.c_str(),
                 std::chrono::duration<double>(now - start).count());
    std::fflush(stderr);
  }
  void watch() {
    std::unique_lock lock(mutex);
    while (!stop) {
      if (stage.empty()) {
        wake.wait(lock);
        continue;
      }
      if (wake.wait_until(lock, next_line) == std::cv_status::timeout && !stop && Clock::now() >= next_line) {
        const auto now = Clock::now();
        print(stage + ", still running", now);
        next_line = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(every_s));
      }
    }
  }
  ~State() {
    if (!watcher.joinable()) return;
    {
      std::lock_guard lock(mutex);
      stop = true;
    }
    wake.notify_all();
    watcher.join();
  }
};

StageLog::StageLog(std::string label, bool long_job) {
  const ProgressMode mode = progress_mode();
  if (mode == ProgressMode::off) return;
  state_ = std::make_shared<State>();
  state_->label = std::move(label);
  // A log (a pipe, a file) gets only the lines of a stage that runs long: a fit of 5,000 poses ran
  // past a minute with nothing in its log (issue 47).
  state_->every_stage = long_job && mode == ProgressMode::terminal;
  const double interval = mode == ProgressMode::terminal ? kProgressAfter : kLogProgressAfter;
  state_->after_s = progress_after_seconds(interval);
  state_->every_s = interval;
  state_->watcher = std::thread([s = state_.get()] { s->watch(); });
}

void StageLog::operator()(const std::string& stage) const {
  if (!state_) return;
  State& s = *state_;
  const auto now = State::Clock::now();
  {
    std::lock_guard lock(s.mutex);
    s.stage = stage;
    s.stage_start = now;
    s.next_line = now + std::chrono::duration_cast<State::Clock::duration>(std::chrono::duration<double>(s.after_s));
    if (s.every_stage) s.print(stage, now);
  }
  s.wake.notify_all();
}

}  // namespace errfield::cli
