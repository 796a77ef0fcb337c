// Cross-check of the variogram cloud, the variogram map and indicator kriging against R gstat, run
// at test time on the Meuse data R's sp package ships (tests/peers/gstat_cloud_map_indicator.R,
// one R run for the suite). errfield runs through its CLI on the CSVs the script wrote:
//  - variogram --cloud (omnidirectional and alpha = 45, tol.hor = 22.5) against variogram(...,
//    cloud = TRUE): the same pairs in the same order, dist and gamma to 1e-12 relative;
//  - variogram --map against variogram(..., map = TRUE) on an even grid (cutoff 1000, width 100)
//    and an uneven one (cutoff 950, width 125): Meuse's integer coordinates put lags exactly on
//    cell edges, so this also checks gstat's edge rule; the same cells and counts, gamma to 1e-12;
//  - interpolate --indicator with --order-correction none against krige(I(zinc < T) ~ 1) for three
//    thresholds that are data values (so the strict '<' matters), a model each: probabilities and
//    variances to 1e-8 (the same linear system; measured 2e-15);
//  - the default order correction against the correction computed here from the uncorrected output,
//    written differently (u_k as the maximum over j <= k, d_k as the minimum over j >= k).
// Skipped with a message when Rscript, gstat or sp is missing.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_cloud_map_indicator_test {

using errfield::testing::csv_columns;
using errfield::testing::run_errfield;

constexpr const char* kModels =
    "sph(sill=0.12,range=700)+nug(0.03);sph(sill=0.18,range=900)+nug(0.06);exp(sill=0.14,range=300)+nug(0.04)";

class GstatCloudMapIndicator : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_cloud_map_indicator.R", "errfield_gstat_cloud_map_indicator");
  }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_cloud_map_indicator.R failed";
  }
  static std::string file(const std::string& name) { return gstat_.file(name); }
  static void run(std::vector<std::string> args) {
    const auto r = run_errfield(args, gstat_.root());
    ASSERT_EQ(r.exit_code, 0) << r.output();
  }
  static inline errfield::testing::GstatScriptRun gstat_;
};

// Same rows: the key columns equal, gamma (and dist) to 1e-12 relative; gstat's NA (an empty
// cell) where ours is empty.
void expect_same_rows(const std::string& ours_path, const std::string& theirs_path, const std::vector<std::string>& keys,
                      const std::vector<std::string>& numbers) {
  const CsvTable ours = CsvTable::read(ours_path), theirs = CsvTable::read(theirs_path);
  ASSERT_EQ(ours.row_count(), theirs.row_count());
  ASSERT_GT(ours.row_count(), 100u);
  const Eigen::MatrixXd ok = ours.numeric_columns(keys), tk = theirs.numeric_columns(keys);
  EXPECT_EQ(ok, tk);
  std::size_t compared = 0;
  for (const auto& name : numbers) {
    const auto oc = ours.column_index(name), tc = theirs.column_index(name);
    for (std::size_t i = 0; i < ours.row_count(); ++i) {
      const std::string& a = ours.row(i)[oc];
      const std::string& b = theirs.row(i)[tc];
      ASSERT_EQ(a.empty(), b == "NA") << name << " row " << i + 1 << ": ours '" << a << "', gstat '" << b << "'";
      if (a.empty()) continue;
      const double x = std::stod(a), y = std::stod(b);
      EXPECT_NEAR(x, y, 1e-12 * std::fabs(y)) << name << " row " << i + 1;
      ++compared;
    }
  }
  EXPECT_GT(compared, 100u);
}

TEST_F(GstatCloudMapIndicator, CloudHasGstatsPairsInGstatsOrder) {
  const std::vector<std::string> base{"variogram", "--input", file("meuse.csv"), "--coords", "x,y", "--value", "logzinc",
                                      "--cloud", "--cutoff", "400"};
  auto omni = base;
  omni.insert(omni.end(), {"--out", file("ours_cloud.csv")});
  run(omni);
  expect_same_rows(file("ours_cloud.csv"), file("cloud.csv"), {"left", "right"}, {"dist", "gamma"});
  auto dir = base;
  dir.insert(dir.end(), {"--alpha", "45", "--tol-hor", "22.5", "--out", file("ours_cloud_dir.csv")});
  run(dir);
  expect_same_rows(file("ours_cloud_dir.csv"), file("cloud_dir.csv"), {"left", "right"}, {"dist", "gamma"});
}

TEST_F(GstatCloudMapIndicator, MapHasGstatsCellsCountsAndSemivariances) {
  run({"variogram", "--input", file("meuse.csv"), "--coords", "x,y", "--value", "logzinc", "--map", "100,100",
       "--cutoff", "1000", "--out", file("ours_map.csv")});
  expect_same_rows(file("ours_map.csv"), file("map.csv"), {"dx", "dy", "np"}, {"gamma"});
  run({"variogram", "--input", file("meuse.csv"), "--coords", "x,y", "--value", "logzinc", "--map", "125,125",
       "--cutoff", "950", "--out", file("ours_map_odd.csv")});
  expect_same_rows(file("ours_map_odd.csv"), file("map_odd.csv"), {"dx", "dy", "np"}, {"gamma"});
}

TEST_F(GstatCloudMapIndicator, IndicatorKrigingEqualsGstatsAndItsOrderCorrectionIsGslibs) {
  const std::vector<std::string> base{"interpolate", "--method", "kriging", "--samples", file("meuse.csv"),
                                      "--targets", file("grid.csv"), "--coords", "x,y", "--value", "zinc",
                                      "--indicator", "183,342,703", "--model", kModels};
  auto raw_args = base;
  raw_args.insert(raw_args.end(), {"--order-correction", "none", "--out", file("ours_ik_raw.csv")});
  run(raw_args);
  auto args = base;
  args.insert(args.end(), {"--out", file("ours_ik.csv")});
  run(args);
  const std::vector<std::string> p{"p_lt_183", "p_lt_342", "p_lt_703"};
  const Eigen::MatrixXd raw = csv_columns(file("ours_ik_raw.csv"), p);
  const Eigen::MatrixXd var = csv_columns(file("ours_ik_raw.csv"), {"var_lt_183", "var_lt_342", "var_lt_703"});
  const Eigen::MatrixXd theirs = csv_columns(file("indicator.csv"), {"p1", "p2", "p3"});
  const Eigen::MatrixXd theirs_var = csv_columns(file("indicator.csv"), {"v1", "v2", "v3"});
  ASSERT_EQ(raw.rows(), 300);
  EXPECT_LE((raw - theirs).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LE((var - theirs_var).cwiseAbs().maxCoeff(), 1e-8);
  RecordProperty("max_abs_difference_from_gstat", format_number((raw - theirs).cwiseAbs().maxCoeff()));

  // The correction, computed here: clip, then u_k = max_{j <= k} p_j, d_k = min_{j >= k} p_j.
  const Eigen::MatrixXd corrected = csv_columns(file("ours_ik.csv"), p);
  const Eigen::MatrixXd corrected_var = csv_columns(file("ours_ik.csv"), {"var_lt_183", "var_lt_342", "var_lt_703"});
  EXPECT_EQ(corrected_var, var);  // the variances are not corrected
  int decreasing = 0, outside = 0;
  for (Eigen::Index t = 0; t < raw.rows(); ++t) {
    Eigen::RowVector3d q = raw.row(t).cwiseMax(0.0).cwiseMin(1.0);
    for (int k = 0; k < 3; ++k) {
      outside += (raw(t, k) < 0.0 || raw(t, k) > 1.0) ? 1 : 0;
      decreasing += (k > 0 && q(k) < q(k - 1)) ? 1 : 0;
      const double u = q.head(k + 1).maxCoeff(), d = q.tail(3 - k).minCoeff();
      EXPECT_NEAR(corrected(t, k), 0.5 * (u + d), 1e-15) << "target " << t + 1 << " threshold " << k + 1;
    }
  }
  // The data exercise both repairs.
  EXPECT_GT(decreasing, 0);
  EXPECT_GT(outside, 0);
}

}  // namespace gstat_cloud_map_indicator_test
}  // namespace errfield
