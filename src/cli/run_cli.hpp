#pragma once
// The body of the `errfield` tool as a function, so that main() and the CLI fuzzer
// (tests/fuzz/fuzz_cli.cpp) run exactly the same code.

namespace errfield::cli {

/// Exit statuses of the tool (also printed by `errfield --help`).
inline constexpr int kExitSuccess = 0;
inline constexpr int kExitFailure = 1;   ///< any other errfield::Error: the job itself failed
inline constexpr int kExitUsage = 2;     ///< InputError, ArgumentError, or a command-line parse error
inline constexpr int kExitResource = 3;  ///< ResourceError: over a memory/size budget
inline constexpr int kExitInternal = 70; ///< anything else: a bug

/// Builds the CLI11 app from the registered subcommands, parses `argv` and runs the chosen
/// command. Every exception becomes a one-line message on stderr and one of the statuses above
/// (--help and --version print and return 0). Never calls exit().
int run_cli(int argc, const char* const* argv);

/// Flushes standard output; kExitFailure with a message on stderr if what the command printed
/// could not be written (a full disk, /dev/full), else 0. run_cli ends with it.
int finish_standard_output();

}  // namespace errfield::cli
