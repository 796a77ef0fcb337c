#pragma once
/// A robot program as bytes, and the edits a compensation makes to it. Use it to rewrite numbers in a
/// program without touching anything else: the file is never decoded (Latin-1 or UTF-8 bytes, CRLF or
/// LF line ends pass through as they are), every edit names the byte span it replaces, and
/// apply_replacements copies every byte outside those spans unchanged.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace errfield::programs {

/// Bytes [begin, end) of a program's text.
struct ByteSpan {
  std::size_t begin = 0, end = 0;
};

/// A number literal as written in a program: its bytes (a leading sign included) and its value.
struct NumberLiteral {
  ByteSpan span;
  double value = 0.0;
};

/// New text for the bytes of `span`.
struct Replacement {
  ByteSpan span;
  std::string text;
};

/// `original` with every replacement applied; all other bytes copied as they are. Replacements may
/// come in any order; overlapping ones are a logic error (std::logic_error).
std::string apply_replacements(std::string_view original, std::vector<Replacement> replacements);

/// 1-based line number of byte `offset` (lines end at '\n'; a CR before it belongs to the line).
std::size_t line_of_offset(std::string_view text, std::size_t offset);

/// `value` with `decimals` digits after the point, trailing zeros (and a bare point) dropped, "-0"
/// written as "0": the spelling errfield gives rewritten program numbers.
std::string format_program_number(double value, int decimals);

/// The whole file as bytes; InputError naming `what` and the path when it cannot be read.
std::string read_program_bytes(const std::string& path, const std::string& what);

}  // namespace errfield::programs
