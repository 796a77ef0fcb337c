// Replays every fuzz seed (tests/fuzz/corpus/<target>/) and every input that once crashed a fuzz
// target (tests/fuzz/regressions/<target>/, one file per bug, named after it) through the same
// checks the fuzzers run (fuzz_checks.hpp). This is the regression test for each fuzz finding; it
// runs in the plain and in the sanitizer build. The CLI inputs are replayed through the real
// `errfield` executable in a scratch directory.

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz/fuzz_checks.hpp"
#include "fuzz/fuzz_json_checks.hpp"

namespace errfield::fuzz {
namespace fuzz_replay_test {

namespace fs = std::filesystem;

std::vector<fs::path> inputs(const std::string& target) {
  std::vector<fs::path> files;
  for (const char* kind : {"corpus", "regressions"}) {
    const fs::path dir = fs::path(ERRFIELD_SOURCE_DIR) / "tests/fuzz" / kind / target;
    if (!fs::exists(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file()) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

template <class Check>
void replay(const std::string& target, Check check) {
  const auto files = inputs(target);
  ASSERT_FALSE(files.empty()) << "no seeds for fuzz target " << target;
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    check(slurp(f));  // aborts (failing this test) on a contract violation
  }
}

TEST(FuzzReplay, Csv) { replay("csv", [](const std::string& s) { check_csv(s); }); }
TEST(FuzzReplay, VariogramModel) {
  replay("variogram_model", [](const std::string& s) { check_variogram_model(s); });
}
TEST(FuzzReplay, ModelJson) { replay("model_json", [](const std::string& s) { check_model_json(s); }); }
TEST(FuzzReplay, RobotJson) { replay("robot_json", [](const std::string& s) { check_robot_json(s); }); }
TEST(FuzzReplay, JsonInputs) { replay("json_inputs", [](const std::string& s) { check_json_inputs(s); }); }

// Runs the CLI with `args` in `dir`, output discarded; returns the wait status.
int run_cli_in(const fs::path& dir, const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(127);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(ERRFIELD_CLI_PATH, argv.data());
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST(FuzzReplay, Cli) {
  const fs::path dir = fs::temp_directory_path() / ("errfield-replay-cli-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_cli_scratch(dir);
  ::putenv(const_cast<char*>(kCliFuzzMaxCubePoints));  // as the fuzzer runs them
  for (const auto& command : kCliScratchCommands) {
    const int status = run_cli_in(dir, command);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "scratch set-up failed: " << command[1];
  }
  const auto files = inputs("cli");
  ASSERT_FALSE(files.empty());
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const auto args = split_cli_args(slurp(f));
    if (!args) continue;  // the fuzzer skips it too
    const int status = run_cli_in(dir, *args);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_NE(WEXITSTATUS(status), kCliInternalError);
    EXPECT_NE(WEXITSTATUS(status), 127) << "could not run " << ERRFIELD_CLI_PATH;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace errfield::fuzz
