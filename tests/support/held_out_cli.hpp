#pragma once
// A CLI test on one SIMULATED session split into training and held-out poses: simulate, split,
// then fit on the training poses and validate on the held-out ones, as a user checks a model.

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/cli_harness.hpp"
#include "support/session_split.hpp"

namespace errfield::testing {

class HeldOutCli : public CliTest {
 protected:
  /// `simulate <options> --robot-out r.json --out all.csv`, then train.csv (the first `n_train`
  /// targets) and hold.csv (the rest).
  void simulate_and_split(const std::string& options, std::size_t n_train) {
    const CliResult r = run("simulate " + options + " --robot-out r.json --out all.csv");
    ASSERT_EQ(r.exit_code, 0) << r.output();
    const SessionSplit s = split_session(read("all.csv"), n_train);
    write("train.csv", s.train);
    write("hold.csv", s.hold);
  }
  /// Fits train.csv with `options` into `model`, validates it on hold.csv: the summary JSON.
  nlohmann::json fit_and_validate(const std::string& options, const std::string& model) {
    const CliResult f = run("fit --robot r.json --data train.csv " + options + " --out " + model);
    EXPECT_EQ(f.exit_code, 0) << f.output();
    const CliResult v = run("validate --model " + model + " --data hold.csv --summary-out s.json");
    EXPECT_EQ(v.exit_code, 0) << v.output();
    return nlohmann::json::parse(read("s.json"));
  }
};

}  // namespace errfield::testing
