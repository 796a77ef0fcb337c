#pragma once
/// A linear model of coregionalization (LMC) for values with P components (e.g. a robot's ex, ey,
/// ez position errors): every direct and cross variogram is a combination of the same K basic
/// structures,
///   gamma_ij(h) = sum_k B_k(i, j) g_k(h),
/// where g_k is a unit-sill basic structure (nug, sph, exp, gau, mat, wen; gstat's `vgm` vocabulary,
/// `range` the scale parameter a) and B_k is the P x P coregionalization matrix of structure k: its
/// diagonal holds the partial sills of the direct variograms, its off-diagonal entries the partial
/// sills of the cross variograms (value unit^2, may be negative). The model is valid (every
/// cokriging variance is >= 0) exactly when every B_k is symmetric positive semi-definite, which
/// the constructor checks.
///
/// This is what gstat's `fit.lmc` produces. The shared model that Kriging uses for vector values is
/// the special case K structures with B_k = b_k I (intrinsic, no cross-covariance). Use an LMC when
/// the components are correlated with each other differently at different ranges.
///
/// JSON form (what `fit-variogram --lmc` writes, what `interpolate --method kriging --model lmc.json` reads):
///   {"type": "lmc", "components": ["ex", "ey", "ez"],
///    "structures": [{"kind": "nug", "sills": [[...], [...], [...]]},
///                   {"kind": "sph", "range": 400, "sills": [[...], [...], [...]]}],
///    "anisotropy": {"ard": [...]}}            (optional, as in a VariogramModel)

#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/anisotropy.hpp"
#include "errfield/variogram_model.hpp"

namespace errfield {

/// One basic structure with its coregionalization matrix.
struct CoregionalizationStructure {
  ModelKind kind = ModelKind::Spherical;
  double range = 0.0;      ///< scale a (lag unit); unused by nug
  double nu = 0.5;         ///< Matérn smoothness (mat only)
  Eigen::MatrixXd sills;   ///< P x P, symmetric positive semi-definite (value unit^2)

  /// The unit-sill structure g_k(h) (0 at h = 0, 1 far away).
  double unit_gamma(double h) const;
  /// False for pow and lin, which have no sill and hence no covariance.
  bool bounded_kind() const { return kind != ModelKind::Power && kind != ModelKind::Linear; }
};

/// Immutable value type; thread-safe to evaluate concurrently.
class CoregionalizationModel {
 public:
  CoregionalizationModel() = default;
  /// Throws ArgumentError naming the structure and entry when: there are no structures; the
  /// matrices are not all P x P with the same P >= 1; a matrix is not symmetric (relative 1e-9) or
  /// not positive semi-definite (an eigenvalue below -1e-10 times the largest); a range is not
  /// positive and finite; nu is outside (0, 100]; a structure is unbounded (pow, lin: cokriging here
  /// works with covariances); `component_names` is neither empty nor of size P.
  CoregionalizationModel(std::vector<CoregionalizationStructure> structures, Anisotropy anisotropy = {},
                         std::vector<std::string> component_names = {});

  /// The intrinsic model with the same structures as `shared` and B_k = sill_k * coregionalization
  /// (coregionalization: P x P, symmetric PSD, e.g. the components' correlation matrix). With the
  /// identity it is the shared model Kriging uses for vector values.
  static CoregionalizationModel intrinsic(const VariogramModel& shared, const Eigen::MatrixXd& coregionalization,
                                          std::vector<std::string> component_names = {});

  int components() const noexcept { return components_; }
  const std::vector<CoregionalizationStructure>& structures() const noexcept { return structures_; }
  const Anisotropy& anisotropy() const noexcept { return anisotropy_; }
  /// Names of the P components (empty when not given).
  const std::vector<std::string>& component_names() const noexcept { return names_; }

  /// gamma_ij(h) for h >= 0 (0 at h = 0).
  double gamma(int i, int j, double h) const;
  /// The P x P matrix of gamma_ij(h).
  Eigen::MatrixXd gamma_matrix(double h) const;
  /// The P x P cross-covariance C(h) = sill() - gamma_matrix(h); C(0) = sill().
  Eigen::MatrixXd covariance_matrix(double h) const;
  /// sum_k B_k: the covariance of the components at one location.
  Eigen::MatrixXd sill() const;
  /// sum_k of the nugget structures' B_k (P x P zeros when there is none).
  Eigen::MatrixXd nugget() const;
  /// The direct variogram of component i as a VariogramModel (partial sills B_k(i, i)).
  VariogramModel direct_model(int i) const;
  /// Text summary, one line per structure ("sph(range=400) B=[[...],[...]]"), for reports.
  std::string to_string() const;

 private:
  std::vector<CoregionalizationStructure> structures_;
  Anisotropy anisotropy_;
  std::vector<std::string> names_;
  int components_ = 0;
};

void to_json(nlohmann::json& j, const CoregionalizationModel& model);
/// Throws ArgumentError naming the offending field.
void from_json(const nlohmann::json& j, CoregionalizationModel& model);
/// Whether a parsed JSON document is an LMC (has "type": "lmc").
bool is_coregionalization_json(const nlohmann::json& j);
/// Reads an LMC JSON file; throws InputError naming the file and the problem.
CoregionalizationModel load_coregionalization_model(std::string_view path);

}  // namespace errfield
