#pragma once
/// The one limit on a requested OpenMP thread count, shared by every Options::validate(), the CLI
/// (`--threads`) and the Python module (`threads=`), so that all three refuse the same values.
///
/// Why a limit: each thread costs a stack and a workspace, and libgomp aborts the process ("Out of
/// memory allocating ... bytes") when asked for 10^9 of them, before any errfield code can report it.

#include <string>

namespace errfield {

/// Most threads a job may ask for (far above any machine errfield runs on; 0 = OpenMP's default).
inline constexpr int kMaxThreads = 1024;

/// Checks a thread count before a parallel region: negative is ArgumentError, more than kMaxThreads
/// ResourceError; both messages start with `what` (an option or parameter name, e.g. "--threads").
void check_thread_count(const std::string& what, int threads);

}  // namespace errfield
