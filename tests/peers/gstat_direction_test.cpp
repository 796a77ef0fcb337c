// Peer cross-check against R gstat (tests/peers/gstat_direction.R, run at test time on data
// generated here): directional empirical variograms, gstat's alpha/tol.hor in 2-D (its default
// tolerance 90/length(alpha) and a narrow one) and alpha/beta/tol.ver in 3-D, with the same
// boundaries (gstat's bin convention), with the automatic pair search (all pairs, for 300 points)
// and a forced one (the sorted columns; the ordered cell list for a dip test with a nonzero dip).
// Pair counts equal, mean lag and gamma to 1e-12 relative
// (the sums differ only in their order). The coordinates are random reals, so no pair lies within
// rounding of a tolerance boundary, where gstat (pi = 3.14159265359) and errfield (std::numbers::pi)
// may round differently (docs/geostatistics.md, "Directional variograms"). Skipped when Rscript or
// gstat is missing.

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"

namespace errfield {
namespace gstat_direction_test {

namespace fs = std::filesystem;

bool gstat_available() {
  return std::system("Rscript -e 'suppressPackageStartupMessages(library(gstat))' >/dev/null 2>&1") == 0;
}

class GstatDirectionPeer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!gstat_available()) return;
    dir_ = fs::temp_directory_path() / ("errfield_gstat_direction_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // SIMULATED: 300 points in a 100 x 100 x 50 box, a trend along x plus noise.
    std::mt19937_64 rng(20261123);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 1.0);
    const int n = 300;
    x_.resize(n, 3);
    v_.resize(n, 1);
    std::ofstream out(dir_ / "data.csv");
    out << "x,y,z,v\n";
    for (int i = 0; i < n; ++i) {
      x_(i, 0) = 100.0 * u(rng);
      x_(i, 1) = 100.0 * u(rng);
      x_(i, 2) = 50.0 * u(rng);
      v_(i, 0) = 0.05 * x_(i, 0) + std::sin(x_(i, 1) / 20.0) + noise(rng);
      out << format_number(x_(i, 0)) << "," << format_number(x_(i, 1)) << "," << format_number(x_(i, 2))
          << "," << format_number(v_(i, 0)) << "\n";
    }
    out.close();
    const std::string cmd = "Rscript " + std::string(ERRFIELD_SOURCE_DIR) + "/tests/peers/gstat_direction.R " +
                            (dir_ / "data.csv").string() + " 16,32,48,64,80 " + (dir_ / "gstat").string() +
                            " 2>" + (dir_ / "r.log").string();
    ran_ = std::system(cmd.c_str()) == 0;
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  void SetUp() override {
    if (!gstat_available()) GTEST_SKIP() << "Rscript with the gstat package not found (apt-get install r-cran-gstat)";
    ASSERT_TRUE(ran_) << "gstat_direction.R failed; see " << (dir_ / "r.log");
  }

  // Ours for each direction in turn, compared with gstat's rows (empty bins dropped) in order.
  static void compare(const std::string& file, const Eigen::MatrixXd& x,
                      const std::vector<VariogramDirection>& directions) {
    const CsvTable g = CsvTable::read((dir_ / file).string());
    const auto np = g.numeric_column("np");
    const auto dist = g.numeric_column("dist");
    const auto gamma = g.numeric_column("gamma");
    const auto hor = g.numeric_column("dir.hor");
    const auto ver = g.numeric_column("dir.ver");
    // Automatic (all pairs for 300 points) and a forced pair search (the sorted columns, or for a
    // dip test with a nonzero dip the ordered cell list): the same rows.
    for (PairSearch search : {PairSearch::Automatic, PairSearch::CellList}) {
      std::size_t row = 0;
      for (const VariogramDirection& d : directions) {
        SCOPED_TRACE(file + " " + d.to_string() + (search == PairSearch::CellList ? " forced pair search" : ""));
        EmpiricalVariogramOptions o;
        o.convention = BinConvention::Gstat;
        o.direction = d;
        o.pair_search = search;
        const auto ours = empirical_variogram(x, v_, LagBins::uniform(0.0, 80.0, 16.0), o);
        for (const auto& b : ours.bins) {
          if (b.pairs == 0) continue;
          ASSERT_LT(row, g.row_count());
          SCOPED_TRACE("bin [" + format_number(b.lag_lo) + ", " + format_number(b.lag_hi) + "]");
          EXPECT_EQ(hor[row], d.alpha_deg());
          EXPECT_EQ(ver[row], d.beta_deg());
          EXPECT_EQ(static_cast<double>(b.pairs), np[row]);
          EXPECT_NEAR(b.lag_mean, dist[row], 1e-12 * dist[row]);
          EXPECT_NEAR(b.gamma, gamma[row], 1e-12 * gamma[row]);
          ++row;
        }
    }
    EXPECT_EQ(row, g.row_count());
    }
  }

  static inline fs::path dir_;
  static inline Eigen::MatrixXd x_, v_;
  static inline bool ran_ = false;
};

TEST_F(GstatDirectionPeer, HorizontalDirectionsWithGstatsDefaultTolerance) {
  std::vector<VariogramDirection> d;
  for (double a : {0.0, 45.0, 90.0, 135.0}) d.push_back(VariogramDirection::gstat(a, 22.5));
  compare("gstat_2d_default.csv", x_.leftCols(2), d);
}

TEST_F(GstatDirectionPeer, NarrowToleranceAndAnAlphaBeyond180) {
  compare("gstat_2d_narrow.csv", x_.leftCols(2),
          {VariogramDirection::gstat(30.0, 10.0), VariogramDirection::gstat(200.0, 10.0)});
}

TEST_F(GstatDirectionPeer, HorizontalDipIn3D) {
  compare("gstat_3d_flat.csv", x_, {VariogramDirection::gstat(45.0, 30.0, 0.0, 20.0)});
}

TEST_F(GstatDirectionPeer, DipIn3D) {
  compare("gstat_3d_dip.csv", x_,
          {VariogramDirection::gstat(45.0, 30.0, 30.0, 20.0), VariogramDirection::gstat(45.0, 30.0, -20.0, 20.0)});
}

}  // namespace
}  // namespace errfield
