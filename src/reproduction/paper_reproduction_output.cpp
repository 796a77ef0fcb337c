// Output side of the paper reproduction: statistics, console tables, CSV files and the HTML report.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "errfield/atomic_file.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/csv_writing.hpp"
#include "errfield/error.hpp"
#include "errfield/report/html_report.hpp"
#include "errfield/robot/paper_reference.hpp"
#include "errfield/reproduction/paper_reproduction.hpp"

namespace errfield::reproduction {

using namespace errfield::robot;

using report::Align;
using report::fixed;
using report::TextColumn;
using report::TextTable;

ErrorStats error_stats(const std::vector<double>& errors_mm) {
  ErrorStats s;
  if (errors_mm.empty()) return {NAN, NAN, NAN};
  double sum = 0.0;
  for (double e : errors_mm) {
    s.max_mm = std::max(s.max_mm, std::abs(e));
    sum += std::abs(e);
  }
  const double n = static_cast<double>(errors_mm.size());
  s.mean_mm = sum / n;
  double ss = 0.0;
  for (double e : errors_mm) ss += (std::abs(e) - s.mean_mm) * (std::abs(e) - s.mean_mm);
  s.std_mm = errors_mm.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0;
  return s;
}

Spread spread_of(std::vector<double> v) {
  if (v.empty()) return {NAN, NAN, NAN, NAN, NAN};
  std::sort(v.begin(), v.end());
  // Linear interpolation between order statistics (type 7, R's default quantile).
  auto q = [&](double p) {
    const double h = p * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(h));
    const std::size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
  };
  return {q(0.5), q(0.25), q(0.75), v.front(), v.back()};
}

namespace {

/// "pow(sill=1.26e-04, exponent=2) + nug(0.0292)": the fitted model with 3 significant digits.
std::string short_model_text(const VariogramModel& m) {
  std::string out;
  char buf[160];
  for (const auto& c : m.components()) {
    if (!out.empty()) out += " + ";
    const std::string kind(model_kind_name(c.kind));
    if (c.kind == ModelKind::Nugget)
      std::snprintf(buf, sizeof buf, "nug(%.3g)", c.sill);
    else if (c.kind == ModelKind::Power)
      std::snprintf(buf, sizeof buf, "pow(sill=%.3g, exponent=%.3g)", c.sill, c.range);
    else if (c.kind == ModelKind::Linear)
      std::snprintf(buf, sizeof buf, "lin(slope=%.3g)", c.sill);
    else
      std::snprintf(buf, sizeof buf, "%s(sill=%.3g, range=%.3g)", kind.c_str(), c.sill, c.range);
    out += buf;
  }
  return out.empty() ? "(none)" : out;
}

std::string spread_text(const Spread& s, int decimals, bool with_range) {
  if (!with_range) return fixed(s.median, decimals);
  return fixed(s.median, decimals) + " [" + fixed(s.q25, decimals) + "–" + fixed(s.q75, decimals) + "]";
}

const paper::ErrorSummaryRow* paper_row(const std::string& method) {
  for (const auto& r : paper::table6_compensation())
    if (r.name == method) return &r;
  return nullptr;
}

TextTable variogram_table(const VariogramComparison& v) {
  TextTable t({TextColumn("lag bin", v.lag_unit, Align::Left), TextColumn("pairs"), TextColumn("mean lag", v.lag_unit),
               TextColumn("gamma sim", "mm²"), TextColumn("model", "mm²"), TextColumn("gamma paper", "mm²")});
  for (const auto& r : v.rows)
    t.add_row({std::string("[") + fixed(r.lag_lo, 0) + ", " + fixed(r.lag_hi, 0) + ")", std::to_string(r.pairs),
               fixed(r.lag_mean, 1), fixed(r.gamma_mm2, 4), fixed(r.model_gamma_mm2, 4), fixed(r.paper_gamma_mm2, 4)});
  return t;
}

TextTable grid_step_table(const std::vector<GridStepRow>& rows) {
  TextTable t({TextColumn("step", "mm"), TextColumn("grid nodes"), TextColumn("mean |err|", "mm"),
               TextColumn("max |err|", "mm"), TextColumn("RMS", "mm")});
  for (const auto& r : rows)
    t.add_row({fixed(r.step_mm, 0), std::to_string(r.nodes), fixed(r.mean_abs_error_mm, 4), fixed(r.max_abs_error_mm, 4),
               fixed(r.rms_error_mm, 4)});
  return t;
}

TextTable table6_table(const Table6& t6, const std::string& metric, bool with_paper) {
  std::vector<TextColumn> cols{TextColumn("method", "", Align::Left), TextColumn("max", "mm"), TextColumn("mean", "mm"),
                               TextColumn("std", "mm"), TextColumn("refused")};
  if (with_paper) {
    cols.emplace_back("paper max", "mm");
    cols.emplace_back("paper mean", "mm");
    cols.emplace_back("paper std", "mm");
  }
  TextTable t(cols);
  const bool range = t6.runs > 1;
  for (const auto& r : t6.rows) {
    if (r.metric != metric) continue;
    std::vector<std::string> cells{r.method, spread_text(r.max_mm, 3, range), spread_text(r.mean_mm, 3, range),
                                   spread_text(r.std_mm, 3, range), std::to_string(r.failed_targets)};
    if (with_paper) {
      const auto* p = paper_row(r.method);
      cells.push_back(p ? fixed(p->max_mm, 3) : "");
      cells.push_back(p ? fixed(p->mean_mm, 3) : "");
      cells.push_back(p ? fixed(p->std_mm, 3) : "");
    }
    t.add_row(std::move(cells));
  }
  return t;
}

TextTable assembly_table(const std::vector<AssemblyRow>& rows) {
  TextTable t({TextColumn("stage", "", Align::Left), TextColumn("max", "mm"), TextColumn("mean", "mm"),
               TextColumn("std", "mm"), TextColumn("paper max", "mm"), TextColumn("paper mean", "mm"),
               TextColumn("paper std", "mm")});
  for (const auto& r : rows) {
    const paper::ErrorSummaryRow* p = nullptr;
    for (const auto& pr : paper::table8_assembly())
      if (r.stage == pr.name || (r.stage.rfind("after (distance-idw)", 0) == 0 && pr.name == "after")) p = &pr;
    t.add_row({r.stage, fixed(r.deviation.max_mm, 3), fixed(r.deviation.mean_mm, 3), fixed(r.deviation.std_mm, 3),
               p ? fixed(p->max_mm, 3) : "", p ? fixed(p->mean_mm, 3) : "", p ? fixed(p->std_mm, 3) : ""});
  }
  return t;
}

TextTable orientation_table(const OrientationExperiment& e) {
  TextTable t({TextColumn("orientation", "", Align::Left), TextColumn("method", "", Align::Left),
               TextColumn("space", "", Align::Left), TextColumn("max", "mm"), TextColumn("mean", "mm"),
               TextColumn("std", "mm"), TextColumn("refused")});
  for (const auto& r : e.rows)
    t.add_row({r.orientation, r.method, r.space, fixed(r.max_mm, 3), fixed(r.mean_mm, 3), fixed(r.std_mm, 3),
               std::to_string(r.refused)});
  return t;
}

/// The experiment's set-up and what it measured, one statement per entry (console and report).
std::vector<std::string> orientation_notes(const OrientationExperiment& e) {
  const auto& o = e.options;
  std::vector<std::string> notes;
  notes.push_back("SIMULATED, beyond the paper (SPEC section 8, item 5): " + std::to_string(o.training_poses) +
                  " training and " + std::to_string(o.validation_poses) +
                  " independent validation poses, positions uniform in the 500 mm cube; 'varying': RX, RY, RZ "
                  "each uniform within ±" + fixed(o.orientation_spread_deg, 0) +
                  "° of tool-down (180°, 0°, 0°), redrawn where IK fails (" +
                  std::to_string(e.rejected_orientation_draws) +
                  " draws rejected); 'constant': the same positions at tool-down. Vector kriging of the registered "
                  "3-D errors of the training poses (each measured once), locations = nominal positions (task, mm) "
                  "or nominal joints (joint, deg, eq. 16); residual |P' − P| at the validation poses.");
  std::string span;
  for (int k = 0; k < 6; ++k) span += (k ? ", " : "") + fixed(e.joint_span_deg[k], 0);
  notes.push_back("Varying orientation spans the joints by (" + span +
                  ") deg (J1..J6, max − min over the training poses); at the same position the true error moves by " +
                  fixed(e.orientation_effect_mean_mm, 3) + " mm mean / " + fixed(e.orientation_effect_max_mm, 3) +
                  " mm max between the drawn orientation and tool-down: the part a task-space field cannot see.");
  for (const auto& r : e.rows)
    if (!r.model.components().empty())
      notes.push_back("Fitted variogram (" + r.orientation + ", " + r.space + " space, mm², lag in " +
                      (r.space == "joint" ? "deg" : "mm") + "): " + short_model_text(r.model));
  return notes;
}

std::string metric_title(const std::string& metric) {
  if (metric == "distance") return "distance error to the fixed base point P0 (the tracker), the paper's metric";
  if (metric == "position") return "3-D position error |P' − P| in the registered frame";
  if (metric == "distance-robot-base") return "distance error to a robot-position base point, as measured";
  return "distance error to a robot-position base point re-commanded through each method (own base)";
}

const char* kMetrics[] = {"distance", "position", "distance-robot-base", "distance-own-base"};

}  // namespace

std::string reproduction_summary(const ReproductionResult& r) {
  std::string out;
  out += "errfield reproduce — SIMULATED ER20-C10 and laser tracker (seed " + std::to_string(r.options.seed) +
         ", " + std::to_string(r.table6.runs) + " runs)\n\n";
  out += "Tables 3/4: distance-error variogram, " + std::to_string(r.options.variogram_configurations) +
         " random configurations in the Table 2 ranges\n";
  for (const auto* v : {&r.joint_variogram, &r.task_variogram}) {
    out += "\n" + std::string(v == &r.joint_variogram ? "Table 3 (joint space)" : "Table 4 (task space)") +
           ", fitted " + short_model_text(v->fitted) + " [mm², lag in " + v->lag_unit + "]\n";
    out += variogram_table(*v).to_text();
  }
  out += "\nFig. 5: grid-step sweep, 500 mm cube, distance-error IDW at " + std::to_string(r.options.heldout_points) +
         " held-out points\n";
  out += grid_step_table(r.grid_steps).to_text();
  out += "\nTable 6: 125 grid points, 64 samples; median [25%–75%] over " + std::to_string(r.table6.runs) + " runs\n";
  for (const char* m : kMetrics) {
    out += "\n" + metric_title(m) + "\n";
    out += table6_table(r.table6, m, std::string(m) == "distance").to_text();
  }
  for (const auto& n : r.table6.notes) out += "  * " + n + "\n";
  out += "\nTable 8: assembly test, tool-tip deviation from 15 holes\n";
  out += assembly_table(r.assembly).to_text();
  out += "\nBeyond the paper (SIMULATED): compensation with varying tool orientation, task vs joint space;\n"
         "residual 3-D position error |P' − P| at the validation poses\n";
  out += orientation_table(r.beyond_orientation).to_text();
  for (const auto& n : orientation_notes(r.beyond_orientation)) out += "  * " + n + "\n";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f", r.seconds);
  out += "\n(" + std::string(buf) + " s)\n";
  return out;
}

namespace {

report::LinePlot variogram_plot(const VariogramComparison& v) {
  report::LinePlot p;
  p.title = std::string(v.space == "joint" ? "Table 3: variogram in joint space" : "Table 4: variogram in task space");
  p.x_axis = {"lag", v.lag_unit, 0.0};
  p.y_axis = {"semivariance", "mm²", std::nullopt, std::nullopt, true};
  report::Series sim{"simulated", {}, {}, report::SeriesStyle::Points, ""};
  report::Series paper{"paper", {}, {}, report::SeriesStyle::LinePoints, "#7f7f7f"};
  report::Series model{"fitted model", {}, {}, report::SeriesStyle::Dashed, "#000000"};
  for (const auto& row : v.rows) {
    const double centre = 0.5 * (row.lag_lo + row.lag_hi);
    if (row.pairs > 0) {
      sim.x.push_back(row.lag_mean);
      sim.y.push_back(row.gamma_mm2);
    }
    paper.x.push_back(centre);
    paper.y.push_back(row.paper_gamma_mm2);
  }
  const double hi = v.rows.empty() ? 1.0 : v.rows.back().lag_hi;
  for (int i = 0; i <= 100; ++i) {
    model.x.push_back(hi * i / 100.0);
    model.y.push_back(v.fitted.gamma(hi * i / 100.0));
  }
  p.series = {sim, model, paper};
  return p;
}

// A CSV cell of a number; empty when it is not finite. Text cells (method and stage names) go
// through csv_cell like every CSV writer's.
std::string finite_cell(double v) { return std::isfinite(v) ? format_number(v) : std::string(); }

std::string variogram_csv(const VariogramComparison& v) {
  std::string csv = "lag_lo,lag_hi,lag_mean,gamma,pairs,model_gamma,paper_gamma\n";
  for (const auto& row : v.rows)
    csv += finite_cell(row.lag_lo) + "," + finite_cell(row.lag_hi) + "," + finite_cell(row.lag_mean) + "," + finite_cell(row.gamma_mm2) + "," +
           std::to_string(row.pairs) + "," + finite_cell(row.model_gamma_mm2) + "," + finite_cell(row.paper_gamma_mm2) + "\n";
  return csv;
}

std::string grid_step_csv(const ReproductionResult& r) {
  std::string csv = "step_mm,nodes,mean_abs_error_mm,max_abs_error_mm,rms_error_mm\n";
  for (const auto& g : r.grid_steps)
    csv += finite_cell(g.step_mm) + "," + std::to_string(g.nodes) + "," + finite_cell(g.mean_abs_error_mm) + "," +
           finite_cell(g.max_abs_error_mm) + "," + finite_cell(g.rms_error_mm) + "\n";
  return csv;
}

struct Table6Csv {
  std::string headline, spread, points;
};

// table6.csv holds the two headline metrics only (distance, position), medians over the runs;
// every metric with its spread is in table6_spread.csv.
Table6Csv table6_csv(const ReproductionResult& r) {
  Table6Csv out;
  std::string& csv = out.headline;
  std::string& spread = out.spread;
  csv = "method,metric,max_mm,mean_mm,std_mm\n";
  spread = "method,metric,figure,median_mm,q25_mm,q75_mm,min_mm,max_mm,runs,refused_targets\n";
  for (const auto& row : r.table6.rows) {
    if (row.metric == "distance" || row.metric == "position")
      csv += csv_cell(row.method) + "," + csv_cell(row.metric) + "," + finite_cell(row.max_mm.median) + "," + finite_cell(row.mean_mm.median) + "," +
           finite_cell(row.std_mm.median) + "\n";
    for (auto [fig, s] : {std::pair<const char*, const Spread*>{"max", &row.max_mm}, {"mean", &row.mean_mm},
                          {"std", &row.std_mm}})
      spread += csv_cell(row.method) + "," + csv_cell(row.metric) + "," + fig + "," + finite_cell(s->median) + "," + finite_cell(s->q25) + "," +
                finite_cell(s->q75) + "," + finite_cell(s->min) + "," + finite_cell(s->max) + "," + std::to_string(r.table6.runs) + "," +
                std::to_string(row.failed_targets) + "\n";
  }
  out.points = "method,sample,distance_error_mm,position_error_mm\n";
  for (const auto& m : r.table6.first_run)
    for (std::size_t i = 0; i < m.distance_error_mm.size(); ++i)
      out.points += csv_cell(m.method) + "," + std::to_string(i + 1) + "," + finite_cell(m.distance_error_mm[i]) + "," +
                    finite_cell(m.position_error_mm[i]) + "\n";
  return out;
}

std::string assembly_csv(const ReproductionResult& r) {
  std::string csv = "stage,max_mm,mean_mm,std_mm\n";
  for (const auto& a : r.assembly)
    csv += csv_cell(a.stage) + "," + finite_cell(a.deviation.max_mm) + "," + finite_cell(a.deviation.mean_mm) + "," + finite_cell(a.deviation.std_mm) + "\n";
  return csv;
}

std::string orientation_csv(const ReproductionResult& r) {
  const auto& e = r.beyond_orientation;
  std::string csv =
      "orientation,orientation_spread_deg,method,space,training_poses,validation_poses,max_mm,mean_mm,std_mm,"
      "refused_targets\n";
  for (const auto& row : e.rows)
    csv += csv_cell(row.orientation) + "," + finite_cell(row.orientation == "varying" ? e.options.orientation_spread_deg : 0.0) + "," +
           csv_cell(row.method) + "," + csv_cell(row.space) + "," + std::to_string(e.options.training_poses) + "," +
           std::to_string(e.options.validation_poses) + "," + finite_cell(row.max_mm) + "," + finite_cell(row.mean_mm) + "," +
           finite_cell(row.std_mm) + "," + std::to_string(row.refused) + "\n";
  return csv;
}

report::LinePlot grid_step_plot(const ReproductionResult& r) {
  report::LinePlot p;
  p.title = "Fig. 5: prediction error against grid step";
  p.x_axis = {"grid step", "mm", 0.0};
  p.y_axis = {"prediction error", "mm", std::nullopt, std::nullopt, true};
  report::Series mean{"mean |error|", {}, {}, report::SeriesStyle::LinePoints, ""};
  report::Series rms{"RMS", {}, {}, report::SeriesStyle::LinePoints, ""};
  report::Series mx{"max |error|", {}, {}, report::SeriesStyle::LinePoints, ""};
  for (const auto& g : r.grid_steps) {
    mean.x.push_back(g.step_mm), mean.y.push_back(g.mean_abs_error_mm);
    rms.x.push_back(g.step_mm), rms.y.push_back(g.rms_error_mm);
    mx.x.push_back(g.step_mm), mx.y.push_back(g.max_abs_error_mm);
  }
  p.series = {mean, rms, mx};
  return p;
}

// Fig. 9 (distance) or the 3-D position error, per sample of the first run.
report::LinePlot per_sample_plot(const ReproductionResult& r, bool dist) {
  report::LinePlot p;
  p.title = dist ? "Fig. 9: distance error per sample (run 1)" : "3-D position error per sample (run 1)";
  p.x_axis = {"sample", ""};
  p.y_axis = {dist ? "|distance error|" : "|position error|", "mm", std::nullopt, std::nullopt, true};
  for (const auto& m : r.table6.first_run) {
    report::Series s{m.method, {}, {}, report::SeriesStyle::LinePoints, ""};
    const auto& v = dist ? m.distance_error_mm : m.position_error_mm;
    for (std::size_t i = 0; i < v.size(); ++i) {
      s.x.push_back(static_cast<double>(i + 1));
      s.y.push_back(std::abs(v[i]));
    }
    p.series.push_back(std::move(s));
  }
  p.height_px = 460;
  return p;
}

void add_table6(report::HtmlReport& html, const ReproductionResult& r) {
  html.add_heading("Table 6: compensation accuracy");
  html.add_paragraph("Median over " + std::to_string(r.table6.runs) +
                     " runs (new samples, measurement noise and repeatability on the same simulated robot), with the "
                     "25%–75% range in brackets.");
  for (const auto& note : r.table6.notes) html.add_paragraph(note);
  for (const char* m : kMetrics) html.add_table(table6_table(r.table6, m, std::string(m) == "distance"), metric_title(m));
  for (const char* which : {"distance", "position"}) {
    const bool dist = std::string(which) == "distance";
    html.add_figure(per_sample_plot(r, dist),
                    dist ? "Absolute distance error (as measured) at each of the 64 samples after each method."
                         : "Full 3-D position error at each sample: what the radial correction of the "
                           "distance methods cannot remove.");
  }
}

void add_assembly(report::HtmlReport& html, const ReproductionResult& r) {
  html.add_heading("Table 8: assembly test");
  html.add_table(assembly_table(r.assembly), "Tool-tip deviation from the 15 holes");
  if (r.assembly.empty()) return;
  report::BarChart c;
  c.title = "Fig. 11: tool-tip deviation per hole";
  c.category_label = "hole";
  c.y_axis = {"deviation", "mm"};
  for (std::size_t i = 0; i < r.assembly.front().per_hole_mm.size(); ++i) c.categories.push_back(std::to_string(i + 1));
  for (const auto& a : r.assembly) c.series.push_back({a.stage, a.per_hole_mm, ""});
  html.add_figure(c, "Deviation of the simulated tool tip from each hole before and after compensation.");
}

std::string report_html(const ReproductionResult& r) {
  report::HtmlReport html("errfield: reproduction of Wang et al. (2026) on a simulated ER20-C10", true);
  html.add_heading("Set-up");
  for (const auto& s : r.setup) html.add_paragraph(s);
  html.add_heading("Tables 3 and 4: spatial similarity of the distance error");
  for (const auto* v : {&r.joint_variogram, &r.task_variogram}) {
    html.add_figure(variogram_plot(*v), "Empirical variogram of the simulated distance error (points), the fitted model " +
                                            short_model_text(v->fitted) + " (dashed) and the paper's values (grey).");
    html.add_table(variogram_table(*v), v->space == "joint" ? "Table 3 (joint space)" : "Table 4 (task space)");
  }
  html.add_heading("Fig. 5: choice of the grid step");
  html.add_figure(grid_step_plot(r), "Distance-error IDW from grids of each step, evaluated at held-out points of the 500 mm cube "
                                     "against the simulated robot's true distance error. The paper chose 125 mm.");
  html.add_table(grid_step_table(r.grid_steps), "Fig. 5 data");
  add_table6(html, r);
  add_assembly(html, r);
  html.add_heading("Beyond the paper: compensation with varying tool orientation (SIMULATED)");
  html.add_paragraph("The paper compensates at one constant tool orientation, where a position fixes the joints and "
                     "task and joint space carry the same information. Here the orientation varies from target to "
                     "target, so one position is reached by different joint configurations with different errors.");
  for (const auto& note : orientation_notes(r.beyond_orientation)) html.add_paragraph(note);
  html.add_table(orientation_table(r.beyond_orientation),
                 "Residual 3-D position error at the validation poses (SIMULATED): varying vs constant orientation, "
                 "vector kriging in task and in joint space");
  // The command that reproduces the page; no run time or date: the same seed gives the same bytes
  // (the time is printed on the console only).
  html.add_heading("Run");
  html.add_preformatted("errfield reproduce --seed " + std::to_string(r.options.seed) + " --runs " +
                        std::to_string(r.options.runs));
  return html.to_html();
}

// The directory is made if needed, and removed again (when still empty) if the files cannot go in.
void commit_into(AtomicFileSet& outputs, const std::filesystem::path& dir) {
  std::error_code ec;
  const bool existed = std::filesystem::is_directory(dir, ec);
  if (!existed) {
    std::filesystem::create_directories(dir, ec);
    if (ec) throw Error("cannot create output directory '" + dir.string() + "': " + ec.message());
  }
  try {
    outputs.commit();
  } catch (...) {
    if (!existed) std::filesystem::remove(dir, ec);  // only if still empty
    throw;
  }
}

}  // namespace

std::vector<std::filesystem::path> write_reproduction(const ReproductionResult& r, const std::filesystem::path& dir) {
  // Every file is assembled in memory first and then replaced all or none (AtomicFileSet): a
  // failure or a signal never leaves this run's tables next to an older run's report.
  AtomicFileSet outputs;
  std::vector<std::filesystem::path> written;
  auto put = [&](const std::string& name, std::string content) {
    outputs.add(dir / name, std::move(content));
    written.push_back(dir / name);
  };
  put("table3.csv", variogram_csv(r.joint_variogram));
  put("table4.csv", variogram_csv(r.task_variogram));
  put("fig5.csv", grid_step_csv(r));
  Table6Csv table6 = table6_csv(r);
  put("table6.csv", std::move(table6.headline));
  put("table6_spread.csv", std::move(table6.spread));
  put("table6_points.csv", std::move(table6.points));
  put("table8.csv", assembly_csv(r));
  put("beyond_orientation.csv", orientation_csv(r));
  put("report.html", report_html(r));
  commit_into(outputs, dir);
  return written;
}

}  // namespace errfield::reproduction
