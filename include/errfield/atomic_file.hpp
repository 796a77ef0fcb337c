#pragma once
/// Writing output files so that a reader never sees a half-written one: the content goes to a
/// temporary file in the same directory, which is renamed over the target only on `commit()`.
/// If the writer is destroyed without commit (an exception, an early return) the temporary file
/// is removed and any previous file at the target is left untouched. A SIGINT/SIGTERM while a
/// writer is open removes its temporary file too.

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace errfield {

class AtomicFileWriter {
 public:
  /// Opens a temporary file next to `target`. Throws Error if it cannot be created.
  explicit AtomicFileWriter(std::filesystem::path target);
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  std::ostream& stream() { return out_; }
  /// Flushes, closes and renames onto the target. Throws Error on any I/O failure (the target is
  /// then unchanged).
  void commit();
  const std::filesystem::path& target() const noexcept { return target_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::ofstream out_;
  bool committed_ = false;
  int slot_ = -1;  // entry in the signal-cleanup table
};

/// Writes `content` to `target` atomically (see AtomicFileWriter).
void write_file_atomically(const std::filesystem::path& target, std::string_view content);

}  // namespace errfield
