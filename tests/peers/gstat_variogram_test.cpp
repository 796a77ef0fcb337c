// Peer cross-check against R gstat (tests/peers/gstat_variogram.R, run at test time on data
// generated here): the empirical variogram with the same boundaries (gstat's bin convention)
// agrees to 1e-9 relative, Matheron and Cressie-Hawkins, and fit_variogram on gstat's own
// empirical variogram reaches a weighted SSE no worse than gstat's fit.variogram (or the same
// parameters), for Nj, Nj/gamma^2 and Nj/h^2 weights. Skipped when Rscript or gstat is missing.

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield {
namespace gstat_variogram_test {

namespace fs = std::filesystem;

bool gstat_available() {
  return std::system("Rscript -e 'suppressPackageStartupMessages(library(gstat))' >/dev/null 2>&1") == 0;
}

class GstatPeer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!gstat_available()) return;
    dir_ = fs::temp_directory_path() / ("errfield_gstat_peer_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // Simulated data: 3-D integer locations in a 1000 mm cube (integer coordinates make lags hit
    // the boundaries exactly, which tests the tie rule), a smooth field plus noise.
    std::mt19937_64 rng(20261122);
    std::uniform_int_distribution<int> u(0, 1000);
    std::normal_distribution<double> noise(0.0, 0.1);
    const int n = 500;
    x_.resize(n, 3);
    v_.resize(n, 1);
    std::ofstream out(dir_ / "data.csv");
    out << "x,y,z,v\n";
    for (int i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) x_(i, a) = u(rng);
      v_(i, 0) = std::sin(x_(i, 0) / 300.0) + 0.5 * std::cos(x_(i, 1) / 200.0) + noise(rng);
      out << format_number(x_(i, 0)) << "," << format_number(x_(i, 1)) << "," << format_number(x_(i, 2))
          << "," << format_number(v_(i, 0)) << "\n";
    }
    out.close();
    const std::string cmd = "Rscript " + std::string(ERRFIELD_SOURCE_DIR) +
                            "/tests/peers/gstat_variogram.R " + (dir_ / "data.csv").string() + " " +
                            kBoundaries + " " + (dir_ / "gstat").string() + " 2>" +
                            (dir_ / "r.log").string();
    ran_ = std::system(cmd.c_str()) == 0;
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  void SetUp() override {
    if (!gstat_available()) GTEST_SKIP() << "Rscript with the gstat package not found (apt-get install r-cran-gstat)";
    ASSERT_TRUE(ran_) << "gstat_variogram.R failed; see " << (dir_ / "r.log");
  }

  // gstat's boundaries b_1..b_n; our edges are 0, b_1, ..., b_n with the gstat convention.
  static constexpr const char* kBoundaries = "50,100,150,200,300,400,500,600,700,800,900,1000";
  static std::vector<double> edges() { return {0, 50, 100, 150, 200, 300, 400, 500, 600, 700, 800, 900, 1000}; }

  static inline fs::path dir_;
  static inline Eigen::MatrixXd x_, v_;
  static inline bool ran_ = false;
};

void compare_variogram(const EmpiricalVariogram& ours, const CsvTable& gstat) {
  // gstat drops empty bins; match its rows to our non-empty bins in order.
  std::size_t row = 0;
  const auto np = gstat.numeric_column("np");
  const auto dist = gstat.numeric_column("dist");
  const auto gamma = gstat.numeric_column("gamma");
  for (const auto& b : ours.bins) {
    if (b.pairs == 0) continue;
    ASSERT_LT(row, gstat.row_count());
    SCOPED_TRACE("bin [" + format_number(b.lag_lo) + ", " + format_number(b.lag_hi) + "]");
    EXPECT_EQ(static_cast<double>(b.pairs), np[row]);
    EXPECT_NEAR(b.lag_mean, dist[row], 1e-9 * dist[row]);
    EXPECT_NEAR(b.gamma, gamma[row], 1e-9 * gamma[row]);
    ++row;
  }
  EXPECT_EQ(row, gstat.row_count());
}

TEST_F(GstatPeer, EmpiricalVariogramMatchesWithTheSameBoundaries) {
  EmpiricalVariogramOptions o;
  o.convention = BinConvention::Gstat;
  const auto bins = LagBins::from_edges(edges());
  compare_variogram(empirical_variogram(x_, v_, bins, o),
                    CsvTable::read((dir_ / "gstat_matheron.csv").string()));
  o.estimator = VariogramEstimator::CressieHawkins;
  compare_variogram(empirical_variogram(x_, v_, bins, o),
                    CsvTable::read((dir_ / "gstat_cressie.csv").string()));
}

TEST_F(GstatPeer, DefaultBinsAreGstats) {
  // No bins given, 2-D data (x, y): gstat's cutoff (0.33333 x the bounding-box diagonal) and
  // width (cutoff / 15). (gstat 2.1's 3-D default is not the 3-D diagonal's third - on data
  // spanning a 1000 mm cube it came out 1615 mm instead of 1716 - so 3-D is not compared.)
  EmpiricalVariogramOptions o;
  o.convention = BinConvention::Gstat;
  const Eigen::MatrixXd xy = x_.leftCols(2);
  const LagBins bins = LagBins::gstat_default(xy);
  EXPECT_EQ(bins.size(), 15u);
  compare_variogram(empirical_variogram(xy, v_, bins, o), CsvTable::read((dir_ / "gstat_default.csv").string()));
}

TEST_F(GstatPeer, FitIsAtLeastAsGoodAsGstatFitVariogram) {
  // Both fit gstat's own empirical variogram, so the inputs are identical.
  const CsvTable vg = CsvTable::read((dir_ / "gstat_matheron.csv").string());
  const auto h = vg.numeric_column("dist");
  const auto g = vg.numeric_column("gamma");
  std::vector<std::uint64_t> n;
  for (double v : vg.numeric_column("np")) n.push_back(static_cast<std::uint64_t>(v));
  const CsvTable fits = CsvTable::read((dir_ / "gstat_fit.csv").string());
  const auto psill = fits.numeric_column("psill");
  const auto range = fits.numeric_column("range");
  const auto nugget = fits.numeric_column("nugget");
  const auto method = fits.numeric_column("method");
  ASSERT_EQ(fits.row_count(), 9u);
  for (std::size_t r = 0; r < fits.row_count(); ++r) {
    const std::string kind = fits.row(r)[fits.column_index("model")];
    const FitWeighting w = weighting_from_name(format_number(method[r]));
    SCOPED_TRACE(kind + " fit.method " + format_number(method[r]));
    VariogramFitOptions o;
    o.weighting = w;
    const ModelKind k = model_kind_from_name(kind);
    const auto ours = fit_variogram(h, g, n, {{k, 0.0, 0.0, 0.5}}, o);
    ASSERT_NE(ours.status, FitStatus::Failed) << ours.message;
    std::vector<ModelComponent> theirs{{k, psill[r], range[r], 0.5}};
    if (nugget[r] > 0.0) theirs.push_back({ModelKind::Nugget, nugget[r], 0.0, 0.5});
    const double sse_theirs = weighted_sse(h, g, n, VariogramModel(theirs), w);
    const auto& c = ours.model.components();
    const bool same_parameters = std::fabs(c[0].sill - psill[r]) <= 1e-3 * psill[r] &&
                                 std::fabs(c[0].range - range[r]) <= 1e-3 * range[r] &&
                                 std::fabs(ours.model.nugget() - nugget[r]) <= 1e-3 * psill[r];
    // Optimizers differ (gstat: Gauss-Newton with iterative reweighting for method 2; ours:
    // direct minimization with BOBYQA), so we require the criterion value, not the path:
    // ours <= gstat's (1 + 1e-6), or the same parameters to 1e-3 relative.
    EXPECT_TRUE(ours.weighted_sse <= sse_theirs * (1 + 1e-6) || same_parameters)
        << "ours " << ours.model.to_string() << " SSE " << ours.weighted_sse << "; gstat "
        << VariogramModel(theirs).to_string() << " SSE " << sse_theirs;
    RecordProperty(kind + "_" + format_number(method[r]) + "_sse_ratio",
                   format_number(ours.weighted_sse / sse_theirs));
  }
}


// Nested fits (issue 36): nug + sph + sph from one template, as gstat's vgm(..., add.to = ...), on a
// variogram that follows a nested model (gstat_variogram.R). Every parameter free: our weighted SSE
// reaches gstat's or lower. Ranges held (fit.ranges = FALSE): the sills solve a linear weighted
// least squares whose optimum is inside the feasible set here, unique, so both give the same sills.
TEST_F(GstatPeer, NestedTemplateFitsReachGstatsSse) {
  const CsvTable vg = CsvTable::read((dir_ / "gstat_nested_vario.csv").string());
  const auto h = vg.numeric_column("dist");
  const auto g = vg.numeric_column("gamma");
  std::vector<std::uint64_t> n;
  for (double v : vg.numeric_column("np")) n.push_back(static_cast<std::uint64_t>(v));
  const CsvTable fits = CsvTable::read((dir_ / "gstat_nested.csv").string());
  const auto method = fits.numeric_column("method");
  const auto structure = fits.numeric_column("structure");
  const auto start_psill = fits.numeric_column("start_psill");
  const auto start_range = fits.numeric_column("start_range");
  const auto psill = fits.numeric_column("psill");
  const auto range = fits.numeric_column("range");
  ASSERT_EQ(fits.row_count(), 12u);  // 2 cases x 2 methods x 3 rows
  for (std::size_t r0 = 0; r0 < fits.row_count(); r0 += 3) {
    const std::string fit_case = fits.row(r0)[fits.column_index("case")];
    SCOPED_TRACE(fit_case + " fit.method " + format_number(method[r0]));
    ASSERT_EQ(structure[r0], 0.0);  // gstat's first row is the nugget
    VariogramFitOptions o;
    o.weighting = weighting_from_name(format_number(method[r0]));
    o.nugget_start = start_psill[r0];
    std::vector<ModelComponent> tmpl, theirs;
    for (std::size_t r = r0 + 1; r < r0 + 3; ++r) {
      tmpl.push_back({ModelKind::Spherical, start_psill[r], start_range[r], 0.5});
      theirs.push_back({ModelKind::Spherical, psill[r], range[r], 0.5});
    }
    theirs.push_back({ModelKind::Nugget, psill[r0], 0.0, 0.5});
    if (fit_case == "fixed_ranges") o.hold_range = {true, true};
    const auto ours = fit_variogram(h, g, n, tmpl, o);
    ASSERT_EQ(ours.status, FitStatus::Converged) << ours.message;
    const double sse_theirs = weighted_sse(h, g, n, VariogramModel(theirs), o.weighting);
    EXPECT_LE(ours.weighted_sse, sse_theirs * (1 + 1e-6))
        << "ours " << ours.model.to_string() << "; gstat " << VariogramModel(theirs).to_string();
    if (fit_case == "fixed_ranges") {
      const auto& c = ours.model.components();
      ASSERT_EQ(c.size(), 3u);
      for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(c[k].range, theirs[k].range);
        EXPECT_NEAR(c[k].sill, theirs[k].sill, 1e-6 * VariogramModel(theirs).sill());
      }
      EXPECT_NEAR(ours.model.nugget(), psill[r0], 1e-6 * VariogramModel(theirs).sill());
    }
    RecordProperty(fit_case + "_" + format_number(method[r0]) + "_sse_ratio",
                   format_number(ours.weighted_sse / sse_theirs));
  }
}

}  // namespace
}  // namespace errfield
