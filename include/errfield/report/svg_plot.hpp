#pragma once
/// Plots drawn as self-contained SVG text (no script, no external font or stylesheet), for
/// reports that open anywhere, offline, and print. Use `LinePlot` for curves and point clouds
/// (variograms with fitted models, a grid-step sweep, per-point errors) and `BarChart` for grouped
/// bars (before/after per target). Every axis has ticks at 1-2-5 steps and a label with its unit.
///
/// Rendering is a pure function of the plot description: the same input gives the same bytes.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace errfield::report {

/// One axis: label and unit are printed as "label [unit]". Limits default to the data's range
/// extended to round ticks; `include_zero` stretches the range to contain 0.
struct AxisSpec {
  AxisSpec() = default;
  AxisSpec(std::string label_, std::string unit_ = {}, std::optional<double> min_ = std::nullopt,
           std::optional<double> max_ = std::nullopt, bool include_zero_ = false)
      : label(std::move(label_)), unit(std::move(unit_)), min(min_), max(max_), include_zero(include_zero_) {}

  std::string label;
  std::string unit;
  std::optional<double> min;
  std::optional<double> max;
  bool include_zero = false;
};

enum class SeriesStyle {
  Line,        ///< a polyline through the points (breaks at NaN)
  Points,      ///< markers only
  LinePoints,  ///< both
  Dashed,      ///< a dashed polyline (e.g. a fitted model or a reference)
};

/// A named series of (x, y) pairs. A NaN y leaves a gap. `color` is a CSS colour ("#1f77b4");
/// empty takes the next colour of the palette.
struct Series {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
  SeriesStyle style = SeriesStyle::LinePoints;
  std::string color;
};

/// A 2-D plot with any number of series and a legend (shown when a series has a name).
struct LinePlot {
  std::string title;
  AxisSpec x_axis;
  AxisSpec y_axis;
  std::vector<Series> series;
  int width_px = 760;
  int height_px = 420;
  bool simulated = false;  ///< stamps "SIMULATED" in the plot area
};

/// One group of bars, one value per category.
struct BarSeries {
  std::string name;
  std::vector<double> values;
  std::string color;
};

/// Grouped bars: one slot per category, one bar per series in each slot.
struct BarChart {
  std::string title;
  std::string category_label;          ///< x-axis label (e.g. "hole")
  std::vector<std::string> categories;  ///< x tick labels
  AxisSpec y_axis;                      ///< min defaults to 0
  std::vector<BarSeries> series;
  int width_px = 760;
  int height_px = 420;
  bool simulated = false;
};

/// SVG for the plot. Throws ArgumentError when a series' x and y differ in length, a bar series
/// has a different number of values than categories, or a size is below 200 px.
std::string render_svg(const LinePlot& plot);
std::string render_svg(const BarChart& chart);

/// Round tick positions covering [lo, hi] at a 1, 2 or 5 × 10^k step, about `target` of them.
/// lo < hi; both finite.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

/// Width of one character of a 12 px sans-serif tick label (digits, '-', '.': ~0.55 em) and the
/// least gap between two labels, in pixels: the budget by which x labels are thinned out.
inline constexpr double kLabelCharWidthPx = 7.0;
inline constexpr double kLabelGapPx = 8.0;

/// True when the labels of evenly spaced x `ticks` (tick_label text), centred on their ticks
/// across `frame_px` pixels, leave kLabelGapPx between neighbours. A LinePlot keeps fewer ticks
/// (down to 2) until they do; a BarChart labels every k-th category for the same reason.
bool x_labels_fit(const std::vector<double>& ticks, double frame_px);

/// Bins of a histogram of magnitudes: `count` bins of `width` from 0.
struct HistogramBins {
  double width = 1.0;
  std::size_t count = 1;
};
/// Bins for the magnitudes |v| of the finite `values`, over [0, max]: a round width (1, 2 or
/// 5 x 10^k) near the Freedman-Diaconis width 2 IQR n^(-1/3), with about 8 to 30 bins over the
/// range. Fixed bins put all 294 "after" errors of a real validation (0.02-0.1 mm) into one 0.2 mm
/// bar; these follow the data. No finite value, or all 0: one bin of width 1.
HistogramBins histogram_bins(const std::vector<double>& values);

/// Tick label for `value` on an axis whose ticks are `step` apart: just enough decimals.
std::string tick_label(double value, double step);

/// Text with &, <, >, " and ' escaped for XML/HTML.
std::string escape_xml(std::string_view text);

/// The palette (10 colours, colour-blind-friendly order); colour i of it, wrapping around.
std::string_view palette_color(std::size_t i);

}  // namespace errfield::report
