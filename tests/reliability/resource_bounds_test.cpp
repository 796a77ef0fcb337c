// Resource bounds at the command line: a job that would exceed the memory budget stops at once
// with a ResourceError (exit code 3) that names the cheaper back end, instead of being killed by
// the kernel's OOM killer after minutes of swapping. Dense kriging with N = 200,000 samples would
// need 2 N^2 doubles = 640 GB.

#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/cube_budget.hpp"
#include "errfield/compensation/planning/measurement_plan.hpp"
#include "errfield/robot/simulator.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace resource_bounds_test {

using ::testing::AllOf;
using ::testing::HasSubstr;
using testing::ScratchDir;

std::string samples_csv(std::size_t n) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 2000.0);
  std::string s = "x,y,z,v\n";
  s.reserve(n * 40);
  char line[128];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(line, sizeof line, "%.3f,%.3f,%.3f,%.4f\n", u(rng), u(rng), u(rng), u(rng) / 1000.0);
    s += line;
  }
  return s;
}

TEST(ResourceBounds, DenseKrigingOf200000SamplesIsRefusedNamingLocalAndSparse) {
  ScratchDir dir;
  dir.write("s.csv", samples_csv(200000));
  dir.write("t.csv", "x,y,z\n1000,1000,1000\n");
  dir.write("o.csv", "previous\n");
  const std::vector<std::string> args{"interpolate", "--method", "kriging", "--samples", "s.csv", "--targets",
                                      "t.csv",       "--coords", "x,y,z",   "--value",   "v",     "--model",
                                      "sph(sill=1,range=300)",  "--out", "o.csv"};
  const auto start = std::chrono::steady_clock::now();
  const auto r = testing::run_errfield(args, dir.path());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal;
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("resource limit"), HasSubstr("dense"), HasSubstr("local"), HasSubstr("sparse")));
  EXPECT_EQ(dir.read("o.csv"), "previous\n");
  // It stops before any O(N^2) work: reading 200,000 rows and one kd-tree take well under this
  // (generous for a loaded machine or a sanitizer build).
  EXPECT_LT(seconds, 60.0);
  // The local back end named in the message does the job.
  auto local = args;
  local.insert(local.end() - 2, {"--backend", "local", "--neighbors", "32"});
  const auto ok = testing::run_errfield(local, dir.path());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// Jobs whose size follows an option (plan and simulate: (SIZE/--step + 1)^3 cube points, each an
// IK solve and ~2 KB of memory): refused up front with exit code 3, naming the option, the number
// of points and the step that fits, before any allocation, and leaving the previous output.
TEST(ResourceBounds, SimulateWithATinyStepIsRefusedNamingTheStepAndTheSize) {
  ScratchDir dir;
  dir.write("o.csv", "previous\n");
  struct Job {
    std::vector<std::string> args;
    std::vector<std::string> says;
  };
  const std::vector<Job> jobs{
      // 500 mm / 0.01 mm = 50,000 cells per side: 50,001^3 = 1.25e14 grid points.
      {{"simulate", "--step", "0.01", "--out", "o.csv"}, {"--step 0.01", "50000 cells per side", "1.25e+14 grid points",
                                                          "1000000 points", "--step >= 5.051 mm"}},
      {{"simulate", "--sample", "cells", "--step", "0.01", "--out", "o.csv"}, {"--step 0.01", "1.25e+14"}},
      {{"simulate", "--sample", "random:50000000", "--out", "o.csv"}, {"--sample random:50000000", "5e+07 points"}},
      {{"simulate", "--sample", "random:1e15", "--out", "o.csv"}, {"--sample random:1e15", "1e+15 points"}},
  };
  for (const auto& job : jobs) {
    const auto start = std::chrono::steady_clock::now();
    const auto r = testing::run_errfield(job.args, dir.path());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.signal, 0) << testing::command_line(job.args);
    EXPECT_EQ(r.exit_code, 3) << testing::command_line(job.args) << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("resource limit")) << testing::command_line(job.args);
    for (const auto& s : job.says) EXPECT_THAT(r.err, HasSubstr(s)) << testing::command_line(job.args);
    EXPECT_LT(seconds, 20.0) << "refused before the work, not after";
    EXPECT_EQ(dir.read("o.csv"), "previous\n");
  }
}

TEST(ResourceBounds, PlanWithATinyStepIsRefusedCountingTheCellSamples) {
  ScratchDir dir;
  // 250 cells per side: 251^3 = 15,813,251 grid points.
  auto r = testing::run_errfield({"plan", "--cube", "750,-250,350,500", "--step", "2", "--out", "p.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("--step 2"), HasSubstr("250 cells per side"), HasSubstr("1.58e+07 grid points")));
  // 80 cells per side: 81^3 = 531,441 grid points fit, but with one sample per cell (80^3 = 512,000)
  // the job is 1,043,441 points; at most 78 cells per side fit (79^3 + 78^3 = 967,591).
  r = testing::run_errfield(
      {"plan", "--cube", "750,-250,350,500", "--step", "6.25", "--samples-out", "s.csv", "--out", "p.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("1043441 grid points and cell samples"), HasSubstr("at most 78 cells per side")));
  EXPECT_TRUE(dir.entries().empty()) << ::testing::PrintToString(dir.entries());
}

TEST(ResourceBounds, LibraryChecksTheCubeBudgetAtTheBoundary) {
  using robot::check_cube_budget;
  using robot::kMaxCubePoints;
  ASSERT_EQ(kMaxCubePoints, 1000000u);
  // 99 cells per side: 100^3 = 10^6 points, the limit itself; 100 cells: 101^3 = 1,030,301.
  EXPECT_NO_THROW(check_cube_budget(99.0, 1.0, false, "step"));
  EXPECT_THROW(check_cube_budget(100.0, 1.0, false, "step"), ResourceError);
  // With cell samples: 79^3 + 78^3 = 967,591 fits, 80^3 + 79^3 = 1,005,039 does not.
  EXPECT_NO_THROW(check_cube_budget(78.0, 1.0, true, "step"));
  EXPECT_THROW(check_cube_budget(79.0, 1.0, true, "step"), ResourceError);
  // The library entry points check it too, before allocating.
  const robot::MeasurementCube cube = robot::paper_cube();
  EXPECT_THROW(cube.grid(0.01), ResourceError);
  robot::SimulationRng rng(1);
  EXPECT_THROW(cube.random_per_cell(0.01, rng), ResourceError);
  EXPECT_EQ(cube.grid(125.0).size(), 125u);
  compensation::PlanOptions o;
  o.size_mm = 500;
  o.step_mm = 2;
  EXPECT_THROW(o.validate(), ResourceError);
  o.step_mm = 0.3;  // does not divide 500: an argument error, not a resource one
  EXPECT_THROW(o.validate(), ArgumentError);
}

// variogram --bins: the per-chunk sums are kVariogramChunks x (bins + 1) x (2 + components)
// doubles; `--bins 0:10000000:1` asked for 15.4 GB (measured peak RSS 15.5 GB, 56 s, before the
// budget) and is now refused at once.
TEST(ResourceBounds, VariogramWithTenMillionBinsIsRefusedNamingTheBinCount) {
  ScratchDir dir;
  dir.write("s.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n5,5,5,4\n");
  const auto r = testing::run_errfield(
      {"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:10000000:1", "--out", "o.csv"},
      dir.path());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  // 2^30 bytes / (64 chunks x 3 sums x 8 bytes) = 699,050 slots, one of them the discard slot.
  EXPECT_THAT(r.err, AllOf(HasSubstr("10000000 lag bins"), HasSubstr("15.4 GB"), HasSubstr("at most 699049 bins"),
                           HasSubstr("--bins")));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "o.csv"));
}

TEST(ResourceBounds, VariogramAccumulatorBudgetAtTheBoundary) {
  const Eigen::MatrixXd x = (Eigen::MatrixXd(3, 1) << 0.0, 1.0, 2.5).finished();
  const Eigen::MatrixXd z = (Eigen::MatrixXd(3, 1) << 1.0, 2.0, 4.0).finished();
  EmpiricalVariogramOptions o;
  // 10 bins + the discard slot, 64 chunks, 3 sums of 8 bytes: exactly 16,896 bytes.
  o.max_accumulator_bytes = 16896;
  EXPECT_NO_THROW(empirical_variogram(x, z, LagBins::uniform(0, 10, 1), o));
  EXPECT_THROW(empirical_variogram(x, z, LagBins::uniform(0, 11, 1), o), ResourceError);
  // Three components: 5 sums per slot.
  const Eigen::MatrixXd z3 = Eigen::MatrixXd::Ones(3, 3);
  o.max_accumulator_bytes = 64 * 5 * 8 * 11;
  EXPECT_NO_THROW(empirical_variogram(x, z3, LagBins::uniform(0, 10, 1), o));
  EXPECT_THROW(empirical_variogram(x, z3, LagBins::uniform(0, 11, 1), o), ResourceError);
}

}  // namespace
}  // namespace errfield
