#include "errfield/programs/krl_program.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <regex>
#include <set>

#include "errfield/error.hpp"
#include "errfield/programs/abb_confdata.hpp"
#include "errfield/programs/program_lexer.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::programs {

Eigen::Matrix3d kuka_abc_rotation(double a_deg, double b_deg, double c_deg) {
  // KUKA's A about z, then B about the new y, then C about the newest x: errfield's rz, ry, rx.
  return robot::rotation_from_rpy_deg(c_deg, b_deg, a_deg);
}

Eigen::Vector3d kuka_abc_of(const Eigen::Matrix3d& r) {
  const Eigen::Vector3d rpy = robot::rpy_deg_from_rotation(r);
  return {rpy.z(), rpy.y(), rpy.x()};
}

int krl_bits(const std::string& text) {
  std::string t = text;
  t.erase(std::remove_if(t.begin(), t.end(), [](unsigned char c) { return std::isspace(c); }), t.end());
  if (t.empty()) return -1;
  if (t.size() >= 3 && t.front() == '\'' && t.back() == '\'') {
    const char base = static_cast<char>(std::toupper(static_cast<unsigned char>(t[1])));
    const std::string digits = t.substr(2, t.size() - 3);
    if (digits.empty() || digits.size() > 16) return -1;
    int v = 0;
    for (char c : digits) {
      const int d = base == 'B' ? (c == '0' ? 0 : c == '1' ? 1 : -1)
                                : base == 'H' && std::isxdigit(static_cast<unsigned char>(c))
                                      ? (std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : std::toupper(c) - 'A' + 10)
                                      : -1;
      if (d < 0) return -1;
      v = v * (base == 'B' ? 2 : 16) + d;
    }
    return v;
  }
  if (!std::all_of(t.begin(), t.end(), [](unsigned char c) { return std::isdigit(c); }) || t.size() > 6) return -1;
  return std::stoi(t);
}

bool krl_turn_matches(int turn, const robot::JointVector& q_deg) {
  for (int i = 0; i < 6; ++i)
    if (((turn >> i) & 1) != (q_deg[i] < 0.0 ? 1 : 0)) return false;
  return true;
}

// Named, not anonymous: the programs folder is compiled as a unity build beside other readers.
namespace krl_reading {

using Kind = LexKind;

struct Token {
  Kind kind = Kind::punct;
  ByteSpan span;
  std::string text, low;
  double value = 0.0;
  std::size_t line = 0;
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string short_text(std::string text) {
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

struct Source {
  const ProgramFile* file = nullptr;
  std::size_t index = 0;     // 0: the .src, 1: the .dat, 2...: includes
  bool rewritable = false;   // the .src and the .dat
  bool data_file = false;    // DEFDAT ... ENDDAT: NAME={...} lines are declarations
  std::vector<Token> tokens;
  std::map<std::size_t, std::string> folds;                    // line -> text of a ;FOLD comment
  std::vector<std::pair<std::size_t, std::size_t>> lines;      // token ranges, one per source line
  std::string where(std::size_t line) const { return file->path + ":" + std::to_string(line); }
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw InputError(where(line) + ": " + what, file->path, line);
  }
  // The source text of tokens [a, b), whitespace runs collapsed.
  std::string text(std::size_t a, std::size_t b) const {
    if (a >= b) return {};
    return collapse_spaces(std::string_view(file->bytes).substr(tokens[a].span.begin, tokens[b - 1].span.end - tokens[a].span.begin));
  }
  bool is(std::size_t k, std::size_t end, const char* low) const { return k < end && tokens[k].kind != Kind::string && tokens[k].low == low; }
};

// KRL's lexical elements; `;` comments dropped except ;FOLD lines, which are kept as text (the
// inline forms name the tool and base there). '...' are bit literals ('B0110').
void tokenize(Source& src) {
  LexicalRules rules;
  rules.comment = ';';
  rules.ident_first = "_$#";
  rules.ident_rest = "_$";
  rules.quotes = "\"'";
  rules.string_ends_at_line = true;
  rules.two_char_punct = {"==", "<>", "<=", ">="};
  Lexed lexed = lex_program(*src.file, rules);
  for (const LexComment& c : lexed.comments)
    if (lower(c.text.substr(0, 4)) == "fold") src.folds[c.line] += c.text;
  for (LexToken& l : lexed.tokens) {
    Token t;
    t.kind = l.kind;
    t.span = l.span;
    t.low = lower(l.text);
    t.text = std::move(l.text);
    t.value = l.value;
    t.line = l.line;
    src.tokens.push_back(std::move(t));
  }
  for (std::size_t k = 0; k < src.tokens.size();) {
    std::size_t e = k;
    while (e < src.tokens.size() && src.tokens[e].line == src.tokens[k].line) ++e;
    src.lines.push_back({k, e});
    if (src.tokens[k].low == "defdat") src.data_file = true;
    k = e;
  }
}

// Index past the bracket closing the one at `k`, within [k, end); `end` when it is not closed.
std::size_t close_of(const Source& s, std::size_t k, std::size_t end) {
  int depth = 0;
  for (; k < end; ++k) {
    if (s.tokens[k].kind != Kind::punct) continue;
    const std::string& t = s.tokens[k].text;
    if (t == "{" || t == "(" || t == "[") ++depth;
    if (t == "}" || t == ")" || t == "]")
      if (--depth == 0) return k + 1;
  }
  return end;
}

// {NAME value, NAME value, ...}: each field's value tokens, and its number when it is one.
struct Field {
  std::string name;  // lower case
  std::size_t first = 0, end = 0;
  std::optional<NumberLiteral> number;
};

struct Aggregate {
  const Source* source = nullptr;
  std::size_t open = 0, end = 0;  // tokens [open, end) including the braces
  std::vector<Field> fields;
  const Field* find(const char* name) const {
    for (const Field& f : fields)
      if (f.name == name) return &f;
    return nullptr;
  }
  bool has_numbers(std::initializer_list<const char*> names) const {
    return std::all_of(names.begin(), names.end(), [&](const char* n) { return find(n) && find(n)->number; });
  }
  std::string value_text(const Field& f) const { return source->text(f.first, f.end); }
};

std::optional<Aggregate> parse_aggregate(const Source& s, std::size_t k, std::size_t end) {
  if (!s.is(k, end, "{")) return std::nullopt;
  const std::size_t close = close_of(s, k, end);
  if (close == end && !s.is(end - 1, end, "}")) s.fail(s.tokens[k].line, "unterminated aggregate {...}");
  Aggregate a;
  a.source = &s;
  a.open = k;
  a.end = close;
  std::size_t i = k + 1;
  while (i < close - 1) {
    std::size_t e = i;
    int depth = 0;
    while (e < close - 1) {
      const Token& t = s.tokens[e];
      if (t.kind == Kind::punct && (t.text == "{" || t.text == "(" || t.text == "[")) ++depth;
      if (t.kind == Kind::punct && (t.text == "}" || t.text == ")" || t.text == "]")) --depth;
      if (depth == 0 && t.kind == Kind::punct && t.text == ",") break;
      ++e;
    }
    if (e > i && s.tokens[i].kind == Kind::ident) {
      Field f;
      f.name = s.tokens[i].low;
      f.first = i + 1;
      f.end = e;
      const std::size_t len = f.end - f.first;
      if (len == 1 && s.tokens[f.first].kind == Kind::number)
        f.number = NumberLiteral{s.tokens[f.first].span, s.tokens[f.first].value};
      else if (len == 2 && (s.tokens[f.first].text == "-" || s.tokens[f.first].text == "+") && s.tokens[f.first + 1].kind == Kind::number)
        f.number = NumberLiteral{{s.tokens[f.first].span.begin, s.tokens[f.first + 1].span.end},
                                 (s.tokens[f.first].text == "-" ? -1.0 : 1.0) * s.tokens[f.first + 1].value};
      a.fields.push_back(std::move(f));
    }
    i = e + 1;
  }
  return a;
}

bool is_axis_aggregate(const Aggregate& a) { return a.find("a1") != nullptr && a.find("x") == nullptr; }

struct Declaration {
  const Source* source = nullptr;
  std::size_t line = 0;
  std::string type, key;                 // lower case; key "xp1" or "tool_data[1]"
  std::optional<Aggregate> aggregate;    // the value when it is {...}
  std::string expression;                // the value's text otherwise ("" = no value)
  std::string where() const { return source->where(line); }
};

// A name, or a name and one constant index: "xp1", "p[3]", "tool_data[1]"; tokens [k, end).
std::optional<std::string> key_of(const Source& s, std::size_t k, std::size_t end, std::size_t* after = nullptr) {
  if (k >= end || s.tokens[k].kind != Kind::ident) return std::nullopt;
  std::string key = s.tokens[k].low;
  std::size_t next = k + 1;
  if (s.is(next, end, "[") && next + 2 < end && s.tokens[next + 1].kind == Kind::number && s.is(next + 2, end, "]")) {
    key += "[" + std::to_string(static_cast<long>(s.tokens[next + 1].value)) + "]";
    next += 3;
  }
  if (after) *after = next;
  return key;
}

struct State {
  std::string name;       // e.g. "TOOL_DATA[1]"; empty: not known
  std::string unknown;    // why it is not known (with where)
};

const std::set<std::string> kMotions{"ptp", "lin", "circ", "sptp", "slin", "scirc", "spl"};
const std::set<std::string> kRelative{"ptp_rel", "lin_rel", "circ_rel", "sptp_rel", "slin_rel", "scirc_rel"};
const std::set<std::string> kMotionEnds{"c_ptp", "c_dis", "c_vel", "c_ori", "c_spl", "with", "ca"};

class KrlReader {
 public:
  KrlReader(const ProgramFile& src, const ProgramFile& dat, const std::vector<ProgramFile>& includes, const robot::MdhModel& robot,
            const KrlReadOptions& options)
      : robot_(robot), options_(options) {
    sources_.reserve(2 + includes.size());
    auto add = [&](const ProgramFile& f, std::size_t index, bool rewritable) {
      Source s;
      s.file = &f;
      s.index = index;
      s.rewritable = rewritable;
      sources_.push_back(std::move(s));
    };
    add(src, 0, true);
    if (!dat.path.empty()) add(dat, 1, true);
    for (const ProgramFile& f : includes) add(f, sources_.size() + (dat.path.empty() ? 1 : 0), false);
    for (Source& s : sources_) {
      tokenize(s);
      if (s.index != 0) s.data_file = true;  // the .dat and the includes hold declarations
    }
    for (const Source& s : sources_) collect(s);
  }

  std::vector<ProgramTarget> targets() {
    const Source& s = sources_.front();
    std::vector<ProgramTarget> out;
    State tool{"", "no tool is set before this motion ($TOOL is whatever the controller used last)"};
    State base{"", "no base is set before this motion ($BASE is whatever the controller used last)"};
    // Code lines and fold lines in line order.
    std::map<std::size_t, std::pair<std::size_t, std::size_t>> code;
    for (const auto& r : s.lines) code[s.tokens[r.first].line] = r;
    std::set<std::size_t> line_numbers;
    for (const auto& [l, r] : code) line_numbers.insert(l);
    for (const auto& [l, f] : s.folds) line_numbers.insert(l);
    static const std::regex tool_re(R"(\bTool\[\s*(\d+)\s*\])", std::regex::icase), base_re(R"(\bBase\[\s*(\d+)\s*\])", std::regex::icase);
    for (std::size_t line : line_numbers) {
      if (auto f = s.folds.find(line); f != s.folds.end()) {
        std::smatch m;
        if (std::regex_search(f->second, m, tool_re)) tool = {"TOOL_DATA[" + m[1].str() + "]", ""};
        if (std::regex_search(f->second, m, base_re)) base = {"BASE_DATA[" + m[1].str() + "]", ""};
      }
      const auto c = code.find(line);
      if (c == code.end()) continue;
      const auto [a, e] = c->second;
      const std::string& w = s.tokens[a].low;
      if ((w == "$tool" || w == "$base") && s.is(a + 1, e, "=")) {
        State& st = w == "$tool" ? tool : base;
        const std::string family = w == "$tool" ? "tool_data" : "base_data";
        std::size_t after = 0;
        const auto key = key_of(s, a + 2, e, &after);
        if (key && after == e && key->rfind(family + "[", 0) == 0) st = {upper(*key), ""};
        else if (key && after == e && *key == "$nullframe") st = {w == "$tool" ? "TOOL_DATA[0]" : "BASE_DATA[0]", ""};
        else st = {"", s.text(a, e) + " (" + s.where(line) + ") is computed at run time, not known here"};
        continue;
      }
      if (w == "bas" && s.is(a + 1, e, "(") && a + 5 < e && s.tokens[a + 4].kind == Kind::number &&
          (s.tokens[a + 2].low == "#tool" || s.tokens[a + 2].low == "#base")) {
        const int n = static_cast<int>(s.tokens[a + 4].value);
        (s.tokens[a + 2].low == "#tool" ? tool : base) = {(s.tokens[a + 2].low == "#tool" ? "TOOL_DATA[" : "BASE_DATA[") + std::to_string(n) + "]", ""};
        continue;
      }
      if (w == "fdat_act" && s.is(a + 1, e, "=") && a + 3 == e) apply_fdat(s.tokens[a + 2].low, line, tool, base);
      if (kRelative.count(w)) {
        ProgramTarget p = start(s, line);
        p.kind = TargetKind::computed;
        p.label = short_text(s.text(a, e));
        p.note = s.tokens[a].text + ": a motion relative to where the robot is, computed at run time; not rewritten";
        out.push_back(std::move(p));
        continue;
      }
      if (!kMotions.count(w)) continue;
      // The target expressions: up to the approximation/WITH keywords; CIRC and SCIRC have two.
      std::vector<std::pair<std::size_t, std::size_t>> args;
      std::size_t k = a + 1, from = a + 1;
      int depth = 0;
      for (; k < e; ++k) {
        const Token& t = s.tokens[k];
        if (t.kind == Kind::punct && (t.text == "{" || t.text == "(" || t.text == "[")) ++depth;
        if (t.kind == Kind::punct && (t.text == "}" || t.text == ")" || t.text == "]")) --depth;
        if (depth == 0 && (kMotionEnds.count(t.low) && t.kind == Kind::ident)) break;
        if (depth == 0 && t.kind == Kind::punct && t.text == ",") {
          args.push_back({from, k});
          from = k + 1;
        }
      }
      args.push_back({from, k});
      const bool circular = w == "circ" || w == "scirc";
      const bool ptp = w == "ptp" || w == "sptp";
      for (std::size_t n = 0; n < (circular ? 2u : 1u); ++n) {
        ProgramTarget p = start(s, line);
        const std::string role = circular ? (n == 0 ? " auxiliary point" : " end point") : "";
        if (n >= args.size()) {
          p.kind = TargetKind::computed;
          p.label = s.tokens[a].text + role;
          p.refusal = s.tokens[a].text + " without its" + role;
          out.push_back(std::move(p));
          continue;
        }
        set_frames(p, tool, base);
        read_target(s, args[n].first, args[n].second, s.tokens[a].text, role, ptp, p);
        out.push_back(std::move(p));
      }
    }
    return out;
  }

 private:
  static std::string upper(std::string s) {
    for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return s;
  }

  ProgramTarget start(const Source& s, std::size_t line) const {
    ProgramTarget p;
    p.file = s.file->path;
    p.line = line;
    return p;
  }

  void collect(const Source& s) {
    for (const auto& [a, e] : s.lines) {
      std::size_t k = a;
      bool decl = false;
      while (k < e && (s.tokens[k].low == "decl" || s.tokens[k].low == "global" || s.tokens[k].low == "const")) {
        decl = decl || s.tokens[k].low == "decl";
        ++k;
      }
      if (k >= e || s.tokens[k].kind != Kind::ident) continue;
      std::string type;
      std::size_t name = k;
      if (k + 1 < e && s.tokens[k + 1].kind == Kind::ident) {
        type = s.tokens[k].low;
        name = k + 1;
      }
      std::size_t after = 0;
      const auto key = key_of(s, name, e, &after);
      if (!key) continue;
      const bool declaration = decl || s.data_file;
      if (!declaration) {
        // A point assigned in the .src at run time (XP1 = ..., XP1.X = ...).
        if (s.is(after, e, "=") || (s.is(after, e, ".") && after + 2 < e && s.is(after + 2, e, "=")))
          assigned_.emplace(*key, "assigned at run time (" + s.where(s.tokens[a].line) + ": " + short_text(s.text(a, e)) + ")");
        continue;
      }
      Declaration d;
      d.source = &s;
      d.line = s.tokens[a].line;
      d.type = type;
      d.key = *key;
      if (s.is(after, e, "=")) {
        d.aggregate = parse_aggregate(s, after + 1, e);
        if (!d.aggregate || d.aggregate->end != e) {
          d.aggregate.reset();
          d.expression = s.text(after + 1, e);
          if (d.expression.empty()) d.expression = "(nothing)";
        }
      } else if (s.is(after, e, "[")) {
        d.key = s.tokens[name].low;  // an array declared with its size: elements are set elsewhere
      }
      // The first declaration with a value wins: the .src's, then the .dat's, then the includes'.
      const auto known = declarations_.find(d.key);
      const bool has_value = d.aggregate || !d.expression.empty();
      if (known == declarations_.end() || (has_value && !known->second.aggregate && known->second.expression.empty()))
        declarations_[d.key] = std::move(d);
    }
  }

  const Declaration* find(const std::string& key) const {
    const auto d = declarations_.find(key);
    return d == declarations_.end() ? nullptr : &d->second;
  }

  void apply_fdat(const std::string& name, std::size_t line, State& tool, State& base) const {
    const Declaration* d = find(name);
    if (!d || !d->aggregate) return;  // the fold line or $TOOL/$BASE say it then
    const Aggregate& g = *d->aggregate;
    if (const Field* ipo = g.find("ipo_frame"); ipo && lower(g.value_text(*ipo)) == "#tcp") {
      tool = {"", name + " (" + d->where() + ") has IPO_FRAME #TCP: a fixed tool with the part on the flange, not supported"};
      base = tool;
      return;
    }
    if (const Field* t = g.find("tool_no"); t && t->number) tool = {"TOOL_DATA[" + std::to_string(static_cast<int>(t->number->value)) + "]", ""};
    if (const Field* b = g.find("base_no"); b && b->number) base = {"BASE_DATA[" + std::to_string(static_cast<int>(b->number->value)) + "]", ""};
    (void)line;
  }

  // A frame named TOOL_DATA[n] or BASE_DATA[n]: given by option, index 0, or declared.
  std::string resolve(const State& st, const std::map<std::string, Eigen::Isometry3d>& given, const char* what, const char* option,
                      Eigen::Isometry3d& frame) const {
    if (st.name.empty()) return st.unknown;
    for (const auto& [n, f] : given)
      if (lower(n) == lower(st.name)) {
        frame = f;
        return {};
      }
    if (st.name.find("[0]") != std::string::npos) {
      frame = Eigen::Isometry3d::Identity();
      return {};
    }
    const Declaration* d = find(lower(st.name));
    if (!d)
      return std::string(what) + " " + st.name + " is declared nowhere (not in the .src, the .dat nor an --include such as "
             "$config.dat; give " + option + " " + st.name + "=X,Y,Z[,A,B,C] or --include $config.dat)";
    if (!d->aggregate || !d->aggregate->has_numbers({"x", "y", "z", "a", "b", "c"}))
      return std::string(what) + " " + st.name + " (" + d->where() + ") is not a literal {X,Y,Z,A,B,C} (give " + option + " " +
             st.name + "=...)";
    frame = pose_of(*d->aggregate);
    return {};
  }

  static Eigen::Isometry3d pose_of(const Aggregate& g) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.translation() << g.find("x")->number->value, g.find("y")->number->value, g.find("z")->number->value;
    p.linear() = kuka_abc_rotation(g.find("a")->number->value, g.find("b")->number->value, g.find("c")->number->value);
    return p;
  }

  void set_frames(ProgramTarget& p, const State& tool, const State& base) const {
    p.tool_name = tool.name.empty() ? "$TOOL" : tool.name;
    p.frame_name = base.name.empty() ? "$BASE" : base.name;
    std::string why = resolve(tool, options_.tools, "tool", "--tool", p.tool);
    if (why.empty()) why = resolve(base, options_.bases, "base", "--wobj", p.frame);
    p.refusal = why;
  }

  void read_target(const Source& s, std::size_t a, std::size_t e, const std::string& motion, const std::string& role, bool ptp,
                   ProgramTarget& p) {
    if (a >= e) {
      p.kind = TargetKind::computed;
      p.label = motion + role;
      p.refusal = motion + " without a target";
      return;
    }
    if (s.is(a, e, "{") && close_of(s, a, e) == e) {
      const Aggregate g = *parse_aggregate(s, a, e);
      p.label = motion + role + " " + short_text(s.text(a, e));
      if (is_axis_aggregate(g)) {
        p.kind = TargetKind::joints;
        p.refusal.clear();  // the tool and base do not matter to axis values
        p.note = motion + " to axis values: a joint target, sent as written (no Cartesian correction applies)";
        return;
      }
      if (!g.has_numbers({"x", "y", "z", "a", "b", "c"})) {
        p.kind = TargetKind::computed;
        p.note = "a partial aggregate: the components it leaves out come from the robot's position at run time; not rewritten";
        return;
      }
      literal(g, motion, ptp, "", p);
      return;
    }
    std::size_t after = 0;
    const auto key = key_of(s, a, e, &after);
    if (key && after == e) {
      p.label = s.text(a, e) + (role.empty() ? "" : " (" + role.substr(1) + ")");
      const std::string bare = key->substr(0, key->find('['));
      if ((*key)[0] == '$') {
        p.kind = TargetKind::computed;
        p.note = s.text(a, e) + " is a system variable, set by the controller at run time";
        return;
      }
      for (const std::string& k : {*key, bare})
        if (auto r = assigned_.find(k); r != assigned_.end()) {
          p.kind = TargetKind::computed;
          p.note = s.text(a, e) + " is " + r->second;
          return;
        }
      const Declaration* d = find(*key);
      if (!d) {
        if (const Declaration* arr = find(bare); arr && !arr->aggregate && arr->expression.empty()) {
          p.kind = TargetKind::computed;
          p.note = s.text(a, e) + ": an element of " + bare + " (" + arr->where() + ") with no literal value: set at run time";
          return;
        }
        p.refusal = "point '" + s.text(a, e) + "' is declared nowhere (not in the .src, the .dat nor an --include)";
        return;
      }
      if (d->type == "e6axis" || d->type == "axis" || (d->aggregate && is_axis_aggregate(*d->aggregate))) {
        p.kind = TargetKind::joints;
        p.refusal.clear();
        p.note = s.text(a, e) + " (" + d->where() + ") is an axis position: sent as written (no Cartesian correction applies)";
        return;
      }
      if (!d->aggregate) {
        p.kind = TargetKind::computed;
        p.note = d->expression.empty() ? s.text(a, e) + " is declared without a value (" + d->where() + "): set at run time"
                                       : s.text(a, e) + " is declared = " + short_text(d->expression) + " (" + d->where() +
                                             "): computed at run time";
        return;
      }
      if (!d->source->rewritable) {
        p.kind = TargetKind::literal;
        if (p.refusal.empty())
          p.refusal = "point '" + s.text(a, e) + "' is declared in " + d->where() + ", an --include: only the .src and its .dat are rewritten";
        return;
      }
      if (!d->aggregate->has_numbers({"x", "y", "z", "a", "b", "c"})) {
        p.kind = TargetKind::literal;
        if (p.refusal.empty()) p.refusal = "point '" + s.text(a, e) + "' (" + d->where() + ") is not an aggregate with numbers X,Y,Z,A,B,C";
        return;
      }
      literal(*d->aggregate, motion, ptp, std::to_string(d->source->index) + ":" + d->key, p);
      return;
    }
    // An expression: a frame product (:), a function call, ...: computed by the controller.
    p.kind = TargetKind::computed;
    p.label = motion + role + " " + short_text(s.text(a, e));
    std::vector<std::string> depends;
    for (std::size_t k = a; k < e; ++k)
      if (s.tokens[k].kind == Kind::ident && !s.is(k + 1, e, "(") && s.tokens[k].text[0] != '#' &&
          std::find(depends.begin(), depends.end(), s.tokens[k].text) == depends.end() &&
          !(k > a && s.tokens[k - 1].kind == Kind::punct && (s.tokens[k - 1].text == "{" || s.tokens[k - 1].text == ",")))
        depends.push_back(s.tokens[k].text);
    std::string on;
    for (const std::string& d : depends) on += (on.empty() ? "" : ", ") + d;
    p.note = "computed by the controller at run time" + (on.empty() ? std::string() : " from " + on) + " (tool " + p.tool_name +
             ", base " + p.frame_name + "); not a literal, not rewritten";
  }

  void literal(const Aggregate& g, const std::string& motion, bool ptp, const std::string& shared_key, ProgramTarget& p) {
    p.kind = TargetKind::literal;
    p.shared_key = shared_key;
    if (!p.refusal.empty()) return;
    p.pose_in_frame = pose_of(g);
    const Field* sf = g.find("s");
    const Field* tf = g.find("t");
    const int status = sf ? krl_bits(g.value_text(*sf)) : -1, turn = tf ? krl_bits(g.value_text(*tf)) : -1;
    if ((sf && status < 0) || (tf && turn < 0)) {
      p.refusal = "Status/Turn '" + (sf ? g.value_text(*sf) : "") + "' '" + (tf ? g.value_text(*tf) : "") +
                  "' is neither a decimal nor a bit literal ('B0110')";
      return;
    }
    if (sf || tf) {
      const robot::MdhModel robot = robot_;
      p.configuration.matches = [robot, status, turn](const robot::JointVector& q) {
        if (turn >= 0 && !krl_turn_matches(turn, q)) return false;
        // Status bit 0: the wrist centre behind axis 1 (KUKA's overhead area); abb_confdata's cfx
        // bit 2 is the same test on the robot description's frames.
        if (status >= 0 && ((status & 1) != 0) != ((abb_confdata(robot, q).cfx & 4) != 0)) return false;
        return true;
      };
      p.configuration.text = (sf ? "S " + g.value_text(*sf) : std::string()) + (sf && tf ? " " : "") + (tf ? "T " + g.value_text(*tf) : "");
      p.configuration.text += " (Turn and Status bit 0 checked; Status bits 1, 2 not)";
      if (!ptp) {
        p.configuration.ignored = true;
        p.configuration.off_by = motion + " (a CP motion: the controller ignores Status and Turn)";
      }
    }
    const Source* src = g.source;
    std::array<NumberLiteral, 6> lit;
    std::array<std::string, 6> spelled;
    const char* names[6] = {"x", "y", "z", "a", "b", "c"};
    for (std::size_t i = 0; i < 6; ++i) {
      lit[i] = *g.find(names[i])->number;
      spelled[i] = src->file->bytes.substr(lit[i].span.begin, lit[i].span.end - lit[i].span.begin);
    }
    const Eigen::Isometry3d old = p.pose_in_frame;
    const std::size_t file = src->index;
    p.rewrite = [lit, spelled, old, file](const Eigen::Isometry3d& now) {
      std::vector<Replacement> r;
      for (std::size_t i = 0; i < 3; ++i)
        if (std::abs(now.translation()[static_cast<Eigen::Index>(i)] - lit[i].value) >= 0.0005)
          r.push_back({lit[i].span, format_program_number_like(spelled[i], now.translation()[static_cast<Eigen::Index>(i)], 3), file});
      if (robot::rotation_log(now.linear() * old.linear().transpose()).norm() >= 1e-7) {
        // Of the two A,B,C triples of the rotation, the one nearest the written angles, each angle
        // turned by whole turns to within 180 deg of the written one.
        const Eigen::Vector3d abc = kuka_abc_of(now.linear());
        const Eigen::Vector3d written(lit[3].value, lit[4].value, lit[5].value);
        auto near = [&](Eigen::Vector3d v) {
          for (int i = 0; i < 3; ++i) v[i] -= 360.0 * std::round((v[i] - written[i]) / 360.0);
          return v;
        };
        const Eigen::Vector3d one = near(abc), two = near(Eigen::Vector3d(abc[0] + 180.0, 180.0 - abc[1], abc[2] + 180.0));
        const Eigen::Vector3d best = (one - written).cwiseAbs().sum() <= (two - written).cwiseAbs().sum() ? one : two;
        for (std::size_t i = 0; i < 3; ++i)
          if (std::abs(best[static_cast<Eigen::Index>(i)] - lit[3 + i].value) >= 0.00005)
            r.push_back({lit[3 + i].span, format_program_number_like(spelled[3 + i], best[static_cast<Eigen::Index>(i)], 4), file});
      }
      return r;
    };
  }

  const robot::MdhModel& robot_;
  const KrlReadOptions& options_;
  std::vector<Source> sources_;
  std::map<std::string, Declaration> declarations_;  // key -> declaration (the last one read wins)
  std::map<std::string, std::string> assigned_;      // key -> where it is assigned at run time
};

}  // namespace krl_reading

std::vector<ProgramTarget> read_krl_targets(const ProgramFile& src, const ProgramFile& dat, const std::vector<ProgramFile>& includes,
                                            const robot::MdhModel& robot, const KrlReadOptions& options) {
  krl_reading::KrlReader reader(src, dat, includes, robot, options);
  return reader.targets();
}

}  // namespace errfield::programs
