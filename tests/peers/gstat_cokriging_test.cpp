// Cross-check of cokriging against R gstat, run at test time on the Meuse data R's sp package
// ships (tests/peers/gstat_cokriging.R): ordinary cokriging of log(zinc) and log(copper) with an
// explicit linear model of coregionalization (nugget + Sph(800) for the direct and the cross
// variogram), gstat's predict() on meuse.grid globally, with nmax = 20, and with a linear drift per
// variable, and gstat.cv's leave-one-out. errfield runs through its CLI (interpolate and cv
// --method kriging --model lmc.json) on the CSVs the R script wrote. Skipped with a message when
// Rscript, gstat or sp is missing.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_cokriging_test {

using errfield::testing::csv_columns;
using errfield::testing::run_errfield;

// The R script's model in errfield's words: gstat's vgm(psill, "Sph", 800, nugget) per direct
// and cross variogram become the nugget and the Sph coregionalization matrices.
constexpr const char* kLmc = R"({"type": "lmc", "components": ["lzn", "lcu"],
  "structures": [{"kind": "nug", "sills": [[0.05, 0.02], [0.02, 0.04]]},
                 {"kind": "sph", "range": 800, "sills": [[0.55, 0.25], [0.25, 0.15]]}]})";

// The R script runs once for the suite (about 2 s); each test runs errfield on its CSVs.
class GstatCokriging : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_cokriging.R", "errfield_gstat_cokriging");
    if (gstat_.available()) std::ofstream(gstat_.root() / "lmc.json") << kLmc;
  }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_cokriging.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  inline static errfield::testing::GstatScriptRun gstat_;

  // Targets whose nmax-th and (nmax+1)-th nearest samples tie are left out of the comparison.
  static std::vector<bool> tied_neighbourhoods(std::size_t nmax) {
    return errfield::testing::tied_neighbourhoods(csv_columns(file("meuse.csv"), {"x", "y"}),
                                                  csv_columns(file("grid.csv"), {"x", "y"}), nmax);
  }

  static void cokrige(const std::vector<std::string>& extra, const std::string& reference, std::size_t nmax = 0) {
    std::vector<std::string> args{"interpolate", "--method", "kriging", "--samples", file("meuse.csv"), "--targets",
                                  file("grid.csv"), "--coords", "x,y", "--value", "lzn,lcu", "--model", file("lmc.json"),
                                  "--out", file("ours.csv")};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_errfield(args, gstat_.root());
    ASSERT_EQ(r.exit_code, 0) << r.output();
    const Eigen::MatrixXd ours = csv_columns(file("ours.csv"), {"pred_lzn", "var_lzn", "pred_lcu", "var_lcu", "cov_lzn_lcu"});
    const Eigen::MatrixXd theirs = csv_columns(file(reference), {"lzn_pred", "lzn_var", "lcu_pred", "lcu_var", "cov"});
    ASSERT_EQ(ours.rows(), theirs.rows());
    const std::vector<bool> tied = nmax > 0 ? tied_neighbourhoods(nmax) : std::vector<bool>(ours.rows(), false);
    EXPECT_LE(std::count(tied.begin(), tied.end(), true), 10) << "more ties than the Meuse grid has";
    // Predictions are log values ~4..7.5, variances and covariances ~0.02..0.6: relative 1e-8.
    const char* names[] = {"lzn.pred", "lzn.var", "lcu.pred", "lcu.var", "cov.lzn.lcu"};
    double worst = 0.0;
    for (Eigen::Index t = 0; t < ours.rows(); ++t) {
      if (tied[static_cast<std::size_t>(t)]) continue;
      for (Eigen::Index j = 0; j < ours.cols(); ++j) {
        const double scale = std::max(std::abs(theirs(t, j)), 1e-3);
        worst = std::max(worst, std::abs(ours(t, j) - theirs(t, j)) / scale);
        EXPECT_NEAR(ours(t, j), theirs(t, j), 1e-8 * scale) << reference << ", grid cell " << t << ", " << names[j];
      }
    }
    std::cout << reference << ": largest relative difference " << worst << "\n";
  }
};

// One test for the three predictions: ctest runs every test in its own process, and each runs the
// R script (~4 s) first.
TEST_F(GstatCokriging, PredictionsMatchGstat) {
  {
    SCOPED_TRACE("global ordinary cokriging");
    cokrige({}, "cok.csv");
  }
  {
    // gstat's universal cokriging: each variable with its own linear drift in x and y.
    SCOPED_TRACE("global universal cokriging, ~ x + y");
    cokrige({"--kind", "universal1"}, "cok_universal.csv");
  }
  {
    SCOPED_TRACE("local ordinary cokriging, nmax = 20");
    cokrige({"--backend", "local", "--neighbors", "20", "--neighbour-metric", "euclidean"}, "cok_local.csv", 20);
  }
}

// gstat.cv(remove.all = TRUE): every variable of a sample left out, as errfield's leave-one-out
// (the block form of Dubrule's closed form, docs/kriging.md).
TEST_F(GstatCokriging, LeaveOneOutCokriging) {
  const auto r = run_errfield({"cv", "--method", "kriging", "--samples", file("meuse.csv"), "--coords", "x,y", "--value",
                               "lzn,lcu", "--model", file("lmc.json"), "--out", file("cv_ours.csv")},
                              gstat_.root());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const Eigen::MatrixXd ours = csv_columns(file("cv_ours.csv"), {"pred_lzn", "var_lzn", "residual_lzn", "residual_lcu"});
  const Eigen::MatrixXd theirs = csv_columns(file("cv.csv"), {"lzn_pred", "lzn_var", "lzn_residual", "lcu_residual"});
  ASSERT_EQ(ours.rows(), theirs.rows());
  double worst = 0.0;
  for (Eigen::Index i = 0; i < ours.rows(); ++i)
    for (Eigen::Index j = 0; j < ours.cols(); ++j) {
      // Residuals are ~0.3 in size: relative to 0.1 where they pass through zero.
      const double scale = std::max(std::abs(theirs(i, j)), 0.1);
      worst = std::max(worst, std::abs(ours(i, j) - theirs(i, j)) / scale);
      EXPECT_NEAR(ours(i, j), theirs(i, j), 1e-8 * scale) << "sample " << i << ", column " << j;
    }
  std::cout << "gstat.cv: largest relative difference " << worst << "\n";
}

}  // namespace gstat_cokriging_test
}  // namespace errfield
