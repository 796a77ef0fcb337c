// `errfield variogram --alpha/--tol-hor/--beta/--tol-ver/--per-coordinate` through the executable:
// the existing columns stay first and unchanged, one block of rows per direction with its label
// column, numbers equal to the library's directional variogram; gstat's default tolerance.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "support/cli_harness.hpp"

#include <nlohmann/json.hpp>

namespace errfield {
namespace variogram_direction_cli_test {

class VariogramDirectionCli : public testing::CliTest {};

// SIMULATED: 3-D points in a 100 mm cube, a field that varies along x only, plus noise.
std::string simulated_csv(int n, Eigen::MatrixXd* x, Eigen::MatrixXd* z) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::normal_distribution<double> g(0.0, 0.1);
  x->resize(n, 3);
  z->resize(n, 2);
  std::string csv = "x,y,z,a,b\n";
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) (*x)(i, k) = u(rng);
    (*z)(i, 0) = std::sin((*x)(i, 0) / 15.0) + g(rng);
    (*z)(i, 1) = std::cos((*x)(i, 0) / 25.0) + g(rng);
    csv += format_number((*x)(i, 0)) + "," + format_number((*x)(i, 1)) + "," + format_number((*x)(i, 2)) +
           "," + format_number((*z)(i, 0)) + "," + format_number((*z)(i, 1)) + "\n";
  }
  return csv;
}

void expect_block(const CsvTable& t, std::size_t first_row, const EmpiricalVariogram& lib) {
  for (std::size_t b = 0; b < lib.bins.size(); ++b) {
    const auto& row = t.row(first_row + b);
    EXPECT_EQ(std::stoull(row[4]), lib.bins[b].pairs);
    if (lib.bins[b].pairs) EXPECT_EQ(std::stod(row[3]), lib.bins[b].gamma);
  }
}

TEST_F(VariogramDirectionCli, SeveralAlphasWithGstatDefaultToleranceAddADirectionColumn) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(200, &x, &z));
  const auto r = run("variogram --input " + path("in.csv") +
                     " --coords x,y --value a --bins 0:60:15 --alpha 0,45,90,135 --out " + path("v.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::read(path("v.csv"));
  ASSERT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs", "direction"}));
  ASSERT_EQ(t.row_count(), 16u);
  const Eigen::MatrixXd xy = x.leftCols(2);
  const std::vector<double> alphas{0, 45, 90, 135};
  for (std::size_t d = 0; d < 4; ++d) {
    EmpiricalVariogramOptions o;
    o.direction = VariogramDirection::gstat(alphas[d], 22.5);  // gstat: 90 / length(alpha)
    const auto lib = empirical_variogram(xy, z.col(0), LagBins::uniform(0, 60, 15), o);
    for (std::size_t b = 0; b < 4; ++b) EXPECT_EQ(std::stod(t.row(4 * d + b)[5]), alphas[d]);
    expect_block(t, 4 * d, lib);
  }
  // The field varies along x (alpha = 90): that variogram rises above the one along y.
  EXPECT_GT(std::stod(t.row(4 * 2 + 3)[3]), 2.0 * std::stod(t.row(3)[3]));
}

TEST_F(VariogramDirectionCli, DipAndPerCoordinateBlocks) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(150, &x, &z));
  auto r = run("variogram --input " + path("in.csv") +
               " --coords x,y,z --value a,b --bins 0,20,40,80 --alpha 30 --tol-hor 40 --beta 10,80 --tol-ver 30");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  CsvTable t = CsvTable::parse(r.out, "stdout");
  ASSERT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs", "direction", "dip"}));
  ASSERT_EQ(t.row_count(), 6u);
  for (std::size_t d = 0; d < 2; ++d) {
    EmpiricalVariogramOptions o;
    o.direction = VariogramDirection::gstat(30, 40, d ? 80 : 10, 30);
    expect_block(t, 3 * d, empirical_variogram(x, z, LagBins::from_edges({0, 20, 40, 80}), o));
    EXPECT_EQ(t.row(3 * d)[6], d ? "80" : "10");
  }

  r = run("variogram --input " + path("in.csv") +
          " --coords x,y,z --value a --bins 0,20,40,80 --per-coordinate --tol-axis 30 --per-component");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  t = CsvTable::parse(r.out, "stdout");
  ASSERT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs", "gamma_a", "coordinate"}));
  ASSERT_EQ(t.row_count(), 9u);
  const std::vector<std::string> names{"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    EmpiricalVariogramOptions o;
    o.direction = VariogramDirection::axis(k, 3, 30);
    expect_block(t, 3 * static_cast<std::size_t>(k), empirical_variogram(x, z.col(0), LagBins::from_edges({0, 20, 40, 80}), o));
    EXPECT_EQ(t.row(3 * static_cast<std::size_t>(k))[6], names[static_cast<std::size_t>(k)]);
  }
}

TEST_F(VariogramDirectionCli, DirectionsThatDoNotFitAreUsageErrors) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(30, &x, &z));
  const std::string base = "variogram --input " + path("in.csv") + " --value a --bins 0:60:15 ";
  for (const std::string& bad : {"--coords x,y --alpha 0 --tol-hor 200", "--coords x,y --alpha 0,x",
                                 "--coords x,y --alpha 0 --beta 10 --tol-ver 10",
                                 "--coords x,y,z --alpha 0 --per-coordinate", "--coords x,y --tol-hor 10",
                                 "--coords x --alpha 0", "--coords x,y --per-coordinate --tol-axis -1"}) {
    SCOPED_TRACE(bad);
    const auto r = run(base + bad);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--"), std::string::npos) << r.err;  // names the option
  }
}

// fit-variogram --anisotropy rotated writes the library's fit (model with @anis, angles and their
// standard errors in the JSON) and refuses other dimensions with a usage error.
TEST_F(VariogramDirectionCli, RotatedLikelihoodFitWritesTheLibrarysModelAndAngles) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(60, &x, &z));
  const auto r = run("fit-variogram --method reml --anisotropy rotated --input " + path("in.csv") +
                     " --coords x,y --value a --model exp --out " + path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  LikelihoodFitOptions o;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
  const auto lib = fit_likelihood(x.leftCols(2), z.col(0), {{ModelKind::Exponential, 0, 0, 0.5}}, o);
  const auto j = nlohmann::json::parse(read("m.json"));
  EXPECT_EQ(j.get<VariogramModel>().to_string(), lib.model.to_string());
  ASSERT_EQ(j["fit"]["angles_deg"].size(), 1u);
  EXPECT_EQ(j["fit"]["angles_deg"][0].get<double>(), lib.angles_deg[0]);
  EXPECT_NE(r.out.find("angle = "), std::string::npos) << r.out;
  const auto bad = run("fit-variogram --method reml --anisotropy anis --input " + path("in.csv") +
                       " --coords x --value a --model exp");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("2 or 3 coordinates"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace errfield
