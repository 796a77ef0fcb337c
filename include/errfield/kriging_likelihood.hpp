#pragma once
/// Estimating the kriging model's parameters by maximum likelihood (ML) or restricted maximum
/// likelihood (REML) of a Gaussian field, instead of fitting an empirical variogram. Use it when
/// the samples are few or irregular (a binned variogram is then noisy); REML corrects the bias of
/// ML in the sill when a mean or drift is estimated.
///
/// With K(theta) the covariance of the observations (the model's C(h), total sill on the
/// diagonal), F the drift (ordinary: a column of ones; universal: the polynomial drift; plus
/// one column per covariate, LikelihoodFitOptions::covariates) and
/// beta_hat = (F'K^-1F)^-1 F'K^-1 z, the negative log-likelihoods are
///   ML:   0.5 [ log det K + (z - F beta)'K^-1(z - F beta) + N log 2 pi ]
///   REML: 0.5 [ log det K + log det F'K^-1F + (z - F beta)'K^-1(z - F beta) + (N - p) log 2 pi ]
/// (simple kriging: F empty, z minus the known mean). Vector values (N x C) share one model, as
/// kriging does (intrinsic coregionalization): the negative log-likelihood is the sum over the C
/// columns. Dense: O(N^3) per evaluation, so meant for N up to a few thousand. Coordinates are
/// Euclidean (scale them first for a weighted metric); a model's anisotropy (anisotropy.hpp) maps
/// them before the lags are taken.
///
/// The fit of one structure (sph, exp, gau, wen, or mat with nu 0.5, 1.5 or 2.5) plus a nugget,
/// isotropic or with one range per coordinate (ARD), profiles the sill out in closed form and
/// minimizes over log ranges and log(nugget/sill) with analytic gradients (NLopt's L-BFGS) from the
/// best of several screened starts; other structures (nested models, mat with another nu) are
/// fitted isotropically by BOBYQA without gradients. The mathematics: docs/kriging.md.

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/kriging.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

/// Fewest samples fit_likelihood (and `errfield fit-variogram --method ml|reml`) accepts: a sill, a
/// range, a nugget and a mean need more data than parameters.
inline constexpr long kMinLikelihoodSamples = 4;
/// Most samples the exact likelihood accepts (LikelihoodMethod::Exact; ResourceError beyond; the
/// CLI and Python share it): every evaluation factorizes an N x N matrix, O(N^3), and a fit needs
/// hundreds. Beyond it the Vecchia approximation (below) takes over.
inline constexpr long kMaxLikelihoodSamples = 3000;
/// LikelihoodMethod::Auto: the exact likelihood up to this many samples (the exact path as it
/// was before the Vecchia approximation existed), Vecchia above (docs/kriging.md, "Vecchia
/// likelihood", for what it costs in accuracy).
inline constexpr long kExactLikelihoodMaxSamples = kMaxLikelihoodSamples;
/// Most samples the Vecchia likelihood accepts (cost O(N m^3) per evaluation, memory O(N m); the
/// memory is also checked against LikelihoodFitOptions::vecchia_memory_budget_bytes first).
inline constexpr long kMaxVecchiaLikelihoodSamples = 2000000;

/// Most neighbours a Vecchia conditioning set may have (each sample then factorizes an m x m block).
inline constexpr int kMaxVecchiaNeighbours = 400;

/// Rotated anisotropy (LikelihoodFitOptions::Anisotropy::Rotated) runs a profile search of ARD
/// fits over the angles: this many in 2-D (a grid of 6, golden sections, the standard error) and in
/// 3-D (a 6 x 4 x 4 grid, two sweeps of golden sections over three angles, the standard errors).
inline constexpr int kRotatedProfileFits2d = 26;
inline constexpr int kRotatedProfileFits3d = 204;
/// Work budget of a rotated fit, in units of fits x N^3 (exact likelihood) or fits x N m^3
/// (Vecchia, m neighbours): measured ~1e-8 s per unit on the 2-core CI machine (500 3-D samples,
/// exact: 241 s; Vecchia, 3,001 samples, m = 30: > 150 s), so the budget is about a minute.
/// Beyond it, fit_likelihood throws a ResourceError at once naming the samples (or neighbours) that
/// fit; before, a rotated fit of 1,000 samples ran past 10 minutes with no budget at all.
inline constexpr double kMaxRotatedLikelihoodWork = 6e9;

/// How the likelihood is evaluated.
///  Exact:   the dense formula below, O(N^3) per evaluation, N <= kMaxLikelihoodSamples.
///  Vecchia: the nearest-neighbour approximation of Vecchia (1988): the samples are ordered, and
///           each one's density is conditioned only on its m nearest predecessors (in the model's
///           metric), so the joint density is a product of N small Gaussian conditionals and
///           K^-1 ~ U U' with U sparse (m + 1 non-zeros per column). O(N m^3) per evaluation.
///           With m >= N - 1 it is the exact likelihood (any ordering).
///  Auto:    Exact up to kExactLikelihoodMaxSamples samples, Vecchia above.
enum class LikelihoodMethod { Auto, Exact, Vecchia };

/// The order in which the Vecchia approximation conditions the samples on each other.
///  MaxMin:     each next sample is the one farthest from those already ordered (the first: the
///              one nearest the centroid), so early samples spread over the domain and later ones
///              condition on near and far neighbours; the most accurate for a given m in the
///              literature (Guinness 2018) and here (docs/kriging.md). O(N log N) with a kd-tree.
///  Random:     a fixed pseudo-random permutation (seeded, reproducible).
///  Coordinate: sorted along the first coordinate (ties by sample index); the least accurate.
enum class VecchiaOrdering { MaxMin, Random, Coordinate };

/// The spread (max - min) of the values fit_likelihood accepts: outside it the likelihood's sums of
/// squares overflow or underflow a double, so the values must be rescaled first.
inline constexpr double kMinLikelihoodValueSpread = 1e-100;
inline constexpr double kMaxLikelihoodValueSpread = 1e100;

struct LikelihoodFitOptions {
  bool restricted = true;                   ///< REML (true) or ML (false)
  KrigingKind kind = KrigingKind::Ordinary; ///< which mean the likelihood profiles out
  int drift_order = 1;                      ///< Universal: 0, 1 or 2
  double simple_mean = 0.0;                 ///< Simple: the known mean
  /// External drift: N x k covariate values at the samples (row i = sample i), each column one
  /// more drift column of F after the polynomial terms (ordinary: F = [1, covariates], as kriging
  /// with KrigingOptions::covariates). Empty = none. Not with Simple; the rows must match the
  /// samples (choose_likelihood_model, which fits on a subset, does not take them).
  Eigen::MatrixXd covariates;
  /// Names of the covariates' columns, for messages (empty: "covariate 1", ...).
  std::vector<std::string> covariate_names;
  bool fit_nugget = true;                   ///< estimate a nugget (else none)
  /// fit_nugget: the nugget's starting value (value unit^2; > 0) for the derivative-free path
  /// (nested templates); <= 0: 5 % of the values' variance.
  double nugget_start = 0.0;
  /// Parameters held at the structure's given values (> 0) instead of fitted, per non-nugget
  /// component (empty = none held), as VariogramFitOptions::hold_sill / hold_range. A fit with a held
  /// parameter takes the derivative-free path; not with ARD or rotated anisotropy.
  std::vector<bool> hold_sill;
  std::vector<bool> hold_range;
  /// Ard: one range per coordinate (the model gets an Anisotropy::ard); needs the gradient path.
  /// Rotated (2-D/3-D): gstat's anis, angle(s) and ratio(s) fitted too (the model gets an
  /// Anisotropy::rotated): the ARD fit of rotated coordinates, the angles found around it by a
  /// derivative-free profile search (a grid, then golden sections; ~20 ARD fits in 2-D, ~150 in 3-D).
  enum class Anisotropy { None, Ard, Rotated } anisotropy = Anisotropy::None;
  /// mat: try each of these nu and keep the most likely (empty = the structure's nu, fixed).
  std::vector<double> matern_nu_choices;
  /// Gradient path: starting points screened by their likelihood before the local runs.
  int starts = 8;
  /// Gradient path: local L-BFGS runs from the best screened starts.
  int local_runs = 2;
  /// Gradient path: a model to start from as well (e.g. the fit of a subset): its ranges (along
  /// each coordinate with ARD) and nugget / partial sill are screened with the other starts, and
  /// the Vecchia neighbour sets are first found at its ranges. Ignored by rotated fits.
  std::optional<VariogramModel> initial_model;
  /// Lower bound of nugget / total sill when the nugget is fitted: a floor keeps the kriging system
  /// well conditioned (its condition number is then below ~ N / min_nugget_ratio).
  double min_nugget_ratio = 1e-9;
  /// Gradient path: the ranges' standard errors (range_standard_errors), which cost np + 2 more
  /// evaluations with their gradients (8 for an ARD fit in 6-D). The model choice's ranking fits,
  /// which only compare likelihoods, leave them out (NaN).
  bool standard_errors = true;
  int max_evaluations = 3000;
  double relative_tolerance = 1e-9;
  /// Exact, Vecchia, or Auto (exact up to kExactLikelihoodMaxSamples). Vecchia applies to every
  /// path: the gradient path (isotropic, ARD, rotated) and BOBYQA's nested models (their sets found
  /// once, in the isotropic metric).
  LikelihoodMethod method = LikelihoodMethod::Auto;
  /// Auto: the exact likelihood up to this many samples, Vecchia's beyond (1 to
  /// kExactLikelihoodMaxSamples). `interpolate --model auto` lowers it to 500 for its confirming fits:
  /// an exact evaluation costs ~0.1 s at 1,000 samples, a Vecchia one ~0.01 s (docs/kriging.md).
  long exact_max_samples = kExactLikelihoodMaxSamples;
  /// Vecchia: how many nearest predecessors each sample is conditioned on (m). 30 keeps the
  /// approximate REML ranges well within their standard errors of the exact ones in 2-D (measured,
  /// docs/kriging.md); a very smooth field in six dimensions (the robot's joint space) needed 80.
  /// More is closer and costs O(m^3) per sample.
  int vecchia_neighbours = 30;
  VecchiaOrdering vecchia_ordering = VecchiaOrdering::MaxMin;
  /// Vecchia: bytes the neighbour sets and per-sample terms may take; ResourceError before any work
  /// beyond it.
  std::size_t vecchia_memory_budget_bytes = std::size_t{4} << 30;
  /// Throws ArgumentError naming the field.
  void validate() const;
};

struct LikelihoodFitResult {
  VariogramModel model;                    ///< the estimate (structure components, then the nugget)
  double negative_log_likelihood = 0.0;    ///< at the estimate (ML or REML as asked)
  int evaluations = 0;
  bool converged = false;                  ///< NLopt met a tolerance (not the evaluation limit)
  std::string message;                     ///< NLopt's outcome in words
  int parameters = 0;                      ///< estimated covariance parameters (for AIC, BIC)
  double aic = 0.0;                        ///< 2 nll + 2 parameters
  double bic = 0.0;                        ///< 2 nll + parameters log(N C)
  /// Ranges along each coordinate (one entry when isotropic) in the coordinate unit, and their
  /// standard errors from the observed information of the profiled likelihood (delta method on
  /// log ranges); NaN when not available (BOBYQA path, or a singular information matrix).
  /// Rotated: the ranges along the principal axes (major, then minor 1 [, minor 2]), with standard
  /// errors at the fitted angles (not counting the angles' uncertainty).
  std::vector<double> ranges;
  std::vector<double> range_standard_errors;
  /// Rotated only: the angles of gstat's anis (2-D: the major axis, degrees clockwise from +y, in
  /// [0, 180); 3-D: azimuth, dip, rotation) and their standard errors from the curvature of the
  /// profile likelihood (NaN where it is not convex).
  std::vector<double> angles_deg;
  std::vector<double> angle_standard_errors_deg;
};

/// Whether `options` evaluate the likelihood of `samples` samples by the Vecchia approximation.
bool likelihood_uses_vecchia(const LikelihoodFitOptions& options, long samples);

/// The sample budget fit_likelihood checks before any work: ResourceError beyond
/// kMaxLikelihoodSamples for the exact likelihood, beyond kMaxVecchiaLikelihoodSamples or
/// options.vecchia_memory_budget_bytes for Vecchia, and, for rotated anisotropy in `dimension`
/// (2 or 3; 0 = unknown, not checked) coordinates, beyond kMaxRotatedLikelihoodWork. `columns`:
/// value components.
void check_likelihood_budget(Eigen::Index samples, Eigen::Index columns, const LikelihoodFitOptions& options,
                             int dimension = 0);

/// The (restricted) negative log-likelihood above (Vecchia's approximation of it when
/// likelihood_uses_vecchia(options, N); neighbours in the model's metric) for `model` at samples given as the rows of
/// `coordinates` (N x D) with `values` (N x C, C >= 1; a VectorXd is one column). Returns +infinity when K or F'K^-1F is not
/// positive definite. Throws ArgumentError for mismatched sizes or an unbounded model.
double negative_log_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                               const VariogramModel& model, const LikelihoodFitOptions& options);

/// Maximizes the (restricted) likelihood over the partial sills and ranges of `structure` and a
/// nugget (gradient path or BOBYQA, see above; BOBYQA starts from non-zero parameters of
/// `structure`, else data-based defaults). Throws ArgumentError / InputError for bad input (fewer
/// than kMinLikelihoodSamples samples, values that are all equal, a value spread outside
/// [kMinLikelihoodValueSpread, kMaxLikelihoodValueSpread]); the optimizer's outcome is in the result.
/// A range that ends on its box bound (1e-4 or 1e3 times the samples' extent; with ARD: every range
/// on the same bound) is reported as not converged, the message saying which bound and what it
/// means; a single ARD range on a bound is only noted in the message.
LikelihoodFitResult fit_likelihood(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                   const std::vector<ModelComponent>& structure,
                                   const LikelihoodFitOptions& options = {});

}  // namespace errfield

namespace errfield {

/// Automatic model choice by likelihood: every family in `kinds` (mat with each nu in
/// `matern_nu`) with a free nugget, isotropic and (if `try_ard` and D > 1) ARD, fitted by
/// fit_likelihood with `fit`'s kind and REML/ML; the candidate with the smallest criterion
/// (AIC = 2 nll + 2 k, or BIC = 2 nll + k log(N C)) *as fitted on all samples* wins among those
/// whose covariance matrix at the samples has an estimated 1-norm condition number <=
/// max_condition_number and that are not implausible (below). A candidate beyond the limit is never
/// returned; if all are, the nugget floor is raised and the choice repeated.
///
/// Two stages (docs/kriging.md, "Automatic model choice"):
///  1. Ranking: every candidate is fitted on a deterministic random subset of `choice_subsample`
///     samples (all samples when there are no more), with `fit`'s starts and local runs unless
///     ranking_starts / ranking_local_runs say fewer. The candidates' fits run on the OpenMP threads
///     (each fit is the same computation on any number of threads, so the choice does not depend on it).
///  2. Confirmation (when the ranking saw a subset or used fewer starts or runs than fit): the `confirmed` best-ranked candidates (and
///     more until one is plausible) are fitted again on all samples, each starting from its subset
///     estimate as well as from `fit`'s own starts, with one more local run than `fit` has
///     (confirm_with_plain_starts), so that their likelihood is at least that of a plain
///     fit_likelihood(coordinates, values, {family}, fit) on the exact path; the smallest criterion
///     among those all-sample fits wins. When the ranking saw every sample and used `fit`'s starts,
///     each candidate *is* the plain fit of its family, so none of them beats the choice either.
///
/// Implausible winners (set aside for the next candidate, with the reason in `reason` and
/// `warnings`; kept, with a warning, only when every fitted candidate is implausible): every range
/// beyond pathological_range_factor x the samples' extent along its coordinate (a trend, not a
/// range); an anisotropy ratio beyond pathological_anisotropy_ratio between ranges that lie within
/// that factor of their extent (a longer ARD range only says the field is flat along that
/// coordinate); a kriging system near singular (condition number > near_singular_condition).
struct ModelChoiceOptions {
  /// The plain fit of one family: the ranking fits (unless ranking_starts / ranking_local_runs) and
  /// the confirming fits start from these options.
  LikelihoodFitOptions fit;
  std::vector<ModelKind> kinds{ModelKind::Spherical, ModelKind::Exponential, ModelKind::Gaussian, ModelKind::Matern};
  std::vector<double> matern_nu{1.5, 2.5};  ///< mat(0.5) is exp, so it is not repeated by default
  bool try_isotropic = true;
  bool try_ard = true;
  enum class Criterion { Aic, Bic } criterion = Criterion::Aic;
  double max_condition_number = 1e12;
  /// With more samples than this, the candidates are ranked on a deterministic random subset of
  /// this size and the best `confirmed` are fitted again on all samples; 0 = always all. The subset
  /// depends on the samples, not on their order.
  std::size_t choice_subsample = 700;
  /// Ranking fits' screened starts and local L-BFGS runs (0 = fit's). Fewer than fit's make the
  /// ranking cheaper; when the ranking sees every sample its fits are then not plain fits.
  int ranking_starts = 0;
  int ranking_local_runs = 0;
  /// How many of the best-ranked candidates are fitted again on all samples (>= 1).
  std::size_t confirmed = 3;
  /// With more samples than this (> 0), the confirming fits see a deterministic random subset of
  /// this size (drawn as the ranking's, with another seed; >= choice_subsample) instead of all
  /// samples: the exact likelihood costs N^3 per evaluation, and the confirmation was nearly all of a
  /// fit's time at 2,000 samples. The model is then estimated on the subset (the prediction still
  /// krigs with every sample). 0 = all samples.
  std::size_t confirm_subsample = 0;
  /// true: a confirming fit screens the subset estimate with fit's starts and runs fit.local_runs +
  /// 1 local runs (never worse than the plain fit on the exact path). false: one local run from the
  /// best screened start (nearly always the subset estimate): cheaper, without that guarantee.
  bool confirm_with_plain_starts = true;
  /// true: the candidates plausible on the ranking's samples are confirmed first (best ranked
  /// first), and no others; when none is, only the best `confirmed` are (the best kept with a
  /// warning). false: by rank alone, batch by batch until one is plausible on all samples, through
  /// every candidate if need be (ten full fits when every candidate is implausible: an indicator
  /// of a rare class took 2.2 s of `interpolate --model auto` that way, issue 49).
  bool confirm_plausible_first = false;
  double pathological_range_factor = 10.0;
  double pathological_anisotropy_ratio = 100.0;
  double near_singular_condition = 1e10;
  /// Throws ArgumentError naming the field.
  void validate() const;
  /// The fast preset (`interpolate --model auto`, --auto-search fast): ranked on up to 250 samples
  /// with 4 screened starts and one run each; the best 2 plausible ones polished on all samples
  /// from their ranking estimate by one run to a relative tolerance of 1e-6, by the exact likelihood
  /// up to 500 samples and Vecchia's beyond. 0.6-0.9 s at 1,000 samples in 2-D on 2 cores (the defaults: 13-16 s);
  /// on gstat's data sets the same families as the defaults (docs/kriging.md).
  static ModelChoiceOptions fast();
};

struct ModelChoiceCandidate {
  VariogramModel model;           ///< as fitted on all samples when confirmed, else as ranked
  double negative_log_likelihood = 0.0;
  double criterion = 0.0;         ///< AIC or BIC as asked, of the ranking fit (on the subset when there was one)
  /// The criterion of the fit on all samples: the ranking's when it saw every sample, the
  /// confirming fit's when confirmed, NaN otherwise.
  double all_samples_criterion = std::numeric_limits<double>::quiet_NaN();
  double condition_number = 0.0;  ///< of the covariance at the samples (1-norm estimate)
  bool accepted = false;          ///< fitted and well conditioned
  std::string implausible;        ///< why the model is implausible (empty: plausible)
  std::string note;               ///< why rejected, or the optimizer's outcome
};

struct ModelChoice {
  VariogramModel model;
  LikelihoodFitResult fit;                       ///< of the chosen candidate, on all samples
  std::vector<ModelChoiceCandidate> candidates;  ///< every candidate tried, in order
  std::string reason;                            ///< one line: what won, by which criterion, what was set aside
  std::vector<std::string> warnings;             ///< implausible candidates set aside, or an implausible winner kept
};

/// Throws InputError when no candidate can be fitted; ArgumentError for bad options.
ModelChoice choose_likelihood_model(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                    const ModelChoiceOptions& options = {});

}  // namespace errfield
