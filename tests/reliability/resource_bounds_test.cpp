// Resource bounds at the command line: a job that would exceed the memory budget stops at once
// with a ResourceError (exit code 3) that names the cheaper back end, instead of being killed by
// the kernel's OOM killer after minutes of swapping. Dense kriging with N = 200,000 samples would
// need 2 N^2 doubles = 640 GB.

#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_harness.hpp"

namespace errfield {
namespace {

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

}  // namespace
}  // namespace errfield
