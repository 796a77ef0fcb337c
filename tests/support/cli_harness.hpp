#pragma once
// Running the built `errfield` executable from tests (bad-input catalogue, atomic outputs,
// determinism, resource bounds): a scratch directory per test and a runner that keeps stdout,
// stderr, the exit code and any terminating signal apart.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"

namespace errfield::testing {

namespace fs = std::filesystem;

/// A fresh directory named after the running test, removed at the end.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "errfield_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
                       std::to_string(::getpid());
    std::replace(name.begin(), name.end(), '/', '_');  // parameterised tests: "Inst/Suite", "Name/0"
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const fs::path& path() const { return path_; }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  /// Writes `text` to `name` in the directory (binary: CRLF and BOM stay as given).
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return (path_ / name).string();
  }
  std::string read(const std::string& name) const { return slurp(path_ / name); }
  /// Every entry in the directory (names only), sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  fs::path path_;
};

struct CliResult {
  int exit_code = -1;  ///< -1 when killed by a signal
  int signal = 0;      ///< terminating signal, 0 if it exited
  std::string out;
  std::string err;
  /// stdout then stderr (for "the message mentions X" checks that don't care which stream).
  std::string output() const { return out + err; }
};

/// A started `errfield` process (for tests that signal it while it runs).
struct CliProcess {
  pid_t pid = -1;
  fs::path out_file, err_file;
};

/// Starts `errfield args...` in `cwd` with extra environment entries ("NAME=value"); stdout and
/// stderr go to files of their own in the temporary directory (not in `cwd`, so tests listing
/// their outputs see only what the command wrote, and parallel runs sharing a `cwd` don't mix).
/// `stdout_to`, when given, replaces the stdout file (e.g. "/dev/full" for a standard output that
/// cannot be written; the result's `out` is then empty).
inline CliProcess start_errfield(const std::vector<std::string>& args, const fs::path& cwd,
                                 const std::vector<std::string>& env = {}, const fs::path& stdout_to = {}) {
  static int counter = 0;
  const std::string stem = "errfield_cli_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  CliProcess p;
  p.out_file = fs::temp_directory_path() / (stem + ".stdout");
  p.err_file = fs::temp_directory_path() / (stem + ".stderr");
  p.pid = ::fork();
  if (p.pid == 0) {
    if (::chdir(cwd.c_str()) != 0) ::_exit(127);
    const int out = stdout_to.empty() ? ::open(p.out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644)
                                      : ::open(stdout_to.c_str(), O_WRONLY);
    const int err = ::open(p.err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(err, 2);
    for (const auto& e : env) ::putenv(const_cast<char*>(e.c_str()));
    std::vector<char*> argv{const_cast<char*>(ERRFIELD_CLI_PATH)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(ERRFIELD_CLI_PATH, argv.data());
    ::_exit(127);
  }
  return p;
}

inline CliResult wait_errfield(const CliProcess& p) {
  int status = 0;
  ::waitpid(p.pid, &status, 0);
  CliResult r;
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  r.out = ScratchDir::slurp(p.out_file);
  r.err = ScratchDir::slurp(p.err_file);
  std::error_code ec;
  fs::remove(p.out_file, ec);
  fs::remove(p.err_file, ec);
  return r;
}

/// Runs `errfield args...` in `cwd` to completion.
inline CliResult run_errfield(const std::vector<std::string>& args, const fs::path& cwd,
                              const std::vector<std::string>& env = {}) {
  return wait_errfield(start_errfield(args, cwd, env));
}

/// Runs `errfield args...` in `cwd` with its standard output on /dev/full (every write fails with
/// ENOSPC): the way to check that a command treats its console output as output.
inline CliResult run_errfield_to_full_stdout(const std::vector<std::string>& args, const fs::path& cwd) {
  return wait_errfield(start_errfield(args, cwd, {}, "/dev/full"));
}

/// Splits a command line the way a POSIX shell would for plain words, "double" and 'single'
/// quotes (no variables, globs or escapes beyond \" inside double quotes), so tests can write
/// `run_errfield_line("fit --data " + path("d.csv") + " --model \"sph(sill=1,range=2)\"")`.
inline std::vector<std::string> split_command_line(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else if (c == '"' || c == '\'') {
      in_word = true;
      for (++i; i < line.size() && line[i] != c; ++i) {
        if (c == '"' && line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '"') ++i;
        word += line[i];
      }
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

/// Runs `errfield <line>` (split by split_command_line) in `cwd` to completion.
inline CliResult run_errfield_line(const std::string& line, const fs::path& cwd = fs::current_path(),
                                   const std::vector<std::string>& env = {}) {
  return run_errfield(split_command_line(line), cwd, env);
}

/// Base fixture for CLI tests: a ScratchDir per test and shortcuts to files in it; `run` executes
/// the CLI with the scratch directory as working directory.
class CliTest : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return scratch_ / name; }
  std::string write(const std::string& name, const std::string& text) const { return scratch_.write(name, text); }
  std::string read(const std::string& name) const { return scratch_.read(name); }
  static std::string read_text(const std::string& file) { return ScratchDir::slurp(file); }
  CliResult run(const std::string& line, const std::vector<std::string>& env = {}) const {
    return run_errfield_line(line, scratch_.path(), env);
  }
  const fs::path& dir() const { return scratch_.path(); }
  /// Rewrites CSV `in` to `out` (both in the scratch directory): `edit(table, row, cells)` on every
  /// data row that `keep_row` keeps; columns for which `keep_column` is false are dropped. For
  /// tests that hand a command deliberately altered data (units, another robot, missing columns).
  void rewrite(const std::string& in, const std::string& out,
               const std::function<void(const CsvTable&, std::size_t, std::vector<std::string>&)>& edit,
               const std::function<bool(const std::string&)>& keep_column = [](const std::string&) { return true; },
               const std::function<bool(std::size_t)>& keep_row = [](std::size_t) { return true; }) const {
    const CsvTable t = CsvTable::read(path(in));
    std::string text;
    auto line = [&](const std::vector<std::string>& cells) {
      std::string l;
      bool first = true;
      for (std::size_t c = 0; c < cells.size(); ++c)
        if (keep_column(t.header()[c])) {
          l += (first ? "" : ",") + csv_cell(cells[c]);  // quoted as errfield writes
          first = false;
        }
      text += l + "\n";
    };
    line(t.header());
    for (std::size_t i = 0; i < t.row_count(); ++i) {
      if (!keep_row(i)) continue;
      std::vector<std::string> row;
      for (std::size_t c = 0; c < t.header().size(); ++c) row.emplace_back(t.cell(i, c));
      edit(t, i, row);
      line(row);
    }
    write(out, text);
  }

  ScratchDir scratch_;
};

/// "errfield a b c" for failure messages.
inline std::string command_line(const std::vector<std::string>& args) {
  std::string s = "errfield";
  for (const auto& a : args) s += " " + a;
  return s;
}

}  // namespace errfield::testing
