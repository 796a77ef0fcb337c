#include "cli/cli_support.hpp"

#include <omp.h>
#include <unistd.h>

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

void OutputTable::write(const std::string& path) const {
  release_idle_threads();
  write_file_atomically(path, to_csv());
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

bool progress_wanted() {
  const char* forced = std::getenv("ERRFIELD_PROGRESS");
  if (forced && *forced) return std::string_view(forced) != "0";
  return ::isatty(STDERR_FILENO) != 0;
}

double progress_after_seconds() {
  const char* text = std::getenv("ERRFIELD_PROGRESS_AFTER");
  if (!text || !*text) return StageLog::kProgressAfter;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  return end != text && *end == '\0' && v >= 0.0 && v <= 3600.0 ? v : StageLog::kProgressAfter;
}

}  // namespace

struct StageLog::State {
  using Clock = std::chrono::steady_clock;
  std::string label;
  bool every_stage = false;  // long_job: a line at each stage's start
  double after_s = kProgressAfter;
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
        next_line = now + std::chrono::seconds(5);
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
  if (!progress_wanted()) return;
  state_ = std::make_shared<State>();
  state_->label = std::move(label);
  state_->every_stage = long_job;
  state_->after_s = progress_after_seconds();
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
