// End-to-end tests of cokriging through the CLI: `errfield interpolate|cv --method kriging --model
// lmc.json` (the built executable) on simulated data must write what errfield::Cokriging computes
// (the library is checked against the cokriging system written out and against gstat in
// cokriging_test / gstat_cokriging_test), with the documented columns, and refuse what it does
// not support by name.

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/cokriging.hpp"
#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace cokriging_cli_test {

using ::testing::HasSubstr;
using P3 = Eigen::Vector3d;

constexpr const char* kLmc = R"({"type": "lmc", "components": ["dx", "dy", "dz"],
  "structures": [{"kind": "nug", "sills": [[0.002, 0.0005, 0], [0.0005, 0.003, 0], [0, 0, 0.002]]},
                 {"kind": "sph", "range": 500, "sills": [[0.5, 0.3, 0.1], [0.3, 0.4, -0.1], [0.1, -0.1, 0.3]]},
                 {"kind": "exp", "range": 120, "sills": [[0.1, -0.05, 0], [-0.05, 0.2, 0], [0, 0, 0.1]]}]})";

class CokrigingCli : public testing::CliTest {
 protected:
  void SetUp() override {
    // SIMULATED samples and targets in a 1000 mm cube (smooth functions, not a draw of the model).
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1000.0);
    std::ofstream s(path("S.csv")), t(path("T.csv"));
    s.precision(17);
    t.precision(17);
    s << "x,y,z,dx,dy,dz\n";
    for (int i = 0; i < 60; ++i) {
      const P3 p(u(rng), u(rng), u(rng));
      pts_.push_back(p);
      vals_.emplace_back(std::sin(p.x() / 200.0), 0.5 * std::sin(p.x() / 200.0) + std::cos(p.y() / 300.0), 0.001 * p.z());
      s << p.x() << ',' << p.y() << ',' << p.z() << ',' << vals_.back().x() << ',' << vals_.back().y() << ','
        << vals_.back().z() << '\n';
    }
    t << "id,x,y,z\n";
    for (int i = 0; i < 30; ++i) {
      targets_.emplace_back(u(rng), u(rng), u(rng));
      t << i << ',' << targets_.back().x() << ',' << targets_.back().y() << ',' << targets_.back().z() << '\n';
    }
    write("lmc.json", kLmc);
  }
  CoregionalizationModel model() const { return load_coregionalization_model(path("lmc.json")); }
  std::string interpolate(const std::string& extra) const {
    return "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
           " --coords x,y,z --value dx,dy,dz --model " + path("lmc.json") + " --out " + path("P.csv") + extra;
  }
  std::vector<P3> pts_, targets_;
  std::vector<Eigen::Vector3d> vals_;
};

TEST_F(CokrigingCli, InterpolateWritesTheLibrarysMeansVariancesAndCovariances) {
  for (const std::string extra : {"", " --kind universal1 --neighbors 25", " --kind simple --mean 0.2 --nugget-as error"}) {
    const auto r = run(interpolate(extra));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    EXPECT_THAT(r.output(), HasSubstr("cokriging"));
    const CsvTable out = CsvTable::read(path("P.csv"));
    EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "pred_dx", "pred_dy", "pred_dz", "var_dx",
                                                      "var_dy", "var_dz", "cov_dx_dy", "cov_dx_dz", "cov_dy_dz"}));
    KrigingOptions opt;
    if (extra.find("universal1") != std::string::npos) {
      opt.kind = KrigingKind::Universal;
      opt.backend = KrigingBackend::Local;
      opt.neighbors = 25;
    } else if (extra.find("simple") != std::string::npos) {
      opt.kind = KrigingKind::Simple;
      opt.simple_mean = {0.2};
      opt.nugget = NuggetTreatment::MeasurementError;
    }
    const auto pred = Cokriging<P3, Eigen::Vector3d>(pts_, vals_, model(), opt).predict(targets_);
    const Eigen::MatrixXd got = out.numeric_columns(
        {"pred_dx", "pred_dy", "pred_dz", "var_dx", "var_dy", "var_dz", "cov_dx_dy", "cov_dx_dz", "cov_dy_dz"});
    for (std::size_t t = 0; t < targets_.size(); ++t) {
      const auto i = static_cast<Eigen::Index>(t);
      const Eigen::MatrixXd& c = pred.covariance[t];
      // Numbers are written in shortest round-trip form, so they come back exactly.
      for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(got(i, a), pred.mean[t][a]) << extra;
      for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(got(i, 3 + a), c(a, a)) << extra;
      EXPECT_DOUBLE_EQ(got(i, 6), c(0, 1)) << extra;
      EXPECT_DOUBLE_EQ(got(i, 7), c(0, 2)) << extra;
      EXPECT_DOUBLE_EQ(got(i, 8), c(1, 2)) << extra;
    }
  }
}

TEST_F(CokrigingCli, CrossValidationWritesTheLeaveOneOutResidualsAndTheirCovariances) {
  const auto r = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y,z --value dx,dy,dz --model " +
                     path("lmc.json") + " --out " + path("CV.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable out = CsvTable::read(path("CV.csv"));
  EXPECT_EQ(out.header(),
            (std::vector<std::string>{"x", "y", "z", "dx", "dy", "dz", "fold", "pred_dx", "residual_dx", "pred_dy",
                                      "residual_dy", "pred_dz", "residual_dz", "abs_residual", "var", "var_dx", "var_dy",
                                      "var_dz", "cov_dx_dy", "cov_dx_dz", "cov_dy_dz"}));
  const auto cv = Cokriging<P3, Eigen::Vector3d>(pts_, vals_, model()).leave_one_out();
  const Eigen::MatrixXd got =
      out.numeric_columns({"pred_dx", "residual_dy", "var", "var_dz", "cov_dx_dz"});
  for (std::size_t i = 0; i < pts_.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    EXPECT_DOUBLE_EQ(got(k, 0), cv.prediction[i][0]);
    // The command recomputes residual = observed - pred from the CSV's values: a rounding apart.
    EXPECT_NEAR(got(k, 1), cv.residual[i][1], 1e-12);
    EXPECT_DOUBLE_EQ(got(k, 2), cv.covariance[i].trace() / 3.0);
    EXPECT_DOUBLE_EQ(got(k, 3), cv.covariance[i](2, 2));
    EXPECT_DOUBLE_EQ(got(k, 4), cv.covariance[i](0, 2));
  }
}

TEST_F(CokrigingCli, RefusesOptionsCokrigingDoesNotHaveNamingThem) {
  const std::vector<std::pair<std::string, std::string>> cases{
      {" --block 10,10,10", "--block"},
      {" --simulations 2", "--simulations"},
      {" --backend sparse", "--backend sparse"},
      {" --covariates x", "--covariates"},
      {" --measurement-variance x", "--measurement-variance"},
  };
  for (const auto& [extra, option] : cases) {
    const auto r = run(interpolate(extra));
    EXPECT_NE(r.exit_code, 0) << extra;
    EXPECT_THAT(r.output(), HasSubstr(option + " is not available with cokriging")) << r.output();
  }
  const auto folds = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y,z --value dx,dy,dz --model " +
                         path("lmc.json") + " --folds 5");
  EXPECT_NE(folds.exit_code, 0);
  EXPECT_THAT(folds.output(), HasSubstr("--folds 5 is not available with cokriging"));
}

TEST_F(CokrigingCli, RefusesAModelWhoseComponentsAreNotTheValueColumns) {
  const auto swapped = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value dy,dx,dz --model " + path("lmc.json") + " --out " + path("P.csv"));
  EXPECT_NE(swapped.exit_code, 0);
  EXPECT_THAT(swapped.output(), HasSubstr("components are dx,dy,dz but --value is dy,dx,dz"));
  const auto fewer = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                         " --coords x,y,z --value dx,dy --model " + path("lmc.json") + " --out " + path("P.csv"));
  EXPECT_NE(fewer.exit_code, 0);
  EXPECT_THAT(fewer.output(), HasSubstr("has 3 components (dx,dy,dz) but --value gives 2 column(s) (dx,dy)"));
  EXPECT_FALSE(std::ifstream(path("P.csv")).good()) << "nothing is written on a refusal";
}

TEST_F(CokrigingCli, AnUnnamedModelTakesTheValueColumnsInOrder) {
  std::string unnamed = kLmc;
  const std::string names = "\"components\": [\"dx\", \"dy\", \"dz\"],";
  unnamed.erase(unnamed.find(names), names.size());
  write("lmc.json", unnamed);
  const auto r = run(interpolate(""));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("does not name its components; taken in --value order (dx,dy,dz)"));
}

// Heterotopic samples: an empty value cell is "not measured" for cokriging only; every command
// that needs every value still refuses it naming file, line and column, and so does cokriging for
// a row with nothing measured or a non-numeric cell.
TEST_F(CokrigingCli, EmptyValueCellsAreNotMeasuredForCokrigingAndRefusedElsewhere) {
  const CsvTable full = CsvTable::read(path("S.csv"));
  std::ofstream s(path("H.csv"));
  s << "x,y,z,dx,dy,dz\n";
  std::vector<Eigen::Vector3d> gappy = vals_;
  for (std::size_t i = 0; i < full.row_count(); ++i) {
    for (std::size_t c = 0; c < 6; ++c) {
      // dy missing at every third sample, dz at every fourth (never both with dx).
      const bool gap = (c == 4 && i % 3 == 1) || (c == 5 && i % 4 == 2);
      if (gap) gappy[i][static_cast<int>(c) - 3] = std::numeric_limits<double>::quiet_NaN();
      s << (c ? "," : "") << (gap ? std::string() : std::string(full.cell(i, c)));
    }
    s << "\n";
  }
  s.close();
  const std::string tail = " --coords x,y,z --value dx,dy,dz --model " + path("lmc.json");
  const auto r = run("interpolate --method kriging --samples " + path("H.csv") + " --targets " + path("T.csv") + tail +
                     " --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto pred = Cokriging<P3, Eigen::Vector3d>(pts_, gappy, model()).predict(targets_);
  const Eigen::MatrixXd got = CsvTable::read(path("P.csv")).numeric_columns({"pred_dy", "var_dz"});
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 0), pred.mean[t][1]);
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 1), pred.covariance[t](2, 2));
  }
  // Leave-one-out of heterotopic cokriging: the library's (every measured component of a sample
  // left out together; tested against refitting without the sample in cokriging_test), a component
  // not measured at a sample has empty prediction and residual cells there.
  const auto cv = run("cv --method kriging --samples " + path("H.csv") + tail + " --out " + path("CV.csv"));
  ASSERT_EQ(cv.exit_code, 0) << cv.output();
  EXPECT_THAT(cv.output(), HasSubstr("dy: predicted 40 of 40"));
  const auto loo = Cokriging<P3, Eigen::Vector3d>(pts_, gappy, model()).leave_one_out();
  const CsvTable written = CsvTable::read(path("CV.csv"));
  for (std::size_t i = 0; i < pts_.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const std::string name = std::string("dxdydz").substr(static_cast<std::size_t>(2 * c), 2);
      const std::string_view pred = written.cell(i, written.column_index("pred_" + name));
      const std::string_view residual = written.cell(i, written.column_index("residual_" + name));
      if (std::isnan(gappy[i][c])) {
        EXPECT_TRUE(pred.empty() && residual.empty()) << "sample " << i << ", " << name;
        continue;
      }
      EXPECT_DOUBLE_EQ(written.numeric_cell(i, written.column_index("pred_" + name)), loo.prediction[i][c]) << i;
      EXPECT_NEAR(written.numeric_cell(i, written.column_index("residual_" + name)), loo.residual[i][c], 1e-12) << i;
    }
  const auto cv_shared = run("cv --method kriging --samples " + path("H.csv") + " --coords x,y,z --value dx,dy,dz --model sph(1,500)");
  EXPECT_EQ(cv_shared.exit_code, 2);
  EXPECT_THAT(cv_shared.output(), HasSubstr("H.csv:3: column 'dy' is empty; expected a number"));
  const auto shared = run("interpolate --method kriging --samples " + path("H.csv") + " --targets " + path("T.csv") +
                          " --coords x,y,z --value dx,dy,dz --model sph(1,500) --out " + path("Q.csv"));
  EXPECT_EQ(shared.exit_code, 2);
  EXPECT_THAT(shared.output(), HasSubstr("H.csv:3: column 'dy' is empty"));
  const auto idw = run("interpolate --method idw --samples " + path("H.csv") + " --targets " + path("T.csv") +
                       " --coords x,y,z --value dx,dy,dz --out " + path("Q.csv"));
  EXPECT_EQ(idw.exit_code, 2);
  EXPECT_THAT(idw.output(), HasSubstr("H.csv:3: column 'dy' is empty"));
  // A word where a number belongs is still an error, and so is a row with no value at all.
  write("W.csv", "x,y,z,dx,dy,dz\n0,0,0,1,abc,2\n1,1,1,2,3,4\n5,0,0,1,2,3\n");
  const auto word = run("interpolate --method kriging --samples " + path("W.csv") + " --targets " + path("T.csv") + tail +
                        " --out " + path("Q.csv"));
  EXPECT_EQ(word.exit_code, 2);
  EXPECT_THAT(word.output(), HasSubstr("W.csv:2: column 'dy': 'abc' is not a number"));
  write("E.csv", "x,y,z,dx,dy,dz\n0,0,0,1,2,2\n1,1,1,,,\n5,0,0,1,2,3\n");
  const auto empty = run("interpolate --method kriging --samples " + path("E.csv") + " --targets " + path("T.csv") + tail +
                         " --out " + path("Q.csv"));
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_THAT(empty.output(), HasSubstr("E.csv:3: cokriging: this sample has no measured component"));
}

}  // namespace cokriging_cli_test
}  // namespace errfield
