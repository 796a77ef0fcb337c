// Cross-check of kriging with external drift against R gstat, run at test time on the Meuse data
// R's sp package ships (tests/peers/gstat_external_drift.R): gstat's classic
// krige(log(zinc) ~ sqrt(dist), meuse, meuse.grid, model), globally and with nmax = 20, with a
// polynomial drift plus the covariate (~ x + y + sqrt(dist)), the residual variogram
// variogram(log(zinc) ~ sqrt(dist), meuse) and krige.cv. errfield runs through its CLI
// (interpolate/cv/variogram --covariates sqrtdist) on the CSVs the R script wrote. Skipped with a
// message when Rscript, gstat or sp is missing.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <filesystem>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_external_drift_test {

using errfield::testing::csv_columns;
using errfield::testing::run_errfield;

// The models of the R script, in errfield's words (gstat's vgm(psill, model, range, nugget)).
constexpr const char* kSph = "sph(sill=0.15,range=800)+nug(0.05)";
constexpr const char* kExp = "exp(sill=0.12,range=250)+nug(0.04)";

// |ours - theirs| <= tol * max(|theirs|, floor), column by column, naming the row.
void expect_close(const Eigen::MatrixXd& ours, const Eigen::MatrixXd& theirs, double tol, double floor,
                  const std::string& what) {
  ASSERT_EQ(ours.rows(), theirs.rows()) << what;
  ASSERT_EQ(ours.cols(), theirs.cols()) << what;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < ours.rows(); ++i)
    for (Eigen::Index j = 0; j < ours.cols(); ++j) {
      const double scale = std::max(std::abs(theirs(i, j)), floor);
      worst = std::max(worst, std::abs(ours(i, j) - theirs(i, j)) / scale);
      EXPECT_NEAR(ours(i, j), theirs(i, j), tol * scale) << what << ", row " << i << ", column " << j;
    }
  std::cout << what << ": largest relative difference " << worst << "\n";
}

// The R script runs once for the suite (about 3 s); each test runs errfield on its CSVs.
class GstatExternalDrift : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_external_drift.R", "errfield_gstat_external_drift");
  }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_external_drift.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  inline static errfield::testing::GstatScriptRun gstat_;

  // Targets whose nmax-th and (nmax+1)-th nearest samples tie (3 of the 3103 Meuse grid cells with
  // nmax = 20) are left out of the comparison.
  std::vector<bool> tied_neighbourhoods(std::size_t nmax) const {
    return errfield::testing::tied_neighbourhoods(csv_columns(file("meuse.csv"), {"x", "y"}),
                                                  csv_columns(file("grid.csv"), {"x", "y"}), nmax);
  }
  void krige(const std::vector<std::string>& extra, const std::string& reference, std::size_t nmax = 0) {
    std::vector<std::string> args{"interpolate", "--method", "kriging", "--samples", file("meuse.csv"), "--targets",
                                  file("grid.csv"), "--coords", "x,y", "--value", "logzinc", "--covariates", "sqrtdist",
                                  "--out", file("ours.csv")};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_errfield(args, gstat_.root());
    ASSERT_EQ(r.exit_code, 0) << r.output();
    // Predictions are log(zinc) ~ 5..7.5, variances ~0.05..0.2: relative 1e-8 of each.
    Eigen::MatrixXd ours = csv_columns(file("ours.csv"), {"pred", "var"}), theirs = csv_columns(file(reference), {"pred", "var"});
    if (nmax > 0) {
      const std::vector<bool> tied = tied_neighbourhoods(nmax);
      const auto kept = static_cast<Eigen::Index>(std::count(tied.begin(), tied.end(), false));
      EXPECT_GE(kept, ours.rows() - 10) << "more ties than the Meuse grid has";
      Eigen::MatrixXd a(kept, 2), b(kept, 2);
      for (Eigen::Index t = 0, k = 0; t < ours.rows(); ++t)
        if (!tied[static_cast<std::size_t>(t)]) {
          a.row(k) = ours.row(t);
          b.row(k++) = theirs.row(t);
        }
      ours = a;
      theirs = b;
    }
    expect_close(ours, theirs, 1e-8, 1e-3, reference);
  }
  errfield::testing::ScratchDir dir_;
};

TEST_F(GstatExternalDrift, GlobalKrigingWithExternalDrift) {
  krige({"--model", kSph}, "ked.csv");
}

TEST_F(GstatExternalDrift, LocalKrigingWithExternalDriftNmax20) {
  krige({"--model", kSph, "--backend", "local", "--neighbors", "20"}, "ked_local.csv", 20);
}

// gstat picks the nmax neighbours by the plain Euclidean distance, whatever the anisotropy:
// errfield's --neighbour-metric euclidean, which searches the coordinates without the covariates.
TEST_F(GstatExternalDrift, AnisotropicLocalKrigingWithGstatsNeighbourhoods) {
  krige({"--model", "sph(sill=0.15,range=800)+nug(0.05)@anis(30,0.5)", "--backend", "local", "--neighbors", "20",
         "--neighbour-metric", "euclidean"},
        "anis_local.csv", 20);
}

TEST_F(GstatExternalDrift, LinearDriftPlusCovariate) {
  krige({"--model", kExp, "--kind", "universal1"}, "uk_ked.csv");
}

TEST_F(GstatExternalDrift, ResidualVariogramOfTheOlsTrend) {
  const auto r = run_errfield({"variogram", "--input", file("meuse.csv"), "--coords", "x,y", "--value", "logzinc",
                               "--covariates", "sqrtdist", "--out", file("vario.csv")},
                              gstat_.root());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const Eigen::MatrixXd ours_all = csv_columns(file("vario.csv"), {"pairs", "lag_mean", "gamma"});
  // gstat leaves out the empty bins.
  std::vector<Eigen::Index> used;
  for (Eigen::Index i = 0; i < ours_all.rows(); ++i)
    if (ours_all(i, 0) > 0) used.push_back(i);
  Eigen::MatrixXd ours(static_cast<Eigen::Index>(used.size()), 3);
  for (std::size_t k = 0; k < used.size(); ++k) ours.row(static_cast<Eigen::Index>(k)) = ours_all.row(used[k]);
  const Eigen::MatrixXd theirs = csv_columns(file("variogram.csv"), {"np", "dist", "gamma"});
  ASSERT_EQ(ours.rows(), theirs.rows());
  for (Eigen::Index i = 0; i < ours.rows(); ++i) EXPECT_EQ(ours(i, 0), theirs(i, 0)) << "pairs of bin " << i;
  expect_close(ours.rightCols(2), theirs.rightCols(2), 1e-10, 0.0, "variogram lag and gamma");
}

TEST_F(GstatExternalDrift, LeaveOneOutWithExternalDrift) {
  const auto r = run_errfield({"cv", "--method", "kriging", "--samples", file("meuse.csv"), "--coords", "x,y",
                               "--value", "logzinc", "--covariates", "sqrtdist", "--model", kSph, "--out",
                               file("cv_ours.csv")},
                              gstat_.root());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  // Residuals are ~0.3 in size: relative to 0.1 where they pass through zero.
  expect_close(csv_columns(file("cv_ours.csv"), {"pred", "var", "residual"}),
               csv_columns(file("cv.csv"), {"pred", "var", "residual"}), 1e-8, 0.1, "krige.cv");
}

}  // namespace gstat_external_drift_test
}  // namespace errfield
