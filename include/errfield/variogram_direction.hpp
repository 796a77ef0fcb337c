#pragma once
/// Which pairs a directional empirical variogram counts: those whose separation s = x_i - x_j
/// points, in either sense, within an angular tolerance of a direction. Use it to look at
/// anisotropy before fitting one (anisotropy.hpp): a field that decorrelates faster along one
/// direction shows a variogram that rises faster along it. Set it in
/// EmpiricalVariogramOptions::direction (empirical_variogram.hpp).
///
/// Conventions (docs/geostatistics.md, "Directional variograms"):
///  - gstat(alpha, tol_hor, beta, tol_ver), 2-D or 3-D, as R gstat's variogram(alpha=, tol.hor=,
///    beta=, tol.ver=): alpha is the horizontal direction in degrees clockwise from +y (axis 1)
///    towards +x (axis 0); beta the dip in degrees up from the x-y plane (axis 2 is up). A pair
///    passes the horizontal test when the angle between (s_x, s_y) and the direction (sin alpha,
///    cos alpha) or its opposite is at most tol_hor; the test is skipped when tol_hor >= 90 (every
///    angle passes) or (s_x, s_y) = 0. It passes the vertical test when the angle between
///    (|(s_x, s_y)|, s_z) and (cos beta, sin beta) or its opposite is at most tol_ver; skipped when
///    tol_ver >= 90 or s = 0. Default tol_ver = 90: no vertical test.
///  - along(u, tol), any dimension: the angle between s and the unit vector u (or -u) is at most
///    tol; axis(k, D, tol) is along(e_k). With tol = 45 the D axis cones are disjoint but for
///    their boundaries: a pair is "along k" when s_k^2 is at least half of |s|^2.
/// Boundary: an angle equal to the tolerance counts in exact arithmetic; the test compares cosines
/// in floating point, so a pair exactly on the boundary (a grid diagonal at tol 45) may fall on
/// either side (gstat too: its pi is 3.14159265359). Use a tolerance a hair wider (45.001) to be
/// sure. A pair at zero separation passes (it only enters a bin starting at lag 0). Angles are
/// taken in the location coordinates, not in a weighted metric's scaled space.
/// Immutable value type; thread-safe.

#include <string>
#include <vector>

namespace errfield {

class VariogramDirection {
 public:
  enum class Kind { All, Gstat, Vector };

  /// Every pair (the omnidirectional variogram).
  VariogramDirection() = default;
  /// gstat's horizontal direction alpha (deg, clockwise from +y) with tolerance tol_hor (deg), and
  /// in 3-D the dip beta (deg) with tolerance tol_ver (deg). Throws ArgumentError for a
  /// non-finite angle or a tolerance outside [0, 180].
  static VariogramDirection gstat(double alpha_deg, double tol_hor_deg, double beta_deg = 0.0,
                                  double tol_ver_deg = 90.0);
  /// Within tol_deg of the direction u (any nonzero vector; normalized here). Throws
  /// ArgumentError for a zero or non-finite u or a tolerance outside [0, 180].
  static VariogramDirection along(std::vector<double> u, double tol_deg);
  /// Along coordinate axis k (0-based) of a D-dimensional space.
  static VariogramDirection axis(int k, int dimension, double tol_deg);

  Kind kind() const noexcept { return kind_; }
  bool is_all() const noexcept { return kind_ == Kind::All; }
  double alpha_deg() const noexcept { return alpha_; }
  double beta_deg() const noexcept { return beta_; }
  double tol_hor_deg() const noexcept { return tol_hor_; }
  double tol_ver_deg() const noexcept { return tol_ver_; }
  /// Unit vector of along()/axis(); empty otherwise.
  const std::vector<double>& unit() const noexcept { return unit_; }
  double tol_deg() const noexcept { return tol_; }
  /// Throws ArgumentError unless the direction fits locations of `dimension` coordinates
  /// (gstat: 2 or 3, the vertical test 3 only; along: the vector's length, at most 64).
  void check_dimension(int dimension) const;
  /// "all", "alpha=45,tol.hor=22.5[,beta=..,tol.ver=..]" or "u=(...),tol=..".
  std::string to_string() const;

 private:
  Kind kind_ = Kind::All;
  double alpha_ = 0.0, beta_ = 0.0, tol_hor_ = 90.0, tol_ver_ = 90.0, tol_ = 180.0;
  std::vector<double> unit_;
};

}  // namespace errfield
