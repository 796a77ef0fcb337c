// `errfield variogram`: empirical variogram of one or several value columns over any number of
// coordinate columns, written as CSV lag_lo,lag_hi,lag_mean,gamma,pairs; directional variograms
// (--alpha/--beta as gstat, --per-coordinate) add one block of rows per direction and a column
// naming it.

#include <charconv>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include "cli/cli_support.hpp"
#include "cli/covariate_sources.hpp"
#include "cli/duplicate_locations.hpp"
#include "cli/grid_map_svg.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/pseudo_variogram_table.hpp"
#include "cli/point_layer.hpp"
#include "cli/variogram_svg.hpp"
#include "cli/value_cells.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/gstat_lag_bins.hpp"
#include "errfield/heterotopic_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/trend_residuals.hpp"
#include "errfield/variogram_cloud.hpp"
#include "errfield/variogram_direction.hpp"

namespace errfield::cli {
namespace {

struct VariogramArgs {
  std::string input, coords, value, bins, estimator = "matheron", convention, out;  // convention "": see run_variogram
  bool per_component = false;
  bool cross = false;  // --cross: direct and cross variograms of every value column pair
  double subsample = 1.0;
  std::uint64_t seed = 0;
  int threads = 0;
  std::uint64_t max_stored = 25'000'000;
  std::string alpha, beta;
  double tol_hor = std::nan(""), tol_ver = std::nan(""), tol_axis = 45.0;
  bool per_coordinate = false;
  std::string covariates;  // --covariates: residuals of the OLS trend 1 + these columns
  bool cloud = false;        // --cloud: every pair, not bins
  std::string map;           // --map DX,DY: variogram map cell widths
  double cutoff = std::nan("");  // --cutoff: of --cloud / --map, or with --width gstat's bins
  double width = std::nan("");   // --width: gstat's bin width (default cutoff / 15)
  bool pseudo = false;           // --pseudo: pseudo cross-variograms of columns never co-located
  std::string duplicates = "keep";  // --duplicates keep|average|first|refuse
  std::uint64_t max_pairs = VariogramCloudOptions{}.max_pairs;
  std::string plot;          // --plot FILE.svg
};

std::vector<double> parse_angles(const std::string& text, const char* option) {
  std::vector<double> out;
  for (const auto& item : split_list(text, option)) {
    double v = 0.0;
    const auto res = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || res.ec != std::errc() || res.ptr != item.data() + item.size() || !std::isfinite(v))
      throw ArgumentError(std::string(option) + ": '" + item + "' in '" + text +
                          "' is not a finite angle in degrees; expected e.g. 0,45,90,135");
    out.push_back(v);
  }
  return out;
}

/// One variogram per direction, with the label of its block of rows.
struct DirectionalRun {
  VariogramDirection direction;
  std::string alpha, beta, coordinate;
};

std::vector<DirectionalRun> directions(const VariogramArgs& a, const std::vector<std::string>& coords) {
  const bool gstat = !a.alpha.empty() || !a.beta.empty();
  if (a.per_coordinate && gstat)
    throw ArgumentError("--per-coordinate cannot be combined with --alpha/--beta; run them separately");
  if (!gstat && (!std::isnan(a.tol_hor) || !std::isnan(a.tol_ver)))
    throw ArgumentError("--tol-hor/--tol-ver need --alpha or --beta");
  std::vector<DirectionalRun> runs;
  if (a.per_coordinate) {
    const int d = static_cast<int>(coords.size());
    for (int k = 0; k < d; ++k)
      naming_options([&] { runs.push_back({VariogramDirection::axis(k, d, a.tol_axis), "", "", coords[static_cast<std::size_t>(k)]}); },
                     {{"variogram direction: tol", "--tol-axis"}});
    return runs;
  }
  if (!gstat) return {DirectionalRun{}};
  // gstat's defaults: tol.hor = 90 / length(alpha), tol.ver = 90 / length(beta).
  const std::vector<double> alphas = a.alpha.empty() ? std::vector<double>{0.0} : parse_angles(a.alpha, "--alpha");
  const std::vector<double> betas = a.beta.empty() ? std::vector<double>{0.0} : parse_angles(a.beta, "--beta");
  const double tol_hor = !std::isnan(a.tol_hor) ? a.tol_hor : a.alpha.empty() ? 90.0 : 90.0 / static_cast<double>(alphas.size());
  const double tol_ver = !std::isnan(a.tol_ver) ? a.tol_ver : a.beta.empty() ? 90.0 : 90.0 / static_cast<double>(betas.size());
  for (double al : alphas)
    for (double be : betas)
      naming_options([&] { runs.push_back({VariogramDirection::gstat(al, tol_hor, be, tol_ver),
                                           a.alpha.empty() ? "" : format_number(al),
                                           a.beta.empty() ? "" : format_number(be), ""}); },
                     {{"variogram direction: tol_hor", "--tol-hor"}, {"variogram direction: tol_ver", "--tol-ver"}});
  return runs;
}

double parse_bins_number(std::string_view text, std::string_view spec) {
  double v = 0.0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto res = std::from_chars(first, last, v);
  if (text.empty() || res.ec != std::errc() || res.ptr != last || !std::isfinite(v))
    throw ArgumentError("--bins: '" + std::string(text) + "' in '" + std::string(spec) +
                        "' is not a finite number; expected lo:max:width (e.g. 0:2200:200) or a "
                        "list of edges (e.g. 0,10,20,50)");
  return v;
}

/// "lo:max:width" -> uniform bins; "e0,e1,..." -> explicit edges.
LagBins parse_bins_option(const std::string& spec) {
  if (spec.find(':') != std::string::npos) {
    std::vector<std::string_view> parts;
    std::string_view rest(spec);
    while (true) {
      const auto c = rest.find(':');
      parts.push_back(rest.substr(0, c));
      if (c == std::string_view::npos) break;
      rest.remove_prefix(c + 1);
    }
    if (parts.size() != 3)
      throw ArgumentError("--bins: '" + spec +
                          "' has " + std::to_string(parts.size()) +
                          " ':'-separated fields; expected lo:max:width, e.g. 0:2200:200");
    return LagBins::uniform(parse_bins_number(parts[0], spec), parse_bins_number(parts[1], spec),
                            parse_bins_number(parts[2], spec));
  }
  std::vector<double> edges;
  for (const auto& item : split_list(spec, "--bins")) edges.push_back(parse_bins_number(item, spec));
  return LagBins::from_edges(std::move(edges));
}

std::string cell(double v) { return std::isnan(v) ? std::string() : format_number(v); }

// --cloud and --map: the options that shape bins are refused by name.
void refuse_bin_options(const VariogramArgs& a, const std::string& what) {
  if (a.cloud && !a.map.empty()) throw ArgumentError("--cloud and --map are two outputs; run them separately");
  const auto refuse = [&](bool given, const std::string& option, const std::string& why) {
    if (given) throw ArgumentError(option + " does not apply to " + what + ": " + why);
  };
  refuse(a.cross, "--cross", "the cloud and the map are of the (summed) direct semivariance");
  refuse(a.per_component, "--per-component", "the cloud and the map write one gamma per pair or cell");
  refuse(a.estimator != "matheron", "--estimator " + a.estimator, "they show 0.5 (z_i - z_j)^2 itself, before any estimator");
  refuse(a.subsample != 1.0, "--subsample", "every pair is shown; use --cutoff to see fewer");
  refuse(a.per_coordinate, "--per-coordinate", "use --alpha/--beta (one direction) with --cloud");
  refuse(!a.convention.empty(), "--convention", "there are no bins");
  refuse(!std::isnan(a.width), "--width", "there are no bins (--map takes its cell widths as --map DX,DY)");
  refuse(a.pseudo, "--pseudo", "the cloud and the map are of one variable's pairs");
  if (a.cloud) refuse(!a.plot.empty(), "--plot", "the plot is of the binned variogram or of the map");
  if (a.cloud) refuse(!a.bins.empty() && !std::isnan(a.cutoff), "--bins", "--cutoff already sets the cloud's cutoff");
  if (!a.cloud) {
    refuse(!a.bins.empty(), "--bins", "give --cutoff C and the cell widths --map DX,DY");
    refuse(!a.alpha.empty() || !a.beta.empty(), "--alpha/--beta", "the map shows every direction");
    if (std::isnan(a.cutoff)) throw ArgumentError("--map needs --cutoff C: the map covers lag vectors from -C to C in x and y");
  }
}

// A table and the line that sums it up on standard error.
struct SummarizedTable {
  OutputTable table;
  std::string summary;
  std::string svg;  // --map --plot: the picture of the map
};

SummarizedTable cloud_table(const VariogramArgs& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                            const std::vector<DirectionalRun>& runs) {
  VariogramCloudOptions o;
  // gstat's cutoff: given, or the last edge of --bins, or a third of the bounding-box diagonal.
  o.cutoff = !std::isnan(a.cutoff) ? a.cutoff : a.bins.empty() ? LagBins::gstat_default(x).edges().back()
                                                               : parse_bins_option(a.bins).edges().back();
  std::vector<std::string> left, right, dist, gamma, alpha, beta;
  for (const DirectionalRun& run : runs) {
    o.direction = run.direction;
    o.max_pairs = a.max_pairs - left.size();  // one budget for all directions together
    VariogramCloud c;
    try {
      naming_options([&] { c = variogram_cloud(x, z, o); }, {{"variogram cloud: cutoff", "--cutoff"},
                                                              {"variogram direction: alpha/beta", "--alpha/--beta"},
                                                              {"variogram direction: tol_ver", "--tol-ver"}});
    } catch (const ResourceError& e) {
      if (runs.size() == 1) throw;
      throw ResourceError(std::string(e.what()) + " (the budget left after the earlier directions, which have " +
                          std::to_string(left.size()) + " of --max-pairs " + std::to_string(a.max_pairs) + ")");
    }
    for (std::size_t k = 0; k < c.size(); ++k) {
      left.push_back(std::to_string(c.left[k] + 1));
      right.push_back(std::to_string(c.right[k] + 1));
      dist.push_back(format_number(c.dist[k]));
      gamma.push_back(format_number(c.gamma[k]));
      alpha.push_back(run.alpha);
      beta.push_back(run.beta);
    }
  }
  SummarizedTable out;
  out.table.add_column("left", left);
  out.table.add_column("right", right);
  out.table.add_column("dist", dist);
  out.table.add_column("gamma", gamma);
  if (!a.alpha.empty()) out.table.add_column("direction", alpha);
  if (!a.beta.empty()) out.table.add_column("dip", beta);
  out.summary = std::to_string(dist.size()) + " pairs within the cutoff " + format_number(o.cutoff);
  return out;
}

// --map DX,DY: the cell widths, each > 0.
std::vector<double> map_cell_widths(const VariogramArgs& a) {
  std::vector<double> w;
  for (const auto& item : split_list(a.map, "--map")) {
    double v = 0.0;
    const auto res = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || res.ec != std::errc() || res.ptr != item.data() + item.size() || !(v > 0.0) || !std::isfinite(v))
      throw ArgumentError("--map: '" + item + "' in '" + a.map + "' is not a cell width > 0; expected DX,DY (e.g. 50,50)");
    w.push_back(v);
  }
  if (w.size() != 2) throw ArgumentError("--map: '" + a.map + "' has " + std::to_string(w.size()) + " widths; expected DX,DY");
  return w;
}

SummarizedTable map_table(const VariogramArgs& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                          const std::vector<std::string>& coord_names) {
  if (coord_names.size() != 2)
    throw ArgumentError("--map: " + std::to_string(coord_names.size()) +
                        " --coords columns; a variogram map is of 2-D lag vectors (give 2 coordinates)");
  VariogramMapOptions o;
  o.cutoff = a.cutoff;
  const std::vector<double> w = map_cell_widths(a);
  o.width_x = w[0];
  o.width_y = w[1];
  VariogramMap m;
  naming_options([&] { m = variogram_map(x, z, o); },
                 {{"variogram map: cutoff", "--cutoff"}, {"variogram map: cell width", "--map"}});
  std::vector<std::string> dx, dy, np, gamma;
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.columns; ++c) {
      const auto k = static_cast<std::size_t>(r) * static_cast<std::size_t>(m.columns) + static_cast<std::size_t>(c);
      dx.push_back(format_number(m.lag_x[static_cast<std::size_t>(c)]));
      dy.push_back(format_number(m.lag_y[static_cast<std::size_t>(r)]));
      np.push_back(std::to_string(m.pairs[k]));
      gamma.push_back(cell(m.gamma[k]));
    }
  SummarizedTable out;
  out.table.add_column("dx", dx);
  out.table.add_column("dy", dy);
  out.table.add_column("np", np);
  out.table.add_column("gamma", gamma);
  out.summary = std::to_string(m.columns) + " x " + std::to_string(m.rows) + " cells of " + format_number(o.width_x) +
                " x " + format_number(o.width_y) + " over lags -" + format_number(o.cutoff) + " .. " + format_number(o.cutoff);
  if (!a.plot.empty()) {
    // Rows from the largest dy down, dx increasing: the picture's order.
    GridMapPlot map;
    map.nx = static_cast<std::size_t>(m.columns);
    map.ny = static_cast<std::size_t>(m.rows);
    map.x_min = m.lag_x.front();
    map.dx = o.width_x;
    map.y_min = m.lag_y.back();
    map.dy = o.width_y;
    for (std::size_t k = 0; k < m.gamma.size(); ++k)
      map.values.push_back(m.pairs[k] > 0 ? m.gamma[k] : std::numeric_limits<double>::quiet_NaN());
    map.x_label = "dx (lag along " + coord_names[0] + ")";
    map.y_label = "dy (lag along " + coord_names[1] + ")";
    map.value_label = "gamma";
    map.title = "variogram map of " + a.value + " (" + std::to_string(x.rows()) + " points; white: no pair)";
    out.svg = grid_map_svg_text(map);
  }
  return out;
}

// --cloud: one row per pair within the cutoff (gstat's variogram(..., cloud = TRUE)); --map DX,DY:
// the variogram map (gstat's map = TRUE).
void run_cloud_or_map(const VariogramArgs& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                      const std::vector<DirectionalRun>& runs, const std::vector<std::string>& coord_names) {
  const std::string what = a.cloud ? "--cloud" : "--map";
  refuse_bin_options(a, what);
  const SummarizedTable out = a.cloud ? cloud_table(a, x, z, runs) : map_table(a, x, z, coord_names);
  if (a.out.empty()) {
    std::cout << out.table.to_csv();
    if (!out.svg.empty()) {
      require_standard_output();
      write_file_atomically(a.plot, out.svg);
    }
  } else if (out.svg.empty()) {
    out.table.write(a.out);
    std::cerr << "variogram " << what << ": " << x.rows() << " points, " << out.summary << ", written to " << a.out << "\n";
  } else {
    AtomicFileSet files;  // the map's table and its picture: both or neither
    files.add(a.out, out.table.to_csv());
    files.add(a.plot, out.svg);
    files.commit();
    std::cerr << "variogram " << what << ": " << x.rows() << " points, " << out.summary << " (picture " << a.plot
              << "), written to " << a.out << "\n";
  }
}

/// --bins without --convention counts a lag equal to an inner edge in the bin above it ([lo, hi), the
/// paper's tables) where gstat counts it in the bin below ((lo, hi]): on lattice data (integer
/// coordinates) that moves many pairs (coalash's first bin: 719 pairs against gstat's 369). Says so,
/// with the first bin that differs, when the two conventions count differently.
void warn_lags_on_edges(const Eigen::MatrixXd& x, const Eigen::MatrixXd& z, const LagBins& bins,
                        EmpiricalVariogramOptions options, const DirectionalRun& run,
                        const std::vector<std::uint64_t>& half_open_pairs, bool heterotopic) {
  options.convention = BinConvention::Gstat;
  options.direction = run.direction;
  const EmpiricalVariogram g = heterotopic ? heterotopic_variogram(x, z, bins, options).variogram
                                           : empirical_variogram(x, z, bins, options);
  for (std::size_t k = 0; k < g.bins.size() && k < half_open_pairs.size(); ++k)
    if (g.bins[k].pairs != half_open_pairs[k]) {
      std::cerr << "variogram: warning: lags fall exactly on --bins edges: bin " << k + 1 << " [" << format_number(bins.lag_lo(k))
                << ", " << format_number(bins.lag_hi(k)) << ") has " << half_open_pairs[k]
                << " pairs with the half-open bins [lo, hi) used (--convention paper, the default with --bins) but "
                << g.bins[k].pairs << " with gstat's (lo, hi] (--convention gstat, as R gstat's boundaries = and "
                << "--cutoff/--width); give --convention to choose and silence this\n";
      return;
    }
}

/// The bins of --bins, or gstat's of --cutoff C [--width W] (width default C/15, cutoff default a
/// third of the bounding-box diagonal); none given: nothing (the caller's default).
std::optional<LagBins> bins_from_options(const VariogramArgs& a, const Eigen::MatrixXd& x) {
  const bool gstat = !std::isnan(a.cutoff) || !std::isnan(a.width);
  if (gstat && !a.bins.empty())
    throw ArgumentError("--bins with --cutoff/--width: give one or the other (--cutoff C --width W is gstat's "
                        "variogram(..., cutoff = C, width = W): bins [0,W], (W,2W], ... up to C)");
  if (!a.bins.empty()) return parse_bins_option(a.bins);
  if (!gstat) return std::nullopt;
  const double cutoff = !std::isnan(a.cutoff) ? a.cutoff : LagBins::gstat_default(x).edges().back();
  const double width = !std::isnan(a.width) ? a.width : cutoff / 15.0;
  std::optional<LagBins> bins;
  naming_options([&] { bins = gstat_cutoff_width_bins(cutoff, width); },
                 {{"lag bins: cutoff", "--cutoff"}, {"lag bins: width", "--width"}});
  return bins;
}

// --pseudo: the direct variograms and the pseudo cross-variograms, one block of rows per variogram.
void run_pseudo(const VariogramArgs& a, const CsvTable& table, const Eigen::MatrixXd& x, const Eigen::MatrixXd& z,
                const std::vector<std::string>& value_names, const std::optional<LagBins>& bins, BinConvention convention) {
  const auto refuse = [&](bool given, const std::string& option, const std::string& why) {
    if (given) throw ArgumentError(option + " does not apply to --pseudo: " + why);
  };
  refuse(a.cross, "--cross", "--pseudo already writes every pair's (pseudo) cross-variogram");
  refuse(a.per_component, "--per-component", "each variogram has its own rows (column id)");
  refuse(a.estimator != "matheron", "--estimator " + a.estimator, "the pseudo cross-variogram is a mean of squared differences (Matheron)");
  refuse(a.subsample != 1.0, "--subsample", "every pair is used");
  refuse(!a.alpha.empty() || !a.beta.empty() || a.per_coordinate, "--alpha/--beta/--per-coordinate",
         "the pseudo cross-variograms are omnidirectional here");
  refuse(!a.covariates.empty(), "--covariates", "residuals of a trend are not supported with --pseudo");
  refuse(!a.plot.empty(), "--plot", "plot each variogram's rows separately");
  std::string note;
  const OutputTable out = with_source(a.input, [&] { return pseudo_variogram_table(x, z, value_names, bins, convention, note); });
  std::cerr << note;
  if (a.out.empty()) {
    std::cout << out.to_csv();
    return;
  }
  out.write(a.out);
  std::cerr << "variogram --pseudo: " << table.row_count() << " rows, " << value_names.size() << " direct and "
            << value_names.size() * (value_names.size() - 1) / 2 << " pseudo cross-variogram(s) ("
            << (bins ? "the bins given" : "gstat's default bins of each") << "), written to " << a.out << "\n";
}

EmpiricalVariogramOptions variogram_options(const VariogramArgs& a, const std::vector<std::string>& value_names) {
  EmpiricalVariogramOptions options;
  options.estimator = estimator_from_name(a.estimator);
  // Without --bins (gstat's default bins, or --cutoff/--width), gstat's boundaries unless --convention says otherwise.
  options.convention = convention_from_name(!a.convention.empty() ? a.convention : a.bins.empty() ? "gstat" : "paper");
  options.pair_fraction = a.subsample;
  options.seed = a.seed;
  check_thread_count("--threads", a.threads);
  options.threads = a.threads;
  options.max_stored_differences = a.max_stored;
  if (a.pseudo && value_names.size() < 2)
    throw ArgumentError("--pseudo needs at least 2 --value columns (variables measured at different rows); got '" + a.value + "'");
  if (a.cross) {
    if (value_names.size() < 2)
      throw ArgumentError("--cross needs at least 2 --value columns (their cross-variograms); got '" + a.value + "'");
    if (options.estimator != VariogramEstimator::Matheron)
      throw ArgumentError("--cross with --estimator " + a.estimator +
                          ": cross-variograms are means of products of differences (Matheron); the robust "
                          "estimators transform |z_i - z_j| and have no signed cross counterpart; use --estimator matheron");
    options.cross_variograms = true;
  }
  naming_options([&] { options.validate(); }, {{"variogram options: pair_fraction", "--subsample"},
                                               {"pair_fraction", "--subsample"},
                                               {"variogram options: threads", "--threads"}});
  return options;
}

// The samples as the variogram sees them: coordinates, values (or residuals of --covariates' trend)
// and the directions asked for.
struct VariogramSamples {
  std::vector<DirectionalRun> runs;
  Eigen::MatrixXd x, z;
  bool heterotopic = false;
};

VariogramSamples read_variogram_samples(const VariogramArgs& a, const PointTable& points,
                                        const std::vector<std::string>& value_names,
                                        const std::vector<std::string>& coord_names) {
  const CsvTable& table = points.table;
  CoordinateSystem crs;  // the layer's; a covariate raster in another CRS is refused
  crs.add(points.crs, "--input " + a.input, a.input);
  if (const std::string w = crs.geographic_warning(); !w.empty()) std::cerr << "errfield variogram: " << w << "\n";
  if (table.row_count() < 2)
    throw InputError(a.input + ": " + std::to_string(table.row_count()) +
                         " data row(s); the variogram needs at least 2 points",
                     a.input);
  VariogramSamples s;
  s.runs = directions(a, coord_names);
  s.x = table.numeric_columns(coord_names);
  // With 2 or more --value columns an empty cell is that column not measured there (heterotopic
  // data); each variogram is then over its own pairs. One column, or the trend of --covariates
  // (which needs every value), keeps refusing empty cells.
  s.z = a.covariates.empty() && value_names.size() >= 2 ? numeric_columns_with_gaps(table, value_names)
                                                        : table.numeric_columns(value_names);
  apply_duplicates_option(a.duplicates, "variogram", !a.covariates.empty(), table, s.x, s.z);
  s.heterotopic = s.z.array().isNaN().any();
  if (!a.covariates.empty()) {
    // gstat's variogram(z ~ cov): the variogram of the residuals of the ordinary least-squares trend.
    // COL or NAME=RASTER (the pixel at each point), as interpolate's external drift takes them.
    const CovariateSources sources = covariate_sources(split_column_list(a.covariates, "--covariates"), &crs);
    const Eigen::MatrixXd covariates = covariate_values(sources, table, s.x, points.labels("sample"));
    s.z = with_source(a.input, [&] { return ols_trend_residuals(s.z, covariates, sources.names); });
  }
  return s;
}

// The cells of the binned variogram, one row per bin and direction.
struct BinnedCells {
  std::vector<std::string> lo, hi, mean, gamma, pairs, alpha, beta, coordinate;
  std::vector<std::vector<std::string>> per_component, cross;
  // Heterotopic: pairs and mean lag of each direct and cross variogram.
  std::vector<std::vector<std::string>> component_pairs, component_lag, cross_pairs, cross_lag;
  std::uint64_t total = 0;
  VariogramPlot plot;
  std::vector<std::uint64_t> first_run_pairs;  // the first direction's pair counts (the --bins edge check)
};

// A direction as the legend of a picture of several names it.
std::string direction_name(const DirectionalRun& run) {
  if (!run.coordinate.empty()) return "along " + run.coordinate;
  std::string name;
  if (!run.alpha.empty()) name = "direction " + run.alpha;
  if (!run.beta.empty()) name += (name.empty() ? "dip " : ", dip ") + run.beta;
  return name.empty() ? "all directions" : name;
}

void add_bin_cells(const VariogramArgs& a, const DirectionalRun& run, bool first_run, const EmpiricalVariogram& v,
                   const HeterotopicVariogram& h, bool heterotopic, BinnedCells& t) {
  const std::size_t values = t.per_component.size();
  for (std::size_t b = 0; b < v.bins.size(); ++b) {
    const VariogramBin& bin = v.bins[b];
    t.lo.push_back(format_number(bin.lag_lo));
    t.hi.push_back(format_number(bin.lag_hi));
    t.mean.push_back(cell(bin.lag_mean));
    t.gamma.push_back(cell(bin.gamma));
    t.pairs.push_back(std::to_string(bin.pairs));
    t.alpha.push_back(run.alpha);
    t.beta.push_back(run.beta);
    t.coordinate.push_back(run.coordinate);
    for (int c = 0; c < v.components(); ++c)
      t.per_component[static_cast<std::size_t>(c)].push_back(cell(v.component_gamma(static_cast<Eigen::Index>(b), c)));
    for (std::size_t c = 0; c < t.cross.size() && a.cross; ++c)
      t.cross[c].push_back(cell(v.cross_gamma(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(c))));
    if (heterotopic) {
      const auto k = static_cast<Eigen::Index>(b);
      for (std::size_t c = 0; c < values; ++c) {
        t.component_pairs[c].push_back(format_number(h.component_pairs(k, static_cast<Eigen::Index>(c))));
        t.component_lag[c].push_back(cell(h.component_lag(k, static_cast<Eigen::Index>(c))));
      }
      for (std::size_t c = 0; c < t.cross.size() && a.cross; ++c) {
        t.cross_pairs[c].push_back(format_number(h.cross_pairs(k, static_cast<Eigen::Index>(c))));
        t.cross_lag[c].push_back(cell(h.cross_lag(k, static_cast<Eigen::Index>(c))));
      }
    }
    t.total += bin.pairs;
    if (b == 0) t.plot.series.push_back({direction_name(run), {}});
    if (bin.pairs > 0) t.plot.series.back().bins.push_back({bin.lag_mean, bin.gamma, bin.pairs});
    if (first_run) t.first_run_pairs.push_back(bin.pairs);
  }
}

BinnedCells binned_variograms(const VariogramArgs& a, const VariogramSamples& s, const LagBins& bins,
                              EmpiricalVariogramOptions& options, std::size_t values) {
  BinnedCells t;
  t.per_component.resize(values);
  t.cross.resize(values * (values - 1) / 2);
  t.component_pairs.resize(values);
  t.component_lag.resize(values);
  t.cross_pairs.resize(t.cross.size());
  t.cross_lag.resize(t.cross.size());
  for (const DirectionalRun& run : s.runs) {
    options.direction = run.direction;
    EmpiricalVariogram v;
    HeterotopicVariogram h;
    naming_options([&] {
                     if (s.heterotopic) {
                       h = heterotopic_variogram(s.x, s.z, bins, options);
                       v = h.variogram;
                     } else {
                       v = empirical_variogram(s.x, s.z, bins, options);
                     }
                   },
                   {{"max_stored_differences", "--max-stored"}, {"pair_fraction (--subsample)", "--subsample"},
                    {"variogram direction: alpha/beta", "--alpha/--beta"},
                    {"variogram direction: tol_ver", "--tol-ver"}});
    add_bin_cells(a, run, &run == &s.runs.front(), v, h, s.heterotopic, t);
  }
  return t;
}

OutputTable binned_table(const VariogramArgs& a, const std::vector<std::string>& value_names, bool heterotopic,
                         const BinnedCells& t) {
  OutputTable out;
  out.add_column("lag_lo", t.lo);
  out.add_column("lag_hi", t.hi);
  out.add_column("lag_mean", t.mean);
  out.add_column("gamma", t.gamma);
  out.add_column("pairs", t.pairs);
  if (a.per_component || a.cross)
    for (std::size_t c = 0; c < value_names.size(); ++c) out.add_column("gamma_" + value_names[c], t.per_component[c]);
  if (a.cross) {
    // Pairs A before B in --value order: EmpiricalVariogram::cross_column's order.
    std::size_t c = 0;
    for (std::size_t i = 0; i < value_names.size(); ++i)
      for (std::size_t j = i + 1; j < value_names.size(); ++j)
        out.add_column("gamma_" + value_names[i] + "_" + value_names[j], t.cross[c++]);
  }
  if (heterotopic) {
    // Each variogram's own pairs: pairs_<A>, lag_mean_<A>, then pairs_<A>_<B>, lag_mean_<A>_<B>.
    for (std::size_t c = 0; c < value_names.size(); ++c) {
      out.add_column("pairs_" + value_names[c], t.component_pairs[c]);
      out.add_column("lag_mean_" + value_names[c], t.component_lag[c]);
    }
    std::size_t c = 0;
    for (std::size_t i = 0; i < value_names.size() && a.cross; ++i)
      for (std::size_t j = i + 1; j < value_names.size(); ++j, ++c) {
        out.add_column("pairs_" + value_names[i] + "_" + value_names[j], t.cross_pairs[c]);
        out.add_column("lag_mean_" + value_names[i] + "_" + value_names[j], t.cross_lag[c]);
      }
  }
  if (!a.alpha.empty()) out.add_column("direction", t.alpha);
  if (!a.beta.empty()) out.add_column("dip", t.beta);
  if (a.per_coordinate) out.add_column("coordinate", t.coordinate);
  return out;
}

// --plot: the picture of the binned variogram (several directions: one colour each, with a legend),
// its axes in the columns' units.
std::string variogram_picture(const VariogramArgs& a, const CsvTable& table, const VariogramSamples& s,
                              const std::vector<std::string>& value_names, const std::vector<std::string>& coord_names,
                              VariogramPlot plot) {
  const DirectionalRun& run = s.runs.front();
  if (s.runs.size() == 1) {
    plot.bins = plot.series.front().bins;
    plot.series.clear();
  }
  plot.title = "empirical variogram of " + a.value +
               (s.runs.size() > 1 ? ", " + std::to_string(s.runs.size()) + " directions"
                                  : (run.alpha.empty() ? "" : ", direction " + run.alpha) +
                                        (run.beta.empty() ? "" : ", dip " + run.beta)) +
               " (" + std::to_string(s.x.rows()) + " points)";
  const std::string lag_unit = unit_of_column(table, coord_names.front());
  const std::string value_unit = value_names.size() == 1 ? unit_of_column(table, value_names.front()) : std::string();
  plot.lag_label = "lag" + (lag_unit.empty() ? std::string() : " [" + lag_unit + "]");
  plot.gamma_label = "semivariance" + (value_unit.empty() ? std::string() : " [" + value_unit + "^2]");
  return variogram_svg_text(plot);
}

void write_binned_variogram(const VariogramArgs& a, const OutputTable& out, const std::string& svg,
                            const VariogramSamples& s, const LagBins& bins, std::uint64_t total) {
  if (a.out.empty()) {
    // The table first: a standard output that cannot be written (> /dev/full) leaves the picture
    // untouched, as --out would.
    std::cout << out.to_csv();
    if (!svg.empty()) {
      require_standard_output();
      write_file_atomically(a.plot, svg);
    }
    return;
  }
  AtomicFileSet files;  // the CSV and the picture: both or neither
  files.add(a.out, out.to_csv());
  if (!svg.empty()) files.add(a.plot, svg);
  files.commit();
  std::cerr << "variogram: " << s.x.rows() << " points, " << total << " pairs in "
            << bins.size() << " bins";
  if (!svg.empty()) std::cerr << " (picture " << a.plot << ")";
  if (s.runs.size() > 1) std::cerr << " x " << s.runs.size() << " directions";
  std::cerr << " written to " << a.out << "\n";
}

void run_variogram(const VariogramArgs& a) {
  const auto value_names = split_column_list(a.value, "--value");
  // A CSV, or a point layer (GeoPackage, shapefile, GeoJSON) whose points give the coordinates.
  const PointTable points = read_point_table(a.input, "--input", {value_names, value_names.size() >= 2 && a.covariates.empty()});
  const auto coord_names = points.coordinate_columns(a.coords, "--coords");
  EmpiricalVariogramOptions options = variogram_options(a, value_names);
  const VariogramSamples s = read_variogram_samples(a, points, value_names, coord_names);
  if (a.cloud || !a.map.empty()) {
    if (s.heterotopic)
      throw InputError(a.input + ": empty --value cells; --cloud and --map need every value column measured at every row",
                       a.input);
    run_cloud_or_map(a, s.x, s.z, s.runs, coord_names);
    return;
  }
  const std::optional<LagBins> given_bins = bins_from_options(a, s.x);
  if (a.pseudo) {
    run_pseudo(a, points.table, s.x, s.z, value_names, given_bins, options.convention);
    return;
  }
  const LagBins bins = given_bins ? *given_bins : LagBins::gstat_default(s.x);
  if (!given_bins)
    std::cerr << "variogram: no --bins: gstat's default, 15 bins of " << format_number(bins.lag_hi(0))
              << " up to " << format_number(bins.edges().back()) << " (a third of the data's bounding-box diagonal)"
              << (options.convention == BinConvention::Gstat ? ", gstat's boundaries" : "") << "\n";
  const BinnedCells cells = binned_variograms(a, s, bins, options, value_names.size());
  if (!a.bins.empty() && a.convention.empty())
    warn_lags_on_edges(s.x, s.z, bins, options, s.runs.front(), cells.first_run_pairs, s.heterotopic);
  const OutputTable out = binned_table(a, value_names, s.heterotopic, cells);
  const std::string svg =
      a.plot.empty() ? std::string() : variogram_picture(a, points.table, s, value_names, coord_names, cells.plot);
  write_binned_variogram(a, out, svg, s, bins, cells.total);
}

void add_input_options(CLI::App* cmd, const std::shared_ptr<VariogramArgs>& args) {
  cmd->add_option("--input", args->input,
                  "CSV with the coordinate and value columns, or a point layer (.gpkg, .shp, .geojson: the coordinates "
                  "are the points', the values attributes)")->required();
  cmd->add_option("--coords", args->coords,
                  "coordinate columns, any number, in one unit (the lags' unit), e.g. x,y (map coordinates, m), x,y,z "
                  "or q1,...,q6 (joint angles, deg); default for a point layer: its points' x,y (and z)");
  cmd->add_option("--value", args->value,
                  "value column, or several comma-separated columns for a vector value (dx,dy,dz)")
      ->required();
}

void add_binning_options(CLI::App* cmd, const std::shared_ptr<VariogramArgs>& args) {
  cmd->add_option("--bins", args->bins,
                  "lo:max:width for bins [lo,lo+w), ... up to max (e.g. 0:2200:200), or explicit "
                  "increasing edges e0,e1,... (e.g. 0,10,20,50); default: gstat's, 15 bins up to a third of the "
                  "bounding-box diagonal of --coords, with gstat's boundaries unless --convention is given");
  cmd->add_option("--estimator", args->estimator,
                  "matheron (default), cressie (Cressie-Hawkins) or dowd (median-based; stores the "
                  "binned differences, at most --max-stored of them)");
  cmd->add_option("--max-stored", args->max_stored,
                  "dowd only: budget of stored differences (8 bytes each; default 25000000)")
      ->check(kUnsignedInteger);
  cmd->add_option("--convention", args->convention,
                  "paper (default with --bins): bins [lo,hi); gstat (default without --bins): [e0,e1], then (lo,hi] "
                  "as R gstat's boundaries=");
  cmd->add_flag("--per-component", args->per_component,
                "add a gamma_<column> column per value column");
  cmd->add_flag("--cross", args->cross,
                "with 2 or more --value columns: the direct variogram gamma_<column> of each and the "
                "cross-variogram gamma_<A>_<B> = 1/(2N) sum (A_i - A_j)(B_i - B_j) of each pair A before B "
                "in --value order (gstat's variogram of a multivariable gstat object; matheron only)");
  cmd->add_option("--subsample", args->subsample,
                  "use a deterministic fraction of the pairs, in (0,1] (default 1: all pairs)");
  cmd->add_option("--seed", args->seed, "seed of --subsample (default 0)")->check(kUnsignedInteger);
  cmd->add_option("--threads", args->threads, "OpenMP threads (default: all); the result does not depend on it");
}

void add_direction_and_trend_options(CLI::App* cmd, const std::shared_ptr<VariogramArgs>& args) {
  cmd->add_option("--alpha", args->alpha,
                  "directional variogram(s), as gstat's alpha: horizontal direction(s) in degrees "
                  "clockwise from +y (2nd coordinate) towards +x (1st), e.g. 0,45,90,135; 2 or 3 "
                  "coordinates. Adds a `direction` column, one block of rows per direction");
  cmd->add_option("--tol-hor", args->tol_hor,
                  "angular tolerance of --alpha in degrees (default 90/number of alphas, gstat's); a "
                  "pair counts when its horizontal angle to alpha (either sense) is <= it");
  cmd->add_option("--beta", args->beta,
                  "dip(s) in degrees up from the x-y plane (3 coordinates), as gstat's beta; adds a "
                  "`dip` column");
  cmd->add_option("--tol-ver", args->tol_ver,
                  "angular tolerance of --beta in degrees (default 90/number of betas)");
  cmd->add_flag("--per-coordinate", args->per_coordinate,
                "one variogram along each coordinate axis (any number of coordinates): the pairs whose "
                "separation is within --tol-axis of the axis. Adds a `coordinate` column");
  cmd->add_option("--tol-axis", args->tol_axis,
                  "angular tolerance of --per-coordinate in degrees (default 45: the pairs whose squared "
                  "separation along the axis is at least half the total; the cones are then disjoint)");
  cmd->add_option("--covariates", args->covariates,
                  "residual variogram: the variogram of z minus its ordinary least-squares trend 1 + these columns "
                  "(COL[,COL...] of --input, or NAME=FILE.tif|.asc: the raster's pixel at each point, 2-D --coords), "
                  "as R gstat's variogram(z ~ COL); for kriging with external drift "
                  "(interpolate --method kriging --covariates)");
}

void add_cloud_and_map_options(CLI::App* cmd, const std::shared_ptr<VariogramArgs>& args) {
  cmd->add_flag("--cloud", args->cloud,
                "the variogram cloud instead of bins: one row per pair (i, j) within --cutoff, columns left,right "
                "(1-based data rows, left > right, gstat's order), dist and gamma = 0.5 (z_left - z_right)^2 (summed "
                "over --value columns); as R gstat's variogram(..., cloud = TRUE). Takes --alpha/--beta (a direction "
                "column per block) and refuses more than --max-pairs pairs (exit 3)");
  cmd->add_option("--max-pairs", args->max_pairs,
                  "--cloud: budget of pairs written (default 1000000, some 40 MB of CSV); more is refused with exit 3 "
                  "before anything is written")
      ->check(kUnsignedInteger);
  cmd->add_option("--map", args->map,
                  "the variogram map of 2-D data (R gstat's variogram(..., map = TRUE)): cells DX wide in x and DY in y, "
                  "centred on -C, -C+DX, ... up to C (--cutoff C), each pair counted at its lag vector and at its "
                  "opposite (the map is symmetric through 0). Columns dx,dy (cell centre), np (lag vectors in the "
                  "cell), gamma (empty when np is 0); rows from the largest dy down, dx increasing, as gstat");
  cmd->add_option("--cutoff", args->cutoff,
                  "binned variogram: gstat's bins [0,W], (W,2W], ... up to C, no lag above C (R gstat's "
                  "variogram(..., cutoff = C, width = W); W from --width, default C/15; gstat's boundaries unless "
                  "--convention); --cloud: pairs at a distance <= C (default: the last --bins edge, else gstat's a "
                  "third of the bounding-box diagonal); --map: the half-width C of the map (required)");
  cmd->add_option("--width", args->width,
                  "bin width W of gstat's bins (lag unit; with or without --cutoff, whose default is then a third of "
                  "the bounding-box diagonal)");
  cmd->add_flag("--pseudo", args->pseudo,
                "with 2 or more --value columns measured at different rows (empty cells elsewhere; never co-located): "
                "the direct variogram of each over its own rows and the pseudo cross-variogram of each pair, "
                "gamma_AB(h) = 1/(2N(h)) sum (a(x_i) - b(x_j))^2 over every i measuring A and j measuring B at lag h, a and "
                "b each column minus its mean, as R gstat's variogram(g, pseudo = TRUE). Columns id (A, B, A.B as gstat), lag_lo,lag_hi,lag_mean,gamma,"
                "pairs; without --bins/--cutoff each variogram gets gstat's default bins of its own; pairs at lag 0 "
                "in a row of their own. The input of fit-variogram --lmc");
}

void add_output_options(CLI::App* cmd, const std::shared_ptr<VariogramArgs>& args) {
  cmd->add_option("--plot", args->plot,
                  "also write an SVG picture of the binned variogram (points labelled by pair count; several directions "
                  "--alpha/--beta/--per-coordinate on one picture, a colour each with a legend; with --map the map "
                  "itself, cells coloured by gamma), written atomically");
  cmd->add_option("--duplicates", args->duplicates,
                  "rows at exactly the same coordinates: keep (default: every row, as gstat's variogram; their pairs have "
                  "lag 0, in the first bin) | average (one sample per location, the mean of each --value column over the "
                  "rows measuring it, as gstat users average before krige) | first (the first row's values) | refuse "
                  "(an error naming both lines)");
  cmd->add_option("--out", args->out, "output CSV (written atomically); default: standard output");
}

void add_variogram_command(CLI::App& app) {
  auto args = std::make_shared<VariogramArgs>();
  auto* cmd = app.add_subcommand(
      "variogram",
      "Empirical semivariogram: gamma(h) = 1/(2 N(h)) sum (z_i - z_j)^2 over the pairs whose lag\n"
      "(Euclidean distance between the --coords columns) falls in each bin. Writes CSV with the\n"
      "columns lag_lo,lag_hi,lag_mean,gamma,pairs; an empty bin has pairs 0 and empty lag_mean and\n"
      "gamma. Several --value columns form a vector value: gamma is then half the mean squared norm\n"
      "of the difference (the sum of the per-column variograms, which --per-component adds as\n"
      "gamma_<column>); --cross also adds the cross-variograms gamma_<A>_<B> (the input of\n"
      "fit-variogram --lmc). --cloud writes every pair (left,right,dist,gamma) instead of bins and\n"
      "--map DX,DY --cutoff C the variogram map of 2-D data (dx,dy,np,gamma), both as R gstat's;\n"
      "--plot FILE.svg also draws the binned variogram. See docs/geostatistics.md.");
  add_input_options(cmd, args);
  add_binning_options(cmd, args);
  add_direction_and_trend_options(cmd, args);
  add_cloud_and_map_options(cmd, args);
  add_output_options(cmd, args);
  cmd->footer(
      "Example:\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dL --bins 0:2200:200 "
      "--out vario.csv\n"
      "  errfield variogram --input errors.csv --coords q1,q2,q3,q4,q5,q6 --value dx,dy,dz "
      "--bins 0,10,20,50,100 --per-component\n"
      "  errfield variogram --input errors.csv --coords x,y --value dL --bins 0:2200:200 "
      "--alpha 0,45,90,135 --tol-hor 22.5\n"
      "  errfield variogram --input errors.csv --coords q1,q2,q3,q4,q5,q6 --value dx,dy,dz "
      "--bins 0:100:10 --per-coordinate\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dx,dy,dz --cross --out cross.csv\n"
      "  errfield variogram --input errors.csv --coords x,y --value dL --cloud --cutoff 300 --out cloud.csv\n"
      "  errfield variogram --input errors.csv --coords x,y --value dL --map 50,50 --cutoff 500 --out map.csv");
  cmd->callback([args] { run_variogram(*args); });
}

Registration register_variogram{"variogram", 10, &add_variogram_command};

}  // namespace
}  // namespace errfield::cli
