// End-to-end tests of `errfield variogram` and `errfield fit-variogram` through the executable.

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/variogram_fit.hpp"
#include "support/cli_harness.hpp"

#include <nlohmann/json.hpp>

namespace errfield {
namespace variogram_cli_test {

namespace fs = std::filesystem;

class VariogramCli : public testing::CliTest {};


// Simulated data: 3-D points and a smooth scalar plus a 3-vector value.
std::string simulated_csv(int n, std::uint64_t seed, Eigen::MatrixXd* x, Eigen::MatrixXd* z) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::normal_distribution<double> g(0.0, 0.05);
  x->resize(n, 3);
  z->resize(n, 4);
  std::string csv = "id,x [mm],y,z,dL,dx,dy,dz\n";
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) (*x)(i, a) = std::round(u(rng));  // integers: lags hit bin edges
    (*z)(i, 0) = std::sin((*x)(i, 0) / 300.0) + g(rng);
    for (int c = 1; c < 4; ++c) (*z)(i, c) = std::cos((*x)(i, c - 1) / 200.0) + g(rng);
    csv += std::to_string(i);
    for (int a = 0; a < 3; ++a) csv.append(",").append(format_number((*x)(i, a)));
    for (int c = 0; c < 4; ++c) csv.append(",").append(format_number((*z)(i, c)));
    csv += "\n";
  }
  return csv;
}

TEST_F(VariogramCli, WritesExactColumnsAndAgreesWithTheLibrary) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(300, 1, &x, &z));
  const auto r = run("variogram --input " + path("in.csv") +
                     " --coords x,y,z --value dL --bins 0:2000:100 --out " + path("v.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::read(path("v.csv"));
  ASSERT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs"}));
  const auto lib = empirical_variogram(x, z.col(0), LagBins::uniform(0.0, 2000.0, 100.0));
  ASSERT_EQ(t.row_count(), 20u);
  bool saw_empty = false;
  for (std::size_t b = 0; b < 20; ++b) {
    EXPECT_EQ(std::stod(t.row(b)[0]), 100.0 * b);
    EXPECT_EQ(std::stoull(t.row(b)[4]), lib.bins[b].pairs);
    if (lib.bins[b].pairs == 0) {
      saw_empty = true;
      EXPECT_EQ(t.row(b)[2], "");
      EXPECT_EQ(t.row(b)[3], "");
    } else {
      EXPECT_EQ(std::stod(t.row(b)[3]), lib.bins[b].gamma);  // shortest round-trip text
      EXPECT_EQ(std::stod(t.row(b)[2]), lib.bins[b].lag_mean);
    }
  }
  EXPECT_TRUE(saw_empty) << "max lag of 1000^3 cube is 1732, so the last bins must be empty";
}

TEST_F(VariogramCli, VectorValueExplicitEdgesStdoutAndPerComponent) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(200, 2, &x, &z));
  const auto r = run("variogram --input " + path("in.csv") +
                     " --coords x,y,z --value dx,dy,dz --bins 0,50,100,300,700 --convention gstat "
                     "--estimator cressie --per-component");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::parse(r.out, "stdout");
  ASSERT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs",
                                                  "gamma_dx", "gamma_dy", "gamma_dz"}));
  EmpiricalVariogramOptions o;
  o.convention = BinConvention::Gstat;
  o.estimator = VariogramEstimator::CressieHawkins;
  const auto lib = empirical_variogram(x, z.rightCols(3), LagBins::from_edges({0, 50, 100, 300, 700}), o);
  ASSERT_EQ(t.row_count(), 4u);
  for (std::size_t b = 0; b < 4; ++b) {
    EXPECT_EQ(std::stod(t.row(b)[3]), lib.bins[b].gamma);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(std::stod(t.row(b)[5 + c]), lib.component_gamma(static_cast<Eigen::Index>(b), c));
  }
}

TEST_F(VariogramCli, WithoutBinsUsesGstatsDefault) {
  // No --bins: 15 bins up to 0.33333 x the bounding-box diagonal, gstat's boundaries - the same as
  // the explicit bins written here from the data's extent (tests/peers/gstat_variogram_test.cpp
  // compares the rule with R gstat itself).
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(200, 3, &x, &z));
  const Eigen::MatrixXd xy = x.leftCols(2);
  const double diagonal = (xy.colwise().maxCoeff() - xy.colwise().minCoeff()).norm();
  const double cutoff = 0.33333 * diagonal, width = cutoff / 15.0;
  const auto r = run("variogram --input in.csv --coords x,y --value dL --out default.csv");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gstat's default"), std::string::npos) << r.err;
  std::string edges;
  for (int k = 0; k <= 15; ++k) edges += (k ? "," : "") + format_number(k * width);
  ASSERT_EQ(run("variogram --input in.csv --coords x,y --value dL --bins " + edges +
                " --convention gstat --out explicit.csv").exit_code,
            0);
  EXPECT_EQ(read("default.csv"), read("explicit.csv"));
  EXPECT_EQ(CsvTable::read(path("default.csv")).row_count(), 15u);
  // --convention still wins when given.
  ASSERT_EQ(run("variogram --input in.csv --coords x,y --value dL --convention paper --out paper.csv").exit_code, 0);
  ASSERT_EQ(run("variogram --input in.csv --coords x,y --value dL --bins " + edges + " --out paper2.csv").exit_code, 0);
  EXPECT_EQ(read("paper.csv"), read("paper2.csv"));
}

TEST_F(VariogramCli, BadInputExitsNonZeroNamingWhereAndWritesNothing) {
  write("bad.csv", "x,y,v\n0,0,1\n1,0,abc\n2,0,3\n");
  auto r = run("variogram --input " + path("bad.csv") + " --coords x,y --value v --bins 0:5:1 --out " +
               path("o.csv"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bad.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(":3"), std::string::npos) << r.err;  // line 3 holds 'abc'
  EXPECT_NE(r.err.find("'v'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("o.csv")));

  write("ok.csv", "x,y,v\n0,0,1\n1,0,2\n2,0,3\n");
  r = run("variogram --input " + path("ok.csv") + " --coords x,w --value v --bins 0:5:1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("'w'"), std::string::npos) << r.err;
  r = run("variogram --input " + path("ok.csv") + " --coords x,y --value v --bins 0:5:0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("width"), std::string::npos) << r.err;
  r = run("variogram --input " + path("ok.csv") + " --coords x,y --value v --bins 0,2,1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("edges[2]"), std::string::npos) << r.err;
  r = run("variogram --input " + path("ok.csv") + " --coords x,y --value v --bins 0:5");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--bins"), std::string::npos) << r.err;
  r = run("variogram --input " + path("ok.csv") + " --coords x,y --value v --bins 0:5:1 --estimator dowd2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("matheron"), std::string::npos) << r.err;
  r = run("variogram --input " + path("missing.csv") + " --coords x,y --value v --bins 0:5:1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;
  write("one.csv", "x,y,v\n0,0,1\n");
  r = run("variogram --input " + path("one.csv") + " --coords x,y --value v --bins 0:5:1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("at least 2"), std::string::npos) << r.err;
  write("nan.csv", "x,y,v\n0,0,1\n1,0,nan\n");
  r = run("variogram --input " + path("nan.csv") + " --coords x,y --value v --bins 0:5:1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nan.csv"), std::string::npos) << r.err;
  r = run("variogram --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("Example"), std::string::npos);
}

TEST_F(VariogramCli, FitVariogramPrintsAndWritesALoadableModel) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(300, 3, &x, &z));
  ASSERT_EQ(run("variogram --input " + path("in.csv") + " --coords x,y,z --value dL --bins 0:2000:100 --out " +
                path("v.csv"))
                .exit_code,
            0);
  const auto r = run("fit-variogram --input " + path("v.csv") +
                     " --model gau --nugget free --weights cressie --out " + path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("gau(sill="), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("weighted SSE (cressie)"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(read("m.json"));
  const auto model = j.get<VariogramModel>();
  EXPECT_EQ(model.to_string(), r.out.substr(0, r.out.find('\n')));
  // The same fit through the library, on the same (empty-bin-free) data.
  const auto lib_vg = empirical_variogram(x, z.col(0), LagBins::uniform(0.0, 2000.0, 100.0));
  VariogramFitOptions o;
  o.weighting = FitWeighting::Cressie;
  const auto lib = fit_variogram(lib_vg, {{ModelKind::Gaussian, 0, 0, 0.5}}, o);
  EXPECT_NEAR(j["fit"]["weighted_sse"].get<double>(), lib.weighted_sse, 1e-12 * lib.weighted_sse);

  auto bad = run("fit-variogram --input " + path("v.csv") + " --model mat");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--nu"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model sph --nugget fixed=abc");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--nugget"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model sph --weights ols");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("nj_h2"), std::string::npos) << bad.err;
  write("bad.csv", "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,1,0.5,0.1,3\n1,2,1.5,x,4\n2,3,2.5,0.3,5\n");
  bad = run("fit-variogram --input " + path("bad.csv") + " --model sph --out " + path("bad.json"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("bad.csv:3"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("'gamma'"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad.json")));
  EXPECT_EQ(run("fit-variogram --help").exit_code, 0);
}

// A nested template with starting values and held parameters (issue 36): the CLI writes the
// library's fit of the same template, keeps held values as given, and names what it refuses.
TEST_F(VariogramCli, FitVariogramTakesANestedTemplateAndHeldParameters) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(200, 11, &x, &z));
  ASSERT_EQ(run("variogram --input " + path("in.csv") + " --coords x,y,z --value dL --bins 0:1200:100 --out " +
                path("v.csv"))
                .exit_code,
            0);
  const std::string tmpl = "nug(sill=0.01)+sph(sill=0.2,range=150)+sph(sill=0.3,range=700)";
  const auto r = run("fit-variogram --input " + path("v.csv") + " --model '" + tmpl + "' --fix range1 --out " +
                     path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lib_vg = empirical_variogram(x, z.col(0), LagBins::uniform(0.0, 1200.0, 100.0));
  VariogramFitOptions o;
  o.nugget_start = 0.01;
  o.hold_range = {true, false};
  const auto lib = fit_variogram(lib_vg, {{ModelKind::Spherical, 0.2, 150, 0.5}, {ModelKind::Spherical, 0.3, 700, 0.5}}, o);
  const auto model = nlohmann::json::parse(read("m.json")).get<VariogramModel>();
  EXPECT_EQ(model.to_string(), lib.model.to_string());
  ASSERT_EQ(model.components().size(), 3u);
  EXPECT_EQ(model.components()[0].range, 150.0);
  // Without a nug term the template has no nugget; --fix nugget holds the template's.
  const auto none = run("fit-variogram --input " + path("v.csv") + " --model 'sph(sill=0.2,range=150)' --out " +
                        path("n.json"));
  ASSERT_EQ(none.exit_code, 0) << none.err;
  EXPECT_EQ(nlohmann::json::parse(read("n.json")).get<VariogramModel>().nugget(), 0.0);
  const auto held = run("fit-variogram --input " + path("v.csv") + " --model '" + tmpl + "' --fix nugget,sill2 --out " +
                        path("h.json"));
  ASSERT_EQ(held.exit_code, 0) << held.err;
  const auto hm = nlohmann::json::parse(read("h.json")).get<VariogramModel>();
  EXPECT_EQ(hm.nugget(), 0.01);
  EXPECT_EQ(hm.components()[1].sill, 0.3);

  auto bad = run("fit-variogram --input " + path("v.csv") + " --model sph --fix range");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("template"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model '" + tmpl + "' --fix range3");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("range1..range2"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model '" + tmpl + "' --fix speed");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--fix: 'speed'"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model 'sph(sill=0.2,range=150)' --fix nugget");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("no nug term"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("v.csv") + " --model 'sph(sill=0.2,range=150)@anis(30,0.5)'");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("isotropic"), std::string::npos) << bad.err;
  bad = run("fit-variogram --method reml --input " + path("in.csv") + " --coords x,y,z --value dL --model '" + tmpl +
            "' --fix nugget");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--fix nugget applies to --method wls"), std::string::npos) << bad.err;
  // REML with a held range: the CLI writes the library's fit, the range as given.
  const auto reml = run("fit-variogram --method reml --input " + path("in.csv") + " --coords x,y,z --value dL --model '" +
                        tmpl + "' --fix range2 --out " + path("r.json"));
  ASSERT_EQ(reml.exit_code, 0) << reml.err;
  LikelihoodFitOptions lo;
  lo.nugget_start = 0.01;
  lo.hold_range = {false, true};
  const auto rlib = fit_likelihood(x, z.col(0), {{ModelKind::Spherical, 0.2, 150, 0.5}, {ModelKind::Spherical, 0.3, 700, 0.5}}, lo);
  const auto rm = nlohmann::json::parse(read("r.json")).get<VariogramModel>();
  EXPECT_EQ(rm.to_string(), rlib.model.to_string());
  EXPECT_EQ(rm.components()[1].range, 700.0);
}

TEST_F(VariogramCli, FitVariogramByLikelihoodMatchesTheLibraryAndRefusesWhatDoesNotApply) {
  // (The optimum itself is checked against scipy in tests/peers/scipy_likelihood_test.cpp.)
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(60, 5, &x, &z));
  const auto r = run("fit-variogram --method reml --input " + path("in.csv") +
                     " --coords \"x [mm],y,z\" --value dL --model exp --out " + path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("REML negative log-likelihood = "), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(read("m.json"));
  EXPECT_EQ(j["fit"]["method"], "reml");
  const auto lib = fit_likelihood(x, z.col(0), {{ModelKind::Exponential, 0, 0, 0.5}});
  EXPECT_EQ(j.get<VariogramModel>().to_string(), lib.model.to_string());
  EXPECT_EQ(j["fit"]["negative_log_likelihood"].get<double>(), lib.negative_log_likelihood);

  auto bad = run("fit-variogram --method reml --input " + path("in.csv") + " --model exp");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--coords"), std::string::npos) << bad.err;
  bad = run("fit-variogram --method ml --input " + path("in.csv") + " --coords x,y,z --value dL --model exp "
            "--weights nj");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--weights applies to --method wls"), std::string::npos) << bad.err;
  // A vector value: one model shared by the components, ARD ranges; the CLI writes the library's fit.
  const auto v = run("fit-variogram --method ml --anisotropy ard --input " + path("in.csv") +
                     " --coords \"x [mm],y,z\" --value dx,dy --model mat --nu 1.5 --out " + path("v.json"));
  ASSERT_EQ(v.exit_code, 0) << v.err;
  LikelihoodFitOptions ard;
  ard.restricted = false;
  ard.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  const auto vlib = fit_likelihood(x, z.middleCols(1, 2), {{ModelKind::Matern, 0, 0, 1.5}}, ard);
  const auto vj = nlohmann::json::parse(read("v.json"));
  EXPECT_EQ(vj.get<VariogramModel>().to_string(), vlib.model.to_string());
  EXPECT_EQ(vj["fit"]["ranges"].size(), 3u);
  bad = run("fit-variogram --method ml --input " + path("in.csv") + " --coords x,y,z --value dL --model exp --anisotropy diag");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("none, ard or rotated"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("in.csv") + " --model exp --anisotropy ard");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--anisotropy applies to --method ml or reml"), std::string::npos) << bad.err;
  bad = run("fit-variogram --method reml --input " + path("in.csv") + " --coords x,y,z --value dL --model lin");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("bounded model"), std::string::npos) << bad.err;
  bad = run("fit-variogram --method mle --input " + path("in.csv") + " --model exp");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("wls, ml or reml"), std::string::npos) << bad.err;
  std::string big = "x,y,z,dL\n";
  for (int i = 0; i < 3001; ++i) big += std::to_string(i) + ",0,0,1\n";
  write("big.csv", big);
  bad = run("fit-variogram --method reml --likelihood exact --input " + path("big.csv") +
            " --coords x,y,z --value dL --model exp --out " + path("big.json"));
  EXPECT_EQ(bad.exit_code, 3);
  EXPECT_NE(bad.err.find("--method wls"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("--likelihood vecchia"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("big.json")));
  // The default (auto) takes them to the Vecchia likelihood: no budget refusal; these values are all
  // equal, which the data check then names (exit 2).
  bad = run("fit-variogram --method reml --input " + path("big.csv") + " --coords x,y,z --value dL --model exp");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("values are equal"), std::string::npos) << bad.err;
  bad = run("fit-variogram --method reml --input " + path("in.csv") +
            " --coords x,y,z --value dL --model exp --vecchia-neighbours 0");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--vecchia-neighbours"), std::string::npos) << bad.err;
  // Issue 35: Vecchia's options on an exact fit did nothing, silently (exit 0).
  bad = run("fit-variogram --method reml --likelihood exact --input " + path("in.csv") +
            " --coords x,y,z --value dL --model exp --vecchia-neighbours 12 --vecchia-ordering random");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--vecchia-neighbours 12, --vecchia-ordering random: they apply to the Vecchia likelihood"),
            std::string::npos)
      << bad.err;
  // Issue 35: rotated anisotropy had no budget (3,001 3-D samples by Vecchia ran past 150 s); now
  // refused at once (exit 3) naming what fits: 6e9 / (204 fits x 30^3) = 1,089 samples.
  bad = run("fit-variogram --method reml --anisotropy rotated --input " + path("big.csv") +
            " --coords x,y,z --value dL --model exp --out " + path("big.json"));
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_NE(bad.err.find("at most 1089 samples"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("--vecchia-neighbours"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("--anisotropy ard"), std::string::npos) << bad.err;
  bad = run("fit-variogram --input " + path("in.csv") + " --model exp --likelihood vecchia");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("apply to --method ml or reml"), std::string::npos) << bad.err;
}

TEST_F(VariogramCli, FitVariogramByTheVecchiaLikelihoodWritesTheLibrarysFit) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(80, 7, &x, &z));
  const auto r = run("fit-variogram --method reml --likelihood vecchia --vecchia-neighbours 12 --vecchia-ordering random "
                     "--anisotropy ard --input " + path("in.csv") + " --coords \"x [mm],y,z\" --value dL --model exp --out " +
                     path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read("m.json"));
  EXPECT_EQ(j["fit"]["likelihood"], "vecchia");
  EXPECT_EQ(j["fit"]["vecchia_neighbours"], 12);
  EXPECT_EQ(j["fit"]["vecchia_ordering"], "random");
  LikelihoodFitOptions o;
  o.method = LikelihoodMethod::Vecchia;
  o.vecchia_neighbours = 12;
  o.vecchia_ordering = VecchiaOrdering::Random;
  o.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  const auto lib = fit_likelihood(x, z.col(0), {{ModelKind::Exponential, 0, 0, 0.5}}, o);
  EXPECT_EQ(j.get<VariogramModel>().to_string(), lib.model.to_string());
  EXPECT_EQ(j["fit"]["negative_log_likelihood"].get<double>(), lib.negative_log_likelihood);
  // Small N by default: the exact likelihood, said so.
  const auto e = run("fit-variogram --method reml --input " + path("in.csv") +
                     " --coords \"x [mm],y,z\" --value dL --model exp --out " + path("e.json"));
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_EQ(nlohmann::json::parse(read("e.json"))["fit"]["likelihood"], "exact");
}

// --cloud over its pair budget exits 3 before writing and names the option that raises it; at the
// budget it writes every pair. --map and --cloud refuse what does not apply with exit 2.
TEST_F(VariogramCli, CloudKeepsItsPairBudgetAndMapRefusesWhatDoesNotApply) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(40, 7, &x, &z));
  std::size_t pairs = 0;  // within the cutoff 300 in x, y
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < i; ++j) pairs += (x.row(i).head(2) - x.row(j).head(2)).norm() <= 300.0;
  ASSERT_GT(pairs, 10u);
  const std::string base = "variogram --input " + path("in.csv") + " --coords x,y --value dL --cloud --cutoff 300 --out " +
                           path("cloud.csv");
  auto r = run(base + " --max-pairs " + std::to_string(pairs - 1));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("--max-pairs"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("cloud.csv")));
  r = run(base + " --max-pairs " + std::to_string(pairs));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::read(path("cloud.csv"));
  EXPECT_EQ(t.header(), (std::vector<std::string>{"left", "right", "dist", "gamma"}));
  EXPECT_EQ(t.row_count(), pairs);
  r = run("variogram --input " + path("in.csv") + " --coords x,y --value dL --map 50,50");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--cutoff"), std::string::npos) << r.err;
  r = run("variogram --input " + path("in.csv") + " --coords x,y,z --value dL --map 50,50 --cutoff 300");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("2 coordinates"), std::string::npos) << r.err;
  r = run(base + " --estimator cressie");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--estimator"), std::string::npos) << r.err;
}

// variogram --plot and fit-variogram --plot write well-formed SVG (parsed by Python's XML parser):
// one point per non-empty bin, each labelled with its pair count, and the model's curve in the fit's
// picture only; a picture that cannot be written leaves --out unwritten too (both or neither).
TEST_F(VariogramCli, PlotsAreWellFormedSvgWithAPointPerBinAndTheFittedCurve) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(120, 3, &x, &z));
  auto r = run("variogram --input " + path("in.csv") + " --coords x,y,z --value dL --bins 0:1000:100 --out " +
               path("v.csv") + " --plot " + path("v.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::size_t bins = 0;
  std::string counts;
  const CsvTable v = CsvTable::read(path("v.csv"));
  for (std::size_t i = 0; i < v.row_count(); ++i)
    if (v.cell(i, v.column_index("pairs")) != std::string_view("0")) {
      ++bins;
      counts += std::string(v.cell(i, v.column_index("pairs"))) + ",";
    }
  r = run("fit-variogram --input " + path("v.csv") + " --model sph --plot " + path("f.svg") + " --out " + path("f.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  write("check.py",
        "import sys, xml.etree.ElementTree as E\n"
        "ns = '{http://www.w3.org/2000/svg}'\n"
        "for f in sys.argv[1:]:\n"
        "    root = E.parse(f).getroot()\n"
        "    circles = [c for c in root.iter(ns + 'circle') if c.get('class') == 'bin']\n"
        "    labels = ''.join(t.text + ',' for t in root.iter(ns + 'text') if t.get('class') == 'pairs')\n"
        "    model = [p for p in root.iter(ns + 'path') if p.get('id') == 'model']\n"
        "    print(len(circles), labels, len(model), len(model[0].get('d').split('L')) if model else 0)\n");
  const std::string cmd = "/usr/bin/python3 " + path("check.py") + " " + path("v.svg") + " " + path("f.svg") + " > " +
                          path("check.out") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << CsvTable::read(path("v.csv")).row_count();
  std::ifstream in(path("check.out"));
  std::string line_v, line_f;
  std::getline(in, line_v);
  std::getline(in, line_f);
  EXPECT_EQ(line_v, std::to_string(bins) + " " + counts + " 0 0");
  EXPECT_EQ(line_f, std::to_string(bins) + " " + counts + " 1 301");
  fs::create_directories(path("dir.svg"));
  r = run("fit-variogram --input " + path("v.csv") + " --model sph --plot " + path("dir.svg") + " --out " + path("g.json"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(path("g.json")));
}

// variogram --plot with several directions (issue 49): one picture, well-formed SVG, every direction's
// non-empty bins as points of its own colour, a legend naming each direction.
TEST_F(VariogramCli, PlotOfSeveralDirectionsHasEachDirectionsBinsAndALegend) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(150, 2, &x, &z));
  const auto r = run("variogram --input " + path("in.csv") + " --coords x,y --value dL --bins 0:800:100 --alpha 0,45,90 --out " +
                     path("v.csv") + " --plot " + path("v.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable v = CsvTable::read(path("v.csv"));
  std::map<std::string, int> bins;
  for (std::size_t i = 0; i < v.row_count(); ++i)
    if (v.cell(i, v.column_index("pairs")) != std::string_view("0")) ++bins[std::string(v.cell(i, v.column_index("direction")))];
  ASSERT_EQ(bins.size(), 3u);
  write("check.py",
        "import sys, xml.etree.ElementTree as E\n"
        "ns = '{http://www.w3.org/2000/svg}'\n"
        "root = E.parse(sys.argv[1]).getroot()\n"
        "for g in root.iter(ns + 'g'):\n"
        "    if g.get('class') == 'bins':\n"
        "        print(g.get('fill'), sum(1 for c in g.iter(ns + 'circle') if c.get('class') == 'bin'))\n"
        "    if g.get('id') == 'legend':\n"
        "        print('legend', '|'.join(t.text for t in g.iter(ns + 'text')))\n");
  const std::string cmd = "/usr/bin/python3 " + path("check.py") + " " + path("v.svg") + " > " + path("check.out") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(path("check.out"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "legend direction 0|direction 45|direction 90");
  std::set<std::string> colours;
  const std::vector<std::string> order{"0", "45", "90"};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string& line = lines[k + 1];
    colours.insert(line.substr(0, line.find(' ')));
    EXPECT_EQ(line.substr(line.find(' ') + 1), std::to_string(bins[order[k]])) << line;
  }
  EXPECT_EQ(colours.size(), 3u);
}

}  // namespace
}  // namespace errfield
