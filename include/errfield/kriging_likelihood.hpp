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
  int max_evaluations = 3000;
  double relative_tolerance = 1e-9;
  /// Exact, Vecchia, or Auto (exact up to kExactLikelihoodMaxSamples). Vecchia applies to every
  /// path: the gradient path (isotropic, ARD, rotated) and BOBYQA's nested models (their sets found
  /// once, in the isotropic metric).
  LikelihoodMethod method = LikelihoodMethod::Auto;
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
/// (AIC = 2 nll + 2 k, or BIC = 2 nll + k log(N C)) wins among those whose covariance matrix at the
/// samples has an estimated 1-norm condition number <= max_condition_number. A candidate beyond
/// it is never returned; if all are, the nugget floor is raised tenfold and the choice repeated.
/// Cost: one likelihood fit per candidate (O(n^3) per evaluation, n = min(N, choice_subsample)),
/// plus one refit on all N samples when N > choice_subsample.
struct ModelChoiceOptions {
  LikelihoodFitOptions fit;
  std::vector<ModelKind> kinds{ModelKind::Spherical, ModelKind::Exponential, ModelKind::Gaussian, ModelKind::Matern};
  std::vector<double> matern_nu{1.5, 2.5};  ///< mat(0.5) is exp, so it is not repeated by default
  bool try_isotropic = true;
  bool try_ard = true;
  enum class Criterion { Aic, Bic } criterion = Criterion::Aic;
  double max_condition_number = 1e12;
  /// With more samples than this, the candidates are compared on a deterministic random subset of
  /// this size (the choice needs the family, not the last digit) and the winner is refitted on all
  /// samples; 0 = always all. The subset depends on the samples, not on their order. 700 covers a
  /// campaign of the real data's size whole: with 300, on SIMULATED KR 16 fits of 400 / 560 / 687
  /// poses (3 draws, docs/robot.md "More data, same model"), the subset's family scored a held-out
  /// RMS 2 % worse on average and up to 9 % worse at 687 poses, for a third of the fit time.
  std::size_t choice_subsample = 700;
};

struct ModelChoiceCandidate {
  VariogramModel model;
  double negative_log_likelihood = 0.0;
  double criterion = 0.0;         ///< AIC or BIC as asked
  double condition_number = 0.0;  ///< of the covariance at the samples (1-norm estimate)
  bool accepted = false;          ///< fitted and well conditioned
  std::string note;               ///< why rejected, or the optimizer's outcome
};

struct ModelChoice {
  VariogramModel model;
  LikelihoodFitResult fit;                       ///< of the chosen candidate
  std::vector<ModelChoiceCandidate> candidates;  ///< every candidate tried, in order
  std::string reason;                            ///< one line: what won and by which criterion
};

/// Throws InputError when no candidate can be fitted; ArgumentError for bad options.
ModelChoice choose_likelihood_model(const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& values,
                                    const ModelChoiceOptions& options = {});

}  // namespace errfield
