// The variogram picture's layout (issue 49): a long model caption stays inside the frame, wrapped,
// with short numbers (the full model in its <title>); the pair counts of crowded bins are never
// written over each other, and every bin keeps its count in its point's <title>.

#include <cstdint>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/variogram_svg.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::cli {
namespace variogram_svg_test {

std::vector<double> numbers_after(const std::string& text, const std::string& attribute) {
  std::vector<double> out;
  const std::regex re(attribute + "=\"([-0-9.e]+)\"");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it)
    out.push_back(std::stod((*it)[1].str()));
  return out;
}

TEST(VariogramSvg, ALongModelCaptionIsWrappedInsideTheFrame) {
  VariogramPlot p;
  p.title = "empirical variogram of v";
  p.bins = {{10.0, 0.2, 40}, {20.0, 0.5, 80}, {30.0, 0.7, 90}};
  p.model = VariogramModel(
      VariogramModel::parse("mat(sill=1.6492129677265621,range=489.37893559044306,nu=1.5)+sph(sill=0.2345678901234,"
                            "range=1234.5678901234)+nug(sill=0.08507352268850096)")
          .components(),
      Anisotropy::ard({1.0, 0.26829524346723893}));
  const std::string svg = variogram_svg_text(p);
  const std::size_t at = svg.find("class=\"caption\"");
  ASSERT_NE(at, std::string::npos) << svg;
  const std::string caption = svg.substr(at, svg.find("</text>", at) - at);
  // Every line starts at the frame's left edge and is at most 100 characters (11 px text: ~620 px
  // in a 720 px picture starting at x = 80).
  const std::regex line("<tspan x=\"([0-9.]+)\" dy=\"[0-9.]+\">([^<]*)</tspan>");
  int lines = 0;
  for (auto it = std::sregex_iterator(caption.begin(), caption.end(), line); it != std::sregex_iterator(); ++it) {
    ++lines;
    EXPECT_EQ(std::stod((*it)[1].str()), 80.0);
    EXPECT_LE((*it)[2].str().size(), 100u) << (*it)[2].str();
  }
  EXPECT_GE(lines, 1);
  // Short numbers on the picture, the full model in its title.
  EXPECT_NE(caption.find("range=489.4"), std::string::npos) << caption;
  EXPECT_EQ(caption.find("489.37893559044306</tspan>"), std::string::npos) << caption;
  EXPECT_NE(caption.find("<title>" + p.model->to_string() + "</title>"), std::string::npos) << caption;
  // The plot area starts below the caption's last line.
  const std::vector<double> heights = numbers_after(svg, "height");
  ASSERT_FALSE(heights.empty());
  EXPECT_GT(heights.front(), 480.0);
}

TEST(VariogramSvg, PairCountsOfCrowdedBinsAreNeverWrittenOverEachOther) {
  VariogramPlot p;
  // 60 bins, 1 apart in lag, on nearly the same semivariance: their counts would all overlap.
  for (int k = 1; k <= 60; ++k) p.bins.push_back({static_cast<double>(k), 1.0 + 0.001 * k, static_cast<std::uint64_t>(1000 + k)});
  const std::string svg = variogram_svg_text(p);
  const std::regex label("<text class=\"pairs\" x=\"([0-9.]+)\" y=\"([0-9.]+)\" font-size=\"10\">([0-9]+)</text>");
  struct Box {
    double x0, y0, x1, y1;
  };
  std::vector<Box> boxes;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), label); it != std::sregex_iterator(); ++it) {
    const double x = std::stod((*it)[1].str()), y = std::stod((*it)[2].str());
    boxes.push_back({x, y - 10.0, x + 6.0 * static_cast<double>((*it)[3].str().size()), y + 1.0});
  }
  ASSERT_GE(boxes.size(), 5u);
  EXPECT_LT(boxes.size(), 60u);  // not every count fits
  for (std::size_t a = 0; a < boxes.size(); ++a)
    for (std::size_t b = a + 1; b < boxes.size(); ++b)
      EXPECT_FALSE(boxes[a].x0 < boxes[b].x1 && boxes[b].x0 < boxes[a].x1 && boxes[a].y0 < boxes[b].y1 &&
                   boxes[b].y0 < boxes[a].y1)
          << a << " " << b;
  // Every bin still has its count in its point's title.
  for (int k = 1; k <= 60; ++k) EXPECT_NE(svg.find(", " + std::to_string(1000 + k) + " pairs</title>"), std::string::npos) << k;
}

}  // namespace variogram_svg_test
}  // namespace errfield::cli
