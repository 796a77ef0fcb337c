// `errfield fit-variogram`: fits a variogram model to the CSV that `errfield variogram` writes
// (weighted least squares), or by maximum likelihood (ML/REML) to the samples themselves.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iostream>
#include <limits>

#include <memory>
#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/covariate_sources.hpp"
#include "cli/duplicate_locations.hpp"
#include "cli/point_layer.hpp"
#include "cli/command_registry.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/value_cells.hpp"
#include "cli/variogram_svg.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/coregionalization_fit.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/heterotopic_variogram.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/range_plausibility.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield::cli {
namespace {

struct FitVariogramArgs {
  std::string input, model, nugget = "free", weights = "nj_h2", out;
  std::string method = "wls", coords, value, anisotropy = "none", kind = "ordinary";
  std::string covariates;  // ml/reml: external-drift columns in F
  bool weights_given = false, range_max_given = false, anisotropy_given = false, kind_given = false;
  std::string nu_text;
  bool nu_given = false;
  std::string likelihood = "auto", ordering = "maxmin";
  int neighbours = LikelihoodFitOptions{}.vecchia_neighbours;
  bool likelihood_given = false;
  std::vector<std::string> vecchia_given;  // --vecchia-neighbours / --vecchia-ordering, as given
  double range_max = 0.0;
  bool lmc = false;                         // --lmc: fit a linear model of coregionalization
  std::string lmc_method = "goulard-voltz";
  bool lmc_method_given = false;
  bool nugget_given = false;
  std::string fix;  // --fix: parameters held at the template's values
  std::string plot;  // --plot FILE.svg (wls): the variogram and the fitted curve
  std::string duplicates = "keep";  // --duplicates keep|average|first|refuse (ml/reml)
};

/// --model as a nested template with starting values, in the model text interpolate reads
/// (`nug(sill=2e4)+sph(sill=3e4,range=25)+sph(sill=4e4,range=80)`, gstat's vgm(..., add.to = ...)):
/// the non-nugget components are the structure, the nug term the nugget's starting value.
struct FitTemplate {
  std::vector<ModelComponent> structure;
  double nugget_start = 0.0;  ///< the template's nug sill; 0: the template has none
  bool has_nugget = false;
};

bool is_template(const std::string& model) { return model.find('(') != std::string::npos; }

FitTemplate parse_fit_template(const FitVariogramArgs& a) {
  if (a.nu_given)
    throw ArgumentError("--nu with a model template: give the Matérn nu in the template, e.g. mat(sill=1,range=50,nu=1.5)");
  VariogramModel m = [&] {
    try {
      return VariogramModel::parse(a.model);
    } catch (const ArgumentError& e) {
      throw ArgumentError(std::string("--model: ") + e.what());
    }
  }();
  if (!m.anisotropy().isotropic())
    throw ArgumentError("--model " + a.model + ": fit-variogram fits an isotropic model to an empirical variogram (or "
                        "--anisotropy for ml/reml); leave the @... anisotropy out of the template");
  FitTemplate t;
  for (const ModelComponent& c : m.components()) {
    if (c.kind == ModelKind::Nugget) {
      if (t.has_nugget) throw ArgumentError("--model " + a.model + ": more than one nug term; expected at most one");
      t.has_nugget = true;
      t.nugget_start = c.sill;
    } else {
      t.structure.push_back(c);
    }
  }
  if (t.structure.empty())
    throw ArgumentError("--model " + a.model + ": no structure besides the nugget; nothing to fit");
  return t;
}

/// --fix LIST: `sill`, `range` (every structure), `sillK`, `rangeK` (the K-th structure of the
/// template, 1-based, nugget not counted), `nugget` (held at the template's nug). gstat's
/// fit.sills / fit.ranges = FALSE.
struct Holds {
  std::vector<bool> sill, range;
  bool nugget = false;
};

Holds parse_holds(const std::string& text, const FitTemplate& t, const std::string& model) {
  Holds h;
  if (text.empty()) return h;
  const std::size_t k = t.structure.size();
  h.sill.assign(k, false);
  h.range.assign(k, false);
  for (const std::string& item : split_column_list(text, "--fix")) {
    auto index_after = [&](const std::string& prefix) -> std::size_t {
      const std::string rest = item.substr(prefix.size());
      if (rest.empty()) return 0;
      std::size_t i = 0;
      const auto res = std::from_chars(rest.data(), rest.data() + rest.size(), i);
      if (res.ec != std::errc() || res.ptr != rest.data() + rest.size() || i < 1 || i > k)
        throw ArgumentError("--fix: '" + item + "'; the template " + model + " has " + std::to_string(k) +
                            " structure(s) besides the nugget: expected " + prefix + " or " + prefix + "1.." +
                            prefix + std::to_string(k));
      return i;
    };
    auto mark = [&](std::vector<bool>& v, std::size_t i) {
      if (i == 0) std::fill(v.begin(), v.end(), true);
      else v[i - 1] = true;
    };
    if (item == "nugget" || item == "nug") {
      if (!t.has_nugget)
        throw ArgumentError("--fix nugget: the template " + model + " has no nug term to hold; add e.g. nug(sill=0.1)");
      h.nugget = true;
    } else if (item.rfind("sill", 0) == 0) {
      mark(h.sill, index_after("sill"));
    } else if (item.rfind("range", 0) == 0) {
      mark(h.range, index_after("range"));
    } else {
      throw ArgumentError("--fix: '" + item + "'; expected sill, range, sillK, rangeK (K = a structure of the "
                          "template, 1-based) or nugget");
    }
  }
  return h;
}

double parse_cell(const CsvTable& t, std::size_t r, std::size_t c) {
  return t.numeric_cell(r, c);
}

std::size_t find_column(const CsvTable& t, const char* ours, const char* gstat) {
  if (t.has_column(ours) || !t.has_column(gstat)) return t.column_index(ours);  // throws listing columns
  return t.column_index(gstat);
}

ModelComponent structure_from(const FitVariogramArgs& a) {
  ModelComponent structure;
  structure.kind = model_kind_from_name(a.model);
  if (structure.kind == ModelKind::Nugget)
    throw ArgumentError("--model: 'nug' alone has nothing to fit; use --nugget for the nugget");
  if (structure.kind == ModelKind::Matern && !a.nu_given)
    throw ArgumentError("--model mat needs --nu (the Matérn smoothness, e.g. 0.5, 1.5, 2.5; with --method ml|reml "
                        "also 'auto': the most likely of 0.5, 1.5 and 2.5)");
  if (structure.kind != ModelKind::Matern && a.nu_given)
    throw ArgumentError("--nu applies to --model mat only (the Matérn smoothness), not --model " + a.model);
  if (a.nu_given && a.nu_text != "auto") {
    const auto res = std::from_chars(a.nu_text.data(), a.nu_text.data() + a.nu_text.size(), structure.nu);
    if (a.nu_text.empty() || res.ec != std::errc() || res.ptr != a.nu_text.data() + a.nu_text.size() ||
        !(structure.nu > 0.0 && structure.nu <= kMaxMaternNu))
      throw ArgumentError("--nu: '" + a.nu_text + "'; expected a number in (0, " + format_number(kMaxMaternNu) + "]" +
                          (a.method == "wls" ? std::string() : std::string(" or auto")));
  } else if (a.nu_given && a.method == "wls") {
    throw ArgumentError("--nu auto applies to --method ml or reml; give --nu a number with --method wls");
  } else {
    structure.nu = 2.5;  // a placeholder for 'auto': the fit tries 0.5, 1.5 and 2.5
  }
  return structure;
}

void print_components(const VariogramModel& model) {
  std::cout << model.to_string() << "\n";
  for (const auto& c : model.components()) {
    std::cout << "  " << model_kind_name(c.kind) << ": "
              << (c.kind == ModelKind::Linear ? "slope" : "sill") << " = " << format_number(c.sill);
    if (c.kind == ModelKind::Power) std::cout << ", exponent = " << format_number(c.range);
    else if (c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear)
      std::cout << ", range = " << format_number(c.range);
    if (c.kind == ModelKind::Matern) std::cout << ", nu = " << format_number(c.nu);
    std::cout << "\n";
  }
}

// The exact likelihood is O(N^3) per evaluation and a fit needs hundreds: beyond
// kMaxLikelihoodSamples it is refused up front (exit 3) with the alternative named; --likelihood
// auto (the default) switches to the Vecchia approximation above kExactLikelihoodMaxSamples, which
// has its own sample and memory budget (check_likelihood_budget, shared with the library and Python).

LikelihoodMethod likelihood_method_from(const std::string& text) {
  if (text == "auto") return LikelihoodMethod::Auto;
  if (text == "exact") return LikelihoodMethod::Exact;
  if (text == "vecchia") return LikelihoodMethod::Vecchia;
  throw ArgumentError("--likelihood: '" + text + "'; expected auto, exact or vecchia");
}

VecchiaOrdering vecchia_ordering_from(const std::string& text) {
  if (text == "maxmin") return VecchiaOrdering::MaxMin;
  if (text == "random") return VecchiaOrdering::Random;
  if (text == "coordinate") return VecchiaOrdering::Coordinate;
  throw ArgumentError("--vecchia-ordering: '" + text + "'; expected maxmin, random or coordinate");
}

// --method ml|reml: the options the likelihood reads, checked in the order the user reads them.
LikelihoodFitOptions likelihood_fit_options(const FitVariogramArgs& a) {
  if ((a.coords.empty() && !is_vector_path(a.input)) || a.value.empty())
    throw ArgumentError("--method " + a.method + " fits the samples themselves: give --coords and --value "
                        "(the columns of --input), e.g. --coords x,y --value z");
  if (a.weights_given) throw ArgumentError("--weights applies to --method wls only");
  if (a.range_max_given) throw ArgumentError("--range-max applies to --method wls only");
  LikelihoodFitOptions o;
  o.restricted = a.method == "reml";
  if (a.anisotropy == "ard") o.anisotropy = LikelihoodFitOptions::Anisotropy::Ard;
  else if (a.anisotropy == "rotated" || a.anisotropy == "anis") o.anisotropy = LikelihoodFitOptions::Anisotropy::Rotated;
  else if (a.anisotropy != "none")
    throw ArgumentError("--anisotropy: '" + a.anisotropy + "'; expected none, ard or rotated (anis)");
  if (a.kind == "ordinary") o.kind = KrigingKind::Ordinary;
  else if (a.kind == "universal1" || a.kind == "universal2") {
    o.kind = KrigingKind::Universal;
    o.drift_order = a.kind == "universal1" ? 1 : 2;
  } else if (a.kind == "simple0") {
    o.kind = KrigingKind::Simple;
  } else {
    throw ArgumentError("--kind: '" + a.kind + "'; expected ordinary, universal1, universal2 or simple0 (known mean 0)");
  }
  if (a.nu_given && a.nu_text == "auto") o.matern_nu_choices = {0.5, 1.5, 2.5};
  if (a.nugget == "free") o.fit_nugget = true;
  else if (a.nugget == "none") o.fit_nugget = false;
  else throw ArgumentError("--nugget: '" + a.nugget + "'; with --method " + a.method + " expected free or none");
  return o;
}

// The structures to fit: a template's (with its holds and nugget start in `o`), or --model's one.
std::vector<ModelComponent> likelihood_structure(const FitVariogramArgs& a, LikelihoodFitOptions& o) {
  std::vector<ModelComponent> structure;
  if (is_template(a.model)) {
    const FitTemplate tmpl = parse_fit_template(a);
    structure = tmpl.structure;
    const Holds holds = parse_holds(a.fix, tmpl, a.model);
    if (holds.nugget)
      throw ArgumentError("--fix nugget applies to --method wls; the likelihood fit estimates the nugget (free) or "
                          "has none (--nugget none)");
    o.hold_sill = holds.sill;
    o.hold_range = holds.range;
    if (!a.nugget_given) o.fit_nugget = tmpl.has_nugget;
    if (o.fit_nugget) o.nugget_start = tmpl.nugget_start;
    if (structure.size() > 1 && o.anisotropy != LikelihoodFitOptions::Anisotropy::None)
      throw ArgumentError("--anisotropy " + a.anisotropy + " fits one structure; the template " + a.model + " has " +
                          std::to_string(structure.size()));
  } else {
    if (!a.fix.empty())
      throw ArgumentError("--fix holds parameters at a template's values: give --model as a template with values, "
                          "e.g. 'nug(sill=0.1)+sph(sill=1,range=400)'");
    structure = {structure_from(a)};
  }
  for (const ModelComponent& c : structure)
    if (c.kind == ModelKind::Power || c.kind == ModelKind::Linear)
      throw ArgumentError("--model " + a.model + ": the likelihood needs a covariance, i.e. a bounded model for every structure "
                          "(sph, exp, gau, mat, wen)");
  return structure;
}

void set_likelihood_method(const FitVariogramArgs& a, LikelihoodFitOptions& o) {
  o.method = likelihood_method_from(a.likelihood);
  o.vecchia_ordering = vecchia_ordering_from(a.ordering);
  o.vecchia_neighbours = a.neighbours;
  if (o.vecchia_neighbours < 1 || o.vecchia_neighbours > kMaxVecchiaNeighbours)
    throw ArgumentError("--vecchia-neighbours: " + std::to_string(a.neighbours) + "; expected 1 to " +
                        std::to_string(kMaxVecchiaNeighbours));
  o.validate();
}

// The samples' count against what the chosen likelihood can afford, before any matrix is built.
void check_likelihood_size(const FitVariogramArgs& a, const LikelihoodFitOptions& o, std::size_t rows,
                           std::size_t values, std::size_t coords) {
  if (!likelihood_uses_vecchia(o, static_cast<long>(rows)) && rows > static_cast<std::size_t>(kMaxLikelihoodSamples))
    throw ResourceError(a.input + ": " + std::to_string(rows) + " samples; --method " + a.method +
                        " --likelihood exact costs O(N^3) per evaluation and is limited to " +
                        std::to_string(kMaxLikelihoodSamples) +
                        ": use --likelihood vecchia (or auto), --method wls on the empirical variogram ('errfield "
                        "variogram'), or a subsample");
  // Options of the Vecchia likelihood on a fit that uses the exact one did nothing, silently.
  if (!a.vecchia_given.empty() && !likelihood_uses_vecchia(o, static_cast<long>(rows))) {
    std::string given;
    for (const auto& g : a.vecchia_given) given += (given.empty() ? "" : ", ") + g;
    throw ArgumentError(given + ": " + (a.vecchia_given.size() > 1 ? "they apply" : "it applies") +
                        " to the Vecchia likelihood, but this fit uses the exact one (" +
                        (o.method == LikelihoodMethod::Exact
                             ? std::string("--likelihood exact")
                             : "--likelihood auto with " + std::to_string(rows) + " samples: exact up to " +
                                   std::to_string(kExactLikelihoodMaxSamples)) +
                        "); drop " + (a.vecchia_given.size() > 1 ? "them" : "it") + " or give --likelihood vecchia");
  }
  naming_options(
      [&] {
        check_likelihood_budget(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(values), o,
                                static_cast<int>(coords));
      },
      {{"(vecchia_neighbours)", "(--vecchia-neighbours)"},
       {"(anisotropy ard:", "(--anisotropy ard:"},
       {"(likelihood vecchia,", "(--likelihood vecchia,"}});
  if (rows < static_cast<std::size_t>(kMinLikelihoodSamples))
    throw InputError(a.input + ": " + std::to_string(rows) + " data row(s); the likelihood fit needs "
                     "at least " + std::to_string(kMinLikelihoodSamples) + " samples", a.input);
}

// The samples of a likelihood fit: coordinates, values and (external drift) covariates.
struct LikelihoodSamples {
  std::vector<std::string> value_names, coord_names, covariate_names;
  std::size_t rows = 0;
  Eigen::MatrixXd x, z;
};

LikelihoodSamples read_likelihood_samples(const FitVariogramArgs& a, LikelihoodFitOptions& o) {
  LikelihoodSamples s;
  s.value_names = split_column_list(a.value, "--value");
  // A CSV, or a point layer (GeoPackage, shapefile, GeoJSON) whose points give the coordinates.
  const PointTable points = read_point_table(a.input, "--input", {s.value_names});
  const CsvTable& t = points.table;
  s.coord_names = points.coordinate_columns(a.coords, "--coords");
  CoordinateSystem crs;  // the layer's; a covariate raster in another CRS is refused
  crs.add(points.crs, "--input " + a.input, a.input);
  if (const std::string w = crs.geographic_warning(); !w.empty()) std::cerr << "errfield fit-variogram: " << w << "\n";
  s.rows = t.row_count();
  check_likelihood_size(a, o, t.row_count(), s.value_names.size(), s.coord_names.size());
  s.x = t.numeric_columns(s.coord_names);
  s.z = t.numeric_columns(s.value_names);
  apply_duplicates_option(a.duplicates, "fit-variogram", !a.covariates.empty(), t, s.x, s.z);
  s.covariate_names = a.covariates.empty() ? std::vector<std::string>{} : split_column_list(a.covariates, "--covariates");
  if (!s.covariate_names.empty()) {
    if (o.kind == KrigingKind::Simple)
      throw ArgumentError("--covariates with --kind simple0; expected --kind ordinary (external drift) or universal1/2");
    // COL or NAME=RASTER (the pixel at each point), as interpolate's external drift takes them.
    const CovariateSources sources = covariate_sources(s.covariate_names, &crs);
    o.covariates = covariate_values(sources, t, s.x, points.labels("sample"));
    o.covariate_names = sources.names;
  }
  return s;
}

// The fitted ranges (and, rotated, angles) with their standard errors: printed, and kept for --out.
struct RangeReport {
  nlohmann::json ranges = nlohmann::json::array(), errors = nlohmann::json::array();
  nlohmann::json angles = nlohmann::json::array(), angle_errors = nlohmann::json::array();
};

RangeReport print_ranges(const LikelihoodFitResult& r, const LikelihoodFitOptions& o,
                         const std::vector<std::string>& coord_names) {
  RangeReport out;
  const bool rotated = !r.angles_deg.empty();
  static const char* const kAxes[] = {"the major axis", "minor axis 1", "minor axis 2"};
  for (std::size_t k = 0; k < r.ranges.size(); ++k) {
    const std::string along = rotated ? std::string(r.ranges.size() == 2 && k == 1 ? "the minor axis" : kAxes[std::min<std::size_t>(k, 2)])
                                      : coord_names[std::min(k, coord_names.size() - 1)];
    // Isotropic: one range per structure of the template (not one per coordinate).
    const bool per_structure = o.anisotropy == LikelihoodFitOptions::Anisotropy::None;
    const std::string label = r.ranges.size() < 2 ? std::string()
                              : per_structure     ? " of structure " + std::to_string(k + 1)
                                                  : " along " + along;
    std::cout << "  range" << label << " = " << format_number(r.ranges[k]);
    // A held range has no standard error ("+- nan" said nothing); nor has a fit of held parameters (BOBYQA).
    const std::size_t structure = std::min(k, o.hold_range.empty() ? std::size_t{0} : o.hold_range.size() - 1);
    if (std::isfinite(r.range_standard_errors[k]))
      std::cout << " +- " << format_number(r.range_standard_errors[k]) << " (standard error)\n";
    else if (!o.hold_range.empty() && o.hold_range[structure])
      std::cout << " (held at the template's value by --fix: no standard error)\n";
    else
      std::cout << " (no standard error: the derivative-free fit used with --fix does not estimate one)\n";
    out.ranges.push_back(r.ranges[k]);
    out.errors.push_back(std::isfinite(r.range_standard_errors[k]) ? nlohmann::json(r.range_standard_errors[k]) : nlohmann::json());
  }
  static const char* const kAngles3[] = {"azimuth", "dip", "rotation"};
  for (std::size_t k = 0; k < r.angles_deg.size(); ++k) {
    std::cout << "  " << (r.angles_deg.size() == 1 ? "angle" : kAngles3[k]) << " = " << format_number(r.angles_deg[k])
              << " deg +- " << format_number(r.angle_standard_errors_deg[k])
              << " (standard error, from the profile likelihood's curvature)\n";
    out.angles.push_back(r.angles_deg[k]);
    out.angle_errors.push_back(std::isfinite(r.angle_standard_errors_deg[k]) ? nlohmann::json(r.angle_standard_errors_deg[k])
                                                                              : nlohmann::json());
  }
  return out;
}

nlohmann::json likelihood_fit_json(const FitVariogramArgs& a, const LikelihoodFitOptions& o, const LikelihoodSamples& s,
                                   const LikelihoodFitResult& r, const RangeReport& report, bool vecchia_fit) {
  nlohmann::json j = r.model;
  j["fit"] = {{"method", a.method},
              {"likelihood", vecchia_fit ? "vecchia" : "exact"},
              {"nugget", a.nugget},
              {"anisotropy", a.anisotropy},
              {"kind", a.kind},
              {"coords", s.coord_names},
              {"covariates", s.covariate_names},
              {"values", s.value_names},
              {"ranges", report.ranges},
              {"range_standard_errors", report.errors},
              {"aic", r.aic},
              {"bic", r.bic},
              {"parameters", r.parameters},
              {"negative_log_likelihood", r.negative_log_likelihood},
              {"samples", s.rows},
              {"evaluations", r.evaluations},
              {"status", r.converged ? "converged" : "not_converged"},
              {"message", r.message},
              {"input", a.input}};
  if (vecchia_fit) {
    j["fit"]["vecchia_neighbours"] = o.vecchia_neighbours;
    j["fit"]["vecchia_ordering"] = a.ordering;
  }
  if (!r.angles_deg.empty()) {
    j["fit"]["angles_deg"] = report.angles;
    j["fit"]["angle_standard_errors_deg"] = report.angle_errors;
  }
  return j;
}

/// ML/REML on the samples (kriging_likelihood.hpp): the likelihood of kriging of --kind (the mean
/// or drift profiled out), nugget free or none, isotropic or ARD, one value or a vector sharing one
/// model.
void run_likelihood_fit(const FitVariogramArgs& a) {
  const bool restricted = a.method == "reml";
  LikelihoodFitOptions o = likelihood_fit_options(a);
  const std::vector<ModelComponent> structure = likelihood_structure(a, o);
  set_likelihood_method(a, o);
  const LikelihoodSamples s = read_likelihood_samples(a, o);
  // A terminal sees what a long fit is doing (a 50,000-sample Vecchia fit takes tens of seconds).
  const bool vecchia_fit = likelihood_uses_vecchia(o, static_cast<long>(s.rows));
  const StageLog stage("fit-variogram", s.rows > 1000);
  stage(std::string(restricted ? "REML" : "ML") + " fit of " + std::to_string(s.rows) + " samples by the " +
        (vecchia_fit ? "Vecchia likelihood (" + std::to_string(o.vecchia_neighbours) + " neighbours per sample)"
                     : std::string("exact likelihood (O(N^3) per evaluation)")));
  const LikelihoodFitResult r = with_source(a.input, [&] { return fit_likelihood(s.x, s.z, structure, o); });
  stage("done");
  print_components(r.model);
  std::cout << (restricted ? "REML" : "ML") << " negative log-likelihood = " << format_number(r.negative_log_likelihood)
            << ", " << s.rows << " samples x " << s.value_names.size() << " value column(s), " << r.evaluations
            << " evaluations, status " << (r.converged ? "converged" : "not converged") << " (" << r.message << ")\n";
  std::cout << "AIC = " << format_number(r.aic) << ", BIC = " << format_number(r.bic) << " (" << r.parameters
            << " covariance parameters)\n";
  const RangeReport report = print_ranges(r, o, s.coord_names);
  if (!a.out.empty()) {
    const nlohmann::json j = likelihood_fit_json(a, o, s, r, report, vecchia_fit);
    require_standard_output();  // the fit went to standard output: all or nothing
    write_file_atomically(a.out, j.dump(2) + "\n");
  }
  if (!r.converged) std::cerr << "errfield fit-variogram: warning: " << r.message << "\n";
  // A free range below the samples' spacing (a nugget) or far beyond their extent (a trend) "converged"
  // silently before (issue 49: oxford's REML range 620 x the extent).
  const bool ranges_held = !o.hold_range.empty() && std::all_of(o.hold_range.begin(), o.hold_range.end(), [](bool h) { return h; });
  if (!ranges_held && r.angles_deg.empty())
    for (const std::string& w : implausible_ranges(r.model, s.x.colwise().maxCoeff() - s.x.colwise().minCoeff(), smallest_sample_spacing(s.x)))
      std::cerr << "errfield fit-variogram: warning: " << w << "\n";
}

/// --lmc on a CSV with one block of rows per variogram, column `id` naming it (A, or A.B / A_B for
/// the cross-variogram of A and B): 'errfield variogram --pseudo', or R gstat's variogram data frame
/// written with write.csv (columns id, np, dist, gamma). Each variogram keeps its own bins, lags and
/// pairs (a heterotopic table); rows with 0 pairs are skipped, and so are rows at lag 0 (gstat's zero
/// estimate of a pseudo cross-variogram: a weight N_j / h_j^2 would be infinite there), counted in
/// `skipped_zero_lag`.
CrossVariogramTable lmc_table_from_blocks(const CsvTable& t, const std::vector<std::string>& names, const std::string& value,
                                          std::size_t& skipped_zero_lag) {
  const std::size_t P = names.size();
  const std::size_t c_id = t.column_index("id");
  const std::size_t c_lag = find_column(t, "lag_mean", "dist");
  const std::size_t c_gamma = t.column_index("gamma");
  const std::size_t c_pairs = find_column(t, "pairs", "np");
  struct Row {
    double lag, pairs, gamma;
  };
  std::vector<std::vector<std::vector<Row>>> rows(P, std::vector<std::vector<Row>>(P));
  const auto where = [&](std::size_t r, std::size_t c) {
    return t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column '" + t.header()[c] + "': ";
  };
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    const std::string id(t.cell(r, c_id));
    std::size_t a = P, b = P;
    for (std::size_t i = 0; i < P; ++i)
      for (std::size_t j = i; j < P; ++j)
        if ((i == j && id == names[i]) ||
            (i != j && (id == names[i] + "." + names[j] || id == names[j] + "." + names[i] || id == names[i] + "_" + names[j] ||
                        id == names[j] + "_" + names[i]))) {
          a = i;
          b = j;
        }
    if (a == P)
      throw InputError(where(r, c_id) + "'" + id + "' names no variogram of --value " + value +
                           " (expected a column name, or A.B for the cross-variogram of A and B)",
                       t.source(), t.line_of_row(r), "id");
    const double np = parse_cell(t, r, c_pairs);
    if (np < 0.0 || np != std::floor(np))
      throw InputError(where(r, c_pairs) + format_number(np) + " is not a pair count (an integer >= 0)", t.source(),
                       t.line_of_row(r), t.header()[c_pairs]);
    if (np == 0.0) continue;  // an empty bin
    const double lag = parse_cell(t, r, c_lag);
    if (lag == 0.0) {
      ++skipped_zero_lag;
      continue;
    }
    rows[a][b].push_back({lag, np, parse_cell(t, r, c_gamma)});
  }
  std::size_t bins = 0;
  for (std::size_t i = 0; i < P; ++i)
    for (std::size_t j = i; j < P; ++j) {
      if (rows[i][j].empty())
        throw InputError(t.source() + ": no row with pairs > 0 for id '" + (i == j ? names[i] : names[i] + "." + names[j]) +
                             "'; --lmc needs every direct and cross variogram of --value " + value,
                         t.source(), 0, "id");
      bins = std::max(bins, rows[i][j].size());
    }
  CrossVariogramTable table;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto p = static_cast<Eigen::Index>(P);
  for (std::size_t k = 0; k < bins; ++k) {
    Eigen::MatrixXd g = Eigen::MatrixXd::Constant(p, p, nan), lag = g, pairs = Eigen::MatrixXd::Zero(p, p);
    double any_lag = nan, most_pairs = 0.0;
    for (std::size_t i = 0; i < P; ++i)
      for (std::size_t j = i; j < P; ++j) {
        if (k >= rows[i][j].size()) continue;
        const Row& row = rows[i][j][k];
        const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
        g(ii, jj) = g(jj, ii) = row.gamma;
        lag(ii, jj) = lag(jj, ii) = row.lag;
        pairs(ii, jj) = pairs(jj, ii) = row.pairs;
        if (std::isnan(any_lag)) any_lag = row.lag;
        most_pairs = std::max(most_pairs, row.pairs);
      }
    table.lag.push_back(any_lag);
    table.pairs.push_back(static_cast<std::uint64_t>(most_pairs));
    table.gamma.push_back(std::move(g));
    table.entry_lag.push_back(std::move(lag));
    table.entry_pairs.push_back(std::move(pairs));
  }
  return table;
}

// --lmc: the options that do not apply refused, and the components (at least two) of --value.
std::vector<std::string> lmc_components(const FitVariogramArgs& a) {
  if (a.method != "wls") throw ArgumentError("--lmc fits by weighted least squares; drop --method " + a.method);
  if (a.anisotropy_given || a.likelihood_given || a.kind_given || !a.covariates.empty())
    throw ArgumentError("--anisotropy, --likelihood, --kind and --covariates apply to --method ml or reml, not --lmc");
  if (a.range_max_given || a.nugget != "free")
    throw ArgumentError("--range-max and --nugget do not apply to --lmc: the template --model holds the structures "
                        "(e.g. nug(0)+sph(1,400))");
  if (a.value.empty())
    throw ArgumentError("--lmc needs --value A,B[,...]: the components (at least 2), whose gamma_<A> and gamma_<A>_<B> "
                        "columns --input holds (errfield variogram --cross), or value columns of the samples with --coords");
  const auto names = split_column_list(a.value, "--value");
  if (names.size() < 2)
    throw ArgumentError("--lmc needs at least 2 --value columns (got '" + a.value + "'); for one, fit without --lmc");
  return names;
}

CoregionalizationFitOptions lmc_fit_options(const FitVariogramArgs& a) {
  CoregionalizationFitOptions o;
  o.method = lmc_fit_method_from_name(a.lmc_method);
  if (a.weights == "cressie" || a.weights == "2")
    throw ArgumentError("--weights cressie with --lmc: its weights depend on each variogram's model; expected nj, "
                        "nj_h2 or unweighted");
  o.weighting = lmc_weighting_from_name(a.weights);
  return o;
}

CoregionalizationTemplate lmc_template(const FitVariogramArgs& a) {
  double nu = 0.0;
  if (a.nu_given) {
    const auto res = std::from_chars(a.nu_text.data(), a.nu_text.data() + a.nu_text.size(), nu);
    if (res.ec != std::errc() || res.ptr != a.nu_text.data() + a.nu_text.size() || !(nu > 0.0 && nu <= kMaxMaternNu))
      throw ArgumentError("--nu: '" + a.nu_text + "'; with --lmc expected a number in (0, " + format_number(kMaxMaternNu) + "]");
  }
  try {
    return parse_coregionalization_template(a.model, nu);
  } catch (const ArgumentError& e) {
    throw ArgumentError(std::string("--model: ") + e.what());
  }
}

// The samples: gstat's default bins and boundaries, as 'errfield variogram --cross' without --bins.
CrossVariogramTable lmc_table_from_samples(const FitVariogramArgs& a, const CsvTable& t,
                                           const std::vector<std::string>& names, const CoregionalizationTemplate& tmpl) {
  Eigen::MatrixXd x = t.numeric_columns(split_column_list(a.coords, "--coords"));
  // An empty cell: that component not measured there (heterotopic samples, as interpolate and
  // variogram read them); each direct and cross variogram is then over its own pairs.
  const Eigen::MatrixXd z = numeric_columns_with_gaps(t, names);
  if (!tmpl.anisotropy.isotropic()) {
    // An anisotropic template: the variograms of the mapped coordinates A x, where the LMC is isotropic.
    const int d = static_cast<int>(x.cols());
    if (tmpl.anisotropy.dimension() != d)
      throw ArgumentError("--model: the anisotropy @" + tmpl.anisotropy.to_string() + " is for " +
                          std::to_string(tmpl.anisotropy.dimension()) + " coordinates but --coords has " + std::to_string(d));
    Eigen::VectorXd in(d), out(d);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      in = x.row(r).transpose();
      tmpl.anisotropy.apply(in.data(), out.data(), d);
      x.row(r) = out.transpose();
    }
  }
  EmpiricalVariogramOptions vo;
  vo.convention = BinConvention::Gstat;
  vo.cross_variograms = true;
  if (z.array().isNaN().any()) {
    const HeterotopicVariogram h =
        with_source(a.input, [&] { return heterotopic_variogram(x, z, LagBins::gstat_default(x), vo); });
    return CrossVariogramTable::from(h);
  }
  const EmpiricalVariogram v = with_source(a.input, [&] { return empirical_variogram(x, z, LagBins::gstat_default(x), vo); });
  return CrossVariogramTable::from(v);
}

// The columns of 'variogram --cross': gamma_<A>[_<B>] per entry, and for heterotopic variograms
// each entry's own pairs_<A>[_<B>] and lag_mean_<A>[_<B>] (empty cells where it has no pair in a bin).
struct CrossColumns {
  std::size_t lag = 0, pairs = 0;
  std::vector<std::vector<std::size_t>> gamma, entry_pairs, entry_lag;
  bool heterotopic = false;
};

CrossColumns cross_columns(const FitVariogramArgs& a, const CsvTable& t, const std::vector<std::string>& names) {
  const std::size_t P = names.size();
  CrossColumns c;
  c.lag = find_column(t, "lag_mean", "dist");
  c.pairs = find_column(t, "pairs", "np");
  c.gamma.assign(P, std::vector<std::size_t>(P));
  for (std::size_t i = 0; i < P; ++i)
    for (std::size_t j = i; j < P; ++j) {
      const std::string name = i == j ? "gamma_" + names[i] : "gamma_" + names[i] + "_" + names[j];
      if (!t.has_column(name))
        throw InputError(a.input + ": no column '" + name + "'; --lmc reads the CSV of 'errfield variogram --value " +
                             a.value + " --cross' (or give --coords to fit the samples in --input)",
                         a.input, 0, name);
      c.gamma[i][j] = c.gamma[j][i] = t.column_index(name);
    }
  c.heterotopic = t.has_column("pairs_" + names[0]);
  c.entry_pairs.assign(P, std::vector<std::size_t>(P));
  c.entry_lag = c.entry_pairs;
  if (c.heterotopic)
    for (std::size_t i = 0; i < P; ++i)
      for (std::size_t j = i; j < P; ++j) {
        const std::string suffix = i == j ? names[i] : names[i] + "_" + names[j];
        for (const std::string& name : {"pairs_" + suffix, "lag_mean_" + suffix})
          if (!t.has_column(name))
            throw InputError(a.input + ": column 'pairs_" + names[0] + "' (heterotopic variograms) but no column '" + name +
                                 "'; --lmc reads the CSV of 'errfield variogram --value " + a.value + " --cross'",
                             a.input, 0, name);
        c.entry_pairs[i][j] = c.entry_pairs[j][i] = t.column_index("pairs_" + suffix);
        c.entry_lag[i][j] = c.entry_lag[j][i] = t.column_index("lag_mean_" + suffix);
      }
  for (const char* label : {"direction", "dip", "coordinate"})
    if (t.has_column(label))
      throw InputError(a.input + ": column '" + label + "': a directional variogram; --lmc fits one isotropic LMC",
                       a.input, 0, label);
  return c;
}

// One bin of 'variogram --cross' per row; empty bins (0 pairs) have empty cells and are skipped.
CrossVariogramTable lmc_table_from_columns(const FitVariogramArgs& a, const CsvTable& t,
                                           const std::vector<std::string>& names) {
  const std::size_t P = names.size();
  CrossVariogramTable table;
  const CrossColumns c = cross_columns(a, t, names);
  for (std::size_t r = 0; r < t.row_count(); ++r) {
    const double np = parse_cell(t, r, c.pairs);
    if (np < 0.0 || np != std::floor(np))
      throw InputError(t.source() + ":" + std::to_string(t.line_of_row(r)) + ": column '" + t.header()[c.pairs] +
                           "': " + format_number(np) + " is not a pair count (an integer >= 0)",
                       t.source(), t.line_of_row(r), t.header()[c.pairs]);
    if (np == 0.0) continue;  // empty bin: empty cells
    const auto p = static_cast<Eigen::Index>(P);
    Eigen::MatrixXd g(p, p);
    if (c.heterotopic) {
      // An entry without pairs in this bin has empty cells: NaN gamma and lag, 0 pairs.
      auto cell_or_nan = [&](std::size_t col) {
        return t.cell(r, col).empty() ? std::numeric_limits<double>::quiet_NaN() : parse_cell(t, r, col);
      };
      Eigen::MatrixXd lag(p, p), pairs(p, p);
      for (std::size_t i = 0; i < P; ++i)
        for (std::size_t j = 0; j < P; ++j) {
          const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
          const double n = t.cell(r, c.entry_pairs[i][j]).empty() ? 0.0 : parse_cell(t, r, c.entry_pairs[i][j]);
          pairs(ii, jj) = n;
          lag(ii, jj) = n > 0.0 ? cell_or_nan(c.entry_lag[i][j]) : std::numeric_limits<double>::quiet_NaN();
          g(ii, jj) = n > 0.0 ? cell_or_nan(c.gamma[i][j]) : std::numeric_limits<double>::quiet_NaN();
        }
      table.entry_lag.push_back(std::move(lag));
      table.entry_pairs.push_back(std::move(pairs));
    } else {
      for (std::size_t i = 0; i < P; ++i)
        for (std::size_t j = 0; j < P; ++j) g(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = parse_cell(t, r, c.gamma[i][j]);
    }
    table.lag.push_back(parse_cell(t, r, c.lag));
    table.pairs.push_back(static_cast<std::uint64_t>(np));
    table.gamma.push_back(std::move(g));
  }
  if (table.lag.empty()) throw InputError(a.input + ": no bin with pairs > 0; nothing to fit", a.input);
  return table;
}

// The direct and cross variograms: from the samples (--coords), from blocks of rows by id, or from
// the columns of 'variogram --cross'.
CrossVariogramTable lmc_variograms(const FitVariogramArgs& a, const std::vector<std::string>& names,
                                   const CoregionalizationTemplate& tmpl) {
  const CsvTable t = CsvTable::read(a.input);
  if (!a.coords.empty()) return lmc_table_from_samples(a, t, names, tmpl);
  if (t.has_column("id")) {
    if (!tmpl.anisotropy.isotropic())
      throw ArgumentError("--model: an anisotropic template (@" + tmpl.anisotropy.to_string() +
                          ") needs the samples (--coords); a variogram CSV's lags are already computed");
    std::size_t zero_lag = 0;
    CrossVariogramTable table = lmc_table_from_blocks(t, names, a.value, zero_lag);
    std::cout << "variograms by id (errfield variogram --pseudo, or gstat's variogram data frame): each with its own "
                 "bins; a pseudo cross-variogram A.B is fitted as the cross-variogram of the LMC, as gstat's fit.lmc "
                 "does"
              << (zero_lag ? " (" + std::to_string(zero_lag) + " row(s) at lag 0 left out)" : std::string()) << "\n";
    return table;
  }
  if (!tmpl.anisotropy.isotropic())
    throw ArgumentError("--model: an anisotropic template (@" + tmpl.anisotropy.to_string() +
                        ") needs the samples (--coords), whose coordinates are mapped before the variograms; a "
                        "variogram CSV's lags are already computed");
  return lmc_table_from_columns(a, t, names);
}

void print_lmc(const CoregionalizationFitResult& r, const CoregionalizationModel& model,
               const CoregionalizationFitOptions& o, std::size_t P) {
  std::cout << "LMC (" << lmc_fit_method_name(o.method) << ", weights " << lmc_weighting_name(o.weighting) << ") of "
            << P << " components over " << r.bins_used << " bins:\n";
  for (std::size_t k = 0; k < r.model.structures().size(); ++k) {
    const CoregionalizationStructure& s = r.model.structures()[k];
    std::cout << "  " << model_kind_name(s.kind);
    if (s.kind != ModelKind::Nugget) std::cout << "(range=" << format_number(s.range) << ")";
    std::cout << "  B = [";
    for (Eigen::Index i = 0; i < s.sills.rows(); ++i) {
      std::cout << (i ? "; " : "");
      for (Eigen::Index j = 0; j < s.sills.cols(); ++j) std::cout << (j ? ", " : "") << format_number(s.sills(i, j));
    }
    const double e = r.smallest_eigenvalue_before_projection[k];
    std::cout << "]  smallest eigenvalue before projection " << format_number(e)
              << (e < 0.0 ? " (clipped to 0: PSD enforced)" : "") << "\n";
  }
  std::cout << "weighted residual = " << format_number(r.weighted_residual) << ", " << r.iterations
            << " iteration(s), " << r.message << "\n";
  if (!model.anisotropy().isotropic())
    std::cout << "anisotropy @" << model.anisotropy().to_string()
              << " (from --model): the variograms are of the mapped coordinates, and the LMC keeps the map\n";
}

/// --lmc: the direct and cross variograms of --value's columns (from a CSV of 'variogram --cross',
/// or computed from the samples with --coords), then the LMC fit (coregionalization_fit.hpp).
void run_lmc_fit(const FitVariogramArgs& a) {
  const auto names = lmc_components(a);
  CoregionalizationFitOptions o = lmc_fit_options(a);
  const CoregionalizationTemplate tmpl = lmc_template(a);
  std::vector<ModelComponent> structures = tmpl.structures;
  const bool ranges_given = tmpl.ranges_given;
  const std::size_t P = names.size();
  const CrossVariogramTable table = lmc_variograms(a, names, tmpl);
  if (table.heterotopic() && !a.lmc_method_given && o.method != LmcFitMethod::Gstat) {
    // gstat's fit.lmc is the fit of heterotopic variograms (each with its own bins and weights).
    o.method = LmcFitMethod::Gstat;
    std::cout << "heterotopic variograms (empty --value cells: each over its own pairs and lags): fitted as gstat's "
                 "fit.lmc (--lmc-method gstat)\n";
  }
  if (!ranges_given) {
    structures = with_source(a.input, [&] { return fit_coregionalization_ranges(table, structures, o.weighting, names); });
    std::cout << "ranges fitted to the mean of the " << P << " direct variograms:";
    for (const ModelComponent& c : structures)
      if (c.kind != ModelKind::Nugget) std::cout << " " << model_kind_name(c.kind) << " " << format_number(c.range);
    std::cout << "\n";
  }
  const CoregionalizationFitResult r = with_source(a.input, [&] { return fit_coregionalization(table, structures, o, names); });
  // The fit is isotropic in the mapped coordinates; the model keeps the template's map.
  const CoregionalizationModel model(r.model.structures(), tmpl.anisotropy, r.model.component_names());
  print_lmc(r, model, o, P);
  if (!a.out.empty()) {
    nlohmann::json j = model;
    j["fit"] = {{"method", std::string(lmc_fit_method_name(o.method))},
                {"weights", std::string(lmc_weighting_name(o.weighting))},
                {"ranges", ranges_given ? "given" : "fitted"},
                {"weighted_residual", r.weighted_residual},
                {"iterations", r.iterations},
                {"converged", r.converged},
                {"smallest_eigenvalue_before_projection", r.smallest_eigenvalue_before_projection},
                {"bins_used", r.bins_used},
                {"input", a.input}};
    require_standard_output();  // the fit went to standard output: all or nothing
    write_file_atomically(a.out, j.dump(2) + "\n");
  }
  if (!r.converged) std::cerr << "errfield fit-variogram: warning: " << r.message << "\n";
}

// --method wls reads an empirical variogram: the options of the samples' likelihood are refused.
void refuse_likelihood_options(const FitVariogramArgs& a) {
  if (a.anisotropy_given) throw ArgumentError("--anisotropy applies to --method ml or reml");
  if (a.likelihood_given)
    throw ArgumentError("--likelihood, --vecchia-neighbours and --vecchia-ordering apply to --method ml or reml");
  if (a.kind_given) throw ArgumentError("--kind applies to --method ml or reml");
  if (!a.covariates.empty())
    throw ArgumentError("--covariates applies to --method ml or reml; for wls, fit the residual variogram of "
                        "'errfield variogram --covariates'");
  if (!a.coords.empty() || !a.value.empty())
    throw ArgumentError("--coords/--value belong to --method ml or reml; --method wls reads an empirical variogram");
}

VariogramFitOptions wls_fit_options(const FitVariogramArgs& a) {
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
  // 0 means "the default" to the library; given on the command line it is a mistake, not a request.
  if (a.range_max_given && !(std::isfinite(a.range_max) && a.range_max > 0.0))
    throw ArgumentError("--range-max: " + format_number(a.range_max) + "; expected a finite range > 0 (lag unit)");
  o.range_max = a.range_max;
  return o;
}

// The structures to fit: a template's (its holds and nug in `o`), or --model's one.
std::vector<ModelComponent> wls_structure(const FitVariogramArgs& a, VariogramFitOptions& o) {
  if (!is_template(a.model)) {
    if (!a.fix.empty())
      throw ArgumentError("--fix holds parameters at a template's values: give --model as a template with values, "
                          "e.g. 'nug(sill=0.1)+sph(sill=1,range=400)'");
    return {structure_from(a)};
  }
  const FitTemplate tmpl = parse_fit_template(a);
  const Holds holds = parse_holds(a.fix, tmpl, a.model);
  o.hold_sill = holds.sill;
  o.hold_range = holds.range;
  // The template's nug: the nugget's starting value (free), or its value when held. An explicit
  // --nugget fixed=V|none overrides it.
  if (holds.nugget) {
    if (a.nugget_given && a.nugget != "free")
      throw ArgumentError("--fix nugget and --nugget " + a.nugget + ": hold the template's nug, or give --nugget, not both");
    o.nugget = NuggetMode::Fixed;
    o.nugget_value = tmpl.nugget_start;
  } else if (!a.nugget_given) {
    o.nugget = tmpl.has_nugget ? NuggetMode::Free : NuggetMode::None;
    o.nugget_start = tmpl.nugget_start;
  } else if (o.nugget == NuggetMode::Free) {
    o.nugget_start = tmpl.nugget_start;
  }
  return tmpl.structure;
}

// A directional variogram (errfield variogram --alpha/--beta/--per-coordinate) holds one block of
// rows per direction; one isotropic fit over all of them would pool what the user separated.
void refuse_several_directions(const FitVariogramArgs& a, const CsvTable& t) {
  for (const char* label : {"direction", "dip", "coordinate"}) {
    if (!t.has_column(label)) continue;
    const std::size_t c = t.column_index(label);
    std::vector<std::string> seen;
    for (std::size_t r = 0; r < t.row_count(); ++r)
      if (std::find(seen.begin(), seen.end(), t.cell(r, c)) == seen.end()) seen.emplace_back(t.cell(r, c));
    if (seen.size() > 1) {
      std::string list;
      for (std::size_t k = 0; k < seen.size() && k < 8; ++k) list += (k ? ", " : "") + seen[k];
      if (seen.size() > 8) list += ", ...";
      throw InputError(a.input + ": column '" + label + "' holds " + std::to_string(seen.size()) +
                           " directions (" + list + "); fit-variogram fits one isotropic model and would pool them. "
                           "Fit one direction at a time (its rows only, e.g. from 'errfield variogram --alpha A'), "
                           "or fit the anisotropy from the samples: --method reml --anisotropy rotated",
                       a.input, 0, label);
    }
  }
}

// The non-empty bins of an empirical variogram: lags, semivariances and pair counts.
struct EmpiricalBins {
  std::vector<double> h, g;
  std::vector<std::uint64_t> n;
};

// Columns of `errfield variogram` (lag_mean, gamma, pairs), or gstat's (dist, gamma, np).
EmpiricalBins read_empirical_bins(const FitVariogramArgs& a) {
  const CsvTable t = CsvTable::read(a.input);
  const std::size_t c_lag = find_column(t, "lag_mean", "dist");
  const std::size_t c_gamma = t.column_index("gamma");
  const std::size_t c_pairs = find_column(t, "pairs", "np");
  refuse_several_directions(a, t);
  EmpiricalBins b;
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
    b.h.push_back(lag);
    b.g.push_back(gamma);
    b.n.push_back(static_cast<std::uint64_t>(np));
  }
  if (b.h.empty()) throw InputError(a.input + ": no bin with pairs > 0; nothing to fit", a.input);
  return b;
}

// --out and --plot: both or neither.
void write_wls_outputs(const FitVariogramArgs& a, const VariogramFitOptions& o, const EmpiricalBins& b,
                       const VariogramFitResult& r, const char* status) {
  AtomicFileSet files;
  if (!a.plot.empty()) {
    VariogramPlot plot;
    for (std::size_t k = 0; k < b.h.size(); ++k) plot.bins.push_back({b.h[k], b.g[k], b.n[k]});
    if (r.status != FitStatus::Failed) plot.model = r.model;
    plot.title = "fit-variogram (" + std::string(weighting_name(o.weighting)) + ") of " + a.input;
    files.add(a.plot, variogram_svg_text(plot));
  }
  if (!a.out.empty()) {
    nlohmann::json j = r.model;
    j["fit"] = {{"weights", std::string(weighting_name(o.weighting))},
                {"nugget", a.nugget},
                {"template", is_template(a.model) ? a.model : std::string()},
                {"fix", a.fix},
                {"weighted_sse", r.weighted_sse},
                {"bins_used", r.bins_used},
                {"evaluations", r.evaluations},
                {"status", status},
                {"message", r.message},
                {"input", a.input}};
    files.add(a.out, j.dump(2) + "\n");
  }
  if (files.size() > 0) {
    require_standard_output();  // the fit went to standard output: all or nothing
    files.commit();
  }
}

void run_fit_variogram(const FitVariogramArgs& a) {
  if (!a.plot.empty() && (a.lmc || a.method != "wls"))
    throw ArgumentError("--plot draws the empirical variogram a --method wls fit was fitted to; " +
                        std::string(a.lmc ? "with --lmc" : "with --method " + a.method) +
                        " plot the samples' variogram with 'errfield variogram --plot' instead");
  if (a.duplicates != "keep" && (a.lmc || a.method == "wls"))
    throw ArgumentError("--duplicates applies to --method ml or reml (the samples themselves); for a variogram CSV give it "
                        "to 'errfield variogram'");
  if (a.lmc) return run_lmc_fit(a);
  if (a.lmc_method_given) throw ArgumentError("--lmc-method applies to --lmc");
  if (a.method == "ml" || a.method == "reml") return run_likelihood_fit(a);
  if (a.method != "wls") throw ArgumentError("--method: '" + a.method + "'; expected wls, ml or reml");
  refuse_likelihood_options(a);
  VariogramFitOptions o = wls_fit_options(a);
  const std::vector<ModelComponent> structure = wls_structure(a, o);
  o.validate();
  const EmpiricalBins b = read_empirical_bins(a);
  const VariogramFitResult r = fit_variogram(b.h, b.g, b.n, structure, o);
  const char* status = r.status == FitStatus::Converged        ? "converged"
                       : r.status == FitStatus::MaxEvaluations ? "max_evaluations"
                                                               : "failed";
  print_components(r.model);
  std::cout << "weighted SSE (" << weighting_name(o.weighting) << ") = " << format_number(r.weighted_sse)
            << ", " << r.bins_used << " bins, status " << status << " (" << r.message << ")\n";
  write_wls_outputs(a, o, b, r, status);
  if (r.status == FitStatus::Failed) throw Error("fit-variogram: the optimizer failed: " + r.message);
}

// What is fitted: an empirical variogram (wls) or the samples (ml, reml).
void add_input_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_option("--input", args->input, "empirical variogram CSV (wls), or the samples CSV (ml, reml)")->required();
  cmd->add_option("--method", args->method,
                  "wls (default: weighted least squares on the empirical variogram), ml or reml (likelihood of the "
                  "samples; REML removes the bias of estimating the mean)");
  cmd->add_option("--coords", args->coords,
                  "ml/reml (and --lmc on samples): coordinate columns of --input, e.g. x,y,z (any unit)");
  cmd->add_option("--value", args->value,
                  "ml/reml: the value column, e.g. z, or several (ex,ey,ez): one model shared by the components, "
                  "the sum of their log-likelihoods; --lmc: the components (>= 2), whose gamma_<A> and gamma_<A>_<B> "
                  "columns --input holds");
}

// Each records that it was given (*_given): it applies to some methods only, and the others refuse it.
void add_likelihood_model_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_option("--anisotropy", args->anisotropy,
                  "ml/reml: none (default, one range), ard (one range per --coords column; the model gets @ard(...)) "
                  "or rotated (alias anis; 2 or 3 --coords: gstat's anis, angle(s) and ratio(s) fitted too; the model "
                  "gets @anis(...))")
      ->each([args](const std::string&) { args->anisotropy_given = true; });
  cmd->add_option("--kind", args->kind,
                  "ml/reml: the kriging whose mean the likelihood profiles out: ordinary (default), universal1, "
                  "universal2, or simple0 (known mean 0, as scikit-learn's GaussianProcessRegressor)")
      ->each([args](const std::string&) { args->kind_given = true; });
  cmd->add_option("--covariates", args->covariates,
                  "ml/reml: columns COL[,COL...] of --input (or NAME=FILE.tif|.asc: the raster's pixel at each "
                  "point, 2-D --coords) added to the drift F (with --kind ordinary: the likelihood of kriging with "
                  "external drift, interpolate --method kriging --covariates)");
}

void add_model_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_option("--model", args->model,
                  "sph, exp, gau, mat (needs --nu), wen, pow or lin; or a nested template with starting values in "
                  "the model text interpolate reads, e.g. 'nug(sill=2e4)+sph(sill=3e4,range=25)+sph(sill=4e4,range=80)' "
                  "(gstat's vgm(..., add.to=...); its nug term is the nugget's start, or leave it out for no nugget); "
                  "with --lmc a template of bounded structures, e.g. nug(0)+sph(1,400) or nug+sph")
      ->required();
  cmd->add_option("--fix", args->fix,
                  "with a --model template: parameters held at the template's values instead of fitted (gstat's "
                  "fit.sills/fit.ranges = FALSE): sill, range (every structure), sillK, rangeK (the K-th structure, "
                  "1-based, nugget not counted) or nugget (wls); a list, e.g. --fix range or --fix range1,sill2");
  cmd->add_option("--nu", args->nu_text,
                  "Matérn smoothness nu (gstat's kappa), fixed during the fit; ml/reml: 'auto' = the most likely of "
                  "0.5, 1.5, 2.5")
      ->each([args](const std::string&) { args->nu_given = true; });
  cmd->add_option("--nugget", args->nugget,
                  "free (default), fixed=V (value unit^2) or none; with a --model template the default follows the "
                  "template: free from its nug term's value, none without one")
      ->each([args](const std::string&) { args->nugget_given = true; });
  cmd->add_option("--weights", args->weights,
                  "wls: nj (N_j, gstat fit.method 1), nj_h2 (N_j/h_j^2, method 7, default), cressie "
                  "(N_j/model(h_j)^2, method 2); --lmc: nj, nj_h2 or unweighted (method 6)")
      ->each([args](const std::string&) { args->weights_given = true; });
  cmd->add_option("--range-max", args->range_max,
                  "wls: upper bound of the range (lag unit); default 100 x the largest lag")
      ->each([args](const std::string&) { args->range_max_given = true; });
}

void add_likelihood_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_option("--likelihood", args->likelihood,
                  "ml/reml: auto (default: exact up to 3000 samples, vecchia above), exact (O(N^3) per evaluation, "
                  "up to 3000 samples) or vecchia (each sample conditioned on its --vecchia-neighbours nearest "
                  "predecessors; docs/kriging.md)")
      ->each([args](const std::string&) { args->likelihood_given = true; });
  cmd->add_option("--vecchia-neighbours", args->neighbours,
                  "ml/reml with the Vecchia likelihood: neighbours per sample, m (default 30)")
      ->each([args](const std::string& v) {
        args->likelihood_given = true;
        args->vecchia_given.push_back("--vecchia-neighbours " + v);
      });
  cmd->add_option("--vecchia-ordering", args->ordering,
                  "ml/reml with the Vecchia likelihood: maxmin (default), random or coordinate")
      ->each([args](const std::string& v) {
        args->likelihood_given = true;
        args->vecchia_given.push_back("--vecchia-ordering " + v);
      });
}

void add_lmc_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_flag("--lmc", args->lmc,
                "fit a linear model of coregionalization to the direct and cross variograms of the --value columns "
                "(>= 2): --input is the CSV of 'errfield variogram --cross' (or the samples, with --coords); --model "
                "is the template, e.g. nug(0)+sph(1,400) (kinds and ranges kept, sills ignored) or nug+sph (ranges "
                "fitted first to the mean direct variogram); --weights nj, nj_h2 (default) or unweighted. Heterotopic "
                "data (empty --value cells; the variogram CSV's pairs_<A> columns): each variogram fitted over its own "
                "bins as gstat's fit.lmc (--lmc-method gstat), ranges from the template; --out "
                "writes the LMC JSON that interpolate and cv --method kriging --model lmc.json read (cokriging)");
  cmd->add_option("--lmc-method", args->lmc_method,
                  "--lmc: goulard-voltz (default: iterated WLS, each B_k projected onto the PSD matrices) or gstat "
                  "(gstat's fit.lmc: separate fits, then negative eigenvalues set to 0)")
      ->each([args](const std::string&) { args->lmc_method_given = true; });
}

void add_output_options(CLI::App* cmd, const std::shared_ptr<FitVariogramArgs>& args) {
  cmd->add_option("--duplicates", args->duplicates,
                  "ml/reml: rows at exactly the same coordinates: keep (default: repeated measurements, which the nugget "
                  "describes) | average (one sample per location, the mean value) | first (the first row's) | refuse");
  cmd->add_option("--plot", args->plot,
                  "--method wls: also write an SVG picture (FILE.svg, for a browser) of the empirical variogram, one "
                  "point per non-empty bin sized by and labelled with its pair count, and the fitted model's curve; "
                  "written atomically, together with --out");
  cmd->add_option("--out", args->out, "output JSON (written atomically)");
}

void add_fit_variogram_command(CLI::App& app) {
  auto args = std::make_shared<FitVariogramArgs>();
  auto* cmd = app.add_subcommand(
      "fit-variogram",
      "Fit a variogram model to an empirical variogram by weighted least squares (as gstat's\n"
      "fit.variogram): minimizes sum_j w_j (gamma_j - model(h_j))^2 over the non-empty bins.\n"
      "Input: the CSV of 'errfield variogram' (lag_mean,gamma,pairs; gstat's dist,gamma,np also\n"
      "work). Prints the fitted model, e.g. sph(sill=0.3,range=400)+nug(sill=0.002), its\n"
      "parameters and the weighted SSE; --out writes it as JSON (readable as a model).\n"
      "--method ml|reml instead maximizes the (restricted) Gaussian likelihood of the samples\n"
      "themselves (--input with --coords and --value; no binning): the model ordinary kriging with\n"
      "that data finds most probable. Exact (O(N^3) per evaluation) up to 3,000 samples, then the\n"
      "Vecchia nearest-neighbour approximation (O(N m^3); --likelihood, --vecchia-neighbours).");
  add_input_options(cmd, args);
  add_likelihood_model_options(cmd, args);
  add_model_options(cmd, args);
  add_likelihood_options(cmd, args);
  add_lmc_options(cmd, args);
  add_output_options(cmd, args);
  cmd->footer(
      "Example:\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dL --bins 0:2200:200 --out vario.csv\n"
      "  errfield fit-variogram --input vario.csv --model sph --nugget free --weights nj_h2 --out model.json\n"
      "  errfield fit-variogram --input vario.csv --model 'nug(sill=0.1)+sph(sill=1,range=300)+sph(sill=1,range=1500)' \\\n"
      "      --fix range1 --out nested.json   # nested structures; the first range held at 300\n"
      "  errfield fit-variogram --method reml --input errors.csv --coords x,y,z --value dL --model exp --out model.json\n"
      "  errfield variogram --input errors.csv --coords x,y,z --value dx,dy,dz --cross --out cross.csv\n"
      "  errfield fit-variogram --lmc --input cross.csv --value dx,dy,dz --model 'nug(0)+sph(1,400)' --out lmc.json\n"
      "  errfield fit-variogram --method reml --anisotropy ard --input residuals.csv --coords q1,q2,q3,q4,q5,q6 \\\n"
      "      --value ex,ey,ez --model mat --nu 2.5 --out model.json   # then fit/interpolate --model model.json\n"
      "(errors.csv, residuals.csv: SIMULATED examples from scripts/make_example_error_field.py, see README.md)");
  cmd->callback([args] { run_fit_variogram(*args); });
}

Registration register_fit_variogram{"fit-variogram", 11, &add_fit_variogram_command};

}  // namespace
}  // namespace errfield::cli
