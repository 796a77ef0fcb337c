// libFuzzer target: the JSON input readers (check_json_inputs in fuzz_json_checks.hpp). One target rather than three
// keeps the CI fuzz stage's time: the first byte picks the reader, the rest is the file.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_json_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  errfield::fuzz::check_json_inputs(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
