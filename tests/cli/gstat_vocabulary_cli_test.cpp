// Issue 49's vocabulary and model checks through the executable, without R (the gstat
// cross-checks are tests/peers/gstat_pseudo_test.cpp and gstat_vocabulary_test.cpp):
//  - variogram --pseudo against a brute-force pseudo cross-variogram written here, and its refusals;
//  - --duplicates refuse names both lines and the option's other values; average merges;
//  - fit-variogram --method reml: a held range prints no "nan"; a free range below the sample
//    spacing or far beyond the extent is warned about, naming a trend.
// Data SIMULATED here.

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace gstat_vocabulary_cli_test {

class GstatVocabularyCli : public testing::CliTest {};

struct Survey {
  std::vector<double> x, y, z;
};

Survey survey(int n, unsigned seed, double shift) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 0.3);
  Survey s;
  for (int i = 0; i < n; ++i) {
    s.x.push_back(u(rng));
    s.y.push_back(u(rng));
    s.z.push_back(std::sin(s.x.back() / 15.0) + shift + g(rng));
  }
  return s;
}

TEST_F(GstatVocabularyCli, PseudoCrossVariogramIsTheMeanOfEveryCrossPairsSquaredResidualDifference) {
  const Survey a = survey(40, 1, 0.0), b = survey(30, 2, 0.5);
  std::string csv = "x,y,a,b\n";
  for (std::size_t i = 0; i < a.x.size(); ++i) csv += format_number(a.x[i]) + "," + format_number(a.y[i]) + "," + format_number(a.z[i]) + ",\n";
  for (std::size_t j = 0; j < b.x.size(); ++j) csv += format_number(b.x[j]) + "," + format_number(b.y[j]) + ",," + format_number(b.z[j]) + "\n";
  write("s.csv", csv);
  const auto r = run("variogram --input " + path("s.csv") + " --coords x,y --value a,b --pseudo --cutoff 50 --width 10 --out " +
                     path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::read(path("p.csv"));
  EXPECT_EQ(t.header(), (std::vector<std::string>{"id", "lag_lo", "lag_hi", "lag_mean", "gamma", "pairs"}));
  // Brute force: bins (10k, 10(k+1)], the first [0, 10]; each survey minus its mean (gstat's residuals of z ~ 1).
  double mean_a = 0.0, mean_b = 0.0;
  for (double v : a.z) mean_a += v / static_cast<double>(a.z.size());
  for (double v : b.z) mean_b += v / static_cast<double>(b.z.size());
  std::vector<double> sum(5, 0.0), lag(5, 0.0), count(5, 0.0);
  for (std::size_t i = 0; i < a.x.size(); ++i)
    for (std::size_t j = 0; j < b.x.size(); ++j) {
      const double h = std::hypot(a.x[i] - b.x[j], a.y[i] - b.y[j]);
      if (h > 50.0) continue;
      const int k = std::max(0, static_cast<int>(std::ceil(h / 10.0)) - 1);
      const double d = (a.z[i] - mean_a) - (b.z[j] - mean_b);
      sum[k] += d * d;
      lag[k] += h;
      count[k] += 1.0;
    }
  std::size_t seen = 0;
  for (std::size_t r2 = 0; r2 < t.row_count(); ++r2) {
    if (t.row(r2)[0] != "a.b") continue;
    const auto k = seen++;
    ASSERT_LT(k, 5u);
    EXPECT_EQ(t.numeric_cell(r2, 1), 10.0 * static_cast<double>(k));
    EXPECT_EQ(t.numeric_cell(r2, t.column_index("pairs")), count[k]);
    EXPECT_NEAR(t.numeric_cell(r2, t.column_index("gamma")), sum[k] / (2.0 * count[k]), 1e-12 * sum[k] / count[k]);
    EXPECT_NEAR(t.numeric_cell(r2, t.column_index("lag_mean")), lag[k] / count[k], 1e-12 * lag[k] / count[k]);
  }
  EXPECT_EQ(seen, 5u);
  // Refusals by name.
  auto bad = run("variogram --input " + path("s.csv") + " --coords x,y --value a --pseudo");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--pseudo needs at least 2 --value columns"), std::string::npos) << bad.err;
  bad = run("variogram --input " + path("s.csv") + " --coords x,y --value a,b --pseudo --alpha 0");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--alpha/--beta/--per-coordinate does not apply to --pseudo"), std::string::npos) << bad.err;
  bad = run("variogram --input " + path("s.csv") + " --coords x,y --value a,b --pseudo --bins 0:50:10 --cutoff 50");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--bins with --cutoff/--width"), std::string::npos) << bad.err;
}

TEST_F(GstatVocabularyCli, DuplicatesRefuseNamesBothLinesAndAverageMerges) {
  write("d.csv", "x,y,z\n0,0,1\n1,0,2\n0,0,3\n0,2,5\n3,1,4\n");
  auto r = run("variogram --input " + path("d.csv") + " --coords x,y --value z --duplicates refuse");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(path("d.csv") + ":4: this sample and " + path("d.csv") + ":2 are at the same location"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--duplicates average"), std::string::npos) << r.err;
  // average: (0,0) holds 2. Lag 1: (0,0)-(1,0), gamma 0. Lags 2 and sqrt 5: (0,0)-(0,2) 4.5, (1,0)-(0,2)
  // 4.5, (1,0)-(3,1) 2; the others (sqrt 10) beyond 2.5.
  r = run("variogram --input " + path("d.csv") + " --coords x,y --value z --duplicates average --bins 0.5,1.5,2.5 --out " +
          path("v.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 row(s) at the location of an earlier row merged"), std::string::npos) << r.err;
  const CsvTable t = CsvTable::read(path("v.csv"));
  EXPECT_EQ(t.numeric_cell(0, t.column_index("pairs")), 1.0);  // (0,0)-(1,0)
  EXPECT_EQ(t.numeric_cell(0, t.column_index("gamma")), 0.0);
  EXPECT_EQ(t.numeric_cell(1, t.column_index("pairs")), 3.0);
  EXPECT_DOUBLE_EQ(t.numeric_cell(1, t.column_index("gamma")), (4.5 + 4.5 + 2.0) / 3.0);
  r = run("variogram --input " + path("d.csv") + " --coords x,y --value z --duplicates sometimes");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("expected keep, average, first or refuse"), std::string::npos) << r.err;
}

std::string field_csv(double trend, double signal, double noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::string csv = "x,y,z\n";
  for (int i = 0; i < 80; ++i) {
    const double x = u(rng), y = u(rng);
    csv += format_number(x) + "," + format_number(y) + "," +
           format_number(trend * x + signal * std::sin(x / 12.0) * std::cos(y / 17.0) + noise * g(rng)) + "\n";
  }
  return csv;
}

TEST_F(GstatVocabularyCli, HeldRangePrintsNoNanAndImplausibleFreeRangesAreWarned) {
  write("f.csv", field_csv(0.0, 1.0, 0.1, 3));
  auto r = run("fit-variogram --method reml --input " + path("f.csv") +
               " --coords x,y --value z --model 'exp(sill=1,range=15)+nug(sill=0.01)' --fix range");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("range = 15 (held at the template's value by --fix: no standard error)"), std::string::npos) << r.out;
  // A strong linear trend in x under ordinary kriging: the range runs away (a trend, not a range).
  write("t.csv", field_csv(1.0, 0.05, 0.05, 4));
  r = run("fit-variogram --method reml --input " + path("t.csv") + " --coords x,y --value z --model gau");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_NE(r.err.find("a trend over the data, not a range"), std::string::npos) << r.output();
  // White noise without a nugget: the range collapses below the closest samples' spacing.
  write("w.csv", field_csv(0.0, 0.0, 1.0, 5));
  r = run("fit-variogram --method reml --input " + path("w.csv") + " --coords x,y --value z --model exp --nugget none");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_NE(r.err.find("below the smallest sample spacing"), std::string::npos) << r.output();
}

}  // namespace gstat_vocabulary_cli_test
}  // namespace errfield
