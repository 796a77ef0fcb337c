#include "errfield/programs/program_lexer.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "errfield/error.hpp"

namespace errfield::programs {

Lexed lex_program(const ProgramFile& file, const LexicalRules& rules) {
  const std::string& s = file.bytes;
  Lexed out;
  std::size_t i = 0, line = 1;
  auto has = [](const std::string& set, char c) { return set.find(c) != std::string::npos; };
  while (i < s.size()) {
    const char c = s[i];
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '\n') {
      ++line;
      ++i;
      continue;
    }
    if (c == rules.comment) {
      const std::size_t start = ++i;
      while (i < s.size() && s[i] != '\n') ++i;
      out.comments.push_back({line, s.substr(start, i - start)});
      continue;
    }
    if (std::isspace(u)) {
      ++i;
      continue;
    }
    LexToken t;
    t.span.begin = i;
    t.line = line;
    if (has(rules.quotes, c)) {
      ++i;
      for (;;) {
        if (i >= s.size() || (rules.string_ends_at_line && s[i] == '\n'))
          throw InputError(file.path + ":" + std::to_string(t.line) + ": unterminated string (" + c + "...)", file.path, t.line);
        if (rules.doubled_quote && s[i] == c && i + 1 < s.size() && s[i + 1] == c) {
          i += 2;
          continue;
        }
        if (rules.backslash_escape && s[i] == '\\' && i + 1 < s.size()) {
          i += 2;
          continue;
        }
        if (s[i] == '\n') ++line;
        if (s[i] == c) break;
        ++i;
      }
      ++i;
      t.kind = LexKind::string;
    } else if (std::isalpha(u) || has(rules.ident_first, c)) {
      ++i;
      while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || has(rules.ident_rest, s[i]))) ++i;
      t.kind = LexKind::ident;
    } else if (number_starts(s, i)) {
      i = number_end(s, i);
      t.kind = LexKind::number;
    } else {
      const std::string two = s.substr(i, 2);
      i += std::find(rules.two_char_punct.begin(), rules.two_char_punct.end(), two) != rules.two_char_punct.end() ? 2 : 1;
      t.kind = LexKind::punct;
    }
    t.span.end = i;
    t.text = s.substr(t.span.begin, t.span.end - t.span.begin);
    if (t.kind == LexKind::number) t.value = std::strtod(t.text.c_str(), nullptr);
    out.tokens.push_back(std::move(t));
  }
  return out;
}

}  // namespace errfield::programs
