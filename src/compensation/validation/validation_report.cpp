#include <algorithm>
#include <cmath>

#include "errfield/compensation/validation/validation.hpp"
#include "errfield/report/html_report.hpp"

namespace errfield::compensation {

namespace {

using report::BarChart;
using report::BarSeries;
using report::LinePlot;
using report::Series;
using report::SeriesStyle;

std::string num(double v) { return std::isfinite(v) ? report::tick_label(v, 1e-4) : "-"; }

void add_rows(report::TextTable& t, const std::string& what, const std::optional<BeforeAfter>& b) {
  if (!b) return;
  auto row = [&](const std::string& when, const ErrorStats& s) {
    t.add_row({what, when, std::to_string(s.count), num(s.mean_mm), num(s.rms_mm), num(s.p95_mm), num(s.max_mm)});
  };
  if (b->before) row("before", *b->before);
  row("after", b->after);
}

double largest_magnitude(const std::vector<double>& v) {
  double hi = 0.0;
  for (double x : v) hi = std::isfinite(x) ? std::max(hi, std::abs(x)) : hi;
  return hi;
}

/// Histogram of |e| before and after on common bins (counts per bin), the bins chosen from the
/// data (report::histogram_bins).
BarChart histogram(const std::string& title, const std::vector<double>& before, const std::vector<double>& after) {
  std::vector<double> all = before;
  all.insert(all.end(), after.begin(), after.end());
  const report::HistogramBins hb = report::histogram_bins(all);
  const double step = hb.width;
  const std::size_t bins = hb.count;
  BarChart c;
  c.title = title;
  // Each bin is labelled by its lower edge: "0.05–0.1" labels ran into each other at 12 bins.
  c.category_label = "|error| [mm], bins of " + report::tick_label(step, step) + " mm from the value shown";
  c.y_axis = report::AxisSpec("points", "", 0.0);
  for (std::size_t b = 0; b < bins; ++b) c.categories.push_back(report::tick_label(static_cast<double>(b) * step, step));
  auto counts = [&](const std::vector<double>& v) {
    std::vector<double> n(bins, 0.0);
    for (double e : v)
      if (std::isfinite(e)) n[std::min(bins - 1, static_cast<std::size_t>(std::floor(std::abs(e) / step)))] += 1.0;
    return n;
  };
  bool any_before = false;
  for (double v : before) any_before = any_before || std::isfinite(v);
  if (any_before) c.series.push_back(BarSeries{"before", counts(before), ""});
  // The colour "after" has beside "before", also in a chart of its own.
  if (!after.empty())
    c.series.push_back(BarSeries{"after", counts(after), any_before ? "" : std::string(report::palette_color(1))});
  return c;
}

/// One chart on common bins, or, when the errors after are far smaller than before (largest
/// after below a quarter of the largest before), one chart each: on bins that hold the
/// errors before, the errors after are all one bar at 0.
std::vector<BarChart> histograms(const std::string& title, const std::vector<double>& before,
                                 const std::vector<double>& after) {
  const double hb = largest_magnitude(before), ha = largest_magnitude(after);
  if (!(hb > 0.0) || ha >= 0.25 * hb) return {histogram(title, before, after)};
  return {histogram(title + ", before compensation", before, {}), histogram(title + ", after compensation", {}, after)};
}

LinePlot per_point(const std::string& title, const std::vector<double>& before, const std::vector<double>& after) {
  LinePlot p;
  p.title = title;
  p.x_axis = report::AxisSpec("point (row order)", "");
  p.y_axis = report::AxisSpec("|error|", "mm", std::nullopt, std::nullopt, true);
  std::vector<double> x(after.size()), b(before.size()), a(after.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    x[i] = static_cast<double>(i);
    a[i] = std::abs(after[i]);
    b[i] = std::abs(before[i]);
  }
  bool any_before = false;
  for (double v : b) any_before = any_before || std::isfinite(v);
  if (any_before) p.series.push_back(Series{"before", x, b, SeriesStyle::Points, ""});
  p.series.push_back(Series{"after", x, a, SeriesStyle::Points, ""});
  return p;
}

/// Where the errors are: |error| after compensation against joint `j` (0-based) for the scored
/// points, and the refused points (drawn at 0 mm) - large errors and refusals at a joint's extremes
/// show up as a cloud at one end of the axis. Empty when no point has joints.
std::optional<LinePlot> against_joint(const ValidationReport& r, int j) {
  Series scored{"after (scored)", {}, {}, SeriesStyle::Points, ""};
  Series refused{"refused (drawn at 0)", {}, {}, SeriesStyle::Points, "#b00020"};
  for (const ValidatedPoint& p : r.points) {
    const double q = p.q_deg[j];
    if (!std::isfinite(q)) continue;
    if (!p.ok()) {
      refused.x.push_back(q);
      refused.y.push_back(0.0);
      continue;
    }
    const double e = r.position ? p.after_mm.norm() : NAN;
    double d = 0.0;
    for (double v : p.distance_after_mm) d = std::isfinite(v) ? std::max(d, std::abs(v)) : d;
    scored.x.push_back(q);
    scored.y.push_back(std::isfinite(e) ? e : d);
  }
  if (scored.x.empty() && refused.x.empty()) return std::nullopt;
  LinePlot p;
  p.title = "q" + std::to_string(j + 1);
  p.x_axis = report::AxisSpec("q" + std::to_string(j + 1), "deg");
  p.y_axis = report::AxisSpec(r.position ? "3-D error after" : "max |distance error| after", "mm", std::nullopt,
                              std::nullopt, true);
  p.width_px = 460;  // the legend takes 200 px: 380 left a 104 px plot
  p.height_px = 260;
  if (!scored.x.empty()) p.series.push_back(std::move(scored));
  if (!refused.x.empty()) p.series.push_back(std::move(refused));
  return p;
}

}  // namespace

std::string validation_report_html(const ValidationReport& r, const std::string& title, bool simulated) {
  report::HtmlReport html(title, simulated);
  html.add_heading("Summary");
  html.add_paragraph(std::to_string(r.points.size()) + " points, " + std::to_string(r.refused) +
                     " refused (not counted below), " + r.mode + " mode. Figures are of error magnitudes: the 3-D "
                     "position error and |distance error|; before and after over the same points.");
  report::TextTable t({{"error", "", report::Align::Left}, {"", "", report::Align::Left}, {"points"}, {"mean", "mm"},
                       {"rms", "mm"}, {"p95", "mm"}, {"max", "mm"}});
  add_rows(t, "3-D position", r.position);
  add_rows(t, "distance", r.distance);
  html.add_table(t);
  if (!r.before_registration.empty()) html.add_paragraph("Before: tracker readings mapped with " + r.before_registration + ".");
  if (!r.after_registration.empty()) html.add_paragraph("After: tracker readings mapped with " + r.after_registration + ".");
  if (r.uncertainty)
    html.add_paragraph("Predictive uncertainty (field + nugget) on " + std::to_string(r.uncertainty->points) +
                       " points: " + num(100.0 * r.uncertainty->coverage95) +
                       " % within the predicted 95 % radius (95 expected); mean |e|²/σ² " +
                       num(r.uncertainty->mean_nees) + " (3 expected).");
  for (const auto& n : r.notes) html.add_paragraph("Note: " + n);
  std::vector<double> pb, pa, db, da;
  for (const ValidatedPoint& p : r.points) {
    if (!p.ok()) continue;
    if (r.position) {
      pb.push_back(p.before_mm.norm());
      pa.push_back(p.after_mm.norm());
    }
    for (std::size_t k = 0; k < p.distance_after_mm.size(); ++k) {
      db.push_back(k < p.distance_before_mm.size() ? p.distance_before_mm[k] : NAN);
      da.push_back(p.distance_after_mm[k]);
    }
  }
  if (r.position && !pa.empty()) {
    html.add_heading("3-D position error");
    for (const BarChart& h : histograms("Histogram of the 3-D position error", pb, pa)) html.add_figure(h);
    html.add_figure(per_point("3-D position error per point", pb, pa));
  }
  if (r.distance && !da.empty()) {
    html.add_heading("Distance error");
    for (const BarChart& h : histograms("Histogram of |distance error|", db, da)) html.add_figure(h);
    html.add_figure(per_point("|distance error| per point and base point", db, da));
  }
  std::vector<LinePlot> joint_views;
  for (int j = 0; j < 6; ++j)
    if (auto v = against_joint(r, j)) joint_views.push_back(std::move(*v));
  if (!joint_views.empty()) {
    html.add_heading("Where: errors and refusals against each joint");
    html.add_paragraph("Each point's error after compensation against its joint angles; refused points (not "
                       "scored: outside the region, not credible, outside the limits, ...) in red at 0 mm. Large "
                       "errors or refusals gathered at one end of an axis are a part of the workspace the model "
                       "covers badly: measure more there, or keep targets away from it.");
    for (const LinePlot& v : joint_views) html.add_figure(v);
  }
  return html.to_html();
}

}  // namespace errfield::compensation
