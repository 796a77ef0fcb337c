#include "errfield/json_file.hpp"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <set>
#include <vector>

#include "errfield/error.hpp"

namespace errfield {
namespace {

using json = nlohmann::json;

constexpr std::size_t kMaxJsonDepth = 100;  // objects and arrays, nested

// Iterator over the text that records how far the parser has read: the SAX key() event carries no
// position, and a duplicate key's line is wanted.
class CountingIterator {
 public:
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;
  CountingIterator(const char* p, const char* begin, std::size_t* consumed) : p_(p), begin_(begin), consumed_(consumed) {}
  reference operator*() const { return *p_; }
  CountingIterator& operator++() {
    ++p_;
    *consumed_ = static_cast<std::size_t>(p_ - begin_);
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator old = *this;
    ++*this;
    return old;
  }
  bool operator==(const CountingIterator& o) const { return p_ == o.p_; }
  bool operator!=(const CountingIterator& o) const { return p_ != o.p_; }

 private:
  const char* p_;
  const char* begin_;
  std::size_t* consumed_;
};

// A SAX pass that keeps the path to the current value ("links[2].a_mm") and stops at the first
// duplicate key or parse error, remembering where.
class StrictSax : public nlohmann::json_sax<json> {
 public:
  std::string message;    // empty: no error
  std::size_t offset = 0; // byte offset of the error
  std::size_t consumed = 0;  // bytes the parser has read so far (CountingIterator)

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override {
    if (too_deep()) return false;
    frames_.push_back({true, {}, {}, 0});
    return true;
  }
  bool key(string_t& k) override {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      f.key = k;
      offset = consumed > 0 ? consumed - 1 : 0;  // the key's closing quote (or one past it)
      message = "key '" + path() + "' given twice (JSON keeps only one of them; remove the other)";
      return false;
    }
    f.key = k;
    return true;
  }
  bool end_object() override { return end(); }
  bool start_array(std::size_t) override {
    if (too_deep()) return false;
    frames_.push_back({false, {}, {}, 0});
    return true;
  }
  bool end_array() override { return end(); }
  bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception& ex) override {
    offset = position;
    if (ex.id == 406) {  // number overflow
      message = "'" + token + "' is beyond the range of a double" + (frames_.empty() ? "" : " (at " + path() + ")");
    } else {
      std::string what = ex.what();
      // "[json.exception.parse_error.101] parse error at line 3, column 5: ..." without the tag
      if (const auto tag = what.find("] "); what.rfind("[json.exception", 0) == 0 && tag != std::string::npos)
        what = what.substr(tag + 2);
      message = "not valid JSON: " + what;
    }
    return false;
  }

  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.object) {
        if (!p.empty()) p += '.';
        p += f.key;
      } else {
        p += '[';
        p += std::to_string(f.index);
        p += ']';
      }
    }
    return p.empty() ? "(top level)" : p;
  }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;
    std::size_t index;
  };
  // The parser is iterative, but dump(), comparisons and messages that quote a value recurse once
  // per level: a 10^6-deep [[[...]]] would overflow the stack there.
  bool too_deep() {
    if (frames_.size() < kMaxJsonDepth) return false;
    offset = consumed > 0 ? consumed - 1 : 0;
    message = "nested more than " + std::to_string(kMaxJsonDepth) + " levels deep at " + path() +
              " (errfield's JSON files nest ~5; the limit is in docs/reliability.md, \"Input limits\")";
    return true;
  }
  bool value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
    return true;
  }
  bool end() {
    frames_.pop_back();
    return value();
  }
  // index counts the elements already seen, so while inside element i it is i (value() runs at its end)
  std::vector<Frame> frames_;
};

std::size_t line_at(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

}  // namespace

nlohmann::json parse_json_text(std::string_view text, const std::string& source) {
  StrictSax sax;
  const CountingIterator first(text.data(), text.data(), &sax.consumed);
  const CountingIterator last(text.data() + text.size(), text.data(), &sax.consumed);
  if (!json::sax_parse(first, last, &sax) || !sax.message.empty()) {
    if (sax.message.empty()) sax.message = "not valid JSON";
    const std::size_t line = line_at(text, sax.offset);
    throw InputError(source + ":" + std::to_string(line) + ": " + sax.message, source, line);
  }
  return json::parse(text.begin(), text.end());
}

std::optional<std::int64_t> json_integer_in(const nlohmann::json& v, std::int64_t lo, std::int64_t hi) {
  if (v.is_number_unsigned()) {
    const std::uint64_t u = v.get<std::uint64_t>();  // may exceed INT64_MAX: compare unsigned
    if (hi < 0 || u > static_cast<std::uint64_t>(hi)) return std::nullopt;
    const auto i = static_cast<std::int64_t>(u);
    return i >= lo ? std::optional<std::int64_t>(i) : std::nullopt;
  }
  if (!v.is_number_integer()) return std::nullopt;
  const std::int64_t i = v.get<std::int64_t>();
  return i >= lo && i <= hi ? std::optional<std::int64_t>(i) : std::nullopt;
}

nlohmann::json read_json_file(const std::filesystem::path& path, const std::string& what) {
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(name + ": is a directory, not a JSON file (" + what + ")", name);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open " + what + " '" + name + "'", name);
  // Bounded: a device such as /dev/zero must not be read until memory runs out.
  constexpr std::size_t kMaxBytes = std::size_t{256} << 20;
  std::string text;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxBytes)
      throw InputError(name + ": larger than 256 MB; not a " + what + " errfield can read", name);
  }
  if (in.bad()) throw InputError(name + ": read error", name);
  nlohmann::json j = parse_json_text(text, name);
  // Every errfield JSON file (model, robot description, simulation) is an object; say so here,
  // once, rather than let a reader's first j["key"] on an array fail as an internal type error.
  if (!j.is_object())
    throw InputError(name + ": the top level is " +
                         (j.is_null() ? std::string("null") : std::string(j.is_array() ? "an " : "a ") + j.type_name()) +
                         "; a " + what + " must be a JSON object ({ \"key\": value, ... })",
                     name, 1);
  return j;
}

}  // namespace errfield
