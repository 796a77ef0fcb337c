// gstat's vocabulary in errfield's CLI, against R gstat (tests/peers/gstat_vocabulary.R, one R run
// for the suite):
//  - variogram --cutoff C --width W on coalash, an integer lattice whose lags fall exactly on bin
//    boundaries: gstat's bins (np exactly, dist and gamma to 1e-12 relative), with W given and
//    with gstat's default W = C/15 (C = 7.5, not a multiple of W);
//  - --bins without --convention warns there (coalash: [0, 1) holds 0 pairs half-open, 369 with
//    gstat's rule) and not with --convention;
//  - --duplicates average: variogram and kriging of a SIMULATED set with 12 locations measured 2
//    or 3 times equal gstat's after averaging the duplicates (aggregate(z ~ x + y, mean)): the
//    variogram to 1e-12, krige's predictions and variances to 1e-9; without the option
//    interpolate refuses, naming --duplicates.
// Skipped with a message when Rscript, gstat or sp is missing.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_vocabulary_test {

using errfield::testing::run_errfield;

class GstatVocabulary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_vocabulary.R", "errfield_gstat_vocabulary"); }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_vocabulary.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  static errfield::testing::CliResult run(std::vector<std::string> args) { return run_errfield(args, gstat_.root()); }
  static inline errfield::testing::GstatScriptRun gstat_;
};

// Our binned variogram's non-empty bins against gstat's rows (one variogram).
void expect_gstat_bins(const std::string& ours_path, const std::string& theirs_path) {
  const CsvTable o = CsvTable::read(ours_path), t = CsvTable::read(theirs_path);
  std::vector<std::size_t> rows;
  for (std::size_t r = 0; r < o.row_count(); ++r)
    if (o.numeric_cell(r, o.column_index("pairs")) > 0.0) rows.push_back(r);
  ASSERT_EQ(rows.size(), t.row_count());
  ASSERT_GT(rows.size(), 3u);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    SCOPED_TRACE("bin " + std::to_string(k));
    EXPECT_EQ(o.numeric_cell(rows[k], o.column_index("pairs")), t.numeric_cell(k, t.column_index("np")));
    const double dist = t.numeric_cell(k, t.column_index("dist")), gamma = t.numeric_cell(k, t.column_index("gamma"));
    EXPECT_NEAR(o.numeric_cell(rows[k], o.column_index("lag_mean")), dist, 1e-12 * dist);
    EXPECT_NEAR(o.numeric_cell(rows[k], o.column_index("gamma")), gamma, 1e-12 * gamma);
  }
}

TEST_F(GstatVocabulary, CutoffAndWidthGiveGstatsBinsOnALattice) {
  auto r = run({"variogram", "--input", file("coalash.csv"), "--coords", "x,y", "--value", "coalash", "--cutoff", "10", "--width",
                "1", "--out", file("ours_cw.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.output();
  expect_gstat_bins(file("ours_cw.csv"), file("coalash_cw.csv"));
  r = run({"variogram", "--input", file("coalash.csv"), "--coords", "x,y", "--value", "coalash", "--cutoff", "7.5", "--out",
           file("ours_c.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.output();
  expect_gstat_bins(file("ours_c.csv"), file("coalash_c.csv"));
}

TEST_F(GstatVocabulary, BinsOnLatticeLagsWarnUnlessAConventionIsGiven) {
  auto r = run({"variogram", "--input", file("coalash.csv"), "--coords", "x,y", "--value", "coalash", "--bins", "0:10:1", "--out",
                file("ours_bins.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_NE(r.err.find("warning: lags fall exactly on --bins edges: bin 1 [0, 1) has 0 pairs"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("but 369 with gstat's"), std::string::npos) << r.err;
  r = run({"variogram", "--input", file("coalash.csv"), "--coords", "x,y", "--value", "coalash", "--bins", "0:10:1",
           "--convention", "paper", "--out", file("ours_bins_paper.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

TEST_F(GstatVocabulary, AveragedDuplicatesGiveGstatsResultAfterAveraging) {
  auto r = run({"variogram", "--input", file("dup.csv"), "--coords", "x,y", "--value", "z", "--duplicates", "average", "--cutoff",
                "60", "--width", "10", "--out", file("ours_dup_vario.csv")});
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_NE(r.err.find("18 row(s) at the location of an earlier row merged"), std::string::npos) << r.err;
  expect_gstat_bins(file("ours_dup_vario.csv"), file("dup_vario.csv"));

  const std::vector<std::string> krige{"interpolate", "--method", "kriging", "--samples", file("dup.csv"), "--targets",
                                       file("dup_targets.csv"), "--coords", "x,y", "--value", "z", "--model",
                                       "exp(sill=1,range=20)+nug(0.1)"};
  auto refused = krige;
  refused.insert(refused.end(), {"--out", file("ours_refused.csv")});
  r = run(refused);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--duplicates average"), std::string::npos) << r.err;
  auto averaged = krige;
  averaged.insert(averaged.end(), {"--duplicates", "average", "--out", file("ours_krige.csv")});
  r = run(averaged);
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable o = CsvTable::read(file("ours_krige.csv")), t = CsvTable::read(file("dup_krige.csv"));
  ASSERT_EQ(o.row_count(), t.row_count());
  for (std::size_t k = 0; k < t.row_count(); ++k) {
    EXPECT_NEAR(o.numeric_cell(k, o.column_index("pred")), t.numeric_cell(k, t.column_index("pred")), 1e-9) << k;
    EXPECT_NEAR(o.numeric_cell(k, o.column_index("var")), t.numeric_cell(k, t.column_index("var")), 1e-9) << k;
  }
}

}  // namespace gstat_vocabulary_test
}  // namespace errfield
