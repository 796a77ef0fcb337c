// Bad-input catalogue at the command line: each case runs the built `errfield` on a deliberately
// broken input and asserts the exit code (2 = input/argument error, 1 = a numerical failure the
// data causes) and that stderr names the file, line, column or parameter to fix. Cases that are
// not errors (all points identical for a variogram, an unreachable IK target) assert the
// documented outcome instead. Robot cases: robot_input_test.cpp.

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace cli_input_test {

using namespace testing::cli_common;


class CliBadInput : public ::testing::Test {
 protected:
  ScratchDir dir;
  CliResult run(const std::vector<std::string>& args) {
    auto r = run_errfield(args, dir.path());
    EXPECT_EQ(r.signal, 0) << testing::command_line(args);
    EXPECT_THAT(r.err, Not(HasSubstr("internal error"))) << testing::command_line(args);
    return r;
  }
  CliResult variogram(const std::string& file, const std::string& bins = "0:2:0.5", const std::string& value = "v") {
    return run({"variogram", "--input", file, "--coords", "x,y,z", "--value", value, "--bins", bins, "--out", "o.csv"});
  }
  CliResult interpolate(const std::string& method, const std::string& samples, const std::string& targets,
                        std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"interpolate", "--method", method, "--samples", samples, "--targets", targets,
                                  "--coords",    "x,y,z",  "--value",  "v",    "--out",     "o.csv"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run(args);
  }
};

TEST_F(CliBadInput, MissingFile) {
  const auto r = variogram("none.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("none.csv"), HasSubstr("cannot open")));
}

TEST_F(CliBadInput, MissingColumn) {
  dir.write("s.csv", "x,y,z,w\n0,0,0,1\n1,1,1,2\n");
  const auto r = variogram("s.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv"), HasSubstr("no column 'v'"), HasSubstr("x,y,z,w")));
}

TEST_F(CliBadInput, ExtraCellInARow) {
  dir.write("s.csv", "x,y,z,v\n0,0,0,1\n1,1,1,2,9\n");
  const auto r = variogram("s.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:3"), HasSubstr("5 cells"), HasSubstr("header has 4")));
}

TEST_F(CliBadInput, DuplicatedColumn) {
  dir.write("s.csv", "x,y,z,v,y\n0,0,0,1,0\n1,1,1,2,0\n");
  const auto r = variogram("s.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:1"), HasSubstr("'y' appears twice")));
}

TEST_F(CliBadInput, NonNumericEmptyNanAndInfCells) {
  const std::pair<const char*, const char*> cases[] = {
      {"abc", "'abc' is not a number"}, {"", "is empty"}, {"NaN", "not a finite number"}, {"inf", "not a finite number"}};
  for (const auto& [cell, words] : cases) {
    dir.write("s.csv", std::string("x,y,z,v\n0,0,0,1\n1,1,1,2\n2,2,2,") + cell + "\n");
    const auto r = variogram("s.csv");
    EXPECT_EQ(r.exit_code, 2) << cell;
    EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:4"), HasSubstr("column 'v'"), HasSubstr(words))) << cell;
  }
  // A bad coordinate is reported the same way, for the column it is in.
  dir.write("s.csv", "x,y,z,v\n0,0,0,1\n1,1,x1,2\n");
  const auto r = variogram("s.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:3"), HasSubstr("column 'z'"), HasSubstr("'x1'")));
}

TEST_F(CliBadInput, BomCrlfSemicolonsAndUnitsAreAccepted) {
  dir.write("s.csv", "\xEF\xBB\xBFx [mm];y [mm];z [mm];v [mm]\r\n0;0;0;1\r\n1;0;0;3\r\n\r\n0;2;0;5\r\n");
  const auto r = variogram("s.csv", "0:3:1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Pairs at lags 1 (gamma 2), 2 (gamma 8) and sqrt(5) (gamma 2): bins [1,2) and [2,3).
  const auto out = CsvTable::parse(dir.read("o.csv"), "o.csv");
  EXPECT_EQ(out.numeric_column("pairs"), (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(out.row(1)[3], "2");
  EXPECT_EQ(out.row(2)[3], "5");
  EXPECT_DOUBLE_EQ(std::stod(out.row(2)[2]), (2.0 + std::sqrt(5.0)) / 2.0);
}

TEST_F(CliBadInput, CrlfErrorsNameTheRightLineWithoutCarriageReturns) {
  dir.write("s.csv", "x,y,z,v\r\n0,0,0,1\r\n# note\r\n1,1,1,bad\r\n");
  const auto r = variogram("s.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("s.csv:4"), HasSubstr("'bad'"), Not(HasSubstr("\r"))));
}

TEST_F(CliBadInput, SingleRow) {
  dir.write("one.csv", "x,y,z,v\n0,0,0,1\n");
  auto r = variogram("one.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("one.csv"), HasSubstr("1 data row"), HasSubstr("at least 2")));
  r = run({"cv", "--method", "idw", "--samples", "one.csv", "--coords", "x,y,z", "--value", "v"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("one.csv"), HasSubstr("at least 2")));
  // A grid needs 2 x 2 x 2 nodes.
  dir.write("t.csv", "x,y,z\n0,0,0\n");
  r = interpolate("idw-grid", "one.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("one.csv"), HasSubstr("1 samples"), HasSubstr("at least 8")));
  // Kriging from one sample is defined (ordinary kriging returns that value): not an error.
  r = interpolate("kriging", "one.csv", "t.csv", {"--model", "sph(1,3)"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(CsvTable::parse(dir.read("o.csv"), "o.csv").numeric_column("pred"), std::vector<double>{1.0});
}

TEST_F(CliBadInput, AllPointsIdentical) {
  dir.write("same.csv", "x,y,z,v\n1,1,1,1\n1,1,1,2\n1,1,1,4\n");
  dir.write("t.csv", "x,y,z\n0,0,0\n");
  // Variogram: not an error; every pair is at lag 0, in the first bin: gamma = (0.5 + 4.5 + 2) / 3.
  auto r = variogram("same.csv", "0:1:0.5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(dir.read("o.csv"), "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,0.5,0,2.3333333333333335,3\n0.5,1,,,0\n");
  // Kriging: the samples are duplicates, named by file and line.
  r = interpolate("kriging", "same.csv", "t.csv", {"--model", "sph(1,3)"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("same.csv:3: kriging: this sample and same.csv:2 are duplicates"));
  // --model auto cannot estimate a variogram from one location.
  r = interpolate("kriging", "same.csv", "t.csv", {"--model", "auto"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("one location"));
}

TEST_F(CliBadInput, DuplicateAndNearDuplicateLocations) {
  dir.write("dup.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n2,0,1,4\n1,0,0,3\n3,1,0,5\n");
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  auto r = interpolate("kriging", "dup.csv", "t.csv", {"--model", "sph(1,3)"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("dup.csv:5: kriging: this sample and dup.csv:3 are duplicates"));
  // 1e-13 apart: accepted, with a warning that the system is ill-conditioned.
  dir.write("near.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n1,1e-13,0,3\n2,0,1,4\n3,1,0,5\n");
  r = interpolate("kriging", "near.csv", "t.csv", {"--model", "sph(1,3)"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("ill-conditioned"), HasSubstr("near-duplicate")));
  // Cross-validation of kriging names them the same way.
  r = run({"cv", "--method", "kriging", "--model", "sph(1,3)", "--samples", "dup.csv", "--coords", "x,y,z", "--value", "v"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("dup.csv:5: kriging: this sample and dup.csv:3 are duplicates"));
  // IDW does not mind duplicates: it averages them.
  r = interpolate("idw", "dup.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(CliBadInput, CollinearAndCoplanarSamplesForUniversalKriging) {
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  dir.write("line.csv", "x,y,z,v\n0,0,0,1\n1,1,1,2\n2,2,2,3\n3,3,3,4\n4,4,4,5\n5,5,5,6\n");
  auto r = interpolate("kriging", "line.csv", "t.csv", {"--model", "sph(1,30)", "--kind", "universal1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, AllOf(HasSubstr("singular drift"), HasSubstr("linear drift (order 1"), HasSubstr("collinear")));
  dir.write("plane.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n1,1,0,4\n2,1,0,5\n1,2,0,6\n");
  r = interpolate("kriging", "plane.csv", "t.csv", {"--model", "sph(1,30)", "--kind", "universal1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, AllOf(HasSubstr("singular drift"), HasSubstr("linear drift (order 1"), HasSubstr("coplanar")));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "o.csv"));  // nothing written, no NaN
  // Ordinary kriging on the same plane is fine.
  r = interpolate("kriging", "plane.csv", "t.csv", {"--model", "sph(1,30)"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // Too few samples for the quadratic drift.
  dir.write("g.csv", kUnitCubeGrid);
  r = interpolate("kriging", "g.csv", "t.csv", {"--model", "sph(1,30)", "--kind", "universal2"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, AllOf(HasSubstr("8 samples"), HasSubstr("10 drift terms"), HasSubstr("quadratic drift (order 2")));
}

TEST_F(CliBadInput, ZeroNegativeAndUnorderedBins) {
  dir.write("g.csv", kUnitCubeGrid);
  auto r = variogram("g.csv", "0:2:0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("bins"), HasSubstr("width = 0")));
  r = variogram("g.csv", "0:2:-0.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("bins"), HasSubstr("width = -0.5")));
  r = variogram("g.csv", "0,1,1,2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("edges[2] = 1"), HasSubstr("strictly increasing")));
}

TEST_F(CliBadInput, GridWithAMissingNode) {
  dir.write("g.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n1,1,0,4\n0,0,1,5\n1,0,1,6\n0,1,1,7\n"
                     "0,0,2,1\n1,0,2,2\n0,1,2,3\n1,1,2,4\n");
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  const auto r = interpolate("idw-grid", "g.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("g.csv"), HasSubstr("incomplete grid"), HasSubstr("(1, 1, 1) has no sample")));
}

TEST_F(CliBadInput, GridWithUnevenSpacing) {
  // x at 0, 1, 3: the step is 1, so x = 2 is reported missing.
  dir.write("g.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n3,0,0,2\n0,1,0,3\n1,1,0,4\n3,1,0,4\n"
                     "0,0,1,5\n1,0,1,6\n3,0,1,6\n0,1,1,7\n1,1,1,8\n3,1,1,8\n");
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  const auto r = interpolate("idw-grid", "g.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("g.csv"), HasSubstr("x [0, 3] step 1"), HasSubstr("at (2, 0, 0) has no sample")));
}

TEST_F(CliBadInput, DuplicateGridNode) {
  dir.write("g.csv", std::string(kUnitCubeGrid) + "1,1,1,9\n");
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  const auto r = interpolate("idw-grid", "g.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("g.csv:10: duplicate grid node"), HasSubstr("g.csv:9 (")));
}

TEST_F(CliBadInput, TargetOutsideTheGrid) {
  dir.write("g.csv", kUnitCubeGrid);
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n0.5,1.5,0.5\n");
  auto r = interpolate("idw-grid", "g.csv", "t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("t.csv:3: target (0.5, 1.5, 0.5) is outside the grid [0, 1] x [0, 1] x [0, 1]"),
                           HasSubstr("--clamp")));
  r = interpolate("idw-grid", "g.csv", "t.csv", {"--clamp"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(CliBadInput, BadOptionValuesNameTheOption) {
  dir.write("g.csv", kUnitCubeGrid);
  dir.write("t.csv", "x,y,z\n0.5,0.5,0.5\n");
  auto r = interpolate("idw", "g.csv", "t.csv", {"--power", "-1"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("power"));
  r = interpolate("kriging", "g.csv", "t.csv", {"--model", "sph(sill=-1,range=2)"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("sill = -1"), HasSubstr("component 1 (sph)")));
  r = interpolate("nosuch", "g.csv", "t.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("nosuch"));
}

}  // namespace
}  // namespace errfield
