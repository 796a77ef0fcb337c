#pragma once
// Subcommands of the `errfield` tool register themselves here, one file each (cmd_<name>.cpp):
//
//   namespace { errfield::cli::Registration reg{"variogram", 10, &add_variogram_command}; }
//
// `order` sorts them in --help. The add function creates the CLI11 subcommand with its options and
// a callback; the callback throws errfield exceptions for bad input, which main() reports.

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace errfield::cli {

using AddCommand = void (*)(CLI::App& app);

struct CommandEntry {
  std::string name;
  int order;
  AddCommand add;
};

std::vector<CommandEntry>& command_registry();

struct Registration {
  Registration(std::string name, int order, AddCommand add) {
    command_registry().push_back({std::move(name), order, add});
  }
};

}  // namespace errfield::cli
