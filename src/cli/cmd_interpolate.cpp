// `errfield interpolate`: predicts a value at every row of a targets CSV from a samples CSV, with
// one of the registered methods (interpolation_methods.hpp), and writes the targets' columns plus
// the predictions.

#include <cmath>
#include <iostream>
#include <memory>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/value_cells.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {
namespace {

struct InterpolateArgs {
  std::string method;
  std::string samples;
  std::string targets;
  std::string coords;
  std::string value;
  std::string out;
  double power = 0.0;
  std::size_t neighbors = 0;
  double radius = 0.0;
  bool clamp = false;
};

struct SharedOptionHandles {
  CLI::Option* power = nullptr;
  CLI::Option* neighbors = nullptr;
  CLI::Option* radius = nullptr;
  CLI::Option* clamp = nullptr;
  std::vector<CLI::Option*> all() const { return {power, neighbors, radius, clamp}; }
};

SharedInterpolationOptions read_shared(const InterpolateArgs& a, const SharedOptionHandles& h) {
  SharedInterpolationOptions s;
  if (h.power->count()) {
    if (!(a.power >= 0.0) || !std::isfinite(a.power))
      throw ArgumentError("--power is " + format_number(a.power) + "; expected a finite value >= 0");
    s.power = a.power;
  }
  if (h.neighbors->count()) {
    if (a.neighbors < 1) throw ArgumentError("--neighbors is 0; expected at least 1");
    s.neighbors = a.neighbors;
  }
  if (h.radius->count()) {
    if (!(a.radius > 0.0) || !std::isfinite(a.radius))
      throw ArgumentError("--radius is " + format_number(a.radius) + "; expected a finite value > 0");
    s.radius = a.radius;
  }
  s.clamp = a.clamp;
  return s;
}

std::vector<std::string> prediction_columns(const std::vector<std::string>& values) {
  if (values.size() == 1) return {"pred"};
  std::vector<std::string> names;
  for (const auto& v : values) names.push_back("pred_" + v);
  return names;
}

std::string cell(double v) { return std::isnan(v) ? std::string() : format_number(v); }

void run_interpolate(const InterpolateArgs& a, const SharedOptionHandles& h, const MethodOptionOwnership& owners) {
  const InterpolationMethod& method = find_method(a.method, false);
  owners.check(method.name, method.accepts, h.all());

  InterpolationRequest r;
  r.coord_columns = split_column_list(a.coords, "--coords");
  r.value_columns = split_column_list(a.value, "--value");
  r.shared = read_shared(a, h);
  with_value_type(r.value_columns.size(), []<class V>() {});  // reject unsupported counts early

  const CsvTable samples = CsvTable::read(a.samples);
  const CsvTable targets = CsvTable::read(a.targets);
  if (samples.row_count() == 0) throw InputError(a.samples + ": no data rows; expected samples", a.samples);
  if (targets.row_count() == 0) throw InputError(a.targets + ": no data rows; expected targets", a.targets);
  r.samples = &samples;
  r.targets = &targets;
  r.sample_coords = samples.numeric_columns(r.coord_columns);
  r.sample_values = method.takes_missing_values && method.takes_missing_values()
                        ? numeric_columns_with_gaps(samples, r.value_columns)
                        : samples.numeric_columns(r.value_columns);
  r.target_coords = targets.numeric_columns(r.coord_columns);
  r.sample_labels = row_labels_of(samples, "sample");
  r.target_labels = row_labels_of(targets, "target");

  const auto default_pred_names = prediction_columns(r.value_columns);
  for (const auto& name : default_pred_names)
    if (targets.has_column(name))
      throw InputError(a.targets + ": already has a column '" + name +
                           "', which the output would repeat; rename it",
                       a.targets, 1, name);

  const InterpolationResult result = method.interpolate(r);
  const auto m = static_cast<Eigen::Index>(targets.row_count());
  const std::vector<std::string> pred_names = result.prediction_names.empty() ? default_pred_names : result.prediction_names;
  for (const auto& name : result.prediction_names)
    if (targets.has_column(name))
      throw InputError(a.targets + ": already has a column '" + name + "', which the output would repeat; rename it",
                       a.targets, 1, name);
  if (result.pred.rows() != m || result.pred.cols() != static_cast<Eigen::Index>(pred_names.size()))
    throw Error("interpolate: method " + method.name + " returned " + std::to_string(result.pred.rows()) + " x " +
                std::to_string(result.pred.cols()) + " predictions; expected " + std::to_string(m) + " x " +
                std::to_string(pred_names.size()));

  OutputTable out;
  out.add_all_columns(targets);
  std::size_t missing = 0;
  for (Eigen::Index i = 0; i < m; ++i) missing += std::isnan(result.pred(i, 0)) ? 1 : 0;
  // Nothing predicted is a failed job, as in predict, validate and cv (a file of empty cells exited 0).
  if (m > 0 && missing == static_cast<std::size_t>(m)) {
    std::string why;
    for (const auto& note : result.notes) why += "; " + note;
    if (r.shared.radius)
      why += "; no target has a sample within --radius " + format_number(*r.shared.radius) +
             " (in the scaled coordinates, where an anisotropy applies): a larger --radius or fewer targets far "
             "from the samples";
    throw Error("interpolate: none of the " + std::to_string(m) + " targets of " + a.targets +
                " got a prediction with --method " + method.name + why + "; " + a.out + " not written");
  }
  for (std::size_t c = 0; c < pred_names.size(); ++c) {
    std::vector<std::string> cells(static_cast<std::size_t>(m));
    for (Eigen::Index i = 0; i < m; ++i) cells[static_cast<std::size_t>(i)] = cell(result.pred(i, static_cast<Eigen::Index>(c)));
    out.add_column(pred_names[c], std::move(cells));
  }
  for (const auto& [name, values] : result.extra_columns) {
    std::vector<std::string> cells(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) cells[i] = cell(values[i]);
    out.add_column(name, std::move(cells));
  }
  for (const auto& note : result.notes) std::cerr << "errfield interpolate: " << note << "\n";
  std::cout << "interpolate: " << m << " targets from " << samples.row_count() << " samples with --method "
            << method.name << "; " << (static_cast<std::size_t>(m) - missing) << " predicted";
  if (missing) std::cout << ", " << missing << " without prediction (empty cells)";
  std::cout << "; wrote " << a.out << "\n";
  require_standard_output();  // before the write: a run that fails leaves the previous file
  out.write(a.out);
}

void add_interpolate_command(CLI::App& app) {
  auto args = std::make_shared<InterpolateArgs>();
  auto handles = std::make_shared<SharedOptionHandles>();
  CLI::App* cmd = app.add_subcommand("interpolate", "Predict values at target points from samples (IDW on a regular grid, scattered IDW, ...)");
  cmd->footer(
      "Methods:\n" +
      [] {
        std::string s;
        for (const auto& m : interpolation_methods())
          if (m.interpolate) s += "  " + m.name + ": " + m.summary + "\n";
        return s;
      }() +
      "\nThe output has every column of the targets file plus 'pred' (for --value dx,dy,dz: pred_dx,pred_dy,pred_dz);\n"
      "a target without a prediction gets empty cells; if no target gets one, nothing is written and the exit\n"
      "status is 1, with the reason. The output is written atomically.\n\n"
      "Example (errors.csv, scattered.csv, targets.csv: SIMULATED, from scripts/make_example_error_field.py):\n"
      "  # the paper's method: distance errors measured on a 125 mm grid, interpolated to targets\n"
      "  errfield interpolate --method idw-grid --samples errors.csv --targets targets.csv \\\n"
      "      --coords x,y,z --value dL --out predicted.csv\n"
      "  errfield interpolate --method idw --samples scattered.csv --targets targets.csv \\\n"
      "      --coords x,y,z --value dx,dy,dz --neighbors 8 --power 2 --out predicted.csv\n");
  cmd->add_option("--method", args->method, "Interpolation method: " + method_names(false))->required();
  cmd->add_option("--samples", args->samples, "CSV with the measured samples (coordinates and values)")->required();
  cmd->add_option("--targets", args->targets, "CSV with the points to predict at (the coordinate columns)")->required();
  cmd->add_option("--coords", args->coords, "Coordinate columns, comma-separated (x,y,z; any number for scattered methods)")->required();
  cmd->add_option("--value", args->value, "Value column, or 2-3 comma-separated columns of a vector value")->required();
  cmd->add_option("--out", args->out, "Output CSV")->required();
  handles->power = cmd->add_option("--power", args->power, "Power p of the inverse-distance weights 1/d^p (default: 1 for idw-grid as in the paper, 2 for idw as in gstat)");
  handles->neighbors = cmd->add_option("--neighbors", args->neighbors, "Use the K nearest samples (scattered methods; default: all)")
                          ->check(kUnsignedInteger);
  handles->radius = cmd->add_option("--radius", args->radius, "Use only samples within this distance, in the coordinates' unit (scattered methods)");
  handles->clamp = cmd->add_flag("--clamp", args->clamp, "idw-grid: interpolate targets outside the grid from the nearest cell instead of failing");
  auto owners = std::make_shared<MethodOptionOwnership>(add_method_options(*cmd, false));
  cmd->callback([args, handles, owners] { run_interpolate(*args, *handles, *owners); });
}

Registration register_interpolate{"interpolate", 30, &add_interpolate_command};

}  // namespace
}  // namespace errfield::cli
