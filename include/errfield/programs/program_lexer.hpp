#pragma once
/// Splitting a robot program's bytes into tokens, with each format's lexical rules (comment
/// character, identifier characters, string quotes and escapes, two-character operators). Use it
/// from a format's reader (RAPID, KRL, URScript): every token keeps its byte span, so numbers can be
/// rewritten in place (program_text.hpp).

#include <cstddef>
#include <string>
#include <vector>

#include "errfield/programs/program_text.hpp"

namespace errfield::programs {

enum class LexKind { ident, number, string, punct };

struct LexToken {
  LexKind kind = LexKind::punct;
  ByteSpan span;
  std::string text;      ///< the bytes as written
  double value = 0.0;    ///< numbers: the value (unsigned: a sign is a punct token of its own)
  std::size_t line = 0;  ///< 1-based
};

/// A comment: its 1-based line and the text after the comment character.
struct LexComment {
  std::size_t line = 0;
  std::string text;
};

struct LexicalRules {
  char comment = '!';               ///< starts a comment to the end of the line
  std::string ident_first = "_";    ///< characters besides letters that start an identifier
  std::string ident_rest = "_";     ///< characters besides letters and digits inside one
  std::string quotes = "\"";        ///< string delimiters
  bool doubled_quote = false;       ///< "" inside a string is a quote (RAPID)
  bool backslash_escape = false;    ///< \x inside a string is one escaped character
  bool string_ends_at_line = false; ///< a line end inside a string is an error (KRL, URScript)
  std::vector<std::string> two_char_punct;  ///< operators read as one token (":=", "==", ...)
};

struct Lexed {
  std::vector<LexToken> tokens;
  std::vector<LexComment> comments;
};

/// The tokens and comments of `file` (InputError naming file and line for an unterminated string).
Lexed lex_program(const ProgramFile& file, const LexicalRules& rules);

}  // namespace errfield::programs
