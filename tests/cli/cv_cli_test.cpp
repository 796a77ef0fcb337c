// End-to-end tests of `errfield cv` and `errfield interpolate --method idw` (the built CLI).

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace cv_cli_test {

using ::testing::HasSubstr;

class ScatteredCli : public testing::CliTest {};


TEST_F(ScatteredCli, IdwInTwoCoordinatesMatchesClosedForm) {
  // Samples (0,0) -> 1 and (4,3) -> 6; target (0,3): distances 3 and 4, p = 2 (default):
  // (1/9 * 1 + 1/16 * 6) / (1/9 + 1/16); the second target sits on a sample.
  write("s.csv", "u,v,val [mm]\n0,0,1\n4,3,6\n");
  write("t.csv", "name,u,v\nA,0,3\nB,4,3\n");
  const auto r = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("t.csv") +
                         " --coords u,v --value val --out " + path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto out = CsvTable::read(path("p.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"name", "u", "v", "pred"}));
  const auto pred = out.numeric_column("pred");
  EXPECT_NEAR(pred[0], (1.0 / 9 + 6.0 / 16) / (1.0 / 9 + 1.0 / 16), 1e-15);
  EXPECT_EQ(pred[1], 6.0);
  // p = 1 and only the nearest neighbour.
  const auto r1 = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("t.csv") +
                          " --coords u,v --value val --power 1 --neighbors 1 --out " + path("p1.csv"));
  ASSERT_EQ(r1.exit_code, 0) << r1.output();
  EXPECT_EQ(CsvTable::read(path("p1.csv")).numeric_column("pred")[0], 1.0);
}

// Issue 35: interpolate exited 0 with every target empty (predict, validate and cv exit 1).
TEST_F(ScatteredCli, RadiusThatLeavesEveryTargetEmptyFailsAndSaysWhy) {
  write("s.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n");
  write("t.csv", "x,y,z\n9,9,9\n8,8,8\n");
  const auto r = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("t.csv") +
                     " --coords x,y,z --value v --radius 2 --out " + path("p.csv"));
  EXPECT_EQ(r.exit_code, 1) << r.output();
  EXPECT_THAT(r.err, HasSubstr("none of the 2 targets"));
  EXPECT_THAT(r.err, HasSubstr("within --radius 2"));
  EXPECT_FALSE(std::filesystem::exists(path("p.csv")));
}

TEST_F(ScatteredCli, RadiusLeavesEmptyCellsAndSaysSo) {
  write("s.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n");
  write("t.csv", "x,y,z\n0.5,0,0\n9,9,9\n");
  const auto r = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("t.csv") +
                         " --coords x,y,z --value v --radius 2 --out " + path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("1 of 2 targets have no sample within --radius 2 (first: "));
  EXPECT_THAT(r.output(), HasSubstr("(first: " + path("t.csv") + ":3)"));
  const auto out = CsvTable::read(path("p.csv"));
  EXPECT_EQ(out.row(0)[3], "1.5");
  EXPECT_EQ(out.row(1)[3], "");
}

TEST_F(ScatteredCli, LeaveOneOutOnThreeCollinearSamplesMatchesHandComputation) {
  // x = 0, 1, 3 with values 0, 1, 3 (mm), p = 2, all neighbours:
  //   sample 0 from (1, 3) at distances 1, 3: (1 + 3/9) / (1 + 1/9) = 1.2       -> residual -1.2
  //   sample 1 from (0, 3) at distances 1, 2: (0 + 3/4) / (1 + 1/4) = 0.6       -> residual  0.4
  //   sample 2 from (0, 1) at distances 3, 2: (1/4) / (1/9 + 1/4) = 9/13        -> residual  3 - 9/13
  write("s.csv", "x,y,dL [mm]\n0,0,0\n1,0,1\n3,0,3\n");
  const auto r = run("cv --method idw --samples " + path("s.csv") + " --coords x,y --value dL --out " + path("cv.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const double e[3] = {-1.2, 0.4, 3.0 - 9.0 / 13.0};
  const auto out = CsvTable::read(path("cv.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"x", "y", "dL [mm]", "fold", "pred", "residual", "abs_residual"}));
  const auto res = out.numeric_column("residual");
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(res[static_cast<std::size_t>(i)], e[i], 1e-15);
  EXPECT_EQ(out.numeric_column("fold"), (std::vector<double>{0, 1, 2}));
  EXPECT_THAT(r.output(), HasSubstr("leave-one-out"));
  const double mean = (e[0] + e[1] + e[2]) / 3, mean_abs = (1.2 + 0.4 + e[2]) / 3;
  const double rms = std::sqrt((e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) / 3);
  char line[128];
  std::snprintf(line, sizeof line, "mean error       %.6g mm", mean);
  EXPECT_THAT(r.output(), HasSubstr(line));
  std::snprintf(line, sizeof line, "mean |error|     %.6g mm", mean_abs);
  EXPECT_THAT(r.output(), HasSubstr(line));
  std::snprintf(line, sizeof line, "max |error|      %.6g mm   at ", e[2]);
  EXPECT_THAT(r.output(), HasSubstr(line));
  EXPECT_THAT(r.output(), HasSubstr("s.csv:4\n"));
  std::snprintf(line, sizeof line, "RMS error        %.6g mm", rms);
  EXPECT_THAT(r.output(), HasSubstr(line));
}

TEST_F(ScatteredCli, KFoldIsDeterministicForASeedAndVectorColumnsAreNamed) {
  std::ostringstream s;
  s << "x,y,z,dx,dy,dz\n";
  for (int i = 0; i < 40; ++i)
    s << i % 7 << "," << (i * 3) % 11 << "," << (i * 5) % 13 << "," << 0.01 * i << "," << -0.02 * (i % 5) << ",0.5\n";
  write("s.csv", s.str());
  const std::string base =
      "cv --method idw --samples " + path("s.csv") + " --coords x,y,z --value dx,dy,dz --folds 4 --neighbors 6 ";
  ASSERT_EQ(run(base + "--seed 9 --out " + path("a.csv")).exit_code, 0);
  ASSERT_EQ(run(base + "--seed 9 --out " + path("b.csv")).exit_code, 0);
  ASSERT_EQ(run(base + "--seed 10 --out " + path("c.csv")).exit_code, 0);
  EXPECT_EQ(read_text(path("a.csv")), read_text(path("b.csv")));
  EXPECT_NE(read_text(path("a.csv")), read_text(path("c.csv")));
  const auto out = CsvTable::read(path("a.csv"));
  for (const char* col : {"fold", "pred_dx", "pred_dy", "pred_dz", "residual_dx", "residual_dy", "residual_dz", "abs_residual"})
    EXPECT_TRUE(out.has_column(col)) << col;
  // dz is constant, so its residual is zero everywhere (IDW reproduces constants).
  for (double v : out.numeric_column("residual_dz")) EXPECT_NEAR(v, 0.0, 1e-15);
  const auto folds = out.numeric_column("fold");
  for (int f = 0; f < 4; ++f) EXPECT_EQ(std::count(folds.begin(), folds.end(), f), 10);
}

TEST_F(ScatteredCli, CvRejectsBadArguments) {
  write("s.csv", "x,v\n0,1\n1,2\n2,4\n");
  const std::string base = "cv --method idw --samples " + path("s.csv") + " --coords x --value v ";
  auto r = run(base + "--folds 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--folds is '1'"));
  r = run(base + "--folds abc");
  EXPECT_EQ(r.exit_code, 2);
  r = run(base + "--folds 4");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--folds 4 for 3 samples"));
  r = run(base + "--seed 3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--seed applies to k-fold"));
  r = run("cv --method idw-grid --samples " + path("s.csv") + " --coords x --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("unknown method 'idw-grid'"));
  write("one.csv", "x,v\n0,1\n");
  r = run("cv --method idw --samples " + path("one.csv") + " --coords x --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("cross-validation needs at least 2"));
  write("bad.csv", "x,v\n0,1\n1,NaN\n");
  r = run("cv --method idw --samples " + path("bad.csv") + " --coords x --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("bad.csv:3: column 'v'"));
  r = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("s.csv") +
              " --coords x --value v --clamp --out " + path("p.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--clamp does not apply to --method idw"));
}

}  // namespace
}  // namespace errfield
