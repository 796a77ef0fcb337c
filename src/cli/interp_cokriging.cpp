// Cokriging for `interpolate` and `cv` with an LMC model file (interp_cokriging.hpp).

#include "cli/interp_cokriging.hpp"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "errfield/cokriging.hpp"
#include "errfield/error.hpp"
#include "errfield/value_rows.hpp"

namespace errfield::cli {

namespace {

std::string cokriging_joined_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

// Column names of the covariance output: var (var_<col>) per component, then cov_<A>_<B>.
std::vector<std::pair<std::string, std::pair<int, int>>> cokriging_covariance_columns(const std::vector<std::string>& values) {
  const int p = static_cast<int>(values.size());
  std::vector<std::pair<std::string, std::pair<int, int>>> columns;
  for (int a = 0; a < p; ++a)
    columns.push_back({p == 1 ? "var" : "var_" + values[static_cast<std::size_t>(a)], {a, a}});
  for (int a = 0; a < p; ++a)
    for (int b = a + 1; b < p; ++b)
      columns.push_back({"cov_" + values[static_cast<std::size_t>(a)] + "_" + values[static_cast<std::size_t>(b)], {a, b}});
  return columns;
}

std::string cokriging_description(const CoregionalizationModel& model, const KrigingOptions& o, const KrigingReport& rep) {
  return "cokriging: " + std::string(kriging_kind_name(o.kind)) +
         (o.kind == KrigingKind::Universal ? " (drift order " + std::to_string(o.drift_order) + " per component)" : std::string()) +
         ", linear model of coregionalization of " + std::to_string(model.components()) + " components (" +
         std::to_string(model.structures().size()) + " structures), " + std::string(kriging_backend_name(o.backend)) +
         " back end" + (std::isfinite(rep.condition_number) ? ", condition number ~" + format_number(rep.condition_number) : std::string());
}

}  // namespace

bool model_file_is_lmc(const std::string& model) {
  if (model.size() < 5 || model.compare(model.size() - 5, 5, ".json") != 0) return false;
  std::ifstream in(model);
  if (!in) return false;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  return !j.is_discarded() && is_coregionalization_json(j);
}

CoregionalizationModel load_lmc_for_values(const std::string& path, const std::vector<std::string>& value_columns) {
  CoregionalizationModel model = load_coregionalization_model(path);
  const auto& names = model.component_names();
  if (static_cast<std::size_t>(model.components()) != value_columns.size())
    throw InputError(path + ": the coregionalization model has " + std::to_string(model.components()) + " components" +
                         (names.empty() ? std::string() : " (" + cokriging_joined_names(names) + ")") + " but --value gives " +
                         std::to_string(value_columns.size()) + " column(s) (" + cokriging_joined_names(value_columns) +
                         "); expected one --value column per model component",
                     path);
  if (!names.empty() && names != value_columns)
    throw InputError(path + ": the coregionalization model's components are " + cokriging_joined_names(names) + " but --value is " +
                         cokriging_joined_names(value_columns) + "; expected the same names in the same order (the model's rows and "
                         "columns are the components in that order)",
                     path);
  return model;
}

InterpolationResult interpolate_cokriging(const InterpolationRequest& r, const CoregionalizationModel& model,
                                          const KrigingOptions& options) {
  InterpolationResult result;
  const auto columns = cokriging_covariance_columns(r.value_columns);
  for (const auto& c : columns)
    if (r.targets->has_column(c.first))
      throw InputError(r.targets->source() + ": already has a column '" + c.first + "', which the output would repeat; rename it",
                       r.targets->source(), 1, c.first);
  const auto points = rows_as_points(r.sample_coords);
  const auto targets = rows_as_points(r.target_coords);
  with_value_type(r.value_columns.size(), [&]<class V>() {
    const auto values = rows_as_values<V>(r.sample_values);
    const Cokriging<Eigen::VectorXd, V> cokriging(points, values, model, options);
    const auto& rep = cokriging.report();
    if (!rep.usable())
      throw Error(r.samples->source() + ": cokriging failed: " + std::string(kriging_status_name(rep.status)) + ": " + rep.message);
    if (!rep.message.empty()) result.notes.push_back(std::string(kriging_status_name(rep.status)) + ": " + rep.message);
    const auto pred = cokriging.predict(targets);
    result.pred = values_as_rows(pred.mean);
    if (pred.failed_targets) {
      Eigen::Index first = 0;
      while (first < result.pred.rows() && !std::isnan(result.pred(first, 0))) ++first;
      result.notes.push_back(std::to_string(pred.failed_targets) + " of " + std::to_string(targets.size()) +
                             " targets could not be cokriged (" + std::string(kriging_status_name(pred.status)) +
                             "; first: " + r.target_labels(static_cast<std::size_t>(first)) + "); their cells are empty");
    }
    for (const auto& [name, entry] : columns) {
      std::vector<double> v(targets.size());
      for (std::size_t t = 0; t < targets.size(); ++t) v[t] = pred.covariance[t](entry.first, entry.second);
      result.extra_columns.emplace_back(name, std::move(v));
    }
    if (model.component_names().empty())
      result.notes.push_back("the coregionalization model does not name its components; taken in --value order (" +
                             cokriging_joined_names(r.value_columns) + ")");
    result.notes.push_back(cokriging_description(model, options, rep));
  });
  return result;
}

CrossValidationOutput cross_validate_cokriging(const CrossValidationRequest& r, const CoregionalizationModel& model,
                                               const KrigingOptions& options) {
  CrossValidationOutput out;
  const auto columns = cokriging_covariance_columns(r.value_columns);
  const auto points = rows_as_points(r.sample_coords);
  with_value_type(r.value_columns.size(), [&]<class V>() {
    const auto values = rows_as_values<V>(r.sample_values);
    const Cokriging<Eigen::VectorXd, V> cokriging(points, values, model, options);
    const auto cv = cokriging.leave_one_out();
    if (cv.prediction.size() != values.size())
      throw Error(r.samples->source() + ": cokriging failed: " + std::string(kriging_status_name(cv.status)) + ": " + cv.message);
    if (!cv.message.empty()) out.notes.push_back(cv.message);
    const std::size_t n = values.size();
    const int p = static_cast<int>(r.value_columns.size());
    out.fold.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.fold[i] = i;
    out.pred = values_as_rows(cv.prediction);
    out.variance.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.variance[i] = cv.covariance[i].trace() / p;
    if (p > 1)
      for (const auto& [name, entry] : columns) {
        std::vector<double> v(n);
        for (std::size_t i = 0; i < n; ++i) v[i] = cv.covariance[i](entry.first, entry.second);
        out.extra_columns.emplace_back(name, std::move(v));
      }
    out.notes.push_back(std::string(options.backend == KrigingBackend::Dense
                                        ? "leave-one-out cokriging in closed form from one factorization"
                                        : "leave-one-out cokriging: each sample from its neighbours without itself") +
                        "; every component of a sample left out together" +
                        (p > 1 ? "; var is the mean of the components' residual variances (var_<col>, cov_<A>_<B>)" : ""));
    out.notes.push_back(cokriging_description(model, options, cokriging.report()));
  });
  return out;
}

}  // namespace errfield::cli
