// Peer cross-check of `errfield fit-variogram --method ml|reml` against an independent numpy/scipy
// implementation (tests/peers/scipy_likelihood.py: the likelihood from the textbook formulas,
// optimized by Nelder-Mead from three starts), on SIMULATED data drawn here: a Gaussian field with
// exponential covariance + nugget at 150 random points of a 500 mm cube. Checks that
//  - the likelihood errfield reports equals scipy's formula at errfield's parameters, and
//  - errfield's optimum is scipy's: objectives within 1e-4 (a likelihood-ratio test needs
//    differences of ~2 to tell models apart) and parameters within 2% (the likelihood is flat near
//    its optimum: 0.1% of range moves it by ~1e-6).
// Skipped when /usr/bin/python3 with numpy and scipy is missing.

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace scipy_likelihood_test {

using testing::run_errfield;
using testing::ScratchDir;

bool scipy_available() {
  return std::system("/usr/bin/python3 -c 'import numpy, scipy.optimize' >/dev/null 2>&1") == 0;
}

void write_simulated_field(const std::string& path) {
  // z = 2 + L e with L L' = 0.5 exp(-h/120) + 0.02 I (Cholesky of the covariance; errfield is not used).
  constexpr int n = 150;
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> u(0.0, 500.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(n, 3);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) x(i, k) = u(rng);
  Eigen::MatrixXd c(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) c(i, j) = 0.5 * std::exp(-(x.row(i) - x.row(j)).norm() / 120.0) + (i == j ? 0.02 : 0.0);
  Eigen::VectorXd e(n);
  for (int i = 0; i < n; ++i) e[i] = g(rng);
  const Eigen::VectorXd z = (c.llt().matrixL() * e).array() + 2.0;
  std::ofstream out(path);
  out << "x,y,z,dL\n";
  for (int i = 0; i < n; ++i)
    out << format_number(x(i, 0)) << "," << format_number(x(i, 1)) << "," << format_number(x(i, 2)) << ","
        << format_number(z[i]) << "\n";
}

class ScipyLikelihoodPeer : public ::testing::TestWithParam<const char*> {};

TEST_P(ScipyLikelihoodPeer, SameOptimumAsAnIndependentImplementation) {
  if (!scipy_available()) GTEST_SKIP() << "/usr/bin/python3 with numpy and scipy not found (apt-get install python3-scipy)";
  const std::string method = GetParam();
  ScratchDir dir;
  write_simulated_field(dir / "field.csv");
  const auto fit = run_errfield({"fit-variogram", "--method", method, "--input", dir / "field.csv", "--coords",
                                 "x,y,z", "--value", "dL", "--model", "exp", "--out", dir / "model.json"},
                                dir.path());
  ASSERT_EQ(fit.exit_code, 0) << fit.output();
  const std::string cmd = "/usr/bin/python3 " + std::string(ERRFIELD_SOURCE_DIR) + "/tests/peers/scipy_likelihood.py " +
                          (dir / "field.csv") + " " + (dir / "model.json") + " " + method + " > " +
                          (dir / "scipy.json");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto ours = nlohmann::json::parse(ScratchDir::slurp(dir / "model.json"));
  const auto peer = nlohmann::json::parse(ScratchDir::slurp(dir / "scipy.json"));

  const double reported = ours["fit"]["negative_log_likelihood"].get<double>();
  EXPECT_NEAR(reported, peer["objective_at_errfield"].get<double>(), 1e-9 * std::abs(reported));
  EXPECT_NEAR(reported, peer["scipy"]["objective"].get<double>(), 1e-4);

  double sill = 0, range = 0, nugget = 0;
  for (const auto& c : ours["components"]) {
    if (c["kind"] == "exp") sill = c["sill"], range = c["range"];
    if (c["kind"] == "nug") nugget = c["sill"];
  }
  EXPECT_NEAR(sill / peer["scipy"]["sill"].get<double>(), 1.0, 0.02) << ours.dump();
  EXPECT_NEAR(range / peer["scipy"]["range"].get<double>(), 1.0, 0.02) << ours.dump();
  EXPECT_NEAR(nugget / peer["scipy"]["nugget"].get<double>(), 1.0, 0.02) << ours.dump();
}

INSTANTIATE_TEST_SUITE_P(Methods, ScipyLikelihoodPeer, ::testing::Values("reml", "ml"));

}  // namespace
}  // namespace errfield
