#pragma once
/// Parametric variogram models and sums of them, in gstat's `vgm` vocabulary so that users and
/// cross-checks speak one language. Use a model to describe how fast an error field decorrelates:
/// fitted to an empirical variogram (variogram_fit.hpp) or written by hand, it drives kriging.
///
/// Each component has a partial sill `sill` (unit of the value squared, e.g. mm^2) and a `range`
/// (unit of the lag, e.g. mm or degrees). As in gstat, `range` is the model's scale parameter `a`:
///   nug  gamma(h) = sill                                  for h > 0, 0 at h = 0
///   sph  gamma(h) = sill (1.5 h/a - 0.5 (h/a)^3)          for h < a, sill beyond (range = a)
///   exp  gamma(h) = sill (1 - exp(-h/a))                  (practical range ~3a)
///   gau  gamma(h) = sill (1 - exp(-(h/a)^2))              (practical range ~sqrt(3) a)
///   mat  gamma(h) = sill (1 - 2^(1-nu)/Gamma(nu) (h/a)^nu K_nu(h/a))   (gstat's "Mat", kappa = nu)
///   wen  gamma(h) = sill (1 - (1 - h/a)^4 (4 h/a + 1))    for h < a (Wendland C2, compact support)
///   pow  gamma(h) = sill h^e                              (unbounded; range = exponent e, 0 < e < 2)
///   lin  gamma(h) = sill h                                (unbounded; sill is the slope per lag unit)
/// The mathematics and references are in docs/geostatistics.md.
///
/// Text form (parse/to_string): components joined by '+', each `kind(sill=S,range=A[,nu=V])`, or
/// positionally `kind(S,A[,V])`; a nugget is `nug(S)`; `pow(sill=S,exponent=E)`, `lin(slope=S)`.
/// Example: "sph(sill=0.3,range=400)+nug(0.002)".
/// A geometric anisotropy of the whole model (anisotropy.hpp) follows an '@':
/// "mat(sill=1,range=40,nu=2.5)+nug(0.01)@ard(1,0.5,0.25)" (ranges 40, 20, 10 along x, y, z), or
/// "sph(sill=1,range=100)@anis(30,0.5)" (gstat's anis). Lags h below are then |A (x - y)|.

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "errfield/anisotropy.hpp"

namespace errfield {

enum class ModelKind { Nugget, Spherical, Exponential, Gaussian, Matern, Wendland, Power, Linear };

/// Short name used in text, JSON and the CLI: "nug", "sph", "exp", "gau", "mat", "wen", "pow", "lin".
std::string_view model_kind_name(ModelKind kind);
/// Inverse of model_kind_name; throws ArgumentError listing the known names.
ModelKind model_kind_from_name(std::string_view name);

/// The largest Matérn smoothness errfield evaluates: beyond it Gamma(nu) and K_nu leave double range
/// at ordinary lags (`--nu 1e8` hung a WLS fit, 1e10 threw from the Bessel function), and the model is
/// the Gaussian one to plotting accuracy anyway (use gau). Every fit and model refuses nu outside
/// (0, kMaxMaternNu], naming it.
inline constexpr double kMaxMaternNu = 100.0;

/// One term of a variogram model. `range` is unused by nug and lin; `nu` only by mat.
struct ModelComponent {
  ModelKind kind = ModelKind::Spherical;
  double sill = 0.0;   ///< partial sill (value unit^2); for lin the slope (value unit^2 per lag unit)
  double range = 0.0;  ///< scale a (lag unit); for pow the exponent
  double nu = 0.5;     ///< Matérn smoothness, 0 < nu <= 100

  /// gamma of this component alone at lag h >= 0.
  double gamma(double h) const;
  /// Whether gamma levels off at `sill` (false for pow and lin).
  bool bounded() const { return kind != ModelKind::Power && kind != ModelKind::Linear; }
  /// Whether gamma reaches the sill at a finite lag (sph, wen): the covariance then has compact
  /// support and kriging systems become sparse.
  bool compact() const { return kind == ModelKind::Spherical || kind == ModelKind::Wendland; }
};

/// A sum of components. Immutable value type; thread-safe to evaluate concurrently.
class VariogramModel {
 public:
  VariogramModel() = default;
  /// Throws ArgumentError naming the component and parameter when a parameter is out of domain
  /// (negative sill, range <= 0, nu outside (0, 100], power exponent outside (0, 2)).
  explicit VariogramModel(std::vector<ModelComponent> components, Anisotropy anisotropy = {});

  /// Parses the text form described above; throws ArgumentError pointing at the offending text.
  static VariogramModel parse(std::string_view text);
  /// Text form that parse() reads back to the same model (numbers in shortest round-trip form).
  std::string to_string() const;

  const std::vector<ModelComponent>& components() const noexcept { return components_; }
  /// The map of coordinate differences applied before the lag (isotropic by default).
  const Anisotropy& anisotropy() const noexcept { return anisotropy_; }
  /// The same components with another anisotropy.
  VariogramModel with_anisotropy(Anisotropy anisotropy) const { return VariogramModel(components_, std::move(anisotropy)); }
  /// The same components, isotropic: what the lag-based evaluation below uses.
  VariogramModel isotropic_part() const { return VariogramModel(components_); }

  /// Semivariance at lag h >= 0 (gamma(0) = 0).
  double gamma(double h) const;
  /// Total sill (sum of partial sills, nugget included). Only meaningful when bounded().
  double sill() const;
  /// Sum of nugget components' sills.
  double nugget() const;
  /// True when every component is bounded, so a covariance C(h) = sill() - gamma(h) exists.
  bool bounded() const;
  /// True when every non-nugget component has compact support (sph, wen).
  bool compact() const;
  /// Largest lag beyond which C(h) = 0 for a compact model (max range); infinity otherwise.
  double support() const;
  /// Covariance C(h) = sill() - gamma(h); C(0) = sill(). Precondition: bounded().
  double covariance(double h) const { return sill() - gamma(h); }

 private:
  std::vector<ModelComponent> components_;
  Anisotropy anisotropy_;
};

/// JSON form: {"components":[{"kind":"sph","sill":0.3,"range":400}, ...]} (nu only for mat), plus
/// "anisotropy": {"ard": [s1, ...]} or {"anis": [angle, ratio]} when not isotropic.
void to_json(nlohmann::json& j, const VariogramModel& model);
/// Throws ArgumentError naming the offending field.
void from_json(const nlohmann::json& j, VariogramModel& model);

/// A model given on a command line or in a file: a path ending in ".json" (a model JSON as
/// fit-variogram writes it) is read, anything else is parsed as model text. Throws ArgumentError /
/// InputError naming the file or the text.
VariogramModel load_variogram_model(std::string_view text_or_file);

}  // namespace errfield
