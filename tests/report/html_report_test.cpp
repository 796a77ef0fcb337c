#include "errfield/report/html_report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unistd.h>

#include "errfield/error.hpp"
#include "support/chromium_render.hpp"

namespace errfield::report {
namespace html_report_test {

namespace fs = std::filesystem;

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

HtmlReport sample_report() {
  HtmlReport r("errfield test report", true);
  r.add_heading("A table");
  TextTable t({{"method", "", Align::Left}, {"max", "mm"}});
  t.add_row({"none", "1.346"});
  t.add_row({"a < b & c", "0.104"});
  r.add_table(t, "Table 6 <demo>");
  r.add_heading("Plots");
  LinePlot p;
  p.title = "Two curves";
  p.x_axis = {"lag", "mm"};
  p.y_axis = {"gamma", "mm²"};
  std::vector<double> x, y1, y2;
  for (int i = 0; i <= 40; ++i) {
    x.push_back(i * 50.0);
    y1.push_back(1.0 - std::exp(-i / 10.0));
    y2.push_back(0.9 * (1.0 - std::exp(-i / 14.0)));
  }
  p.series.push_back({"blue curve", x, y1, SeriesStyle::LinePoints, "#1f77b4"});
  p.series.push_back({"red curve", x, y2, SeriesStyle::Line, "#d62728"});
  r.add_figure(p, "two curves");
  BarChart c;
  c.title = "Bars";
  c.category_label = "hole";
  for (int i = 1; i <= 15; ++i) c.categories.push_back(std::to_string(i));
  c.y_axis = {"deviation", "mm"};
  c.series.push_back({"before", std::vector<double>(15, 1.1), "#ff7f0e"});
  c.series.push_back({"after", std::vector<double>(15, 0.05), "#2ca02c"});
  r.add_figure(c, "bars");
  return r;
}

TEST(HtmlReport, SelfContainedWithBannerAndEscapedText) {
  const HtmlReport r = sample_report();
  const std::string html = r.to_html();
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("id=\"simulated-banner\""), std::string::npos);
  EXPECT_EQ(count(html, "<svg "), 2u);
  EXPECT_EQ(count(html, ">SIMULATED</text>"), 2u);  // every figure stamped
  EXPECT_NE(html.find("a &lt; b &amp; c"), std::string::npos);
  EXPECT_NE(html.find("Table 6 &lt;demo&gt;"), std::string::npos);
  // nothing fetched from anywhere: no script, no link, no external reference
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("http://www.w3.org/2000/svg") != std::string::npos, true);
  EXPECT_EQ(count(html, "http"), count(html, "http://www.w3.org/2000/svg"));
  EXPECT_EQ(r.figure_count(), 2u);
  EXPECT_THROW(HtmlReport("x", false).add_heading("h", 1), ArgumentError);
}

// The report renders in a real browser: headless Chromium lays it out (--dump-dom shows the SVG
// elements in the live DOM) and its screenshot contains the plot colours in quantity, which only
// happens if the SVG curves and bars were drawn.
TEST(HtmlReport, RendersInHeadlessChromium) {
  if (const std::string why = test::chromium_unavailable_reason(); !why.empty()) GTEST_SKIP() << why << "; render check skipped";
  const fs::path dir = fs::temp_directory_path() / ("errfield_report_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path html = dir / "report.html";
  sample_report().write(html);
  const auto r = test::render_in_chromium(html, {"#1f77b4", "#d62728", "#ff7f0e", "#2ca02c", "#fff3cd"});
  ASSERT_FALSE(r.dom.empty()) << "chromium --dump-dom printed nothing";
  EXPECT_EQ(count(r.dom, "<svg "), 2u);
  EXPECT_GE(count(r.dom, "<polyline"), 2u);
  EXPECT_GE(count(r.dom, "<rect"), 30u);  // 30 bars at least
  ASSERT_EQ(r.width, 1100) << "no screenshot decoded";
  EXPECT_GT(r.distinct_colors, 50) << "the page looks blank";
  EXPECT_GT(r.pixels.at("#1f77b4"), 300);   // the blue curve and its markers
  EXPECT_GT(r.pixels.at("#d62728"), 300);   // the red curve
  EXPECT_GT(r.pixels.at("#ff7f0e"), 2000);  // 15 "before" bars
  EXPECT_GT(r.pixels.at("#2ca02c"), 100);   // 15 small "after" bars
  EXPECT_GT(r.pixels.at("#fff3cd"), 5000);  // the SIMULATED banner
  fs::remove_all(dir);
}

}  // namespace
}  // namespace errfield::report
