#include "errfield/report/svg_plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <regex>

#include "errfield/error.hpp"

namespace errfield::report {
namespace svg_plot_test {

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

TEST(NiceTicks, CoverTheRangeWithOneTwoFiveSteps) {
  std::mt19937 rng(7);
  // Ranges of any magnitude, offset from 0 by up to 1000 spans (beyond that, tick spacing drowns in
  // the rounding of the offset, which no axis of ours needs).
  std::uniform_real_distribution<double> offset(-1000, 1000);
  std::uniform_real_distribution<double> log_span(-4, 5);
  for (int trial = 0; trial < 2000; ++trial) {
    const double span = std::pow(10.0, log_span(rng));
    const double lo = offset(rng) * span;
    const double hi = lo + span;
    const auto t = nice_ticks(lo, hi, 6);
    ASSERT_GE(t.size(), 3u);
    ASSERT_LE(t.size(), 14u);
    const double step = t[1] - t[0];
    EXPECT_LE(t.front(), lo + 1e-9 * step);
    EXPECT_GE(t.back(), hi - 1e-9 * step);
    EXPECT_GT(t.front() + step, lo);  // no wasted tick below the data
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-12));
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-6 || std::abs(mantissa - 2) < 1e-6 || std::abs(mantissa - 5) < 1e-6)
        << "step " << step;
    for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-9 * step);
    // (the offset limits the relative rounding of t[i] - t[i-1] to ~1e-13)
  }
  EXPECT_EQ(nice_ticks(0, 1.0, 5), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  EXPECT_THROW(nice_ticks(1, 1), ArgumentError);
}

TEST(TickLabel, UsesJustEnoughDecimals) {
  EXPECT_EQ(tick_label(200, 200), "200");
  EXPECT_EQ(tick_label(0.25, 0.05), "0.25");
  EXPECT_EQ(tick_label(0.2, 0.1), "0.2");
  EXPECT_EQ(tick_label(-1e-17, 0.1), "0.0");
  EXPECT_EQ(tick_label(1.5, 0.5), "1.5");
}

TEST(EscapeXml, EscapesMarkup) { EXPECT_EQ(escape_xml("a<b & \"c\">'"), "a&lt;b &amp; &quot;c&quot;&gt;&#39;"); }

LinePlot two_series() {
  LinePlot p;
  p.title = "Variogram <joint space>";
  p.x_axis = {"lag", "deg"};
  p.y_axis = {"gamma", "mm²", std::nullopt, std::nullopt, true};
  p.series.push_back({"empirical", {5, 15, 25, 35}, {0.01, 0.02, 0.05, 0.11}, SeriesStyle::Points, ""});
  p.series.push_back({"fitted", {0, 10, 20, 30, 40}, {0, 0.01, std::nan(""), 0.09, 0.13}, SeriesStyle::Dashed, "#000000"});
  return p;
}

TEST(RenderSvg, LinePlotDrawsEverySeriesAndLegend) {
  const std::string svg = render_svg(two_series());
  EXPECT_EQ(svg.rfind("<svg ", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("Variogram &lt;joint space&gt;"), std::string::npos);  // title escaped
  EXPECT_NE(svg.find("gamma [mm²]"), std::string::npos);
  EXPECT_NE(svg.find("lag [deg]"), std::string::npos);
  // 4 data markers + 2 legend markers? The Points legend entry has one marker, Dashed none.
  EXPECT_EQ(count(svg, "<circle"), 4u + 1u);
  // the NaN splits the fitted curve into two polylines
  EXPECT_EQ(count(svg, "<polyline"), 2u);
  EXPECT_EQ(count(svg, "stroke-dasharray"), 3u);  // two pieces + legend sample
  EXPECT_NE(svg.find(">empirical<"), std::string::npos);
  EXPECT_NE(svg.find(">fitted<"), std::string::npos);
  EXPECT_EQ(svg.find("SIMULATED"), std::string::npos);
  EXPECT_EQ(svg, render_svg(two_series()));  // deterministic
}

TEST(RenderSvg, PointsMapLinearlyIntoTheFrame) {
  LinePlot p;
  p.title = "map";
  p.x_axis = {"x", "", 0.0, 10.0};
  p.y_axis = {"y", "", 0.0, 10.0};
  p.series.push_back({"", {0, 5, 10}, {0, 5, 10}, SeriesStyle::Points, ""});
  const std::string svg = render_svg(p);
  std::regex circle(R"re(<circle cx="([-0-9.]+)" cy="([-0-9.]+)")re");
  std::vector<std::pair<double, double>> px;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), circle); it != std::sregex_iterator(); ++it)
    px.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  ASSERT_EQ(px.size(), 3u);
  // middle point halfway between the ends, y grows upwards
  EXPECT_NEAR(px[1].first, (px[0].first + px[2].first) / 2, 0.01);
  EXPECT_NEAR(px[1].second, (px[0].second + px[2].second) / 2, 0.01);
  EXPECT_GT(px[0].second, px[2].second);
  EXPECT_LT(px[0].first, px[2].first);
}

TEST(RenderSvg, BarChartHasOneBarPerValue) {
  BarChart c;
  c.title = "before/after";
  c.category_label = "hole";
  c.categories = {"1", "2", "3"};
  c.y_axis = {"deviation", "mm"};
  c.series.push_back({"before", {1.2, 1.0, 1.5}, ""});
  c.series.push_back({"after", {0.05, std::nan(""), 0.1}, ""});
  c.simulated = true;
  const std::string svg = render_svg(c);
  // background + frame + 5 finite bars + 2 legend swatches
  EXPECT_EQ(count(svg, "<rect"), 2u + 5u + 2u);
  EXPECT_NE(svg.find("SIMULATED"), std::string::npos);
  c.series[1].values.pop_back();
  EXPECT_THROW(render_svg(c), ArgumentError);
}

TEST(RenderSvg, RejectsMismatchedSeries) {
  LinePlot p = two_series();
  p.series[0].y.pop_back();
  EXPECT_THROW(render_svg(p), ArgumentError);
  p = two_series();
  p.width_px = 50;
  EXPECT_THROW(render_svg(p), ArgumentError);
}

// Issue 35: the validation report's 0.2 mm bins put all 294 "after" errors (0.02-0.1 mm) into one
// bar. The bins follow the data: on such errors most bars hold points, none holds half of them.
TEST(HistogramBins, FollowTheDataNotAFixedWidth) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.06, 0.015);
  std::vector<double> v;
  for (int i = 0; i < 294; ++i) v.push_back(std::abs(g(rng)));
  const HistogramBins b = histogram_bins(v);
  const double hi = *std::max_element(v.begin(), v.end());
  ASSERT_GT(b.width, 0.0);
  EXPECT_GT(static_cast<double>(b.count) * b.width, hi);  // every value has a bin
  std::vector<int> n(b.count, 0);
  for (double e : v) ++n.at(static_cast<std::size_t>(std::floor(e / b.width)));
  EXPECT_LT(*std::max_element(n.begin(), n.end()), 294 / 2);
  EXPECT_GE(std::count_if(n.begin(), n.end(), [](int k) { return k > 0; }), 6);
  // A far outlier: bins over the whole range, but not hundreds of them.
  v.push_back(10.0);
  const HistogramBins tail = histogram_bins(v);
  EXPECT_GT(static_cast<double>(tail.count) * tail.width, 10.0);
  EXPECT_LE(tail.count, 46u);
  EXPECT_EQ(histogram_bins({}).count, 1u);
}

// Issue 35: the validation report's per-joint plots (a 104 px plot beside a legend) had x labels
// "-150", "-100", ... 17 px apart, running into each other. Neighbouring labels now keep apart by
// their half widths at the label font (7 px a character) plus a gap.
TEST(LinePlot, XTickLabelsOfANarrowPlotDoNotOverlap) {
  for (int width : {380, 460}) {
    LinePlot p;
    p.title = "q1";
    p.x_axis = AxisSpec("q1", "deg");
    p.y_axis = AxisSpec("error", "mm");
    p.width_px = width;
    p.height_px = 260;
    p.series.push_back(Series{"after (scored)", {-150.0, 0.0, 150.0}, {0.1, 0.2, 0.3}, SeriesStyle::Points, ""});
    const std::string svg = render_svg(p);
    // x tick labels sit 19 px below the plot area (whose bottom is 52 px above the figure's).
    const std::regex label("<text x=\"([-0-9.]+)\" y=\"" + std::to_string(260 - 52 + 19) +
                           "\" text-anchor=\"middle\">([^<]*)</text>");
    std::vector<std::pair<double, std::string>> labels;
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), label); it != std::sregex_iterator(); ++it)
      labels.emplace_back(std::stod((*it)[1]), (*it)[2]);
    ASSERT_GE(labels.size(), 2u) << svg;
    for (std::size_t i = 1; i < labels.size(); ++i) {
      const double half_widths = 0.5 * 7.0 * static_cast<double>(labels[i - 1].second.size() + labels[i].second.size());
      EXPECT_GE(labels[i].first - labels[i - 1].first, half_widths + 4.0)
          << width << " px: '" << labels[i - 1].second << "' and '" << labels[i].second << "' overlap";
    }
  }
}

}  // namespace
}  // namespace errfield::report
