#pragma once
// The body of the `errfield` tool as a function, so that main() and the CLI fuzzer
// (tests/fuzz/fuzz_cli.cpp) run exactly the same code.

namespace errfield::cli {

/// Builds the CLI11 app from the registered subcommands, parses `argv` and runs the chosen
/// command. Every exception becomes a one-line message on stderr and an exit code: 0 success,
/// 1 other errfield error, 2 bad input or argument (InputError/ArgumentError), 3 resource limit
/// (ResourceError), 70 internal error; CLI11's own codes for usage errors (--help prints and
/// returns 0). Never calls exit().
int run_cli(int argc, const char* const* argv);

}  // namespace errfield::cli
