#include "errfield/report/svg_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "errfield/error.hpp"

namespace errfield::report {

namespace {

constexpr std::array<std::string_view, 10> kPalette = {
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
    "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};

/// Shortest fixed text for SVG coordinates: two decimals, trailing zeros dropped.
std::string num(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  std::string s = buf;
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

std::string axis_title(const AxisSpec& a) {
  return a.unit.empty() ? a.label : a.label + " [" + a.unit + "]";
}

std::uint64_t fnv1a(std::string_view s, std::uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

struct Range {
  double lo;
  double hi;
  std::vector<double> ticks;
};

/// Axis range: explicit limits win, otherwise the data extended to the outer ticks.
Range make_range(const AxisSpec& spec, double data_lo, double data_hi, int tick_target = 6) {
  double lo = spec.min.value_or(data_lo);
  double hi = spec.max.value_or(data_hi);
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0.0, hi = 1.0;
  if (spec.include_zero) {
    if (!spec.min) lo = std::min(lo, 0.0);
    if (!spec.max) hi = std::max(hi, 0.0);
  }
  if (hi <= lo) {
    const double pad = lo == 0.0 ? 1.0 : 0.5 * std::abs(lo);
    if (!spec.min) lo -= pad;
    if (!spec.max || hi <= lo) hi = lo + 2.0 * pad;
  }
  Range r{lo, hi, nice_ticks(lo, hi, tick_target)};
  if (!spec.min) r.lo = std::min(r.lo, r.ticks.front());
  if (!spec.max) r.hi = std::max(r.hi, r.ticks.back());
  std::erase_if(r.ticks, [&](double t) {
    const double eps = 1e-9 * (r.hi - r.lo);
    return t < r.lo - eps || t > r.hi + eps;
  });
  return r;
}

/// The x range with as many ticks (about 6 at most) as leave room between their labels in
/// `frame_px`: a 104 px wide plot (the per-joint views of the validation report) had 7 labels
/// like "-150" running into each other.
Range x_range_fitting(const AxisSpec& spec, double data_lo, double data_hi, double frame_px) {
  for (int target = 6;; --target) {
    Range r = make_range(spec, data_lo, data_hi, target);
    if (target <= 2 || x_labels_fit(r.ticks, frame_px)) return r;
  }
}

struct Frame {
  double x0, x1, y0, y1;  // plot area in pixels (y0 top)
};

double to_px(double v, double lo, double hi, double p0, double p1) {
  return p0 + (v - lo) / (hi - lo) * (p1 - p0);
}

void open_svg(std::string& out, int w, int h, const std::string& title) {
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"errfield-plot\" width=\"" +
         std::to_string(w) + "\" height=\"" + std::to_string(h) + "\" viewBox=\"0 0 " +
         std::to_string(w) + " " + std::to_string(h) +
         "\" font-family=\"sans-serif\" font-size=\"12\" role=\"img\">\n";
  out += "<title>" + escape_xml(title) + "</title>\n";
  out += "<rect x=\"0\" y=\"0\" width=\"" + std::to_string(w) + "\" height=\"" + std::to_string(h) +
         "\" fill=\"#ffffff\"/>\n";
  out += "<text x=\"" + num(w / 2.0) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">" +
         escape_xml(title) + "</text>\n";
}

void draw_y_axis(std::string& out, const Frame& f, const Range& y, const AxisSpec& spec) {
  const double step = y.ticks.size() > 1 ? y.ticks[1] - y.ticks[0] : (y.hi - y.lo);
  for (double t : y.ticks) {
    const double py = to_px(t, y.lo, y.hi, f.y1, f.y0);
    out += "<line x1=\"" + num(f.x0) + "\" y1=\"" + num(py) + "\" x2=\"" + num(f.x1) + "\" y2=\"" + num(py) +
           "\" stroke=\"#e4e4e4\"/>\n";
    out += "<line x1=\"" + num(f.x0 - 5) + "\" y1=\"" + num(py) + "\" x2=\"" + num(f.x0) + "\" y2=\"" + num(py) +
           "\" stroke=\"#333\"/>\n";
    out += "<text x=\"" + num(f.x0 - 8) + "\" y=\"" + num(py + 4) + "\" text-anchor=\"end\">" +
           escape_xml(tick_label(t, step)) + "</text>\n";
  }
  const double cy = (f.y0 + f.y1) / 2.0;
  out += "<text x=\"16\" y=\"" + num(cy) + "\" text-anchor=\"middle\" transform=\"rotate(-90 16 " + num(cy) +
         ")\">" + escape_xml(axis_title(spec)) + "</text>\n";
}

void draw_frame(std::string& out, const Frame& f) {
  out += "<rect x=\"" + num(f.x0) + "\" y=\"" + num(f.y0) + "\" width=\"" + num(f.x1 - f.x0) + "\" height=\"" +
         num(f.y1 - f.y0) + "\" fill=\"none\" stroke=\"#333\"/>\n";
}

void stamp_simulated(std::string& out, const Frame& f, bool simulated) {
  if (!simulated) return;
  out += "<text class=\"simulated-stamp\" x=\"" + num(f.x1 - 8) + "\" y=\"" + num(f.y0 + 16) +
         "\" text-anchor=\"end\" font-size=\"12\" font-weight=\"bold\" fill=\"#b0b0b0\">SIMULATED</text>\n";
}

struct LegendEntry {
  std::string name;
  std::string color;
  SeriesStyle style;
  bool bar;
};

void draw_legend(std::string& out, const Frame& f, const std::vector<LegendEntry>& entries) {
  double y = f.y0 + 6;
  const double x = f.x1 + 14;
  for (const auto& e : entries) {
    const double cy = y + 8;
    if (e.bar) {
      out += "<rect x=\"" + num(x) + "\" y=\"" + num(cy - 5) + "\" width=\"18\" height=\"10\" fill=\"" + e.color + "\"/>\n";
    } else {
      if (e.style != SeriesStyle::Points)
        out += "<line x1=\"" + num(x) + "\" y1=\"" + num(cy) + "\" x2=\"" + num(x + 22) + "\" y2=\"" + num(cy) +
               "\" stroke=\"" + e.color + "\" stroke-width=\"2\"" +
               (e.style == SeriesStyle::Dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>\n";
      if (e.style == SeriesStyle::Points || e.style == SeriesStyle::LinePoints)
        out += "<circle cx=\"" + num(x + 11) + "\" cy=\"" + num(cy) + "\" r=\"3.5\" fill=\"" + e.color + "\"/>\n";
    }
    // Long names are cut so the legend stays inside its column.
    std::string name = e.name;
    if (name.size() > 26) {
      std::size_t cut = 25;
      while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xC0) == 0x80) --cut;
      name = name.substr(0, cut) + "…";
    }
    out += "<text x=\"" + num(x + 28) + "\" y=\"" + num(cy + 4) + "\">" + escape_xml(name) + "</text>\n";
    y += 20;
  }
}

}  // namespace

std::string_view palette_color(std::size_t i) { return kPalette[i % kPalette.size()]; }

std::string escape_xml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!(lo < hi) || !std::isfinite(lo) || !std::isfinite(hi))
    throw ArgumentError("nice_ticks: need finite lo < hi, got [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  target = std::max(target, 2);
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / mag;
  const double m = norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0;
  const double step = m * mag;
  const double first = std::floor(lo / step + 1e-9);
  const double last = std::ceil(hi / step - 1e-9);
  // For steps below 1, divide by the exact integer 10^n instead of multiplying by the inexact
  // 10^-n, so that 0.6 prints and compares as 0.6.
  const double inverse_mag = mag < 1.0 ? std::round(1.0 / mag) : 0.0;
  std::vector<double> ticks;
  for (double k = first; k <= last + 0.5; k += 1.0) {
    double t = inverse_mag > 0.0 ? (k * m) / inverse_mag : k * step;
    if (std::abs(t) < 1e-12 * step) t = 0.0;
    ticks.push_back(t);
  }
  return ticks;
}

HistogramBins histogram_bins(const std::vector<double>& values) {
  std::vector<double> v;
  v.reserve(values.size());
  for (double x : values)
    if (std::isfinite(x)) v.push_back(std::abs(x));
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  const double hi = v.back();
  if (!(hi > 0.0)) return {};
  const auto quantile = [&](double p) {
    const double at = p * static_cast<double>(v.size() - 1);
    const auto k = static_cast<std::size_t>(std::floor(at));
    const double f = at - static_cast<double>(k);
    return k + 1 < v.size() ? v[k] + f * (v[k + 1] - v[k]) : v[k];
  };
  const double fd = 2.0 * (quantile(0.75) - quantile(0.25)) / std::cbrt(static_cast<double>(v.size()));
  const double wanted = fd > 0.0 ? hi / fd : 20.0;
  const int target = static_cast<int>(std::clamp(std::round(wanted), 8.0, 30.0));
  const std::vector<double> ticks = nice_ticks(0.0, hi, target);
  HistogramBins b;
  b.width = ticks.size() >= 2 ? ticks[1] - ticks[0] : hi;
  b.count = static_cast<std::size_t>(std::floor(hi / b.width)) + 1;
  return b;
}

bool x_labels_fit(const std::vector<double>& ticks, double frame_px) {
  if (ticks.size() < 2) return true;
  const double step = ticks[1] - ticks[0];
  std::size_t widest = 0;
  for (double t : ticks) widest = std::max(widest, tick_label(t, step).size());
  // Evenly spaced ticks across the frame: neighbouring label centres are frame_px / (ticks - 1) apart.
  const double room = frame_px / static_cast<double>(ticks.size() - 1);
  return static_cast<double>(widest) * kLabelCharWidthPx + kLabelGapPx <= room;
}

std::string tick_label(double value, double step) {
  step = std::abs(step);
  int decimals = 0;
  if (step > 0.0 && std::isfinite(step)) {
    double scaled = step;
    while (decimals < 10 && std::abs(scaled - std::round(scaled)) > 1e-6 * std::max(1.0, scaled)) {
      scaled *= 10.0;
      ++decimals;
    }
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  std::string s = buf;
  if (s.find_first_not_of("-0.") == std::string::npos && s.front() == '-') s.erase(0, 1);
  return s;
}

namespace {

void check_size(int w, int h, std::string_view what) {
  if (w < 200 || h < 200)
    throw ArgumentError(std::string(what) + ": size " + std::to_string(w) + "x" + std::to_string(h) +
                        " px is too small; expected at least 200x200");
}

std::string clip_id(std::string_view kind, const std::string& title, int w, int h) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx",
                static_cast<unsigned long long>(fnv1a(title + "|" + std::to_string(w) + "x" + std::to_string(h), fnv1a(kind))));
  return std::string("clip-") + buf;
}

}  // namespace

std::string render_svg(const LinePlot& plot) {
  check_size(plot.width_px, plot.height_px, "LinePlot '" + plot.title + "'");
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  bool legend = false;
  for (const auto& s : plot.series) {
    if (s.x.size() != s.y.size())
      throw ArgumentError("LinePlot '" + plot.title + "': series '" + s.name + "' has " + std::to_string(s.x.size()) +
                          " x values and " + std::to_string(s.y.size()) + " y values");
    legend = legend || !s.name.empty();
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      xlo = std::min(xlo, s.x[i]), xhi = std::max(xhi, s.x[i]);
      ylo = std::min(ylo, s.y[i]), yhi = std::max(yhi, s.y[i]);
    }
  }
  const Frame f{76.0, plot.width_px - (legend ? 200.0 : 24.0), 40.0, plot.height_px - 52.0};
  const Range xr = x_range_fitting(plot.x_axis, xlo, xhi, f.x1 - f.x0);
  const Range yr = make_range(plot.y_axis, ylo, yhi);

  std::string out;
  open_svg(out, plot.width_px, plot.height_px, plot.title);
  const std::string id = clip_id("line", plot.title, plot.width_px, plot.height_px);
  out += "<defs><clipPath id=\"" + id + "\"><rect x=\"" + num(f.x0) + "\" y=\"" + num(f.y0) + "\" width=\"" +
         num(f.x1 - f.x0) + "\" height=\"" + num(f.y1 - f.y0) + "\"/></clipPath></defs>\n";
  draw_y_axis(out, f, yr, plot.y_axis);
  const double xstep = xr.ticks.size() > 1 ? xr.ticks[1] - xr.ticks[0] : (xr.hi - xr.lo);
  for (double t : xr.ticks) {
    const double px = to_px(t, xr.lo, xr.hi, f.x0, f.x1);
    out += "<line x1=\"" + num(px) + "\" y1=\"" + num(f.y0) + "\" x2=\"" + num(px) + "\" y2=\"" + num(f.y1) +
           "\" stroke=\"#efefef\"/>\n";
    out += "<line x1=\"" + num(px) + "\" y1=\"" + num(f.y1) + "\" x2=\"" + num(px) + "\" y2=\"" + num(f.y1 + 5) +
           "\" stroke=\"#333\"/>\n";
    out += "<text x=\"" + num(px) + "\" y=\"" + num(f.y1 + 19) + "\" text-anchor=\"middle\">" +
           escape_xml(tick_label(t, xstep)) + "</text>\n";
  }
  out += "<text x=\"" + num((f.x0 + f.x1) / 2) + "\" y=\"" + num(plot.height_px - 12.0) +
         "\" text-anchor=\"middle\">" + escape_xml(axis_title(plot.x_axis)) + "</text>\n";
  draw_frame(out, f);
  stamp_simulated(out, f, plot.simulated);

  std::vector<LegendEntry> entries;
  out += "<g clip-path=\"url(#" + id + ")\">\n";
  for (std::size_t k = 0; k < plot.series.size(); ++k) {
    const Series& s = plot.series[k];
    const std::string color = s.color.empty() ? std::string(palette_color(k)) : s.color;
    if (!s.name.empty()) entries.push_back({s.name, color, s.style, false});
    out += "<g class=\"series\" data-name=\"" + escape_xml(s.name) + "\">\n";
    if (s.style != SeriesStyle::Points) {
      std::string pts;
      auto flush = [&] {
        if (pts.empty()) return;
        out += "<polyline fill=\"none\" stroke=\"" + color + "\" stroke-width=\"2\"" +
               (s.style == SeriesStyle::Dashed ? " stroke-dasharray=\"6 4\"" : "") + " points=\"" + pts + "\"/>\n";
        pts.clear();
      };
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
          flush();
          continue;
        }
        if (!pts.empty()) pts += ' ';
        pts += num(to_px(s.x[i], xr.lo, xr.hi, f.x0, f.x1)) + "," + num(to_px(s.y[i], yr.lo, yr.hi, f.y1, f.y0));
      }
      flush();
    }
    if (s.style == SeriesStyle::Points || s.style == SeriesStyle::LinePoints) {
      const double r = s.x.size() > 150 ? 2.0 : 3.2;
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
        out += "<circle cx=\"" + num(to_px(s.x[i], xr.lo, xr.hi, f.x0, f.x1)) + "\" cy=\"" +
               num(to_px(s.y[i], yr.lo, yr.hi, f.y1, f.y0)) + "\" r=\"" + num(r) + "\" fill=\"" + color + "\"/>\n";
      }
    }
    out += "</g>\n";
  }
  out += "</g>\n";
  if (legend) draw_legend(out, f, entries);
  out += "</svg>\n";
  return out;
}

std::string render_svg(const BarChart& chart) {
  check_size(chart.width_px, chart.height_px, "BarChart '" + chart.title + "'");
  const std::size_t n = chart.categories.size();
  double ylo = 0.0, yhi = 0.0;
  bool legend = false;
  for (const auto& s : chart.series) {
    if (s.values.size() != n)
      throw ArgumentError("BarChart '" + chart.title + "': series '" + s.name + "' has " +
                          std::to_string(s.values.size()) + " values for " + std::to_string(n) + " categories");
    legend = legend || !s.name.empty();
    for (double v : s.values)
      if (std::isfinite(v)) ylo = std::min(ylo, v), yhi = std::max(yhi, v);
  }
  AxisSpec yspec = chart.y_axis;
  yspec.include_zero = true;
  const Range yr = make_range(yspec, ylo, yhi);
  const Frame f{76.0, chart.width_px - (legend ? 200.0 : 24.0), 40.0, chart.height_px - 52.0};

  std::string out;
  open_svg(out, chart.width_px, chart.height_px, chart.title);
  draw_y_axis(out, f, yr, chart.y_axis);
  const double slot = n ? (f.x1 - f.x0) / static_cast<double>(n) : 0.0;
  // Every k-th category labelled, k as small as leaves room between the labels (at most 24 labels).
  std::size_t widest = 0;
  for (const auto& c : chart.categories) widest = std::max(widest, c.size());
  const double label_px = static_cast<double>(widest) * kLabelCharWidthPx + kLabelGapPx;
  std::size_t label_every = n > 24 ? (n + 23) / 24 : 1;
  while (slot > 0.0 && label_every < n && static_cast<double>(label_every) * slot < label_px) ++label_every;
  for (std::size_t c = 0; c < n; ++c) {
    if (c % label_every) continue;
    const double px = f.x0 + (c + 0.5) * slot;
    out += "<text x=\"" + num(px) + "\" y=\"" + num(f.y1 + 17) + "\" text-anchor=\"middle\">" +
           escape_xml(chart.categories[c]) + "</text>\n";
  }
  out += "<text x=\"" + num((f.x0 + f.x1) / 2) + "\" y=\"" + num(chart.height_px - 12.0) +
         "\" text-anchor=\"middle\">" + escape_xml(chart.category_label) + "</text>\n";
  const double zero = to_px(0.0, yr.lo, yr.hi, f.y1, f.y0);
  const std::size_t m = std::max<std::size_t>(chart.series.size(), 1);
  const double bar = 0.8 * slot / static_cast<double>(m);
  std::vector<LegendEntry> entries;
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const BarSeries& s = chart.series[k];
    const std::string color = s.color.empty() ? std::string(palette_color(k)) : s.color;
    if (!s.name.empty()) entries.push_back({s.name, color, SeriesStyle::Line, true});
    out += "<g class=\"series\" data-name=\"" + escape_xml(s.name) + "\">\n";
    for (std::size_t c = 0; c < n; ++c) {
      const double v = s.values[c];
      if (!std::isfinite(v)) continue;
      const double top = to_px(std::clamp(v, yr.lo, yr.hi), yr.lo, yr.hi, f.y1, f.y0);
      const double x = f.x0 + c * slot + 0.1 * slot + k * bar;
      out += "<rect x=\"" + num(x) + "\" y=\"" + num(std::min(top, zero)) + "\" width=\"" + num(std::max(bar - 1.0, 1.0)) +
             "\" height=\"" + num(std::abs(zero - top)) + "\" fill=\"" + color + "\"/>\n";
    }
    out += "</g>\n";
  }
  draw_frame(out, f);
  stamp_simulated(out, f, chart.simulated);
  if (legend) draw_legend(out, f, entries);
  out += "</svg>\n";
  return out;
}

}  // namespace errfield::report
