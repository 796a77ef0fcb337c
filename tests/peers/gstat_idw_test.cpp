// Cross-check of ScatteredIdw against R gstat's idw() (Debian r-cran-gstat) on generated data:
// same power (idp) and neighbour count (nmax), predictions agree to 1e-9 relative. The reference
// is produced at test time by tests/peers/gstat_idw.R; the test is skipped when Rscript or gstat
// is not installed.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/scattered_idw.hpp"

namespace errfield {
namespace gstat_idw_test {

namespace fs = std::filesystem;

bool have_rscript() { return std::system("command -v Rscript > /dev/null 2>&1") == 0; }

TEST(GstatIdwPeer, ScatteredIdwAgreesWithGstatIdw) {
  if (!have_rscript()) GTEST_SKIP() << "Rscript not found: install r-cran-gstat (scripts/setup.sh) to run this cross-check";
  const fs::path dir = fs::temp_directory_path() / ("errfield_gstat_idw_" + std::to_string(::getpid()));
  fs::create_directories(dir);

  // Simulated data: 500 samples of a smooth error field in a 500 mm cube plus noise, 200 targets.
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> locs(500), targets(200);
  std::vector<double> vals;
  std::ofstream s(dir / "samples.csv");
  s << "x,y,z,v\n";
  for (auto& p : locs) {
    p = Eigen::Vector3d(u(rng), u(rng), u(rng));
    vals.push_back(0.4 * std::sin(p.x() / 140.0) * std::cos(p.y() / 200.0) + 6e-4 * p.z() + noise(rng));
    s << format_number(p.x()) << "," << format_number(p.y()) << "," << format_number(p.z()) << ","
      << format_number(vals.back()) << "\n";
  }
  s.close();
  std::ofstream t(dir / "targets.csv");
  t << "x,y,z\n";
  for (auto& p : targets) {
    p = Eigen::Vector3d(u(rng), u(rng), u(rng));
    t << format_number(p.x()) << "," << format_number(p.y()) << "," << format_number(p.z()) << "\n";
  }
  t.close();
  // A target exactly on a sample: both must return the sample's value.
  {
    std::ofstream app(dir / "targets.csv", std::ios::app);
    app << format_number(locs[17].x()) << "," << format_number(locs[17].y()) << "," << format_number(locs[17].z()) << "\n";
    targets.push_back(locs[17]);
  }

  struct Case {
    double idp;
    std::size_t nmax;  // 0 = all
  };
  const std::vector<Case> cases{{2.0, 8}, {1.0, 12}, {3.0, 5}, {2.0, 0}, {1.5, 30}};
  const fs::path out = dir / "gstat.csv";
  std::string cmd = "Rscript " + std::string(ERRFIELD_SOURCE_DIR) + "/tests/peers/gstat_idw.R " +
                    (dir / "samples.csv").string() + " " + (dir / "targets.csv").string() + " " + out.string();
  for (const Case& c : cases) {
    cmd += ' ';
    cmd += format_number(c.idp);
    cmd += ':';
    cmd += c.nmax ? std::to_string(c.nmax) : std::string("Inf");
  }
  cmd += " > " + (dir / "r.log").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  if (WIFEXITED(status) && WEXITSTATUS(status) == 77) {
    fs::remove_all(dir);
    GTEST_SKIP() << "R package gstat not installed (r-cran-gstat)";
  }
  ASSERT_EQ(status, 0) << "Rscript failed: " << cmd;
  const auto table = CsvTable::read(out.string());
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    SCOPED_TRACE(::testing::Message() << "idp " << c.idp << " nmax " << c.nmax);
    const auto ref = table.numeric_column("pred" + std::to_string(k + 1));
    ASSERT_EQ(ref.size(), targets.size());
    ScatteredIdwOptions o;
    o.power = c.idp;
    o.neighbors = c.nmax;
    const auto pred = ScatteredIdw<Eigen::Vector3d, double>(locs, vals, o).predict(targets);
    for (std::size_t i = 0; i < ref.size(); ++i)
      // 1e-9 relative; values near a zero crossing are compared on the data's scale (0.01 mm).
      EXPECT_LE(std::abs(pred[i] - ref[i]), 1e-9 * std::max(std::abs(ref[i]), 1e-2))
          << "target " << i << ": ours " << pred[i] << ", gstat " << ref[i];
    EXPECT_EQ(pred.back(), vals[17]);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace errfield
