#pragma once
/// Fitting a linear model of coregionalization (coregionalization_model.hpp) to the direct and
/// cross empirical variograms of P value components (empirical_variogram.hpp with
/// cross_variograms). Use it before cokriging, when the components of a vector error (ex, ey, ez)
/// are correlated with each other.
///
/// The kinds and ranges of the K basic structures g_k are fixed; the P x P coregionalization
/// matrices B_k are fitted to the bins j (mean lag h_j, N_j pairs, P x P matrix G_j of direct and
/// cross semivariances) by weighted least squares,
///   Q(B) = sum_j w_j || G_j - sum_k B_k g_k(h_j) ||_F^2     (every entry, off-diagonals twice),
/// with the weights of gstat's fit.method: nj (1) w_j = N_j, nj_h2 (7, the default)
/// w_j = N_j / h_j^2, unweighted (6) w_j = 1. The weight is the same for every entry of a bin,
/// so without the PSD constraint Q separates into one linear fit per direct/cross variogram.
///
/// Methods:
///   GoulardVoltz  (Goulard & Voltz 1992) each B_k in turn is replaced by its exact constrained
///                 minimizer with the others fixed: the unconstrained WLS update projected onto the
///                 PSD cone (eigenvalues clipped at 0, the nearest PSD matrix in Frobenius norm),
///                 until no entry of a B_k moves by more than the relative tolerance (of the
///                 largest entry) or a sweep no longer lowers Q. It starts from
///                 the Gstat result, and every update lowers Q, so its Q is never above Gstat's.
///   Gstat         R gstat's fit.lmc (fit.ranges = FALSE, correct.diagonal = 1): each direct and
///                 cross variogram is fitted alone by linear WLS of its partial sills (a direct
///                 variogram's negative sills are fixed at 0 and the rest refitted, as
///                 fit.variogram does), then each B_k is made PSD by clipping its eigenvalues.
///
/// Ranges: fit_coregionalization_ranges fits them (when the user gives none) to the mean of the
/// direct variograms with fit_variogram (variogram_fit.hpp), gstat's habit of one set of ranges
/// for all components. Formulas: docs/geostatistics.md.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "errfield/coregionalization_model.hpp"
#include "errfield/empirical_variogram.hpp"
#include "errfield/heterotopic_variogram.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

enum class LmcFitMethod {
  GoulardVoltz,  ///< "goulard-voltz": iterated PSD-projected WLS (default)
  Gstat,         ///< "gstat": separate linear fits, then PSD projection (gstat's fit.lmc)
};
std::string_view lmc_fit_method_name(LmcFitMethod m);
/// "goulard-voltz" or "gstat"; throws ArgumentError listing them.
LmcFitMethod lmc_fit_method_from_name(std::string_view name);

enum class LmcWeighting {
  Nj,          ///< "nj": N_j (gstat fit.method 1)
  NjOverH2,    ///< "nj_h2": N_j / h_j^2 (gstat fit.method 7, its default)
  Unweighted,  ///< "unweighted": 1 (gstat fit.method 6, ordinary least squares)
};
std::string_view lmc_weighting_name(LmcWeighting w);
/// "nj", "nj_h2", "unweighted" (and gstat's numbers "1", "7", "6"); throws ArgumentError.
LmcWeighting lmc_weighting_from_name(std::string_view name);

struct CoregionalizationFitOptions {
  LmcFitMethod method = LmcFitMethod::GoulardVoltz;
  LmcWeighting weighting = LmcWeighting::NjOverH2;
  double relative_tolerance = 1e-12;  ///< Goulard-Voltz: stop when max |B change| <= this x max |B|
  int max_iterations = 10000;         ///< Goulard-Voltz sweeps over all B_k
  /// Throws ArgumentError naming the offending field.
  void validate() const;
};

/// Binned direct and cross semivariances: gamma[j] is the symmetric P x P matrix of bin j.
struct CrossVariogramTable {
  std::vector<double> lag;             ///< mean lag h_j of each bin (lag unit)
  std::vector<std::uint64_t> pairs;    ///< N_j (bins with 0 pairs are skipped)
  std::vector<Eigen::MatrixXd> gamma;  ///< value unit^2
  /// Heterotopic data (heterotopic_variogram.hpp): every direct and cross variogram has pairs of
  /// its own, so bin j has a mean lag and a pair count per entry (P x P, symmetric: (i, i) the
  /// direct variogram of i, (i, l) the cross-variogram). Empty for homotopic data, whose
  /// variograms share `lag` and `pairs`; when set, `lag` and `pairs` are not used and an entry
  /// with 0 pairs in a bin (its gamma NaN) is skipped there.
  std::vector<Eigen::MatrixXd> entry_lag, entry_pairs;
  bool heterotopic() const noexcept { return !entry_lag.empty(); }
  /// From an EmpiricalVariogram computed with cross_variograms (throws ArgumentError otherwise).
  static CrossVariogramTable from(const EmpiricalVariogram& v);
  /// From heterotopic variograms computed with cross_variograms (throws ArgumentError otherwise):
  /// each entry with its own lags and pairs.
  static CrossVariogramTable from(const HeterotopicVariogram& v);
};

struct CoregionalizationFitResult {
  CoregionalizationModel model;  ///< the fitted LMC (every B_k PSD)
  double weighted_residual = 0.0;  ///< Q(B) above, value unit^4 x weight unit
  int iterations = 0;              ///< Goulard-Voltz sweeps (0 for Gstat)
  bool converged = true;           ///< false when Goulard-Voltz stopped at max_iterations
  /// Per structure: the smallest eigenvalue of B_k before its PSD projection (for Goulard-Voltz,
  /// of the last unconstrained update). Negative: the projection changed B_k.
  std::vector<double> smallest_eigenvalue_before_projection;
  std::size_t bins_used = 0;
  std::string message;
};

/// Fits the B_k of `structures` (kinds, ranges and nu used; sills ignored; bounded kinds only) to
/// `table`. A heterotopic table (each variogram over its own pairs and lags) is fitted by the
/// Gstat method, each variogram with its own bins and weights, as gstat's fit.lmc fits the
/// variograms of a gstat object with one data set per variable; Goulard-Voltz is refused there
/// (ArgumentError): its block update is the exact constrained minimizer only when every entry of a
/// bin has the same weight. `component_names` (empty or P names) go into the model. Throws ArgumentError for an
/// empty structure list, an unbounded kind (pow, lin), a missing range, mismatched sizes, fewer
/// than 2 components, fewer usable bins than structures, or invalid options; InputError for a
/// non-finite or asymmetric gamma matrix or a negative lag, or a component with no spatial variation (its direct variogram 0 in every bin).
CoregionalizationFitResult fit_coregionalization(const CrossVariogramTable& table,
                                                 const std::vector<ModelComponent>& structures,
                                                 const CoregionalizationFitOptions& options = {},
                                                 std::vector<std::string> component_names = {});

/// The structures with their ranges fitted (sills ignored) to the mean of the direct variograms,
/// (1/P) sum_i gamma_ii, by fit_variogram with the same weighting; a nug structure makes the
/// nugget free, otherwise there is none. Throws like fit_coregionalization, and
/// ArgumentError when the fit fails, or for a heterotopic table (the direct variograms have lags
/// of their own: give the ranges). `component_names` (optional) name the components in messages.
std::vector<ModelComponent> fit_coregionalization_ranges(const CrossVariogramTable& table,
                                                         const std::vector<ModelComponent>& structures,
                                                         LmcWeighting weighting = LmcWeighting::NjOverH2,
                                                         const std::vector<std::string>& component_names = {});

/// The structures of an LMC fit from text: a model in VariogramModel's text form
/// ("nug(0)+sph(1,400)": kinds, ranges and nu kept, sills ignored; ranges_given = true) or
/// '+'-separated kinds ("nug+sph": ranges to be fitted, e.g. by fit_coregionalization_ranges;
/// ranges_given = false; a mat kind takes `nu`, which must then be > 0). A model may carry an
/// anisotropy ('@ard(...)', '@anis(...)'): the LMC is then fitted to the variograms of the mapped
/// coordinates A x (only from samples, where the mapping can be applied) and keeps it. Throws
/// ArgumentError naming the offending text, for an unbounded kind (pow, lin) or mat without nu.
struct CoregionalizationTemplate {
  std::vector<ModelComponent> structures;
  bool ranges_given = false;
  Anisotropy anisotropy;  ///< isotropic unless the template model has one
};
CoregionalizationTemplate parse_coregionalization_template(std::string_view text, double nu = 0.0);

/// Q(B) of `model` on `table` with `weighting` (the quantity both methods minimize).
double coregionalization_weighted_residual(const CrossVariogramTable& table, const CoregionalizationModel& model,
                                           LmcWeighting weighting);

}  // namespace errfield
