// Silent wrong results, round two (issue 12): inputs on which a command exited 0 with a number it
// could not vouch for. Each test states what happened before; now the command refuses (exit 1 or
// 2 with the reason) or writes the right thing. Robot data are SIMULATED (`errfield simulate`).

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <random>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace silent_results_test {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::CliTest;

class SilentResults : public CliTest {
 protected:
  // SIMULATED measurements on the paper's cube (1 base row + 27 grid points at --step 250).
  void simulate(const std::string& file, const std::string& step = "250") {
    const auto r = run("simulate --sample grid --step " + step + " --robot-out " + path("robot.json") + " --out " + path(file));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // `text` with column `col` of data row `row` (0-based, after comments and header) set to `value`
  // (row = -1: every data row).
  static std::string with_cell(const std::string& text, const std::string& col, int row, const std::string& value) {
    std::istringstream in(text);
    std::string out;
    std::size_t index = std::string::npos;
    int data = -1;
    for (std::string l; std::getline(in, l);) {
      if (l.empty() || l[0] == '#') {
        out += l + "\n";
        continue;
      }
      std::vector<std::string> cells;
      std::istringstream cs(l);
      for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
      if (index == std::string::npos) {
        index = static_cast<std::size_t>(std::find(cells.begin(), cells.end(), col) - cells.begin());
        EXPECT_LT(index, cells.size()) << "no column " << col;
      } else if (++data == row || row < 0) {
        cells.at(index) = value;
      }
      for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? "," : "") + cells[i];
      out += "\n";
    }
    return out;
  }
  // The header line (first line not starting with '#') of a CSV file.
  std::string header_of(const std::string& file) const {
    std::istringstream in(read(file));
    for (std::string l; std::getline(in, l);)
      if (!l.empty() && l[0] != '#') return l;
    return {};
  }
  bool exists(const std::string& file) const { return std::filesystem::exists(path(file)); }
};

// ---- implausible measurements -------------------------------------------------------------------

// fit accepted a negative or zero dist_b0 (calibrate rejected them) and compensate then sent
// 240-1081 mm corrections marked ok.
TEST_F(SilentResults, FitRefusesZeroNegativeAndAbsurdDistancesNamingFileLineAndColumn) {
  simulate("g.csv");
  const std::string g = read("g.csv");
  const std::pair<std::string, std::string> values[] = {{"0", "0 mm"}, {"-5", "-5 mm"}, {"1e300", "1e+300 mm"}};
  for (const auto& [v, shown] : values) {
    write("bad.csv", with_cell(g, "dist_b0", 5, v));
    for (const std::string method : {"distance-idw", "distance-kriging"}) {
      const auto r = run("fit --robot " + path("robot.json") + " --data " + path("bad.csv") + " --method " + method + " --out " + path("m.json"));
      EXPECT_EQ(r.exit_code, 2) << v << " " << method << ": " << r.err;
      // data row 5 is on line 5 + 1 (header) + the comment lines; the message names it
      EXPECT_THAT(r.err, AllOf(HasSubstr("bad.csv:"), HasSubstr("column 'dist_b0': " + shown))) << v;
      EXPECT_FALSE(exists("m.json")) << v << " " << method;
    }
  }
  const auto ok = run("fit --robot " + path("robot.json") + " --data " + path("g.csv") + " --method distance-idw --out " + path("m.json"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// calibrate with distances of 1e300 "converged" to a robot with 1e300 mm links; with a frozen
// tracker (every mx,my,mz identical) it collapsed link 3 with only a warning.
TEST_F(SilentResults, CalibrateRefusesAbsurdDistancesAndAFrozenTracker) {
  simulate("g.csv");
  const std::string g = read("g.csv");
  write("far.csv", with_cell(g, "dist_b0", -1, "1e300"));
  auto r = run("calibrate --robot " + path("robot.json") + " --data " + path("far.csv") + " --model distance --out " + path("c.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("far.csv:"), HasSubstr("column 'dist_b0': 1e+300 mm"), HasSubstr("nominal distance")));
  EXPECT_THAT(r.out, Not(HasSubstr("converged")));
  EXPECT_FALSE(exists("c.json"));

  std::string frozen = with_cell(g, "mx", -1, "1200.5");
  frozen = with_cell(frozen, "my", -1, "-30.25");
  frozen = with_cell(frozen, "mz", -1, "800");
  write("frozen.csv", frozen);
  r = run("calibrate --robot " + path("robot.json") + " --data " + path("frozen.csv") + " --model position --out " + path("c.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("frozen.csv: "), HasSubstr("did not follow the reflector")));
  EXPECT_FALSE(exists("c.json"));
  r = run("fit --robot " + path("robot.json") + " --data " + path("frozen.csv") + " --method position-idw --out " + path("m.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("did not follow the reflector"));
  EXPECT_FALSE(exists("m.json"));
}

// ---- no non-finite number in any output --------------------------------------------------------

// variogram gamma for values near 1e300, IDW at 1.7e308, universal kriging's variance far away:
// "inf" was written. Now: exit 1 naming the column and why; the previous output stays.
TEST_F(SilentResults, OverflowingResultsAreRefusedNotWrittenAsInf) {
  write("big.csv", "x,y,z,v\n0,0,0,1e300\n1,0,0,-1e300\n0,1,0,5e299\n0,0,1,-7e299\n");
  write("g.csv", "previous\n");
  auto r = run("variogram --input " + path("big.csv") + " --coords x,y,z --value v --bins 0:2:0.5 --out " + path("g.csv"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("'gamma'"), HasSubstr("inf"), HasSubstr("non-finite")));
  EXPECT_EQ(read("g.csv"), "previous\n");

  write("huge.csv", "x,y,z,v\n0,0,0,1.7e308\n1,0,0,1.7e308\n0,1,0,1.7e308\n0,0,1,1.7e308\n");
  write("t.csv", "x,y,z\n0.3,0.3,0.3\n");
  r = run("interpolate --method idw --samples " + path("huge.csv") + " --targets " + path("t.csv") +
          " --coords x,y,z --value v --out " + path("p.csv"));
  // Either the weighted mean (1.7e308, finite) or a refusal; never "inf".
  if (r.exit_code == 0) {
    EXPECT_THAT(read("p.csv"), Not(HasSubstr("inf")));
  } else {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_THAT(r.err, HasSubstr("non-finite"));
    EXPECT_FALSE(exists("p.csv"));
  }

  std::string s = "x,y,z,v\n";
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int i = 0; i < 40; ++i) s += std::to_string(u(rng)) + "," + std::to_string(u(rng)) + "," + std::to_string(u(rng)) + ",1\n";
  write("s.csv", s);
  write("far.csv", "x,y,z\n1e300,1e300,1e300\n");
  r = run("interpolate --method kriging --kind universal1 --model exp(sill=1,range=3)+nug(0.01) --samples " +
          path("s.csv") + " --targets " + path("far.csv") + " --coords x,y,z --value v --out " + path("k.csv"));
  if (r.exit_code == 0) {
    EXPECT_THAT(read("k.csv"), AllOf(Not(HasSubstr("inf")), Not(HasSubstr("nan"))));
  } else {
    EXPECT_THAT(r.err, HasSubstr("non-finite")) << r.err;
    EXPECT_FALSE(exists("k.csv"));
  }
}

// ik wrote residual_mm = inf for a target 1e300 away.
TEST_F(SilentResults, IkNeverWritesANonFiniteResidual) {
  write("far.csv", "x,y,z,rx,ry,rz\n1200,0,900,180,0,180\n1e300,0,900,180,0,180\n");
  write("o.csv", "previous\n");
  const auto r = run("ik --input " + path("far.csv") + " --out " + path("o.csv"));
  if (r.exit_code == 0) {
    EXPECT_THAT(read("o.csv"), AllOf(Not(HasSubstr("inf")), Not(HasSubstr("nan"))));
  } else {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("row 2"), HasSubstr("non-finite")));
    EXPECT_EQ(read("o.csv"), "previous\n");
  }
}

// --clamp reported a 1e300 target as "interpolated" with an empty prediction.
TEST_F(SilentResults, ClampRefusesATargetTooFarToInterpolate) {
  std::string grid = "x,y,z,v\n";
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) grid += std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + ",1\n";
  write("grid.csv", grid);
  write("t.csv", "x,y,z\n0.5,0.5,0.5\n1e300,0.5,0.5\n");
  const auto r = run("interpolate --method idw-grid --clamp --samples " + path("grid.csv") + " --targets " +
                     path("t.csv") + " --coords x,y,z --value v --out " + path("p.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("t.csv:3"), HasSubstr("too far outside the grid")));
  EXPECT_FALSE(exists("p.csv"));
  write("near.csv", "x,y,z\n0.5,0.5,0.5\n3,0.5,0.5\n");
  const auto ok = run("interpolate --method idw-grid --clamp --samples " + path("grid.csv") + " --targets " +
                      path("near.csv") + " --coords x,y,z --value v --out " + path("p.csv"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// ---- standard output is output -----------------------------------------------------------------

// `errfield variogram ... > /dev/full` exited 0 (also fit-variogram, cv).
TEST_F(SilentResults, AFullStandardOutputIsAFailedJob) {
  write("s.csv", "x,y,z,v\n0,0,0,1\n1,0,0,2\n0,1,0,3\n0,0,1,4\n1,1,0,5\n1,0,1,6\n");
  write("v.csv", "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,1,0.5,0.1,30\n1,2,1.5,0.2,40\n2,3,2.5,0.3,50\n3,4,3.5,0.32,50\n");
  const std::vector<std::vector<std::string>> commands{
      {"variogram", "--input", path("s.csv"), "--coords", "x,y,z", "--value", "v", "--bins", "0:2:0.5"},
      {"fit-variogram", "--input", path("v.csv"), "--model", "sph"},
      {"cv", "--method", "idw", "--samples", path("s.csv"), "--coords", "x,y,z", "--value", "v"},
  };
  for (const auto& args : commands) {
    const auto r = testing::run_errfield_to_full_stdout(args, dir());
    ASSERT_EQ(r.signal, 0) << testing::command_line(args);
    EXPECT_EQ(r.exit_code, 1) << testing::command_line(args);
    EXPECT_THAT(r.err, HasSubstr("cannot write to standard output")) << testing::command_line(args);
  }
}

// ---- models and fits that cannot be vouched for ------------------------------------------------

// compensate with a model whose field is null or missing applied no correction and said ok.
TEST_F(SilentResults, CompensateRefusesAModelWithoutItsField) {
  simulate("g.csv");
  ASSERT_EQ(run("fit --robot " + path("robot.json") + " --data " + path("g.csv") + " --method distance-idw --out " + path("m.json")).exit_code, 0);
  write("t.csv", "q1,q2,q3,q4,q5,q6\n0,-20,30,0,40,0\n");
  auto model = nlohmann::json::parse(read("m.json"));
  model["field"] = nullptr;
  write("null.json", model.dump());
  model.erase("field");
  write("missing.json", model.dump());
  for (const std::string m : {"null", "missing"}) {
    const auto r = run("compensate --model " + path(m + ".json") + " --targets " + path("t.csv") + " --out " + path("o.csv"));
    EXPECT_EQ(r.exit_code, 2) << m << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr(m + ".json"), HasSubstr("\"field\" is " + m), HasSubstr("distance-idw")));
    EXPECT_FALSE(exists("o.csv")) << m;
  }
}

// fit-variogram --method ml|reml on samples all at one location reported "converged" with a
// likelihood of inf (null in the JSON).
TEST_F(SilentResults, LikelihoodFitAtOneLocationIsRefused) {
  write("one.csv", "x,y,z,v\n1,2,3,0.1\n1,2,3,0.3\n1,2,3,0.2\n1,2,3,0.5\n1,2,3,0.4\n");
  for (const std::string method : {"ml", "reml"}) {
    const auto r = run("fit-variogram --method " + method + " --input " + path("one.csv") +
                       " --coords x,y,z --value v --model exp --out " + path("m.json"));
    EXPECT_EQ(r.exit_code, 2) << method << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("one.csv"), HasSubstr("one location")));
    EXPECT_THAT(r.out, Not(HasSubstr("converged")));
    EXPECT_FALSE(exists("m.json"));
  }
}

// k-fold cv in which every fold fails exited 0 ("predicted 0 of 12"); leave-one-out exited 1.
TEST_F(SilentResults, CvWithNoPredictionAtAllFailsForKFoldAsForLeaveOneOut) {
  std::string s = "x,y,z,v\n";
  for (int i = 0; i < 12; ++i) s += std::to_string(i * 10) + ",0,0," + std::to_string(i) + "\n";
  write("s.csv", s);
  for (const std::string folds : {"3", "loo"}) {
    const auto r = run("cv --method idw --radius 1 --folds " + folds + " --samples " + path("s.csv") +
                       " --coords x,y,z --value v --out " + path("cv.csv"));
    EXPECT_EQ(r.exit_code, 1) << folds << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("none of the 12 samples")) << folds;
    EXPECT_FALSE(exists("cv.csv")) << folds;
  }
  const auto ok = run("cv --method idw --radius 15 --folds 3 --samples " + path("s.csv") + " --coords x,y,z --value v");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// ---- never a duplicated column --------------------------------------------------------------------

// fk on the measurement format wrote x,y,z twice; ik and compensate on their own outputs
// duplicated their columns; errfield then refused its own files.
TEST_F(SilentResults, CommandsRunOnTheirOwnOutputsReplaceColumnsNeverDuplicate) {
  simulate("g.csv");
  auto r = run("fk --input " + path("g.csv") + " --out " + path("fk.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("replaced"));
  const auto unique = [&](const std::string& file) {
    const CsvTable t = CsvTable::read(path(file));  // throws on a duplicated column
    return t.header().size();
  };
  std::size_t columns = 0;
  EXPECT_NO_THROW(columns = unique("fk.csv")) << header_of("fk.csv");
  r = run("fk --input " + path("fk.csv") + " --out " + path("fk2.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(header_of("fk2.csv"), header_of("fk.csv"));
  EXPECT_EQ(unique("fk2.csv"), columns);

  write("poses.csv", "x,y,z,rx,ry,rz\n1200,0,900,180,0,180\n1000,200,700,180,10,170\n");
  ASSERT_EQ(run("ik --input " + path("poses.csv") + " --out " + path("ik.csv")).exit_code, 0);
  r = run("ik --input " + path("ik.csv") + " --out " + path("ik2.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NO_THROW(unique("ik2.csv")) << header_of("ik2.csv");
  EXPECT_EQ(header_of("ik2.csv"), header_of("ik.csv"));

  ASSERT_EQ(run("fit --robot " + path("robot.json") + " --data " + path("g.csv") + " --method distance-idw --out " + path("m.json")).exit_code, 0);
  // Two targets outside the cube (refused) and the joints of its centre node (compensated: a job that
  // compensates nothing writes no file to run on).
  const CsvTable g = CsvTable::read(path("g.csv"));
  std::string centre;
  for (int k = 1; k <= 6; ++k) centre += (k > 1 ? "," : "") + std::string(g.cell(14, g.column_index("q" + std::to_string(k))));
  write("t.csv", "q1,q2,q3,q4,q5,q6\n0,-20,30,0,40,0\n10,-10,20,0,30,0\n" + centre + "\n");
  r = run("compensate --model " + path("m.json") + " --targets " + path("t.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(CsvTable::read(path("c.csv")).cell(2, CsvTable::read(path("c.csv")).column_index("status")), "ok");
  r = run("compensate --model " + path("m.json") + " --targets " + path("c.csv") + " --out " + path("c2.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NO_THROW(unique("c2.csv")) << header_of("c2.csv");
  EXPECT_EQ(header_of("c2.csv"), header_of("c.csv"));
}

// A model with IDW power 1e6 gave empty predictions labelled ik-unreachable: the weights
// 1/d^p underflowed to 0/0. Relative to the nearest vertex they are (d_min/d)^p in (0, 1]: a
// power that large is nearest-vertex interpolation.
TEST_F(SilentResults, IdwWithAHugePowerIsTheNearestVertexNotAnEmptyPrediction) {
  simulate("g.csv");
  ASSERT_EQ(run("fit --robot " + path("robot.json") + " --data " + path("g.csv") + " --method distance-idw --power 1e6 --out " + path("m.json")).exit_code, 0);
  // Targets inside the cube but at no grid node: joints halfway between neighbouring nodes' joints.
  const CsvTable g = CsvTable::read(path("g.csv"));
  std::string t = "q1,q2,q3,q4,q5,q6\n";
  // Row 0 is the base row; rows 1..27 the 3x3x3 grid (x fastest), row 14 its centre. Midpoints
  // between the centre and three face centres lie well inside the cube, so the targets are inside
  // the region whatever the FK's curvature between grid joints.
  const std::pair<std::size_t, std::size_t> neighbours[] = {{14, 13}, {14, 15}, {14, 23}};
  for (const auto& [a, b] : neighbours) {
    for (int j = 0; j < 6; ++j) {
      const std::size_t col = g.column_index("q" + std::to_string(j + 1));
      t += (j ? "," : "") + format_number((g.numeric_cell(a, col) + g.numeric_cell(b, col)) / 2);
    }
    t += "\n";
  }
  write("t.csv", t);
  const auto r = run("compensate --model " + path("m.json") + " --targets " + path("t.csv") + " --out " + path("c.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable c = CsvTable::read(path("c.csv"));
  for (std::size_t i = 0; i < c.row_count(); ++i) {
    EXPECT_EQ(c.row(i)[c.column_index("status")], "ok") << i;
    EXPECT_TRUE(std::isfinite(c.numeric_cell(i, c.column_index("pred_dl")))) << i;
    EXPECT_TRUE(std::isfinite(c.numeric_cell(i, c.column_index("cq1")))) << i;
  }
}

// ---- issue 20: likelihood fits and fits that say "converged" without an estimate ---------------

// Samples on a 6 x 5 grid (unit spacing) with the value `f(x, y)`, as the CSV fit-variogram reads.
std::string grid_samples(double (*f)(double, double)) {
  std::string s = "x,y,v\n";
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j) s += std::to_string(i) + "," + std::to_string(j) + "," + format_number(f(i, j)) + "\n";
  return s;
}

// ML/REML on values that are all equal reported "converged" with a sill of 8e-34.
TEST_F(SilentResults, LikelihoodFitOfConstantValuesIsRefused) {
  write("c.csv", grid_samples([](double, double) { return 2.5; }));
  for (const std::string method : {"ml", "reml"}) {
    const auto r = run("fit-variogram --method " + method + " --input " + path("c.csv") +
                       " --coords x,y --value v --model exp --out " + path("m.json"));
    EXPECT_EQ(r.exit_code, 2) << method << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr("c.csv"), HasSubstr("values are equal"), HasSubstr("constant")));
    EXPECT_THAT(r.out, Not(HasSubstr("converged")));
    EXPECT_FALSE(exists("m.json"));
  }
  // --model auto fits the same likelihood: the data's own reason, not "no candidate well conditioned".
  write("t.csv", "x,y\n0.5,0.5\n");
  const auto r = run("interpolate --method kriging --model auto --samples " + path("c.csv") + " --targets " +
                     path("t.csv") + " --coords x,y --value v --out " + path("p.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("c.csv"), HasSubstr("no candidate model could be fitted"), HasSubstr("values are equal")));
  EXPECT_FALSE(exists("p.csv"));
}

// Values of ~1e200 (or ~1e-200) said "not positive definite at any starting point".
TEST_F(SilentResults, LikelihoodFitOfExtremeMagnitudesSaysRescale) {
  write("big.csv", grid_samples([](double x, double y) { return 1e200 * (1.0 + std::sin(x) * std::cos(y)); }));
  write("tiny.csv", grid_samples([](double x, double y) { return 1e-200 * (1.0 + std::sin(x) * std::cos(y)); }));
  for (const std::string f : {"big.csv", "tiny.csv"}) {
    const auto r = run("fit-variogram --method reml --input " + path(f) + " --coords x,y --value v --model exp");
    EXPECT_EQ(r.exit_code, 2) << f << ": " << r.err;
    EXPECT_THAT(r.err, AllOf(HasSubstr(f), HasSubstr("rescale the values")));
  }
}

// On the Meuse data (log zinc) REML exp ran the range to its upper bound and said "converged". A
// plane (a pure trend) drives the range to the bound the same way: the variogram grows without
// levelling off over the sampled area.
TEST_F(SilentResults, LikelihoodFitWithTheRangeOnItsBoundSaysSo) {
  write("trend.csv", grid_samples([](double x, double y) { return 0.5 * x + 0.3 * y + 0.01 * std::sin(7 * x + 3 * y); }));
  const auto r = run("fit-variogram --method reml --input " + path("trend.csv") +
                     " --coords x,y --value v --model exp --out " + path("m.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("status not converged"), HasSubstr("upper bound"), HasSubstr("no finite range")));
  EXPECT_THAT(r.err, HasSubstr("upper bound"));
  const auto j = nlohmann::json::parse(read("m.json"));
  EXPECT_EQ(j["fit"]["status"], "not_converged");
  // The reported range is the bound: 1000 x the samples' extent (the diagonal of the 5 x 4 grid).
  const double bound = 1000.0 * std::hypot(5.0, 4.0);
  EXPECT_NEAR(j["fit"]["ranges"][0].get<double>(), bound, 1e-6 * bound);
}

// fit-variogram on a directional variogram pooled all directions into one isotropic fit, exit 0.
TEST_F(SilentResults, FitVariogramRefusesSeveralDirectionsPooled) {
  const std::string header = "lag_lo,lag_hi,lag_mean,gamma,pairs,direction\n";
  const std::string rows0 = "0,1,0.5,0.1,30,0\n1,2,1.5,0.2,40,0\n2,3,2.5,0.3,50,0\n3,4,3.5,0.32,50,0\n";
  const std::string rows90 = "0,1,0.5,0.2,30,90\n1,2,1.5,0.4,40,90\n2,3,2.5,0.5,50,90\n3,4,3.5,0.52,50,90\n";
  write("dir.csv", header + rows0 + rows90);
  const auto r = run("fit-variogram --input " + path("dir.csv") + " --model sph --out " + path("m.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("dir.csv"), HasSubstr("column 'direction'"), HasSubstr("2 directions (0, 90)"),
                           HasSubstr("one direction at a time"), HasSubstr("--anisotropy rotated")));
  EXPECT_FALSE(exists("m.json"));
  // One direction's rows alone are one variogram: fitted.
  write("one.csv", header + rows90);
  const auto ok = run("fit-variogram --input " + path("one.csv") + " --model sph --out " + path("m.json"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

}  // namespace
}  // namespace errfield
