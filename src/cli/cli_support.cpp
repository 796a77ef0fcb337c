#include "cli/cli_support.hpp"

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

void OutputTable::write(const std::string& path) const {
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
