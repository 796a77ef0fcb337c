#pragma once
/// Direction filter of the empirical variogram's pair loop: whether the separation
/// s = x_i - x_j of a pair lies within an angular tolerance of a direction (either sign, as gstat's
/// symmetric variograms). Used by bin_pair_rows, bin_pair_rows_euclidean and
/// store_pair_differences (pair_binning.hpp), which mark a rejected pair's lag NaN so that it falls
/// in no bin. The angle is taken in the location coordinates, whatever the metric.
///
/// Two kinds (errfield::VariogramDirection builds them and documents the conventions):
///  - gstat (2-D/3-D): horizontal test on axes 0, 1 with the direction (sin alpha, cos alpha)
///    (alpha clockwise from +y), made only when tol_hor < 90 deg and (s_x, s_y) != 0; vertical
///    test on (|s_xy|, s_z) with (cos beta, sin beta), made only when tol_ver < 90 deg and s != 0.
///  - vector (any dimension): |s . u| >= cos(tol) |s| for a unit vector u; s = 0 is accepted.
/// Both accept an angle equal to the tolerance in exact arithmetic (cosines compared with >=).
/// Plain pointers, no allocation, no exceptions.

#include <cmath>
#include <cstddef>
#include <limits>

namespace errfield::kernels {

struct DirectionCone {
  const double* coordinates = nullptr;  ///< axis-major: coordinates[a * n + i]
  std::size_t n = 0;
  int dimension = 0;
  bool gstat = false;
  // gstat kind
  bool check_hor = false;
  double hor_x = 0.0, hor_y = 1.0, cos_tol_hor = -1.0;
  bool check_ver = false;
  double ver_xy = 1.0, ver_z = 0.0, cos_tol_ver = -1.0;
  // vector kind: unit vector of `dimension` entries
  const double* axis = nullptr;
  double cos_tol = -1.0;
};

/// Whether the separation s (dimension entries) is within the cone.
inline bool direction_accepts(const DirectionCone& c, const double* s) noexcept {
  if (c.gstat) {
    const double px = s[0];
    const double py = c.dimension > 1 ? s[1] : 0.0;
    const double pz = c.dimension > 2 ? s[2] : 0.0;
    const double xy2 = px * px + py * py;
    if (c.check_hor && xy2 != 0.0) {
      const double cosine = (px * c.hor_x + py * c.hor_y) / std::sqrt(xy2);
      if (std::fabs(cosine) < c.cos_tol_hor) return false;
    }
    if (c.check_ver && (xy2 != 0.0 || pz != 0.0)) {
      const double cosine = (std::sqrt(xy2) * c.ver_xy + pz * c.ver_z) / std::sqrt(xy2 + pz * pz);
      if (std::fabs(cosine) < c.cos_tol_ver) return false;
    }
    return true;
  }
  double dot = 0.0, norm2 = 0.0;
  for (int a = 0; a < c.dimension; ++a) {
    dot += s[a] * c.axis[a];
    norm2 += s[a] * s[a];
  }
  if (norm2 == 0.0) return true;
  return std::fabs(dot) >= c.cos_tol * std::sqrt(norm2);
}

/// h[t] = NaN for the pairs (i, j0 + t), t < m, outside the cone (at most 64 axes).
inline void mask_directions(const DirectionCone& c, std::size_t i, std::size_t j0, std::size_t m,
                            double* h) noexcept {
  double s[64];
  s[0] = s[1] = s[2] = 0.0;  // the gstat test reads three axes (dimension >= 2 is checked)
  const std::size_t D = static_cast<std::size_t>(c.dimension);
  for (std::size_t t = 0; t < m; ++t) {
    for (std::size_t a = 0; a < D; ++a)
      s[a] = c.coordinates[a * c.n + i] - c.coordinates[a * c.n + j0 + t];
    if (!direction_accepts(c, s)) h[t] = std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace errfield::kernels
