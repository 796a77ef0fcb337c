#pragma once
/// Writing output files so that a reader never sees a half-written one: the content goes to a
/// temporary file in the same directory, which is renamed over the target only on `commit()`.
/// If the writer is destroyed without commit (an exception, an early return) the temporary file
/// is removed and any previous file at the target is left untouched. A signal that ends the
/// process (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGUSR1, SIGABRT, ...) while a writer is
/// open removes its temporary file too.
///
/// A target that is a symlink is followed: the file it names is replaced, the link stays. A target
/// that is a character device or a FIFO (/dev/null, a named pipe) is written through, never
/// replaced by a regular file; such a write is not atomic. A directory, block device or socket
/// is refused. The temporary's name is shortened as needed to stay within NAME_MAX.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace errfield {

class AtomicFileWriter {
 public:
  /// Opens a temporary file next to `target`. Throws Error if it cannot be created.
  explicit AtomicFileWriter(std::filesystem::path target);
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  std::ostream& stream() { return through_ ? static_cast<std::ostream&>(buffer_) : out_; }
  /// Flushes and closes the temporary file without renaming it (commit() then only renames).
  /// Throws Error on an I/O failure (disk full); the target is then unchanged. Optional.
  void finish_writing();
  /// Flushes, closes and renames onto the target. Throws Error on any I/O failure (the target is
  /// then unchanged).
  void commit();
  const std::filesystem::path& target() const noexcept { return target_; }
  /// True when the target is a device or FIFO, written only at commit() (see above).
  bool writes_through() const noexcept { return through_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path final_;  // target_ with symlinks followed: what the rename replaces
  std::filesystem::path temporary_;
  std::ofstream out_;
  std::ostringstream buffer_;  // the content for a write-through target
  bool through_ = false;
  bool committed_ = false;
  bool finished_ = false;
  int slot_ = -1;  // entry in the signal-cleanup table
};

/// Writes `content` to `target` atomically (see AtomicFileWriter).
void write_file_atomically(const std::filesystem::path& target, std::string_view content);

/// True when writing `a` and `b` would write one regular file: the same inode when both exist,
/// else the same resolved path (`c.json`, `./c.json`, `d/../c.json`, a symlink to it).
bool same_output_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// The several output files of one command, replaced all or none: commit() writes every file to
/// its temporary first (an unwritable directory or a full disk throws before any target is
/// touched), then renames them one after the other. Use it instead of consecutive
/// write_file_atomically calls, which leave a mix of new and old files when a later one fails.
/// Before writing, commit() refuses a target that is a directory and the same file named twice
/// (ArgumentError; see same_output_file). Signals that end the process are held back during the
/// renames (and act right after), so a signal never leaves new and old files mixed. Device and
/// FIFO targets are written before the renames: one that fails (/dev/full) leaves every regular
/// target untouched. (A rename can still fail individually, e.g. on a target that became a
/// directory after the check; the files renamed before stay replaced, and a device already has its bytes.)
class AtomicFileSet {
 public:
  /// Queues `content` for `target`; nothing is written until commit().
  void add(std::filesystem::path target, std::string content);
  /// Writes all temporaries, then renames them in the order added. Throws Error naming the file.
  void commit();
  std::size_t size() const noexcept { return files_.size(); }

 private:
  std::vector<std::pair<std::filesystem::path, std::string>> files_;
};

}  // namespace errfield
