#include "errfield/programs/program_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "errfield/error.hpp"

namespace errfield::programs {

std::string apply_replacements(std::string_view original, std::vector<Replacement> replacements) {
  std::sort(replacements.begin(), replacements.end(),
            [](const Replacement& a, const Replacement& b) { return a.span.begin < b.span.begin; });
  std::string out;
  out.reserve(original.size() + 16 * replacements.size());
  std::size_t at = 0;
  for (const Replacement& r : replacements) {
    if (r.span.begin < at || r.span.end < r.span.begin || r.span.end > original.size())
      throw std::logic_error("apply_replacements: overlapping or out-of-range span");
    out.append(original.substr(at, r.span.begin - at));
    out += r.text;
    at = r.span.end;
  }
  out.append(original.substr(at));
  return out;
}

std::size_t line_of_offset(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

std::string format_program_number(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string read_program_bytes(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(what + " " + path + ": cannot be read", path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace errfield::programs
