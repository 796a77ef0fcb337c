#pragma once
// `interpolate --grid ... --plot map.svg` (a prediction map with the samples on it) and `variogram
// --map ... --plot map.svg` (the variogram map): an SVG picture of values on a regular 2-D grid.
// One rectangle per run of equally coloured cells along a row (a 200 x 200 grid is not 40,000
// elements), cells drawn to scale (one unit is as long in x as in y), a colour bar, and the points
// over the map. Hand-written SVG 1.1 text, as variogram_svg.hpp; its ticks and number formats.
//
// Colours: viridis (van der Walt & Smith, matplotlib), 9 stops interpolated linearly and quantized
// to 64 levels: readable in grey and by colour-blind readers, dark at the low end.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cli/variogram_svg.hpp"

namespace errfield::cli {

struct GridMapPlot {
  std::size_t nx = 0, ny = 0;
  double x_min = 0.0, dx = 1.0;  ///< cell centres x_min + i dx
  double y_min = 0.0, dy = 1.0;  ///< cell centres y_min + j dy; row 0 of `values` is the top (largest y)
  std::vector<double> values;    ///< nx * ny, row by row from the top, x increasing; NaN: no value
  std::vector<std::array<double, 2>> points;  ///< drawn over the map (e.g. the samples)
  std::string title, x_label = "x", y_label = "y", value_label;
};

namespace grid_map_svg {

/// The viridis colour of t in [0, 1], quantized to 64 levels, as "#rrggbb".
inline std::string colour(double t) {
  static constexpr std::array<std::array<int, 3>, 9> kStops{{{68, 1, 84},
                                                              {71, 45, 123},
                                                              {59, 82, 139},
                                                              {44, 114, 142},
                                                              {33, 145, 140},
                                                              {40, 174, 128},
                                                              {94, 201, 98},
                                                              {173, 220, 48},
                                                              {253, 231, 37}}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
  t = std::round(t * 63.0) / 63.0;
  const double at = t * 8.0;
  const auto k = std::min<std::size_t>(7, static_cast<std::size_t>(at));
  const double f = at - static_cast<double>(k);
  char text[8];
  int rgb[3];
  for (int c = 0; c < 3; ++c)
    rgb[c] = static_cast<int>(std::lround(kStops[k][static_cast<std::size_t>(c)] * (1.0 - f) +
                                          kStops[k + 1][static_cast<std::size_t>(c)] * f));
  std::snprintf(text, sizeof text, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
  return text;
}

}  // namespace grid_map_svg

/// The SVG document. All-NaN values give an empty map with the axes.
inline std::string grid_map_svg_text(const GridMapPlot& p) {
  using namespace variogram_svg;
  using grid_map_svg::colour;
  constexpr double kLeft = 90, kTop = 50, kBoxW = 560, kBoxH = 440, kBar = 18;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : p.values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  const bool any = lo <= hi;
  if (!any) lo = 0.0, hi = 1.0;
  const double span = hi > lo ? hi - lo : 1.0;
  // Cell edges in coordinates, and one scale for both axes.
  const double x0 = p.x_min - 0.5 * p.dx, x1 = p.x_min + (static_cast<double>(p.nx) - 0.5) * p.dx;
  const double y0 = p.y_min - 0.5 * p.dy, y1 = p.y_min + (static_cast<double>(p.ny) - 0.5) * p.dy;
  const double scale = std::min(kBoxW / std::max(x1 - x0, 1e-300), kBoxH / std::max(y1 - y0, 1e-300));
  const double map_w = (x1 - x0) * scale, map_h = (y1 - y0) * scale;
  const auto X = [&](double x) { return kLeft + (x - x0) * scale; };
  const auto Y = [&](double y) { return kTop + (y1 - y) * scale; };
  // At least 720 px wide: a tall map leaves room for the title.
  const double width = std::max(720.0, kLeft + map_w + 130), height = kTop + map_h + 60;

  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << px(width) << "\" height=\"" << px(height)
    << "\" viewBox=\"0 0 " << px(width) << " " << px(height) << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<title>" << escaped(p.title) << "</title>\n"
    << "<rect x=\"0\" y=\"0\" width=\"" << px(width) << "\" height=\"" << px(height) << "\" fill=\"white\"/>\n"
    << "<text x=\"" << px(kLeft) << "\" y=\"28\" font-size=\"15\">" << escaped(p.title) << "</text>\n";
  // The cells: one rectangle per run of equal colour along a row.
  s << "<g id=\"cells\" shape-rendering=\"crispEdges\">\n";
  const double cw = p.dx * scale, ch = p.dy * scale;
  for (std::size_t r = 0; r < p.ny; ++r) {
    std::size_t c = 0;
    while (c < p.nx) {
      const double v = p.values[r * p.nx + c];
      if (!std::isfinite(v)) {
        ++c;
        continue;
      }
      const std::string fill = colour((v - lo) / span);
      std::size_t end = c + 1;
      while (end < p.nx && std::isfinite(p.values[r * p.nx + end]) && colour((p.values[r * p.nx + end] - lo) / span) == fill)
        ++end;
      s << "<rect x=\"" << px(kLeft + static_cast<double>(c) * cw) << "\" y=\"" << px(kTop + static_cast<double>(r) * ch)
        << "\" width=\"" << px(static_cast<double>(end - c) * cw) << "\" height=\"" << px(ch) << "\" fill=\"" << fill
        << "\"/>\n";
      c = end;
    }
  }
  s << "</g>\n";
  // The frame, ticks and labels (ticks at multiples of a nice step inside the map).
  s << "<g id=\"axes\" stroke=\"#000\" fill=\"none\">\n<rect x=\"" << px(kLeft) << "\" y=\"" << px(kTop) << "\" width=\""
    << px(map_w) << "\" height=\"" << px(map_h) << "\"/>\n</g>\n<g id=\"tick-labels\" fill=\"#000\">\n";
  const double xs = nice_step(x1 - x0, 5), ys = nice_step(y1 - y0, 5);
  for (double t = std::ceil(x0 / xs) * xs; t <= x1 + 1e-9 * xs; t += xs)
    s << "<path d=\"M" << px(X(t)) << "," << px(kTop + map_h) << " v5\" stroke=\"#000\"/><text x=\"" << px(X(t))
      << "\" y=\"" << px(kTop + map_h + 19) << "\" text-anchor=\"middle\">" << tick_label(std::abs(t) < 1e-12 * xs ? 0.0 : t)
      << "</text>\n";
  for (double t = std::ceil(y0 / ys) * ys; t <= y1 + 1e-9 * ys; t += ys)
    s << "<path d=\"M" << px(kLeft) << "," << px(Y(t)) << " h-5\" stroke=\"#000\"/><text x=\"" << px(kLeft - 8) << "\" y=\""
      << px(Y(t) + 4) << "\" text-anchor=\"end\">" << tick_label(std::abs(t) < 1e-12 * ys ? 0.0 : t) << "</text>\n";
  s << "<text x=\"" << px(kLeft + map_w / 2) << "\" y=\"" << px(kTop + map_h + 42) << "\" text-anchor=\"middle\">"
    << escaped(p.x_label) << "</text>\n<text transform=\"translate(18," << px(kTop + map_h / 2)
    << ") rotate(-90)\" text-anchor=\"middle\">" << escaped(p.y_label) << "</text>\n</g>\n";
  // The points over the map.
  s << "<g id=\"points\" fill=\"white\" stroke=\"#000\" stroke-width=\"0.8\">\n";
  for (const auto& q : p.points)
    if (q[0] >= x0 && q[0] <= x1 && q[1] >= y0 && q[1] <= y1)
      s << "<circle cx=\"" << px(X(q[0])) << "\" cy=\"" << px(Y(q[1])) << "\" r=\"2.5\"/>\n";
  s << "</g>\n";
  // The colour bar: low at the bottom, with the smallest, middle and largest value.
  const double bx = kLeft + map_w + 20;
  s << "<g id=\"colour-bar\">\n";
  for (int k = 0; k < 64; ++k) {
    const double t = static_cast<double>(k) / 63.0;
    s << "<rect x=\"" << px(bx) << "\" y=\"" << px(kTop + map_h * (1.0 - static_cast<double>(k + 1) / 64.0))
      << "\" width=\"" << kBar << "\" height=\"" << px(map_h / 64.0 + 0.5) << "\" fill=\"" << colour(t) << "\"/>\n";
  }
  for (int k = 0; k <= 2 && any; ++k) {
    const double v = lo + span * k / 2.0;
    s << "<text class=\"bar-label\" x=\"" << px(bx + kBar + 5) << "\" y=\"" << px(kTop + map_h * (1.0 - k / 2.0) + 4)
      << "\">" << escaped(shortened_numbers(format_number(v))) << "</text>\n";
  }
  s << "<text x=\"" << px(bx) << "\" y=\"" << px(kTop - 8) << "\">" << escaped(p.value_label) << "</text>\n</g>\n</svg>\n";
  return s.str();
}

}  // namespace errfield::cli
