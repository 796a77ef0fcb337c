#include "cli/run_cli.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {

std::vector<CommandEntry>& command_registry() {
  static std::vector<CommandEntry> entries;
  return entries;
}

namespace {

/// Every option read into an unsigned integer refuses a negative value (kUnsignedInteger): CLI11
/// 2.1 reads "-1" as 2^64 - 1 (`plan --count -1`, `--seed -1` wrapped). Done here, over the whole
/// command tree, so that no option (nor one added later) can miss it.
void refuse_negative_unsigned_options(CLI::App& app) {
  for (CLI::Option* option : app.get_options())
    if (option->get_type_name() == "UINT") option->check(kUnsignedInteger);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) refuse_negative_unsigned_options(*sub);
}

}  // namespace

int run_cli(int argc, const char* const* argv) {
  CLI::App app{
      "errfield — spatially correlated error fields: variograms, IDW and kriging, and robot "
      "error compensation.\n"
      "Run 'errfield <command> --help' for a command's options and an example."};
  app.require_subcommand(1);
  app.footer(
      "Exit status: 0 success; 1 the job failed (a singular system, an unreachable target, an output\n"
      "that cannot be written); 2 bad input or usage (the message names the file:line, column or\n"
      "option); 3 the job would exceed a resource budget (the message names the option or back end to\n"
      "change); 70 internal error (a bug: please report it with the command line).");
  app.set_version_flag("--version", "errfield 0.1.0");
  auto& entries = command_registry();
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.order != b.order ? a.order < b.order : a.name < b.name; });
  for (const auto& e : entries) e.add(app);
  refuse_negative_unsigned_options(app);
  // CLI11 would answer a mistyped command with "A subcommand is required"; name it instead.
  if (argc > 1 && argv[1][0] != '-' &&
      std::none_of(entries.begin(), entries.end(), [&](const auto& e) { return e.name == argv[1]; })) {
    std::string names;
    for (const auto& e : entries) names += (names.empty() ? "" : ", ") + e.name;
    std::cerr << "errfield: unknown command '" << argv[1] << "'; the commands are: " << names
              << "\nRun 'errfield --help' for what each does.\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 has a code per kind of parse error (105, 106, 109, ...); scripts get one: --help and
    // --version succeed, every other command-line mistake is a usage error like a bad value.
    return app.exit(e) == 0 ? 0 : kExitUsage;
  } catch (const InputError& e) {
    std::cerr << "errfield: input error: " << e.what() << "\n";
    return kExitUsage;
  } catch (const ArgumentError& e) {
    std::cerr << "errfield: invalid argument: " << e.what() << "\n";
    return kExitUsage;
  } catch (const ResourceError& e) {
    std::cerr << "errfield: resource limit: " << e.what() << "\n";
    return kExitResource;
  } catch (const std::bad_alloc&) {
    // A job no budget foresaw: still a resource limit, not a bug (and no message from the runtime).
    std::cerr << "errfield: resource limit: out of memory: the job needs more memory than this process can get; "
                 "make it smaller (fewer samples, targets, neighbours or runs) or give it more memory\n";
    return kExitResource;
  } catch (const Error& e) {
    std::cerr << "errfield: error: " << e.what() << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "errfield: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
  return finish_standard_output();
}

int finish_standard_output() {
  // Results printed to standard output count as output: a full disk or a closed pipe there must
  // not end in "success" (`errfield variogram ... > /dev/full` did).
  std::cout.flush();
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
  if (!failed) return 0;
  const int err = errno;
  std::cerr << "errfield: error: cannot write to standard output" << (err ? std::string(": ") + std::strerror(err) : "")
            << "\n";
  return kExitFailure;
}

}  // namespace errfield::cli
