// End-to-end tests of `errfield interpolate` (the built CLI, via ERRFIELD_CLI_PATH).


#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace interpolate_cli_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class InterpolateCli : public testing::CliTest {

 protected:

  // The paper's 5 x 5 x 5 grid with a linear field f = 0.001 x - 0.0005 y + 0.0002 z + 0.01 (mm),
  // rows shuffled; `skip` drops one node, `extra` appends rows verbatim.
  static double field(double x, double y, double z) { return 0.001 * x - 0.0005 * y + 0.0002 * z + 0.01; }
  void write_grid(const std::string& name, int skip = -1, const std::string& extra = "") const {
    std::vector<std::array<int, 3>> nodes;
    for (int k = 0; k < 5; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) nodes.push_back({i * 125, j * 125, k * 125});
    std::shuffle(nodes.begin(), nodes.end(), std::mt19937(3));
    std::ostringstream s;
    s << "x [mm],y [mm],z [mm],dL [mm],dx,dy,dz\n";
    for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
      if (n == skip) continue;
      const auto& p = nodes[static_cast<std::size_t>(n)];
      s << p[0] << "," << p[1] << "," << p[2] << "," << format_number(field(p[0], p[1], p[2])) << ","
        << format_number(0.5 * field(p[0], p[1], p[2])) << "," << format_number(-field(p[0], p[1], p[2])) << ",0.25\n";
    }
    s << extra;
    write(name, s.str());
  }
};

TEST_F(InterpolateCli, GridMethodIsExactAtNodesAndCellCentresOfALinearField) {
  write_grid("grid.csv");
  // Cell centres: all 8 vertices are equidistant, so IDW gives their mean = the linear field there.
  write("targets.csv",
        "id,x,y,z\n"
        "a,62.5,62.5,62.5\n"
        "b,312.5,187.5,437.5\n"
        "c,250,375,0\n"
        "d,500,500,500\n");
  const auto r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " +
                         path("targets.csv") + " --coords x,y,z --value dL --out " + path("pred.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto out = CsvTable::read(path("pred.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"id", "x", "y", "z", "pred"}));
  EXPECT_EQ(out.row(1)[0], "b");
  const auto pred = out.numeric_column("pred");
  const double expected[4] = {field(62.5, 62.5, 62.5), field(312.5, 187.5, 437.5), field(250, 375, 0),
                              field(500, 500, 500)};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(pred[static_cast<std::size_t>(i)], expected[i], 1e-15) << i;
}

TEST_F(InterpolateCli, VectorValuesGetOnePredictionColumnEach) {
  write_grid("grid.csv");
  write("targets.csv", "x,y,z\n62.5,62.5,62.5\n");
  const auto r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " +
                         path("targets.csv") + " --coords x,y,z --value dx,dy,dz --power 2 --out " + path("pred.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto out = CsvTable::read(path("pred.csv"));
  EXPECT_EQ(out.header(), (std::vector<std::string>{"x", "y", "z", "pred_dx", "pred_dy", "pred_dz"}));
  const double f = field(62.5, 62.5, 62.5);
  EXPECT_NEAR(out.numeric_column("pred_dx")[0], 0.5 * f, 1e-15);
  EXPECT_NEAR(out.numeric_column("pred_dy")[0], -f, 1e-15);
  EXPECT_NEAR(out.numeric_column("pred_dz")[0], 0.25, 1e-15);
}

TEST_F(InterpolateCli, MissingNodeIsNamedAndNoOutputIsWritten) {
  write_grid("grid.csv", 40);
  write("targets.csv", "x,y,z\n1,1,1\n");
  write("pred.csv", "old content\n");
  const auto r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " +
                         path("targets.csv") + " --coords x,y,z --value dL --out " + path("pred.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("grid.csv: incomplete grid"));
  EXPECT_THAT(r.output(), HasSubstr("has no sample"));
  EXPECT_THAT(r.output(), HasSubstr("124 samples"));
  std::ifstream in(path("pred.csv"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "old content");  // the previous file is untouched
}

TEST_F(InterpolateCli, DuplicateNodeNamesBothLines) {
  write_grid("grid.csv", -1, "250,250,250,0,0,0,0\n");
  write("targets.csv", "x,y,z\n1,1,1\n");
  const auto r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " +
                         path("targets.csv") + " --coords x,y,z --value dL --out " + path("pred.csv"));
  EXPECT_EQ(r.exit_code, 2);
  // header is line 1, 125 nodes, then the copy on line 127
  EXPECT_THAT(r.output(), HasSubstr("grid.csv:127: duplicate grid node (2, 2, 2) at (250, 250, 250)"));  // header is line 1, 125 nodes, then the copy
  EXPECT_FALSE(fs::exists(path("pred.csv")));
}

TEST_F(InterpolateCli, OutsideTargetFailsUnlessClamped) {
  write_grid("grid.csv");
  write("targets.csv", "x,y,z\n10,10,10\n-20,250,250\n");
  const std::string base = "interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " +
                           path("targets.csv") + " --coords x,y,z --value dL --out " + path("pred.csv");
  const auto strict = run(base);
  EXPECT_EQ(strict.exit_code, 2);
  EXPECT_THAT(strict.output(), HasSubstr("targets.csv:3: target (-20, 250, 250) is outside the grid [0, 500] x [0, 500] x [0, 500]"));
  EXPECT_FALSE(fs::exists(path("pred.csv")));
  const auto clamped = run(base + " --clamp");
  ASSERT_EQ(clamped.exit_code, 0) << clamped.output();
  EXPECT_THAT(clamped.output(), HasSubstr("1 of 2 targets are outside the grid"));
  // The target (-20, 250, 250) is clamped to cell (0, 2, 2) (a target on a face belongs to the cell
  // above it); IDW (p = 1) over that cell's vertices with the target's true distances:
  const double p[3] = {-20, 250, 250};
  double wsum = 0, acc = 0;
  for (int i : {0, 125})
    for (int j : {250, 375})
      for (int k : {250, 375}) {
        const double d = std::sqrt((p[0] - i) * (p[0] - i) + (p[1] - j) * (p[1] - j) + (p[2] - k) * (p[2] - k));
        wsum += 1 / d;
        acc += field(i, j, k) / d;
      }
  EXPECT_NEAR(CsvTable::read(path("pred.csv")).numeric_column("pred")[1], acc / wsum, 1e-15);
}

TEST_F(InterpolateCli, BadInputNamesFileLineAndColumn) {
  write_grid("grid.csv", -1, "");
  write("targets.csv", "x,y,z\n1,1,1\n2,abc,2\n");
  const std::string tail = " --coords x,y,z --value dL --out " + path("pred.csv");
  auto r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " + path("targets.csv") + tail);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("targets.csv:3: column 'y': 'abc' is not a number"));

  r = run("interpolate --method idw-grid --samples " + path("nope.csv") + " --targets " + path("targets.csv") + tail);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("nope.csv"));

  write("t2.csv", "x,y\n1,1\n");
  r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " + path("t2.csv") + tail);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("no column 'z'"));

  write("good.csv", "x,y,z\n1,1,1\n");
  r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " + path("good.csv") +
              " --coords x,y --value dL --out " + path("pred.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("needs exactly 3 coordinate columns"));

  r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " + path("targets.csv") + tail +
              " --neighbors 4");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--neighbors does not apply to --method idw-grid"));

  r = run("interpolate --method magic --samples " + path("grid.csv") + " --targets " + path("targets.csv") + tail);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("unknown method 'magic'"));

  write("t3.csv", "x,y,z,pred\n1,1,1,0\n");
  r = run("interpolate --method idw-grid --samples " + path("grid.csv") + " --targets " + path("t3.csv") + tail);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("already has a column 'pred'"));
  EXPECT_FALSE(fs::exists(path("pred.csv")));
}

TEST_F(InterpolateCli, HelpShowsMethodsAndAnExample) {
  const auto r = run("interpolate --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.output(), HasSubstr("idw-grid"));
  EXPECT_THAT(r.output(), HasSubstr("Example"));
}

}  // namespace
}  // namespace errfield
