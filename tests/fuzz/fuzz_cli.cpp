// libFuzzer target: the CLI's argument handling, run_cli(argc, argv), with every subcommand
// compiled in. Input format and safety rules: split_cli_args in fuzz_checks.hpp (commands run in a
// fresh scratch directory and can only name files there; plan/simulate sizes are capped by
// ERRFIELD_MAX_CUBE_POINTS; `reproduce` only with inputs that stop before the experiments).
// Contract checked: any argument list ends in an exit code — never an uncaught exception, exit(),
// a crash or a sanitizer report — and never in the "internal error" code 70.

#include <signal.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string_view>
#include <vector>

#include "cli/run_cli.hpp"
#include "fuzz/fuzz_checks.hpp"

namespace {

std::filesystem::path g_scratch;

void remove_scratch() {
  std::error_code ec;
  std::filesystem::remove_all(g_scratch, ec);
}

// The scratch commands run at the first input, not in LLVMFuzzerInitialize. libFuzzer installs its
// signal handlers (SIGALRM: -timeout and -max_total_time; SIGABRT, SIGINT, SIGTERM, SIGUSR1/2,
// SIGXFSZ: its crash report and the input's artifact) only after LLVMFuzzerInitialize, and leaves
// alone a signal that already has a plain handler. The CLI's first output installs its cleanup
// handler (src/io/atomic_file.cpp) on every such signal still at its default; run from
// LLVMFuzzerInitialize, it took them all: libFuzzer's interval timer (every -timeout/2 + 1 s) then
// ended the process with SIGALRM after ~11 s ("Alarm clock", exit 142, no report, no final
// stats), and an abort() from a contract check would have left no artifact. Run from here, the CLI
// finds libFuzzer's handlers in place and keeps them (its rule for a handler the caller set).
void make_scratch_outputs_once() {
  static const bool done = [] {
    // No CLI output may come before this point: SIGALRM is libFuzzer's (an SA_SIGINFO handler),
    // or at its default with -timeout=0, never the CLI's plain handler. Fail loudly, not at the
    // next timer tick.
    struct sigaction alarm {};
    ERRFIELD_FUZZ_CHECK(::sigaction(SIGALRM, nullptr, &alarm) == 0);
    ERRFIELD_FUZZ_CHECK((alarm.sa_flags & SA_SIGINFO) || alarm.sa_handler == SIG_DFL);
    for (const auto& command : errfield::fuzz::kCliScratchCommands) {
      std::vector<const char*> argv;
      for (const auto& a : command) argv.push_back(a.c_str());
      if (errfield::cli::run_cli(static_cast<int>(argv.size()), argv.data()) != 0) std::abort();
    }
    return true;
  }();
  (void)done;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char tmpl[] = "/tmp/errfield-fuzz-cli-XXXXXX";
  if (!::mkdtemp(tmpl)) std::abort();
  g_scratch = tmpl;
  std::filesystem::current_path(g_scratch);
  std::atexit(remove_scratch);
  errfield::fuzz::write_cli_scratch(g_scratch);
  ::putenv(const_cast<char*>(errfield::fuzz::kCliFuzzMaxCubePoints));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto args =
      errfield::fuzz::split_cli_args(std::string_view(reinterpret_cast<const char*>(data), size));
  if (!args) return 0;
  make_scratch_outputs_once();
  std::vector<const char*> argv;
  for (const auto& a : *args) argv.push_back(a.c_str());
  const int code = errfield::cli::run_cli(static_cast<int>(argv.size()), argv.data());
  ERRFIELD_FUZZ_CHECK(code != errfield::fuzz::kCliInternalError);
  return 0;
}
