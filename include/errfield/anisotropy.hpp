#pragma once
/// Geometric anisotropy of a covariance: the field decorrelates faster along some directions than
/// others. Use it when one range cannot describe every axis: joints that move the tool by different
/// amounts per degree (automatic relevance determination, ARD: one range per coordinate, any
/// dimension), or a field stretched along an oblique direction (gstat's `anis`, rotated, 2-D/3-D).
///
/// It is a linear map A of coordinate differences: the lag the (isotropic) variogram model sees is
///   h = |A (x - y)|
/// so that kriging honours it by mapping the locations once (every back end: dense, local with its
/// neighbours found in the mapped space, sparse). Conventions (docs/geostatistics.md, "Anisotropy"):
///   - ard(s_1, ..., s_D): A = diag(1/s_k); the range along coordinate k is range * s_k.
///   - anis(angle, ratio) in 2-D, gstat's: the major axis points `angle` degrees clockwise from +y
///     (north); the range across it is ratio * range (0 < ratio <= 1 usually, any > 0 accepted).
///   - anis(p, q, r, s, t) in 3-D, gstat's (GSLIB's): azimuth p clockwise from +y, dip q up from the
///     horizontal, rotation r about the major axis; ratios s (minor 1) and t (minor 2) to the major
///     range.
/// Text form: the suffix "@ard(...)" or "@anis(...)" of a model text (variogram_model.hpp).
/// Immutable value type; thread-safe.

#include <string>
#include <string_view>
#include <vector>

namespace errfield {

class Anisotropy {
 public:
  enum class Type { None, Ard, Rotated };

  /// Isotropic (A = identity in any dimension).
  Anisotropy() = default;
  /// One range multiplier per coordinate, each finite and > 0; throws ArgumentError naming it.
  static Anisotropy ard(std::vector<double> range_multipliers);
  /// gstat's anis: 2 numbers (2-D) or 5 (3-D), angles in degrees; throws ArgumentError.
  static Anisotropy rotated(std::vector<double> gstat_anis);
  /// Parses "ard(1,0.5,2)" or "anis(30,0.5)"; throws ArgumentError pointing at the text.
  static Anisotropy parse(std::string_view text);

  Type type() const noexcept { return type_; }
  bool isotropic() const noexcept { return type_ == Type::None; }
  /// Number of coordinates it applies to (0 for isotropic: any).
  int dimension() const noexcept { return dimension_; }
  /// The numbers as given (ARD multipliers, or gstat's anis).
  const std::vector<double>& parameters() const noexcept { return parameters_; }
  /// A: row-major D x D when rotated, its D diagonal entries 1/s_k for ARD, empty for isotropic.
  const std::vector<double>& matrix() const noexcept { return matrix_; }
  /// out = A in (D doubles each, D = dimension() unless isotropic; `in` and `out` must not
  /// overlap). Isotropic: a copy.
  void apply(const double* in, double* out, int dimension) const;
  /// "ard(1,0.5)" / "anis(30,0.5)"; empty for isotropic.
  std::string to_string() const;

 private:
  Type type_ = Type::None;
  int dimension_ = 0;
  std::vector<double> parameters_;
  std::vector<double> matrix_;
};

}  // namespace errfield
