// `errfield variogram --cross` and `errfield fit-variogram --lmc` through the executable, against
// the library on the same data.

#include <cmath>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/coregionalization_fit.hpp"
#include "errfield/coregionalization_model.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace lmc_cli_test {

class LmcCli : public testing::CliTest {};

// Simulated data: 2-D points, three correlated components (a shared smooth part plus noise).
std::string simulated_csv(int n, Eigen::MatrixXd* x, Eigen::MatrixXd* z) {
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<int> u(0, 1000);
  std::normal_distribution<double> g(0.0, 0.2);
  x->resize(n, 2);
  z->resize(n, 3);
  std::string csv = "x,y,ex,ey,ez\n";
  for (int i = 0; i < n; ++i) {
    (*x)(i, 0) = u(rng);
    (*x)(i, 1) = u(rng);
    const double s = std::sin((*x)(i, 0) / 150.0) * std::cos((*x)(i, 1) / 200.0);
    (*z)(i, 0) = s + g(rng);
    (*z)(i, 1) = -0.5 * s + g(rng);
    (*z)(i, 2) = 0.8 * s + g(rng);
    csv += format_number((*x)(i, 0)) + "," + format_number((*x)(i, 1));
    for (int c = 0; c < 3; ++c) csv += "," + format_number((*z)(i, c));
    csv += "\n";
  }
  return csv;
}

double cell(const CsvTable& t, std::size_t r, const std::string& column) {
  return t.numeric_cell(r, t.column_index(column));
}

TEST_F(LmcCli, CrossAddsDirectAndCrossColumnsEqualToTheLibrary) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(150, &x, &z));
  const auto r = run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --bins 0:600:50 --cross --out " +
                     path("v.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = CsvTable::read(path("v.csv"));
  EXPECT_EQ(t.header(), (std::vector<std::string>{"lag_lo", "lag_hi", "lag_mean", "gamma", "pairs", "gamma_ex", "gamma_ey",
                                                  "gamma_ez", "gamma_ex_ey", "gamma_ex_ez", "gamma_ey_ez"}));
  EmpiricalVariogramOptions o;
  o.cross_variograms = true;
  const EmpiricalVariogram v = empirical_variogram(x, z, LagBins::uniform(0.0, 600.0, 50.0), o);
  ASSERT_EQ(t.row_count(), v.bins.size());
  const char* names[] = {"ex", "ey", "ez"};
  for (std::size_t b = 0; b < v.bins.size(); ++b) {
    ASSERT_GT(v.bins[b].pairs, 0u);
    EXPECT_EQ(cell(t, b, "pairs"), static_cast<double>(v.bins[b].pairs));
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        const std::string column = i == j ? std::string("gamma_") + names[i]
                                          : std::string("gamma_") + names[i] + "_" + names[j];
        EXPECT_EQ(cell(t, b, column), v.gamma_of(b, i, j)) << column << " bin " << b;  // shortest round trip
      }
  }
}

TEST_F(LmcCli, CrossRefusesOneColumnAndTheRobustEstimators) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(20, &x, &z));
  auto r = run("variogram --input " + path("in.csv") + " --coords x,y --value ex --cross");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--cross needs at least 2 --value columns"), std::string::npos) << r.err;
  r = run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey --cross --estimator cressie");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--estimator cressie"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Matheron"), std::string::npos) << r.err;
}

// Issue 35: an LMC of constant data was written as all zeros with exit 0. A component with no
// spatial variation (its direct variogram 0 in every bin) is refused, named.
TEST_F(LmcCli, ConstantComponentIsRefusedNotFittedAsZeros) {
  Eigen::MatrixXd x, z;
  (void)simulated_csv(60, &x, &z);  // the points and values
  std::string flat = "x,y,ex,ey,ez\n", all = flat;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const std::string xy = format_number(x(i, 0)) + "," + format_number(x(i, 1));
    flat += xy + "," + format_number(z(i, 0)) + ",5," + format_number(z(i, 2)) + "\n";
    all += xy + ",1,2,3\n";
  }
  write("flat.csv", flat);
  write("all.csv", all);
  for (const char* model : {"nug(0)+sph(1,400)", "nug+sph"}) {
    auto r = run("fit-variogram --lmc --input " + path("flat.csv") + " --coords x,y --value ex,ey,ez --model " + model +
                 " --out " + path("flat.json"));
    EXPECT_EQ(r.exit_code, 2) << r.output();
    EXPECT_THAT(r.err, ::testing::HasSubstr("no spatial variation in 'ey'")) << model;
    EXPECT_FALSE(std::filesystem::exists(path("flat.json")));
    r = run("fit-variogram --lmc --input " + path("all.csv") + " --coords x,y --value ex,ey,ez --model " + model +
            " --out " + path("all.json"));
    EXPECT_EQ(r.exit_code, 2) << r.output();
    EXPECT_THAT(r.err, ::testing::HasSubstr("no spatial variation in 'ex', 'ey', 'ez'")) << model;
    EXPECT_THAT(r.err, ::testing::HasSubstr("every component")) << model;
  }
}

TEST_F(LmcCli, FitLmcWritesTheModelTheLibraryFitsAndReportsTheProjection) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(150, &x, &z));
  ASSERT_EQ(run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --bins 0:600:50 --cross --out " +
                path("v.csv")).exit_code, 0);
  EmpiricalVariogramOptions vo;
  vo.cross_variograms = true;
  const CrossVariogramTable table =
      CrossVariogramTable::from(empirical_variogram(x, z, LagBins::uniform(0.0, 600.0, 50.0), vo));
  const std::vector<ModelComponent> structures{{.kind = ModelKind::Nugget}, {.kind = ModelKind::Spherical, .range = 400.0}};
  for (const std::string method : {"goulard-voltz", "gstat"}) {
    const auto r = run("fit-variogram --lmc --input " + path("v.csv") + " --value ex,ey,ez --model nug(0)+sph(1,400) "
                       "--lmc-method " + method + " --weights nj --out " + path("lmc.json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    CoregionalizationFitOptions o;
    o.method = lmc_fit_method_from_name(method);
    o.weighting = LmcWeighting::Nj;
    const CoregionalizationFitResult lib = fit_coregionalization(table, structures, o, {"ex", "ey", "ez"});
    const CoregionalizationModel written = load_coregionalization_model(path("lmc.json"));
    EXPECT_EQ(written.component_names(), (std::vector<std::string>{"ex", "ey", "ez"}));
    ASSERT_EQ(written.structures().size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      EXPECT_EQ(written.structures()[k].kind, structures[k].kind);
      // The CSV holds shortest round-trip numbers, so the fit sees the library's doubles.
      EXPECT_LT((written.structures()[k].sills - lib.model.structures()[k].sills).cwiseAbs().maxCoeff(), 1e-12)
          << method << " structure " << k;
    }
    EXPECT_NE(r.out.find("smallest eigenvalue before projection"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("weighted residual = " + format_number(lib.weighted_residual)), std::string::npos) << r.out;
    const nlohmann::json j = nlohmann::json::parse(read("lmc.json"));
    EXPECT_EQ(j["type"], "lmc");
    EXPECT_EQ(j["fit"]["method"], method);
    EXPECT_EQ(j["fit"]["iterations"], lib.iterations);
  }
  // Kinds only: ranges fitted first, reported.
  const auto r = run("fit-variogram --lmc --input " + path("v.csv") + " --value ex,ey,ez --model nug+sph");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ranges fitted to the mean of the 3 direct variograms"), std::string::npos) << r.out;
  // From the samples with --coords: gstat's default bins, as 'variogram --cross' without --bins.
  ASSERT_EQ(run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --cross --out " + path("d.csv")).exit_code, 0);
  const auto from_csv = run("fit-variogram --lmc --input " + path("d.csv") + " --value ex,ey,ez --model nug(0)+exp(1,200)");
  const auto from_samples =
      run("fit-variogram --lmc --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --model nug(0)+exp(1,200)");
  ASSERT_EQ(from_samples.exit_code, 0) << from_samples.err;
  EXPECT_EQ(from_samples.out, from_csv.out);
}

TEST_F(LmcCli, FitLmcRejectsMisuseNamingTheOption) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(60, &x, &z));
  ASSERT_EQ(run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey --cross --out " + path("v.csv")).exit_code, 0);
  const std::string base = "fit-variogram --lmc --input " + path("v.csv");
  struct Case {
    std::string args, expected;
  };
  for (const Case& c : {Case{" --value ex --model nug(0)+sph(1,400)", "at least 2 --value columns"},
                        Case{" --model nug(0)+sph(1,400)", "--lmc needs --value"},
                        Case{" --value ex,ey --model nug(0)+pow(1,1.5)", "pow has no sill"},
                        Case{" --value ex,ey --model nug+lin", "lin has no sill"},
                        Case{" --value ex,ey --model sph(1,", "--model"},
                        Case{" --value ex,ey --model nug+sphx", "nug(0)+sph(1,400)"},
                        Case{" --value ex,ez --model nug(0)+sph(1,400)", "no column 'gamma_ex_ez'"},
                        Case{" --value ex,ey --model nug(0)+sph(1,400) --lmc-method fast", "goulard-voltz or gstat"},
                        Case{" --value ex,ey --model nug(0)+sph(1,400) --weights cressie", "--weights cressie"}}) {
    const auto r = run(base + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
  }
  const auto r = run("fit-variogram --input " + path("v.csv") + " --model sph --lmc-method gstat");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--lmc-method applies to --lmc"), std::string::npos) << r.err;
}

// An anisotropic template: the same LMC as the isotropic template on coordinates scaled by the map
// (ard(1, 0.5): lag |(dx, dy / 0.5)|), written with the map so that cokriging applies it.
TEST_F(LmcCli, AnisotropicTemplateFitsTheMappedCoordinatesAndKeepsTheMap) {
  Eigen::MatrixXd x, z;
  write("in.csv", simulated_csv(150, &x, &z));
  std::string scaled = "x,y,ex,ey,ez\n";
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    scaled += format_number(x(i, 0)) + "," + format_number(x(i, 1) / 0.5);
    for (int c = 0; c < 3; ++c) scaled += "," + format_number(z(i, c));
    scaled += "\n";
  }
  write("scaled.csv", scaled);
  auto r = run("fit-variogram --lmc --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --model 'nug(0)+gau(1,300)@ard(1,0.5)' --out " +
               path("aniso.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("anisotropy @ard(1,0.5)"), std::string::npos) << r.out;
  r = run("fit-variogram --lmc --input " + path("scaled.csv") + " --coords x,y --value ex,ey,ez --model 'nug(0)+gau(1,300)' --out " +
          path("iso.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CoregionalizationModel aniso = load_coregionalization_model(path("aniso.json"));
  const CoregionalizationModel iso = load_coregionalization_model(path("iso.json"));
  EXPECT_EQ(aniso.anisotropy().to_string(), "ard(1,0.5)");
  ASSERT_EQ(aniso.structures().size(), iso.structures().size());
  for (std::size_t k = 0; k < iso.structures().size(); ++k)
    EXPECT_LE((aniso.structures()[k].sills - iso.structures()[k].sills).cwiseAbs().maxCoeff(),
              1e-9 * iso.structures()[k].sills.cwiseAbs().maxCoeff() + 1e-15)
        << "structure " << k;
  // A variogram CSV cannot be mapped: refused naming the reason.
  r = run("variogram --input " + path("in.csv") + " --coords x,y --value ex,ey,ez --cross --out " + path("v.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run("fit-variogram --lmc --input " + path("v.csv") + " --value ex,ey,ez --model 'nug(0)+gau(1,300)@ard(1,0.5)'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("needs the samples (--coords)"), std::string::npos) << r.err;
}

}  // namespace lmc_cli_test
}  // namespace errfield
