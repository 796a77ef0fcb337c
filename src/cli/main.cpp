// Entry point of the `errfield` command-line tool; the body is run_cli() (cli/run_cli.cpp).

#include "cli/run_cli.hpp"

int main(int argc, char** argv) { return errfield::cli::run_cli(argc, argv); }
