#include "errfield/number_format.hpp"

#include <charconv>
#include <cstdio>

namespace errfield {

std::string format_number(double value) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, res.ptr);
}

std::string format_significant(double value, int digits) {
  char buf[64];
  const int n = std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  return std::string(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
}

}  // namespace errfield
