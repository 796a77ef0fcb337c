// libFuzzer target: see check_robot_json in fuzz_checks.hpp for what is checked.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  errfield::fuzz::check_robot_json(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
