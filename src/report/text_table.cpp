#include "errfield/report/text_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "errfield/error.hpp"

namespace errfield::report {

void TextTable::add_row(std::vector<std::string> cells) {
  if (cells.size() != columns_.size())
    throw ArgumentError("TextTable::add_row: row " + std::to_string(rows_.size() + 1) + " has " +
                        std::to_string(cells.size()) + " cells; the table has " +
                        std::to_string(columns_.size()) + " columns");
  rows_.push_back(std::move(cells));
}

void TextTable::add_separator() { separators_.push_back(rows_.size()); }

bool TextTable::separator_before(std::size_t i) const {
  return std::find(separators_.begin(), separators_.end(), i) != separators_.end();
}

std::size_t display_width(std::string_view text) {
  std::size_t n = 0;
  for (unsigned char c : text)
    if ((c & 0xC0) != 0x80) ++n;  // count lead bytes only
  return n;
}

namespace {

std::string pad(const std::string& s, std::size_t width, Align align) {
  const std::size_t w = display_width(s);
  const std::string fill(width > w ? width - w : 0, ' ');
  return align == Align::Right ? fill + s : s + fill;
}

}  // namespace

std::string TextTable::to_text(std::string_view indent) const {
  const std::size_t n = columns_.size();
  std::vector<std::size_t> width(n, 0);
  bool any_unit = false;
  for (std::size_t c = 0; c < n; ++c) {
    width[c] = std::max(display_width(columns_[c].header), width[c]);
    if (!columns_[c].unit.empty()) {
      any_unit = true;
      width[c] = std::max(width[c], display_width(columns_[c].unit) + 2);
    }
    for (const auto& r : rows_) width[c] = std::max(width[c], display_width(r[c]));
  }
  std::size_t total = 0;
  for (std::size_t c = 0; c < n; ++c) total += width[c] + (c ? 2 : 0);
  const std::string rule = std::string(indent) + std::string(total, '-') + "\n";

  auto line = [&](auto cell_of) {
    std::string out(indent);
    for (std::size_t c = 0; c < n; ++c) {
      if (c) out += "  ";
      out += pad(cell_of(c), width[c], columns_[c].align);
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out + "\n";
  };
  std::string out = line([&](std::size_t c) { return columns_[c].header; });
  if (any_unit)
    out += line([&](std::size_t c) { return columns_[c].unit.empty() ? std::string() : "[" + columns_[c].unit + "]"; });
  out += rule;
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    if (r > 0 && separator_before(r)) out += rule;
    out += line([&](std::size_t c) { return rows_[r][c]; });
  }
  return out;
}

std::string fixed(double value, int decimals) {
  if (std::isnan(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::clamp(decimals, 0, 12), value);
  std::string s = buf;
  if (s.rfind("-0", 0) == 0 && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);  // no "-0.000"
  return s;
}

}  // namespace errfield::report
