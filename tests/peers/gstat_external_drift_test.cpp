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
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace gstat_external_drift_test {

using errfield::testing::run_errfield;
using errfield::testing::ScratchDir;

bool gstat_with_meuse() {
  return std::system("Rscript -e 'suppressPackageStartupMessages({library(gstat); library(sp)})' >/dev/null 2>&1") == 0;
}

// The models of the R script, in errfield's words (gstat's vgm(psill, model, range, nugget)).
constexpr const char* kSph = "sph(sill=0.15,range=800)+nug(0.05)";
constexpr const char* kExp = "exp(sill=0.12,range=250)+nug(0.04)";

Eigen::MatrixXd columns(const std::string& path, const std::vector<std::string>& names) {
  return CsvTable::read(path).numeric_columns(names);
}

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

class GstatExternalDrift : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!gstat_with_meuse()) GTEST_SKIP() << "Rscript with gstat and sp not found; install r-cran-gstat to run this cross-check";
    const std::string cmd = "Rscript '" ERRFIELD_SOURCE_DIR "/tests/peers/gstat_external_drift.R' '" +
                            dir_.path().string() + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  void krige(const std::vector<std::string>& extra, const std::string& reference) {
    std::vector<std::string> args{"interpolate", "--method", "kriging", "--samples", dir_ / "meuse.csv", "--targets",
                                  dir_ / "grid.csv", "--coords", "x,y", "--value", "logzinc", "--covariates", "sqrtdist",
                                  "--out", dir_ / "ours.csv"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_errfield(args, dir_.path());
    ASSERT_EQ(r.exit_code, 0) << r.output();
    // Predictions are log(zinc) ~ 5..7.5, variances ~0.05..0.2: relative 1e-8 of each.
    expect_close(columns(dir_ / "ours.csv", {"pred", "var"}), columns(dir_ / reference, {"pred", "var"}), 1e-8, 1e-3,
                 reference);
  }
  ScratchDir dir_;
};

TEST_F(GstatExternalDrift, GlobalKrigingWithExternalDrift) {
  krige({"--model", kSph}, "ked.csv");
}

TEST_F(GstatExternalDrift, LocalKrigingWithExternalDriftNmax20) {
  krige({"--model", kSph, "--backend", "local", "--neighbors", "20"}, "ked_local.csv");
}

TEST_F(GstatExternalDrift, LinearDriftPlusCovariate) {
  krige({"--model", kExp, "--kind", "universal1"}, "uk_ked.csv");
}

TEST_F(GstatExternalDrift, ResidualVariogramOfTheOlsTrend) {
  const auto r = run_errfield({"variogram", "--input", dir_ / "meuse.csv", "--coords", "x,y", "--value", "logzinc",
                               "--covariates", "sqrtdist", "--out", dir_ / "vario.csv"},
                              dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const Eigen::MatrixXd ours_all = columns(dir_ / "vario.csv", {"pairs", "lag_mean", "gamma"});
  // gstat leaves out the empty bins.
  std::vector<Eigen::Index> used;
  for (Eigen::Index i = 0; i < ours_all.rows(); ++i)
    if (ours_all(i, 0) > 0) used.push_back(i);
  Eigen::MatrixXd ours(static_cast<Eigen::Index>(used.size()), 3);
  for (std::size_t k = 0; k < used.size(); ++k) ours.row(static_cast<Eigen::Index>(k)) = ours_all.row(used[k]);
  const Eigen::MatrixXd theirs = columns(dir_ / "variogram.csv", {"np", "dist", "gamma"});
  ASSERT_EQ(ours.rows(), theirs.rows());
  for (Eigen::Index i = 0; i < ours.rows(); ++i) EXPECT_EQ(ours(i, 0), theirs(i, 0)) << "pairs of bin " << i;
  expect_close(ours.rightCols(2), theirs.rightCols(2), 1e-10, 0.0, "variogram lag and gamma");
}

TEST_F(GstatExternalDrift, LeaveOneOutWithExternalDrift) {
  const auto r = run_errfield({"cv", "--method", "kriging", "--samples", dir_ / "meuse.csv", "--coords", "x,y",
                               "--value", "logzinc", "--covariates", "sqrtdist", "--model", kSph, "--out",
                               dir_ / "cv_ours.csv"},
                              dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  // Residuals are ~0.3 in size: relative to 0.1 where they pass through zero.
  expect_close(columns(dir_ / "cv_ours.csv", {"pred", "var", "residual"}),
               columns(dir_ / "cv.csv", {"pred", "var", "residual"}), 1e-8, 0.1, "krige.cv");
}

}  // namespace gstat_external_drift_test
}  // namespace errfield
