// `errfield cv`: leave-one-out or k-fold cross-validation of a scattered estimator on a samples
// CSV; prints the summary and optionally writes the per-sample predictions and residuals.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <memory>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/coordinate_system.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/point_layer.hpp"
#include "cli/value_cells.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {
namespace {

struct CvArgs {
  std::string method;
  std::string samples;
  std::string coords;
  std::string value;
  std::string crs;  // --crs: checked against the inputs' CRSs (a layer, covariate rasters)
  std::string folds = "loo";
  std::uint64_t seed = 1;
  std::string out;
  double power = 0.0;
  std::size_t neighbors = 0;
  double radius = 0.0;
};

struct CvHandles {
  CLI::Option* power = nullptr;
  CLI::Option* neighbors = nullptr;
  CLI::Option* radius = nullptr;
  CLI::Option* seed = nullptr;
};

std::size_t parse_folds(const std::string& text) {
  if (text == "loo") return 0;
  std::size_t pos = 0;
  unsigned long long k = 0;
  try {
    k = std::stoull(text, &pos);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos != text.size() || text.empty() || text[0] == '-' || k < 2)
    throw ArgumentError("--folds is '" + text + "'; expected 'loo' (leave-one-out) or a number of folds >= 2");
  return static_cast<std::size_t>(k);
}

std::string cell(double v) { return std::isnan(v) ? std::string() : format_number(v); }

std::string with_unit(double v, const std::string& unit) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return unit.empty() ? std::string(buf) : std::string(buf) + " " + unit;
}

// The request's options: folds, seed and the shared neighbourhood options the method accepts.
CrossValidationRequest cv_request(const CvArgs& a, const CvHandles& h) {
  CrossValidationRequest r;
  r.value_columns = split_column_list(a.value, "--value");
  r.folds = parse_folds(a.folds);
  r.seed = a.seed;
  if (r.folds == 0 && h.seed->count())
    throw ArgumentError("--seed applies to k-fold cross-validation (--folds K), not to --folds loo");
  if (h.power->count()) {
    if (!(a.power >= 0.0) || !std::isfinite(a.power))
      throw ArgumentError("--power is " + format_number(a.power) + "; expected a finite value >= 0");
    r.shared.power = a.power;
  }
  if (h.neighbors->count()) {
    if (a.neighbors < 1) throw ArgumentError("--neighbors is 0; expected at least 1");
    r.shared.neighbors = a.neighbors;
  }
  if (h.radius->count()) {
    if (!(a.radius > 0.0) || !std::isfinite(a.radius))
      throw ArgumentError("--radius is " + format_number(a.radius) + "; expected a finite value > 0");
    r.shared.radius = a.radius;
  }
  with_value_type(r.value_columns.size(), []<class V>() {});
  return r;
}

// The samples into the request (which points at `samples`: it must outlive the request).
void attach_samples(const CvArgs& a, const PointTable& points, bool gaps, CrossValidationRequest& r) {
  const CsvTable& samples = points.table;
  const std::size_t n = samples.row_count();
  if (n < 2)
    throw InputError(a.samples + ": " + std::to_string(n) + " data rows; cross-validation needs at least 2", a.samples);
  if (r.folds > n)
    throw ArgumentError("--folds " + std::to_string(r.folds) + " for " + std::to_string(n) + " samples in " + a.samples +
                        "; expected at most one fold per sample");
  r.samples = &samples;
  r.sample_coords = samples.numeric_columns(r.coord_columns);
  // Heterotopic cokriging (kriging with an LMC --model): an empty cell is that component not
  // measured at the sample; every other method keeps refusing empty cells.
  r.sample_values = gaps ? numeric_columns_with_gaps(samples, r.value_columns) : samples.numeric_columns(r.value_columns);
  r.sample_labels = points.labels("sample");
}

// The columns --out adds: pred and residual (one per component), refused before the work when the
// samples already have one of them.
struct CvColumns {
  std::vector<std::string> pred, residual;
};

CvColumns cv_columns(const CvArgs& a, const CrossValidationRequest& r) {
  const std::size_t c = r.value_columns.size();
  CvColumns names;
  for (const auto& v : r.value_columns) {
    names.pred.push_back(c == 1 ? "pred" : "pred_" + v);
    names.residual.push_back(c == 1 ? "residual" : "residual_" + v);
  }
  std::vector<std::string> added{"fold"};
  added.insert(added.end(), names.pred.begin(), names.pred.end());
  added.insert(added.end(), names.residual.begin(), names.residual.end());
  added.push_back("abs_residual");
  added.push_back("var");
  if (!a.out.empty())
    for (const auto& name : added)
      if (r.samples->has_column(name))
        throw InputError(a.samples + ": already has a column '" + name + "', which the output would repeat; rename it",
                         a.samples, 1, name);
  return names;
}

// No prediction at all is a failed job (k-fold said "predicted 0 of 12" and exited 0), whatever
// made every fold fail; the notes say why.
void refuse_nothing_predicted(const CvArgs& a, const std::string& method, const CrossValidationRequest& r,
                              const CrossValidationOutput& result, const CrossValidationSummary& s, bool heterotopic) {
  const bool nothing_predicted =
      heterotopic ? !(r.sample_values.array().isFinite() && result.pred.array().isFinite()).any() : s.predicted == 0;
  if (!nothing_predicted) return;
  std::string why;
  for (const auto& note : result.notes) why += "; " + note;
  throw Error("cv: none of the " + std::to_string(r.samples->row_count()) + " samples of " + a.samples +
              " could be predicted by --method " + method +
              (why.empty() ? std::string(" (e.g. no neighbour within --radius)") : why) + "; nothing written");
}

// --out: the samples with fold, predictions, residuals, |residual|, variance and the method's extras.
OutputTable cv_table(const CvArgs& a, const CrossValidationRequest& r, const CvColumns& names,
                     const CrossValidationOutput& result, const Eigen::MatrixXd& residuals) {
  const CsvTable& samples = *r.samples;
  const std::size_t n = samples.row_count(), c = r.value_columns.size();
  OutputTable out;
  out.add_all_columns(samples);
  std::vector<std::string> folds(n);
  for (std::size_t i = 0; i < n; ++i) folds[i] = std::to_string(result.fold[i]);
  out.add_column("fold", std::move(folds));
  for (std::size_t k = 0; k < c; ++k) {
    std::vector<std::string> p(n), e(n);
    for (std::size_t i = 0; i < n; ++i) {
      p[i] = cell(result.pred(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)));
      e[i] = cell(residuals(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)));
    }
    out.add_column(names.pred[k], std::move(p));
    out.add_column(names.residual[k], std::move(e));
  }
  std::vector<std::string> abs(n);
  for (std::size_t i = 0; i < n; ++i) abs[i] = cell(residuals.row(static_cast<Eigen::Index>(i)).norm());
  out.add_column("abs_residual", std::move(abs));
  if (!result.variance.empty()) {
    std::vector<std::string> var(n);
    for (std::size_t i = 0; i < n; ++i) var[i] = cell(result.variance[i]);
    out.add_column("var", std::move(var));
  }
  for (const auto& [name, values] : result.extra_columns) {
    if (samples.has_column(name))
      throw InputError(a.samples + ": already has a column '" + name + "', which the output would repeat; rename it",
                       a.samples, 1, name);
    std::vector<std::string> cells(n);
    for (std::size_t i = 0; i < n; ++i) cells[i] = cell(values[i]);
    out.add_column(name, std::move(cells));
  }
  return out;
}

void print_cv_summary(const CvArgs& a, const std::string& method, const CrossValidationRequest& r,
                      const CrossValidationSummary& s, const std::string& unit) {
  const std::size_t c = r.value_columns.size();
  const std::string what = c == 1 ? r.value_columns.front() : "(" + a.value + ")";
  std::cout << "cross-validation of --method " << method << " on " << a.samples << ": " << r.samples->row_count()
            << " samples, "
            << (r.folds == 0 ? std::string("leave-one-out") : std::to_string(r.folds) + "-fold (seed " + std::to_string(r.seed) + ")")
            << "\n";
  std::cout << "  value            " << what << (unit.empty() ? "" : " [" + unit + "]") << "\n";
  std::cout << "  predicted        " << s.predicted << " of " << s.samples << "\n";
  if (s.predicted == 0) return;
  std::cout << "  mean error       ";
  for (std::size_t k = 0; k < c; ++k) std::cout << (k ? ", " : "") << with_unit(s.mean_error[k], unit);
  std::cout << "   (observed - predicted" << (c > 1 ? ", per component" : "") << ")\n";
  std::cout << "  mean |error|     " << with_unit(s.mean_abs_error, unit) << (c > 1 ? "   (Euclidean norm)" : "") << "\n";
  std::cout << "  max |error|      " << with_unit(s.max_abs_error, unit) << "   at " << r.sample_labels(s.max_abs_index)
            << "\n";
  std::cout << "  RMS error        " << with_unit(s.rms_error, unit) << "\n";
  if (s.mean_z) {
    std::cout << "  mean z           " << with_unit(*s.mean_z, "") << "   (residual / prediction sd; ~0)\n";
    std::cout << "  mean z^2         " << with_unit(*s.mean_squared_z, "") << "   (~1 when the variance is right)\n";
  }
}

// Heterotopic: the summary is over the samples where every component is measured (and predicted);
// each component's own figures are over the samples that measure it.
void print_per_component(const CrossValidationRequest& r, const Eigen::MatrixXd& residuals, const std::string& unit) {
  std::cout << "  per component    (heterotopic: the lines above are over the samples measuring every component, "
               "these each over the samples that measure it)\n";
  for (std::size_t k = 0; k < r.value_columns.size(); ++k) {
    const auto col = residuals.col(static_cast<Eigen::Index>(k));
    std::size_t measured = 0, predicted = 0;
    double sum = 0.0, sum_sq = 0.0;
    for (Eigen::Index i = 0; i < col.size(); ++i) {
      if (std::isnan(r.sample_values(i, static_cast<Eigen::Index>(k)))) continue;
      ++measured;
      if (!std::isfinite(col(i))) continue;
      ++predicted;
      sum += col(i);
      sum_sq += col(i) * col(i);
    }
    std::cout << "    " << r.value_columns[k] << ": predicted " << predicted << " of " << measured;
    if (predicted > 0)
      std::cout << ", mean error " << with_unit(sum / static_cast<double>(predicted), unit) << ", RMS error "
                << with_unit(std::sqrt(sum_sq / static_cast<double>(predicted)), unit);
    std::cout << "\n";
  }
}

void run_cv(const CvArgs& a, const CvHandles& h, const MethodOptionOwnership& owners) {
  const InterpolationMethod& method = find_method(a.method, true);
  owners.check(method.name, method.accepts, {h.power, h.neighbors, h.radius});
  CrossValidationRequest r = cv_request(a, h);

  CoordinateSystem cs;
  if (!a.crs.empty()) cs.add(parse_crs(a.crs, "--crs"), "--crs");
  const bool gaps = method.takes_missing_values && method.takes_missing_values();
  const PointTable points = read_point_table(a.samples, "--samples", {r.value_columns, gaps});
  const CsvTable& samples = points.table;
  cs.add(points.crs, "--samples " + a.samples, a.samples);
  r.coord_columns = points.coordinate_columns(a.coords, "--coords");
  r.coordinate_system = &cs;
  if (const std::string w = cs.geographic_warning(); !w.empty()) std::cerr << "errfield cv: " << w << "\n";
  attach_samples(a, points, gaps, r);
  const bool heterotopic = r.sample_values.array().isNaN().any();
  const CvColumns names = cv_columns(a, r);

  const CrossValidationOutput result = method.cross_validate(r);
  const std::size_t n = samples.row_count(), c = r.value_columns.size();
  if (result.pred.rows() != static_cast<Eigen::Index>(n) || result.pred.cols() != static_cast<Eigen::Index>(c) ||
      result.fold.size() != n)
    throw Error("cv: method " + method.name + " returned results of the wrong size");
  const Eigen::MatrixXd residuals = r.sample_values - result.pred;
  const CrossValidationSummary s = summarize_residuals(residuals, result.variance);
  refuse_nothing_predicted(a, method.name, r, result, s, heterotopic);

  // Written after the summary (require_standard_output): a standard output that cannot be written
  // (> /dev/full) replaced --out, then exited 1 (issue 47, the class of item 10).
  std::optional<OutputTable> table;
  if (!a.out.empty()) table = cv_table(a, r, names, result, residuals);

  // Units from the value columns' headers ("dL [mm]"); shown only when all columns agree.
  std::string unit = unit_of_column(samples, r.value_columns.front());
  for (const auto& v : r.value_columns)
    if (unit_of_column(samples, v) != unit) unit.clear();
  print_cv_summary(a, method.name, r, s, unit);
  if (heterotopic) print_per_component(r, residuals, unit);
  else if (s.predicted < s.samples)
    std::cout << "  " << (s.samples - s.predicted) << " samples had no prediction (e.g. no neighbour within --radius)\n";
  for (const auto& note : result.notes) std::cerr << "errfield cv: " << note << "\n";
  if (table) {
    std::cout << "wrote " << a.out << "\n";
    require_standard_output();
    table->write(a.out);
  }
}

void add_cv_command(CLI::App& app) {
  auto args = std::make_shared<CvArgs>();
  auto handles = std::make_shared<CvHandles>();
  CLI::App* cmd = app.add_subcommand("cv", "Cross-validate an interpolation method on samples (leave-one-out or k-fold)");
  cmd->footer(
      "Each sample (leave-one-out) or each of K folds is predicted from the other samples; the summary\n"
      "gives the mean error (observed - predicted), mean and max |error| and the RMS error, in the unit\n"
      "of the value column (e.g. 'z [m]' -> m). k-fold folds come from a seeded shuffle: the same\n"
      "--seed gives the same folds everywhere. --out writes every sample column plus fold, pred,\n"
      "residual and abs_residual (vector values: pred_<col>, residual_<col>; abs_residual is the norm).\n\n"
      "Methods: " + method_names(true) + "\n\n"
      "Example:\n"
      "  errfield cv --method idw --samples scattered.csv --coords x,y,z --value dL --neighbors 8 --folds 10 \\\n"
      "      --seed 42 --out cv_points.csv\n");
  cmd->add_option("--method", args->method, "Method to validate: " + method_names(true))->required();
  cmd->add_option("--samples", args->samples,
                  "Samples: a CSV (coordinates and values), or a point layer (.gpkg, .shp, .geojson: the coordinates are "
                  "the points', the values attributes)")->required();
  cmd->add_option("--coords", args->coords,
                  "Coordinate columns, comma-separated (any number); default for a point layer: its points' x,y (and z)");
  cmd->add_option("--value", args->value, "Value column (attribute of a point layer), or 2-3 comma-separated columns of a vector value")->required();
  cmd->add_option("--crs", args->crs,
                  "The CRS of the coordinates (EPSG:NNNN, WKT or a PROJ string), checked against the CRS of a point layer "
                  "and of covariate rasters (errfield does not reproject)");
  cmd->add_option("--folds", args->folds, "'loo' (leave-one-out, default) or the number of folds K >= 2");
  handles->seed = cmd->add_option("--seed", args->seed, "Seed of the k-fold assignment (default 1)")->check(kUnsignedInteger);
  cmd->add_option("--out", args->out, "Optional CSV of per-sample predictions and residuals");
  handles->power = cmd->add_option("--power", args->power, "Power p of the inverse-distance weights (idw: default 2)");
  handles->neighbors = cmd->add_option("--neighbors", args->neighbors, "Use the K nearest samples (default: all)")
                          ->check(kUnsignedInteger);
  handles->radius = cmd->add_option("--radius", args->radius, "Use only samples within this distance (coordinates' unit)");
  auto owners = std::make_shared<MethodOptionOwnership>(add_method_options(*cmd, true));
  cmd->callback([args, handles, owners] { run_cv(*args, *handles, *owners); });
}

Registration register_cv{"cv", 35, &add_cv_command};

}  // namespace
}  // namespace errfield::cli
