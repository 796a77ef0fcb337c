#include "errfield/report/html_report.hpp"

#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"

namespace errfield::report {

namespace {

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 24px auto; max-width: 1000px; color: #222; line-height: 1.45; }
h1 { font-size: 24px; margin-bottom: 4px; }
h2 { font-size: 19px; margin-top: 32px; border-bottom: 1px solid #ccc; padding-bottom: 3px; }
h3 { font-size: 16px; margin-top: 22px; }
.banner { background: #fff3cd; border: 1px solid #e0c060; padding: 8px 12px; font-weight: bold; margin: 12px 0; }
table { border-collapse: collapse; margin: 10px 0 4px 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 3px 9px; }
th { background: #f2f2f2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.rule td { border-top: 2px solid #888; }
caption { caption-side: top; text-align: left; font-weight: bold; padding-bottom: 4px; }
figure { margin: 18px 0; }
figcaption { font-size: 13px; color: #444; max-width: 760px; }
pre { background: #f6f6f6; padding: 8px; overflow-x: auto; font-size: 12px; }
)";

}  // namespace

HtmlReport::HtmlReport(std::string title, bool simulated) : title_(std::move(title)), simulated_(simulated) {}

void HtmlReport::add_heading(const std::string& text, int level) {
  if (level < 2 || level > 3)
    throw ArgumentError("HtmlReport::add_heading: level " + std::to_string(level) + "; expected 2 or 3");
  const char* open = level == 2 ? "<h2>" : "<h3>";
  const char* close = level == 2 ? "</h2>\n" : "</h3>\n";
  body_ += open;
  body_ += escape_xml(text);
  body_ += close;
}

void HtmlReport::add_paragraph(const std::string& text) { body_ += "<p>" + escape_xml(text) + "</p>\n"; }

void HtmlReport::add_preformatted(const std::string& text) { body_ += "<pre>" + escape_xml(text) + "</pre>\n"; }

void HtmlReport::add_table(const TextTable& table, const std::string& caption) {
  body_ += "<table>\n";
  if (!caption.empty()) body_ += "<caption>" + escape_xml(caption) + "</caption>\n";
  body_ += "<tr>";
  for (const auto& c : table.columns())
    body_ += "<th>" + escape_xml(c.header) + (c.unit.empty() ? "" : " [" + escape_xml(c.unit) + "]") + "</th>";
  body_ += "</tr>\n";
  for (std::size_t r = 0; r < table.row_count(); ++r) {
    body_ += (r > 0 && table.separator_before(r)) ? "<tr class=\"rule\">" : "<tr>";
    for (std::size_t c = 0; c < table.columns().size(); ++c)
      body_ += std::string(table.columns()[c].align == Align::Right ? "<td class=\"num\">" : "<td>") +
               escape_xml(table.row(r)[c]) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
}

void HtmlReport::add_svg(const std::string& svg, const std::string& caption) {
  ++figures_;
  body_ += "<figure>\n" + svg;
  if (!caption.empty())
    body_ += "<figcaption>Figure " + std::to_string(figures_) + ". " + escape_xml(caption) + "</figcaption>\n";
  body_ += "</figure>\n";
}

void HtmlReport::add_figure(LinePlot plot, const std::string& caption) {
  plot.simulated = plot.simulated || simulated_;
  add_svg(render_svg(plot), caption);
}

void HtmlReport::add_figure(BarChart chart, const std::string& caption) {
  chart.simulated = chart.simulated || simulated_;
  add_svg(render_svg(chart), caption);
}

std::string HtmlReport::to_html() const {
  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
                    escape_xml(title_) + (simulated_ ? " (SIMULATED)" : "") + "</title>\n<style>" + kStyle +
                    "</style>\n</head>\n<body>\n<h1>" + escape_xml(title_) + "</h1>\n";
  if (simulated_)
    out += "<div class=\"banner\" id=\"simulated-banner\">SIMULATED: every number and plot in this report comes "
           "from a simulated robot and tracker, not from measurements.</div>\n";
  out += body_;
  out += "</body>\n</html>\n";
  return out;
}

void HtmlReport::write(const std::filesystem::path& path) const { write_file_atomically(path, to_html()); }

}  // namespace errfield::report
