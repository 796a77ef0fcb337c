// Peer cross-check against R gstat (tests/peers/gstat_lmc.R, run at test time) on the meuse data
// of R's sp package (log zinc, copper, lead; real measurements, not simulated):
//  - variogram(g) of a three-variable gstat object against empirical_variogram with
//    cross_variograms, gstat's default bins (cutoff = diagonal / 3, width = cutoff / 15) and
//    boundaries: every direct and cross gamma and mean lag to 1e-12 relative, np exactly. gstat
//    counts a cross-variogram's pairs in both orders, (x_i, x_j) and (x_j, x_i), so its np for a
//    cross id is twice ours (the gamma is the same: each product appears twice over twice the pairs).
//  - fit.lmc against fit_coregionalization with LmcFitMethod::Gstat and weights nj_h2. What gstat
//    2.1's fit.lmc does (getAnywhere(fit.lmc)): with fit.ranges = FALSE (its default) it calls
//    fit.variogram(x, model, fit.ranges = FALSE) on each direct and cross variogram separately
//    (fit.method 7: weights N_j / h_j^2) — a linear fit of the partial sills; fit.variogram, for a
//    direct variogram whose fit has a negative partial sill, sets it to 0, fixes it and refits the
//    others. Then, per structure, the P x P matrix of partial sills is replaced by
//    V max(D, 0) V^T (posdef(): eigenvalues below 0 set to 0) and its diagonal multiplied by
//    correct.diagonal = 1. The exp model below has a nugget matrix with a negative eigenvalue, so
//    the projection is exercised. Sills agree to 1e-8 relative to the largest sill.
// Skipped when Rscript, gstat or sp is missing.

#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "errfield/coregionalization_fit.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "support/gstat_peer.hpp"

namespace errfield {
namespace gstat_lmc_test {

class GstatLmcPeer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gstat_.start(ERRFIELD_SOURCE_DIR "/tests/peers/gstat_lmc.R", "errfield_gstat_lmc_peer");
  }
  static void TearDownTestSuite() { gstat_.finish(); }
  void SetUp() override {
    if (!gstat_.available()) GTEST_SKIP() << errfield::testing::kGstatMissing;
    ASSERT_TRUE(gstat_.succeeded()) << "tests/peers/gstat_lmc.R failed";
  }
  static EmpiricalVariogram ours() {
    const CsvTable t = CsvTable::read(gstat_.file("meuse.csv"));
    const Eigen::MatrixXd x = t.numeric_columns({"x", "y"});
    const Eigen::MatrixXd z = t.numeric_columns(names());
    EmpiricalVariogramOptions o;
    o.convention = BinConvention::Gstat;
    o.cross_variograms = true;
    return empirical_variogram(x, z, LagBins::gstat_default(x), o);
  }
  static std::vector<std::string> names() { return {"lzn", "lcu", "lpb"}; }
  // gstat's id of the direct (a == b) or cross variogram of components a <= b.
  static std::string id(int a, int b) { return a == b ? names()[a] : names()[a] + "." + names()[b]; }

  inline static errfield::testing::GstatScriptRun gstat_;
};

TEST_F(GstatLmcPeer, DirectAndCrossVariogramsMatchGstatsMultivariableVariogram) {
  const EmpiricalVariogram v = ours();
  const CsvTable g = CsvTable::read(gstat_.file("variogram.csv"));
  const std::size_t c_id = g.column_index("id");
  std::map<std::string, std::vector<std::size_t>> rows;  // id -> rows in bin order
  for (std::size_t r = 0; r < g.row_count(); ++r) rows[g.row(r)[c_id]].push_back(r);
  ASSERT_EQ(rows.size(), 6u);
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      const std::vector<std::size_t>& mine = rows[id(a, b)];
      std::size_t next = 0;
      for (std::size_t k = 0; k < v.bins.size(); ++k) {
        if (v.bins[k].pairs == 0) continue;  // gstat drops empty bins
        ASSERT_LT(next, mine.size()) << id(a, b);
        const std::size_t r = mine[next++];
        SCOPED_TRACE(id(a, b) + " bin " + std::to_string(k));
        EXPECT_EQ(g.numeric_cell(r, g.column_index("np")), static_cast<double>((a == b ? 1 : 2) * v.bins[k].pairs));
        const double dist = g.numeric_cell(r, g.column_index("dist"));
        const double gamma = g.numeric_cell(r, g.column_index("gamma"));
        EXPECT_NEAR(v.bins[k].lag_mean, dist, 1e-12 * dist);
        EXPECT_NEAR(v.gamma_of(k, a, b), gamma, 1e-12 * std::abs(gamma));
      }
      EXPECT_EQ(next, mine.size()) << id(a, b);
    }
}

TEST_F(GstatLmcPeer, GstatMethodMatchesFitLmc) {
  const CrossVariogramTable table = CrossVariogramTable::from(ours());
  struct Case {
    std::string file;
    std::vector<ModelComponent> structures;
  };
  for (const Case& c : {Case{"fit_sph.csv", {{.kind = ModelKind::Nugget}, {.kind = ModelKind::Spherical, .range = 800.0}}},
                        Case{"fit_exp.csv", {{.kind = ModelKind::Nugget}, {.kind = ModelKind::Exponential, .range = 300.0}}}}) {
    SCOPED_TRACE(c.file);
    CoregionalizationFitOptions o;
    o.method = LmcFitMethod::Gstat;
    o.weighting = LmcWeighting::NjOverH2;
    const CoregionalizationFitResult r = fit_coregionalization(table, c.structures, o, names());
    const CsvTable g = CsvTable::read(gstat_.file(c.file));
    ASSERT_EQ(g.row_count(), 6u * c.structures.size());
    double largest = 0.0;
    for (const auto& s : r.model.structures()) largest = std::max(largest, s.sills.cwiseAbs().maxCoeff());
    for (std::size_t row = 0; row < g.row_count(); ++row) {
      const std::string name = g.row(row)[g.column_index("id")];
      const auto k = static_cast<std::size_t>(g.numeric_cell(row, g.column_index("structure")));
      int a = -1, b = -1;
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j)
          if (id(i, j) == name) a = i, b = j;
      ASSERT_GE(a, 0) << name;
      EXPECT_NEAR(r.model.structures()[k].sills(a, b), g.numeric_cell(row, g.column_index("psill")), 1e-8 * largest)
          << name << " structure " << k;
    }
    if (c.file == "fit_exp.csv") {
      EXPECT_LT(r.smallest_eigenvalue_before_projection[0], 0.0);  // projection active
    }
    // Goulard-Voltz on the same table is PSD and no worse in the objective both report.
    o.method = LmcFitMethod::GoulardVoltz;
    const CoregionalizationFitResult gv = fit_coregionalization(table, c.structures, o, names());
    EXPECT_LE(gv.weighted_residual, r.weighted_residual);
  }
}

}  // namespace gstat_lmc_test
}  // namespace errfield
