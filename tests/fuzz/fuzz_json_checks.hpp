#pragma once
// Fuzz contracts of the JSON input files (issue 12): the strict reader every JSON input goes
// through (errfield/json_file.hpp), and the two documents it feeds that the other targets do not
// cover: the compensation model `compensate` reads (joints go to a robot from it) and the
// simulation set-up of `simulate --config`. Shared by the libFuzzer target fuzz_json_inputs.cpp
// (check_json_inputs: the first byte picks the reader) and by fuzz_replay_test.cpp.

#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/compensation/model/compensation.hpp"
#include "errfield/robot/simulator.hpp"
#include "fuzz/fuzz_checks.hpp"

namespace errfield::fuzz {

inline bool names_source(const InputError& e) {
  // The file is the plain path even for a nested member (its path is in the message and column).
  return std::string_view(e.what()).find("fuzz.json") != std::string_view::npos && e.file() == "fuzz.json";
}

/// parse_json_text: bad text only ever raises InputError naming the file and a line >= 1; it
/// accepts exactly the documents nlohmann::json accepts that have no key twice in one object; a
/// parsed document re-parses from its own dump to the same value.
inline void check_json_file(std::string_view text) {
  nlohmann::json j;
  try {
    j = parse_json_text(text, "fuzz.json");
  } catch (const InputError& e) {
    ERRFIELD_FUZZ_CHECK(names_source(e));
    ERRFIELD_FUZZ_CHECK(e.row() >= 1);
    return;
  }
  ERRFIELD_FUZZ_CHECK(nlohmann::json::accept(text.begin(), text.end()));
  ERRFIELD_FUZZ_CHECK(parse_json_text(j.dump(), "again.json") == j);
}

/// A compensation model: only InputError (naming the file) or ArgumentError for anything that is
/// not a model; a model that loads never marks a target `ok` without finite joints to send.
inline void check_compensation_model(std::string_view text) {
  std::optional<compensation::CompensationModel> model;
  try {
    const auto j = parse_json_text(text, "fuzz.json");
    model.emplace(with_json_source("fuzz.json", [&] { return compensation::CompensationModel::from_json(j, "fuzz.json"); }));
  } catch (const InputError& e) {
    ERRFIELD_FUZZ_CHECK(names_source(e));
    return;
  } catch (const ArgumentError&) {
    return;
  }
  robot::JointVector q;
  q << 10.0, -20.0, 30.0, 0.0, 45.0, 0.0;
  compensation::CompensatedTarget c;
  try {
    c = model->compensate_joints(model->command_model(), q, 0.25);
  } catch (const Error&) {
    return;  // refused with a reason: allowed
  }
  if (c.ok())
    for (int k = 0; k < 6; ++k) ERRFIELD_FUZZ_CHECK(std::isfinite(c.q_command_deg[k]));
}

/// A simulation set-up (`simulate --config`): only InputError (naming the file) or ArgumentError.
inline void check_simulator_config(std::string_view text) {
  try {
    const auto j = parse_json_text(text, "fuzz.json");
    const auto config =
        with_json_source("fuzz.json", [&] { return robot::SimulatorConfig::from_json(j, "fuzz.json"); });
    // What loads also writes: to_json must not throw on a set-up from_json accepted.
    (void)config.to_json().dump();
  } catch (const InputError& e) {
    ERRFIELD_FUZZ_CHECK(names_source(e));
  } catch (const ArgumentError&) {
  }
}

/// The fuzz target's input: 'f' + text -> check_json_file, 'm' + text -> check_compensation_model,
/// 's' + text -> check_simulator_config; any other first byte picks by its value modulo 3.
inline void check_json_inputs(std::string_view data) {
  if (data.empty()) return;
  const unsigned char selector = static_cast<unsigned char>(data.front());
  const std::string_view text = data.substr(1);
  const int which = selector == 'f' ? 0 : selector == 'm' ? 1 : selector == 's' ? 2 : selector % 3;
  if (which == 0) check_json_file(text);
  else if (which == 1) check_compensation_model(text);
  else check_simulator_config(text);
}

}  // namespace errfield::fuzz
