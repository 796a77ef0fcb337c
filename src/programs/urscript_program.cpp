#include "errfield/programs/urscript_program.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <optional>
#include <set>

#include "errfield/error.hpp"
#include "errfield/programs/program_lexer.hpp"
#include "errfield/robot/pose.hpp"

namespace errfield::programs {

Eigen::Isometry3d urscript_pose(const std::array<double, 6>& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << 1000.0 * p[0], 1000.0 * p[1], 1000.0 * p[2];
  t.linear() = robot::rotation_exp(Eigen::Vector3d(p[3], p[4], p[5]));
  return t;
}

std::array<double, 6> urscript_pose_of(const Eigen::Isometry3d& pose_mm) {
  const Eigen::Vector3d w = robot::rotation_log(pose_mm.linear());
  return {pose_mm.translation().x() / 1000.0, pose_mm.translation().y() / 1000.0, pose_mm.translation().z() / 1000.0, w.x(), w.y(), w.z()};
}

// Named, not anonymous: the programs folder is compiled as a unity build beside other readers.
namespace urscript_reading {

using Kind = LexKind;

using Token = LexToken;

std::string short_text(std::string text) {
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

struct Script {
  const ProgramFile* file = nullptr;
  std::vector<Token> tokens;
  std::vector<std::pair<std::size_t, std::size_t>> statements;  // token ranges
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw InputError(file->path + ":" + std::to_string(line) + ": " + what, file->path, line);
  }
  bool is(std::size_t k, std::size_t end, const char* text) const { return k < end && tokens[k].kind != Kind::string && tokens[k].text == text; }
  std::string text(std::size_t a, std::size_t b) const {
    if (a >= b) return {};
    return collapse_spaces(std::string_view(file->bytes).substr(tokens[a].span.begin, tokens[b - 1].span.end - tokens[a].span.begin));
  }
};

// URScript's lexical elements, `#` comments dropped; statements end at the end of a line outside
// brackets.
Script tokenize(const ProgramFile& f) {
  Script sc;
  sc.file = &f;
  LexicalRules rules;
  rules.comment = '#';
  rules.quotes = "\"'";
  rules.backslash_escape = true;
  rules.string_ends_at_line = true;
  rules.two_char_punct = {"==", "!=", "<=", ">="};
  sc.tokens = lex_program(f, rules).tokens;
  int depth = 0;
  std::size_t from = 0, open_line = 0;
  for (std::size_t k = 0; k < sc.tokens.size(); ++k) {
    const Token& t = sc.tokens[k];
    if (t.kind == Kind::punct && (t.text == "(" || t.text == "[")) {
      if (depth++ == 0) open_line = t.line;
    }
    if (t.kind == Kind::punct && (t.text == ")" || t.text == "]")) --depth;
    const bool last = k + 1 == sc.tokens.size() || (depth <= 0 && sc.tokens[k + 1].line != t.line);
    if (last) {
      sc.statements.push_back({from, k + 1});
      from = k + 1;
      depth = 0;
    }
  }
  if (depth > 0) sc.fail(open_line, "unterminated bracket");
  return sc;
}

// Six signed numbers in brackets: p[...] (pose) or [...] (joints); tokens [k, end).
struct Six {
  std::array<NumberLiteral, 6> numbers;
  std::array<std::string, 6> spelled;
  std::size_t end = 0;  // past the ']'
};

std::optional<Six> six_numbers(const Script& s, std::size_t k, std::size_t end) {
  if (!s.is(k, end, "[")) return std::nullopt;
  Six six;
  ++k;
  for (std::size_t n = 0; n < 6; ++n) {
    double sign = 1.0;
    std::size_t first = k;
    if (s.is(k, end, "-") || s.is(k, end, "+")) {
      sign = s.tokens[k].text == "-" ? -1.0 : 1.0;
      ++k;
    }
    if (k >= end || s.tokens[k].kind != Kind::number) return std::nullopt;
    six.numbers[n] = NumberLiteral{{s.tokens[first].span.begin, s.tokens[k].span.end}, sign * s.tokens[k].value};
    six.spelled[n] = s.file->bytes.substr(s.tokens[first].span.begin, s.tokens[k].span.end - s.tokens[first].span.begin);
    ++k;
    if (!s.is(k, end, n == 5 ? "]" : ",")) return std::nullopt;
    ++k;
  }
  six.end = k;
  return six;
}

std::array<double, 6> values(const Six& six) {
  std::array<double, 6> v{};
  for (std::size_t i = 0; i < 6; ++i) v[i] = six.numbers[i].value;
  return v;
}

struct Assignment {
  std::size_t line = 0;
  std::size_t count = 0;          // how many times the name is assigned
  std::optional<Six> pose, joints;  // the value when it is p[6 numbers] / [6 numbers]
  std::string expression;
};

// The rotation vector of `r` nearest `written` (the same rotation by angle theta or theta - 2 pi).
Eigen::Vector3d rotation_vector_near(const Eigen::Matrix3d& r, const Eigen::Vector3d& written) {
  const Eigen::Vector3d w = robot::rotation_log(r);
  const double angle = w.norm();
  if (angle < 1e-12) return w;
  const Eigen::Vector3d other = w * (angle - 2.0 * std::numbers::pi) / angle;
  return (other - written).norm() < (w - written).norm() ? other : w;
}

int decimals_of(const std::string& spelled) {
  const auto dot = spelled.find('.');
  if (dot == std::string::npos || spelled.find_first_of("eE") != std::string::npos) return 0;
  return static_cast<int>(spelled.size() - dot - 1);
}

class UrscriptReader {
 public:
  UrscriptReader(const ProgramFile& program, const UrscriptReadOptions& options) : s_(tokenize(program)), options_(options) {
    for (const auto& [a, e] : s_.statements) {
      std::size_t k = a;
      if (s_.is(k, e, "global") || s_.is(k, e, "local")) ++k;
      if (k + 1 >= e || s_.tokens[k].kind != Kind::ident || !s_.is(k + 1, e, "=")) continue;
      Assignment& as = assigned_[s_.tokens[k].text];
      ++as.count;
      as.line = s_.tokens[a].line;
      as.pose.reset();
      as.joints.reset();
      as.expression = s_.text(k + 2, e);
      if (s_.is(k + 2, e, "p")) {
        if (auto six = six_numbers(s_, k + 3, e); six && six->end == e) as.pose = six;
      } else if (auto six = six_numbers(s_, k + 2, e); six && six->end == e) {
        as.joints = six;
      }
    }
  }

  std::vector<ProgramTarget> targets() {
    std::vector<ProgramTarget> out;
    std::string tool_name = "tcp";
    std::optional<Eigen::Isometry3d> tool;
    std::string tool_unknown =
        "no set_tcp before this move: the TCP in force is the installation's active TCP, which the program does not hold (give "
        "--tool tcp=X,Y,Z,RX,RY,RZ with set_tcp's numbers: m and a rotation vector in rad)";
    if (auto t = options_.tools.find("tcp"); t != options_.tools.end()) {
      tool = t->second;
      tool_unknown.clear();
    }
    static const std::set<std::string> moves{"movel", "movej", "movep", "movec"};
    for (std::size_t k = 0; k + 1 < s_.tokens.size(); ++k) {
      const Token& t = s_.tokens[k];
      if (t.kind != Kind::ident || !s_.is(k + 1, s_.tokens.size(), "(") || (k > 0 && s_.is(k - 1, k, "def"))) continue;
      if (t.text != "set_tcp" && !moves.count(t.text)) continue;
      const std::size_t close = close_paren(k + 1);
      const auto args = arguments(k + 2, close - 1);
      if (t.text == "set_tcp") {
        tool_name = "set_tcp (line " + std::to_string(t.line) + ")";
        std::optional<std::array<double, 6>> v;
        if (!args.empty()) v = pose_value(args[0].first, args[0].second);
        if (v) {
          tool = urscript_pose(*v);
          tool_unknown.clear();
        } else {
          tool.reset();
          tool_unknown = "the TCP is set at line " + std::to_string(t.line) + " to " + short_text(s_.text(k, close)) +
                         ", computed at run time: not known here";
        }
        continue;
      }
      const std::size_t count = t.text == "movec" ? 2 : 1;
      for (std::size_t n = 0; n < count; ++n) {
        ProgramTarget p;
        p.file = s_.file->path;
        p.line = t.line;
        p.tool_name = tool_name;
        if (tool) p.tool = *tool;
        p.refusal = tool_unknown;
        const std::string role = count == 2 ? (n == 0 ? " via" : " to") : "";
        if (n >= args.size()) {
          p.kind = TargetKind::computed;
          p.label = t.text + role;
          p.refusal = t.text + " without its" + (role.empty() ? " pose" : role + " pose");
        } else {
          read_target(args[n].first, args[n].second, t.text + role, p);
        }
        out.push_back(std::move(p));
      }
      k = close - 1;
    }
    return out;
  }

 private:
  std::size_t close_paren(std::size_t k) const {
    int depth = 0;
    for (; k < s_.tokens.size(); ++k) {
      const Token& t = s_.tokens[k];
      if (t.kind == Kind::punct && (t.text == "(" || t.text == "[")) ++depth;
      if (t.kind == Kind::punct && (t.text == ")" || t.text == "]"))
        if (--depth == 0) return k + 1;
    }
    s_.fail(s_.tokens.back().line, "unterminated bracket");
  }

  // The positional arguments (before any name=value) of a call's tokens [a, e).
  std::vector<std::pair<std::size_t, std::size_t>> arguments(std::size_t a, std::size_t e) const {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    int depth = 0;
    std::size_t from = a;
    for (std::size_t k = a; k <= e; ++k) {
      const bool end = k == e;
      if (!end) {
        const Token& t = s_.tokens[k];
        if (t.kind == Kind::punct && (t.text == "(" || t.text == "[")) ++depth;
        if (t.kind == Kind::punct && (t.text == ")" || t.text == "]")) --depth;
        if (!(depth == 0 && t.kind == Kind::punct && t.text == ",")) continue;
      }
      if (k > from && !(s_.tokens[from].kind == Kind::ident && s_.is(from + 1, k, "="))) out.push_back({from, k});
      from = k + 1;
    }
    return out;
  }

  const Assignment* variable(std::size_t a, std::size_t e) const {
    if (e != a + 1 || s_.tokens[a].kind != Kind::ident) return nullptr;
    const auto v = assigned_.find(s_.tokens[a].text);
    return v == assigned_.end() ? nullptr : &v->second;
  }

  std::optional<std::array<double, 6>> pose_value(std::size_t a, std::size_t e) const {
    if (s_.is(a, e, "p"))
      if (auto six = six_numbers(s_, a + 1, e); six && six->end == e) return values(*six);
    if (const Assignment* v = variable(a, e); v && v->count == 1 && v->pose) return values(*v->pose);
    return std::nullopt;
  }

  void read_target(std::size_t a, std::size_t e, const std::string& move, ProgramTarget& p) {
    const std::string written = short_text(s_.text(a, e));
    if (s_.is(a, e, "p"))
      if (auto six = six_numbers(s_, a + 1, e); six && six->end == e) {
        p.label = move + " " + written;
        literal(*six, "", p);
        return;
      }
    if (auto six = six_numbers(s_, a, e); six && six->end == e) {
      p.label = move + " " + written;
      p.kind = TargetKind::joints;
      p.refusal.clear();
      p.note = move + " to a joint list: a joint target, sent as written (no Cartesian correction applies)";
      return;
    }
    if (e == a + 1 && s_.tokens[a].kind == Kind::ident) {
      const std::string name = s_.tokens[a].text;
      p.label = name;
      const Assignment* v = variable(a, e);
      if (!v) {
        p.refusal = "variable '" + name + "' is assigned nowhere in the program";
        return;
      }
      if (v->joints && v->count == 1) {
        p.kind = TargetKind::joints;
        p.refusal.clear();
        p.note = name + " (line " + std::to_string(v->line) + ") is a joint list: sent as written (no Cartesian correction applies)";
        return;
      }
      if (v->count != 1 || !v->pose) {
        p.kind = TargetKind::computed;
        p.note = name + (v->count != 1 ? " is assigned " + std::to_string(v->count) + " times (last at line " + std::to_string(v->line) + ")"
                                       : " is assigned " + short_text(v->expression) + " (line " + std::to_string(v->line) + ")") +
                 ": computed at run time, not rewritten";
        return;
      }
      literal(*v->pose, name, p);
      // Polyscope stores a waypoint twice: Name_p (pose) and Name_q (joints); the joints pick the solution.
      if (p.refusal.empty() && name.size() > 2 && name.substr(name.size() - 2) == "_p") {
        const auto q = assigned_.find(name.substr(0, name.size() - 2) + "_q");
        if (q != assigned_.end() && q->second.count == 1 && q->second.joints) {
          robot::JointVector stored;
          for (int i = 0; i < 6; ++i) stored[i] = q->second.joints->numbers[static_cast<std::size_t>(i)].value * 180.0 / std::numbers::pi;
          // Whole turns apart are one configuration: every UR joint turns +-360 deg, and the IK may
          // return a joint one turn from the stored one.
          p.configuration.matches = [stored](const robot::JointVector& joints) {
            for (int i = 0; i < 6; ++i) {
              const double d = joints[i] - stored[i];
              if (std::abs(d - 360.0 * std::round(d / 360.0)) >= kUrStoredJointsDeg) return false;
            }
            return true;
          };
          p.configuration.text = q->first + " (the joints stored beside " + name + ", within " +
                                 std::to_string(static_cast<int>(kUrStoredJointsDeg)) + " deg)";
        }
      }
      return;
    }
    p.kind = TargetKind::computed;
    p.label = move + " " + written;
    std::vector<std::string> depends;
    for (std::size_t k = a; k < e; ++k)
      if (s_.tokens[k].kind == Kind::ident && !s_.is(k + 1, e, "(") && !s_.is(k + 1, e, "=") && s_.tokens[k].text != "p" &&
          std::find(depends.begin(), depends.end(), s_.tokens[k].text) == depends.end())
        depends.push_back(s_.tokens[k].text);
    std::string on;
    for (const std::string& d : depends) on += (on.empty() ? "" : ", ") + d;
    p.note = "computed by the controller at run time" + (on.empty() ? std::string() : " from " + on) + "; not a literal, not rewritten";
  }

  void literal(const Six& six, const std::string& shared_key, ProgramTarget& p) {
    p.kind = TargetKind::literal;
    p.shared_key = shared_key;
    if (!p.refusal.empty()) return;
    p.pose_in_frame = urscript_pose(values(six));
    p.frame_name = "base";
    p.rewrite = [six](const Eigen::Isometry3d& now) {
      std::vector<Replacement> r;
      const Eigen::Vector3d written_w(six.numbers[3].value, six.numbers[4].value, six.numbers[5].value);
      const Eigen::Vector3d w = rotation_vector_near(now.linear(), written_w);
      const double v[6] = {now.translation().x() / 1000.0, now.translation().y() / 1000.0, now.translation().z() / 1000.0, w.x(), w.y(), w.z()};
      for (std::size_t i = 0; i < 6; ++i) {
        const int decimals = std::max(decimals_of(six.spelled[i]), 6);
        if (std::abs(v[i] - six.numbers[i].value) >= 0.5 * std::pow(10.0, -decimals))
          r.push_back({six.numbers[i].span, format_program_number_like(six.spelled[i], v[i], decimals)});
      }
      return r;
    };
  }

  Script s_;
  const UrscriptReadOptions& options_;
  std::map<std::string, Assignment> assigned_;
};

}  // namespace urscript_reading

std::vector<ProgramTarget> read_urscript_targets(const ProgramFile& program, const UrscriptReadOptions& options) {
  urscript_reading::UrscriptReader reader(program, options);
  return reader.targets();
}

}  // namespace errfield::programs
