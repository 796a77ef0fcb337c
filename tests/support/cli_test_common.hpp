#pragma once
// What the bad-input catalogue (tests/bad_input/*) and the CLI reliability tests share: the gmock
// matchers and harness names they all use, and a small valid sample file. A test file brings them
// in with `using namespace testing::cli_common;` inside its own anonymous namespace.

#include <gmock/gmock.h>

#include "support/cli_harness.hpp"

namespace errfield::testing::cli_common {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using errfield::testing::CliResult;
using errfield::testing::run_errfield;
using errfield::testing::ScratchDir;

/// A complete 2 x 2 x 2 grid on the unit cube with values 1..8 (x fastest), header x,y,z,v: a
/// valid sample file for every command that reads x,y,z,v (idw-grid, kriging, variogram, cv).
inline constexpr const char* kUnitCubeGrid =
    "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n1,1,0,4\n0,0,1,5\n1,0,1,6\n0,1,1,7\n1,1,1,8\n";

}  // namespace errfield::testing::cli_common
