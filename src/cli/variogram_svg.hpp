#pragma once
// `variogram --plot` and `fit-variogram --plot`: an SVG picture of an empirical variogram - one
// point per non-empty bin, its area proportional to the bin's pair count and the count written
// beside it (as gstat's plot(v, plot.numbers = TRUE)) - with, for fit-variogram, the fitted model
// as a curve. Hand-written SVG 1.1 text (no plotting dependency), which any browser shows.
// Axes start at 0 and have "nice" ticks (1, 2 or 5 times a power of ten); units are taken from the
// column headers when they carry one ("x [mm]").

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "errfield/csv_table.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield::cli {

struct VariogramPlotBin {
  double lag = 0.0, gamma = 0.0;
  std::uint64_t pairs = 0;
};

/// One direction's bins on a picture of several (variogram --alpha 0,45,90 --plot).
struct VariogramPlotSeries {
  std::string name;  ///< in the legend, e.g. "direction 45"
  std::vector<VariogramPlotBin> bins;
};

struct VariogramPlot {
  std::vector<VariogramPlotBin> bins;  ///< non-empty bins (one variogram; ignored when `series` is given)
  std::vector<VariogramPlotSeries> series;  ///< several directions, each its colour and a legend
  std::optional<VariogramModel> model; ///< drawn as a curve (its isotropic part) when given
  std::string title;                   ///< e.g. "dL" or the model text
  std::string lag_label = "lag";       ///< x axis, with its unit if known: "lag [mm]"
  std::string gamma_label = "semivariance";
};

namespace variogram_svg {

/// Text safe inside SVG elements and attributes.
inline std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// A tick step of 1, 2 or 5 times a power of ten giving about `target` intervals over [0, top].
inline double nice_step(double top, int target) {
  const double raw = top / target;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

/// Coordinates in the picture, rounded to 0.01 px (short text, no visible difference).
inline std::string px(double v) {
  std::ostringstream s;
  s << std::round(v * 100.0) / 100.0;
  return s.str();
}

/// A tick value with at most 10 significant digits (k * 0.2 prints 0.6, not 0.6000000000000001).
inline std::string tick_label(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

/// `text` with every number written to 4 significant digits ("range=489.37901359674305" ->
/// "range=489.4"): a caption a reader can take in; the full text stays in the element's <title>.
inline std::string shortened_numbers(const std::string& text) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    const bool starts = (c >= '0' && c <= '9') || (c == '.' && i + 1 < text.size() && text[i + 1] >= '0' && text[i + 1] <= '9');
    if (!starts) {
      out += c;
      ++i;
      continue;
    }
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(text.substr(i), &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0) {
      out += c;
      ++i;
      continue;
    }
    std::ostringstream s;
    s.precision(4);
    s << v;
    out += s.str();
    i += used;
  }
  return out;
}

/// `text` cut into lines of at most `width` characters after a '+', ',' or ' ' where it can be (a
/// longer piece without one is cut where it must).
inline std::vector<std::string> wrapped(const std::string& text, std::size_t width) {
  std::vector<std::string> lines;
  std::string rest = text;
  while (rest.size() > width) {
    std::size_t cut = std::string::npos;
    for (std::size_t k = width; k > width / 2; --k)
      if (rest[k - 1] == '+' || rest[k - 1] == ',' || rest[k - 1] == ' ') {
        cut = k;
        break;
      }
    if (cut == std::string::npos) cut = width;
    lines.push_back(rest.substr(0, cut));
    rest = rest.substr(cut);
  }
  if (!rest.empty()) lines.push_back(rest);
  return lines;
}

}  // namespace variogram_svg

/// The plot area: its corner and size in the picture, and the axes' ends.
struct VariogramPlotFrame {
  double left, top, width, height, x_top, y_top;
  double X(double h) const { return left + width * h / x_top; }
  double Y(double g) const { return top + height * (1.0 - g / y_top); }
};

/// The bins' points, their pair counts and (several directions) the legend.
inline void write_bins(std::ostringstream& s, const std::vector<VariogramPlotSeries>& series, std::uint64_t max_pairs,
                       const VariogramPlotFrame& f) {
  using namespace variogram_svg;
  const auto X = [&](double h) { return f.X(h); };
  const auto Y = [&](double g) { return f.Y(g); };
  const double kLeft = f.left, kTop = f.top, plot_w = f.width;
  // One point per bin: area proportional to its pairs, the count beside it (above right, else below
  // right; left out where both would overlap a count already written: issue 49, the counts of close
  // bins were written over each other; every count stays in its point's <title>).
  struct Box {
    double x0, y0, x1, y1;
  };
  std::vector<Box> placed;
  const auto free_at = [&](const Box& b) {
    for (const Box& o : placed)
      if (b.x0 < o.x1 && o.x0 < b.x1 && b.y0 < o.y1 && o.y0 < b.y1) return false;
    return true;
  };
  // Several directions: a colour each (colour-blind safe, Okabe & Ito) and a legend at the top right
  // of the plot area, whose box no count is written over.
  static const char* const kColours[] = {"#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000"};
  if (series.size() > 1) {
    s << "<g id=\"legend\">\n";
    for (std::size_t k = 0; k < series.size(); ++k) {
      const double ly = kTop + 12 + 16.0 * static_cast<double>(k);
      const double lx = kLeft + plot_w - 150;
      s << "<circle cx=\"" << px(lx) << "\" cy=\"" << px(ly - 4) << "\" r=\"5\" fill=\"" << kColours[k % 7] << "\"/>"
        << "<text x=\"" << px(lx + 10) << "\" y=\"" << px(ly) << "\">" << escaped(series[k].name) << "</text>\n";
    }
    s << "</g>\n";
    placed.push_back({kLeft + plot_w - 158, kTop, kLeft + plot_w, kTop + 16.0 * static_cast<double>(series.size()) + 4});
  }
  for (std::size_t k = 0; k < series.size(); ++k) {
    s << "<g class=\"bins\"" << (k == 0 ? " id=\"bins\"" : "") << " fill=\""
      << (series.size() > 1 ? kColours[k % 7] : "#1f4e79") << "\">\n";
    for (const auto& b : series[k].bins) {
      const double r = 2.0 + 5.0 * std::sqrt(static_cast<double>(b.pairs) / static_cast<double>(max_pairs));
      s << "<circle class=\"bin\" cx=\"" << px(X(b.lag)) << "\" cy=\"" << px(Y(b.gamma)) << "\" r=\"" << px(r)
        << "\"><title>" << (series[k].name.empty() ? std::string() : escaped(series[k].name) + ": ") << "lag "
        << format_number(b.lag) << ", gamma " << format_number(b.gamma) << ", " << b.pairs << " pairs</title></circle>\n";
      // 10 px text: ~6 px per digit, 10 px high above its baseline.
      const double w = 6.0 * static_cast<double>(std::to_string(b.pairs).size());
      const double lx = X(b.lag) + r + 2;
      for (const double base : {Y(b.gamma) - r - 2, Y(b.gamma) + r + 10}) {
        const Box box{lx, base - 10.0, lx + w, base + 1.0};
        if (!free_at(box)) continue;
        placed.push_back(box);
        s << "<text class=\"pairs\" x=\"" << px(lx) << "\" y=\"" << px(base) << "\" font-size=\"10\">" << b.pairs
          << "</text>\n";
        break;
      }
    }
    s << "</g>\n";
  }
}

/// The SVG document. Throws nothing; an empty `bins` gives empty axes.
inline std::string variogram_svg_text(const VariogramPlot& p) {
  using namespace variogram_svg;
  constexpr double kWidth = 720, kLeft = 80, kRight = 30, kBottom = 60, kCaptionLine = 15;
  // The model's caption under the title, left-aligned inside the frame, wrapped (issue 49: written
  // right-aligned on one line, a long nested or ARD model ran off the picture's left edge).
  const std::vector<std::string> caption =
      p.model ? wrapped(shortened_numbers(p.model->to_string()), 100) : std::vector<std::string>{};
  const double kTop = 50 + kCaptionLine * static_cast<double>(caption.size());
  const double kHeight = 430 + kTop;
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  const std::vector<VariogramPlotSeries> series =
      p.series.empty() ? std::vector<VariogramPlotSeries>{{std::string(), p.bins}} : p.series;
  double max_lag = 0.0, max_gamma = 0.0;
  std::uint64_t max_pairs = 1;
  for (const auto& one : series)
    for (const auto& b : one.bins) {
      max_lag = std::max(max_lag, b.lag);
      max_gamma = std::max(max_gamma, b.gamma);
      max_pairs = std::max(max_pairs, b.pairs);
    }
  if (!(max_lag > 0.0)) max_lag = 1.0;
  const double x_step = nice_step(max_lag * 1.05, 6);
  const double x_top = std::ceil(max_lag * 1.05 / x_step) * x_step;
  // The model curve on 300 lags from just above 0 (where a nugget jumps) to the axis' end.
  std::vector<std::pair<double, double>> curve;
  if (p.model) {
    const VariogramModel iso = p.model->isotropic_part();
    for (int k = 0; k <= 300; ++k) {
      const double h = k == 0 ? 1e-9 * x_top : x_top * k / 300.0;
      const double g = iso.gamma(h);
      if (std::isfinite(g)) {
        curve.emplace_back(h, g);
        max_gamma = std::max(max_gamma, g);
      }
    }
  }
  if (!(max_gamma > 0.0)) max_gamma = 1.0;
  const double y_step = nice_step(max_gamma * 1.1, 5);
  const double y_top = std::ceil(max_gamma * 1.1 / y_step) * y_step;
  const int x_ticks = static_cast<int>(std::lround(x_top / x_step));
  const int y_ticks = static_cast<int>(std::lround(y_top / y_step));
  const auto X = [&](double h) { return kLeft + plot_w * h / x_top; };
  const auto Y = [&](double g) { return kTop + plot_h * (1.0 - g / y_top); };

  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << kWidth << "\" height=\"" << kHeight
    << "\" viewBox=\"0 0 " << kWidth << " " << kHeight << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<title>" << escaped(p.title.empty() ? std::string("empirical variogram") : p.title) << "</title>\n"
    << "<rect x=\"0\" y=\"0\" width=\"" << kWidth << "\" height=\"" << kHeight << "\" fill=\"white\"/>\n";
  s << "<text x=\"" << px(kLeft) << "\" y=\"28\" font-size=\"15\">" << escaped(p.title) << "</text>\n";
  // Grid lines and ticks.
  s << "<g id=\"axes\" stroke=\"#000\" fill=\"none\">\n";
  s << "<path d=\"M" << px(kLeft) << "," << px(kTop) << " V" << px(kTop + plot_h) << " H" << px(kLeft + plot_w)
    << "\"/>\n";
  for (int k = 0; k <= x_ticks; ++k) s << "<path d=\"M" << px(X(k * x_step)) << "," << px(kTop + plot_h) << " v5\"/>\n";
  for (int k = 0; k <= y_ticks; ++k) s << "<path d=\"M" << px(kLeft) << "," << px(Y(k * y_step)) << " h-5\"/>\n";
  s << "</g>\n<g id=\"tick-labels\" fill=\"#000\">\n";
  for (int k = 0; k <= x_ticks; ++k)
    s << "<text x=\"" << px(X(k * x_step)) << "\" y=\"" << px(kTop + plot_h + 20) << "\" text-anchor=\"middle\">"
      << tick_label(k * x_step) << "</text>\n";
  for (int k = 0; k <= y_ticks; ++k)
    s << "<text x=\"" << px(kLeft - 8) << "\" y=\"" << px(Y(k * y_step) + 4) << "\" text-anchor=\"end\">"
      << tick_label(k * y_step) << "</text>\n";
  s << "<text x=\"" << px(kLeft + plot_w / 2) << "\" y=\"" << px(kHeight - 15) << "\" text-anchor=\"middle\">"
    << escaped(p.lag_label) << "</text>\n";
  s << "<text transform=\"translate(20," << px(kTop + plot_h / 2) << ") rotate(-90)\" text-anchor=\"middle\">"
    << escaped(p.gamma_label) << "</text>\n</g>\n";
  if (!curve.empty()) {
    s << "<path id=\"model\" fill=\"none\" stroke=\"#c0392b\" stroke-width=\"2\" d=\"";
    for (std::size_t k = 0; k < curve.size(); ++k)
      s << (k ? " L" : "M") << px(X(curve[k].first)) << "," << px(Y(std::min(curve[k].second, y_top)));
    s << "\"><title>" << escaped(p.model->to_string()) << "</title></path>\n";
    s << "<text class=\"caption\" x=\"" << px(kLeft) << "\" y=\"46\" fill=\"#c0392b\" font-size=\"11\"><title>"
      << escaped(p.model->to_string()) << "</title>";
    for (std::size_t k = 0; k < caption.size(); ++k)
      s << "<tspan x=\"" << px(kLeft) << "\" dy=\"" << (k ? px(kCaptionLine) : "0") << "\">" << escaped(caption[k])
        << "</tspan>";
    s << "</text>\n";
  }
  write_bins(s, series, max_pairs, {kLeft, kTop, plot_w, plot_h, x_top, y_top});
  s << "</svg>\n";
  return s.str();
}

}  // namespace errfield::cli
