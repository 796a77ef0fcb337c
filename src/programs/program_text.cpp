#include "errfield/programs/program_text.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "errfield/error.hpp"

namespace errfield::programs {

namespace {
bool digit_at(std::string_view s, std::size_t i) { return i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); }
}  // namespace

bool number_starts(std::string_view s, std::size_t i) { return digit_at(s, i) || (i < s.size() && s[i] == '.' && digit_at(s, i + 1)); }

std::size_t number_end(std::string_view s, std::size_t i) {
  while (digit_at(s, i)) ++i;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (digit_at(s, i)) ++i;
  }
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    std::size_t j = i + 1;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
    if (digit_at(s, j)) {
      while (digit_at(s, j)) ++j;
      i = j;
    }
  }
  return i;
}

std::string collapse_spaces(std::string_view raw) {
  std::string out;
  for (char c : raw) {
    const bool space = std::isspace(static_cast<unsigned char>(c));
    if (space && (out.empty() || out.back() == ' ')) continue;
    out += space ? ' ' : c;
  }
  return out;
}

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

std::string format_program_number_like(std::string_view original, double value, int decimals) {
  std::string s = format_program_number(value, decimals);
  const bool had_point = original.find('.') != std::string_view::npos && original.find_first_of("eE") == std::string_view::npos;
  if (had_point && s.find('.') == std::string::npos) s += ".0";
  // ".417" and "-.191" (URScript as Polyscope writes it): no zero before the point.
  const std::size_t o = !original.empty() && (original[0] == '-' || original[0] == '+') ? 1 : 0;
  const std::size_t n = !s.empty() && s[0] == '-' ? 1 : 0;
  if (o < original.size() && original[o] == '.' && s.compare(n, 2, "0.") == 0) s.erase(n, 1);
  return s;
}

std::string read_program_bytes(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(what + " " + path + ": cannot be read", path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace errfield::programs
