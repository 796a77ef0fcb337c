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

namespace errfield::report {
namespace {

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

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  ::pclose(p);
  return out;
}

// The report renders in a real browser: headless Chromium lays it out (--dump-dom shows the SVG
// elements in the live DOM) and its screenshot contains the plot colours in quantity, which only
// happens if the SVG curves and bars were drawn.
TEST(HtmlReport, RendersInHeadlessChromium) {
  const char* chromium = "/usr/bin/chromium";
  if (!fs::exists(chromium)) GTEST_SKIP() << "chromium not installed (scripts/setup.sh installs it); render check skipped";
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "/usr/bin/python3 missing; render check skipped";
  const fs::path dir = fs::temp_directory_path() / ("errfield_report_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path html = dir / "report.html";
  sample_report().write(html);
  const std::string flags = std::string(chromium) +
                            " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                            " --disable-background-networking --disable-component-update --disable-sync"
                            " --user-data-dir=" + (dir / "profile").string();
  const std::string dom = run("timeout 90 " + flags + " --dump-dom file://" + html.string() + " 2>/dev/null");
  ASSERT_FALSE(dom.empty()) << "chromium --dump-dom printed nothing";
  EXPECT_EQ(count(dom, "<svg "), 2u);
  EXPECT_GE(count(dom, "<polyline"), 2u);
  EXPECT_GE(count(dom, "<rect"), 30u);  // 30 bars at least

  const fs::path png = dir / "shot.png";
  run("timeout 90 " + flags + " --screenshot=" + png.string() + " --window-size=1100,1400 file://" + html.string() +
      " >/dev/null 2>&1");
  ASSERT_TRUE(fs::exists(png)) << "no screenshot written";
  const std::string census = run("/usr/bin/python3 " ERRFIELD_SOURCE_DIR "/tests/peers/png_color_census.py " +
                                 png.string() + " '#1f77b4' '#d62728' '#ff7f0e' '#2ca02c' '#fff3cd'");
  std::istringstream in(census);
  int w = 0, h = 0, distinct = 0;
  in >> w >> h >> distinct;
  ASSERT_EQ(w, 1100) << census;
  std::map<std::string, long> pixels;
  std::string color;
  long n = 0;
  while (in >> color >> n) pixels[color] = n;
  EXPECT_GT(distinct, 50) << "the page looks blank";
  EXPECT_GT(pixels["#1f77b4"], 300) << census;  // the blue curve and its markers
  EXPECT_GT(pixels["#d62728"], 300) << census;  // the red curve
  EXPECT_GT(pixels["#ff7f0e"], 2000) << census;  // 15 "before" bars
  EXPECT_GT(pixels["#2ca02c"], 100) << census;  // 15 small "after" bars
  EXPECT_GT(pixels["#fff3cd"], 5000) << census;  // the SIMULATED banner
  fs::remove_all(dir);
}

}  // namespace
}  // namespace errfield::report
