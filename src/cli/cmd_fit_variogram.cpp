// `errfield fit-variogram`: fits a variogram model to the CSV that `errfield variogram` writes.

#include <charconv>
#include <cmath>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield::cli {
namespace {

struct FitArgs {
  std::string input, model, nugget = "free", weights = "nj_h2", out;
  double nu = 0.5;
  bool nu_given = false;
  double range_max = 0.0;
};

double parse_cell(const CsvTable& t, std::size_t r, std::size_t c) {
  return t.numeric_cell(r, c);
}

std::size_t find_column(const CsvTable& t, const char* ours, const char* gstat) {
  if (t.has_column(ours) || !t.has_column(gstat)) return t.column_index(ours);  // throws listing columns
  return t.column_index(gstat);
}

void run_fit(const FitArgs& a) {
  VariogramFitOptions o;
  o.weighting = weighting_from_name(a.weights);
  if (a.nugget == "free") {
    o.nugget = NuggetMode::Free;
  } else if (a.nugget == "none") {
    o.nugget = NuggetMode::None;
  } else if (a.nugget.rfind("fixed=", 0) == 0) {
    o.nugget = NuggetMode::Fixed;
    const std::string v = a.nugget.substr(6);
    const auto res = std::from_chars(v.data(), v.data() + v.size(), o.nugget_value);
    if (v.empty() || res.ec != std::errc() || res.ptr != v.data() + v.size() ||
        !std::isfinite(o.nugget_value) || o.nugget_value < 0.0)
      throw ArgumentError("--nugget: '" + a.nugget + "'; expected fixed=V with a finite V >= 0");
  } else {
    throw ArgumentError("--nugget: '" + a.nugget + "'; expected free, fixed=V or none");
  }
  o.range_max = a.range_max;
  o.validate();
  ModelComponent structure;
  structure.kind = model_kind_from_name(a.model);
  if (structure.kind == ModelKind::Nugget)
    throw ArgumentError("--model: 'nug' alone has nothing to fit; use --nugget for the nugget");
  if (structure.kind == ModelKind::Matern && !a.nu_given)
    throw ArgumentError("--model mat needs --nu (the Matérn smoothness, e.g. 0.5, 1.5, 2.5)");
  if (!(a.nu > 0.0)) throw ArgumentError("--nu: " + format_number(a.nu) + "; expected > 0");
  structure.nu = a.nu;

  // Columns of `errfield variogram` (lag_mean, gamma, pairs), or gstat's (dist, gamma, np).
  const CsvTable t = CsvTable::read(a.input);
  const std::size_t c_lag = find_column(t, "lag_mean", "dist");
  const std::size_t c_gamma = t.column_index("gamma");
  const std::size_t c_pairs = find_column(t, "pairs", "np");
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    const double np = parse_cell(t, r, c_pairs);
    if (np < 0.0 || np != std::floor(np))
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column '" +
                           t.header()[c_pairs] + "': " + format_number(np) +
                           " is not a pair count (an integer >= 0)",
                       t.source(), t.line_of_row(r), t.header()[c_pairs]);
    if (np == 0.0) continue;  // empty bin: its lag_mean and gamma cells are empty
    const double lag = parse_cell(t, r, c_lag);
    const double gamma = parse_cell(t, r, c_gamma);
    if (lag < 0.0 || gamma < 0.0)
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) +
                           ": negative lag or gamma; expected values >= 0",
                       t.source(), t.line_of_row(r), lag < 0.0 ? t.header()[c_lag] : t.header()[c_gamma]);
    h.push_back(lag);
    g.push_back(gamma);
    n.push_back(static_cast<std::uint64_t>(np));
  }
  if (h.empty()) throw InputError(a.input + ": no bin with pairs > 0; nothing to fit", a.input);

  const VariogramFitResult r = fit_variogram(h, g, n, {structure}, o);
  const char* status = r.status == FitStatus::Converged        ? "converged"
                       : r.status == FitStatus::MaxEvaluations ? "max_evaluations"
                                                               : "failed";
  std::cout << r.model.to_string() << "\n";
  for (const auto& c : r.model.components()) {
    std::cout << "  " << model_kind_name(c.kind) << ": "
              << (c.kind == ModelKind::Linear ? "slope" : "sill") << " = " << format_number(c.sill);
    if (c.kind == ModelKind::Power) std::cout << ", exponent = " << format_number(c.range);
    else if (c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear)
      std::cout << ", range = " << format_number(c.range);
    if (c.kind == ModelKind::Matern) std::cout << ", nu = " << format_number(c.nu);
    std::cout << "\n";
  }
  std::cout << "weighted SSE (" << weighting_name(o.weighting) << ") = " << format_number(r.weighted_sse)
            << ", " << r.bins_used << " bins, status " << status << " (" << r.message << ")\n";

  if (!a.out.empty()) {
    nlohmann::json j = r.model;
    j["fit"] = {{"weights", std::string(weighting_name(o.weighting))},
                {"nugget", a.nugget},
                {"weighted_sse", r.weighted_sse},
                {"bins_used", r.bins_used},
                {"evaluations", r.evaluations},
                {"status", status},
                {"message", r.message},
                {"input", a.input}};
    write_file_atomically(a.out, j.dump(2) + "\n");
  }
  if (r.status == FitStatus::Failed) throw Error("fit-variogram: the optimizer failed: " + r.message);
}

void add_fit_variogram_command(CLI::App& app) {
  auto args = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand(
      "fit-variogram",
      "Fit a variogram model to an empirical variogram by weighted least squares (as gstat's\n"
      "fit.variogram): minimizes sum_j w_j (gamma_j - model(h_j))^2 over the non-empty bins.\n"
      "Input: the CSV of 'errfield variogram' (lag_mean,gamma,pairs; gstat's dist,gamma,np also\n"
      "work). Prints the fitted model, e.g. sph(sill=0.3,range=400)+nug(sill=0.002), its\n"
      "parameters and the weighted SSE; --out writes it as JSON (readable as a model).");
  cmd->add_option("--input", args->input, "empirical variogram CSV")->required();
  cmd->add_option("--model", args->model, "sph, exp, gau, mat (needs --nu), wen, pow or lin")->required();
  cmd->add_option("--nu", args->nu, "Matérn smoothness nu (gstat's kappa), fixed during the fit")
      ->each([args](const std::string&) { args->nu_given = true; });
  cmd->add_option("--nugget", args->nugget, "free (default), fixed=V (value unit^2) or none");
  cmd->add_option("--weights", args->weights,
                  "nj (N_j, gstat fit.method 1), nj_h2 (N_j/h_j^2, method 7, default), cressie "
                  "(N_j/model(h_j)^2, method 2)");
  cmd->add_option("--range-max", args->range_max,
                  "upper bound of the range (lag unit); default 100 x the largest lag");
  cmd->add_option("--out", args->out, "output JSON (written atomically)");
  cmd->footer(
      "Example:\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dL --bins 0:2200:200 --out vario.csv\n"
      "  errfield fit-variogram --input vario.csv --model sph --nugget free --weights nj_h2 --out model.json");
  cmd->callback([args] { run_fit(*args); });
}

Registration reg{"fit-variogram", 11, &add_fit_variogram_command};

}  // namespace
}  // namespace errfield::cli
