#pragma once
/// Fitting a variogram model (variogram_model.hpp) to an empirical variogram
/// (empirical_variogram.hpp) by weighted least squares, in gstat's `fit.variogram` vocabulary.
/// Use it to turn binned semivariances into the model that kriging needs.
///
/// Over the non-empty bins j (mean lag h_j, semivariance g_j, N_j pairs) it minimizes
///   SSE(theta) = sum_j w_j (g_j - gamma(h_j; theta))^2
/// with the weights of gstat's fit.method:
///   nj       (fit.method = 1)  w_j = N_j
///   cressie  (fit.method = 2)  w_j = N_j / gamma(h_j; theta)^2   (model value; Cressie 1985)
///   nj_h2    (fit.method = 7)  w_j = N_j / h_j^2                 (gstat's default)
/// over the partial sills and ranges of the given structure (Matérn nu stays fixed) and, as
/// asked, a nugget (free, fixed at a value, or none). Lags and semivariances are scaled to order 1
/// internally, so coordinates in the thousands of mm or values in um^2 fit alike. The optimizer is
/// NLopt's BOBYQA (bound-constrained, derivative-free) from several starting points; the best
/// result is kept. Formulas and units: docs/geostatistics.md.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "errfield/empirical_variogram.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

enum class FitWeighting {
  Nj,        ///< "nj": N_j (gstat fit.method 1)
  Cressie,   ///< "cressie": N_j / gamma_model(h_j)^2 (gstat fit.method 2)
  NjOverH2,  ///< "nj_h2": N_j / h_j^2 (gstat fit.method 7, its default)
};
std::string_view weighting_name(FitWeighting w);
/// Accepts "nj", "nj_h2", "cressie" (and gstat's numbers "1", "7", "2"); throws ArgumentError.
FitWeighting weighting_from_name(std::string_view name);

enum class NuggetMode {
  Free,   ///< fitted, >= 0
  Fixed,  ///< held at VariogramFitOptions::nugget_value
  None,   ///< no nugget component
};

struct VariogramFitOptions {
  FitWeighting weighting = FitWeighting::NjOverH2;
  NuggetMode nugget = NuggetMode::Free;
  double nugget_value = 0.0;  ///< value unit^2, for NuggetMode::Fixed (>= 0)
  /// Bounds in the data's units; a bound <= 0 means "automatic": ranges within
  /// [1e-6, 100] x the largest lag, partial sills within [0, 100] x the largest semivariance.
  double range_min = 0.0;
  double range_max = 0.0;
  double sill_max = 0.0;
  /// NuggetMode::Free: a starting value of the nugget (value unit^2; > 0), tried beside the
  /// automatic starts with the structure's own parameters (a template such as
  /// `nug(sill=2e4)+sph(sill=3e4,range=25)`); <= 0: none.
  double nugget_start = 0.0;
  /// Parameters held at the structure's given values instead of fitted (gstat's fit.sills = FALSE /
  /// fit.ranges = FALSE, per structure): entry i is for the i-th non-nugget component of the
  /// structure. Empty = nothing held; otherwise one entry per component. A held parameter must be
  /// given (> 0) in the structure; a held power exponent is the component's `range`.
  std::vector<bool> hold_sill;
  std::vector<bool> hold_range;
  int starts = 6;                      ///< starting points of the multistart (>= 1)
  double relative_tolerance = 1e-12;   ///< NLopt ftol_rel and xtol_rel of each local run
  int max_evaluations = 20000;         ///< per local run
  /// Throws ArgumentError naming the offending field.
  void validate() const;
};

enum class FitStatus {
  Converged,       ///< a local run met the tolerance
  MaxEvaluations,  ///< the best run stopped at max_evaluations
  Failed,          ///< NLopt reported an error; `model` holds the starting point
};

struct VariogramFitResult {
  VariogramModel model;        ///< fitted model (structure components first, then the nugget)
  double weighted_sse = 0.0;   ///< SSE(theta) above, in the data's units
  FitStatus status = FitStatus::Failed;
  std::string message;         ///< NLopt's outcome in words, and any parameter left at an upper bound
  int evaluations = 0;         ///< objective evaluations over all starts
  std::size_t bins_used = 0;   ///< non-empty bins that entered the fit
};

/// Fits the components of `structure` (kinds, and nu for mat; non-zero parameters are used as one
/// of the starting points, and held ones are kept; a nug component in it is ignored, the nugget
/// follows options.nugget and options.nugget_start). Nested structures (sph + sph, ...) fit alike.
/// to the bins with lags `lag` (> 0 for nj_h2), semivariances `gamma` and pair counts `pairs`
/// (bins with 0 pairs are skipped). Throws ArgumentError for mismatched sizes, an empty
/// structure, fewer usable bins than free parameters, or invalid options; InputError for a
/// non-finite or negative lag or semivariance.
VariogramFitResult fit_variogram(std::span<const double> lag, std::span<const double> gamma,
                                 std::span<const std::uint64_t> pairs,
                                 const std::vector<ModelComponent>& structure,
                                 const VariogramFitOptions& options = {});

/// Same, from an EmpiricalVariogram (mean lag of each bin as h_j).
VariogramFitResult fit_variogram(const EmpiricalVariogram& empirical,
                                 const std::vector<ModelComponent>& structure,
                                 const VariogramFitOptions& options = {});

/// The weighted SSE of `model` on the given bins, with the weights of `weighting` (cressie uses
/// the model's own values). Bins with 0 pairs are skipped.
double weighted_sse(std::span<const double> lag, std::span<const double> gamma,
                    std::span<const std::uint64_t> pairs, const VariogramModel& model,
                    FitWeighting weighting);

}  // namespace errfield
