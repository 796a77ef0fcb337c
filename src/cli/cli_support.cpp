#include "cli/cli_support.hpp"

#include <omp.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

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

StageLog::StageLog(std::string label, bool long_job)
    : label_(std::move(label)),
      enabled_(long_job && ::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()) {}

void StageLog::operator()(const std::string& stage) const {
  if (!enabled_) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s: %s (%.1f s)\n", label_.c_str(), stage.c_str(), s);
  std::fflush(stderr);
}

}  // namespace errfield::cli
