#include "errfield/atomic_file.hpp"

#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <memory>
#include <mutex>
#include <random>

#include "errfield/error.hpp"

namespace errfield {
namespace {

namespace fs = std::filesystem;

// Signals whose default action ends the process: each must remove the open temporaries first, or
// an interrupted write leaves a partial `.name.tmp...` file (SIGHUP from a closed terminal, SIGPIPE
// from `errfield ... | head`, SIGQUIT, SIGUSR1 from a job controller, SIGABRT from a failed
// allocation, ...). SIGSEGV/SIGBUS are left to the sanitizers and the kernel.
constexpr int kCleanupSignals[] = {SIGHUP,  SIGINT,  SIGQUIT, SIGTERM, SIGPIPE,   SIGUSR1, SIGUSR2,
                                   SIGALRM, SIGXCPU, SIGXFSZ, SIGABRT, SIGVTALRM};

// Temporary files currently open, so that a signal can remove them before the process dies.
// A fixed-size table of C strings: the signal handler may only call async-signal-safe functions.
constexpr int kMaxPending = 64;
char g_pending[kMaxPending][PATH_MAX];
volatile std::sig_atomic_t g_pending_used[kMaxPending];
std::mutex g_pending_mutex;
std::once_flag g_handlers_installed;

sigset_t cleanup_signal_set() {
  sigset_t set;
  sigemptyset(&set);
  for (int s : kCleanupSignals) sigaddset(&set, s);
  return set;
}

extern "C" void remove_pending_and_reraise(int signal_number) {
  for (int i = 0; i < kMaxPending; ++i)
    if (g_pending_used[i]) ::unlink(g_pending[i]);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(signal_number, &dfl, nullptr);
  // The signal is blocked while this handler runs; it is delivered (with the default action) as
  // soon as the handler returns.
  ::raise(signal_number);
}

void install_handlers() {
  struct sigaction sa {};
  sa.sa_handler = remove_pending_and_reraise;
  sa.sa_mask = cleanup_signal_set();  // a second signal must not cut the cleanup short
  for (int s : kCleanupSignals) {
    struct sigaction old {};
    // A signal the caller ignores (nohup's SIGHUP, a shell's SIGPIPE) or handles stays that way.
    if (::sigaction(s, nullptr, &old) == 0 && old.sa_handler == SIG_DFL && !(old.sa_flags & SA_SIGINFO))
      ::sigaction(s, &sa, nullptr);
  }
}

int register_pending(const std::string& path) {
  std::call_once(g_handlers_installed, install_handlers);
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

// Where the bytes for `target` really go. An existing name is followed through symlinks to the
// file it names (the link stays a link); a dangling symlink to the file it would create.
// `write_through`: the target is a character device or FIFO (/dev/null, /dev/stdout on a pipe, a
// named pipe): it is opened and written, never replaced by a regular file.
struct ResolvedTarget {
  fs::path path;
  bool write_through = false;
};

ResolvedTarget resolve_target(const fs::path& target) {
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw Error(target.string() + ": cannot replace file: it is a directory");
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return {target, true};
    if (!S_ISREG(st.st_mode))
      throw Error(target.string() + ": refusing to write: it is " +
                  (S_ISBLK(st.st_mode) ? "a block device" : S_ISSOCK(st.st_mode) ? "a socket" : "not a regular file"));
    std::error_code ec;
    const fs::path real = fs::canonical(target, ec);
    return {ec ? target : real, false};
  }
  // Not there (yet): follow a dangling symlink chain to the name it would create.
  fs::path p = target;
  for (int hops = 0; hops < 40; ++hops) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return {p, false};
    const fs::path next = fs::read_symlink(p, ec);
    if (ec) return {p, false};
    p = next.is_absolute() ? next : p.parent_path() / next;
  }
  throw Error(target.string() + ": cannot write: too many levels of symbolic links");
}

// ".<name>.tmp<pid>_<n>", with <name> shortened so that the whole stays within NAME_MAX: a valid
// 250-byte output name must not fail for its temporary's sake. Cut at a UTF-8 character boundary.
std::string temporary_name(const std::string& name) {
  std::random_device rd;
  const std::string suffix = ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(rd() % 1000000);
  std::size_t keep = name.size();
  const std::size_t room = NAME_MAX - 1 - suffix.size();
  if (keep > room) {
    keep = room;
    while (keep > 0 && (static_cast<unsigned char>(name[keep]) & 0xC0) == 0x80) --keep;
  }
  std::string out(1, '.');
  out.append(name, 0, keep);
  out.append(suffix);
  return out;
}

}  // namespace

AtomicFileWriter::AtomicFileWriter(std::filesystem::path target) : target_(std::move(target)) {
  const ResolvedTarget resolved = resolve_target(target_);
  if (resolved.write_through) {
    through_ = true;  // written at commit(); see resolve_target
    return;
  }
  const auto& real = resolved.path;
  const auto dir = real.has_parent_path() ? real.parent_path() : fs::path(".");
  final_ = real;
  temporary_ = dir / temporary_name(real.filename().string());
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
  if (!committed_ && !through_) {
    out_.close();
    std::error_code ec;
    fs::remove(temporary_, ec);
  }
  unregister_pending(slot_);
}

void AtomicFileWriter::finish_writing() {
  if (finished_) return;
  if (through_) {
    finished_ = true;  // the bytes are in buffer_ until commit()
    return;
  }
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok || out_.fail()) throw Error(target_.string() + ": write failed (disk full?)");
  finished_ = true;
}

void AtomicFileWriter::commit() {
  finish_writing();
  if (through_) {
    std::ofstream device(target_, std::ios::binary);
    if (!device) throw Error(target_.string() + ": cannot open for writing");
    const std::string bytes = buffer_.str();
    device.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    device.flush();
    if (!device) throw Error(target_.string() + ": write failed (device full or closed?)");
    committed_ = true;
    return;
  }
  std::error_code ec;
  fs::rename(temporary_, final_, ec);
  if (ec) throw Error(target_.string() + ": cannot replace file: " + ec.message());
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& target, std::string_view content) {
  AtomicFileWriter writer(target);
  writer.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
  writer.commit();
}

bool same_output_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  struct stat sa {}, sb {};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0;
  const bool b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && S_ISREG(sa.st_mode);
  if (a_exists != b_exists) return false;
  // Neither exists yet: compare where they would be created (c.json, ./c.json, d/../c.json and a
  // dangling symlink to c.json are one file).
  std::error_code ec1, ec2;
  const fs::path ra = fs::weakly_canonical(fs::absolute(resolve_target(a).path, ec1), ec1);
  const fs::path rb = fs::weakly_canonical(fs::absolute(resolve_target(b).path, ec2), ec2);
  return !ec1 && !ec2 && ra == rb;
}

void AtomicFileSet::add(std::filesystem::path target, std::string content) {
  files_.emplace_back(std::move(target), std::move(content));
}

void AtomicFileSet::commit() {
  // Checks that would otherwise fail half-way through the renames: the same file named twice
  // (the second would silently replace the first) and a target that is a directory.
  for (std::size_t i = 0; i < files_.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j)
      if (same_output_file(files_[i].first, files_[j].first))
        throw ArgumentError(files_[i].first.string() + ": the same output file is given twice (also as " +
                            files_[j].first.string() + ")");
    resolve_target(files_[i].first);  // throws for a directory, a block device, a socket
  }
  std::vector<std::unique_ptr<AtomicFileWriter>> writers;
  writers.reserve(files_.size());
  for (const auto& [target, content] : files_) {
    writers.push_back(std::make_unique<AtomicFileWriter>(target));
    writers.back()->stream().write(content.data(), static_cast<std::streamsize>(content.size()));
    writers.back()->finish_writing();
  }
  // Devices and FIFOs before any rename, with signals open: a write that fails there (/dev/full,
  // a closed pipe) must leave every regular target untouched (all or none), and opening a FIFO
  // waits for its reader, which a user must be able to interrupt (the temporaries are then removed).
  for (auto& w : writers)
    if (w->writes_through()) w->commit();
  // Every signal that would end the process waits until every rename is done: one between two
  // renames would leave new and old files mixed. It is delivered (and ends the process) right after.
  const sigset_t block = cleanup_signal_set();
  sigset_t previous;
  ::pthread_sigmask(SIG_BLOCK, &block, &previous);
  try {
    for (auto& w : writers)
      if (!w->writes_through()) w->commit();
  } catch (...) {
    ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    throw;
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  files_.clear();
}

}  // namespace errfield
