// End-to-end tests of --covariates (kriging with external drift) in `errfield interpolate
// --method kriging`, `cv`, `variogram` and `fit-variogram --method reml` on simulated data: the CLI
// must write what the library computes (the library is checked against the bordered system in
// kriging_external_drift_test and against gstat in peers/gstat_external_drift_test), and refuse a
// missing or non-finite covariate naming the file, row and column.

#include <cmath>
#include <fstream>
#include <random>

#include <Eigen/Dense>
#include <gmock/gmock.h>
#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/kriging.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/trend_residuals.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace external_drift_cli_test {

using ::testing::HasSubstr;
using P2 = Eigen::Vector2d;
constexpr const char* kModel = "exp(sill=0.3,range=150)+nug(0.01)";

class ExternalDriftCli : public testing::CliTest {
 protected:
  void SetUp() override {
    // Simulated: a field in a 1000 x 1000 square whose mean follows a covariate c (a "distance").
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(0.0, 1000.0);
    std::normal_distribution<double> e(0.0, 0.05);
    std::ofstream s(path("S.csv")), t(path("T.csv"));
    s.precision(17);
    t.precision(17);
    s << "x,y,v,c\n";
    auto cov = [](const P2& p) { return std::sqrt(std::abs(p.x() - 400.0) / 100.0); };
    for (int i = 0; i < 90; ++i) {
      const P2 p(u(rng), u(rng));
      pts_.push_back(p);
      cov_s_.push_back(cov(p));
      vals_.push_back(-0.8 * cov(p) + std::sin(p.y() / 150.0) + e(rng));
      s << p.x() << ',' << p.y() << ',' << vals_.back() << ',' << cov_s_.back() << '\n';
    }
    t << "id,x,y,c\n";
    for (int i = 0; i < 30; ++i) {
      targets_.emplace_back(u(rng), u(rng));
      cov_t_.push_back(cov(targets_.back()));
      t << i << ',' << targets_.back().x() << ',' << targets_.back().y() << ',' << cov_t_.back() << '\n';
    }
  }
  static Eigen::MatrixXd column(const std::vector<double>& v) {
    return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  std::vector<P2> pts_, targets_;
  std::vector<double> vals_, cov_s_, cov_t_;
};

TEST_F(ExternalDriftCli, InterpolateWritesTheLibrarysPredictions) {
  for (const std::string extra : {"", " --neighbors 20", " --kind universal1"}) {
    const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                       " --coords x,y --value v --covariates c --model \"" + kModel + "\"" + extra + " --out " +
                       path("P.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    EXPECT_THAT(r.err, HasSubstr("external drift (1 covariate(s))"));
    KrigingOptions o;
    o.covariates = {"c"};
    if (extra == " --neighbors 20") {
      o.backend = KrigingBackend::Local;
      o.neighbors = 20;
    } else if (!extra.empty()) {
      o.kind = KrigingKind::Universal;
    }
    const Kriging<P2, double> k(pts_, vals_, column(cov_s_), VariogramModel::parse(kModel), o);
    const auto pred = k.predict(targets_, column(cov_t_));
    const Eigen::MatrixXd got = CsvTable::read(path("P.csv")).numeric_columns({"pred", "var"});
    for (std::size_t t = 0; t < targets_.size(); ++t) {
      EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 0), pred.mean[t]) << extra;
      EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 1), pred.variance[t]) << extra;
    }
  }
}

TEST_F(ExternalDriftCli, CrossValidationUsesTheCovariates) {
  const auto loo = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y --value v --covariates c --model \"" +
                       kModel + "\" --out " + path("L.csv"));
  ASSERT_EQ(loo.exit_code, 0) << loo.output();
  KrigingOptions o;
  o.covariates = {"c"};
  const auto cv = Kriging<P2, double>(pts_, vals_, column(cov_s_), VariogramModel::parse(kModel), o).leave_one_out();
  const Eigen::MatrixXd got = CsvTable::read(path("L.csv")).numeric_columns({"pred", "var"});
  for (std::size_t i = 0; i < pts_.size(); ++i) {
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(i), 0), cv.prediction[i]);
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(i), 1), cv.variance[i]);
  }
  // k-fold: each held-out sample predicted from the other folds with its own covariate; with
  // the covariate the residuals must differ from those without (the drift is used).
  const auto kfold = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y --value v --covariates c --model \"" +
                         kModel + "\" --folds 5 --out " + path("K.csv"));
  ASSERT_EQ(kfold.exit_code, 0) << kfold.output();
  const auto plain = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y --value v --model \"" + kModel +
                         "\" --folds 5 --out " + path("K0.csv"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output();
  const CsvTable with = CsvTable::read(path("K.csv")), without = CsvTable::read(path("K0.csv"));
  EXPECT_EQ(with.numeric_columns({"fold"}), without.numeric_columns({"fold"})) << "the same folds";
  EXPECT_GT((with.numeric_columns({"pred"}) - without.numeric_columns({"pred"})).cwiseAbs().maxCoeff(), 1e-3);
  // The held-out predictions are kriging from the other folds: check fold 0 against the library.
  const Eigen::MatrixXd fold = with.numeric_columns({"fold"}), pred = with.numeric_columns({"pred"});
  std::vector<P2> train, test;
  std::vector<double> train_v, train_c, test_c, test_pred;
  for (std::size_t i = 0; i < pts_.size(); ++i)
    if (fold(static_cast<Eigen::Index>(i), 0) == 0) {
      test.push_back(pts_[i]);
      test_c.push_back(cov_s_[i]);
      test_pred.push_back(pred(static_cast<Eigen::Index>(i), 0));
    } else {
      train.push_back(pts_[i]);
      train_v.push_back(vals_[i]);
      train_c.push_back(cov_s_[i]);
    }
  ASSERT_FALSE(test.empty());
  const auto p = Kriging<P2, double>(train, train_v, column(train_c), VariogramModel::parse(kModel), o).predict(test, column(test_c));
  for (std::size_t i = 0; i < test.size(); ++i) EXPECT_DOUBLE_EQ(test_pred[i], p.mean[i]);
}

TEST_F(ExternalDriftCli, VariogramIsThatOfTheOlsResiduals) {
  const auto r = run("variogram --input " + path("S.csv") + " --coords x,y --value v --covariates c --bins 0:500:50 --out " +
                     path("V.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  // Independent: OLS by the normal equations of [1, c], then the library's variogram.
  const Eigen::VectorXd z = column(vals_), c = column(cov_s_);
  Eigen::MatrixXd f(z.size(), 2);
  f << Eigen::VectorXd::Ones(z.size()), c;
  const Eigen::VectorXd beta = (f.transpose() * f).ldlt().solve(f.transpose() * z);
  const Eigen::MatrixXd resid = z - f * beta;
  Eigen::MatrixXd x(static_cast<Eigen::Index>(pts_.size()), 2);
  for (std::size_t i = 0; i < pts_.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = pts_[i].transpose();
  EmpiricalVariogramOptions vo;
  const EmpiricalVariogram v = empirical_variogram(x, resid, LagBins::uniform(0.0, 500.0, 50.0), vo);
  const Eigen::MatrixXd got = CsvTable::read(path("V.csv")).numeric_columns({"gamma"});
  ASSERT_EQ(got.rows(), static_cast<Eigen::Index>(v.bins.size()));
  for (std::size_t b = 0; b < v.bins.size(); ++b)
    EXPECT_NEAR(got(static_cast<Eigen::Index>(b), 0), v.bins[b].gamma, 1e-12 * v.bins[b].gamma) << "bin " << b;
}

TEST_F(ExternalDriftCli, RemlFitHasTheCovariateInTheDrift) {
  const auto r = run("fit-variogram --method reml --input " + path("S.csv") + " --coords x,y --value v --covariates c "
                     "--model exp --out " + path("M.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const nlohmann::json fitted = nlohmann::json::parse(read("M.json"));
  EXPECT_EQ(fitted["fit"]["covariates"], nlohmann::json::array({"c"}));
  // The fitted model is at least as likely as the plain fit's model under the likelihood with the
  // covariate (it maximizes that likelihood), and the nll printed is that likelihood at it.
  const auto plain = run("fit-variogram --method reml --input " + path("S.csv") + " --coords x,y --value v --model exp "
                         "--out " + path("M0.json"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output();
  Eigen::MatrixXd x(static_cast<Eigen::Index>(pts_.size()), 2);
  for (std::size_t i = 0; i < pts_.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = pts_[i].transpose();
  LikelihoodFitOptions o;
  o.covariates = column(cov_s_);
  const VariogramModel with = load_variogram_model(path("M.json")), without = load_variogram_model(path("M0.json"));
  const double nll_with = negative_log_likelihood(x, column(vals_), with, o);
  EXPECT_LE(nll_with, negative_log_likelihood(x, column(vals_), without, o) + 1e-6);
  EXPECT_THAT(r.out, HasSubstr("REML negative log-likelihood = " + format_number(nll_with).substr(0, 6)));
}

TEST_F(ExternalDriftCli, MissingOrNonFiniteCovariateNamesFileRowAndColumn) {
  rewrite("T.csv", "T_noc.csv", [](const CsvTable&, std::size_t, std::vector<std::string>&) {},
          [](const std::string& col) { return col != "c"; });
  const auto missing = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T_noc.csv") +
                           " --coords x,y --value v --covariates c --model \"" + kModel + "\" --out " + path("P.csv"));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_THAT(missing.err, HasSubstr(path("T_noc.csv") + ": no column 'c'"));
  rewrite("S.csv", "S_nan.csv", [](const CsvTable& t, std::size_t row, std::vector<std::string>& cells) {
    if (row == 4) cells[t.column_index("c")] = "nan";
  });
  for (const std::string& cmd : {"interpolate --method kriging --targets " + path("T.csv") + " --out " + path("P.csv"),
                                std::string("cv --method kriging")}) {
    const auto nan = run(cmd + " --samples " + path("S_nan.csv") + " --coords x,y --value v --covariates c --model \"" +
                         kModel + "\"");
    EXPECT_NE(nan.exit_code, 0) << cmd;
    EXPECT_THAT(nan.err, HasSubstr(path("S_nan.csv") + ":6: column 'c'")) << cmd;  // data row 4 is line 6
  }
  const auto variogram = run("variogram --input " + path("S_nan.csv") + " --coords x,y --value v --covariates c");
  EXPECT_NE(variogram.exit_code, 0);
  EXPECT_THAT(variogram.err, HasSubstr(path("S_nan.csv") + ":6: column 'c'"));
  const auto simple = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                          " --coords x,y --value v --covariates c --kind simple --mean 0.1 --model \"" + kModel + "\" --out " +
                          path("P.csv"));
  EXPECT_NE(simple.exit_code, 0);
  EXPECT_THAT(simple.err, HasSubstr("covariates"));
}

}  // namespace external_drift_cli_test
}  // namespace errfield
