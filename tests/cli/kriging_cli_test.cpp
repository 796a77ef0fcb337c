// End-to-end tests of `errfield interpolate --method kriging` and `errfield cv --method kriging`
// (the built CLI) on simulated data: the CLI must write what the library computes (the library is
// checked against gstat and closed forms in kriging_test / gstat_krige_test), with the documented
// columns, and reject bad input with a message.

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/conditional_simulation.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"
#include "errfield/kriging.hpp"
#include "errfield/indicator_kriging.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace kriging_cli_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
using P3 = Eigen::Vector3d;

class KrigingCli : public testing::CliTest {

 protected:
  void SetUp() override {
    // Simulated samples and targets in a 1000 mm cube.
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> u(0.0, 1000.0);
    std::ofstream s(path("S.csv")), t(path("T.csv"));
    s.precision(17);
    t.precision(17);
    s << "x,y,z,v,dx,dy,dz\n";
    for (int i = 0; i < 120; ++i) {
      const P3 p(u(rng), u(rng), u(rng));
      const double v = std::sin(p.x() / 200.0) + 0.001 * p.z();
      pts_.push_back(p);
      vals_.push_back(v);
      vecs_.emplace_back(v, 0.5 * v, std::cos(p.y() / 300.0));
      s << p.x() << ',' << p.y() << ',' << p.z() << ',' << v << ',' << vecs_.back().x() << ',' << vecs_.back().y() << ','
        << vecs_.back().z() << '\n';
    }
    t << "id,x,y,z\n";
    for (int i = 0; i < 50; ++i) {
      targets_.emplace_back(u(rng), u(rng), u(rng));
      t << i << ',' << targets_.back().x() << ',' << targets_.back().y() << ',' << targets_.back().z() << '\n';
    }
  }
  std::vector<P3> pts_, targets_;
  std::vector<double> vals_;
  std::vector<Eigen::Vector3d> vecs_;
};

const char* kModel = "sph(sill=0.5,range=400)+nug(0.001)";

TEST_F(KrigingCli, InterpolateWritesTheLibrarysPredictionsAndVariances) {
  for (const std::string extra : {"", " --kind universal1 --neighbors 25", " --kind simple --mean 0.2 --backend sparse"}) {
    const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --model \"" + kModel + "\"" + extra + " --out " + path("P.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    const CsvTable out = CsvTable::read(path("P.csv"));
    EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "pred", "var"}));
    KrigingOptions opt;
    if (extra.find("universal1") != std::string::npos) {
      opt.kind = KrigingKind::Universal;
      opt.backend = KrigingBackend::Local;
      opt.neighbors = 25;
    } else if (extra.find("simple") != std::string::npos) {
      opt.kind = KrigingKind::Simple;
      opt.simple_mean = {0.2};
      opt.backend = KrigingBackend::Sparse;
    }
    const auto pred = Kriging<P3, double>(pts_, vals_, VariogramModel::parse(kModel), opt).predict(targets_);
    const Eigen::MatrixXd got = out.numeric_columns({"pred", "var"});
    for (std::size_t t = 0; t < targets_.size(); ++t) {
      // Numbers are written in shortest round-trip form, so they come back exactly.
      EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 0), pred.mean[t]) << extra;
      EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 1), pred.variance[t]) << extra;
    }
  }
}

TEST_F(KrigingCli, VectorValuesGetOneColumnPerComponent) {
  const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                         " --coords x,y,z --value dx,dy,dz --model \"" + kModel + "\" --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable out = CsvTable::read(path("P.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "pred_dx", "pred_dy", "pred_dz", "var_dx", "var_dy",
                                                    "var_dz"}));
  const auto pred = Kriging<P3, Eigen::Vector3d>(pts_, vecs_, VariogramModel::parse(kModel)).predict(targets_);
  const Eigen::MatrixXd got = out.numeric_columns({"pred_dx", "pred_dy", "pred_dz", "var_dx", "var_dz"});
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    const auto i = static_cast<Eigen::Index>(t);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(got(i, c), pred.mean[t][c]);
    EXPECT_DOUBLE_EQ(got(i, 3), pred.variance[t]);
    EXPECT_DOUBLE_EQ(got(i, 4), pred.variance[t]);
  }
}

TEST_F(KrigingCli, ModelAutoPrintsTheFittedModel) {
  const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                         " --coords x,y,z --value v --model auto --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("--model auto"));
  EXPECT_THAT(r.output(), ::testing::AnyOf(HasSubstr("sph(sill="), HasSubstr("exp(sill="), HasSubstr("gau(sill="),
                                           HasSubstr("mat(sill=")));
  // The choice says why: the criterion and that ill-conditioned fits were excluded.
  EXPECT_THAT(r.output(), HasSubstr("chosen by smallest AIC"));
  EXPECT_THAT(r.output(), HasSubstr("condition number"));
}

TEST_F(KrigingCli, CvLeaveOneOutMatchesTheLibrary) {
  const auto r = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y,z --value v --model \"" + kModel +
                         "\" --out " + path("CV.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("closed form"));
  const auto loo = Kriging<P3, double>(pts_, vals_, VariogramModel::parse(kModel)).leave_one_out();
  const Eigen::MatrixXd got = CsvTable::read(path("CV.csv")).numeric_columns({"pred", "var"});
  for (std::size_t i = 0; i < pts_.size(); ++i) {
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(i), 0), loo.prediction[i]);
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(i), 1), loo.variance[i]);
  }
  const auto k = run("cv --method kriging --samples " + path("S.csv") + " --coords x,y,z --value v --model \"" +
                         kModel + "\" --folds 5 --neighbors 20");
  ASSERT_EQ(k.exit_code, 0) << k.output();
  EXPECT_THAT(k.output(), HasSubstr("5-fold"));
  EXPECT_THAT(k.output(), HasSubstr("mean z^2"));
}

TEST_F(KrigingCli, BadInputIsRejectedWithAMessage) {
  const std::string base = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --out " + path("P.csv");
  auto r = run(base + " --model \"" + kModel + "\" --kind simple");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--mean"));
  r = run(base + " --model \"exp(sill=1,range=100)\" --backend sparse");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("compactly supported"));
  r = run(base + " --model \"sph(sill=1)\"");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("has no range"));
  r = run(base);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--model"));
  r = run(base + " --model \"" + kModel + "\" --kind kriging");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--kind"));
  r = run(base + " --model \"" + kModel + "\" --neighbour-metric euclidean");  // dense: no neighbours to choose
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--neighbour-metric"));
  r = run(base + " --model \"" + kModel + "\" --neighbors 10 --neighbour-metric manhattan");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("expected model or euclidean"));
  EXPECT_FALSE(fs::exists(path("P.csv")));
  r = run("interpolate --method idw --samples " + path("S.csv") + " --targets " + path("T.csv") +
              " --coords x,y,z --value v --model auto --out " + path("P.csv"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--model applies to --method kriging"));
}

TEST_F(KrigingCli, HelpExplainsTheRangeConvention) {
  const auto r = run("interpolate --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("scale parameter a, not the practical range"));
}

TEST_F(KrigingCli, NeighbourMetricMattersOnlyWithAnisotropy) {
  // Isotropic model: the model's lag is the Euclidean distance, so both metrics choose the same
  // neighbours and give identical output; an anisotropic model (tests/peers/gstat_anis_test.cpp
  // compares 'euclidean' with gstat) generally does not.
  const std::string base = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --neighbors 12 ";
  for (const std::string metric : {"model", "euclidean"})
    ASSERT_EQ(run(base + "--model \"" + std::string(kModel) + "\" --neighbour-metric " + metric + " --out " + path(metric + ".csv")).exit_code, 0);
  EXPECT_EQ(read("model.csv"), read("euclidean.csv"));
  const std::string anis = "sph(sill=0.5,range=400)+nug(0.001)@anis(30,20,10,0.3,0.2)";
  for (const std::string metric : {"model", "euclidean"})
    ASSERT_EQ(run(base + "--model \"" + anis + "\" --neighbour-metric " + metric + " --out " + path("a" + metric + ".csv")).exit_code, 0);
  EXPECT_NE(read("amodel.csv"), read("aeuclidean.csv"));
}

TEST_F(KrigingCli, SimulationsWriteTheLibrarysDraws) {
  // --simulations N writes sim1..simN after pred and var: the library's draws for the same seed,
  // and pred/var the plain kriging's.
  const std::string sequential = " --neighbors 25 --simulation-method sequential --simulation-neighbours 12";
  for (const std::string extra : {std::string(), sequential, sequential + " --simulation-draws-per-path 1"}) {
    const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --model \"" + kModel + "\" --simulations 3 --seed 5" + extra +
                           " --out " + path("P.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    const CsvTable out = CsvTable::read(path("P.csv"));
    EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "pred", "var", "sim1", "sim2", "sim3"}));
    KrigingOptions opt;
    SimulationOptions so;
    so.draws = 3;
    so.seed = 5;
    if (!extra.empty()) {
      opt.backend = KrigingBackend::Local;
      opt.neighbors = 25;
      so.method = UnconditionalMethod::Sequential;
      so.neighbours = 12;
      if (extra != sequential) so.draws_per_path = 1;  // a path per draw: other draws than the default's
    }
    const auto sim = simulate_conditional<P3, double>(pts_, vals_, targets_, VariogramModel::parse(kModel), opt, so);
    const auto pred = Kriging<P3, double>(pts_, vals_, VariogramModel::parse(kModel), opt).predict(targets_);
    const Eigen::MatrixXd got = out.numeric_columns({"pred", "var", "sim1", "sim2", "sim3"});
    for (std::size_t t = 0; t < targets_.size(); ++t) {
      const auto i = static_cast<Eigen::Index>(t);
      EXPECT_NEAR(got(i, 0), pred.mean[t], 1e-12 * (1.0 + std::abs(pred.mean[t]))) << extra;
      EXPECT_NEAR(got(i, 1), pred.variance[t], 1e-12) << extra;
      for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(got(i, 2 + k), sim.draws[static_cast<std::size_t>(k)][t]) << extra;
    }
  }
  const std::string base = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --model \"" + kModel + "\" --out " + path("Q.csv");
  auto r = run(base + " --seed 4");  // a seed without draws is a mistake, not a no-op
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--seed applies to --simulations"));
  r = run(base + " --simulations 2 --simulation-method turning-bands");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--simulation-method"));
  r = run(base + " --simulations 0");
  EXPECT_NE(r.exit_code, 0);
  r = run(base + " --simulation-draws-per-path 5");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--simulation-draws-per-path"));
  EXPECT_FALSE(fs::exists(path("Q.csv")));
}

TEST_F(KrigingCli, SimulationsCsvIsTheLibrarysNumbersAsShortestText) {
  // A table of more than 100,000 cells is written as numbers formatted in blocks of rows, in
  // parallel: byte for byte what format_number and csv_cell make of each cell, rows in order, for
  // 1 and 2 threads; a target that could not be kriged (no sample within --radius) has empty
  // cells; a text cell that needs quotes is quoted. 1,100 targets x 106 columns.
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::vector<P3> targets;
  std::vector<std::string> names;
  std::ofstream t(path("TB.csv"));
  t.precision(17);
  t << "name,x,y,z\n";
  for (int i = 0; i < 1100; ++i) {
    targets.emplace_back(i % 250 == 7 ? P3(9000.0 + i, 9000.0, 9000.0) : P3(u(rng), u(rng), u(rng)));
    names.push_back(i % 3 == 0 ? "p," + std::to_string(i) : "p" + std::to_string(i));
    t << csv_cell(names.back()) << ',' << targets.back().x() << ',' << targets.back().y() << ',' << targets.back().z() << '\n';
  }
  t.close();
  const CsvTable input = CsvTable::read(path("TB.csv"));
  KrigingOptions opt;
  opt.backend = KrigingBackend::Local;
  opt.neighbors = 20;
  opt.radius = 500.0;
  SimulationOptions so;
  so.draws = 100;
  so.seed = 3;
  const auto sim = simulate_conditional<P3, double>(pts_, vals_, targets, VariogramModel::parse(kModel), opt, so);
  ASSERT_EQ(sim.failed_targets, 5u);
  std::string expected = "name,x,y,z,pred,var";
  for (int k = 1; k <= 100; ++k) expected += ",sim" + std::to_string(k);
  expected += '\n';
  auto number = [](double v) { return std::isnan(v) ? std::string() : format_number(v); };
  for (std::size_t i = 0; i < targets.size(); ++i) {
    std::vector<std::string> cells;
    for (std::size_t c = 0; c < 4; ++c) cells.emplace_back(input.cell(i, c));  // the input's own text
    cells.push_back(number(sim.mean[i]));
    cells.push_back(number(sim.variance[i]));
    for (const auto& draw : sim.draws) cells.push_back(number(draw[i]));
    append_csv_line(expected, cells);
  }
  for (const char* threads : {"OMP_NUM_THREADS=1", "OMP_NUM_THREADS=2"}) {
    const auto r = run("interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("TB.csv") +
                           " --coords x,y,z --value v --model \"" + kModel +
                           "\" --backend local --neighbors 20 --radius 500 --simulations 100 --seed 3 --out " + path("PB.csv"),
                       {threads});
    ASSERT_EQ(r.exit_code, 0) << r.output();
    EXPECT_TRUE(read("PB.csv") == expected) << threads;
  }
}

TEST_F(KrigingCli, BlockKrigingWritesTheLibrarysBlocks) {
  const std::string base = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --model \"" + kModel + "\" --out " + path("P.csv");
  auto r = run(base + " --block 50,50,20 --block-points 3");
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto blocks = Kriging<P3, double>(pts_, vals_, VariogramModel::parse(kModel))
                          .predict_blocks(targets_, BlockDiscretization{{50.0, 50.0, 20.0}, 3});
  const Eigen::MatrixXd got = CsvTable::read(path("P.csv")).numeric_columns({"pred", "var"});
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 0), blocks.mean[t]);
    EXPECT_DOUBLE_EQ(got(static_cast<Eigen::Index>(t), 1), blocks.variance[t]);
  }
  const std::string other = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                            " --coords x,y,z --value v --model \"" + kModel + "\" --out " + path("Q.csv");
  r = run(other + " --block 50,50");  // two sizes for three coordinates
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("one size per coordinate"));
  r = run(other + " --block-points 3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--block-points applies to --block"));
  r = run(other + " --block 50,50,20 --simulations 2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("--block"));
  r = run(other + " --block 50,50,20 --backend sparse");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("sparse"));
  EXPECT_FALSE(fs::exists(path("Q.csv")));
}

// SIMULATED: n samples uniform in [0, 1000]^2 of sin(x / a) cos(y / b) + N(0, noise^2), as x,y,v:
// the first `train` rows to `file`, the others to `held_out`.
void write_sine_field(const std::string& file, const std::string& held_out, int n, int train, double a, double b,
                      double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::normal_distribution<double> e(0.0, noise);
  std::ofstream s(file), t;
  if (!held_out.empty()) t.open(held_out);
  s.precision(10);
  t.precision(10);
  s << "x,y,v\n";
  t << "x,y,v\n";
  for (int i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    (i < train ? s : t) << x << ',' << y << ',' << std::sin(x / a) * std::cos(y / b) + e(rng) << '\n';
  }
}

TEST_F(KrigingCli, ModelAutoKeepsTheLikelihoodFamiliesBeyond3000Samples) {
  // Issue 23: beyond 3,000 samples --model auto used to fall back to a weighted fit of the empirical
  // variogram (isotropic, and on a 125 mm grid no nugget). Now the families are the same at any N:
  // compared on 700 samples, the winner refitted on all by the Vecchia likelihood. SIMULATED 2-D
  // field with noise variance 4e-4: the nugget must be found, near that.
  write_sine_field(path("big.csv"), "", 3100, 3100, 150.0, 220.0, 0.02, 31);
  std::ofstream t(path("bigt.csv"));
  t << "x,y\n500,500\n250,750\n";
  t.close();
  const auto r = run("interpolate --method kriging --samples " + path("big.csv") + " --targets " + path("bigt.csv") +
                     " --coords x,y --value v --model auto --neighbors 16 --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("REML fits"));
  EXPECT_THAT(r.output(), HasSubstr("refitted on all"));
  EXPECT_THAT(r.output(), Not(HasSubstr("empirical variogram")));
  const std::string out = r.output();
  const auto at = out.find("+nug(sill=");
  ASSERT_NE(at, std::string::npos) << out;
  const double nugget = std::stod(out.substr(at + 10));
  EXPECT_GT(nugget, 0.5 * 4e-4);
  EXPECT_LT(nugget, 2.0 * 4e-4);
}

// interpolate --indicator writes p_lt_<T> (order-corrected) and var_lt_<T> as the library's
// indicator_kriging with one model per threshold (here with the local back end), and refuses
// misuse with exit 2 naming the option.
TEST_F(KrigingCli, IndicatorWritesTheLibrarysProbabilitiesAndRefusesMisuse) {
  const std::string models = "sph(sill=0.15,range=500)+nug(0.02);exp(sill=0.2,range=200)+nug(0.05);sph(sill=0.1,range=300)";
  const std::string base = "interpolate --method kriging --samples " + path("S.csv") + " --targets " + path("T.csv") +
                           " --coords x,y,z --value v --neighbors 30";
  auto r = run(base + " --indicator -0.5,0,0.5 --model \"" + models + "\" --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const CsvTable out = CsvTable::read(path("P.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "p_lt_-0.5", "p_lt_0", "p_lt_0.5", "var_lt_-0.5",
                                                    "var_lt_0", "var_lt_0.5"}));
  std::vector<VariogramModel> m;
  for (const char* t : {"sph(sill=0.15,range=500)+nug(0.02)", "exp(sill=0.2,range=200)+nug(0.05)", "sph(sill=0.1,range=300)"})
    m.push_back(VariogramModel::parse(t));
  KrigingOptions opt;
  opt.backend = KrigingBackend::Local;
  opt.neighbors = 30;
  const std::vector<double> thresholds{-0.5, 0.0, 0.5};
  const auto ik = indicator_kriging<P3>(pts_, vals_, targets_, thresholds, m, opt);
  EXPECT_EQ(out.numeric_columns({"p_lt_-0.5", "p_lt_0", "p_lt_0.5"}), ik.probability);
  EXPECT_EQ(out.numeric_columns({"var_lt_-0.5", "var_lt_0", "var_lt_0.5"}), ik.variance);
  EXPECT_THAT(r.err, HasSubstr("order relations"));
  r = run(base + " --model \"" + kModel + "\" --order-correction none --out " + path("Q.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--indicator"));
  r = run(base + " --indicator 0.5,0 --model \"" + kModel + "\" --out " + path("Q.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--indicator"));
  r = run(base + " --indicator -0.5,0,0.5 --model \"" + kModel + ";" + kModel + "\" --out " + path("Q.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("2 models"));
}

// --auto-search fast (the default) and thorough: both choose a model and say how; fast ranks on a
// subset of 250 and names it, thorough sees all 400; their held-out errors on the same SIMULATED
// field (smooth sine + noise 0.05) agree within 5 %; a wrong word is refused naming the option.
TEST_F(KrigingCli, AutoSearchFastAndThoroughAgreeHeldOut) {
  write_sine_field(path("a.csv"), path("at.csv"), 500, 400, 170.0, 230.0, 0.05, 11);
  std::array<double, 2> rmse{};
  for (int k = 0; k < 2; ++k) {
    const std::string search = k == 0 ? "fast" : "thorough";
    const auto r = run("interpolate --method kriging --samples " + path("a.csv") + " --targets " + path("at.csv") +
                       " --coords x,y --value v --model auto --auto-search " + search + " --out " + path("A.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    EXPECT_THAT(r.output(), HasSubstr(k == 0 ? "ranked on a random subset of 250 of the 400 samples, the best 2 refitted on all"
                                             : "the best 3 refitted with more starts"));
    const Eigen::MatrixXd got = CsvTable::read(path("A.csv")).numeric_columns({"v", "pred"});
    rmse[static_cast<std::size_t>(k)] = std::sqrt((got.col(0) - got.col(1)).squaredNorm() / static_cast<double>(got.rows()));
  }
  EXPECT_LT(rmse[0], 1.05 * rmse[1]) << rmse[0] << " vs " << rmse[1];
  EXPECT_LT(rmse[0], 0.08);  // the noise alone is 0.05
  const auto bad = run("interpolate --method kriging --samples " + path("a.csv") + " --targets " + path("at.csv") +
                       " --coords x,y --value v --model auto --auto-search quick --out " + path("B.csv"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.output(), HasSubstr("--auto-search"));
  EXPECT_FALSE(fs::exists(path("B.csv")));
}

}  // namespace
}  // namespace errfield
