#pragma once
/// A self-contained HTML report: one file with its plots as inline SVG, no script, no external
/// stylesheet, font or image, so it opens offline in any browser and can be archived or mailed.
/// Use it to present a run's results: headings, paragraphs, tables (the same TextTable printed on
/// the terminal) and figures (svg_plot.hpp). A report on simulated data carries a "SIMULATED"
/// banner at the top and on every figure.

#include <filesystem>
#include <string>
#include <vector>

#include "errfield/report/svg_plot.hpp"
#include "errfield/report/text_table.hpp"

namespace errfield::report {

class HtmlReport {
 public:
  /// `simulated` puts the banner at the top and stamps every figure added later.
  HtmlReport(std::string title, bool simulated);

  /// A section heading (level 2 or 3); text is escaped.
  void add_heading(const std::string& text, int level = 2);
  /// A paragraph of plain text (escaped; no markup).
  void add_paragraph(const std::string& text);
  /// A table with an optional caption; cells are escaped.
  void add_table(const TextTable& table, const std::string& caption = {});
  /// A figure: the plot is rendered here (stamped SIMULATED if the report is), with a caption.
  void add_figure(LinePlot plot, const std::string& caption = {});
  void add_figure(BarChart chart, const std::string& caption = {});
  /// A preformatted block (monospace), e.g. a command line or a JSON model.
  void add_preformatted(const std::string& text);

  bool simulated() const noexcept { return simulated_; }
  /// Number of figures added so far.
  std::size_t figure_count() const noexcept { return figures_; }

  /// The whole document.
  std::string to_html() const;
  /// Writes to_html() atomically (AtomicFileWriter); throws Error on I/O failure.
  void write(const std::filesystem::path& path) const;

 private:
  void add_svg(const std::string& svg, const std::string& caption);

  std::string title_;
  bool simulated_;
  std::string body_;
  std::size_t figures_ = 0;
};

}  // namespace errfield::report
