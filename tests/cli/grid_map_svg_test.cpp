// The grid map picture (issue 49: `interpolate --grid --plot`, `variogram --map --plot`): cells to
// scale where there is a value and nowhere else, the colour scale's ends at the smallest and
// largest value, points outside the map left out; and at the command line, the map is written with
// --out (both or neither) and refused where there is no grid.

#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/grid_map_svg.hpp"
#include "support/cli_harness.hpp"

namespace errfield::cli {
namespace grid_map_svg_test {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

struct Cell {
  double x, y, w, h;
  std::string fill;
};

std::vector<Cell> cells_of(const std::string& svg) {
  const std::size_t a = svg.find("<g id=\"cells\""), b = svg.find("</g>", a);
  const std::string part = svg.substr(a, b - a);
  const std::regex re("<rect x=\"([0-9.]+)\" y=\"([0-9.]+)\" width=\"([0-9.]+)\" height=\"([0-9.]+)\" fill=\"(#[0-9a-f]{6})\"/>");
  std::vector<Cell> out;
  for (auto it = std::sregex_iterator(part.begin(), part.end(), re); it != std::sregex_iterator(); ++it)
    out.push_back({std::stod((*it)[1].str()), std::stod((*it)[2].str()), std::stod((*it)[3].str()),
                   std::stod((*it)[4].str()), (*it)[5].str()});
  return out;
}

TEST(GridMapSvg, CellsToScaleWhereThereIsAValueAndTheScalesEndsAtTheExtremes) {
  GridMapPlot p;
  p.nx = 3;
  p.ny = 2;
  p.x_min = 10.0;  // centres 10, 12, 14 (dx 2); 5, 7 (dy 2)
  p.dx = 2.0;
  p.y_min = 5.0;
  p.dy = 2.0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  p.values = {0.0, 1.0, nan,    // top row (y = 7)
              2.0, 2.0, 4.0};   // bottom row (y = 5): the equal pair is one rectangle
  p.points = {{{11.0, 6.0}}, {{100.0, 6.0}}};  // the second is outside the map
  p.title = "test";
  const std::string svg = grid_map_svg_text(p);
  const std::vector<Cell> cells = cells_of(svg);
  ASSERT_EQ(cells.size(), 4u) << svg;
  // The map spans 6 x 4 units; one scale for both axes, so a cell is square.
  const double unit = cells[0].w;
  EXPECT_NEAR(cells[0].h, unit, 0.011);
  EXPECT_NEAR(cells[1].x - cells[0].x, unit, 0.011);
  EXPECT_NEAR(cells[2].w, 2.0 * unit, 0.011);  // 2.0, 2.0 merged
  EXPECT_NEAR(cells[2].y - cells[0].y, unit, 0.011);
  // The NaN cell is not drawn: the top row covers two cells only.
  EXPECT_NEAR(cells[0].w + cells[1].w, 2.0 * unit, 0.011);
  // Viridis' ends at the smallest (0) and largest (4) value.
  EXPECT_EQ(cells[0].fill, "#440154");
  EXPECT_EQ(cells[3].fill, "#fde725");
  EXPECT_EQ(grid_map_svg::colour(0.0), "#440154");
  EXPECT_EQ(grid_map_svg::colour(1.0), "#fde725");
  // One point drawn (the other is outside the map).
  const std::size_t a = svg.find("<g id=\"points\""), b = svg.find("</g>", a);
  const std::string points = svg.substr(a, b - a);
  const std::regex circle("<circle");
  EXPECT_EQ(std::distance(std::sregex_iterator(points.begin(), points.end(), circle), std::sregex_iterator()), 1);
}

class GridMapCli : public testing::CliTest {};

TEST_F(GridMapCli, InterpolateAndVariogramMapsAreWrittenWithTheirTablesOrNotAtAll) {
  std::ofstream s(path("s.csv"));
  s << "x,y,v\n";
  for (int i = 0; i < 40; ++i) s << (i % 7) * 13.0 + 0.5 * i << ',' << (i / 7) * 11.0 << ',' << std::sin(0.3 * i) << '\n';
  s.close();
  auto r = run("interpolate --method idw --samples " + path("s.csv") +
               " --coords x,y --value v --grid 0:100:5,0:60:5 --out " + path("g.csv") + " --plot " + path("g.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.output(), HasSubstr("and the map " + path("g.svg")));
  ASSERT_TRUE(fs::exists(path("g.svg")));
  std::ifstream in(path("g.svg"));
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_FALSE(cells_of(svg).empty());
  EXPECT_THAT(svg, HasSubstr("<g id=\"points\""));
  // No grid, no map: refused before anything is written.
  r = run("interpolate --method idw --samples " + path("s.csv") + " --targets " + path("s.csv") +
          " --coords x,y --value v --out " + path("t.csv") + " --plot " + path("t.svg"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--plot"));
  EXPECT_FALSE(fs::exists(path("t.csv")));
  EXPECT_FALSE(fs::exists(path("t.svg")));
  // The variogram map, with its table.
  r = run("variogram --input " + path("s.csv") + " --coords x,y --value v --map 10,10 --cutoff 50 --out " + path("m.csv") +
          " --plot " + path("m.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_TRUE(fs::exists(path("m.csv")));
  std::ifstream min(path("m.svg"));
  const std::string map((std::istreambuf_iterator<char>(min)), std::istreambuf_iterator<char>());
  EXPECT_FALSE(cells_of(map).empty());
  EXPECT_THAT(map, HasSubstr("variogram map of v"));
  // A picture that cannot be written leaves the table unwritten too.
  fs::create_directories(path("dir.svg"));
  r = run("variogram --input " + path("s.csv") + " --coords x,y --value v --map 10,10 --cutoff 50 --out " + path("n.csv") +
          " --plot " + path("dir.svg"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(path("n.csv")));
  // The cloud has no picture.
  r = run("variogram --input " + path("s.csv") + " --coords x,y --value v --cloud --out " + path("c.csv") + " --plot " +
          path("c.svg"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output(), HasSubstr("--plot"));
}

}  // namespace grid_map_svg_test
}  // namespace errfield::cli
