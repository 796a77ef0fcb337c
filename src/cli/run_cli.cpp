#include "cli/run_cli.hpp"

#include <algorithm>
#include <iostream>

#include "cli/command_registry.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {

std::vector<CommandEntry>& command_registry() {
  static std::vector<CommandEntry> entries;
  return entries;
}

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
  } catch (const Error& e) {
    std::cerr << "errfield: error: " << e.what() << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "errfield: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
  return 0;
}

}  // namespace errfield::cli
