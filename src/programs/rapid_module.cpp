#include "errfield/programs/rapid_module.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <set>

#include "errfield/error.hpp"
#include "errfield/programs/abb_confdata.hpp"
#include "errfield/programs/program_lexer.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::programs {
namespace {

using Tok = LexKind;

using Token = LexToken;

bool ident_start(unsigned char c) { return std::isalpha(c) || c == '_'; }
bool ident_char(unsigned char c) { return std::isalnum(c) || c == '_'; }

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// RAPID's lexical elements, comments (! to the end of the line) dropped. Identifiers are compared
// without case (RAPID is case-insensitive).
std::vector<Token> tokenize(const ProgramFile& f) {
  LexicalRules rules;
  rules.comment = '!';
  rules.doubled_quote = true;
  rules.backslash_escape = true;
  rules.two_char_punct = {":=", "<>", "<=", ">="};
  return lex_program(f, rules).tokens;
}

// An aggregate value ([a, [b, c], ...]) or a leaf: a signed number, or any other expression.
struct Node {
  bool aggregate = false;
  std::vector<Node> items;
  std::size_t first = 0, end = 0;  // token range
  std::optional<NumberLiteral> number;
};

struct Source {
  const ProgramFile* file = nullptr;
  std::vector<Token> tokens;
  std::size_t line(std::size_t token) const {
    return line_of_offset(file->bytes, token < tokens.size() ? tokens[token].span.begin : file->bytes.size());
  }
  [[noreturn]] void fail(std::size_t token, const std::string& what) const {
    const std::size_t l = line(token);
    throw InputError(file->path + ":" + std::to_string(l) + ": " + what, file->path, l);
  }
  bool is(std::size_t k, const char* text) const { return k < tokens.size() && tokens[k].kind != Tok::string && lower(tokens[k].text) == lower(text); }
  // The source text of tokens [a, b), whitespace runs collapsed to one space.
  std::string text(std::size_t a, std::size_t b) const {
    if (a >= b) return {};
    return collapse_spaces(std::string_view(file->bytes).substr(tokens[a].span.begin, tokens[b - 1].span.end - tokens[a].span.begin));
  }
};

// Index past the bracket that closes the one at `k` ([, ( or {).
std::size_t skip_group(const Source& s, std::size_t k) {
  int depth = 0;
  for (; k < s.tokens.size(); ++k) {
    const std::string& t = s.tokens[k].text;
    if (s.tokens[k].kind != Tok::punct) continue;
    if (t == "[" || t == "(" || t == "{") ++depth;
    if (t == "]" || t == ")" || t == "}") {
      if (--depth == 0) return k + 1;
    }
  }
  s.fail(k - 1, "unterminated bracket");
}

Node parse_value(const Source& s, std::size_t& k, std::size_t stop) {
  Node n;
  n.first = k;
  if (k < stop && s.tokens[k].kind == Tok::punct && s.tokens[k].text == "[") {
    n.aggregate = true;
    const std::size_t close = skip_group(s, k) - 1;
    ++k;
    while (k < close) {
      n.items.push_back(parse_value(s, k, close));
      if (k < close && s.tokens[k].text == ",") ++k;
    }
    k = close + 1;
    n.end = k;
    return n;
  }
  int depth = 0;
  while (k < stop) {
    const Token& t = s.tokens[k];
    if (t.kind == Tok::punct) {
      if (t.text == "(" || t.text == "[" || t.text == "{") ++depth;
      else if (t.text == ")" || t.text == "]" || t.text == "}") {
        if (depth == 0) break;
        --depth;
      } else if (t.text == "," && depth == 0) break;
    }
    ++k;
  }
  n.end = k;
  const std::size_t len = n.end - n.first;
  const bool signed_number = len == 2 && s.tokens[n.first].kind == Tok::punct &&
                             (s.tokens[n.first].text == "-" || s.tokens[n.first].text == "+") &&
                             s.tokens[n.first + 1].kind == Tok::number;
  if (len == 1 && s.tokens[n.first].kind == Tok::number)
    n.number = NumberLiteral{s.tokens[n.first].span, s.tokens[n.first].value};
  else if (signed_number)
    n.number = NumberLiteral{{s.tokens[n.first].span.begin, s.tokens[n.first + 1].span.end},
                             (s.tokens[n.first].text == "-" ? -1.0 : 1.0) * s.tokens[n.first + 1].value};
  return n;
}

bool numbers(const Node& n, std::size_t count) {
  return n.aggregate && n.items.size() == count &&
         std::all_of(n.items.begin(), n.items.end(), [](const Node& i) { return i.number.has_value(); });
}

// [[x,y,z],[q1,q2,q3,q4]] (pose data of tooldata and wobjdata; robtarget's first two parts).
std::optional<Eigen::Isometry3d> pose_of(const Node& trans, const Node& rot, std::string& problem) {
  if (!numbers(trans, 3) || !numbers(rot, 4)) {
    problem = "expected [x,y,z] and [q1,q2,q3,q4] numbers";
    return std::nullopt;
  }
  Eigen::Quaterniond q(rot.items[0].number->value, rot.items[1].number->value, rot.items[2].number->value,
                       rot.items[3].number->value);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) < 1e-3)) {
    problem = "quaternion of norm " + std::to_string(norm) + " (expected a unit quaternion [q1,q2,q3,q4], q1 the scalar part)";
    return std::nullopt;
  }
  q.normalize();
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = q.toRotationMatrix();
  p.translation() << trans.items[0].number->value, trans.items[1].number->value, trans.items[2].number->value;
  return p;
}

struct Declaration {
  const Source* source = nullptr;
  bool in_program = false;
  std::string type, storage, name;
  std::size_t name_token = 0;
  std::optional<Node> value;  // absent: declared without an initial value
  bool array = false;
};

struct Move {
  int target_count = 1;  // MoveC: CirPoint and ToPoint
  int tool_index = 3;    // positional index of Tool
  bool linear = true;    // ConfL (else ConfJ)
  bool joints = false;   // MoveAbsJ, MoveExtJ
};

std::optional<Move> move_of(const std::string& name) {
  const std::string n = lower(name);
  static const std::set<std::string> joint{"moveabsj", "moveabsjdo", "moveabsjsync", "moveabsjao", "moveabsjgo", "moveextj"};
  if (joint.count(n)) return Move{1, 3, false, true};
  static const std::set<std::string> l{"movel", "movelao", "moveldo", "movelgo", "movelsync"};
  static const std::set<std::string> j{"movej", "movejao", "movejdo", "movejgo", "movejsync"};
  static const std::set<std::string> c{"movec", "movecao", "movecdo", "movecgo", "movecsync"};
  if (l.count(n)) return Move{1, 3, true, false};
  if (j.count(n)) return Move{1, 3, false, false};
  if (c.count(n)) return Move{2, 4, true, false};
  if (n == "triggl") return Move{1, 4, true, false};
  if (n == "triggj") return Move{1, 4, false, false};
  if (n == "triggc") return Move{2, 5, true, false};
  return std::nullopt;
}

// One argument of an instruction: its positional tokens and its optional arguments (\Name:=expr).
struct Argument {
  std::size_t first = 0, end = 0;
  std::map<std::string, std::pair<std::size_t, std::size_t>> options;  // lower-case name -> value tokens
};

std::vector<Argument> split_arguments(const Source& s, std::size_t k, std::size_t stop) {
  std::vector<Argument> out;
  Argument a;
  a.first = k;
  std::size_t positional_end = std::string::npos;
  auto finish = [&](std::size_t at) {
    a.end = positional_end == std::string::npos ? at : positional_end;
    if (a.end > a.first) out.push_back(a);
    a = Argument{};
    positional_end = std::string::npos;
  };
  int depth = 0;
  while (k < stop) {
    const Token& t = s.tokens[k];
    if (t.kind == Tok::punct && (t.text == "(" || t.text == "[" || t.text == "{")) ++depth;
    if (t.kind == Tok::punct && (t.text == ")" || t.text == "]" || t.text == "}")) --depth;
    if (depth == 0 && t.kind == Tok::punct && t.text == ",") {
      finish(k);
      a.first = ++k;
      continue;
    }
    if (depth == 0 && t.kind == Tok::punct && t.text == "\\" && k + 1 < stop) {
      if (positional_end == std::string::npos) positional_end = k;
      const std::string name = lower(s.tokens[k + 1].text);
      k += 2;
      std::size_t v = k, e = k;
      if (k < stop && s.tokens[k].text == ":=") {
        v = ++k;
        int d = 0;
        while (k < stop) {
          const Token& u = s.tokens[k];
          if (u.kind == Tok::punct && (u.text == "(" || u.text == "[" || u.text == "{")) ++d;
          if (u.kind == Tok::punct && (u.text == ")" || u.text == "]" || u.text == "}")) --d;
          if (d == 0 && u.kind == Tok::punct && (u.text == "," || u.text == "\\")) break;
          ++k;
        }
        e = k;
      }
      a.options[name] = {v, e};
      continue;
    }
    ++k;
  }
  finish(stop);
  return out;
}

class RapidReader {
 public:
  RapidReader(const ProgramFile& program, const std::vector<ProgramFile>& includes, const robot::MdhModel& robot,
              const RapidReadOptions& options)
      : robot_(robot), options_(options) {
    sources_.reserve(1 + includes.size());
    sources_.push_back(Source{&program, tokenize(program)});
    for (const ProgramFile& f : includes) sources_.push_back(Source{&f, tokenize(f)});
    for (std::size_t i = 0; i < sources_.size(); ++i) collect_declarations(sources_[i], i == 0);
  }

  std::vector<ProgramTarget> targets() {
    const Source& s = sources_.front();
    std::vector<ProgramTarget> out;
    bool conf_l = true, conf_j = true;
    std::string conf_l_at, conf_j_at;
    for (std::size_t k = 0; k < s.tokens.size(); ++k) {
      const Token& t = s.tokens[k];
      if (t.kind != Tok::ident || (k > 0 && (s.tokens[k - 1].text == "\\" || s.tokens[k - 1].text == "."))) continue;
      const std::string w = lower(t.text);
      if ((w == "confl" || w == "confj") && s.is(k + 1, "\\")) {
        const bool on = s.is(k + 2, "On");
        (w == "confl" ? conf_l : conf_j) = on;
        (w == "confl" ? conf_l_at : conf_j_at) = (w == "confl" ? "ConfL\\" : "ConfJ\\") + std::string(on ? "On" : "Off") +
                                                 " (line " + std::to_string(s.line(k)) + ")";
        continue;
      }
      const std::optional<Move> move = move_of(t.text);
      if (!move || s.is(k + 1, "(") || s.is(k + 1, ":=")) continue;
      std::size_t stop = k + 1;
      int depth = 0;
      while (stop < s.tokens.size() && !(depth == 0 && s.tokens[stop].text == ";")) {
        const std::string& u = s.tokens[stop].text;
        if (s.tokens[stop].kind == Tok::punct && (u == "(" || u == "[" || u == "{")) ++depth;
        if (s.tokens[stop].kind == Tok::punct && (u == ")" || u == "]" || u == "}")) --depth;
        ++stop;
      }
      const std::vector<Argument> args = split_arguments(s, k + 1, stop);
      const std::size_t line = s.line(k);
      if (move->joints) {
        ProgramTarget p;
        p.file = s.file->path;
        p.line = line;
        p.kind = TargetKind::joints;
        p.label = args.empty() ? t.text : short_text(s.text(args[0].first, args[0].end));
        p.note = t.text + ": a joint target, sent as written (no Cartesian correction applies)";
        out.push_back(std::move(p));
        k = stop;
        continue;
      }
      const bool conf_on = move->linear ? conf_l : conf_j;
      const std::string off_by = move->linear ? conf_l_at : conf_j_at;
      std::string tool_name, wobj_name = "wobj0";
      Eigen::Isometry3d tool = Eigen::Isometry3d::Identity(), wobj = Eigen::Isometry3d::Identity();
      std::string refusal;
      if (static_cast<int>(args.size()) <= move->tool_index) {
        refusal = t.text + " with " + std::to_string(args.size()) + " arguments: expected the tool as argument " +
                  std::to_string(move->tool_index + 1);
      } else {
        const Argument& ta = args[static_cast<std::size_t>(move->tool_index)];
        tool_name = s.text(ta.first, ta.end);
        refusal = resolve_tool(tool_name, tool);
        for (const Argument& a : args) {
          const auto o = a.options.find("wobj");
          if (o != a.options.end()) wobj_name = s.text(o->second.first, o->second.second);
        }
        if (refusal.empty()) refusal = resolve_wobj(wobj_name, wobj);
      }
      for (int n = 0; n < move->target_count && n < static_cast<int>(args.size()); ++n) {
        ProgramTarget p;
        p.file = s.file->path;
        p.line = line;
        p.tool_name = tool_name;
        p.tool = tool;
        p.frame_name = wobj_name;
        p.frame = wobj;
        p.refusal = refusal;
        const std::string role = move->target_count == 2 ? (n == 0 ? " CirPoint" : " ToPoint") : "";
        read_target(s, args[static_cast<std::size_t>(n)], t.text + role, p);
        if (p.kind == TargetKind::literal && p.refusal.empty() && p.configuration.matches) {
          p.configuration.ignored = !conf_on;
          p.configuration.off_by = off_by;
        }
        out.push_back(std::move(p));
      }
      k = stop;
    }
    return out;
  }

 private:
  static std::string short_text(std::string text) {
    if (text.size() > 60) text = text.substr(0, 57) + "...";
    return text;
  }

  void collect_declarations(const Source& s, bool in_program) {
    for (std::size_t k = 0; k + 2 < s.tokens.size(); ++k) {
      const std::string w = lower(s.tokens[k].text);
      if (s.tokens[k].kind != Tok::ident) continue;
      if (w == "const" || w == "pers" || w == "var") {
        Declaration d;
        d.source = &s;
        d.in_program = in_program;
        d.storage = s.tokens[k].text;
        d.type = lower(s.tokens[k + 1].text);
        d.name = s.tokens[k + 2].text;
        d.name_token = k + 2;
        std::size_t j = k + 3;
        if (s.is(j, "{")) {
          d.array = true;
          j = skip_group(s, j);
        }
        if (s.is(j, ":=")) {
          ++j;
          std::size_t stop = j;
          while (stop < s.tokens.size() && s.tokens[stop].text != ";") stop = s.is(stop, "[") ? skip_group(s, stop) : stop + 1;
          d.value = parse_value(s, j, stop);
        }
        if (d.type == "robtarget" || d.type == "tooldata" || d.type == "wobjdata")
          declarations_[d.type].emplace(lower(d.name), std::move(d));
        k = j > k ? j - 1 : k;
        continue;
      }
      // A robtarget assigned in a routine is a run-time value (p := Offs(...), p := CRobT(), p.trans.x := ...).
      if (in_program && (k == 0 || s.tokens[k - 1].text == ";" || s.tokens[k - 1].text == ")" ||
                         s.tokens[k - 1].kind == Tok::ident)) {
        std::size_t j = k + 1;
        while (j < s.tokens.size() && (s.is(j, ".") || s.is(j, "{"))) j = s.is(j, "{") ? skip_group(s, j) : j + 2;
        if (s.is(j, ":=")) {
          std::size_t stop = j;
          while (stop < s.tokens.size() && s.tokens[stop].text != ";") ++stop;
          assigned_.emplace(lower(s.tokens[k].text), "assigned at run time (line " + std::to_string(s.line(k)) + ": " +
                                                         short_text(s.text(k, stop)) + ")");
        }
      }
    }
  }

  const Declaration* find(const std::string& type, const std::string& name) const {
    const auto t = declarations_.find(type);
    if (t == declarations_.end()) return nullptr;
    const auto d = t->second.find(lower(name));
    return d == t->second.end() ? nullptr : &d->second;
  }

  std::string where(const Declaration& d) const {
    return d.source->file->path + ":" + std::to_string(d.source->line(d.name_token));
  }

  std::string resolve_tool(const std::string& name, Eigen::Isometry3d& tool) const {
    for (const auto& [n, t] : options_.tools)
      if (lower(n) == lower(name)) {
        tool = t;
        return {};
      }
    if (lower(name) == "tool0") return {};
    const Declaration* d = find("tooldata", name);
    if (!d)
      return "tool '" + name + "' is declared nowhere (not in the module nor in an --include; give --tool " + name +
             "=X,Y,Z[,RX,RY,RZ] or --include the module that declares it)";
    if (!d->value || d->array)
      return "tool '" + name + "' (" + where(*d) + ") has no literal value to read (give --tool " + name + "=...)";
    const Node& v = *d->value;
    std::string problem;
    if (!v.aggregate || v.items.size() < 2 || !v.items[1].aggregate || v.items[1].items.size() != 2)
      return "tool '" + name + "' (" + where(*d) + ") is not tooldata [robhold,[[x,y,z],[q1,q2,q3,q4]],load]";
    if (lower(d->source->text(v.items[0].first, v.items[0].end)) == "false")
      return "tool '" + name + "' (" + where(*d) + ") is a stationary tool (robhold FALSE): not supported";
    const auto pose = pose_of(v.items[1].items[0], v.items[1].items[1], problem);
    if (!pose) return "tool '" + name + "' (" + where(*d) + "): " + problem;
    tool = *pose;
    return {};
  }

  std::string resolve_wobj(const std::string& name, Eigen::Isometry3d& frame) const {
    for (const auto& [n, t] : options_.wobjs)
      if (lower(n) == lower(name)) {
        frame = t;
        return {};
      }
    if (lower(name) == "wobj0") return {};
    const Declaration* d = find("wobjdata", name);
    if (!d)
      return "work object '" + name + "' is declared nowhere (not in the module nor in an --include; give --wobj " + name +
             "=X,Y,Z[,RX,RY,RZ] or --include the module that declares it)";
    if (!d->value || d->array) return "work object '" + name + "' (" + where(*d) + ") has no literal value to read";
    const Node& v = *d->value;
    if (!v.aggregate || v.items.size() != 5 || !v.items[3].aggregate || v.items[3].items.size() != 2 || !v.items[4].aggregate ||
        v.items[4].items.size() != 2)
      return "work object '" + name + "' (" + where(*d) + ") is not wobjdata [robhold,ufprog,ufmec,uframe,oframe]";
    const Source& s = *d->source;
    if (lower(s.text(v.items[0].first, v.items[0].end)) == "true")
      return "work object '" + name + "' (" + where(*d) + ") is held by the robot (robhold TRUE, stationary tool): not supported";
    const std::string ufmec = s.text(v.items[2].first, v.items[2].end);
    if (lower(s.text(v.items[1].first, v.items[1].end)) == "false" || (ufmec != "\"\"" && !ufmec.empty()))
      return "work object '" + name + "' (" + where(*d) + ") is moved by a mechanical unit (" + ufmec +
             "): a coordinated frame, not supported";
    std::string problem;
    const auto uframe = pose_of(v.items[3].items[0], v.items[3].items[1], problem);
    if (!uframe) return "work object '" + name + "' (" + where(*d) + ") uframe: " + problem;
    const auto oframe = pose_of(v.items[4].items[0], v.items[4].items[1], problem);
    if (!oframe) return "work object '" + name + "' (" + where(*d) + ") oframe: " + problem;
    frame = *uframe * *oframe;
    return {};
  }

  // Fills `p` from the target argument `a` of a move: a literal, a declared robtarget, or an expression.
  void read_target(const Source& s, const Argument& a, const std::string& instruction, ProgramTarget& p) {
    if (a.end <= a.first) {
      p.kind = TargetKind::computed;
      p.label = instruction;
      p.refusal = "no target argument";
      return;
    }
    if (s.is(a.first, "[")) {
      std::size_t k = a.first;
      const Node n = parse_value(s, k, a.end);
      p.label = instruction + " inline";
      read_literal(s, n, p, "");
      return;
    }
    const std::string name = s.tokens[a.first].text;
    const bool single = a.end == a.first + 1 && s.tokens[a.first].kind == Tok::ident;
    const bool element = s.tokens[a.first].kind == Tok::ident && s.is(a.first + 1, "{") && a.end == a.first + 4 &&
                         s.tokens[a.first + 2].kind == Tok::number && s.is(a.first + 3, "}");
    if (single || element) {
      p.label = s.text(a.first, a.end);
      const Declaration* d = find("robtarget", name);
      const auto runtime = assigned_.find(lower(name));
      if (runtime != assigned_.end()) {
        p.kind = TargetKind::computed;
        p.note = p.label + " is " + runtime->second;
        return;
      }
      if (!d) {
        p.kind = TargetKind::literal;
        p.refusal = joined_refusal(p.refusal, "robtarget '" + name + "' is declared nowhere (not in the module nor in an --include)");
        return;
      }
      if (!d->value) {
        p.kind = TargetKind::computed;
        p.note = p.label + " is declared without a value (" + where(*d) + "): set at run time";
        return;
      }
      if (!d->in_program) {
        p.refusal = joined_refusal(p.refusal, "robtarget '" + name + "' is declared in " + where(*d) +
                                                  ", an --include: only --program is rewritten");
        return;
      }
      const Node* n = &*d->value;
      if (!n->aggregate) {
        p.kind = TargetKind::computed;
        p.note = p.label + " is declared := " + short_text(d->source->text(n->first, n->end)) + " (" + where(*d) +
                 "): computed at run time";
        return;
      }
      if (element) {
        const auto index = static_cast<std::size_t>(s.tokens[a.first + 2].value);
        if (!d->array || !n->aggregate || index < 1 || index > n->items.size()) {
          p.refusal = joined_refusal(p.refusal, p.label + ": no such element of " + d->name + " (" + where(*d) + ")");
          return;
        }
        n = &n->items[index - 1];
      } else if (d->array) {
        p.refusal = joined_refusal(p.refusal, p.label + " is an array (" + where(*d) + ")");
        return;
      }
      read_literal(*d->source, *n, p, lower(d->name) + (element ? "{" + std::to_string(static_cast<long>(s.tokens[a.first + 2].value)) + "}" : ""));
      return;
    }
    // An expression: a function of other data (Offs, RelTool, CalcRobT, ...), computed by the controller.
    p.kind = TargetKind::computed;
    p.label = short_text(s.text(a.first, a.end));
    std::vector<std::string> depends;
    for (std::size_t k = a.first; k < a.end; ++k)
      if (s.tokens[k].kind == Tok::ident && !s.is(k + 1, "(") && std::find(depends.begin(), depends.end(), s.tokens[k].text) == depends.end())
        depends.push_back(s.tokens[k].text);
    std::string on;
    for (const std::string& d : depends) on += (on.empty() ? "" : ", ") + d;
    p.note = "computed by the controller at run time" + (on.empty() ? std::string() : " from " + on) +
             " (the tool " + p.tool_name + ", work object " + p.frame_name + "); not a literal, not rewritten";
  }

  static std::string joined_refusal(const std::string& a, const std::string& b) { return a.empty() ? b : a; }

  void read_literal(const Source&, const Node& n, ProgramTarget& p, const std::string& shared_key) {
    p.kind = TargetKind::literal;
    p.shared_key = shared_key;
    if (!p.refusal.empty()) return;
    if (!n.aggregate || n.items.size() != 4 || !numbers(n.items[2], 4) || !n.items[3].aggregate) {
      p.refusal = "robtarget is not [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]] with numbers";
      return;
    }
    std::string problem;
    const auto pose = pose_of(n.items[0], n.items[1], problem);
    if (!pose) {
      p.refusal = "robtarget: " + problem;
      return;
    }
    p.pose_in_frame = *pose;
    AbbConfdata want;
    want.cf1 = static_cast<int>(n.items[2].items[0].number->value);
    want.cf4 = static_cast<int>(n.items[2].items[1].number->value);
    want.cf6 = static_cast<int>(n.items[2].items[2].number->value);
    want.cfx = static_cast<int>(n.items[2].items[3].number->value);
    const robot::MdhModel robot = robot_;
    p.configuration.matches = [robot, want](const robot::JointVector& q) { return abb_confdata(robot, q) == want; };
    p.configuration.text = want.to_string();
    std::array<NumberLiteral, 3> xyz;
    std::array<NumberLiteral, 4> quat;
    for (int i = 0; i < 3; ++i) xyz[static_cast<std::size_t>(i)] = *n.items[0].items[static_cast<std::size_t>(i)].number;
    for (int i = 0; i < 4; ++i) quat[static_cast<std::size_t>(i)] = *n.items[1].items[static_cast<std::size_t>(i)].number;
    const Eigen::Isometry3d old = *pose;
    p.rewrite = [xyz, quat, old](const Eigen::Isometry3d& now) {
      std::vector<Replacement> r;
      for (int i = 0; i < 3; ++i) {
        const NumberLiteral& lit = xyz[static_cast<std::size_t>(i)];
        // Numbers that do not change at the written precision keep their spelling.
        if (std::abs(now.translation()[i] - lit.value) >= 0.0005) r.push_back({lit.span, format_program_number(now.translation()[i], 3)});
      }
      if (robot::rotation_log(now.linear() * old.linear().transpose()).norm() >= 1e-7) {
        Eigen::Quaterniond q(now.linear());
        const Eigen::Quaterniond was(old.linear());
        if (q.w() * quat[0].value + q.x() * quat[1].value + q.y() * quat[2].value + q.z() * quat[3].value < 0.0) q.coeffs() = -q.coeffs();
        const double v[4] = {q.w(), q.x(), q.y(), q.z()};
        for (int i = 0; i < 4; ++i) r.push_back({quat[static_cast<std::size_t>(i)].span, format_program_number(v[i], 8)});
        (void)was;
      }
      return r;
    };
  }

  const robot::MdhModel& robot_;
  const RapidReadOptions& options_;
  std::vector<Source> sources_;
  std::map<std::string, std::map<std::string, Declaration>> declarations_;  // type -> lower name -> declaration
  std::map<std::string, std::string> assigned_;                               // lower name -> where
};

}  // namespace

std::vector<ProgramTarget> read_rapid_targets(const ProgramFile& program, const std::vector<ProgramFile>& includes,
                                              const robot::MdhModel& robot, const RapidReadOptions& options) {
  RapidReader reader(program, includes, robot, options);
  return reader.targets();
}

}  // namespace errfield::programs
