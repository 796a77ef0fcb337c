#include "errfield/atomic_file.hpp"

#include <pthread.h>
#include <signal.h>

#include <csignal>
#include <memory>
#include <cstdio>
#include <mutex>
#include <random>
#include <set>
#include <unistd.h>

#include "errfield/error.hpp"

namespace errfield {
namespace {

// Temporary files currently open, so that SIGINT/SIGTERM can remove them before the process dies.
// A fixed-size table of C strings: the signal handler may only call async-signal-safe functions.
constexpr int kMaxPending = 64;
char g_pending[kMaxPending][4096];
volatile std::sig_atomic_t g_pending_used[kMaxPending];
std::mutex g_pending_mutex;
std::once_flag g_handlers_installed;

extern "C" void remove_pending_and_reraise(int signal_number) {
  for (int i = 0; i < kMaxPending; ++i)
    if (g_pending_used[i]) ::unlink(g_pending[i]);
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

int register_pending(const std::string& path) {
  std::call_once(g_handlers_installed, [] {
    std::signal(SIGINT, remove_pending_and_reraise);
    std::signal(SIGTERM, remove_pending_and_reraise);
  });
  std::lock_guard lock(g_pending_mutex);
  for (int i = 0; i < kMaxPending; ++i) {
    if (!g_pending_used[i] && path.size() < sizeof g_pending[i]) {
      std::snprintf(g_pending[i], sizeof g_pending[i], "%s", path.c_str());
      g_pending_used[i] = 1;
      return i;
    }
  }
  return -1;  // table full: the file is still written atomically, only not cleaned on a signal
}

void unregister_pending(int slot) {
  if (slot < 0) return;
  std::lock_guard lock(g_pending_mutex);
  g_pending_used[slot] = 0;
}

}  // namespace

AtomicFileWriter::AtomicFileWriter(std::filesystem::path target) : target_(std::move(target)) {
  std::random_device rd;
  const auto dir = target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
  std::string name = ".";
  name.append(target_.filename().string());
  name.append(".tmp");
  name.append(std::to_string(::getpid()));
  name.push_back('_');
  name.append(std::to_string(rd() % 1000000));
  temporary_ = dir / name;
  // Registered before the file exists: a SIGINT between creating and registering it would
  // otherwise leave the temporary behind (found by tests/reliability/atomic_output_test.cpp).
  slot_ = register_pending(temporary_.string());
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) {
    unregister_pending(slot_);
    slot_ = -1;
    throw Error(target_.string() + ": cannot create output file (temporary " + temporary_.string() +
                ")");
  }
}

AtomicFileWriter::~AtomicFileWriter() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
  unregister_pending(slot_);
}

void AtomicFileWriter::finish_writing() {
  if (finished_) return;
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok || out_.fail()) throw Error(target_.string() + ": write failed (disk full?)");
  finished_ = true;
}

void AtomicFileWriter::commit() {
  finish_writing();
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) throw Error(target_.string() + ": cannot replace file: " + ec.message());
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& target, std::string_view content) {
  AtomicFileWriter writer(target);
  writer.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
  writer.commit();
}

void AtomicFileSet::add(std::filesystem::path target, std::string content) {
  files_.emplace_back(std::move(target), std::move(content));
}

void AtomicFileSet::commit() {
  // Checks that would otherwise fail half-way through the renames: the same file named twice
  // (the second would silently replace the first) and a target that is a directory.
  for (std::size_t i = 0; i < files_.size(); ++i) {
    std::error_code ec;
    const auto canonical = std::filesystem::weakly_canonical(files_[i].first, ec);
    for (std::size_t j = 0; j < i && !ec; ++j) {
      std::error_code ec2;
      if (std::filesystem::weakly_canonical(files_[j].first, ec2) == canonical && !ec2)
        throw Error(files_[i].first.string() + ": the same output file is given twice (also as " +
                    files_[j].first.string() + ")");
    }
    if (std::filesystem::is_directory(files_[i].first, ec))
      throw Error(files_[i].first.string() + ": cannot replace file: it is a directory");
  }
  std::vector<std::unique_ptr<AtomicFileWriter>> writers;
  writers.reserve(files_.size());
  for (const auto& [target, content] : files_) {
    writers.push_back(std::make_unique<AtomicFileWriter>(target));
    writers.back()->stream().write(content.data(), static_cast<std::streamsize>(content.size()));
    writers.back()->finish_writing();
  }
  // SIGINT/SIGTERM wait until every rename is done: a signal between two renames would leave new
  // and old files mixed. They are delivered (and end the process) right after.
  sigset_t block, previous;
  sigemptyset(&block);
  sigaddset(&block, SIGINT);
  sigaddset(&block, SIGTERM);
  ::pthread_sigmask(SIG_BLOCK, &block, &previous);
  try {
    for (auto& w : writers) w->commit();
  } catch (...) {
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    throw;
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  files_.clear();
}

}  // namespace errfield
