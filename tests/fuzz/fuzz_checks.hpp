#pragma once
// What each fuzz target checks, shared by the libFuzzer executables (tests/fuzz/fuzz_*.cpp) and
// the replay test (tests/fuzz/fuzz_replay_test.cpp), which runs every seed and every past crash
// (tests/fuzz/regressions/<target>/) through the same checks in the plain and sanitizer builds.
//
// A violated contract prints what went wrong and aborts: libFuzzer then saves the input, and in
// the replay test the process dies, which fails that test.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/mdh_model.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::fuzz {

[[noreturn]] inline void contract_violated(const char* what) {
  std::fprintf(stderr, "fuzz contract violated: %s\n", what);
  std::abort();
}
#define ERRFIELD_FUZZ_CHECK(cond) \
  do {                            \
    if (!(cond)) ::errfield::fuzz::contract_violated(#cond); \
  } while (0)

/// CsvTable::parse and the numeric readers: malformed input only ever raises InputError naming the
/// source (and the column, for a bad cell); a table that parses is consistent.
inline void check_csv(std::string_view text) {
  try {
    const auto table = CsvTable::parse(text, "fuzz.csv");
    const auto& header = table.header();
    ERRFIELD_FUZZ_CHECK(!header.empty());
    for (std::size_t r = 0; r < table.row_count(); ++r) {
      std::size_t text_bytes = 0;  // every cell of the row is there, and no more
      for (std::size_t c = 0; c < header.size(); ++c) text_bytes += table.cell(r, c).size();
      ERRFIELD_FUZZ_CHECK(text_bytes <= text.size());
      bool beyond_refused = false;
      try {
        (void)table.cell(r, header.size());
      } catch (const std::out_of_range&) {
        beyond_refused = true;
      }
      ERRFIELD_FUZZ_CHECK(beyond_refused);
      ERRFIELD_FUZZ_CHECK(table.line_of_row(r) >= 2);  // line 1 is at best the header
    }
    for (const auto& name : header) {
      ERRFIELD_FUZZ_CHECK(table.has_column(name));  // every header cell can be looked up by itself
      try {
        const auto values = table.numeric_column(name);
        ERRFIELD_FUZZ_CHECK(values.size() == table.row_count());
        for (double v : values) ERRFIELD_FUZZ_CHECK(std::isfinite(v));
      } catch (const InputError& e) {
        ERRFIELD_FUZZ_CHECK(e.file() == "fuzz.csv" && !e.column().empty() && e.row() >= 2);
      }
    }
    try {
      const auto m = table.numeric_columns(header);
      ERRFIELD_FUZZ_CHECK(static_cast<std::size_t>(m.rows()) == table.row_count());
    } catch (const InputError&) {
    }
  } catch (const InputError& e) {
    ERRFIELD_FUZZ_CHECK(e.file() == "fuzz.csv");
  }
}

/// Two models are the same when every parameter that matters for their kind is equal.
inline bool same_model(const VariogramModel& a, const VariogramModel& b) {
  if (a.components().size() != b.components().size()) return false;
  for (std::size_t i = 0; i < a.components().size(); ++i) {
    const auto& x = a.components()[i];
    const auto& y = b.components()[i];
    if (x.kind != y.kind || x.sill != y.sill) return false;
    const bool has_range = x.kind != ModelKind::Nugget && x.kind != ModelKind::Linear;
    if (has_range && x.range != y.range) return false;
    if (x.kind == ModelKind::Matern && x.nu != y.nu) return false;
  }
  return true;
}

/// A valid model: gamma is never NaN nor negative, and (bounded) never above the total sill.
inline void check_model_values(const VariogramModel& model) {
  for (const double h : {0.0, 1e-300, 1e-9, 0.5, 1.0, 10.0, 1e3, 1e6}) {
    const double g = model.gamma(h);
    ERRFIELD_FUZZ_CHECK(!std::isnan(g));
    ERRFIELD_FUZZ_CHECK(g >= 0.0);
    if (model.bounded()) ERRFIELD_FUZZ_CHECK(g <= model.sill() * (1.0 + 1e-12));
  }
}

/// VariogramModel::parse: bad text only raises ArgumentError; a model that parses prints to text
/// that parses back to the same model, and its values are sane.
inline void check_variogram_model(std::string_view text) {
  VariogramModel model;
  try {
    model = VariogramModel::parse(text);
  } catch (const ArgumentError&) {
    return;
  }
  ERRFIELD_FUZZ_CHECK(same_model(model, VariogramModel::parse(model.to_string())));
  check_model_values(model);
}

/// The model JSON reader: text that is not JSON is the caller's parse error; JSON that is not a
/// valid model only raises ArgumentError; a valid model round-trips through to_json.
inline void check_model_json(std::string_view text) {
  const auto j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return;
  VariogramModel model;
  try {
    model = j.get<VariogramModel>();
  } catch (const ArgumentError&) {
    return;
  }
  const nlohmann::json out = model;
  ERRFIELD_FUZZ_CHECK(same_model(out.get<VariogramModel>(), model));
  ERRFIELD_FUZZ_CHECK(same_model(VariogramModel::parse(out.at("expression").get<std::string>()), model));
  check_model_values(model);
}

/// The robot JSON reader (MdhModel::from_json): text that is not JSON is the caller's parse error
/// (MdhModel::load turns it into an InputError); JSON that is not a robot only raises InputError or
/// ArgumentError; a robot that loads saves to JSON that loads back to the same MD-H table.
inline void check_robot_json(std::string_view text) {
  const auto j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return;
  std::optional<robot::MdhModel> model;
  try {
    model.emplace(robot::MdhModel::from_json(j, "fuzz.json"));
  } catch (const InputError& e) {
    ERRFIELD_FUZZ_CHECK(std::string_view(e.what()).find("fuzz.json") != std::string_view::npos);
    return;
  } catch (const ArgumentError&) {
    return;
  }
  const auto again = robot::MdhModel::from_json(model->to_json(), "again.json");
  for (int i = 0; i < robot::kJointCount; ++i) {
    const auto& a = model->link(i);
    const auto& b = again.link(i);
    ERRFIELD_FUZZ_CHECK(a.alpha_deg == b.alpha_deg && a.a_mm == b.a_mm && a.theta0_deg == b.theta0_deg &&
                        a.d_mm == b.d_mm && a.beta_deg == b.beta_deg && a.q_min_deg == b.q_min_deg &&
                        a.q_max_deg == b.q_max_deg);
  }
  ERRFIELD_FUZZ_CHECK(again.name() == model->name());
}

/// Names of the files write_cli_scratch and kCliScratchCommands put in the scratch directory.
inline const std::vector<std::string> kCliScratchFiles{"s.csv", "t.csv", "v.csv", "m.json", "bad.csv", "r.json",
                                                       "q.csv", "p.csv", "g.csv", "gr.json", "c.csv", "cm.json"};

/// `reproduce` runs the whole paper (seconds per run even in Release, far more under the fuzzer's
/// sanitizers), so the fuzzer only takes `reproduce` inputs that stop before the experiments: every
/// `--out` (at least one) must name an existing scratch file, which the command refuses after
/// parsing and validating all options (or the input asks for --help). Its argument handling is fuzzed; the run itself is not
/// (tests/reliability covers it).
inline bool reproduce_stops_early(const std::vector<std::string>& args) {
  bool has_out = false;
  for (std::size_t i = 1; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") return true;  // help is printed during parsing
    std::string value;
    if (args[i] == "--out") {
      if (i + 1 >= args.size()) return true;  // "--out" without a value: a usage error
      value = args[i + 1];
    } else if (args[i].rfind("--out=", 0) == 0) {
      value = args[i].substr(6);
    } else {
      continue;
    }
    if (std::find(kCliScratchFiles.begin(), kCliScratchFiles.end(), value) == kCliScratchFiles.end()) return false;
    has_out = true;
  }
  return has_out;
}

/// The CLI fuzzer's input format: arguments separated by '\n' (argv[0] "errfield" is added).
/// Returns nothing for inputs the fuzzer skips: too long, more than 24 arguments, an argument
/// with '/', ".." or a NUL byte (so that commands only ever touch the scratch directory), or a
/// `reproduce` that would run (reproduce_stops_early). Cube sizes (plan/simulate --step) are
/// bounded by ERRFIELD_MAX_CUBE_POINTS = kCliFuzzMaxCubePoints, set by both CLI harnesses.
inline std::optional<std::vector<std::string>> split_cli_args(std::string_view data) {
  if (data.size() > 2048) return std::nullopt;
  std::vector<std::string> args{"errfield"};
  std::string current;
  for (const char c : data) {
    if (c == '\n') {
      args.push_back(current);
      current.clear();
      if (args.size() > 24) return std::nullopt;
    } else {
      current.push_back(c);
    }
  }
  args.push_back(current);
  for (const auto& a : args)
    if (a.find('/') != std::string::npos || a.find("..") != std::string::npos ||
        a.find('\0') != std::string::npos)
      return std::nullopt;
  if (std::find(args.begin(), args.end(), "reproduce") != args.end() && !reproduce_stops_early(args))
    return std::nullopt;
  return args;
}

/// The cube-point budget (robot::max_cube_points) under the CLI fuzzer: plan and simulate stay
/// at milliseconds per input instead of up to 10^6 IK solves.
inline constexpr const char* kCliFuzzMaxCubePoints = "ERRFIELD_MAX_CUBE_POINTS=2000";

/// Commands run once in the scratch directory after write_cli_scratch, making the measurement
/// files fit/calibrate/compensate seeds point at (SIMULATED): g.csv (27-point grid + base point),
/// gr.json (its nominal robot), c.csv (8 validation points) and cm.json (a distance-idw model).
inline const std::vector<std::vector<std::string>> kCliScratchCommands{
    {"errfield", "simulate", "--seed", "3", "--step", "250", "--out", "g.csv", "--robot-out", "gr.json"},
    {"errfield", "simulate", "--seed", "4", "--sample", "cells", "--step", "250", "--out", "c.csv"},
    {"errfield", "fit", "--robot", "gr.json", "--data", "g.csv", "--method", "distance-idw", "--out", "cm.json"},
};

/// Small valid inputs the CLI fuzzer's commands can be pointed at by name, written into `dir`.
inline void write_cli_scratch(const std::filesystem::path& dir) {
  auto write = [&](const char* name, const char* content) {
    std::ofstream(dir / name, std::ios::binary) << content;
  };
  write("s.csv",
        "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n1,1,0,4\n0,0,1,5\n1,0,1,6\n0,1,1,7\n1,1,1,8\n");
  write("t.csv", "x,y,z\n0.5,0.5,0.5\n0.25,0.75,0.1\n");
  write("v.csv",
        "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,0.5,0.3,0.1,10\n0.5,1,0.8,0.4,20\n1,1.5,1.2,0.6,25\n");
  write("m.json", R"({"components":[{"kind":"sph","sill":1,"range":2},{"kind":"nug","sill":0.1}]})");
  write("bad.csv", "x,y\n1,nan\n");
  write("r.json", robot::MdhModel::er20_c10().to_json().dump().c_str());
  write("q.csv", "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n10,-20,30,-40,50,-60\n");
  write("p.csv", "x,y,z,rx,ry,rz\n1200,100,900,180,0,0\n5000,0,0,0,0,0\n");
}

/// Exit code run_cli returns for an exception that is not an errfield::Error: always a bug.
constexpr int kCliInternalError = 70;

}  // namespace errfield::fuzz
