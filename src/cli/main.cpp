// Entry point of the `errfield` command-line tool; the body is run_cli() (cli/run_cli.cpp).

#include <malloc.h>

#include "cli/run_cli.hpp"

int main(int argc, char** argv) {
  // Memory a command frees stays in the process for its next allocations. glibc's defaults give
  // blocks of 128 kB and more straight back to the kernel (mmap/munmap, trimming the heap's top),
  // so a buffer freed and allocated again costs fresh pages: a fault and the kernel clearing each
  // 4 kB page. On this machine (a VM) that cost dominated: `interpolate --simulations 100` on
  // 10,000 targets had 20,800 page faults, clear_page a quarter of its CPU time (perf, 2026-11-29).
  // A command is one short job; its peak memory is unchanged, only not returned before exit.
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);  // glibc's largest allowed value
  mallopt(M_TRIM_THRESHOLD, 512 * 1024 * 1024);
  mallopt(M_TOP_PAD, 16 * 1024 * 1024);
  return errfield::cli::run_cli(argc, argv);
}
