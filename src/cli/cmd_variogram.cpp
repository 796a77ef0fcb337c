// `errfield variogram`: empirical variogram of one or several value columns over any number of
// coordinate columns, written as CSV lag_lo,lag_hi,lag_mean,gamma,pairs.

#include <charconv>
#include <cmath>
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {
namespace {

struct VariogramArgs {
  std::string input, coords, value, bins, estimator = "matheron", convention = "paper", out;
  bool per_component = false;
  double subsample = 1.0;
  std::uint64_t seed = 0;
  int threads = 0;
  std::uint64_t max_stored = 25'000'000;
};

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

void run_variogram(const VariogramArgs& a) {
  const auto coord_names = split_column_list(a.coords, "--coords");
  const auto value_names = split_column_list(a.value, "--value");
  const LagBins bins = parse_bins_option(a.bins);
  EmpiricalVariogramOptions options;
  options.estimator = estimator_from_name(a.estimator);
  options.convention = convention_from_name(a.convention);
  options.pair_fraction = a.subsample;
  options.seed = a.seed;
  options.threads = a.threads;
  options.max_stored_differences = a.max_stored;
  naming_options([&] { options.validate(); }, {{"variogram options: pair_fraction", "--subsample"},
                                               {"pair_fraction", "--subsample"},
                                               {"variogram options: threads", "--threads"}});

  const CsvTable table = CsvTable::read(a.input);
  if (table.row_count() < 2)
    throw InputError(a.input + ": " + std::to_string(table.row_count()) +
                         " data row(s); the variogram needs at least 2 points",
                     a.input);
  const Eigen::MatrixXd x = table.numeric_columns(coord_names);
  const Eigen::MatrixXd z = table.numeric_columns(value_names);
  EmpiricalVariogram v;
  naming_options([&] { v = empirical_variogram(x, z, bins, options); },
                 {{"max_stored_differences", "--max-stored"}, {"pair_fraction (--subsample)", "--subsample"}});

  OutputTable out;
  std::vector<std::string> lo, hi, mean, gamma, pairs;
  for (const auto& b : v.bins) {
    lo.push_back(format_number(b.lag_lo));
    hi.push_back(format_number(b.lag_hi));
    mean.push_back(cell(b.lag_mean));
    gamma.push_back(cell(b.gamma));
    pairs.push_back(std::to_string(b.pairs));
  }
  out.add_column("lag_lo", lo);
  out.add_column("lag_hi", hi);
  out.add_column("lag_mean", mean);
  out.add_column("gamma", gamma);
  out.add_column("pairs", pairs);
  if (a.per_component) {
    for (int c = 0; c < v.components(); ++c) {
      std::vector<std::string> g;
      for (Eigen::Index b = 0; b < v.component_gamma.rows(); ++b) g.push_back(cell(v.component_gamma(b, c)));
      out.add_column("gamma_" + value_names[static_cast<std::size_t>(c)], g);
    }
  }
  if (a.out.empty()) {
    std::cout << out.to_csv();
  } else {
    out.write(a.out);
    std::uint64_t total = 0;
    for (const auto& b : v.bins) total += b.pairs;
    std::cerr << "variogram: " << table.row_count() << " points, " << total << " pairs in "
              << bins.size() << " bins written to " << a.out << "\n";
  }
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
      "gamma_<column>). See docs/geostatistics.md.");
  cmd->add_option("--input", args->input, "CSV with the coordinate and value columns")->required();
  cmd->add_option("--coords", args->coords,
                  "coordinate columns, any number, e.g. x,y,z (task space, mm) or q1,q2,q3,q4,q5,q6 "
                  "(joint space, deg)")
      ->required();
  cmd->add_option("--value", args->value,
                  "value column, or several comma-separated columns for a vector value (dx,dy,dz)")
      ->required();
  cmd->add_option("--bins", args->bins,
                  "lo:max:width for bins [lo,lo+w), ... up to max (e.g. 0:2200:200), or explicit "
                  "increasing edges e0,e1,... (e.g. 0,10,20,50)")
      ->required();
  cmd->add_option("--estimator", args->estimator,
                  "matheron (default), cressie (Cressie-Hawkins) or dowd (median-based; stores the "
                  "binned differences, at most --max-stored of them)");
  cmd->add_option("--max-stored", args->max_stored,
                  "dowd only: budget of stored differences (8 bytes each; default 25000000)")
      ->check(kUnsignedInteger);
  cmd->add_option("--convention", args->convention,
                  "paper (default): bins [lo,hi); gstat: [e0,e1], then (lo,hi] as R gstat's boundaries=");
  cmd->add_flag("--per-component", args->per_component,
                "add a gamma_<column> column per value column");
  cmd->add_option("--subsample", args->subsample,
                  "use a deterministic fraction of the pairs, in (0,1] (default 1: all pairs)");
  cmd->add_option("--seed", args->seed, "seed of --subsample (default 0)")->check(kUnsignedInteger);
  cmd->add_option("--threads", args->threads, "OpenMP threads (default: all); the result does not depend on it");
  cmd->add_option("--out", args->out, "output CSV (written atomically); default: standard output");
  cmd->footer(
      "Example:\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dL --bins 0:2200:200 "
      "--out vario.csv\n"
      "  errfield variogram --input errors.csv --coords q1,q2,q3,q4,q5,q6 --value dx,dy,dz "
      "--bins 0,10,20,50,100 --per-component");
  cmd->callback([args] { run_variogram(*args); });
}

Registration reg{"variogram", 10, &add_variogram_command};

}  // namespace
}  // namespace errfield::cli
