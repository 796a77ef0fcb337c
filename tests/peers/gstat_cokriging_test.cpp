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
#include <nlohmann/json.hpp>

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

// Heterotopic cokriging (tests/peers/gstat_heterotopic.R): SIMULATED data, V at 80 locations, U at
// about 60 % of them (empty cells elsewhere); gstat with one data set per variable.
class GstatHeterotopicCokriging : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_heterotopic.R", "errfield_gstat_heterotopic");
    if (gstat_.available())
      std::ofstream(gstat_.root() / "lmc.json") << R"({"type": "lmc", "components": ["V", "U"],
  "structures": [{"kind": "nug", "sills": [[0.05, 0.02], [0.02, 0.04]]},
                 {"kind": "sph", "range": 40, "sills": [[0.8, 0.4], [0.4, 0.5]]}]})";
  }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_heterotopic.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  inline static errfield::testing::GstatScriptRun gstat_;

  static void cokrige(const std::vector<std::string>& extra, const std::string& reference,
                      const std::string& model = "lmc.json") {
    std::vector<std::string> args{"interpolate", "--method", "kriging", "--samples", file("samples.csv"), "--targets",
                                  file("targets.csv"), "--coords", "x,y", "--value", "V,U", "--model", file(model),
                                  "--out", file("ours.csv")};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_errfield(args, gstat_.root());
    ASSERT_EQ(r.exit_code, 0) << r.output();
    const Eigen::MatrixXd ours = csv_columns(file("ours.csv"), {"pred_V", "var_V", "pred_U", "var_U", "cov_V_U"});
    const Eigen::MatrixXd theirs = csv_columns(file(reference), {"V_pred", "V_var", "U_pred", "U_var", "cov"});
    ASSERT_EQ(ours.rows(), theirs.rows());
    // Values and variances are O(0.1..2); both solve the same ~130-unknown system: relative 1e-8.
    double worst = 0.0;
    for (Eigen::Index t = 0; t < ours.rows(); ++t)
      for (Eigen::Index j = 0; j < ours.cols(); ++j) {
        const double scale = std::max(std::abs(theirs(t, j)), 1e-3);
        worst = std::max(worst, std::abs(ours(t, j) - theirs(t, j)) / scale);
        EXPECT_NEAR(ours(t, j), theirs(t, j), 1e-8 * scale) << reference << ", target " << t << ", column " << j;
      }
    std::cout << reference << ": largest relative difference " << worst << "\n";
  }
};

TEST_F(GstatHeterotopicCokriging, PredictionsMatchGstat) {
  {
    SCOPED_TRACE("global ordinary cokriging, U at ~60 % of the samples");
    cokrige({}, "cok.csv");
  }
  {
    // gstat's maxdist takes each variable's data within 35; errfield's radius the samples within
    // 35 and, of each, the components it has: the same rows (no sample at exactly 35).
    SCOPED_TRACE("local ordinary cokriging, maxdist 35");
    cokrige({"--backend", "local", "--radius", "35", "--neighbour-metric", "euclidean"}, "cok_local.csv");
  }
}

TEST_F(GstatHeterotopicCokriging, VariogramsMatchGstat) {
  const auto r = run_errfield({"variogram", "--input", file("samples.csv"), "--coords", "x,y", "--value", "V,U", "--cross",
                               "--bins", "0,10,20,30,40,50,60", "--convention", "gstat", "--out", file("vario.csv")},
                              gstat_.root());
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable direct = CsvTable::read(file("direct.csv"));
  const Eigen::MatrixXd theirs_direct = csv_columns(file("direct.csv"), {"np", "dist", "gamma"});
  const Eigen::MatrixXd theirs_cross = csv_columns(file("cross.csv"), {"np", "dist", "gamma"});
  // Every bin has pairs here, so gstat's rows are the 6 bins in order for each variogram.
  for (const std::string id : {"V", "U"}) {
    const Eigen::MatrixXd ours = csv_columns(file("vario.csv"), {"pairs_" + id, "lag_mean_" + id, "gamma_" + id});
    Eigen::Index b = 0;
    for (std::size_t row = 0; row < direct.row_count(); ++row) {
      if (direct.cell(row, direct.column_index("id")) != id) continue;
      ASSERT_LT(b, ours.rows());
      const auto k = static_cast<Eigen::Index>(row);
      EXPECT_EQ(ours(b, 0), theirs_direct(k, 0)) << id << ", bin " << b;
      // Means of up to ~450 terms of size ~1: relative 1e-12 covers the summation order.
      EXPECT_NEAR(ours(b, 1), theirs_direct(k, 1), 1e-10 * theirs_direct(k, 1)) << id << ", bin " << b;
      EXPECT_NEAR(ours(b, 2), theirs_direct(k, 2), 1e-10 * theirs_direct(k, 2)) << id << ", bin " << b;
      ++b;
    }
    EXPECT_EQ(b, 6) << id;
  }
  const Eigen::MatrixXd ours = csv_columns(file("vario.csv"), {"pairs_V_U", "lag_mean_V_U", "gamma_V_U"});
  ASSERT_EQ(ours.rows(), theirs_cross.rows());
  for (Eigen::Index b = 0; b < ours.rows(); ++b) {
    // gstat counts a cross-variogram's pairs in both orders.
    EXPECT_EQ(2 * ours(b, 0), theirs_cross(b, 0)) << "bin " << b;
    EXPECT_NEAR(ours(b, 1), theirs_cross(b, 1), 1e-10 * theirs_cross(b, 1)) << "bin " << b;
    EXPECT_NEAR(ours(b, 2), theirs_cross(b, 2), 1e-10 * std::abs(theirs_cross(b, 2))) << "bin " << b;
  }
}

// fit-variogram --lmc on heterotopic samples, against gstat's fit.lmc (fit.ranges = FALSE, fit.method
// 7) on the heterotopic object's direct variograms (each variable over its own data) and the
// collocated cross-variogram: each variogram is fitted alone over its own bins and weights, then
// every structure's matrix made PSD. The nugget matrix's projection is exercised (rank 1 after it).
// Both solve the same 2-unknown weighted least-squares problems on variograms equal to ~1e-14: the
// sills to 1e-9 relative to the largest; cokriging with the fitted LMCs then as with a given one.
TEST_F(GstatHeterotopicCokriging, LmcFitMatchesGstatFitLmc) {
  auto run = [&](const std::vector<std::string>& args) {
    const auto r = run_errfield(args, gstat_.root());
    EXPECT_EQ(r.exit_code, 0) << r.output();
    return r;
  };
  run({"variogram", "--input", file("samples.csv"), "--coords", "x,y", "--value", "V,U", "--cross", "--bins",
       "0,10,20,30,40,50,60", "--convention", "gstat", "--out", file("vario.csv")});
  // No --lmc-method: heterotopic variograms take gstat's method, and say so.
  const auto fit = run({"fit-variogram", "--input", file("vario.csv"), "--value", "V,U", "--lmc", "--model",
                        "nug(0)+sph(1,40)", "--out", file("fit.json")});
  EXPECT_NE(fit.output().find("--lmc-method gstat"), std::string::npos) << fit.output();
  std::ifstream fitted(file("fit.json"));
  const auto j = nlohmann::json::parse(fitted);
  const Eigen::MatrixXd theirs = csv_columns(file("lmc_fit.csv"), {"V", "U", "V_U"});  // rows: nug, sph
  ASSERT_EQ(j.at("structures").size(), 2u);
  const double scale = theirs.cwiseAbs().maxCoeff();
  for (Eigen::Index k = 0; k < 2; ++k) {
    const auto& sills = j.at("structures")[static_cast<std::size_t>(k)].at("sills");
    EXPECT_NEAR(sills[0][0].get<double>(), theirs(k, 0), 1e-9 * scale) << "structure " << k << ", V";
    EXPECT_NEAR(sills[1][1].get<double>(), theirs(k, 1), 1e-9 * scale) << "structure " << k << ", U";
    EXPECT_NEAR(sills[0][1].get<double>(), theirs(k, 2), 1e-9 * scale) << "structure " << k << ", V.U";
  }
  {
    SCOPED_TRACE("global ordinary cokriging with the fitted LMC");
    cokrige({}, "cok_fit.csv", "fit.json");
  }
  // The samples themselves (--coords, gstat's default bins) fit as their variogram CSV does.
  run({"variogram", "--input", file("samples.csv"), "--coords", "x,y", "--value", "V,U", "--cross", "--convention",
       "gstat", "--out", file("vario_default.csv")});
  run({"fit-variogram", "--input", file("vario_default.csv"), "--value", "V,U", "--lmc", "--lmc-method", "gstat",
       "--model", "nug(0)+sph(1,40)", "--out", file("fit_csv.json")});
  run({"fit-variogram", "--input", file("samples.csv"), "--coords", "x,y", "--value", "V,U", "--lmc", "--model",
       "nug(0)+sph(1,40)", "--out", file("fit_samples.json")});
  std::ifstream csv_json(file("fit_csv.json")), samples_json(file("fit_samples.json"));
  const auto from_csv = nlohmann::json::parse(csv_json);
  const auto from_samples = nlohmann::json::parse(samples_json);
  for (std::size_t k = 0; k < 2; ++k)
    for (std::size_t a = 0; a < 2; ++a)
      for (std::size_t b = 0; b < 2; ++b) {
        const double x = from_samples.at("structures")[k].at("sills")[a][b].get<double>();
        const double y = from_csv.at("structures")[k].at("sills")[a][b].get<double>();
        // The CSV holds the variograms as shortest round-trip text: the same doubles.
        EXPECT_EQ(x, y) << "structure " << k << ", entry " << a << "," << b;
      }
  // Goulard-Voltz asked for explicitly: refused, naming the method that fits these.
  const auto gv = run_errfield({"fit-variogram", "--input", file("vario.csv"), "--value", "V,U", "--lmc", "--lmc-method",
                                "goulard-voltz", "--model", "nug(0)+sph(1,40)"},
                               gstat_.root());
  EXPECT_EQ(gv.exit_code, 2) << gv.output();
  EXPECT_NE(gv.output().find("gstat method"), std::string::npos) << gv.output();
}

}  // namespace gstat_cokriging_test
}  // namespace errfield
