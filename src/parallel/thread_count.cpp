#include "errfield/thread_count.hpp"

#include <thread>

#include "errfield/error.hpp"

namespace errfield {

void check_thread_count(const std::string& what, int threads) {
  if (threads < 0)
    throw ArgumentError(what + " is " + std::to_string(threads) + "; expected 0 (OpenMP's default) or a count >= 1");
  if (threads > kMaxThreads)
    throw ResourceError(what + " " + std::to_string(threads) + ": at most " + std::to_string(kMaxThreads) +
                        " threads per job (this machine has " + std::to_string(std::thread::hardware_concurrency()) +
                        " hardware threads); use 0 for OpenMP's default");
}

}  // namespace errfield
