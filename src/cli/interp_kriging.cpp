// `errfield interpolate --method kriging` and `errfield cv --method kriging`: simple, ordinary and
// universal kriging (errfield/kriging.hpp) with the dense, local or sparse back end, and a model
// given as text or fitted automatically (--model auto).

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>
#include <iostream>
#include <limits>
#include <memory>

#include "cli/cli_support.hpp"
#include "cli/covariate_sources.hpp"
#include "cli/interp_cokriging.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/raster_file.hpp"
#include "errfield/conditional_simulation.hpp"
#include "errfield/cross_validation.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/error.hpp"
#include "errfield/indicator_kriging.hpp"
#include "errfield/value_rows.hpp"
#include "errfield/interpolation_options.hpp"
#include "errfield/kriging.hpp"
#include "errfield/kriging_likelihood.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield::cli {
namespace {

struct KrigingCliOptions {
  std::string model;
  std::string kind = "ordinary";
  double mean = std::numeric_limits<double>::quiet_NaN();  // NaN = not given
  std::string backend;
  std::string neighbour_metric;  // "" = not given
  std::size_t min_neighbours = 0;  // 0 = none
  std::size_t octant_max = 0;      // 0 = no limit
  std::string nugget_as = "micro";
  std::string duplicates = "refuse";  // --duplicates refuse|average
  std::string measurement_variance;
  std::vector<std::string> covariates;  // --covariates: external-drift columns
  // interpolate only: conditional simulation
  std::size_t simulations = 0;  // 0 = none
  std::uint64_t seed = 1;
  std::string simulation_method = "auto";
  std::size_t simulation_neighbours = 60;
  std::size_t simulation_draws_per_path = SimulationOptions{}.draws_per_path;
  // interpolate only: block kriging
  std::vector<double> block;  // empty = point kriging
  int block_points = 4;
  std::string block_rule = "gauss";
  // interpolate only: indicator kriging
  std::string indicator;                    // --indicator T1,T2,...
  std::string order_correction = "gslib";   // --order-correction gslib|none
  std::string auto_search = "fast";         // --auto-search fast|thorough (--model auto)
};
KrigingCliOptions cli_options;
// interpolate's --seed, --simulation-method, --simulation-neighbours, --simulation-draws-per-path: refused
// without --simulations.
// Kept apart from cli_options, which cv's registration resets after interpolate's.
std::vector<CLI::Option*> simulation_only_options;
std::vector<CLI::Option*> block_only_options;  // --block-points: refused without --block
std::vector<CLI::Option*> indicator_only_options;  // --order-correction: refused without --indicator
// --indicator itself: given (even as '') means indicator kriging, whose empty thresholds are then
// refused; its value alone cannot tell `--indicator ''` from no --indicator.
CLI::Option* indicator_option = nullptr;

// The model and the kriging system: what interpolate and cv share.
void add_kriging_model_options(CLI::App& cmd, KrigingCliOptions& o, const char* group) {
  cmd.add_option("--model", o.model,
                 "Variogram model in gstat's vgm terms, e.g. \"sph(sill=0.3,range=400)+nug(0.002)\" (models: nug, sph, "
                 "exp, gau, mat, wen; 'sill' is the partial sill of that component). NOTE: 'range' of exp and gau is "
                 "the scale parameter a, not the practical range (practical range ~3a for exp, ~1.73a for gau), as in "
                 "gstat. A model JSON file (fit-variogram --out) is read. 'auto': REML fits of sph/exp/gau/mat(1.5,2.5) "
                 "with a nugget, isotropic and ARD, compared on up to 250 samples (--auto-search), and the one with the "
                 "smallest AIC whose kriging system is well conditioned and whose ranges are plausible, refitted on all "
                 "samples (printed with the reason); with --backend sparse, the best weighted fit of sph to the "
                 "empirical variogram. A linear model of coregionalization (an LMC JSON, \"type\": \"lmc\", as "
                 "fit-variogram --lmc writes) with one component per --value column, in --value order: cokriging, "
                 "which writes var_<col> per component and the prediction error covariances cov_<A>_<B> "
                 "(docs/kriging.md, Cokriging); not with --covariates, --measurement-variance, --block, --simulations, "
                 "--backend sparse")
      ->group(group);
  cmd.add_option("--auto-search", o.auto_search,
                 "--model auto: fast (default: the 10 candidates ranked on a random subset of up to 250 samples, the "
                 "best 2 plausible ones polished on all samples from their ranking estimate by the exact likelihood up to 500 "
                 "samples and Vecchia's beyond; ~0.7 s at 1,000 samples in 2-D) | thorough (ranked on up to 700, the best 3 "
                 "refitted on all from fit-variogram's starts as well, exact up to 3,000: never less likely than a "
                 "plain fit-variogram --method reml of their family; ~10x slower). docs/kriging.md compares them on "
                 "gstat's data sets")
      ->check(CLI::IsMember({"fast", "thorough"}))
      ->group(group);
  cmd.add_option("--kind", o.kind, "simple | ordinary (default) | universal1 | universal2 (linear / quadratic drift in the coordinates)")
      ->group(group);
  cmd.add_option("--mean", o.mean, "Known mean for --kind simple")->group(group);
  cmd.add_option("--backend", o.backend,
                 "dense (one Cholesky of all samples; default unless --neighbors/--radius) | local (the --neighbors K "
                 "nearest and/or those within --radius per target; large N) | sparse (CHOLMOD; compact models sph/wen only)")
      ->group(group);
  cmd.add_option("--neighbour-metric", o.neighbour_metric,
                 "local back end: model (default: the K nearest by the model's lag, anisotropy applied) | euclidean "
                 "(by the plain distance of the coordinates, as R gstat's nmax/maxdist; --radius then in that "
                 "distance). They differ only with an anisotropic model")
      ->group(group);
  cmd.add_option("--min-neighbours", o.min_neighbours,
                 "local back end: a target with fewer than N neighbours (the --neighbors nearest within --radius) "
                 "gets empty cells and the run says how many (gstat's nmin; default 0 = no minimum)")
      ->group(group);
  cmd.add_option("--octant-max", o.octant_max,
                 "local back end: keep at most K of the neighbours, nearest first, per quadrant (2-D) or octant "
                 "(3-D) around the target (gstat's omax, after --neighbors/--radius; default 0 = no limit)")
      ->group(group);
  cmd.add_option("--nugget-as", o.nugget_as,
                 "micro (default, gstat's krige: exact at the samples) | error (the nugget is measurement error, like "
                 "gstat's Err: predictions of the error-free signal, smoothing)")
      ->group(group);
  cmd.add_option("--duplicates", o.duplicates,
                 "samples at exactly the same location (a singular kriging system): refuse (default; the error names "
                 "both lines) | average (one sample there with the mean value and the variance of the mean, as gstat "
                 "users average duplicates before krige)")
      ->group(group);
  cmd.add_option("--measurement-variance", o.measurement_variance,
                 "Column of the samples file with each sample's measurement variance (value unit^2)")
      ->group(group);
  cmd.add_option("--covariates", o.covariates,
                 "External drift: columns COL[,COL...] present in the samples and the targets files, each one more "
                 "drift term. With --kind ordinary this is kriging with external drift (gstat's krige(z ~ COL)); with "
                 "universal1/2 the polynomial drift plus the covariates. Not with --kind simple. NAME=FILE.tif (or "
                 ".asc, any raster GDAL reads) reads covariate NAME from the first band of that raster at each "
                 "sample and target (2-D --coords; the value of the pixel containing the point; a point outside the "
                 "raster or on a nodata pixel is refused)")
      ->delimiter(',')
      ->group(group);
}

void add_block_options(CLI::App& cmd, KrigingCliOptions& o, const char* group) {
  cmd.add_option("--block", o.block,
                 "Block kriging: predict the average over a block of size DX,DY[,DZ] (one size per --coords column, in "
                 "their unit) centred on each target, and that average's error variance (gstat's krige(..., block = "
                 "c(DX, DY))); dense and local back ends")
      ->delimiter(',')
      ->group(group);
  auto* block_points = cmd.add_option("--block-points", o.block_points,
                                      "--block: discretization points per axis (default 4, as gstat: 16 points in 2-D)")
                           ->check(CLI::Range(1, 64))
                           ->group(group);
  auto* block_rule = cmd.add_option("--block-rule", o.block_rule,
                                    "--block: how the block average is integrated: gauss (default, Gauss-Legendre "
                                    "points and weights, gstat's default) | regular (an even grid of equal weights, "
                                    "gstat's set = list(nblockdiscr = N))")
                         ->check(CLI::IsMember({"gauss", "regular"}))
                         ->group(group);
  block_only_options = {block_points, block_rule};
}

void add_simulation_options(CLI::App& cmd, KrigingCliOptions& o, const char* group) {
  cmd.add_option("--simulations", o.simulations,
                 "Conditional Gaussian simulation: also write N realisations of the field that honour the samples "
                 "and the model (nugget and drift included), columns sim1..simN (sim<k>_<col> for vectors); their "
                 "mean over draws is pred and their variance var. Conditioning by kriging: every back end")
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000}))
      ->group(group);
  auto* seed = cmd.add_option("--seed", o.seed, "--simulations: random seed (default 1); the same seed gives the same "
                                                   "draws, byte for byte, for any thread count")
                      ->group(group);
  auto* method = cmd.add_option("--simulation-method", o.simulation_method,
                 "--simulations: how the unconditional field is drawn: auto (default: cholesky up to 2,000 distinct "
                 "locations, samples + targets; sequential beyond) | cholesky (exact) | sequential (along a random "
                 "path, each location from its --simulation-neighbours nearest earlier ones; large target sets)")
      ->group(group);
  auto* neighbours = cmd.add_option("--simulation-neighbours", o.simulation_neighbours,
                 "--simulations with the sequential method: earlier-simulated locations each one is conditioned on "
                 "(default 60: with 30 the draws of a gau model were 8 % too variable, docs/kriging.md)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000}))
      ->group(group);
  auto* per_path = cmd.add_option("--simulation-draws-per-path", o.simulation_draws_per_path,
                 "--simulations with the sequential method: draws that share one random path and its neighbour "
                 "weights (default 100, as gstat, whose draws all share one path: 100 draws cost one path; 1 = a "
                 "path per draw, each draw's own approximation error, 100 times the cost)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000}))
      ->group(group);
  simulation_only_options = {seed, method, neighbours, per_path};
}

void add_indicator_options(CLI::App& cmd, KrigingCliOptions& o, const char* group) {
  indicator_option = cmd.add_option("--indicator", o.indicator,
                 "Indicator kriging: thresholds T1,T2,... (increasing) of the one --value column. For each, the samples "
                 "become I(z < T) (1 below, 0 at or above: gstat's krige(I(z < T) ~ 1)), kriged with that threshold's "
                 "--model: one model for all, one per threshold separated by ';' (\"sph(sill=0.12,range=700)+nug(0.03);"
                 "exp(sill=0.2,range=300)\"), or auto (fitted to each threshold's indicators). Writes p_lt_<T>, the "
                 "probability P(z < T) (1 - it: of reaching T), and var_lt_<T>, the indicator kriging variance, instead "
                 "of pred and var")
      ->group(group);
  auto* order = cmd.add_option("--order-correction", o.order_correction,
                               "--indicator: gslib (default: clip to [0,1], then the average of an upward and a downward "
                               "pass makes the probabilities non-decreasing in T, GSLIB's correction) | none (each "
                               "threshold as kriged, as gstat's krige of one indicator)")
                    ->check(CLI::IsMember({"gslib", "none"}))
                    ->group(group);
  indicator_only_options = {order};
}

void add_kriging_options(CLI::App& cmd) {
  auto& o = cli_options;
  // run_cli() may run more than once in a process (the CLI fuzzer): start from the defaults, not
  // from the previous run's values.
  o = KrigingCliOptions{};
  const char* group = "kriging (--method kriging)";
  add_kriging_model_options(cmd, o, group);
  if (cmd.get_name() != "interpolate") return;  // cv has its own --seed (the folds')
  add_block_options(cmd, o, group);
  add_simulation_options(cmd, o, group);
  add_indicator_options(cmd, o, group);
}

// gstat's defaults for variogram(): cutoff one third of the bounding-box diagonal, 15 bins.
VariogramModel auto_model(const Eigen::MatrixXd& coords, const Eigen::MatrixXd& values, bool compact_only,
                          std::vector<std::string>& notes) {
  const double diagonal = (coords.colwise().maxCoeff() - coords.colwise().minCoeff()).norm();
  if (!(diagonal > 0.0)) throw InputError("--model auto: all samples are at one location; cannot estimate a variogram");
  const double cutoff = diagonal / 3.0;
  EmpiricalVariogramOptions vo;
  vo.convention = BinConvention::Gstat;
  const EmpiricalVariogram ev = empirical_variogram(coords, values, LagBins::uniform(0.0, cutoff, cutoff / 15.0), vo);
  // One model for every component (intrinsic coregionalization): fit the mean per-component gamma.
  std::vector<double> lag, gamma;
  std::vector<std::uint64_t> pairs;
  for (const auto& b : ev.bins) {
    if (b.pairs == 0) continue;
    lag.push_back(b.lag_mean);
    gamma.push_back(b.gamma / static_cast<double>(values.cols()));
    pairs.push_back(b.pairs);
  }
  // gau is left out: fitted without a nugget it makes the kriging system numerically singular
  // (condition numbers ~1e18 are common); give it explicitly with a nugget if it is wanted.
  std::vector<ModelKind> kinds{ModelKind::Spherical};
  if (!compact_only) kinds.push_back(ModelKind::Exponential);
  VariogramFitOptions fo;
  bool have = false;
  VariogramFitResult best;
  for (ModelKind k : kinds) {
    ModelComponent c;
    c.kind = k;
    const VariogramFitResult r = fit_variogram(lag, gamma, pairs, {c}, fo);
    if (r.status == FitStatus::Failed || !r.model.bounded()) continue;
    if (!have || r.weighted_sse < best.weighted_sse) {
      best = r;
      have = true;
    }
  }
  if (!have) throw InputError("--model auto: no variogram model could be fitted to the samples' empirical variogram");
  notes.push_back("--model auto: empirical variogram (" + std::to_string(lag.size()) + " non-empty bins up to lag " +
                  format_number(cutoff) + ", gstat's default cutoff), best fit of " +
                  (compact_only ? std::string("sph") : std::string("sph and exp")) + " with free nugget (weights nj_h2): " +
                  best.model.to_string() + " (weighted SSE " + format_number(best.weighted_sse) + ")");
  return best.model;
}

// --model auto: REML fits of sph/exp/gau/mat(1.5, 2.5) with a nugget, isotropic and ARD, for the
// kriging kind asked; the smallest AIC on all samples among the well-conditioned, plausible ones
// (ranked on a subset, the best two or three refitted on all; the Vecchia likelihood beyond a size, so
// more samples never change the family to one without a nugget or ARD).
VariogramModel likelihood_auto_model(const Eigen::MatrixXd& coords, const Eigen::MatrixXd& values,
                                     const KrigingOptions& kriging, std::vector<std::string>& notes) {
  // fast: ModelChoiceOptions::fast() (~0.7 s at 1,000 samples; docs/kriging.md compares it with
  // thorough on gstat's data sets). thorough: ten candidates ranked by one polished run each from
  // the best of four screened starts on up to 700 samples; the best three fitted again with
  // fit-variogram's starts (8 screened, 2 runs) plus their ranking estimate, so that a plain
  // `fit-variogram --method reml` of their family never beats the choice.
  ModelChoiceOptions mo = cli_options.auto_search == "fast" ? ModelChoiceOptions::fast() : ModelChoiceOptions{};
  if (cli_options.auto_search != "fast") {
    mo.ranking_starts = 4;
    mo.ranking_local_runs = 1;
  }
  mo.fit.kind = kriging.kind;
  mo.fit.drift_order = kriging.drift_order;
  if (kriging.kind == KrigingKind::Simple) mo.fit.simple_mean = kriging.simple_mean.empty() ? 0.0 : kriging.simple_mean[0];
  mo.max_condition_number = kriging.max_condition_number;
  mo.fit.standard_errors = false;
  const ModelChoice choice = choose_likelihood_model(coords, values, mo);
  for (const auto& w : choice.warnings) notes.push_back("--model auto: warning: " + w);
  notes.push_back("--model auto: " + choice.model.to_string() + ", chosen by " + choice.reason);
  return choice.model;
}

// The kriging option words as given on the command line (--kind, --mean, --backend, --neighbors,
// --radius, --neighbour-metric, --nugget-as), for kriging and cokriging alike.
KrigingOptions kriging_options_from_cli(const SharedInterpolationOptions& shared) {
  const auto& o = cli_options;
  KrigingOptionText text;
  text.kind = o.kind;
  if (!std::isnan(o.mean)) text.mean = std::vector<double>{o.mean};
  if (!o.backend.empty()) text.backend = o.backend;
  text.neighbors = shared.neighbors;
  text.radius = shared.radius;
  if (!o.neighbour_metric.empty()) text.neighbour_metric = o.neighbour_metric;
  text.min_neighbours = o.min_neighbours;
  text.octant_max = o.octant_max;
  text.nugget = o.nugget_as;
  text.duplicates = o.duplicates;
  return kriging_options_from_text(text, cli_option_names());
}

struct Setup {
  VariogramModel model;
  KrigingOptions options;
  Eigen::VectorXd measurement_variance;
  Eigen::MatrixXd sample_covariates;  // N x k (k = options.covariates.size())
  CovariateSources covariate_sources;

  Eigen::MatrixXd target_covariates(const InterpolationRequest& r) const {
    return options.covariates.empty() ? Eigen::MatrixXd()
                                      : covariate_values(covariate_sources, *r.targets, r.target_coords, r.target_labels);
  }
};

Setup make_setup(const CsvTable& samples, const Eigen::MatrixXd& coords, const Eigen::MatrixXd& values,
                 const RowLabels& sample_labels, CoordinateSystem* coordinate_system,
                 const SharedInterpolationOptions& shared, std::vector<std::string>& notes) {
  const auto& o = cli_options;
  Setup s;
  s.options = kriging_options_from_cli(shared);
  auto& opt = s.options;
  opt.sample_labels = sample_labels;
  if (!o.covariates.empty()) {
    opt.covariates = o.covariates;
    opt.validate();  // names the kind when it is simple, before any file is read for them
    s.covariate_sources = covariate_sources(o.covariates, coordinate_system);
    opt.covariates = s.covariate_sources.names;
    s.sample_covariates = covariate_values(s.covariate_sources, samples, coords, opt.sample_labels);
  }

  if (o.model.empty()) throw ArgumentError("--method kriging needs --model, e.g. --model \"sph(sill=0.3,range=400)+nug(0.002)\" or --model auto");
  if (o.model == "auto" && !((coords.colwise().maxCoeff() - coords.colwise().minCoeff()).norm() > 0.0))
    throw InputError("--model auto: all samples are at one location; cannot estimate a variogram");
  if (o.model == "auto" && !opt.covariates.empty())
    throw ArgumentError("--model auto does not take --covariates yet; fit the residual variogram (errfield variogram "
                        "--covariates, or fit-variogram --method reml --covariates) and pass it as --model");
  if (o.model == "auto" && opt.backend != KrigingBackend::Sparse) {
    s.model = with_source(samples.source(), [&] { return likelihood_auto_model(coords, values, opt, notes); });
  } else {
    s.model = o.model == "auto" ? auto_model(coords, values, opt.backend == KrigingBackend::Sparse, notes)
                                : load_variogram_model(o.model);
  }
  if (!o.measurement_variance.empty()) s.measurement_variance = samples.numeric_columns({o.measurement_variance}).col(0);
  return s;
}

const char* status_word(KrigingStatus s) { return kriging_status_name(s).data(); }

// k-fold kriges each fold from the other folds' samples alone, where a duplicate pair would be
// named by its index within that subset ("samples 3 and 7"); checked on the whole file first, so
// the message names both rows as file:line like every row error.
void refuse_duplicate_samples(const Eigen::MatrixXd& coords, const RowLabels& labels) {
  std::vector<Eigen::Index> order(static_cast<std::size_t>(coords.rows()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  auto less = [&](Eigen::Index a, Eigen::Index b) {
    for (Eigen::Index c = 0; c < coords.cols(); ++c)
      if (coords(a, c) != coords(b, c)) return coords(a, c) < coords(b, c);
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < order.size(); ++k) {
    const Eigen::Index a = order[k - 1], b = order[k];
    if (coords.row(a) != coords.row(b)) continue;
    const auto first = static_cast<std::size_t>(std::min(a, b)), later = static_cast<std::size_t>(std::max(a, b));
    throw InputError(labels(later) + ": kriging: this sample and " + labels(first) +
                         " are duplicates (same location); remove one, or give --duplicates average (one sample, their mean)",
                     labels.source, labels.line(later));
  }
}

// --model names a linear model of coregionalization (an LMC JSON): cokriging. The kriging options
// cokriging does not have are refused by name, never ignored.
KrigingOptions cokriging_options(const CsvTable& samples, const SharedInterpolationOptions& shared, bool interpolate) {
  const auto& o = cli_options;
  const auto refuse = [&](const std::string& option, const std::string& why) {
    throw ArgumentError(option + " is not available with cokriging (--model " + o.model +
                        " is a linear model of coregionalization): " + why);
  };
  if (!o.covariates.empty()) refuse("--covariates", "external drift is not supported; use --kind ordinary, universal1 or universal2");
  if (!o.measurement_variance.empty())
    refuse("--measurement-variance", "per-sample measurement variances are not supported; the model's nugget with --nugget-as error is the observation noise");
  if (interpolate) {
    if (!o.block.empty()) refuse("--block", "block cokriging is not implemented; predict at points");
    if (o.simulations > 0) refuse("--simulations", "conditional co-simulation is not implemented");
    for (const CLI::Option* opt : simulation_only_options)
      if (opt->count()) refuse(opt->get_name(), "it belongs to --simulations, which cokriging does not have");
    for (const CLI::Option* opt : block_only_options)
      if (opt->count()) refuse(opt->get_name(), "it belongs to --block, which cokriging does not have");
  }
  if (o.backend == "sparse") refuse("--backend sparse", "use --backend dense (default) or local (--neighbors K)");
  KrigingOptions options = kriging_options_from_cli(shared);
  options.sample_labels = row_labels_of(samples, "sample");
  return options;
}

// What indicator kriging does not combine with, refused by name, and --model and thresholds required.
void refuse_with_indicator(const InterpolationRequest& r) {
  const auto& o = cli_options;
  const auto refuse = [&](bool given, const std::string& option, const std::string& why) {
    if (given) throw ArgumentError(option + " does not combine with --indicator: " + why);
  };
  refuse(r.value_columns.size() != 1, "--value with " + std::to_string(r.value_columns.size()) + " columns",
         "indicator kriging takes one value column (its thresholds are of that column)");
  refuse(model_file_is_lmc(o.model), "an LMC --model", "give one variogram model per threshold, separated by ';'");
  refuse(!o.covariates.empty(), "--covariates", "indicator kriging with external drift is not implemented");
  refuse(!o.measurement_variance.empty(), "--measurement-variance", "the indicators are 0 or 1, without measurement error");
  refuse(!o.block.empty(), "--block", "block indicator kriging is not implemented; predict at points");
  refuse(o.simulations > 0, "--simulations", "indicator simulation is not implemented");
  for (const CLI::Option* opt : simulation_only_options) refuse(opt->count() > 0, opt->get_name(), "it belongs to --simulations");
  for (const CLI::Option* opt : block_only_options) refuse(opt->count() > 0, opt->get_name(), "it belongs to --block");
  if (o.model.empty())
    throw ArgumentError("--indicator needs --model: one variogram model for every threshold, one per threshold separated by "
                        "';', or auto");
  if (o.indicator.find_first_not_of(" \t") == std::string::npos)
    throw ArgumentError("--indicator is '" + o.indicator + "': no thresholds; expected increasing thresholds T1,T2,... in "
                        "the unit of --value, e.g. 200,400,800 (or drop --indicator for kriging of the values)");
}

// --indicator T1,T2,...: the thresholds as given (they name the columns) and as numbers.
struct Thresholds {
  std::vector<std::string> texts;
  std::vector<double> values;
};

Thresholds indicator_thresholds() {
  const auto& o = cli_options;
  Thresholds t;
  for (auto item : split_list(o.indicator, "--indicator")) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    double v = 0.0;
    const auto res = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || res.ec != std::errc() || res.ptr != item.data() + item.size() || !std::isfinite(v))
      throw ArgumentError("--indicator: '" + item + "' in '" + o.indicator + "' is not a finite number; expected "
                          "increasing thresholds T1,T2,... in the unit of --value, e.g. 200,400,800");
    t.texts.push_back(item);
    t.values.push_back(v);
  }
  naming_options([&] { check_indicator_thresholds(t.values); }, {{"indicator kriging: thresholds", "--indicator: thresholds"},
                                                                 {"indicator kriging: threshold", "--indicator: threshold"}});
  return t;
}

// --model: one model for all thresholds, or one per threshold separated by ';'.
std::vector<std::string> indicator_model_texts(std::size_t thresholds) {
  const auto& o = cli_options;
  std::vector<std::string> model_texts;
  for (std::size_t start = 0;;) {
    const auto end = o.model.find(';', start);
    model_texts.push_back(o.model.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  if (model_texts.size() != 1 && model_texts.size() != thresholds)
    throw ArgumentError("--model: " + std::to_string(model_texts.size()) + " models (';'-separated) for " +
                        std::to_string(thresholds) + " --indicator thresholds; give one model for all, or one per threshold");
  return model_texts;
}

// Each threshold's model: given, or (auto) fitted to that threshold's indicators.
std::vector<VariogramModel> indicator_models(const InterpolationRequest& r, const Thresholds& t,
                                             const std::vector<std::string>& model_texts, const KrigingOptions& options,
                                             const Eigen::VectorXd& z, std::vector<std::string>& notes) {
  std::vector<VariogramModel> models;
  for (std::size_t k = 0; k < t.values.size(); ++k) {
    const std::string& text = model_texts[model_texts.size() == 1 ? 0 : k];
    if (text == "auto") {
      const std::vector<double> ind = indicators_below(std::span<const double>(z.data(), static_cast<std::size_t>(z.size())), t.values[k]);
      const Eigen::MatrixXd indicator = Eigen::Map<const Eigen::VectorXd>(ind.data(), static_cast<Eigen::Index>(ind.size()));
      if (indicator.minCoeff() == indicator.maxCoeff())
        throw InputError(r.samples->source() + ": --indicator " + t.texts[k] + ": every sample is " +
                             (indicator(0, 0) == 1.0 ? "below" : "at or above") +
                             " it, so --model auto has no variogram to fit; drop the threshold or give its model",
                         r.samples->source());
      std::vector<std::string> fit_notes;
      models.push_back(with_source(r.samples->source(), [&] {
        return options.backend == KrigingBackend::Sparse ? auto_model(r.sample_coords, indicator, true, fit_notes)
                                                         : likelihood_auto_model(r.sample_coords, indicator, options, fit_notes);
      }));
      for (const auto& n : fit_notes) notes.push_back("threshold " + t.texts[k] + ": " + n);
    } else if (model_texts.size() == 1 && k > 0) {
      models.push_back(models.front());
    } else {
      models.push_back(load_variogram_model(text));
    }
  }
  return models;
}

// p_lt_<T> and var_lt_<T> per threshold, and the notes that say what was kriged and corrected.
void add_indicator_results(const InterpolationRequest& r, const Thresholds& t, const std::vector<VariogramModel>& models,
                           const Eigen::VectorXd& z, const IndicatorKrigingResult& ik, bool correct_order,
                           std::size_t targets, InterpolationResult& result) {
  if (!ik.message.empty()) result.notes.push_back(ik.message);
  result.pred = ik.probability;
  for (std::size_t k = 0; k < t.values.size(); ++k) {
    result.prediction_names.push_back("p_lt_" + t.texts[k]);
    const Eigen::VectorXd v = ik.variance.col(static_cast<Eigen::Index>(k));
    result.extra_columns.emplace_back("var_lt_" + t.texts[k], std::vector<double>(v.data(), v.data() + v.size()));
    const auto below = (z.array() < t.values[k]).count();
    result.notes.push_back("indicator kriging: I(" + r.value_columns[0] + " < " + t.texts[k] + ") with " +
                           models[k].to_string() + " (" + std::to_string(below) + " of " + std::to_string(z.size()) +
                           " samples below)");
  }
  if (ik.failed_targets)
    result.notes.push_back(std::to_string(ik.failed_targets) + " of " + std::to_string(targets) +
                           " targets could not be kriged for some threshold; their cells are empty");
  if (correct_order)
    result.notes.push_back("order relations: " + std::to_string(ik.correction.rows_changed) + " of " +
                           std::to_string(targets) + " targets corrected (clipped to [0,1] and made non-decreasing, "
                           "GSLIB's average of upward and downward passes), largest change " +
                           format_number(ik.correction.max_change) + (ik.correction.max_change > 0.1 ? " - large: check "
                           "that the models of neighbouring thresholds agree" : ""));
}

// --indicator T1,T2,...: indicator kriging (errfield/indicator_kriging.hpp), one model per threshold.
InterpolationResult interpolate_indicator(const InterpolationRequest& r) {
  const auto& o = cli_options;
  InterpolationResult result;
  refuse_with_indicator(r);
  const Thresholds t = indicator_thresholds();
  const std::vector<std::string> model_texts = indicator_model_texts(t.values.size());
  KrigingOptions options = kriging_options_from_cli(r.shared);
  options.sample_labels = row_labels_of(*r.samples, "sample");
  const Eigen::VectorXd z = r.sample_values.col(0);
  const std::vector<VariogramModel> models = indicator_models(r, t, model_texts, options, z, result.notes);
  const auto points = rows_as_points(r.sample_coords);
  const auto targets = rows_as_points(r.target_coords);
  IndicatorKrigingOptions io;
  io.correct_order = o.order_correction == "gslib";
  const IndicatorKrigingResult ik = indicator_kriging<Eigen::VectorXd>(
      std::span<const Eigen::VectorXd>(points), std::span<const double>(z.data(), static_cast<std::size_t>(z.size())),
      std::span<const Eigen::VectorXd>(targets), std::span<const double>(t.values),
      std::span<const VariogramModel>(models), options, io);
  if (!ik.usable())
    throw Error(r.samples->source() + ": indicator kriging failed: " + std::string(status_word(ik.status)) + ": " + ik.message);
  add_indicator_results(r, t, models, z, ik, io.correct_order, targets.size(), result);
  return result;
}

// The options of one output (--simulations, --block) refused without it or with the other; the
// columns they would add refused when the targets already have them.
UnconditionalMethod check_output_options(const InterpolationRequest& r) {
  const std::size_t c = r.value_columns.size();
  if (cli_options.simulations == 0)
    for (const CLI::Option* o : simulation_only_options)
      if (o->count()) throw ArgumentError(o->get_name() + " applies to --simulations N (conditional simulation); add it or drop " + o->get_name());
  if (cli_options.block.empty())
    for (const CLI::Option* o : block_only_options)
      if (o->count()) throw ArgumentError(o->get_name() + " applies to --block DX,DY[,DZ] (block kriging); add it or drop " + o->get_name());
  if (!cli_options.block.empty() && cli_options.simulations > 0)
    throw ArgumentError("--simulations draws at points; it does not combine with --block (block kriging)");
  if (!cli_options.block.empty() && cli_options.block.size() != r.coord_columns.size())
    throw ArgumentError("--block: " + std::to_string(cli_options.block.size()) + " sizes for " +
                        std::to_string(r.coord_columns.size()) + " --coords columns; expected one size per coordinate");
  UnconditionalMethod simulation_method = UnconditionalMethod::Auto;
  try {
    simulation_method = unconditional_method_from_name(cli_options.simulation_method);
  } catch (const ArgumentError& e) {
    throw ArgumentError(std::string("--simulation-method: ") + e.what());
  }
  for (std::size_t k = 1; k <= cli_options.simulations; ++k)
    for (std::size_t j = 0; j < c; ++j) {
      const std::string name = "sim" + std::to_string(k) + (c == 1 ? std::string() : "_" + r.value_columns[j]);
      if (r.targets->has_column(name))
        throw InputError(r.targets->source() + ": already has a column '" + name + "', which the output would repeat; rename it",
                         r.targets->source(), 1, name);
    }
  return simulation_method;
}

// --simulations N: the draws' mean and variance are the prediction; the draws become columns
// sim<k>[_<col>].
template <class V>
KrigingPrediction<V> simulated_prediction(const InterpolationRequest& r, const Setup& s, const auto& points,
                                          const auto& values, const auto& targets, std::span<const double> meas,
                                          UnconditionalMethod simulation_method, InterpolationResult& result) {
  const std::size_t c = r.value_columns.size();
  KrigingPrediction<V> pred;
  SimulationOptions so;
  so.draws = cli_options.simulations;
  so.seed = cli_options.seed;
  so.method = simulation_method;
  so.neighbours = cli_options.simulation_neighbours;
  so.draws_per_path = cli_options.simulation_draws_per_path;
  const Eigen::MatrixXd target_covariates = s.target_covariates(r);
  const auto sim = simulate_conditional<Eigen::VectorXd, V>(points, values, s.sample_covariates, targets,
                                                            target_covariates, s.model, s.options, so, {}, meas);
  pred.status = sim.status;
  pred.message = sim.message;
  pred.mean = sim.mean;
  pred.variance = sim.variance;
  pred.failed_targets = sim.failed_targets;
  for (std::size_t k = 0; k < sim.draws.size(); ++k) {
    const Eigen::MatrixXd draw = values_as_rows(sim.draws[k]);
    for (std::size_t j = 0; j < c; ++j) {
      const std::string name = "sim" + std::to_string(k + 1) + (c == 1 ? std::string() : "_" + r.value_columns[j]);
      const Eigen::VectorXd column = draw.col(static_cast<Eigen::Index>(j));
      result.extra_columns.emplace_back(name, std::vector<double>(column.data(), column.data() + column.size()));
    }
  }
  result.notes.push_back("simulation: " + std::to_string(sim.draws.size()) + " conditional draws (seed " +
                         std::to_string(cli_options.seed) + "), unconditional field by " + sim.method);
  return pred;
}

// --block DX,DY[,DZ]: the block averages centred on the targets.
template <class V>
KrigingPrediction<V> block_prediction(const InterpolationRequest& r, const Setup& s,
                                      const Kriging<Eigen::VectorXd, V>& kriging, const auto& targets,
                                      InterpolationResult& result) {
  BlockDiscretization block{cli_options.block, cli_options.block_points};
  block.rule = cli_options.block_rule == "regular" ? BlockDiscretization::Rule::Regular
                                                   : BlockDiscretization::Rule::GaussLegendre;
  const Eigen::MatrixXd target_covariates = s.target_covariates(r);
  KrigingPrediction<V> pred = kriging.predict_blocks(targets, block, target_covariates, r.target_labels);
  result.notes.push_back("block kriging: blocks of " + format_number(cli_options.block[0]) +
                         [&] {
                           std::string t;
                           for (std::size_t k = 1; k < cli_options.block.size(); ++k) t += " x " + format_number(cli_options.block[k]);
                           return t;
                         }() +
                         " centred on the targets, " + std::to_string(block.offsets(static_cast<int>(cli_options.block.size())).cols()) +
                         " " + cli_options.block_rule + " points each; pred and var are of the block averages");
  return pred;
}

// pred, var (before the draws' columns) and the notes that say what was kriged and where it failed.
template <class V>
void add_kriging_results(const InterpolationRequest& r, const Setup& s, const auto& rep, const KrigingPrediction<V>& pred,
                         const std::vector<std::string>& var_names, std::size_t targets, InterpolationResult& result) {
  result.pred = values_as_rows(pred.mean);
  if (pred.failed_targets) {
    Eigen::Index first = 0;
    while (first < result.pred.rows() && !std::isnan(result.pred(first, 0))) ++first;
    result.notes.push_back(std::to_string(pred.failed_targets) + " of " + std::to_string(targets) +
                           " targets could not be kriged (" + status_word(pred.status) + "; first: " +
                           r.target_labels(static_cast<std::size_t>(first)) + "); their cells are empty");
  }
  // var before the draws' columns
  for (auto it = var_names.rbegin(); it != var_names.rend(); ++it)
    result.extra_columns.emplace(result.extra_columns.begin(), *it, pred.variance);
  result.notes.push_back("kriging: " + std::string(kriging_kind_name(s.options.kind)) +
                         (s.options.kind == KrigingKind::Universal ? " (drift order " + std::to_string(s.options.drift_order) + ")" : std::string()) +
                         (s.options.covariates.empty() ? std::string() : " with external drift (" + std::to_string(s.options.covariates.size()) + " covariate(s))") +
                         ", model " + s.model.to_string() + ", " + std::string(kriging_backend_name(s.options.backend)) +
                         " back end" +
                         (std::isfinite(rep.condition_number) ? ", condition number ~" + format_number(rep.condition_number) : std::string()));
}

InterpolationResult interpolate_kriging(const InterpolationRequest& r) {
  if (!cli_options.indicator.empty() || (indicator_option != nullptr && indicator_option->count() > 0))
    return interpolate_indicator(r);
  for (const CLI::Option* o : indicator_only_options)
    if (o->count()) throw ArgumentError(o->get_name() + " applies to --indicator T1,T2,... (indicator kriging); add it or drop " + o->get_name());
  InterpolationResult result;
  if (model_file_is_lmc(cli_options.model)) {
    const KrigingOptions options = cokriging_options(*r.samples, r.shared, true);
    return interpolate_cokriging(r, load_lmc_for_values(cli_options.model, r.value_columns), options);
  }
  const Setup s = make_setup(*r.samples, r.sample_coords, r.sample_values, r.sample_labels, r.coordinate_system, r.shared, result.notes);
  const auto points = rows_as_points(r.sample_coords);
  const auto targets = rows_as_points(r.target_coords);
  const std::size_t c = r.value_columns.size();
  std::vector<std::string> var_names;
  for (const auto& v : r.value_columns) var_names.push_back(c == 1 ? "var" : "var_" + v);
  for (const auto& name : var_names)
    if (r.targets->has_column(name))
      throw InputError(r.targets->source() + ": already has a column '" + name + "', which the output would repeat; rename it",
                       r.targets->source(), 1, name);
  const UnconditionalMethod simulation_method = check_output_options(r);
  with_value_type(c, [&]<class V>() {
    const auto values = rows_as_values<V>(r.sample_values);
    std::span<const double> meas(s.measurement_variance.data(), static_cast<std::size_t>(s.measurement_variance.size()));
    const Kriging<Eigen::VectorXd, V> kriging(points, values, s.sample_covariates, s.model, s.options, {}, meas);
    const auto& rep = kriging.report();
    if (!rep.usable())
      throw Error(r.samples->source() + ": kriging failed: " + std::string(status_word(rep.status)) + ": " + rep.message);
    if (!rep.message.empty()) result.notes.push_back(std::string(status_word(rep.status)) + ": " + rep.message);
    if (rep.merged_duplicates) result.notes.push_back(std::to_string(rep.merged_duplicates) + " duplicate samples merged");
    KrigingPrediction<V> pred;
    if (cli_options.simulations > 0)
      pred = simulated_prediction<V>(r, s, points, values, targets, meas, simulation_method, result);
    else if (!cli_options.block.empty())
      pred = block_prediction<V>(r, s, kriging, targets, result);
    else
      pred = s.options.covariates.empty() ? kriging.predict(targets)
                                          : kriging.predict(targets, s.target_covariates(r), r.target_labels);
    add_kriging_results<V>(r, s, rep, pred, var_names, targets.size(), result);
  });
  return result;
}

CrossValidationOutput cross_validate_kriging(const CrossValidationRequest& r) {
  CrossValidationOutput out;
  if (model_file_is_lmc(cli_options.model)) {
    if (r.folds > 0)
      throw ArgumentError("--folds " + std::to_string(r.folds) + " is not available with cokriging (--model " + cli_options.model +
                          " is a linear model of coregionalization): its cross-validation is leave-one-out; drop --folds");
    const KrigingOptions options = cokriging_options(*r.samples, r.shared, false);
    return cross_validate_cokriging(r, load_lmc_for_values(cli_options.model, r.value_columns), options);
  }
  const Setup s = make_setup(*r.samples, r.sample_coords, r.sample_values, r.sample_labels, r.coordinate_system, r.shared, out.notes);
  if (s.measurement_variance.size() > 0 && r.folds > 0)
    out.notes.push_back("k-fold z-scores use the kriging variance without the held-out samples' measurement variance");
  const auto points = rows_as_points(r.sample_coords);
  with_value_type(r.value_columns.size(), [&]<class V>() {
    const auto values = rows_as_values<V>(r.sample_values);
    if (r.folds == 0 && s.options.backend != KrigingBackend::Sparse) {
      // Leave-one-out: closed form (dense) or one local solve per sample, from one set-up.
      std::span<const double> meas(s.measurement_variance.data(), static_cast<std::size_t>(s.measurement_variance.size()));
      auto options = s.options;
      const Kriging<Eigen::VectorXd, V> kriging(points, values, s.sample_covariates, s.model, options, {}, meas);
      if (kriging.report().merged_duplicates)
        throw InputError(r.samples->source() + ": cv --method kriging: duplicate samples; remove them first",
                         r.samples->source());
      const auto cv = kriging.leave_one_out();
      if (cv.prediction.size() != values.size())
        throw Error(r.samples->source() + ": kriging failed: " + std::string(status_word(cv.status)) + ": " + cv.message);
      if (!cv.message.empty()) out.notes.push_back(cv.message);
      out.fold.resize(values.size());
      for (std::size_t i = 0; i < values.size(); ++i) out.fold[i] = i;
      out.pred = values_as_rows(cv.prediction);
      out.variance = cv.variance;
      out.notes.push_back(s.options.backend == KrigingBackend::Dense
                              ? "leave-one-out in closed form (Dubrule 1983) from one factorization"
                              : "leave-one-out: each sample kriged from its neighbours without itself");
      return;
    }
    if (s.options.duplicates == DuplicatePolicy::Error) refuse_duplicate_samples(r.sample_coords, s.options.sample_labels);
    CrossValidationOptions cvo;
    cvo.folds = r.folds;
    cvo.seed = r.seed;
    CrossValidationResult<V> result;
    if (s.options.covariates.empty()) {
      KrigingEstimator<Eigen::VectorXd, V> estimator{s.model, s.options, {}};
      result = cross_validate(estimator, std::span<const Eigen::VectorXd>(points), std::span<const V>(values), cvo);
    } else {
      // The same folds as without covariates: each location carries its covariates after its
      // coordinates, and the estimator splits them again.
      Eigen::MatrixXd joined(r.sample_coords.rows(), r.sample_coords.cols() + s.sample_covariates.cols());
      joined << r.sample_coords, s.sample_covariates;
      const auto joined_points = rows_as_points(joined);
      const ExternalDriftKrigingEstimator<V> estimator{s.model, s.options, static_cast<Eigen::Index>(r.sample_coords.cols())};
      result = cross_validate(estimator, std::span<const Eigen::VectorXd>(joined_points), std::span<const V>(values), cvo);
    }
    out.fold = result.fold;
    out.pred = values_as_rows(result.predicted);
    out.variance = result.variance;
  });
  return out;
}

InterpolationMethodRegistration kriging_method{{
    "kriging",
    "simple / ordinary / universal kriging with a variogram --model (gstat vgm terms; 'range' of exp/gau is "
    "the scale a, not the practical range) or --model auto; writes pred and the kriging variance var "
    "(var_<col> for vectors); --backend dense|local|sparse, --neighbors K / --radius R for local; with an LMC "
    "JSON as --model, cokriging (var_<col> per component, cov_<A>_<B>)",
    {"--neighbors", "--radius"},
    &add_kriging_options,
    &interpolate_kriging,
    &cross_validate_kriging,
    // Heterotopic cokriging: a component with an empty cell is not measured at that sample.
    [] { return model_file_is_lmc(cli_options.model); },
}};

}  // namespace
}  // namespace errfield::cli
