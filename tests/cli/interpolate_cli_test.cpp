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
#include <nlohmann/json.hpp>

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

// `interpolate --grid` and raster outputs / covariates (GDAL). The rasters are read back by GDAL
// itself (Debian's python3-gdal, a dependency of gdal-bin): geotransform, band descriptions,
// nodata and every value, exactly (Python prints shortest round-trip doubles).
class InterpolateGridCli : public testing::CliTest {
 protected:
  void SetUp() override {
    if (!ERRFIELD_HAVE_GDAL) GTEST_SKIP() << "built without GDAL (libgdal-dev): rasters are refused";
    // Simulated samples in [0, 50] x [0, 40] with a covariate-driven mean.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> e(0.0, 0.1);
    std::ostringstream s;
    s.precision(17);
    s << "x,y,v,c\n";
    for (int i = 0; i < 25; ++i) {
      const double x = 50.0 * u(rng), y = 40.0 * u(rng);
      xs_.push_back(x);
      ys_.push_back(y);
      s << x << ',' << y << ',' << (0.5 * covariate_at(x, y) + std::sin(y / 9.0) + e(rng)) << ',' << covariate_at(x, y) << '\n';
    }
    write("S.csv", s.str());
    // The same nodes as --grid 0:40:10,5:37:10 (x 0..40, y 5, 15, 25, 35: 37 is not a node),
    // here row by row from the smallest y, so that the raster's order is checked too.
    std::ostringstream t;
    t.precision(17);
    t << "id,x,y,c\n";
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 5; ++i) t << j * 5 + i << ',' << 10 * i << ',' << 5 + 10 * j << ',' << covariate_at(10 * i, 5 + 10 * j) << '\n';
    write("T.csv", t.str());
  }
  // The covariate raster of the tests: 12 x 10 pixels of 5 x 5 from (-5, -5), written as an ESRI
  // ASCII grid; covariate_at computes the value of the pixel containing (x, y) independently.
  static constexpr double kX0 = -5.0, kYTop = 45.0, kCell = 5.0;
  static double pixel_value(int col, int row) { return std::sqrt(std::abs(col * kCell - 20.0) / 10.0) + 0.1 * row; }
  static double covariate_at(double x, double y) {
    return pixel_value(static_cast<int>(std::floor((x - kX0) / kCell)), static_cast<int>(std::floor((kYTop - y) / kCell)));
  }
  void write_covariate_raster(const std::string& name) const {
    std::ostringstream a;
    a.precision(17);
    a << "ncols 12\nnrows 10\nxllcorner " << kX0 << "\nyllcorner " << kYTop - 10 * kCell << "\ncellsize " << kCell << "\n";
    for (int row = 0; row < 10; ++row) {
      for (int col = 0; col < 12; ++col) a << (col ? " " : "") << pixel_value(col, row);
      a << '\n';
    }
    write(name, a.str());
  }
  // Every band of each raster file, read by GDAL (as raw Float64, row by row from the top; numpy,
  // whose import doubled the reader's start, is not needed): {file: {"geo": [...], "bands": [{"name", "nodata", "values"}]}}.
  nlohmann::json read_rasters(const std::vector<std::string>& files) const {
    std::string list;
    for (const auto& f : files) list += (list.empty() ? "'" : ", '") + path(f) + "'";
    write("dump.py",
          "import json, struct\nfrom osgeo import gdal\ngdal.UseExceptions()\n"
          "gdal.SetConfigOption('AAIGRID_DATATYPE', 'Float64')\nout = {}\n"
          "for f in [" + list + "]:\n"
          "    d = gdal.Open(f)\n"
          "    bands = []\n"
          "    for b in range(1, d.RasterCount + 1):\n"
          "        band = d.GetRasterBand(b)\n"
          "        bands.append({'name': band.GetDescription(), 'nodata': band.GetNoDataValue(),\n"
          "                      'values': list(struct.unpack('<%dd' % (d.RasterXSize * d.RasterYSize),\n"
          "                          band.ReadRaster(buf_type=gdal.GDT_Float64)))})\n"
          "    out[f.split('/')[-1]] = {'geo': list(d.GetGeoTransform()), 'bands': bands}\n"
          "print(json.dumps(out))\n");
    FILE* p = ::popen(("/usr/bin/python3 " + path("dump.py") + " 2>&1").c_str(), "r");
    std::string text;
    char buffer[4096];
    for (std::size_t n; p && (n = std::fread(buffer, 1, sizeof buffer, p)) > 0;) text.append(buffer, n);
    const int status = p ? ::pclose(p) : -1;
    EXPECT_EQ(status, 0) << text;
    return nlohmann::json::parse(text, nullptr, false);
  }
  // Row of T.csv of the raster pixel (col, row): row 0 is y = 35.
  static std::size_t target_row(std::size_t col, std::size_t row) { return (3 - row) * 5 + col; }
  std::vector<double> xs_, ys_;
};

TEST_F(InterpolateGridCli, RastersHoldTheSamePredictionsAsTheNodesGivenAsCsv) {
  const std::string model = " --model \"exp(sill=0.5,range=15)+nug(0.01)\"";
  const std::vector<std::string> methods{"kriging" + model, "kriging" + model + " --neighbors 8", "idw --neighbors 6"};
  std::vector<std::string> rasters;
  for (std::size_t m = 0; m < methods.size(); ++m) {
    const std::string base = "interpolate --method " + methods[m] + " --samples " + path("S.csv") + " --coords x,y --value v";
    const std::string k = std::to_string(m);
    auto r = run(base + " --targets " + path("T.csv") + " --out " + path("P" + k + ".csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output();
    // Every back end as a GeoTIFF; the ESRI ASCII grid and the grid's CSV once (the same code after).
    std::vector<std::string> outs{"G" + k + ".tif"};
    if (m == 0) outs.insert(outs.end(), {"G0.asc", "G0.csv"});
    for (const std::string& out : outs) {
      r = run(base + " --grid 0:40:10,5:37:10 --out " + path(out));
      ASSERT_EQ(r.exit_code, 0) << out << r.output();
      EXPECT_THAT(r.out, HasSubstr("the 5 x 4 nodes of --grid"));
    }
    rasters.push_back("G" + k + ".tif");
  }
  rasters.insert(rasters.end(), {"G0.asc", "G0_var.asc"});
  // The CSV of a grid run: the nodes in raster order, row 0 at the largest y.
  const CsvTable g0 = CsvTable::read(path("G0.csv"));
  EXPECT_EQ(g0.header(), (std::vector<std::string>{"x", "y", "pred", "var"}));
  ASSERT_EQ(g0.row_count(), 20u);
  EXPECT_EQ(g0.row(0)[0] + "," + g0.row(0)[1], "0,35");
  EXPECT_EQ(g0.row(19)[0] + "," + g0.row(19)[1], "40,5");

  const nlohmann::json got = read_rasters(rasters);
  ASSERT_TRUE(got.is_object()) << got;
  // Pixel centres at the nodes: origin (xmin - dx/2, ytop + dy/2), pixel size (10, -10).
  const std::vector<double> geo{-5.0, 10.0, 0.0, 40.0, 0.0, -10.0};
  for (std::size_t m = 0; m < methods.size(); ++m) {
    const std::string k = std::to_string(m);
    const CsvTable csv = CsvTable::read(path("P" + k + ".csv"));
    std::vector<std::string> columns{"pred"};
    if (m != 2) columns.push_back("var");
    const Eigen::MatrixXd expected = csv.numeric_columns(columns);
    const auto& tif = got.at("G" + k + ".tif");
    EXPECT_EQ(tif.at("geo").get<std::vector<double>>(), geo);
    ASSERT_EQ(tif.at("bands").size(), columns.size());
    for (std::size_t b = 0; b < columns.size(); ++b) {
      const auto& band = tif.at("bands")[b];
      EXPECT_EQ(band.at("name"), columns[b]);
      EXPECT_EQ(band.at("nodata"), -9999.0);
      const auto tif_values = band.at("values").get<std::vector<double>>();
      ASSERT_EQ(tif_values.size(), 20u);
      std::vector<double> asc_values;
      if (m == 0) {
        const auto& asc = got.at(b == 0 ? "G0.asc" : "G0_var.asc");
        EXPECT_EQ(asc.at("geo").get<std::vector<double>>(), geo);
        EXPECT_EQ(asc.at("bands")[0].at("nodata"), -9999.0);
        asc_values = asc.at("bands")[0].at("values").get<std::vector<double>>();
        ASSERT_EQ(asc_values.size(), 20u);
      }
      for (std::size_t row = 0; row < 4; ++row)
        for (std::size_t col = 0; col < 5; ++col) {
          // The same arithmetic per target in another order: equal up to the last bits.
          const double want = expected(static_cast<Eigen::Index>(target_row(col, row)), static_cast<Eigen::Index>(b));
          EXPECT_DOUBLE_EQ(tif_values[row * 5 + col], want) << methods[m] << " " << columns[b] << " pixel " << col << "," << row;
          if (m == 0) EXPECT_DOUBLE_EQ(asc_values[row * 5 + col], want) << columns[b] << " pixel " << col << "," << row;
        }
    }
  }
}

TEST_F(InterpolateGridCli, NodesWithoutPredictionAreNodataAndBadGridsAreRefused) {
  // IDW within radius 6: a node with no sample that close gets no prediction.
  const std::string base = "interpolate --method idw --radius 6 --samples " + path("S.csv") + " --coords x,y --value v";
  auto r = run(base + " --grid 0:40:10,5:37:10 --nodata -1e30 --out " + path("G.tif"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const nlohmann::json got = read_rasters({"G.tif"});
  ASSERT_TRUE(got.is_object()) << got;
  const auto& band = got.at("G.tif").at("bands")[0];
  EXPECT_EQ(band.at("nodata"), -1e30);
  const auto values = band.at("values").get<std::vector<double>>();
  ASSERT_EQ(values.size(), 20u);
  std::size_t empty = 0;
  for (std::size_t row = 0; row < 4; ++row)
    for (std::size_t col = 0; col < 5; ++col) {
      const double x = 10.0 * static_cast<double>(col), y = 35.0 - 10.0 * static_cast<double>(row);
      bool near = false;
      for (std::size_t i = 0; i < xs_.size(); ++i) near = near || std::hypot(xs_[i] - x, ys_[i] - y) <= 6.0;
      empty += near ? 0 : 1;
      if (near) EXPECT_NE(values[row * 5 + col], -1e30) << x << "," << y;
      else EXPECT_EQ(values[row * 5 + col], -1e30) << x << "," << y;
    }
  EXPECT_GT(empty, 0u);  // the case this test is about
  EXPECT_LT(empty, 20u);
  EXPECT_THAT(r.out, HasSubstr(std::to_string(empty) + " without prediction (nodata -1e+30)"));

  const std::string kriging = "interpolate --method kriging --model \"exp(sill=0.5,range=15)\" --samples " + path("S.csv") +
                              " --coords x,y --value v";
  // XMAX is a node when it is a whole number of steps away, despite rounding: 0.3 / 0.1 = 2.9999999999999996.
  r = run(kriging + " --grid 0:1:0.1,0:0.3:0.1 --out " + path("N.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.out, HasSubstr("the 11 x 4 nodes of --grid"));
  const CsvTable nodes = CsvTable::read(path("N.csv"));
  ASSERT_EQ(nodes.row_count(), 44u);
  EXPECT_EQ(nodes.row(10)[0], "1");  // x = 0 + 10 * 0.1, computed per node, not summed
  EXPECT_EQ(nodes.numeric_column("y")[0], 3 * 0.1);

  r = run(kriging + " --targets " + path("T.csv") + " --grid 0:40:10,5:37:10 --out " + path("P.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--targets and --grid both give the targets"));
  r = run(kriging + " --grid 0:40:10,5:37:10 --max-grid-nodes 19 --out " + path("P.csv"));
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr("5 x 4 = 20 nodes, more than --max-grid-nodes 19"));
  r = run(kriging + " --targets " + path("T.csv") + " --out " + path("P.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("a raster needs targets on a grid"));
  r = run(kriging + " --grid 0:40:10,5:37:5 --out " + path("P.asc"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("an ESRI ASCII grid has square cells"));
  r = run(kriging + " --grid 0:40:0,5:37:10 --out " + path("P.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--grid: dx is 0; expected > 0"));
  EXPECT_FALSE(fs::exists(path("P.csv")) || fs::exists(path("P.tif")) || fs::exists(path("P.asc")));
}

// Issue 47 item 11: a grid over --max-grid-nodes is exit 3 naming it whatever its size. 1e300
// nodes was exit 2 (a per-axis cap) while 1e18 was exit 3; 2^32 x 2^32 nodes wrapped round to 0
// in size_t; an XMAX - XMIN that overflows to inf is one more. And `--indicator ''` ran plain
// kriging instead of refusing its empty thresholds.
TEST_F(InterpolateGridCli, EveryGridOverTheBudgetIsExitThreeAndAnEmptyIndicatorIsRefused) {
  const std::string kriging = "interpolate --method kriging --model \"exp(sill=0.5,range=15)\" --samples " + path("S.csv") +
                              " --coords x,y --value v --out " + path("P.csv");
  for (const std::string grid : {"0:1e9:1,0:1e9:1", "0:1e150:1,0:1e150:1", "0:4294967295:1,0:4294967295:1",
                                 "-1e308:1e308:1,0:1:1", "0:1e300:1e-300,0:1:1"}) {
    const auto r = run(kriging + " --grid " + grid);
    EXPECT_EQ(r.exit_code, 3) << grid << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr("more than --max-grid-nodes 4000000")) << grid;
  }
  EXPECT_FALSE(fs::exists(path("P.csv")));

  for (const std::string thresholds : {"", " "}) {
    const auto r = run(kriging + " --grid 0:10:1,0:10:1 --indicator '" + thresholds + "'");
    EXPECT_EQ(r.exit_code, 2) << r.output();
    EXPECT_THAT(r.err, HasSubstr("--indicator is '" + thresholds + "': no thresholds"));
  }
  EXPECT_FALSE(fs::exists(path("P.csv")));
}

TEST_F(InterpolateGridCli, RasterCovariateEqualsTheSameCovariateAsCsvColumns) {
  write_covariate_raster("cov.asc");
  const std::string kriging = "interpolate --method kriging --model \"exp(sill=0.3,range=15)+nug(0.01)\" --coords x,y "
                              "--value v --covariates ";
  auto r = run(kriging + "c --samples " + path("S.csv") + " --targets " + path("T.csv") + " --out " + path("csv.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.err, HasSubstr("external drift (1 covariate(s))"));
  r = run(kriging + "c=" + path("cov.asc") + " --samples " + path("S.csv") + " --targets " + path("T.csv") + " --out " + path("asc.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  // The grid's nodes take the covariate from the raster too (a GeoTIFF made by gdal_translate).
  ASSERT_EQ(std::system(("gdal_translate -q --config AAIGRID_DATATYPE Float64 " + path("cov.asc") + " " + path("cov.tif")).c_str()), 0);
  r = run(kriging + "c=" + path("cov.tif") + " --samples " + path("S.csv") + " --grid 0:40:10,5:37:10 --out " + path("grid.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const Eigen::MatrixXd want = CsvTable::read(path("csv.csv")).numeric_columns({"pred", "var"});
  const Eigen::MatrixXd from_asc = CsvTable::read(path("asc.csv")).numeric_columns({"pred", "var"});
  const Eigen::MatrixXd from_tif = CsvTable::read(path("grid.csv")).numeric_columns({"pred", "var"});
  ASSERT_EQ(from_tif.rows(), 20);
  for (Eigen::Index i = 0; i < want.rows(); ++i)
    for (Eigen::Index c = 0; c < 2; ++c) {
      EXPECT_EQ(from_asc(i, c), want(i, c)) << i;  // the same numbers in the same order
      const auto t = static_cast<std::size_t>(i);
      const std::size_t raster_index = (3 - t / 5) * 5 + t % 5;  // T.csv goes up from y = 5, the raster down
      EXPECT_DOUBLE_EQ(from_tif(static_cast<Eigen::Index>(raster_index), c), want(i, c)) << i;
    }
  // A sample outside the raster is named, nothing is written.
  write("S2.csv", read("S.csv") + "60,20,1,0\n");
  r = run(kriging + "c=" + path("cov.tif") + " --samples " + path("S2.csv") + " --grid 0:40:10,5:37:10 --out " + path("bad.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("S2.csv:27: the point (60, 20) is outside the raster"));
  EXPECT_FALSE(fs::exists(path("bad.csv")));
}

// The residual variogram and the likelihood fit take the same raster covariate (issue 36 item 6):
// byte for byte what the covariate as a CSV column gives (its values are the pixels', computed
// independently by covariate_at), and a sample outside the raster is named.
TEST_F(InterpolateGridCli, VariogramAndFitVariogramTakeARasterCovariateAsTheColumn) {
  write_covariate_raster("cov.asc");
  const std::string variogram = "variogram --input " + path("S.csv") + " --coords x,y --value v --bins 0:30:10 --covariates ";
  auto r = run(variogram + "c --out " + path("vcsv.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  r = run(variogram + "c=" + path("cov.asc") + " --out " + path("vasc.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_EQ(read("vasc.csv"), read("vcsv.csv"));
  const std::string fit = "fit-variogram --method reml --input " + path("S.csv") +
                          " --coords x,y --value v --model exp --covariates ";
  r = run(fit + "c --out " + path("fcsv.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  r = run(fit + "c=" + path("cov.asc") + " --out " + path("fasc.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const auto model_of = [&](const std::string& f) {
    nlohmann::json j = nlohmann::json::parse(read(f));
    j["fit"].erase("covariates");  // the text given: "c" and "c=<path>"
    return j.dump();
  };
  EXPECT_EQ(model_of("fasc.json"), model_of("fcsv.json"));
  write("S2.csv", read("S.csv") + "60,20,1,0\n");
  r = run("variogram --input " + path("S2.csv") + " --coords x,y --value v --bins 0:30:10 --covariates c=" + path("cov.asc") +
          " --out " + path("vbad.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("S2.csv:27: the point (60, 20) is outside the raster"));
  EXPECT_FALSE(fs::exists(path("vbad.csv")));
}

}  // namespace
}  // namespace errfield
