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
  app.set_version_flag("--version", "errfield 0.1.0");
  auto& entries = command_registry();
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.order != b.order ? a.order < b.order : a.name < b.name; });
  for (const auto& e : entries) e.add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const InputError& e) {
    std::cerr << "errfield: input error: " << e.what() << "\n";
    return 2;
  } catch (const ArgumentError& e) {
    std::cerr << "errfield: invalid argument: " << e.what() << "\n";
    return 2;
  } catch (const ResourceError& e) {
    std::cerr << "errfield: resource limit: " << e.what() << "\n";
    return 3;
  } catch (const Error& e) {
    std::cerr << "errfield: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "errfield: internal error: " << e.what() << "\n";
    return 70;
  }
  return 0;
}

}  // namespace errfield::cli
