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

/// A file's name (for the report and messages) and its bytes.
struct ProgramFile {
  std::string path;
  std::string bytes;
};

/// Bytes [begin, end) of a program's text.
struct ByteSpan {
  std::size_t begin = 0, end = 0;
};

/// A number literal as written in a program: its bytes (a leading sign included) and its value.
struct NumberLiteral {
  ByteSpan span;
  double value = 0.0;
};

/// New text for the bytes of `span` of one of the files a reader rewrites: `file` 0 is the program
/// itself, other indices are the reader's (KRL: 1 is the .dat beside the .src).
struct Replacement {
  ByteSpan span;
  std::string text;
  std::size_t file = 0;
};

/// True when a number literal starts at byte `i`: a digit, or a point followed by one (".5").
bool number_starts(std::string_view s, std::size_t i);

/// End of the number literal starting at `i` (number_starts): digits, a fraction, an exponent
/// (`1.5E+3`; an `E` not followed by digits is not part of the number).
std::size_t number_end(std::string_view s, std::size_t i);

/// `raw` with every run of white space written as one space (labels and messages).
std::string collapse_spaces(std::string_view raw);

/// `original` with every replacement applied; all other bytes copied as they are. Replacements may
/// come in any order; overlapping ones are a logic error (std::logic_error).
std::string apply_replacements(std::string_view original, std::vector<Replacement> replacements);

/// 1-based line number of byte `offset` (lines end at '\n'; a CR before it belongs to the line).
std::size_t line_of_offset(std::string_view text, std::size_t offset);

/// `value` with `decimals` digits after the point, trailing zeros (and a bare point) dropped, "-0"
/// written as "0": the spelling errfield gives rewritten program numbers.
std::string format_program_number(double value, int decimals);

/// `value` written like `original` (a number as the program spelled it): format_program_number's
/// spelling, plus ".0" when the original had a decimal point and the new text has none (KRL and
/// URScript writers spell whole reals "100.0"), and no 0 before the point when the original had none
/// (".417", "-.191").
std::string format_program_number_like(std::string_view original, double value, int decimals);

/// The whole file as bytes; InputError naming `what` and the path when it cannot be read.
std::string read_program_bytes(const std::string& path, const std::string& what);

}  // namespace errfield::programs
