#pragma once
/// Reading a JSON input file (robot description, simulation set-up, fitted model) so that every
/// defect is bad input naming the file: a directory or unreadable path, invalid JSON
/// (`file:line: not valid JSON: ...`), a number beyond the range of a double (`1e400`) and a key
/// given twice in one object (`file:line: key 'links[2].a_mm' given twice`: nlohmann::json would
/// silently keep the last one, so a hand-edited file could lose an edit without a word).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"

namespace errfield {

/// Parses `text` read from `source`. Throws InputError naming `source`, the line and (where it
/// applies) the key path.
nlohmann::json parse_json_text(std::string_view text, const std::string& source);

/// Reads and parses the file at `path` (see parse_json_text). `what` names the kind of file in the
/// messages ("robot description"). Input limits (docs/reliability.md, "Input limits"): at most
/// 256 MiB, nested at most 100 levels (parse_json_text), and the top level must be an object (every errfield JSON file is one); InputError else.
nlohmann::json read_json_file(const std::filesystem::path& path, const std::string& what);

/// The integer `v` holds when it is a JSON integer (`8`, not `8.0` or `8.5`) within [lo, hi]; nothing
/// otherwise (then the caller names the member and the range). nlohmann's get<int>() keeps the low 32
/// bits of a 64-bit value: a hand-edited degree 4294967304 was read as 8.
std::optional<std::int64_t> json_integer_in(const nlohmann::json& v, std::int64_t lo, std::int64_t hi);

/// Runs `f()` (reading fields of a JSON document from `source`) and turns any nlohmann::json
/// exception a field access lets through (a wrong type the reader did not check) into an
/// InputError naming `source`: bad input, never an internal error.
template <class F>
auto with_json_source(const std::string& source, F f) {
  try {
    return f();
  } catch (const nlohmann::json::exception& e) {
    std::string what = e.what();
    if (const auto bracket = what.find("] "); what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos)
      what = what.substr(bracket + 2);
    throw InputError(source + ": unexpected JSON content: " + what, source);
  }
}

}  // namespace errfield
